//! The user's guide (the README and docs/COMMANDS.md) against the command line: every
//! `naocalib SUBCOMMAND … --flag` it names is a subcommand and a flag of that subcommand as
//! its `--help` (derived from clap) lists them, every inline `--flag` is a flag of some
//! subcommand, the quick start's two commands are there, and every link into the repository
//! points at a file that exists.

use std::collections::{BTreeMap, BTreeSet};
use std::path::Path;

use crate::util::{naocalib, stderr};

/// The README as the repository has it.
const README: &str = include_str!("../../README.md");

/// The guide's pages whose command lines and links are checked: path and text.
const GUIDE: [(&str, &str); 2] = [
    ("README.md", README),
    ("docs/COMMANDS.md", include_str!("../../docs/COMMANDS.md")),
];

/// The quick start's commands, exactly (CI runs `scripts/test.sh`).
const QUICK_START: [&str; 2] = [
    "scripts/install-deps.sh && cargo run --release -- solve --detect --body data/sample",
    "scripts/test.sh",
];

/// One command line the guide names: where (page and line number) and the words after
/// `naocalib`.
#[derive(Debug)]
struct Mention {
    page: &'static str,
    line: usize,
    words: Vec<String>,
}

/// What `naocalib PATH --help` lists: the flags (`--force`, `-j`) and the subcommands.
#[derive(Debug, Default)]
struct Help {
    flags: BTreeSet<String>,
    subcommands: BTreeSet<String>,
}

/// `naocalib PATH… --help`, parsed.
fn help(path: &[String]) -> Help {
    let out = naocalib().args(path).arg("--help").output().expect("ran");
    assert!(
        out.status.success(),
        "naocalib {} --help failed: {}",
        path.join(" "),
        stderr(&out)
    );
    let text = String::from_utf8_lossy(&out.stdout);
    let mut help = Help::default();
    let mut in_commands = false;
    for line in text.lines() {
        let trimmed = line.trim_start();
        let indent = line.len() - trimmed.len();
        if line.starts_with("Commands:") {
            in_commands = true;
            continue;
        }
        if !line.starts_with(' ') {
            in_commands = false;
        }
        // A subcommand is indented by two spaces, an option by at most six; what is indented
        // more is a description's continuation.
        if in_commands {
            if indent == 2
                && let Some(name) = trimmed.split_whitespace().next()
            {
                help.subcommands.insert(name.to_string());
            }
        } else if indent <= 6 && trimmed.starts_with('-') {
            // `-j, --threads <N>`, `--detect`: the flag words before the description.
            for word in trimmed.split([' ', ',', '=']) {
                if is_flag(word) {
                    help.flags.insert(word.to_string());
                }
                if !(word.is_empty() || word.starts_with('-')) {
                    break;
                }
            }
        }
    }
    help
}

/// `--long-flag` or `-x`.
fn is_flag(word: &str) -> bool {
    let long = word.strip_prefix("--").is_some_and(|rest| {
        rest.chars().next().is_some_and(|c| c.is_ascii_lowercase())
            && rest
                .chars()
                .all(|c| c.is_ascii_lowercase() || c.is_ascii_digit() || c == '-')
    });
    let short = word.len() == 2
        && word.starts_with('-')
        && word.chars().nth(1).is_some_and(|c| c.is_ascii_alphabetic());
    long || short
}

/// A word as a flag, with the synopsis' brackets and ellipses and a `=value` taken off.
fn flag_of(word: &str) -> Option<String> {
    let word = word.trim_matches(|c| matches!(c, '[' | ']' | '(' | ')' | '…' | '`' | ',' | '.'));
    let word = word.split('=').next().unwrap_or(word);
    is_flag(word).then(|| word.to_string())
}

