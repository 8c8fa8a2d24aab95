//! A calibration file format as one trait, [`Format`], which every format implements in
//! its team's module; and what the one list of them, [`FORMATS`], gives the CLI and the
//! docs: the `--format` names and help ([`named`], [`names`], [`help`]), the format a file
//! name implies ([`from_path`]), the format a file's text is in ([`recognised`]) and
//! docs/EXPORTS.md's table of formats ([`table`]).

use std::fmt;
use std::path::Path;

use super::{Calibration, ExportError, FORMATS, Imported, parse_error, source};

/// A calibration file format: naocalib's own (the TOML and the JSON of
/// [`super::own`]) or the layout of a team's file that a robot loads, which naocalib also
/// reads (`naocalib import`) and updates in place (`naocalib export --update`).
///
/// Each format is a unit struct in its team's module, beside the team's units, axes, sign
/// conventions and the citations of the team's code; [`FORMATS`] lists them. A team format
/// implements [`Format::read`] and [`Format::update`] too (and [`Format::joints`],
/// [`Format::file_names`] where they apply); naocalib's own formats answer `false` to
/// [`Format::robot`] and keep the default `read` and `update`, which refuse.
///
/// Adding a format: its unit struct and `impl Format` in its team's module, one line in
/// [`FORMATS`], and `NAOCALIB_BLESS=1 cargo test --test it docs_table` to write its row
/// into docs/EXPORTS.md's table.
pub trait Format: Sync {
    /// The `--format` name (`bhuman-camera`).
    fn name(&self) -> &'static str;
    /// The file name `--dir` gives it, relative to the directory.
    fn file(&self) -> &'static str;
    /// One line for `--help`: the team, the file and what it carries.
    fn description(&self) -> &'static str;
    /// Its row of docs/EXPORTS.md's table ([`table`]).
    fn doc_row(&self) -> DocRow;
    /// Whether `code` — a file's text without comments ([`source::code`]) — is in this
    /// layout: for `naocalib import` without `--format`, and to refuse an update of a file
    /// in another layout. Layouts are told by their keys, never by words in comments.
    fn recognise(&self, code: &str) -> bool;
    /// The calibration as a fresh file of this format, starting with naocalib's header
    /// where the format has comments (what wrote it, the units, the compensation rule) and
    /// a `NOT A CALIBRATION` marker when [`Calibration::problems`] finds any.
    fn write(&self, cal: &Calibration) -> String;
    /// The values a file of this format holds, as naocalib parameters in report units
    /// ([`Imported`]: joint offsets as α = −stored, camera corrections converted to
    /// naocalib's offsets). The default refuses: naocalib's own files are read with
    /// [`super::read_calibration`], not imported.
    fn read(&self, text: &str, path: &Path) -> Result<Imported, ExportError> {
        let _ = text;
        Err(parse_error(
            path,
            format!("import is not supported for --format {}", self.name()),
        ))
    }
    /// `text`, a robot's file of this format, with what `cal` determined replaced and every
    /// other byte kept ([`super::update()`] adds the layout check, the refusals and the
    /// backups). The default refuses.
    fn update(&self, text: &str, path: &Path, cal: &Calibration) -> Result<String, ExportError> {
        let _ = (text, cal);
        Err(parse_error(
            path,
            format!("--update is not supported for --format {}", self.name()),
        ))
    }
    /// Whether a robot loads files of this format — then [`Format::read`] and
    /// [`Format::update`] work, and a result that is not a calibration is refused — as
    /// every team format; not naocalib's own TOML and JSON.
    fn robot(&self) -> bool {
        true
    }
    /// Whether the file carries joint offsets (which a calibration of angles already
    /// corrected by the robot's joint calibration writes only by updating the robot's
    /// file: [`super::check_fresh`]).
    fn joints(&self) -> bool {
        false
    }
    /// The `--out` file names that imply this format without `--format` ([`from_path`]).
    fn file_names(&self) -> NameRule {
        NameRule::None
    }
    /// Whether the file carries the cameras' intrinsics only: a directory export writes it
    /// only for a calibration that carries intrinsics ([`Calibration::cameras`]), and a
    /// fresh file of it is refused for one that does not.
    fn intrinsics(&self) -> bool {
        false
    }
    /// Whether `cal` carries what a file of the cameras' intrinsics ([`Format::intrinsics`])
    /// holds: any camera's intrinsics by default; a file of one camera's, that camera's.
    fn has_intrinsics_for(&self, cal: &Calibration) -> bool {
        !cal.cameras.is_empty()
    }
    /// The cameras' intrinsics a file of this format holds (`naocalib import`), each as
    /// the prior of a calibration held at them; none by default.
    fn read_cameras(
        &self,
        text: &str,
        path: &Path,
    ) -> Result<Vec<(crate::model::CameraId, crate::calibration::Prior)>, ExportError> {
        let _ = (text, path);
        Ok(Vec::new())
    }
}

