#!/usr/bin/env python3
"""The one-pass step (the last gather and the next scatter in one pass, Simulation::allow_scatter_ahead) against the
two passes, in one bench_step program: each round runs step/2d/{usl,usl-ahead,musl,musl-ahead}/n:N/threads:2 in one
process (fresh simulations, in that program's order) and takes the ratio one pass / two passes; prints the medians
of the rates and of the per-round ratios, with their range (docs/PERFORMANCE.md, "The last gather and the next
scatter in one pass").

  python3 tools/one_pass_ratio.py build/bench/bench_step 10000000 7
"""
import json, subprocess, statistics, sys
if len(sys.argv) != 4:
    sys.exit("usage: one_pass_ratio.py BENCH_STEP PARTICLES ROUNDS")
binary, n, rounds = sys.argv[1], sys.argv[2], int(sys.argv[3])
ratios = {"usl": [], "musl": []}
rates = {}
for r in range(rounds):
    out = subprocess.run([binary, f"--benchmark_filter=step/2d/(usl|usl-ahead|musl|musl-ahead)/n:{n}/threads:2/",
                          "--benchmark_format=json"], check=True, capture_output=True, text=True).stdout
    b = {x["name"].split("/")[2]: x["particle_steps_per_s"] for x in json.loads(out)["benchmarks"] if x.get("run_type") == "iteration"}
    for k, v in b.items(): rates.setdefault(k, []).append(v)
    for s in ratios: ratios[s].append(b[s + "-ahead"] / b[s])
    print(f"round {r+1}: " + " ".join(f"{k}={v/1e6:.1f}M" for k, v in sorted(b.items())), file=sys.stderr, flush=True)
for s in ratios:
    rs = sorted(ratios[s])
    print(f"{s}: two passes {statistics.median(rates[s])/1e6:.1f} M, one pass {statistics.median(rates[s+'-ahead'])/1e6:.1f} M, "
          f"one/two median {statistics.median(rs):.2f} (range {rs[0]:.2f}-{rs[-1]:.2f}, {len(rs)} rounds)")
