#!/usr/bin/env bash
# Configure and build ssslab in build/<type> (default: release). Extra arguments go to CMake.
#   scripts/build.sh                    optimised build in build/release
#   scripts/build.sh asan               AddressSanitizer + UBSan build in build/asan (Clang)
#   scripts/build.sh tsan               ThreadSanitizer build in build/tsan (line tables only)
set -euo pipefail
cd "$(dirname "$0")/.."
kind="${1:-release}"
[[ $# -gt 0 ]] && shift
generator=()
command -v ninja >/dev/null 2>&1 && generator=(-G Ninja)
case "$kind" in
  release) flags=(-DCMAKE_BUILD_TYPE=Release) ;;
  debug)   flags=(-DCMAKE_BUILD_TYPE=Debug) ;;
  # The sanitizer builds leave MPI out (Open MPI's own allocations would read as leaks) and the
  # Python module (an uninstrumented interpreter would have to preload the sanitizer runtime).
  # Line tables only (-g1): the reports' stack traces keep their file:line, and the build (CI's
  # largest step) takes a third less time than with full debug information. Built with Clang
  # (scripts/setup.sh --dev): measured on two cores, 7 min from scratch against GCC 12's 17.5 min
  # with the same flags; the release build stays GCC's, so CI compiles with both.
  asan)    command -v clang++ >/dev/null || { echo "build.sh asan: needs Clang (scripts/setup.sh --dev)" >&2; exit 2; }
           export CC=clang CXX=clang++
           flags=(-DCMAKE_BUILD_TYPE=RelWithDebInfo "-DCMAKE_CXX_FLAGS_RELWITHDEBINFO=-O2 -g1 -DNDEBUG" -DSSSLAB_SANITIZE=address,undefined -DSSSLAB_BUILD_BENCHMARKS=OFF -DSSSLAB_WITH_MPI=OFF -DSSSLAB_WITH_PYTHON=OFF) ;;
  # ThreadSanitizer: the threaded engines' races (tests labelled tsan run in it in CI).
  # Linked with oneTBB built with TSan (scripts/tbb_tsan.sh), found first through the run path.
  tsan)    bash scripts/tbb_tsan.sh
           flags=(-DCMAKE_BUILD_TYPE=Release -DCMAKE_CXX_FLAGS=-g1 -DSSSLAB_SANITIZE=thread -DSSSLAB_BUILD_BENCHMARKS=OFF -DSSSLAB_WITH_MPI=OFF -DSSSLAB_WITH_PYTHON=OFF
                  -DTBB_DIR="$PWD/build/tbb-tsan/install/lib/cmake/TBB") ;;
  *) echo "usage: $0 [release|debug|asan|tsan] [cmake args...]" >&2; exit 2 ;;
esac
# Configured unless a configure already finished (one that failed leaves a cache but no build
# files: it is run again, so that a fixed setup is picked up).
if [[ ! -f "build/$kind/CMakeCache.txt" || ( ! -f "build/$kind/build.ninja" && ! -f "build/$kind/Makefile" ) ]]; then
  cmake -S . -B "build/$kind" "${generator[@]}" "${flags[@]}" "$@"
fi
# SSSLAB_TARGETS="a b": build those targets only (CI's ThreadSanitizer build: the threaded tests).
targets=()
for t in ${SSSLAB_TARGETS:-}; do targets+=(--target "$t"); done
cmake --build "build/$kind" -j "$(nproc)" "${targets[@]}"
