#!/usr/bin/env bash
# Strong scaling over MPI (core/distributed.h): one fixed MCML run (tests/data b_giov_n15.mci,
# a three-layer slab) on 1, 2, 4, ... ranks of one thread each, and on one rank with every core,
# timed end to end (mpirun's start included). Ranks beyond the machine's cores share them: those
# rows are marked oversubscribed and measure the overhead, not a speed-up. `seconds` is the
# wall time of the command, `run_seconds` the run's own (its provenance's wall_seconds). Each configuration's
# outputs are checked to be the one-rank run's (the estimates are bit-identical).
#
#   scripts/strong_scaling.sh [photons] [max_ranks]     default 3000000 photons, 4 ranks
#
# Writes results/scaling/strong_scaling.csv and strong_scaling.png (python3-matplotlib), and
# prints the table.
set -euo pipefail
cd "$(dirname "$0")/.."
photons="${1:-3000000}"
max_ranks="${2:-4}"
bin="$PWD/build/release/ssslab"
mci="$PWD/tests/data/mcml-1.2.2/b_giov_n15.mci"
out="$PWD/results/scaling"
cores=$(nproc)
[[ -x "$bin" ]] || { echo "strong_scaling: build first (scripts/build.sh)" >&2; exit 2; }
command -v mpirun >/dev/null || { echo "strong_scaling: no mpirun (apt-get install openmpi-bin)" >&2; exit 2; }
mkdir -p "$out"
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
cp "$mci" "$work/"

run() {  # run <ranks> <threads per rank>: prints the wall seconds
  local ranks=$1 threads=$2 dir="$work/r$1t$2"
  mkdir -p "$dir" && cp "$work/b_giov_n15.mci" "$dir/"
  local t0 t1
  t0=$(date +%s.%N)
  (cd "$dir" && SSSLAB_PROGRESS=0 mpirun --allow-run-as-root --oversubscribe --bind-to none \
     -np "$ranks" "$bin" mcml b_giov_n15.mci --photons "$photons" --threads "$threads" -q)
  t1=$(date +%s.%N)
  # The same estimates as one rank: the tables after the header (line 11 on) are identical.
  if [[ -f "$work/r1t1/b_giov_n15.mco" ]] &&
     ! cmp -s <(tail -n +11 "$work/r1t1/b_giov_n15.mco") <(tail -n +11 "$dir/b_giov_n15.mco"); then
    echo "strong_scaling: $ranks ranks x $threads threads gave other results than one rank" >&2
    exit 1
  fi
  # wall seconds, and the run's own (its provenance: from the start of the batches to the end)
  echo "$(echo "$t1 - $t0" | bc -l) $(sed -n 's/^wall_seconds = //p' "$dir/b_giov_n15.mco.toml")"
}

csv="$out/strong_scaling.csv"
echo "ranks,threads_per_rank,cores,oversubscribed,photons,seconds,run_seconds,speedup,efficiency" > "$csv"
base=""
ranks=1
while (( ranks <= max_ranks )); do
  read -r s rs < <(run "$ranks" 1)
  [[ -z "$base" ]] && base=$s
  over=$(( ranks > cores ? 1 : 0 ))
  used=$(( ranks < cores ? ranks : cores ))
  printf '%d,1,%d,%d,%d,%.3f,%.3f,%.3f,%.3f\n' "$ranks" "$used" "$over" "$photons" "$s" "$rs" \
    "$(echo "$base / $s" | bc -l)" "$(echo "$base / $s / $used" | bc -l)" >> "$csv"
  ranks=$(( ranks * 2 ))
done
read -r s rs < <(run 1 "$cores")
printf '1,%d,%d,0,%d,%.3f,%.3f,%.3f,%.3f\n' "$cores" "$cores" "$photons" "$s" "$rs" \
  "$(echo "$base / $s" | bc -l)" "$(echo "$base / $s / $cores" | bc -l)" >> "$csv"
column -s, -t < "$csv"

"$(command -v /usr/bin/python3 || command -v python3)" - "$csv" "$out/strong_scaling.png" <<'PY' || echo "strong_scaling: no plot (python3-matplotlib?)" >&2
import csv, sys
import matplotlib
matplotlib.use("Agg")
import matplotlib.pyplot as plt
rows = list(csv.DictReader(open(sys.argv[1])))
mpi = [r for r in rows if r["threads_per_rank"] == "1"]
fig, ax = plt.subplots(figsize=(5, 3.6))
for over, mark, label in ((0, "o-", "ranks of 1 thread"), (1, "x--", "oversubscribed (ranks > cores)")):
    pts = [r for r in mpi if int(r["oversubscribed"]) == over]
    if over and pts:
        pts = [p for p in mpi if int(p["oversubscribed"]) == 0][-1:] + pts
    if pts:
        ax.plot([int(r["ranks"]) for r in pts], [float(r["speedup"]) for r in pts], mark, label=label)
cores = int(rows[-1]["cores"])
ax.plot([1, cores], [1, cores], ":", color="grey", label="ideal")
thr = rows[-1]
ax.plot([1], [float(thr["speedup"])], "s", label=f"1 rank, {cores} threads")
ax.set_xlabel("MPI ranks")
ax.set_ylabel("speed-up over 1 rank")
ax.set_title(f"Strong scaling: MCML, {int(rows[0]['photons']):,} photons")
ax.set_xscale("log", base=2)
ax.legend(fontsize=8)
fig.tight_layout()
fig.savefig(sys.argv[2], dpi=120)
print("strong_scaling: wrote", sys.argv[2])
PY
echo "strong_scaling: wrote $csv"
