#!/usr/bin/env bash
# The figures of docs/scale-out.md for a sweep file (default examples/sweeps/examples-256.json):
#   1. cold cache: 3 shards started at once, each entry's bakes counted in their logs;
#   2. warm cache: one process; the 3 shards one after another and the merge (the overhead of
#      sharding: references and scenes loaded again per shard, the merge's copies);
#   3. warm cache: the 3 shards as a job array on a one-node Slurm cluster
#      (scripts/slurm/local-cluster.sh, 2 CPUs, one CPU a task) and the dependent merge.
# Wall and CPU seconds from /usr/bin/time; everything under a temporary folder (kept: its path
# is printed).
#
# usage: scripts/measure-sweep.sh [SPEC.json] [path/to/meso]
set -euo pipefail
here=$(cd "$(dirname "$0")/.." && pwd)
spec=$(realpath "${1:-$here/examples/sweeps/examples-256.json}")
meso=$(realpath "${2:-$here/build/meso}")
work=$(mktemp -d /tmp/meso-measure.XXXXXX)
export MESO_CACHE_DIR=$work/cache MESO=$meso
echo "measure-sweep: $spec in $work; $("$meso" sweep "$spec" --list | tail -n +2 | wc -l) jobs"
timed() { # label command...: wall and CPU seconds of the command
    local label=$1
    shift
    /usr/bin/time -f "$label: wall %e s, user %U s, system %S s" -a -o "$work/times.txt" "$@"
}

# 1. cold cache, 3 shards at once
start=$(date +%s.%N)
for k in 0 1 2; do
    timed "cold shard $k/3" "$meso" sweep "$spec" -o "$work/cold" --shard $k/3 --verbose \
        >"$work/cold-$k.log" 2>&1 &
done
wait
timed "cold merge" "$meso" sweep --merge "$work/cold" --quiet
echo "cold, 3 shards at once + merge: wall $(awk -v s="$start" -v e="$(date +%s.%N)" "BEGIN {printf \"%.1f\", e - s}") s" >>"$work/times.txt"
grep -h 'bake cache: stored' "$work"/cold-*.log | sed 's/.*stored //' | sort | uniq -c |
    awk '{n++; b += $1; if ($1 > 1) d += $1 - 1} END {printf "cold cache: %d bakes stored for %d entries (%d duplicates)\n", b, n, d}' \
        >>"$work/times.txt"

# 2. warm: one process, then the shards one after another and the merge
timed "warm single process" "$meso" sweep "$spec" -o "$work/single" --quiet
for k in 0 1 2; do
    timed "warm shard $k/3 alone" "$meso" sweep "$spec" -o "$work/sequential" --shard $k/3 --quiet
done
timed "warm merge" "$meso" sweep --merge "$work/sequential" --quiet

# 3. warm: the job array on a local Slurm cluster
source "$here/scripts/slurm/local-cluster.sh"
mkdir -p "$work/slurm"
trap 'cluster_stop' EXIT INT TERM
if cluster_start "$work/slurm"; then
    cd "$work"
    start=$(date +%s.%N)
    array=$(sbatch --parsable --array=0-2 "$here/scripts/slurm/sweep.sbatch" "$spec" "$work/array" 3)
    merge=$(sbatch --parsable --dependency=afterok:"$array" "$here/scripts/slurm/sweep.sbatch" \
        "$spec" "$work/array" 3)
    cluster_wait 7200 "$array" "$merge"
    echo "slurm, 3-task array (2 CPUs) + merge: wall $(awk -v s="$start" -v e="$(date +%s.%N)" "BEGIN {printf \"%.1f\", e - s}") s" \
        >>"$work/times.txt"
else
    echo "slurm: not measured: $cluster_error" >>"$work/times.txt"
fi
cat "$work/times.txt"
