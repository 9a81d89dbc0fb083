#!/usr/bin/env bash
# The cost of the large plate's manufactured body force: `mpm run` on tools/scenes/plate-large.json (512² cells,
# 2x2 particles per cell, MUSL, neo-Hookean, body force) and on the benchmark block (tools/scenes/block-1e6.json
# on the same 512² grid, MUSL, no body force), alternated in every repetition. Prints the medians of the summaries'
# particle_steps_per_s (time stepping only) and the median and range of the paired ratios plate / block.
#
# Usage: tools/plate_cost.sh [--mpm BINARY] [--reps N] [--threads T] [--steps S]
#   defaults: build/tools/mpm, 3 repetitions, 2 threads, 64 steps
set -euo pipefail
root=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
steps=64
help_lines=8
# shellcheck source=tools/cost_args.sh
source "$root/tools/cost_args.sh"
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
rate() { python3 -c "import json, sys; print(json.load(open(sys.argv[1]))['particle_steps_per_s'])" "$work/s.json"; }
for ((r = 1; r <= reps; ++r)); do
  "$mpm" run "$root/tools/scenes/plate-large.json" --set time.end="$(python3 -c "print($steps * 6.25e-6)")" \
    --threads "$threads" --quiet --out "$work/plate.h5" --summary "$work/s.json" > /dev/null
  plate=$(rate)
  "$mpm" run "$root/tools/scenes/block-1e6.json" --set algorithm.update=musl --set grid.cells=[512,512] \
    --set time.end="$(python3 -c "print($steps * 1e-5)")" --threads "$threads" --quiet --summary "$work/s.json" > /dev/null
  echo "$plate $(rate)"
done | python3 -c '
import statistics, sys
rows = [tuple(map(float, line.split())) for line in sys.stdin]
plate, block = zip(*rows)
ratios = sorted(p / b for p, b in rows)
print("| plate-large | block (512², MUSL) | plate / block: median of paired ratios (range) |")
print("|---:|---:|---:|")
print(f"| {statistics.median(plate) / 1e6:.1f} M | {statistics.median(block) / 1e6:.1f} M | "
      f"{statistics.median(ratios):.2f} ({ratios[0]:.2f}–{ratios[-1]:.2f}) |")
'
