#!/usr/bin/env bash
# The cost of the TLS reconstruction against direct mapping, side by side: `mpm run` on the benchmark block
# (tools/scenes/block-1e6.json: neo-Hookean, lumped mass, quadratic B-splines, MUSL) with 2x2 and 3x3 particles
# per cell at ~1e6 particles, direct and TLS alternated in every repetition so that both see the same host load.
# Prints a Markdown table of the medians of the summaries' particle_steps_per_s (time stepping only), their ratio
# TLS / direct, and the median and range of the paired ratios (each TLS run over the direct run just before it: on
# a shared host whose speed drifts between repetitions, the pairs see the most similar load).
#
# Usage: tools/tls_cost.sh [--mpm BINARY] [--reps N] [--threads T] [--steps S]
#   defaults: build/tools/mpm, 3 repetitions, 2 threads, 32 steps (dt = 1e-5)
set -euo pipefail
root=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
steps=32
help_lines=10
# shellcheck source=tools/cost_args.sh
source "$root/tools/cost_args.sh"
end=$(python3 -c "print($steps * 1e-5)")
summary=$(mktemp)
trap 'rm -f "$summary"' EXIT
# layout (particles per cell) and cells per axis for ~1e6 particles
configs=("[2,2] [500,500]" "[3,3] [333,333]")
for ((r = 1; r <= reps; ++r)); do
  for cfg in "${configs[@]}"; do
    read -r ppc cells <<< "$cfg"
    for mapping in direct tls; do
      "$mpm" run "$root/tools/scenes/block-1e6.json" --set algorithm.update='"musl"' \
        --set algorithm.mapping="\"$mapping\"" --set particles.per_cell="$ppc" --set grid.cells="$cells" \
        --set time.end="$end" --threads "$threads" --quiet --summary "$summary" > /dev/null
      echo "$ppc $mapping $(python3 -c "import json, sys; print(json.load(open(sys.argv[1]))['particle_steps_per_s'])" "$summary")"
    done
  done
done | python3 -c "
import collections, statistics, sys
runs = collections.defaultdict(list)
for line in sys.stdin:
    ppc, mapping, rate = line.split()
    runs[(ppc, mapping)].append(float(rate))
print('| particles per cell | direct, particle-steps/s | TLS, particle-steps/s | TLS / direct | paired: median (range) | runs |')
print('|---|---:|---:|---:|---:|---:|')
for ppc in sorted({k[0] for k in runs}):
    d, t = statistics.median(runs[(ppc, 'direct')]), statistics.median(runs[(ppc, 'tls')])
    paired = [tr / dr for dr, tr in zip(runs[(ppc, 'direct')], runs[(ppc, 'tls')])]
    print(f'| {ppc} | {d / 1e6:.2f} M | {t / 1e6:.2f} M | {t / d:.2f} | {statistics.median(paired):.2f} '
          f'({min(paired):.2f}–{max(paired):.2f}) | {len(paired)} |')
"
echo
echo "mpm: $mpm; $threads threads; $steps MUSL steps per run; $(nproc) CPUs: $(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2 | xargs); $(date -u +%Y-%m-%dT%H:%MZ)"
