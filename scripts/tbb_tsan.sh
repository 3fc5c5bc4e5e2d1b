#!/usr/bin/env bash
# oneTBB built with ThreadSanitizer, for the TSan build (scripts/build.sh tsan). Debian's libtbb is
# not instrumented: TSan cannot see the ordering that its scheduler provides (a task spawned, a
# pipeline stage handed on) and reports every hand-over as a race. This builds the very version
# Debian installed, from Debian's source package, into build/tbb-tsan/install (same soname and
# ABI; the TSan build links it and finds it through its run path). About half a minute.
set -euo pipefail
cd "$(dirname "$0")/.."
root="$PWD/build/tbb-tsan"
[[ -f "$root/install/lib/libtbb.so.12" ]] && exit 0
version=$(dpkg-query -W -f='${source:Version}' libtbb12)
mkdir -p "$root/apt/lists/partial" "$root/apt/archives/partial" "$root/src"
# Debian's deb-src index in a private apt state, leaving the system's package lists alone.
cat > "$root/apt/sources.list" <<SRC
deb-src http://deb.debian.org/debian bookworm main
deb-src http://deb.debian.org/debian-security bookworm-security main
deb-src http://deb.debian.org/debian bookworm-updates main
SRC
apt_opts=(-o Dir::Etc::sourcelist="$root/apt/sources.list" -o Dir::Etc::sourceparts=/nonexistent
          -o Dir::State::Lists="$root/apt/lists" -o Dir::Cache::Archives="$root/apt/archives"
          -o APT::Sandbox::User=root)
apt-get "${apt_opts[@]}" update -qq
(cd "$root/src" && apt-get "${apt_opts[@]}" source --download-only -qq "onetbb=$version")
# Unpacked with Debian's patches applied.
(cd "$root/src" && dpkg-source --no-check -x onetbb_*.dsc tree > /dev/null)
src="$root/src/tree"
generator=()
command -v ninja >/dev/null 2>&1 && generator=(-G Ninja)
cmake -S "$src" -B "$root/build" "${generator[@]}" -DCMAKE_BUILD_TYPE=Release -DTBB_SANITIZE=thread \
  -DTBB_TEST=OFF -DTBB_EXAMPLES=OFF -DTBBMALLOC_BUILD=OFF -DTBB_STRICT=OFF \
  -DCMAKE_INSTALL_PREFIX="$root/install" -DCMAKE_INSTALL_LIBDIR=lib > "$root/configure.log"
cmake --build "$root/build" -j "$(nproc)" > "$root/build.log"
cmake --install "$root/build" > "$root/install.log"
echo "tbb_tsan: oneTBB $version with ThreadSanitizer in $root/install"