/// The words of a command line after `naocalib` (or after `cargo run … --`), if it is one.
fn naocalib_words(command: &str) -> Option<Vec<String>> {
    let command = command.split(" #").next().unwrap_or(command);
    let words: Vec<&str> = command.split_whitespace().collect();
    let start = if let Some(i) = words
        .iter()
        .position(|w| matches!(*w, "naocalib" | "./naocalib"))
    {
        i + 1
    } else if words.starts_with(&["cargo", "run"]) {
        words.iter().position(|w| *w == "--")? + 1
    } else {
        return None;
    };
    (start < words.len()).then(|| words[start..].iter().map(|w| w.to_string()).collect())
}

/// Every command line the guide names: in code blocks (a line with `naocalib`, continued
/// by a trailing `\` or by indented lines), and in inline code (`` `naocalib solve --json` ``
/// or `` `solve --json` `` with a subcommand first).
fn mentions(subcommands: &BTreeSet<String>) -> Vec<Mention> {
    let mut found = Vec::new();
    for (page, text) in GUIDE {
        found.extend(page_mentions(page, text, subcommands));
    }
    found
}

/// [`mentions`] on one page.
fn page_mentions(page: &'static str, text: &str, subcommands: &BTreeSet<String>) -> Vec<Mention> {
    let mut found = Vec::new();
    let mut in_code = false;
    let mut current: Option<(usize, String)> = None;
    let flush = |current: &mut Option<(usize, String)>, found: &mut Vec<Mention>| {
        if let Some((line, text)) = current.take()
            && let Some(words) = naocalib_words(&text)
        {
            found.push(Mention { page, line, words });
        }
    };
    for (i, line) in text.lines().enumerate() {
        let number = i + 1;
        if line.trim_start().starts_with("```") {
            flush(&mut current, &mut found);
            in_code = !in_code;
            continue;
        }
        if in_code {
            let body = line.trim_start().trim_start_matches("$ ");
            let continues = current
                .as_ref()
                .is_some_and(|(_, text)| text.trim_end().ends_with('\\'))
                || (current.is_some() && line.starts_with(' ') && !body.starts_with('#'));
            if continues {
                if let Some((_, text)) = current.as_mut() {
                    text.push(' ');
                    text.push_str(body.trim_end_matches('\\'));
                }
            } else {
                flush(&mut current, &mut found);
                current = Some((number, body.trim_end_matches('\\').to_string()));
            }
            continue;
        }
        for (k, span) in line.split('`').enumerate() {
            if k % 2 == 0 {
                continue;
            }
            let first = span.split_whitespace().next().unwrap_or("");
            let words = if subcommands.contains(first) {
                Some(span.split_whitespace().map(str::to_string).collect())
            } else {
                naocalib_words(span)
            };
            if let Some(words) = words {
                found.push(Mention {
                    page,
                    line: number,
                    words,
                });
            }
        }
    }
    flush(&mut current, &mut found);
    found
}

/// The flags the inline code of the guide names on their own (`` `--plots DIR` ``): page,
/// line, flag.
fn bare_flags() -> Vec<(&'static str, usize, String)> {
    let mut found = Vec::new();
    for (page, text) in GUIDE {
        let mut in_code = false;
        for (i, line) in text.lines().enumerate() {
            if line.trim_start().starts_with("```") {
                in_code = !in_code;
                continue;
            }
            if in_code {
                continue;
            }
            for (k, span) in line.split('`').enumerate() {
                if k % 2 == 1
                    && span.starts_with('-')
                    && let Some(flag) = span.split_whitespace().next().and_then(flag_of)
                {
                    found.push((page, i + 1, flag));
                }
            }
        }
    }
    found
}

