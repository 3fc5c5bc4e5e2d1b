#!/usr/bin/env bash
# Fuzz the readers of user input with libFuzzer (fuzz/README.md): .mci and .mco files, experiment
# configs, scene files and OBJ meshes. Builds build/fuzz with Clang (AddressSanitizer,
# UndefinedBehaviorSanitizer, coverage from all of ssslab), or the targets in a given build
# configured with -DSSSLAB_BUILD_FUZZERS=ON (CI: the ASan build, its coverage the readers'
# alone, -DSSSLAB_FUZZ_COVERAGE=readers), then runs each target for the given
# seconds from its committed seeds (fuzz/corpus/<target>) and the inputs found so far
# (results/fuzz/<target>/corpus, not committed). A failing input is written to
# results/fuzz/<target>/ and the script exits non-zero: copy it to fuzz/regressions/<target>/
# once fixed, so that the tests replay it forever.
#
#   scripts/fuzz.sh [--build DIR] [seconds per target] [targets...]
#                                   default build/fuzz, 60 s, every target
set -euo pipefail
cd "$(dirname "$0")/.."
build=build/fuzz
if [[ "${1:-}" == "--build" ]]; then
  build="${2:?fuzz: --build needs a build folder}"
  shift 2
  grep -q '^SSSLAB_BUILD_FUZZERS:BOOL=ON' "$build/CMakeCache.txt" 2>/dev/null ||
    { echo "fuzz: $build is not configured with -DSSSLAB_BUILD_FUZZERS=ON" >&2; exit 2; }
fi
seconds="${1:-60}"
[[ $# -gt 0 ]] && shift
targets=("$@")
[[ ${#targets[@]} -eq 0 ]] && targets=(mci mco config scene obj)
command -v clang++ >/dev/null || { echo "fuzz: needs clang (scripts/setup.sh --dev)" >&2; exit 2; }

generator=()
command -v ninja >/dev/null 2>&1 && generator=(-G Ninja)
if [[ "$build" == build/fuzz && ! -f build/fuzz/CMakeCache.txt ]]; then
  CC=clang CXX=clang++ cmake -S . -B build/fuzz "${generator[@]}" -DCMAKE_BUILD_TYPE=Release \
    -DCMAKE_CXX_FLAGS=-g1 -DSSSLAB_SANITIZE=address,undefined -DSSSLAB_BUILD_FUZZERS=ON \
    -DSSSLAB_BUILD_TESTS=OFF -DSSSLAB_BUILD_BENCHMARKS=OFF -DSSSLAB_WITH_MPI=OFF -DSSSLAB_WITH_PYTHON=OFF \
    -DSSSLAB_WITH_GL=OFF
fi
cmake --build "$build" -j "$(nproc)" $(printf -- '--target fuzz_%s ' "${targets[@]}")

# The targets run side by side, as many at a time as there are cores (each fuzzer is one
# process), each for the given seconds; their results are printed in order once all are done.
run_target() {
  local t="$1" out="results/fuzz/$1"
  mkdir -p "$out/corpus"
  if ASAN_OPTIONS=detect_leaks=1:abort_on_error=1 UBSAN_OPTIONS=print_stacktrace=1:halt_on_error=1 \
      LSAN_OPTIONS=suppressions=$PWD/tests/lsan.supp \
      "$build/fuzz/fuzz_$t" "$out/corpus" "fuzz/corpus/$t" \
      -max_total_time="$seconds" -timeout=10 -rss_limit_mb=2048 -malloc_limit_mb=1024 \
      -max_len=16384 -artifact_prefix="$out/" -print_final_stats=1 2> "$out/log.txt"; then
    echo 0 > "$out/status"
  else
    echo 1 > "$out/status"
  fi
}
cores=$(nproc)
for t in "${targets[@]}"; do
  rm -f "results/fuzz/$t/status"
  while (( $(jobs -rp | wc -l) >= cores )); do wait -n || true; done
  run_target "$t" &
done
wait

failed=0
for t in "${targets[@]}"; do
  out="results/fuzz/$t"
  echo "== fuzz_$t: $seconds s"
  if [[ "$(cat "$out/status" 2>/dev/null)" != "0" ]]; then
    failed=1
    tail -60 "$out/log.txt"
    echo "fuzz_$t FAILED: the input is in $out/ (crash-*, timeout-*, oom-*)"
  else
    grep -E "^stat::number_of_executed_units|^stat::new_units_added" "$out/log.txt" | tr '\n' ' '
    echo
  fi
done
exit $failed
