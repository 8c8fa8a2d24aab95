#!/usr/bin/env bash
# Record, then check, that naocalib's commands give the same calibration on the bundled
# sample and on N simulated datasets (with and without upper captures, with realistic
# effects and `--model auto`) with a variety of options:
#
# - `solve` (JSON and text) on every dataset; `--export`, `--report` and `--plots` on a
#   subset; `--start-from` a calibration imported from team files;
# - `batch` (text, `--json`, `--out`, `--report`) over all datasets and over subsets with
#   options (compliance and play freed, drift against the first run of one robot);
# - `compare` (text and JSON) on the subset;
# - `export` (`--dir`, every format; `--out` TOML, standing and lying) of recorded results;
# - `import` of the exported team files.
#
#   scripts/same-outputs.sh record DIR [N]   # before a change: datasets and outputs into DIR
#   scripts/same-outputs.sh check DIR        # after it: the same commands, compared
#
# `check` compares with scripts/compare_outputs.py (python3): every value within 1e-9 of
# its magnitude (or 1e-12 absolute), every σ and test statistic within 1e-6 relative, the
# same parameters determined and held, the same diagnosis, stderr and exit status; printed
# numbers to their last digit. It says where the largest differences are (file, key, both
# values) and exits non-zero when anything is beyond them. Wall times are left out.
#
# Uses target/release/naocalib (build it first: cargo build --release), or $NAOCALIB.
set -euo pipefail
mode=${1:?record or check}
dir=${2:?directory for datasets and outputs}
n=${3:-100}
bin=${NAOCALIB:-$(cd "$(dirname "$0")/.." && pwd)/target/release/naocalib}
repo=$(cd "$(dirname "$0")/.." && pwd)
dir=$(mkdir -p "$dir" && cd "$dir" && pwd)

# The solve options of case `seed mod 10`, and whether its dataset has realistic effects.
options() {
    case $(($1 % 10)) in
    0) echo "" ;;
    1) echo "--model auto" ;;
    2) echo "--loss huber" ;;
    3) echo "--loss cauchy:2" ;;
    4) echo "--bootstrap 20" ;;
    5) echo "--solver lm" ;;
    6) echo "--solver tiny" ;;
    7) echo "--plain-std" ;;
    8) echo "--free compliance,play --px-noise 0.1" ;;
    9) echo "--model auto --fix CamYaw --loss huber" ;;
    esac
}
effects() {
    case $(($1 % 10)) in
    1 | 8 | 9) echo "--effects realistic" ;;
    *) echo "" ;;
    esac
}
# Upper captures on every third dataset.
upper() {
    [ $(($1 % 3)) = 0 ] && echo "--upper-stances $((4 + $1 % 5))" || true
}

case $mode in
record)
    mkdir -p "$dir/data" "$dir/out"
    rm -f "$dir/cases"
    for seed in $(seq 1 "$n"); do
        d=$dir/data/s$seed
        # shellcheck disable=SC2046
        "$bin" simulate --seed "$seed" --joint-noise-deg 0.1 --stances $((12 + seed % 13)) \
            $(effects "$seed") $(upper "$seed") --force "$d" >/dev/null
        if [ $((seed % 10)) = 2 ] || [ $((seed % 10)) = 3 ] || [ $((seed % 10)) = 9 ]; then
            # a few gross outliers for the robust fits
            awk -F, -v OFS=, 'NR > 1 && NR % 97 == 0 { $4 += 25 } { print }' "$d/corners.csv" >"$d/c" &&
                mv "$d/c" "$d/corners.csv"
        fi
        echo "$seed $(options "$seed")" >>"$dir/cases"
    done
    ;;
check) ;;
*)
    echo "mode: record or check" >&2
    exit 2
    ;;
esac

out=$dir/out
[ "$mode" = check ] && out=$dir/out.check
rm -rf "$out.tmp"
if [ "$mode" = check ]; then rm -rf "$out"; fi
mkdir -p "$out"
save=$dir/out
data=$dir/data
# Outputs are named relative to $out, so that what the commands print of them is the same
# in both modes.
cd "$out"

# One command: stdout into NAME, stderr and the exit code into NAME.err.
run() { # NAME ARGS...
    local name=$1 code=0
    shift
    "$bin" "$@" >"$name" 2>"$name.err" || code=$?
    echo "exit $code" >>"$name.err"
}
# `solve` as JSON and as text.
solve() { # NAME DATASET OPTIONS...
    local name=$1 d=$2
    shift 2
    run "$name.json" solve "$d" --json "$@"
    run "$name.txt" solve "$d" "$@"
}
# The subset for the slower commands: cases 0 and 8 (plain, and compliance and play freed).
subset=$(awk '$1 % 10 == 0 || $1 % 10 == 8 { print $1 }' "$dir/cases")

solve sample "$repo/data/sample"
while read -r seed opts; do
    # shellcheck disable=SC2086
    solve "s$seed" "$data/s$seed" $opts
done <"$dir/cases"

# solve's files: calibration files, the HTML report, plots.
run solve-files-sample.txt solve "$repo/data/sample" --export solve-files-sample.export \
    --report solve-files-sample.html --plots solve-files-sample.plots
for seed in $subset; do
    # shellcheck disable=SC2046
    run "solve-files-s$seed.txt" solve "$data/s$seed" $(options "$seed") \
        --export "solve-files-s$seed.export" --report "solve-files-s$seed.html"
done

# batch: everything; the subset with options; drift of one robot against its first run.
batch() { # NAME ARGS...
    local name=$1
    shift
    run "$name.txt" batch "$@"
    run "$name.json" batch --json "$@"
}
# (--force: the text and the JSON run write the same files.)
batch batch-all "$data" "$repo/data/sample" --out batch-all.out --force --no-progress
# shellcheck disable=SC2046
batch batch-effects $(for s in $subset; do echo "$data/s$s"; done) \
    --free compliance,play --solver lm --report batch-effects.html --force --no-progress
# shellcheck disable=SC2046
batch batch-drift $(for s in $(seq 1 5); do echo "$data/s$s"; done) --robots all \
    --drift first --drift-threshold 2 --plain-std --report batch-drift.html --force \
    --no-progress

# compare, every solver of this build.
run compare-sample.txt compare "$repo/data/sample"
run compare-sample.json compare "$repo/data/sample" --json
for seed in $subset; do
    run "compare-s$seed.txt" compare "$data/s$seed"
    run "compare-s$seed.json" compare "$data/s$seed" --json --loss huber
done

# export of the recorded results (the same input before and after), and import of the
# team files it wrote; then a solve starting from that import.
for name in sample $(for s in $subset; do echo "s$s"; done); do
    run "export-$name.txt" export "$save/$name.json" --dir "export-$name.dir"
    run "export-$name.lying.txt" export "$save/$name.json" --posture lying \
        --out "export-$name.lying.toml" --out "export-$name.bhuman-joints.cfg"
    run "import-$name.txt" import "export-$name.dir/cameraCalibration.cfg" \
        "export-$name.dir/jointCalibration.cfg" --out "import-$name.toml"
    run "import-$name.nomadz.txt" import "export-$name.dir/nomadz/cameraCalibration.cfg" \
        "export-$name.dir/nomadz/jointCalibration.cfg" --out "import-$name.nomadz.json"
done
for seed in $subset; do
    # shellcheck disable=SC2046
    solve "start-s$seed" "$data/s$seed" $(options "$seed") --start-from "import-s$seed.toml"
done

if [ "$mode" = check ]; then
    python3 "$repo/scripts/compare_outputs.py" "$save" "$out"
fi