#[test]
fn every_flag_the_readme_names_exists() {
    let top = help(&[]);
    assert!(
        top.subcommands.contains("solve") && top.subcommands.contains("capture"),
        "naocalib --help lists no subcommands: {:?}",
        top.subcommands
    );
    let mut helps: BTreeMap<Vec<String>, Help> = BTreeMap::new();
    let mut problems = Vec::new();
    let mut checked = BTreeSet::new();
    for mention in mentions(&top.subcommands) {
        let Some(sub) = mention.words.first() else {
            continue;
        };
        if sub.starts_with('-') {
            continue; // `naocalib --help`, `--version`
        }
        if !top.subcommands.contains(sub) {
            problems.push(format!(
                "{} line {}: `naocalib {sub}` is no subcommand",
                mention.page, mention.line
            ));
            continue;
        }
        let mut path = vec![sub.clone()];
        let mut rest = &mention.words[1..];
        let inner = helps
            .entry(path.clone())
            .or_insert_with(|| help(&path))
            .subcommands
            .clone();
        if let Some(next) = rest.first()
            && inner.contains(next)
        {
            path.push(next.clone());
            rest = &rest[1..];
        }
        let help = helps.entry(path.clone()).or_insert_with(|| help(&path));
        for flag in rest.iter().filter_map(|w| flag_of(w)) {
            checked.insert((path.join(" "), flag.clone()));
            if !help.flags.contains(&flag) {
                problems.push(format!(
                    "{} line {}: `naocalib {} {flag}`: no such flag (it has {})",
                    mention.page,
                    mention.line,
                    path.join(" "),
                    help.flags.iter().cloned().collect::<Vec<_>>().join(" ")
                ));
            }
        }
    }
    let all_flags: BTreeSet<String> = top
        .subcommands
        .iter()
        .filter(|s| *s != "help")
        .flat_map(|s| {
            let path = vec![s.clone()];
            helps
                .entry(path.clone())
                .or_insert_with(|| help(&path))
                .flags
                .clone()
        })
        .collect();
    for (page, line, flag) in bare_flags() {
        if !all_flags.contains(&flag) {
            problems.push(format!(
                "{page} line {line}: `{flag}` is no subcommand's flag"
            ));
        }
    }
    assert!(problems.is_empty(), "{}", problems.join("\n"));
    // The parser must have found the commands, not skipped them: the day's steps and the
    // command summary name a flag of every subcommand a user runs.
    let subcommands_checked: BTreeSet<&str> = checked.iter().map(|(s, _)| s.as_str()).collect();
    for sub in [
        "solve", "detect", "plan", "capture", "export", "import", "batch",
    ] {
        assert!(
            subcommands_checked.contains(sub),
            "the guide names no flag of `naocalib {sub}` (checked: {subcommands_checked:?})"
        );
    }
    assert!(
        checked.len() >= 40,
        "only {} subcommand flags found in the guide",
        checked.len()
    );
}

#[test]
fn readme_has_the_quick_start_and_its_links_exist() {
    for command in QUICK_START {
        assert!(
            README.lines().any(|l| l.trim() == command),
            "the README lacks the line `{command}`"
        );
    }
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let mut missing = Vec::new();
    for (page, text) in GUIDE {
        let dir = root
            .join(page)
            .parent()
            .expect("a page's folder")
            .to_path_buf();
        for (i, line) in text.lines().enumerate() {
            for target in line.split("](").skip(1) {
                let target = target.split(')').next().unwrap_or("");
                let (file, anchor) = target.split_once('#').unwrap_or((target, ""));
                if file.contains("://") {
                    continue;
                }
                let path = if file.is_empty() {
                    root.join(page)
                } else {
                    dir.join(file)
                };
                if !path.exists() {
                    missing.push(format!("{page} line {}: {target}", i + 1));
                } else if !anchor.is_empty() {
                    let text = std::fs::read_to_string(&path).expect("readable");
                    if !text
                        .lines()
                        .any(|l| l.starts_with('#') && slug(l) == anchor)
                    {
                        missing.push(format!("{page} line {}: {target} (no such heading)", i + 1));
                    }
                }
            }
        }
    }
    assert!(missing.is_empty(), "links to nothing: {missing:?}");
}

/// A Markdown heading's anchor as GitHub makes it: lower case, punctuation dropped, spaces
/// as hyphens (`## 9 What σ means` → `9-what-σ-means`).
fn slug(heading: &str) -> String {
    heading
        .trim_start_matches('#')
        .trim()
        .to_lowercase()
        .chars()
        .filter(|c| c.is_alphanumeric() || matches!(c, ' ' | '-' | '_'))
        .map(|c| if c == ' ' { '-' } else { c })
        .collect()
}
