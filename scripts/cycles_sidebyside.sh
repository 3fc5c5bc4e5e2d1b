#!/usr/bin/env bash
# ssslab's path tracer against Blender's Cycles on one scene (README "Ground truth against
# Cycles"): the scene is exported (meshes + scene.json), rendered by `ssslab render` (one image
# with standard errors) and by Cycles K times with different seeds (scripts/cycles_render.py:
# every bounce limit lifted, no clamping, no denoising, no adaptive sampling), and the two are
# compared by `ssslab compare` (image means and per-block chi-square).
#
#   scripts/cycles_sidebyside.sh [scene.toml] [--size N] [--spp-ours N] [--spp-cycles N]
#                                [--runs K] [--block B] [--threads T] [--out DIR]
#                                [--ours-args "ARGS"] [--cycles-args "ARGS"]
#
# Besides the test of sameness it prints each side's efficiency 1/(MSE x time) per channel (MSE
# the mean pixel variance; time ssslab's whole render and the sum of Cycles' render calls without
# Blender's start-up), both renderers on the same T threads (default: all). --ours-args passes
# further options to `ssslab render` (e.g. "--absorption per-channel": an estimator's option
# against Cycles); --cycles-args further options to scripts/cycles_render.py (e.g.
# "--native-lights": Cycles' own Spot and radius Point in place of the exact export, to see the
# difference).
#
# Defaults: experiments/scenes/cycles/ketchup-matched.toml, 128 x 128, 16384 spp (ours), 16 runs
# of 512 spp (Cycles), blocks of 16 pixels, results/cycles/<scene>/. Needs Debian's blender
# (apt-get install blender); not part of the tests (Blender is a 300 MB dependency).
set -euo pipefail
cd "$(dirname "$0")/.."

scene=experiments/scenes/cycles/ketchup-matched.toml
size=128 spp_ours=16384 spp_cycles=512 runs=16 block=16 threads=0 out="" ours_args="" cycles_args=""
while [[ $# -gt 0 ]]; do
  case "$1" in
    --size) size=$2; shift 2 ;;
    --spp-ours) spp_ours=$2; shift 2 ;;
    --spp-cycles) spp_cycles=$2; shift 2 ;;
    --runs) runs=$2; shift 2 ;;
    --block) block=$2; shift 2 ;;
    --threads) threads=$2; shift 2 ;;
    --out) out=$2; shift 2 ;;
    --ours-args) ours_args=$2; shift 2 ;;
    --cycles-args) cycles_args=$2; shift 2 ;;
    -*) echo "cycles_sidebyside.sh: unknown option $1" >&2; exit 2 ;;
    *) scene=$1; shift ;;
  esac
done
command -v blender > /dev/null || { echo "cycles_sidebyside.sh: needs Blender (apt-get install blender)" >&2; exit 2; }
ssslab=${SSSLAB:-build/release/ssslab}
[[ -x $ssslab ]] || bash scripts/build.sh
name=$(basename "$scene" .toml)
out=${out:-results/cycles/$name}
mkdir -p "$out"

"$ssslab" scene "$scene" --export-obj "$out/export" > /dev/null
json=$(ls "$out"/export/*/scene.json)
echo "ssslab: $size x $size, $spp_ours spp${ours_args:+, $ours_args}"
start=$(date +%s%N)
# shellcheck disable=SC2086  # ours_args: options split into words on purpose
"$ssslab" render "$scene" --width "$size" --height "$size" --spp "$spp_ours" --seed 11 \
  --threads "$threads" --out "$out/ssslab.exr" -q $ours_args
ours_s=$(awk -v a="$start" -v b="$(date +%s%N)" 'BEGIN { printf "%.1f", (b - a) / 1e9 }')
echo "Cycles: $runs runs of $spp_cycles spp${cycles_args:+, $cycles_args}"
files=()
cycles_s=0
for k in $(seq 1 "$runs"); do
  # shellcheck disable=SC2086  # cycles_args: options split into words on purpose
  blender -b --factory-startup -P scripts/cycles_render.py -- "$json" "$out/cycles_$k.exr" \
    --spp "$spp_cycles" --seed "$((1000 + k))" --width "$size" --height "$size" \
    --threads "$threads" $cycles_args > "$out/cycles_$k.log" 2>&1 ||
    { tail -5 "$out/cycles_$k.log" >&2; exit 1; }
  files+=("$out/cycles_$k.exr")
  s=$(sed -n 's/^cycles_render.py: render_seconds //p' "$out/cycles_$k.log")
  cycles_s=$(awk -v a="$cycles_s" -v b="$s" 'BEGIN { printf "%.3f", a + b }')
done
{
  echo "scene $scene, $size x $size; ssslab $spp_ours spp in ${ours_s} s; Cycles $runs x $spp_cycles spp in ${cycles_s} s ($(blender --version | head -1))"
  "$ssslab" compare --a "$out/ssslab.exr" --b "${files[@]}" --block "$block" --csv "$out/blocks.csv" \
    --seconds-a "$ours_s" --seconds-b "$cycles_s"
} | tee "$out/summary.txt"
