#!/usr/bin/env bash
# The robot in its own pictures, measured as a team would meet it (the README's day): per
# simulated robot with team-sized hidden offsets, its files (the truth with the cameras'
# angles 0.3° and the legs' 0.5° off, alternately up and down; the head's as they are),
# a plan made past the body around them (`plan --around`), its pictures drawn
# with its body (`simulate --images --body --team-offsets`), the vertices found by
# `detect --body --start-from` its files, and the fit `solve --model auto --start-from`
# its files (the head's offsets held at the files'). Per robot it prints
# the planned vertices (in plain sight past the body, as `plan` predicts them),
# the vertices the body as it is leaves in sight (the simulator's truth), the vertices
# found, the worst distance of a found vertex from the truth (any found vertex whose window
# the body covers is named), and the RMS and largest err/σ of the fitted parameters.
# docs/PERFORMANCE.md ("The robot in its own pictures") quotes its output.
#
#   scripts/body-figures.sh [SANDAL] [CAMERAS] [SEEDS...]
#
# SANDAL: turned (naocalib's: 7 × 5 squares turned by 90°, centred 200 mm ahead of the
# ankle) or paper (the same board along the foot, centred 170 mm ahead); CAMERAS: lower,
# both (an upper camera with the lower one's intrinsics) or intrinsics (both, their
# intrinsics free: plan --families paper,intrinsics, robots with intrinsics offsets, solve
# --model auto --free intrinsics).
# Default: turned lower 3 4 5. Needs python3 for the comparison.
set -euo pipefail
cd "$(dirname "$0")/.."
sandal=${1:-turned}
cameras=${2:-lower}
shift $(($# < 2 ? $# : 2))
seeds=("$@")
[ ${#seeds[@]} -gt 0 ] || seeds=(3 4 5)

cargo build --release --quiet
naocalib=$PWD/target/release/naocalib
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT

# The camera and sandal: the simulator's V4 camera and naocalib's sandal (`simulate`'s
# dataset.toml), or the paper's board on it.
"$naocalib" simulate "$work/base" --stances 1 --heads 1 >/dev/null
config=$work/config.toml
case $sandal in
turned) cp "$work/base/dataset.toml" "$config" ;;
paper)
    sed -e 's/^mount_origin_mm = .*/mount_origin_mm = [170.0, 0.0, 0.0]/' \
        -e 's/^mount_rpy_deg = .*/mount_rpy_deg = [0.0, 0.0, 0.0]/' \
        "$work/base/dataset.toml" >"$config"
    ;;
*) echo "unknown sandal '$sandal' (paper, turned)" >&2; exit 2 ;;
esac
plan_flags=()
sim_flags=()
solve_flags=(--model auto)
case $cameras in
lower) ;;
both | intrinsics)
    # The [upper_camera] with the lower one's intrinsics, as the simulator's V6 has.
    sed -n '/^\[camera\]/,/^$/p' "$config" | sed 's/^\[camera\]/[upper_camera]/' >>"$config"
    if [ "$cameras" = intrinsics ]; then
        # As the plan advises for intrinsics (and the session of docs/PERFORMANCE.md):
        # around the files, a box of ±1° lets the boards sweep the images.
        plan_flags+=(--families paper,intrinsics --offset-deg 1)
        sim_flags+=(--effects intrinsics)
        solve_flags+=(--free intrinsics)
    fi
    ;;
*) echo "unknown cameras '$cameras' (lower, both, intrinsics)" >&2; exit 2 ;;
esac

# The robot's files: its true offsets, the cameras' angles 0.3° and the legs' 0.5° off,
# alternately up and down, in naocalib's calibration TOML (`naocalib import`'s). The head's
# offsets are as the files hold them: the framework applies them before the camera's
# correction, so a calibration is for the files' head offsets (`solve --start-from`).
files() {
    python3 - "$1" "$2" <<'EOF'
import re, sys
truth, out = sys.argv[1:]
values = dict(re.findall(r"^(\w+) = (\S+)", open(truth).read(), re.M))
legs = [f"{s}{j}" for s in "LR" for j in
        ["HipYawPitch", "HipRoll", "HipPitch", "KneePitch", "AnklePitch", "AnkleRoll"]]
angles = ["CamYaw", "CamPitch", "CamRoll", "UpperCamYaw", "UpperCamPitch", "UpperCamRoll"]
units = dict(re.findall(r"^(\w+) = \S+ +# (\S+)", open(truth).read(), re.M))
with open(out, "w") as f:
    f.write('format = "naocalib-calibration"\nversion = 1\nsolver = "naocalib import"\n')
    for name, unit in units.items():
        # What the files do not hold (the sandals' mounting, the intrinsics' corrections,
        # …) is zero.
        value = float(values[name]) if name.startswith("Head") else 0.0
        if name in angles + legs:
            k = (angles + legs).index(name)
            value = float(values[name]) + (0.3 if name in angles else 0.5) * (-1) ** k
        f.write(f'\n[parameters.{name}]\nvalue = {value!r}\nstd = 0.0\nunit = "{unit}"\n')
EOF
}

