#!/usr/bin/env bash
# Record, then check, that `naocalib solve` prints the same results (JSON and text) on the
# bundled sample and on N simulated datasets with a variety of options; only wall times
# (the JSON's "seconds", the text's "time …" line) are left out of the comparison; what
# it prints on stderr and its exit code are compared too.
#
#   scripts/same-outputs.sh record DIR [N]   # before a change: datasets and outputs into DIR
#   scripts/same-outputs.sh check DIR        # after it: the same commands, compared byte for byte
#
# Uses target/release/naocalib (build it first: cargo build --release), or $NAOCALIB.
set -euo pipefail
mode=${1:?record or check}
dir=${2:?directory for datasets and outputs}
n=${3:-100}
bin=${NAOCALIB:-$(cd "$(dirname "$0")/.." && pwd)/target/release/naocalib}
repo=$(cd "$(dirname "$0")/.." && pwd)

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

# The JSON without "seconds", the text without its "time" line.
strip_json() { grep -v '^  "seconds": ' "$1"; }
strip_text() { grep -v '^time ' "$1"; }

case $mode in
record)
    mkdir -p "$dir/data" "$dir/out"
    rm -f "$dir/cases"
    for seed in $(seq 1 "$n"); do
        d=$dir/data/s$seed
        # shellcheck disable=SC2046
        "$bin" simulate --seed "$seed" --joint-noise-deg 0.1 --stances $((12 + seed % 13)) \
            $(effects "$seed") --force "$d" >/dev/null
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
mkdir -p "$out"
save=$dir/out
# `solve` as JSON and as text, stdout then stderr and the exit code, into $out/NAME.*
solve() { # NAME DATASET OPTIONS...
    local name=$1 data=$2
    shift 2
    local code=0
    "$bin" solve "$data" --json "$@" >"$out/$name.json" 2>"$out/$name.json.err" || code=$?
    echo "exit $code" >>"$out/$name.json.err"
    code=0
    "$bin" solve "$data" "$@" >"$out/$name.txt" 2>"$out/$name.txt.err" || code=$?
    echo "exit $code" >>"$out/$name.txt.err"
}
solve sample "$repo/data/sample"
while read -r seed opts; do
    # shellcheck disable=SC2086
    solve "s$seed" "$dir/data/s$seed" $opts
done <"$dir/cases"

if [ "$mode" = check ]; then
    same=0 differ=0
    for f in "$save"/*; do
        g=$out/$(basename "$f")
        case $f in
        *.json) a=$(strip_json "$f") b=$(strip_json "$g") ;;
        *.txt) a=$(strip_text "$f") b=$(strip_text "$g") ;;
        *) a=$(cat "$f") b=$(cat "$g") ;;
        esac
        if [ "$a" = "$b" ]; then
            same=$((same + 1))
        else
            differ=$((differ + 1))
            echo "differs: $(basename "$f")"
        fi
    done
    echo "$same outputs identical, $differ differ (wall times left out)"
    [ "$differ" = 0 ]
fi