impl dyn Format + '_ {
    /// Whether `text` is in this format's layout ([`Format::recognise`] on the text
    /// without comments).
    pub fn matches(&self, text: &str) -> bool {
        self.recognise(&source::code(text))
    }
}

impl PartialEq for dyn Format {
    fn eq(&self, other: &Self) -> bool {
        self.name() == other.name()
    }
}

impl Eq for dyn Format {}

impl fmt::Debug for dyn Format {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

/// A format's row of docs/EXPORTS.md's table ([`table`]), in Markdown.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct DocRow {
    /// What the file carries: its keys.
    pub carries: &'static str,
    /// The units of its values.
    pub units: &'static str,
    /// Its axis convention, cited from the team's code.
    pub axes: &'static str,
}

/// Which `--out` file names imply a format without `--format` ([`from_path`]), matched on
/// the lower-cased file name. The more specific rule wins: an exact name over a word, a
/// word over an ending.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum NameRule {
    /// No name: the format needs `--format`.
    None,
    /// A name with this ending (`.toml`).
    Ending(&'static str),
    /// A name with this ending that contains the word (`.cfg`, `camera`).
    Containing {
        /// The ending.
        ending: &'static str,
        /// The word.
        word: &'static str,
    },
    /// Exactly this name, lower-case (`cameramatrixoffset.cfg`).
    Exactly(&'static str),
}

impl NameRule {
    /// How specifically the rule takes the lower-cased file `name` (higher wins), if at all.
    fn rank(self, name: &str) -> Option<u8> {
        match self {
            NameRule::None => None,
            NameRule::Ending(ending) => name.ends_with(ending).then_some(1),
            NameRule::Containing { ending, word } => {
                (name.ends_with(ending) && name.contains(word)).then_some(2)
            }
            NameRule::Exactly(exact) => (name == exact).then_some(3),
        }
    }
}

/// The format named `name` (`--format NAME`).
pub fn named(name: &str) -> Option<&'static dyn Format> {
    FORMATS.iter().copied().find(|f| f.name() == name)
}

/// The `--format` names, comma-separated (for messages).
pub fn names() -> String {
    FORMATS
        .iter()
        .map(|f| f.name())
        .collect::<Vec<_>>()
        .join(", ")
}

/// One line per format, `name: description (file)` (for the CLI help).
pub fn help() -> String {
    FORMATS
        .iter()
        .map(|f| format!("{}: {} ({})", f.name(), f.description(), f.file()))
        .collect::<Vec<_>>()
        .join("\n")
}

/// The format a file name implies ([`Format::file_names`]; the most specific rule, the
/// first in [`FORMATS`] among equals): `*.toml`, `*.json`, `*camera*.cfg` (B-Human),
/// `*joint*.cfg` (B-Human), `CameraMatrixOffset.cfg` (NaoTH).
pub fn from_path(path: &Path) -> Option<&'static dyn Format> {
    let name = path.file_name()?.to_string_lossy().to_lowercase();
    let mut best: Option<(u8, &'static dyn Format)> = None;
    for &format in FORMATS {
        if let Some(rank) = format.file_names().rank(&name)
            && best.is_none_or(|(b, _)| rank > b)
        {
            best = Some((rank, format));
        }
    }
    best.map(|(_, format)| format)
}

