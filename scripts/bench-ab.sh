#!/usr/bin/env bash
# A/B of two meso binaries on a noisy machine: ROUNDS rounds of `meso bench`, the two binaries
# alternating inside each round (so slow drifts of the host hit both alike), then one table of
# the medians over the rounds (scripts/bench_ab.py; docs/performance.md, "Comparing two builds").
#   scripts/bench-ab.sh [-r ROUNDS] [-o OUTDIR] BASE_MESO NEW_MESO [-- BENCH ARGS...]
# e.g. scripts/bench-ab.sh -r 5 /tmp/meso-main build-native/meso -- examples/bricks-plane.json \
#          --techniques relief,relief_exact --frames 15
# Without bench arguments every example x technique is timed with 15 frames a run.
set -euo pipefail
rounds=3
out=
while getopts "r:o:h" opt; do
    case $opt in
    r) rounds=$OPTARG ;;
    o) out=$OPTARG ;;
    *) sed -n '2,8p' "$0" | sed 's/^# \{0,1\}//'; exit 2 ;;
    esac
done
shift $((OPTIND - 1))
if [ $# -lt 2 ]; then sed -n '2,8p' "$0" | sed 's/^# \{0,1\}//' >&2; exit 2; fi
base=$(realpath "$1") new=$(realpath "$2")
shift 2
[ "${1:-}" = "--" ] && shift
args=("$@")
[ ${#args[@]} -gt 0 ] || args=(--frames 15)
case $rounds in '' | *[!0-9]* | 0) echo "bench-ab.sh: -r $rounds: not a positive count" >&2; exit 2 ;; esac
for bin in "$base" "$new"; do
    [ -x "$bin" ] || { echo "bench-ab.sh: $bin: not an executable" >&2; exit 2; }
done
out=${out:-$(mktemp -d "${TMPDIR:-/tmp}/bench-ab.XXXXXX")}
mkdir -p "$out"
cd "$(dirname "$0")/.."
for r in $(seq 1 "$rounds"); do
    for side in base new; do
        bin=$base
        [ $side = new ] && bin=$new
        echo "bench-ab.sh: round $r of $rounds, $side (load $(cut -d' ' -f1 /proc/loadavg))" >&2
        "$bin" bench "${args[@]}" --quiet --json "$out/$side-$r.json" >/dev/null
    done
done
python3 scripts/bench_ab.py "$out"
echo "bench-ab.sh: the runs' JSON files are in $out" >&2