echo "sandal $sandal, cameras $cameras: plan around each robot's files"
printf '%-5s %8s %8s %8s %8s %10s %8s %8s %s\n' \
    seed planned visible found dropped "worst px" "RMS z" "max |z|" families
for seed in "${seeds[@]}"; do
    drawn=(--board "$config" --team-offsets --seed "$seed" "${sim_flags[@]}")
    "$naocalib" simulate "$work/drawn-$seed" "${drawn[@]}" --stances 1 --heads 1 >/dev/null
    files "$work/drawn-$seed/truth.toml" "$work/files-$seed.toml"
    "$naocalib" plan "$work/plan-$seed.csv" --camera "$config" "${plan_flags[@]}" \
        --around "$work/files-$seed.toml" >"$work/plan-$seed.txt"
    planned=$(grep -o '[0-9]* of [0-9]* planned vertices have their window in plain sight' \
        "$work/plan-$seed.txt" | cut -d' ' -f1)
    robot=(--stance-file "$work/plan-$seed.csv" --truth "$work/drawn-$seed/truth.toml"
        --board "$config" --joint-noise-deg 0.1 --seed "$seed")
    # The same robot, stances and joint noise twice: its pictures, and its true vertices.
    "$naocalib" simulate "$work/images-$seed" "${robot[@]}" --body --images >/dev/null
    "$naocalib" simulate "$work/truth-$seed" "${robot[@]}" --body --px-noise 0 >/dev/null
    # Where every vertex in the image truly is, hidden or not.
    "$naocalib" simulate "$work/all-$seed" "${robot[@]}" --px-noise 0 >/dev/null
    detected=$("$naocalib" detect "$work/images-$seed" --body \
        --start-from "$work/files-$seed.toml" 2>&1 | tail -1)
    dropped=$(grep -o '[0-9]* vertices dropped' <<<"$detected" | cut -d' ' -f1)
    "$naocalib" solve "$work/images-$seed" "${solve_flags[@]}" --json \
        --start-from "$work/files-$seed.toml" \
        >"$work/fit-$seed.json" 2>/dev/null || true
    python3 - "$work/all-$seed" "$work/truth-$seed" "$work/images-$seed" \
        "$work/fit-$seed.json" "$seed" "$planned" "${dropped:-0}" <<'EOF'
import csv, json, math, sys
all_dir, truth_dir, found_dir, fit, seed, planned, dropped = sys.argv[1:]
def corners(d):
    return {(r["capture"], r["row"], r["col"]): (float(r["u"]), float(r["v"]))
            for r in csv.DictReader(open(d + "/corners.csv"))}
every, truth, found = corners(all_dir), corners(truth_dir), corners(found_dir)
stray = [k for k in found if k not in truth]
worst = max((math.dist(found[k], every[k]) for k in found), default=0.0)
run = json.load(open(fit))
z = [(p["value"] - p["truth"]) / p["std"] for p in run["parameters"].values()
     if (p.get("std") or 0) > 0 and p.get("truth") is not None]
rms = math.sqrt(sum(x * x for x in z) / len(z))
print(f"{seed:<5} {planned:>8} {len(truth):>8} {len(found):>8} {dropped:>8} {worst:>10.3f} "
      f"{rms:>8.2f} {max(map(abs, z)):>8.2f} {','.join(run['families'])}"
      + (f"  ({len(stray)} found whose window the body covers, worst "
         f"{max(math.dist(found[k], every[k]) for k in stray):.3f} px)" if stray else ""))
EOF
done
