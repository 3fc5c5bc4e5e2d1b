#!/usr/bin/env bash
# Configure and build ssslab in build/<type> (default: release). Extra arguments go to CMake.
#   scripts/build.sh                    optimised build in build/release
#   scripts/build.sh asan               AddressSanitizer + UBSan build in build/asan
set -euo pipefail
cd "$(dirname "$0")/.."
kind="${1:-release}"
[[ $# -gt 0 ]] && shift
generator=()
command -v ninja >/dev/null 2>&1 && generator=(-G Ninja)
case "$kind" in
  release) flags=(-DCMAKE_BUILD_TYPE=Release) ;;
  debug)   flags=(-DCMAKE_BUILD_TYPE=Debug) ;;
  # The sanitizer builds leave MPI out: Open MPI's own allocations would read as leaks.
  asan)    flags=(-DCMAKE_BUILD_TYPE=RelWithDebInfo -DSSSLAB_SANITIZE=address,undefined -DSSSLAB_BUILD_BENCHMARKS=OFF -DSSSLAB_WITH_MPI=OFF) ;;
  *) echo "usage: $0 [release|debug|asan] [cmake args...]" >&2; exit 2 ;;
esac
if [[ ! -f "build/$kind/CMakeCache.txt" ]]; then
  cmake -S . -B "build/$kind" "${generator[@]}" "${flags[@]}" "$@"
fi
cmake --build "build/$kind" -j "$(nproc)"
