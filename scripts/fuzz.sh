#!/usr/bin/env bash
# Fuzz meso's loaders with libFuzzer (clang, ASan + UBSan + float-cast-overflow):
#   scripts/fuzz.sh SECONDS [png|scene|mesh|bake|environment ...]   (default: all, SECONDS each)
# Builds build-fuzz/ (BUILD_FUZZ overrides), runs each target on its kept corpus
# tests/fuzz/corpus/<target>/, then merges the inputs that found new coverage into it. A crash
# is written to tests/fuzz/crashes/<target>/: fix it, then move the file into the corpus,
# where `make test` replays it (fuzz_corpus_<target>) in every build.
set -euo pipefail
seconds=${1:?usage: scripts/fuzz.sh SECONDS [png|scene|mesh|bake|environment ...]}
shift
targets=("$@")
[ ${#targets[@]} -gt 0 ] || targets=(png scene mesh bake environment)
root=$(cd "$(dirname "$0")/.." && pwd)
build=${BUILD_FUZZ:-$root/build-fuzz}

# libFuzzer comes with clang (Debian's package); `make test` replays the corpus without it.
if ! command -v "${CC:-clang}" >/dev/null; then
    sudo=""
    [ "$(id -u)" -eq 0 ] || sudo="sudo"
    echo "fuzz.sh: installing clang (libFuzzer)" >&2
    DEBIAN_FRONTEND=noninteractive $sudo apt-get install -y -qq --no-install-recommends clang >/dev/null
fi

CC=${CC:-clang} cmake -S "$root" -B "$build" -DCMAKE_BUILD_TYPE=RelWithDebInfo \
    -DMESO_FUZZ=ON -DMESO_SANITIZE=ON -DMESO_NATIVE=OFF >/dev/null
cmake --build "$build" -j "${JOBS:-2}" --target $(printf 'fuzz_%s ' "${targets[@]}")

# Leaks do not stop the run (a leak found by chance would end a target at once); every kept
# input and every new one is replayed with LeakSanitizer at the end instead.
export ASAN_OPTIONS=${ASAN_OPTIONS:-detect_leaks=0:abort_on_error=1}
export UBSAN_OPTIONS=${UBSAN_OPTIONS:-print_stacktrace=1:halt_on_error=1}
export MESO_CACHE_DIR=off TMPDIR=$build
status=0
for target in "${targets[@]}"; do
    corpus=$root/tests/fuzz/corpus/$target
    found=$build/found/$target
    crashes=$root/tests/fuzz/crashes/$target
    mkdir -p "$found" "$crashes"
    echo "fuzz_$target: $seconds s on $(ls "$corpus" | wc -l) kept inputs"
    "$build/fuzz_$target" -max_total_time="$seconds" -timeout=30 -rss_limit_mb=2048 \
        -max_len=65536 -artifact_prefix="$crashes/" "$found" "$corpus" || status=1
    # keep only what adds coverage
    "$build/fuzz_$target" -merge=1 "$corpus" "$found" >/dev/null 2>&1 || true
    rmdir "$crashes" 2>/dev/null || echo "fuzz_$target: crashes in $crashes"
    # every input kept or found, once more with LeakSanitizer (one process per 500 inputs)
    leaks=0
    : >"$build/leaks-$target.log"
    while read -r batch; do
        # shellcheck disable=SC2086
        ASAN_OPTIONS=detect_leaks=1:abort_on_error=1 "$build/fuzz_$target" -runs=0 $batch \
            >>"$build/leaks-$target.log" 2>&1 || { leaks=1; status=1; }
    done < <(find "$corpus" "$found" -type f | xargs -n 500 echo)
    [ $leaks -eq 0 ] && echo "fuzz_$target: no leak in $(find "$corpus" "$found" -type f | wc -l) inputs" ||
        echo "fuzz_$target: LeakSanitizer report in $build/leaks-$target.log"
done
exit $status
