#!/usr/bin/env python3
"""Compares the outputs `scripts/same-outputs.sh` recorded (BEFORE) with those of a check run
(AFTER) under the calibration's tolerances, and says where the largest differences are.

    python3 scripts/compare_outputs.py BEFORE AFTER

What must agree:

- every number of a JSON output within 1e-9 of its magnitude or 1e-12 absolute; every σ
  (`std`, `std_sandwich`, a bootstrap's `std`, the noise model's `noise.px` and
  `noise.joint_deg`, ...) and test statistic (`statistic`, `p_value`, the SVD report's
  singular values, condition number and correlations, `sigma` and `*_px2`) within 1e-6
  relative; integers, strings and booleans exactly (so the same
  parameters are determined, held and suggested, and the diagnosis reads the same);
- every number printed in a text, HTML, SVG or team file to its printed precision: equal, or
  one unit apart in its last printed digit (a rounding that fell the other way), and the
  text around the numbers exactly; integers exactly. A number printed in full (15 or more
  significant digits: the shortest text that reads back exactly, as the team files and
  `calibration.toml` write values and σ) is not rounded for print, so it is held to the
  values' tolerance instead (1e-9 of its magnitude or 1e-12 absolute);
- the exit status and what is printed on stderr (as text);
- other files (PNG, PDF) byte for byte.

Left out: wall times (`seconds`, `seconds_mean`, `wall_seconds`, `solver_seconds`, the text's
`time` lines, `compare`'s solver and wall ms columns). The optimiser's path — its iteration
count and termination message (`iterations`, `termination`, the text's `solver ...:
converged after N iterations (...)` line) — is not the calibration: where it differs the
file is counted apart and named, not failed. A batch JSON whose runs gained keys (present
after, absent before) is compared without them, and the keys are named.

Exit status 0 when every file agrees within these tolerances, 1 otherwise.
"""

import json
import math
import os
import re
import sys

WALL_KEYS = {"seconds", "seconds_mean", "wall_seconds", "solver_seconds"}
PATH_KEYS = {"iterations", "termination"}
# Keys whose numbers are σ or test statistics (1e-6 relative).
STAT_KEYS = {
    "std",
    "std_sandwich",
    "sandwich",
    "statistic",
    "p_value",
    "singular_values",
    "condition_number",
    "r",
    "sigma",
    "explained_px2",
    "residual_sigma_px",
    "relative_singular_value",
}
VALUE_REL, VALUE_ABS, STAT_REL = 1e-9, 1e-12, 1e-6
# A printed number with this many significant digits or more is printed in full.
FULL_DIGITS = 15

NUMBER = re.compile(r"[-+]?(?:\d+\.\d*|\.\d+|\d+)(?:[eE][-+]?\d+)?")
SOLVER_LINE = re.compile(r"^solver \S+: .*iterations")


def is_stat(path):
    """Whether the JSON path (a list of keys and indices) names a σ or a test statistic
    (the noise model's levels, `noise.px` and `noise.joint_deg`, are σ too)."""
    keys = [k for k in path if isinstance(k, str)]
    if len(keys) >= 2 and keys[-2] == "noise":
        return True
    return any(k in STAT_KEYS or "std" in k or "sigma" in k for k in keys[-2:])


class Report:
    def __init__(self):
        # (relative difference / tolerance, description) of the largest per class
        self.largest = {}
        self.problems = []
        self.path_differs = False
        self.noted = False

    def note(self, kind, ratio, where, a, b, rel):
        self.noted = True
        best = self.largest.get(kind)
        if best is None or ratio > best[0]:
            self.largest[kind] = (ratio, where, a, b, rel)

    def fail(self, message):
        self.problems.append(message)


