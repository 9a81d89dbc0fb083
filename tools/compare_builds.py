#!/usr/bin/env python3
"""Side-by-side throughput of bench_step programs (builds, commits, or MPM_ISA choices), in alternating rounds.

Each round runs every variant once, in the given order, on the same benchmark filter; the table gives each
variant's median particle-steps/s over the rounds and the median of its per-round ratio to the first variant (the
ratio of runs made back to back, robust to a shared machine's drift). Example (docs/PERFORMANCE.md):

  python3 tools/compare_builds.py --rounds 5 --filter 'step/2d/(usl|musl)/n:1000000/threads:2/' \\
      sse2='env MPM_ISA=baseline build/bench/bench_step' avx2=build/bench/bench_step \\
      native=build-native/bench/bench_step
"""
import argparse
import json
import shlex
import statistics
import subprocess
import sys


def run(command, bench_filter):
    out = subprocess.run(shlex.split(command) + [f"--benchmark_filter={bench_filter}", "--benchmark_format=json"],
                         check=True, capture_output=True, text=True).stdout
    return {b["name"]: b["particle_steps_per_s"] for b in json.loads(out)["benchmarks"]
            if b.get("run_type") == "iteration"}


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--rounds", type=int, default=5)
    ap.add_argument("--filter", required=True, help="Google Benchmark filter, e.g. 'step/2d/usl/n:1000000/'")
    ap.add_argument("variants", nargs="+", metavar="LABEL=COMMAND", help="the first is the reference of the ratios")
    args = ap.parse_args()
    variants = []
    for v in args.variants:
        label, sep, command = v.partition("=")
        if not sep or not command:
            sys.exit(f"compare_builds.py: expected LABEL=COMMAND, got {v!r}")
        variants.append((label, command))

    rates = {label: [] for label, _ in variants}  # per round: {benchmark: particle-steps/s}
    for r in range(args.rounds):
        for label, command in variants:
            rates[label].append(run(command, args.filter))
        print(f"round {r + 1}/{args.rounds} done", file=sys.stderr)

    ref = variants[0][0]
    names = sorted(rates[ref][0])
    print(f"| benchmark | {' | '.join(label for label, _ in variants)} |")
    print("|---|" + "---:|" * len(variants))
    for name in names:
        cells = []
        for label, _ in variants:
            median = statistics.median(round_[name] for round_ in rates[label])
            ratio = statistics.median(a[name] / b[name] for a, b in zip(rates[label], rates[ref]))
            cells.append(f"{median / 1e6:.1f} M" + ("" if label == ref else f" ({ratio:.2f}×)"))
        print(f"| {name} | {' | '.join(cells)} |")


if __name__ == "__main__":
    main()