/// The patterns of the file names [`from_path`] knows, for `--out`'s help: `*.toml,
/// *.json, *camera*.cfg, *joint*.cfg` (an exact name, one team's file, is not a pattern).
pub fn name_patterns() -> String {
    let patterns: Vec<String> = FORMATS
        .iter()
        .filter_map(|f| match f.file_names() {
            NameRule::Ending(ending) => Some(format!("*{ending}")),
            NameRule::Containing { ending, word } => Some(format!("*{word}*{ending}")),
            NameRule::None | NameRule::Exactly(_) => None,
        })
        .collect();
    patterns.join(", ")
}

/// The names [`from_path`] knows by their pattern, for the error of a name it does not:
/// `.toml, .json, cameraCalibration.cfg or jointCalibration.cfg` (each ending, and the
/// file of each format known by a word in its name).
pub fn name_hints() -> String {
    let hints: Vec<&str> = FORMATS
        .iter()
        .filter_map(|f| match f.file_names() {
            NameRule::Ending(ending) => Some(ending),
            NameRule::Containing { .. } => f.file().rsplit('/').next(),
            NameRule::None | NameRule::Exactly(_) => None,
        })
        .collect();
    match hints.split_last() {
        Some((last, first)) if !first.is_empty() => format!("{} or {last}", first.join(", ")),
        _ => hints.join(""),
    }
}

/// The robot format a file's text is in ([`Format::recognise`] on the text without
/// comments), if any: the first in [`FORMATS`].
pub fn recognised(text: &str) -> Option<&'static dyn Format> {
    let code = source::code(text);
    FORMATS
        .iter()
        .copied()
        .filter(|f| f.robot())
        .find(|f| f.recognise(&code))
}

/// docs/EXPORTS.md's table of formats, in Markdown: one row per format of [`FORMATS`], in
/// order (`--format`, the `--dir` file, [`DocRow`]).
pub fn table() -> String {
    let mut s = String::from(
        "| `--format` | file (`--dir` name) | carries | units | axis convention |\n\
         | --- | --- | --- | --- | --- |\n",
    );
    for f in FORMATS {
        let row = f.doc_row();
        s.push_str(&format!(
            "| `{}` | `{}` | {} | {} | {} |\n",
            f.name(),
            f.file(),
            row.carries,
            row.units,
            row.axes
        ));
    }
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_list_has_each_name_and_file_once() {
        for (k, f) in FORMATS.iter().enumerate() {
            assert_eq!(named(f.name()), Some(*f));
            for g in &FORMATS[..k] {
                assert_ne!(f.name(), g.name());
                assert_ne!(f.file(), g.file(), "{} and {}", f.name(), g.name());
            }
        }
        assert_eq!(named("nope"), None);
    }

    #[test]
    fn naocalibs_own_formats_are_neither_imported_nor_updated() {
        let own: Vec<&str> = FORMATS
            .iter()
            .filter(|f| !f.robot())
            .map(|f| f.name())
            .collect();
        assert_eq!(own, ["toml", "json"]);
        let path = Path::new("x.cfg");
        for f in FORMATS.iter().filter(|f| !f.robot()) {
            let read = f.read("", path).unwrap_err().to_string();
            assert_eq!(
                read,
                format!("x.cfg: import is not supported for --format {}", f.name())
            );
            let cal = Calibration {
                origin: crate::calibration::Origin::Solved,
                solver: None,
                dataset: None,
                converged: None,
                rms_px: None,
                parameters: Vec::new(),
                angles: None,
                posture: super::super::Posture::Lying,
                standing: Default::default(),
                cameras: Default::default(),
            };
            let update = f.update("", path, &cal).unwrap_err().to_string();
            assert!(update.contains("--update is not supported"), "{update}");
        }
    }

    #[test]
    fn the_name_rules_give_the_help_and_the_hint() {
        assert_eq!(name_patterns(), "*.toml, *.json, *camera*.cfg, *joint*.cfg");
        assert_eq!(
            name_hints(),
            ".toml, .json, cameraCalibration.cfg or jointCalibration.cfg"
        );
        assert_eq!(
            NameRule::Exactly("cameramatrixoffset.cfg").rank("cameramatrixoffset.cfg"),
            Some(3)
        );
        assert_eq!(NameRule::None.rank("a.cfg"), None);
    }
}