def compare_number(a, b, path, where, report):
    if isinstance(a, bool) or isinstance(b, bool) or isinstance(a, int) and isinstance(b, int):
        if a != b:
            report.fail(f"{where}: {a} vs {b}")
        return
    a, b = float(a), float(b)
    if a == b or (math.isnan(a) and math.isnan(b)):
        return
    if not (math.isfinite(a) and math.isfinite(b)):
        report.fail(f"{where}: {a!r} vs {b!r}")
        return
    diff = abs(a - b)
    scale = max(abs(a), abs(b))
    rel = diff / scale
    if is_stat(path):
        tol = STAT_REL * scale
        kind = "σ or test statistic"
    else:
        tol = max(VALUE_REL * scale, VALUE_ABS)
        kind = "value"
    report.note(kind, diff / tol, where, a, b, rel)
    if diff > tol:
        report.fail(f"{where}: {a!r} vs {b!r} (relative {rel:.2e})")


def compare_json(a, b, path, where, report):
    key = path[-1] if path and isinstance(path[-1], str) else None
    if key in WALL_KEYS:
        return
    if key in PATH_KEYS:
        if a != b:
            report.path_differs = True
        return
    if isinstance(a, dict) and isinstance(b, dict):
        if a.keys() != b.keys():
            report.fail(f"{where}: keys {sorted(a.keys() ^ b.keys())} in one only")
            return
        for k in a:
            compare_json(a[k], b[k], path + [k], f"{where}.{k}", report)
    elif isinstance(a, list) and isinstance(b, list):
        if len(a) != len(b):
            report.fail(f"{where}: {len(a)} vs {len(b)} entries")
            return
        for i, (x, y) in enumerate(zip(a, b)):
            compare_json(x, y, path + [i], f"{where}[{i}]", report)
    elif isinstance(a, (int, float)) and isinstance(b, (int, float)):
        compare_number(a, b, path, where, report)
    elif a != b:
        report.fail(f"{where}: {a!r} vs {b!r}")


def runs_of(doc):
    if isinstance(doc, dict) and isinstance(doc.get("runs"), list):
        return [r for r in doc["runs"] if isinstance(r, dict)]
    return [doc] if isinstance(doc, dict) and "solver" in doc else []


def drop_gained(before, after):
    """The keys the runs of `after` have and those of `before` lack, removed from `after`."""
    had = {k for r in runs_of(before) for k in r}
    gained = {k for r in runs_of(after) for k in r} - had
    for r in runs_of(after):
        for k in gained:
            r.pop(k, None)
    return gained


def decimals(token):
    mantissa = re.split(r"[eE]", token)[0]
    return len(mantissa.split(".")[1]) if "." in mantissa else None


def significant(token):
    digits = re.split(r"[eE]", token)[0].lstrip("+-").replace(".", "").lstrip("0")
    return len(digits)


def compare_text(a, b, name, report):
    la, lb = a.splitlines(), b.splitlines()
    if len(la) != len(lb):
        report.fail(f"{name}: {len(la)} vs {len(lb)} lines")
        return
    for n, (x, y) in enumerate(zip(la, lb), 1):
        if x == y:
            continue
        if SOLVER_LINE.match(x) and SOLVER_LINE.match(y):
            report.path_differs = True
            continue
        if NUMBER.split(x) != NUMBER.split(y):
            report.fail(f"{name}:{n}: {x.strip()!r} vs {y.strip()!r}")
            return
        for s, t in zip(NUMBER.findall(x), NUMBER.findall(y)):
            if s == t:
                continue
            u, v = float(s), float(t)
            if max(significant(s), significant(t)) >= FULL_DIGITS:
                diff = abs(u - v)
                bound = max(VALUE_REL * max(abs(u), abs(v)), VALUE_ABS)
                report.note("printed number", diff / bound, f"{name}:{n}", s, t,
                            diff / max(abs(u), abs(v), VALUE_ABS))
                if diff > bound:
                    report.fail(f"{name}:{n}: {s} vs {t} in {x.strip()!r}")
                    return
                continue
            d = decimals(s)
            if d is None or d != decimals(t):
                report.fail(f"{name}:{n}: {s} vs {t} in {x.strip()!r}")
                return
            exponent = re.split(r"[eE]", s)
            unit = 10.0 ** -d * (10.0 ** int(exponent[1]) if len(exponent) > 1 else 1.0)
            diff = abs(u - v)
            rel = diff / max(abs(u), abs(v), unit)
            report.note("printed number", diff / unit, f"{name}:{n}", s, t, rel)
            if diff > unit * (1 + 1e-9):
                report.fail(f"{name}:{n}: {s} vs {t} in {x.strip()!r}")
                return


