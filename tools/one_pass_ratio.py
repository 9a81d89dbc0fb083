#!/usr/bin/env python3
"""The one-pass step (the last gather and the next scatter in one pass, Simulation::allow_scatter_ahead) against the
two passes, in one bench_step program: each round runs step/2d/{usl,usl-ahead,musl,musl-ahead}/n:N/threads:2 in one
process (fresh simulations, in that program's order) and takes the ratio one pass / two passes; prints the medians
of the rates and of the per-round ratios, with their range (docs/PERFORMANCE.md, "The last gather and the next
scatter in one pass").

  python3 tools/one_pass_ratio.py build/bench/bench_step 10000000 7
"""
import os
import shlex
import statistics
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from compare_builds import run  # noqa: E402  (one bench_step run: {benchmark name: particle-steps/s})


def main():
    if len(sys.argv) != 4:
        sys.exit("usage: one_pass_ratio.py BENCH_STEP PARTICLES ROUNDS")
    binary, n, rounds = sys.argv[1], sys.argv[2], int(sys.argv[3])
    schemes = ("usl", "musl")
    rates, ratios = {}, {s: [] for s in schemes}
    for r in range(rounds):
        by_scheme = {name.split("/")[2]: rate
                     for name, rate in run(shlex.quote(binary), f"step/2d/(usl|usl-ahead|musl|musl-ahead)/n:{n}/threads:2/").items()}
        for scheme, rate in by_scheme.items():
            rates.setdefault(scheme, []).append(rate)
        for s in schemes:
            ratios[s].append(by_scheme[s + "-ahead"] / by_scheme[s])
        print(f"round {r + 1}: " + " ".join(f"{k}={v / 1e6:.1f}M" for k, v in sorted(by_scheme.items())),
              file=sys.stderr, flush=True)
    for s in schemes:
        rs = sorted(ratios[s])
        print(f"{s}: two passes {statistics.median(rates[s]) / 1e6:.1f} M, one pass "
              f"{statistics.median(rates[s + '-ahead']) / 1e6:.1f} M, one/two median {statistics.median(rs):.2f} "
              f"(range {rs[0]:.2f}-{rs[-1]:.2f}, {len(rs)} rounds)")


if __name__ == "__main__":
    main()
