#!/usr/bin/env bash
# The CMake package as a user outside the tree meets it: `cmake --install` build/release into
# build/package/prefix, build examples/custom_model/ against the installed tree only, and run its
# experiment (the out-of-tree "three_gaussian" model scored beside the built-in ones against
# MCML ground truth, --quick). Checks that the model's rows are there, finite and energy-
# conserving, that the plain `ssslab` refuses the model it does not know (exit 2), and that the
# installed Python module imports from the prefix alone and computes a profile.
# Needs build/release (scripts/build.sh). Exits non-zero on any failure.
set -euo pipefail
cd "$(dirname "$0")/.."
root="$PWD/build/package"
rm -rf "$root"
mkdir -p "$root"
cmake --install build/release --prefix "$root/prefix" > "$root/install.log"
generator=()
command -v ninja >/dev/null 2>&1 && generator=(-G Ninja)
cmake -S examples/custom_model -B "$root/custom_model" "${generator[@]}" \
  -DCMAKE_PREFIX_PATH="$root/prefix" > "$root/configure.log"
cmake --build "$root/custom_model" -j "$(nproc)"
"$root/custom_model/custom_model" run examples/custom_model/three_gaussian.toml --quick \
  --results "$root/results"
python3 - "$root/results/custom-three-gaussian/kernels/rank1_and_three_gaussians" <<'PY'
import csv, math, sys
d = sys.argv[1]
rows = [r for r in csv.DictReader(open(d + "/kernels.csv")) if r["label"] == "three_gaussian"]
if len(rows) != 15:
    sys.exit(f"three_gaussian: {len(rows)} kernel rows, expected 5 materials x 3 channels")
for r in rows:
    rms, l1 = float(r["kernel_rms"]), float(r["l1_error"])
    if not (math.isfinite(rms) and rms > 0 and l1 < 1e-9):
        sys.exit(f"three_gaussian {r['material']} {r['channel']}: kernel_rms {rms}, l1_error {l1}")
props = {r["label"]: r for r in csv.DictReader(open(d + "/properties.csv"))}
print("model                     kernel_rms_mean  image_rms_mean  build_s_mean")
for label, r in props.items():
    print(f"{label:26s}{float(r['kernel_rms_mean']):15.4g}{float(r['image_rms_mean']):16.4g}"
          f"{float(r['build_s_mean']):14.4g}")
PY
status=0
"$root/prefix/bin/ssslab" run examples/custom_model/three_gaussian.toml --quick --dry-run \
  2> "$root/refused.txt" || status=$?
if [[ $status -ne 2 ]] || ! grep -q 'unknown model "three_gaussian"' "$root/refused.txt"; then
  echo "the installed ssslab should refuse three_gaussian with exit 2, got $status:"
  cat "$root/refused.txt"
  exit 1
fi
# The Python module as installed (when the build has it): imported from the prefix alone, its
# libraries found through its RPATH, one profile computed.
module=$(find "$root/prefix" -name 'ssslab.cpython-*.so' | head -n 1)
if [[ -n "$(find build/release/python -maxdepth 1 -name 'ssslab.cpython-*.so' 2>/dev/null)" ]]; then
  [[ -n "$module" ]] || { echo "the build has the Python module, the install does not"; exit 1; }
  (cd "$root" && env -u LD_LIBRARY_PATH PYTHONPATH="$(dirname "$module")" /usr/bin/python3 - "$root/prefix" <<'PY'
import sys
import ssslab
if not ssslab.__file__.startswith(sys.argv[1]):
    sys.exit(f"imported {ssslab.__file__}, not the installed module")
rd, total = ssslab.diffusion_profile("dipole", ssslab.material("Skin1"), [0.01, 0.1])
print(f"installed Python module: {ssslab.__file__}, dipole R_d(0.1 cm) red {rd[0][1]:.6g}")
PY
  )
fi
echo "package check passed: examples/custom_model built against $root/prefix and ran"