def strip_text(rel, text):
    lines = text.splitlines()
    if os.path.basename(rel).startswith("compare-") and rel.endswith(".txt"):
        out = []
        for line in lines:
            f = line.split()
            if len(f) > 7 and f[1] in ("yes", "NO", "FAILED"):
                f[6] = f[7] = "-"
                line = " ".join(f)
            out.append(line)
        return "\n".join(out)
    if rel.endswith((".txt", ".html")):
        return "\n".join(l for l in lines if not l.startswith("time "))
    return text


TEXT = (".txt", ".err", ".html", ".svg", ".cfg", ".toml", ".csv", ".json", ".md", ".scad")


def compare_file(rel, fa, fb, report, gained_keys):
    """True when the two files agree within the tolerances."""
    with open(fa, "rb") as f:
        a = f.read()
    with open(fb, "rb") as f:
        b = f.read()
    if a == b:
        return True
    if not rel.endswith(TEXT):
        report.fail(f"{rel}: bytes differ")
        return False
    try:
        a, b = a.decode(), b.decode()
    except UnicodeDecodeError:
        report.fail(f"{rel}: bytes differ")
        return False
    before = len(report.problems)
    if rel.endswith(".json"):
        try:
            ja, jb = json.loads(a), json.loads(b)
        except ValueError:
            ja = jb = None
        if ja is not None:
            gained_keys.update(drop_gained(ja, jb))
            compare_json(ja, jb, [], rel, report)
            return len(report.problems) == before
    compare_text(strip_text(rel, a), strip_text(rel, b), rel, report)
    return len(report.problems) == before


def files(root):
    out = []
    for d, _, names in os.walk(root):
        for n in names:
            out.append(os.path.relpath(os.path.join(d, n), root))
    return sorted(out)


def main():
    if len(sys.argv) != 3:
        print(__doc__.strip().splitlines()[2].strip(), file=sys.stderr)
        return 2
    before, after = sys.argv[1:]
    report = Report()
    identical = within = differ = path = 0
    gained_keys = set()
    for rel in files(before):
        fa, fb = os.path.join(before, rel), os.path.join(after, rel)
        if not os.path.exists(fb):
            differ += 1
            print(f"missing: {rel}")
            continue
        with open(fa, "rb") as f, open(fb, "rb") as g:
            if f.read() == g.read():
                identical += 1
                continue
        report.path_differs = False
        report.noted = False
        shown = len(report.problems)
        if compare_file(rel, fa, fb, report, gained_keys):
            if report.noted or report.path_differs:
                within += 1
            else:
                identical += 1  # but for wall times
            path += report.path_differs
        else:
            differ += 1
            for p in report.problems[shown : shown + 3]:
                print(f"differs: {p}")
            del report.problems[shown:]
    new = len(set(files(after)) - set(files(before)))
    total = identical + within + differ
    print(
        f"{identical} of {total} outputs identical, {within} within the tolerances, "
        f"{differ} differ (wall times left out); {new} new files"
    )
    if path:
        print(f"{path} of them with another optimiser path (iterations, termination)")
    if gained_keys:
        print(f"batch runs compared without the keys they gained: {' '.join(sorted(gained_keys))}")
    for kind in ("value", "σ or test statistic", "printed number"):
        if kind in report.largest:
            ratio, where, a, b, rel = report.largest[kind]
            print(
                f"largest difference of a {kind}: {where}: {a} vs {b} "
                f"(relative {rel:.2e}, {ratio:.3g} of its tolerance)"
            )
    return 0 if differ == 0 else 1


if __name__ == "__main__":
    sys.exit(main())
