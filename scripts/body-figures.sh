#!/usr/bin/env bash
# The robot in its own pictures, measured as a team would meet it: a plan made past the
# body (`plan --sight`), photographed by simulated robots with team-sized hidden offsets
# whose pictures draw their bodies (`simulate --images --body --team-offsets`), the
# vertices found by `detect --body`, and the fit `solve --model auto`. Per robot it prints
# the planned vertices (in plain sight past the body, as `plan` predicts them at zero),
# the vertices the body as it is leaves in sight (the simulator's truth), the vertices
# found, the worst distance of a found vertex from the truth (any found vertex whose window
# the body covers is named), and the RMS and largest err/σ of the fitted parameters.
# docs/PERFORMANCE.md ("The robot in its own pictures") quotes its output.
#
#   scripts/body-figures.sh [SANDAL] [CAMERAS] [SEEDS...]
#
# SANDAL: paper (7 × 5 squares centred 170 mm ahead of the ankle) or turned (the same
# board turned by 90°, centred 200 mm ahead); CAMERAS: lower, both (an upper camera with
# the lower one's intrinsics) or intrinsics (both, their intrinsics free: plan
# --families paper,intrinsics, robots with intrinsics offsets, solve --model auto
# --free intrinsics).
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

# The camera and sandal: the simulator's V4 camera (`simulate`'s dataset.toml).
"$naocalib" simulate "$work/base" --stances 1 --heads 1 >/dev/null
config=$work/config.toml
case $sandal in
paper) cp "$work/base/dataset.toml" "$config" ;;
turned)
    sed -e 's/^mount_origin_mm = .*/mount_origin_mm = [200.0, 0.0, 0.0]/' \
        -e 's/^mount_rpy_deg = .*/mount_rpy_deg = [0.0, 0.0, 90.0]/' \
        "$work/base/dataset.toml" >"$config"
    ;;
*) echo "unknown sandal '$sandal' (paper, turned)" >&2; exit 2 ;;
esac
plan_flags=(--sight)
sim_flags=()
solve_flags=(--model auto)
case $cameras in
lower) ;;
both | intrinsics)
    # The [upper_camera] with the lower one's intrinsics, as the simulator's V6 has.
    sed -n '/^\[camera\]/,/^$/p' "$config" | sed 's/^\[camera\]/[upper_camera]/' >>"$config"
    if [ "$cameras" = intrinsics ]; then
        plan_flags+=(--families paper,intrinsics)
        sim_flags+=(--effects intrinsics)
        solve_flags+=(--free intrinsics)
    fi
    ;;
*) echo "unknown cameras '$cameras' (lower, both, intrinsics)" >&2; exit 2 ;;
esac

"$naocalib" plan "$work/plan.csv" --camera "$config" "${plan_flags[@]}" >"$work/plan.txt"
planned=$(grep -o '[0-9]* of [0-9]* planned vertices have their window in plain sight' \
    "$work/plan.txt" | cut -d' ' -f1)
captures=$(($(wc -l <"$work/plan.csv") - 1))
echo "sandal $sandal, cameras $cameras: plan --sight of $captures captures," \
    "$planned vertices planned in plain sight past the body"
printf '%-5s %8s %8s %8s %8s %10s %8s %8s %s\n' \
    seed planned visible found dropped "worst px" "RMS z" "max |z|" families
for seed in "${seeds[@]}"; do
    robot=(--stance-file "$work/plan.csv" --board "$config" --team-offsets
        --joint-noise-deg 0.1 --seed "$seed" "${sim_flags[@]}")
    # The same robot, stances and joint noise twice: its pictures, and its true vertices.
    "$naocalib" simulate "$work/images-$seed" "${robot[@]}" --body --images >/dev/null
    "$naocalib" simulate "$work/truth-$seed" "${robot[@]}" --body --px-noise 0 >/dev/null
    # Where every vertex in the image truly is, hidden or not.
    "$naocalib" simulate "$work/all-$seed" "${robot[@]}" --px-noise 0 >/dev/null
    detected=$("$naocalib" detect "$work/images-$seed" --body 2>&1 | tail -1)
    dropped=$(grep -o '[0-9]* vertices dropped' <<<"$detected" | cut -d' ' -f1)
    "$naocalib" solve "$work/images-$seed" "${solve_flags[@]}" --json \
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
