#!/usr/bin/env bash
# make test-slurm (docs/scale-out.md): a real one-node Slurm cluster on this machine (Debian's
# munge, slurmctld and slurmd, a generated slurm.conf in a temporary folder: localhost, 2 CPUs)
# runs a sweep of 24+ jobs as a job array of 3 shards and a dependent merge job; the merged
# results must equal a single-process sweep's (every image byte-identical, every metric column
# equal; timing columns excepted). Then one shard is cancelled mid-way (scancel) and submitted
# again, and the same checks pass, with no temporary file left in the cache or the output.
# Every daemon started is stopped at the end, on failure too. Skipped, with a message, where
# the cluster cannot start (packages missing, not root).
#
# usage: scripts/test-slurm.sh [path/to/meso]
set -euo pipefail
here=$(cd "$(dirname "$0")/.." && pwd)
meso=$(realpath "${1:-$here/build/meso}")
skip() {
    echo "test-slurm: skipped: $*" >&2
    exit 0
}
source "$here/scripts/slurm/local-cluster.sh"
[ -x "$meso" ] || { echo "test-slurm: $meso: not built" >&2; exit 1; }

work=$(mktemp -d /tmp/meso-test-slurm.XXXXXX)
cleanup() {
    local status=$?
    cluster_stop # every daemon started, by process id
    if [ $status -ne 0 ]; then
        echo "test-slurm: FAILED; the logs:" >&2
        tail -n 20 "$work"/*.log >&2 2>/dev/null || true
    fi
    rm -rf "$work"
    exit $status
}
trap cleanup EXIT INT TERM

fail() {
    echo "test-slurm: FAILED: $*" >&2
    exit 1
}

mkdir -p "$work/cache"
cluster_start "$work" || skip "$cluster_error"
echo "test-slurm: cluster up ($SLURM_CONF)"

# ---- the sweep: 3 scenes, 26 jobs at 48x48 ----
export MESO_CACHE_DIR=$work/cache MESO=$meso
cat >"$work/spec.json" <<EOF
{
  "scenes": ["$here/examples/bricks-plane.json", "$here/examples/bumps-sphere.json",
             "$here/examples/weave-plane.json"],
  "techniques": ["flat", "bump", "parallax", "relief", "relief_layers", "vdm"],
  "options": {"relief": {"linear_steps": [4, 8, 16, 32]}, "relief_layers": {"linear_steps": [8, 16, 32]}},
  "sizes": [48],
  "frames": 1
}
EOF
jobs=$("$meso" sweep "$work/spec.json" --list | tail -n +2 | wc -l)
echo "test-slurm: $jobs jobs"
sbatch_script=$here/scripts/slurm/sweep.sbatch

wait_for() { # job ids...: until none is pending or running (at most 10 minutes)
    cluster_wait 600 "$@" || fail "jobs $* still running after 10 minutes"
}

# The merged folder against the single process's.
check_same() {
    local dir=$1
    [ -f "$dir/results.csv" ] || fail "$dir/results.csv: missing (merge did not run)"
    python3 - "$work/single/results.csv" "$dir/results.csv" <<'EOF' || fail "$dir: results differ"
import csv, sys
timing = {"prepare_ms", "frame_ms", "reference_ms", "job_s"}
a = list(csv.DictReader(open(sys.argv[1])))
b = list(csv.DictReader(open(sys.argv[2])))
assert len(a) == len(b) and len(a) >= 24, (len(a), len(b))
for x, y in zip(a, b):
    for k in x:
        if k not in timing and x[k] != y[k]:
            sys.exit(f"job {x['id']}: {k}: {x[k]} != {y[k]}")
assert all(x["status"] == "ok" and x["psnr_covered_db"] for x in a), "a job without metrics"
EOF
    local images=0
    while IFS= read -r f; do
        cmp -s "$work/single/$f" "$dir/$f" || fail "$dir/$f differs from the single process's"
        images=$((images + 1))
    done < <(cd "$work/single" && find jobs refs -name '*.png' | sort)
    [ "$images" -ge "$jobs" ] || fail "only $images images"
    local theirs
    theirs=$(cd "$dir" && find jobs refs -name '*.png' | wc -l)
    [ "$theirs" -eq "$images" ] || fail "$dir has $theirs images, the single process $images"
    if find "$dir" "$MESO_CACHE_DIR" -name '*.tmp*' | grep -q .; then
        fail "temporary files left: $(find "$dir" "$MESO_CACHE_DIR" -name '*.tmp*' | head -3)"
    fi
    echo "test-slurm: $dir: $images images byte-identical, metrics equal, no temporary file"
}

# ---- 1. the array and the dependent merge ----
cd "$work"
array=$(sbatch --parsable --array=0-2 "$sbatch_script" "$work/spec.json" "$work/out" 3)
merge=$(sbatch --parsable --dependency=afterok:"$array" "$sbatch_script" "$work/spec.json" "$work/out" 3)
wait_for "$array" "$merge"
# The shards started at once on a cold cache: how many times each entry was baked and stored
# (atomically: a second store of an entry replaces it with the same bytes).
stores=$(cat "$work"/meso-sweep-"$array"_*.log | grep 'bake cache: stored' || true)
entries=$(echo "$stores" | grep -c . || true)
unique=$(echo "$stores" | sed 's/.*stored //' | sort -u | grep -c . || true)
echo "test-slurm: cold cache, 3 shards at once: $entries bakes stored for $unique entries"
"$meso" sweep "$work/spec.json" -o "$work/single" --quiet
check_same "$work/out"

# ---- 2. a shard cancelled mid-way, submitted again ----
# the shard with the most jobs, cancelled once it has finished one of them and not all
victim=0 mine=0
for k in 0 1 2; do
    count=$("$meso" sweep "$work/spec.json" --list --shard $k/3 | tail -n +2 | wc -l)
    if [ "$count" -gt "$mine" ]; then victim=$k mine=$count; fi
done
[ "$mine" -ge 2 ] || fail "no shard has 2 jobs to cancel one mid-way"
array=$(sbatch --parsable --array=0-2 "$sbatch_script" "$work/spec.json" "$work/out2" 3)
cancelled=0
for _ in $(seq 3000); do
    done_jobs=$( (find "$work/out2/shards/$victim/jobs" -name result.json 2>/dev/null || true) | wc -l)
    if [ "$done_jobs" -ge 1 ]; then
        # stopped at once (SIGSTOP), so the shard cannot finish while the cancel travels
        scontrol suspend "${array}_$victim" || true
        scancel "${array}_$victim" || true
        cancelled=1
        break
    fi
    sleep 0.02
done
[ $cancelled -eq 1 ] || fail "shard $victim never finished a job"
wait_for "$array"
state=$(scontrol -o show job "${array}_$victim" | grep -o 'JobState=[A-Z_]*')
finished=$(find "$work/out2/shards/$victim/jobs" -name result.json | wc -l)
echo "test-slurm: shard $victim $state after $finished of its $mine jobs"
[ "$state" = "JobState=CANCELLED" ] || fail "shard $victim was not cancelled ($state)"
[ "$finished" -lt "$mine" ] || fail "shard $victim finished before it was cancelled: no test of the rerun"
again=$(sbatch --parsable --array=$victim "$sbatch_script" "$work/spec.json" "$work/out2" 3)
merge=$(sbatch --parsable --dependency=afterok:"$again" "$sbatch_script" "$work/spec.json" "$work/out2" 3)
wait_for "$again" "$merge"
grep -q "$finished already done" "$work"/meso-sweep-"$again"_$victim.log ||
    fail "the rerun of shard $victim did not skip its $finished finished jobs: $(head -n 3 "$work"/meso-sweep-"$again"_$victim.log)"
check_same "$work/out2"
echo "test-slurm: passed"
