#!/usr/bin/python3
"""Summarises the JSON output of the benchmark programs (tools/run_bench.sh) into a Markdown table and a PNG.

    /usr/bin/python3 tools/plot_bench.py --results build-bench/results \\
        --table docs/bench_table.md --png docs/throughput.png

Reads bench_{basis,transfer,step,stream}.json (Google Benchmark JSON, repetitions reported as aggregates; the
median is used, or the single run where a benchmark ran once) and run_meta.txt (written by run_bench.sh).
Any file may be missing; its section is then left out.
"""
import argparse
import json
import math
import os
import re
import subprocess
import sys

UNIT = {"ns": 1e-9, "us": 1e-6, "ms": 1e-3, "s": 1.0}


def load(path):
    """{base name: entry} of the medians (or single runs) in one benchmark JSON file; base name without the
    /iterations:, /min_time:, /real_time decorations."""
    if not os.path.exists(path):
        return None, {}
    with open(path) as f:
        text = f.read()
    try:
        doc = json.loads(text)
    except json.JSONDecodeError as e:
        print(f"plot_bench.py: {path}: not valid JSON ({e}); skipped", file=sys.stderr)
        return None, {}
    medians, singles = {}, {}
    for b in doc.get("benchmarks", []):
        if b.get("error_occurred"):
            print(f"plot_bench.py: {b['name']}: {b.get('error_message')}", file=sys.stderr)
            continue
        name = re.sub(r"/(iterations:\d+|min_time:[0-9.]+|real_time|manual_time)", "", b.get("run_name", b["name"]))
        entry = dict(b)
        entry["seconds"] = b["real_time"] * UNIT[b.get("time_unit", "ns")]
        if b.get("run_type") == "aggregate":
            if b.get("aggregate_name") == "median":
                medians[name] = entry
            elif b.get("aggregate_name") == "cv":
                medians.setdefault("__cv__", {})[name] = b["real_time"]
        else:
            singles.setdefault(name, entry)
    cv = medians.pop("__cv__", {})
    out = dict(singles)
    out.update(medians)
    for name, e in out.items():
        e["cv"] = cv.get(name)  # coefficient of variation over repetitions (None for single runs)
        e["reps"] = e.get("repetitions", 1) if name in medians else 1
    return doc.get("context", {}), out


def args_of(name):
    """'step/2d/usl/n:1000/threads:2' -> ('step/2d/usl', {'n': 1000, 'threads': 2})."""
    parts = name.split("/")
    base = [p for p in parts if ":" not in p]
    kv = {}
    for p in parts:
        if ":" in p:
            k, v = p.split(":", 1)
            try:
                kv[k] = int(v)
            except ValueError:
                kv[k] = v
    return "/".join(base), kv


def fmt_time(s):
    for scale, unit in ((1.0, "s"), (1e-3, "ms"), (1e-6, "µs")):
        if s / scale >= 0.9995:
            return f"{s / scale:.3g} {unit}"
    return f"{s * 1e9:.3g} ns"


def fmt_rate(r):
    if r is None:
        return "–"
    for scale, unit in ((1e9, "G"), (1e6, "M"), (1e3, "k")):
        if r >= scale:
            return f"{r / scale:.3g} {unit}"
    return f"{r:.3g}"


def cv_percent(e):
    # Google Benchmark reports the cv aggregate as a fraction in real_time (displayed as %)
    return None if e.get("cv") is None else 100.0 * e["cv"]


def fmt_pct(e):
    c = cv_percent(e)
    return "–" if c is None else f"{c:.1f}"


def busy(e):
    """Main-thread CPU time / wall time of a run: ~1 on an idle machine (TBB's main thread works too); well
    below 1 means the program waited for a CPU that other processes held."""
    cpu = e.get("cpu_time")
    return f"{cpu / e['real_time']:.2f}" if cpu and e.get("real_time") else "–"


def read_meta(results):
    meta, runs = {}, {}
    path = os.path.join(results, "run_meta.txt")
    if os.path.exists(path):
        with open(path) as f:
            for line in f:
                line = line.rstrip("\n")
                if line.startswith("run "):
                    fields = line.split()
                    runs[fields[1]] = dict(kv.split("=", 1) for kv in fields[2:])
                elif "=" in line:
                    k, v = line.split("=", 1)
                    meta[k] = v
    return meta, runs


def machine_fallback(meta, build_dir):
    """Fills what run_meta.txt did not have from this machine (when the table is made without run_bench.sh)."""
    if "cpu" not in meta:
        try:
            with open("/proc/cpuinfo") as f:
                meta["cpu"] = next(l.split(":", 1)[1].strip() for l in f if l.startswith("model name"))
        except (OSError, StopIteration):
            meta["cpu"] = "unknown"
    meta.setdefault("nproc", str(os.cpu_count()))
    if "compiler" not in meta:
        cxx = "c++"
        cache = os.path.join(build_dir or "", "CMakeCache.txt")
        if os.path.exists(cache):
            with open(cache) as f:
                for l in f:
                    if l.startswith("CMAKE_CXX_COMPILER:"):
                        cxx = l.split("=", 1)[1].strip()
        try:
            meta["compiler"] = subprocess.run([cxx, "--version"], capture_output=True, text=True).stdout.splitlines()[0]
        except (OSError, IndexError):
            meta["compiler"] = "unknown"
    return meta


# ------------------------------------------------------------------------------------------------------------
def section_header(lines, meta, runs, contexts):
    lines.append("# Benchmark results")
    lines.append("")
    lines.append("Generated by `tools/run_bench.sh` → `tools/plot_bench.py` from Google Benchmark JSON "
                 "(median of the repetitions; cv = coefficient of variation over them; *CPU/wall* = CPU time of the "
                 "main thread / wall time, ≈ 1 when the program had its CPUs to itself — lower values mean other "
                 "processes took CPU time from the run and its times are too long).")
    lines.append("")
    date = meta.get("date") or next((c.get("date") for c in contexts if c), "unknown")
    lines.append(f"- **Machine:** {meta.get('cpu', 'unknown')}, {meta.get('nproc', '?')} logical CPUs"
                 + (f", {meta['mem_total']} RAM" if meta.get("mem_total") else "")
                 + (f", kernel {meta['kernel']}" if meta.get("kernel") else ""))
    flags = meta.get("cxx_flags_release", "")
    native = meta.get("mpm_native", "")
    lines.append(f"- **Compiler:** {meta.get('compiler', 'unknown')}; Release flags `{flags}`"
                 + (f", MPM_NATIVE={native}" if native else ""))
    lines.append(f"- **Date:** {date}" + (f" (binaries built: {meta['built']})" if meta.get("built") else ""))
    if meta.get("nice", "0") not in ("", "0"):
        lines.append(f"- Programs ran under `nice -n {meta['nice']}` (ahead of other work on a shared machine).")
    ctx = next((c for c in contexts if c), {})
    if ctx.get("library_build_type") == "debug":
        lines.append("- Google Benchmark library: Debian's build reports itself as *debug*; this affects only the "
                     "harness around each timed loop, not the timed code.")
    if runs:
        parts = []
        for prog, r in runs.items():
            parts.append(f"{prog}: {float(r.get('wall', 0)):.0f} s wall, load {r.get('load_before', '?')} before, "
                         f"other processes {float(r.get('other_share', 0)) * 100:.0f} % of the CPUs")
        lines.append("- **Run conditions:** " + "; ".join(parts) + ".")
        busy = [float(r.get("other_share", 0)) for r in runs.values()]
        if busy and max(busy) > 0.05:
            lines.append("  **Caution:** other processes used CPU during the run; 2-thread figures are the most "
                         "affected (they need both cores).")
    lines.append("")


def section_weights(lines, res):
    rows = []
    for dim in ("1d", "2d"):
        for degree in ("linear", "quadratic", "cubic"):
            for kind in ("weights", "stencil"):
                fast = res.get(f"{kind}/{dim}/{degree}/fast")
                gen = res.get(f"{kind}/{dim}/{degree}/generic")
                if not fast and not gen:
                    continue
                def per_point(e):
                    return 1.0 / e["items_per_second"] if e and e.get("items_per_second") else None
                pf, pg = per_point(fast), per_point(gen)
                rows.append((kind, dim, degree, pf, pg, fast, gen))
    if not rows:
        return
    lines.append("## Basis: fast path vs generic Cox–de Boor")
    lines.append("")
    lines.append("Per point: `weights` = `stencil_at` + `for_each_node` (all S^d values and gradients), "
                 "`stencil` = `stencil_at` only (per-axis values and derivatives). 65 536 random points, one thread.")
    lines.append("")
    lines.append("| what | dim | degree | fast ns/point | generic ns/point | generic / fast | cv % (fast, generic) |")
    lines.append("|---|---|---|---:|---:|---:|---|")
    for kind, dim, degree, pf, pg, fast, gen in rows:
        tf = f"{pf * 1e9:.1f}" if pf else "–"
        tg = f"{pg * 1e9:.1f}" if pg else "–"
        ratio = f"**{pg / pf:.1f}×**" if pf and pg else "–"
        cvs = f"{fmt_pct(fast) if fast else '–'}, {fmt_pct(gen) if gen else '–'}"
        lines.append(f"| {kind} | {dim} | {degree} | {tf} | {tg} | {ratio} | {cvs} |")
    lines.append("")


def section_p2g(lines, res):
    p2g = {}
    for name, e in res.items():
        base, kv = args_of(name)
        if base.startswith("p2g/"):
            p2g.setdefault(kv["n"], {})[(base.split("/")[1], kv["threads"])] = e
    if not p2g:
        return
    lines.append("## P2G (mass + momentum + force, 2D quadratic): coloured vs baselines")
    lines.append("")
    lines.append("Each run produces the finished grid from zero. *vs coloured* = time / time of the coloured scatter "
                 "at the same thread count (>1: slower than coloured). *speed-up* = serial time / time. *tls*: the "
                 "reconstruction stage instead of direct P2G — single-cell binning, TLS rebuild of ρ, v, σ at 2×2 "
                 "Gauss points per cell (every fit from the 3×3 neighbourhood at 2×2 particles per cell), "
                 "coloured Gauss-point scatter — so its *vs coloured* is the stage's cost per particle against "
                 "direct mapping's.")
    lines.append("")
    lines.append("| particles | variant | threads | median | Mparticles/s | vs coloured | speed-up vs serial | cv % | CPU/wall |")
    lines.append("|---:|---|---:|---:|---:|---:|---:|---:|---:|")
    order = ["serial", "coloured", "atomic", "per_thread", "tls"]
    for n in sorted(p2g):
        d = p2g[n]
        serial = d.get(("serial", 1))
        for variant in order:
            for t in (1, 2):
                e = d.get((variant, t))
                if not e:
                    continue
                col = d.get(("coloured", t))
                vs = e["seconds"] / col["seconds"] if col else None
                sp = serial["seconds"] / e["seconds"] if serial else None
                parts = int(e.get("particles", n))
                lines.append(f"| {parts:,} | {variant} | {t} | {fmt_time(e['seconds'])} | "
                             f"{e['items_per_second'] / 1e6:.1f} | {vs:.2f} | {sp:.2f} | {fmt_pct(e)} | {busy(e)} |"
                             if vs is not None and sp is not None else
                             f"| {parts:,} | {variant} | {t} | {fmt_time(e['seconds'])} | "
                             f"{e['items_per_second'] / 1e6:.1f} | – | – | {fmt_pct(e)} | {busy(e)} |")
    lines.append("")


def section_other_kernels(lines, res):
    rows = {}
    for name, e in res.items():
        base, kv = args_of(name)
        if base.split("/")[0] in ("g2p", "fused", "stress", "bin", "permute"):
            rows.setdefault((base, kv["n"]), {})[kv["threads"]] = e
    if not rows:
        return
    lines.append("## G2P, fused MUSL pass, stress, binning, reordering (2D quadratic)")
    lines.append("")
    lines.append("USL runs `g2p/usl`; MUSL runs `fused/musl_velocity_momentum` (v_p update + momentum scatter, "
                 "coloured) and `g2p/position_deformation`; the stress update is part of the deformation gathers "
                 "and is timed alone as `stress/neo_hookean`.")
    lines.append("")
    lines.append("| kernel | particles | 1 thread | 2 threads | Mparticles/s (1 / 2 thr) | 2-thread speed-up | CPU/wall (1 / 2 thr) |")
    lines.append("|---|---:|---:|---:|---:|---:|---:|")
    for (base, n), d in sorted(rows.items(), key=lambda x: (x[0][0].split("/")[0] != "g2p", x[0])):
        e1, e2 = d.get(1), d.get(2)
        parts = int((e1 or e2).get("particles", n))
        r1 = f"{e1['items_per_second'] / 1e6:.1f}" if e1 else "–"
        r2 = f"{e2['items_per_second'] / 1e6:.1f}" if e2 else "–"
        sp = f"{e1['seconds'] / e2['seconds']:.2f}" if e1 and e2 else "–"
        lines.append(f"| {base} | {parts:,} | {fmt_time(e1['seconds']) if e1 else '–'} | "
                     f"{fmt_time(e2['seconds']) if e2 else '–'} | {r1} / {r2} | {sp} | "
                     f"{busy(e1) if e1 else '–'} / {busy(e2) if e2 else '–'} |")
    lines.append("")


def section_schedule(lines, res):
    """The USL gather under each oneTBB partitioner and grain size (schedule/g2p_usl/...), 2 threads."""
    cells = {}
    for name, e in res.items():
        base, kv = args_of(name)
        parts = base.split("/")
        if parts[0] != "schedule":
            continue
        cells[(kv["n"], parts[2], kv["grain"])] = e
    if not cells:
        return
    sizes = sorted({k[0] for k in cells})
    grains = sorted({k[2] for k in cells})
    order = ["auto", "static", "simple", "affinity"]
    parts = [p for p in order if any(k[1] == p for k in cells)]
    lines.append("## Gather schedule: oneTBB partitioner and grain (USL gather, 2D quadratic, 2 threads)")
    lines.append("")
    lines.append("Mparticles/s of `gather_g2p` (velocity, position, deformation and stress) as one `tbb::parallel_for` "
                 "over particle ranges of *grain* particles; the engine runs auto with grain 2048 "
                 "(`engine/parallel_over.hpp`).")
    lines.append("")
    head = "| particles | partitioner | " + " | ".join(f"grain {g}" for g in grains) + " |"
    lines.append(head)
    lines.append("|---:|---|" + "---:|" * len(grains))
    for n in sizes:
        for p in parts:
            row = []
            for g in grains:
                e = cells.get((n, p, g))
                row.append(f"{e['items_per_second'] / 1e6:.1f}" if e else "–")
            lines.append(f"| {n:,} | {p} | " + " | ".join(row) + " |")
    lines.append("")
    for n in sizes:
        engine = cells.get((n, "auto", 2048))
        (_, bp, bg), best = min(((k, e) for k, e in cells.items() if k[0] == n), key=lambda ke: ke[1]["seconds"])
        slowest = max(e["seconds"] for k, e in cells.items() if k[0] == n)
        if engine:
            lines.append(f"- {n:,} particles: fastest {bp} with grain {bg}; the engine's schedule takes "
                         f"{engine['seconds'] / best['seconds']:.3f}× its time, the slowest schedule "
                         f"{slowest / best['seconds']:.3f}×.")
    lines.append("")


def step_rows(res):
    rows = {}
    for name, e in res.items():
        base, kv = args_of(name)
        parts = base.split("/")
        if parts[0] != "step":
            continue
        rows[(parts[1], parts[2], kv["n"], kv["threads"])] = e
    return rows


def readme_tables(res, meta):
    """The README's headline tables (2D, 2 threads): throughput by size, speed-ups, the TLS and fast-path ratios,
    then the P2G and basis ratios — all from the same results as docs/bench_table.md."""
    rows = step_rows(res)
    decade = lambda n: int(round(math.log10(n)))  # 99,856 and 9,998,244 particles are the 1e5 and 1e7 columns
    cols = (4, 5, 6, 7)
    def at(scheme, d, t):
        return next((e for (dim, sc, n, th), e in rows.items()
                     if dim == "2d" and sc == scheme and th == t and decade(n) == d), None)
    def rate(scheme, d):
        e = at(scheme, d, 2)
        return fmt_rate(e["particle_steps_per_s"]) if e and e.get("particle_steps_per_s") else ""
    def ratio(num, den, d, t=2):
        a, b = at(num, d, t), at(den, d, t)
        return f"{b['seconds'] / a['seconds']:.2f}" if a and b else ""
    def speedup(scheme, d):
        a, b = at(scheme, d, 1), at(scheme, d, 2)
        return f"{a['seconds'] / b['seconds']:.2f}" if a and b else ""
    build = "native build (MPM_NATIVE=ON)" if meta.get("mpm_native") == "ON" else "portable build"
    out = [f"Generated by `tools/run_bench.sh` on {meta.get('cpu', 'unknown')} ({meta.get('nproc', '?')} CPUs), "
           f"{build}, {meta.get('date', 'date unknown')}; full table with run conditions: `docs/bench_table.md`.", "",
           "| 2D quadratic BSMPM, neo-Hookean, particle-steps/s, 2 threads | 1e4 | 1e5 | 1e6 | 1e7 |",
           "|---|---:|---:|---:|---:|"]
    def row(label, f):
        out.append(f"| {label} | " + " | ".join(f(d) for d in cols) + " |")
    row("USL, direct mapping", lambda d: rate("usl", d))
    row("MUSL, direct mapping", lambda d: rate("musl", d))
    row("2-thread speed-up, USL / MUSL", lambda d: " / ".join(x for x in (speedup("usl", d), speedup("musl", d)) if x))
    row("MUSL-TLS / MUSL-direct, 2×2 particles per cell", lambda d: ratio("musl-tls", "musl", d))
    row("MUSL-TLS / MUSL-direct, 3×3 particles per cell", lambda d: ratio("musl-tls-9ppc", "musl-9ppc", d))
    row("whole step, fast path / Cox–de Boor weights (USL)", lambda d: ratio("usl", "usl-generic", d))
    p2g = {}
    for name, e in res.items():
        base, kv = args_of(name)
        if base.startswith("p2g/") and kv["threads"] == 2:
            p2g.setdefault(kv["n"], {})[base.split("/")[1]] = e
    out += ["", "| ratio (side by side, same run, 2 threads) | value |", "|---|---:|"]
    for n in sorted(p2g):
        d = p2g[n]
        col = d.get("coloured")
        if not col:
            continue
        vs = " / ".join(f"{d[v]['seconds'] / col['seconds']:.2f}×" if v in d else "–" for v in ("atomic", "per_thread"))
        out.append(f"| P2G, {n:,} particles: time of atomic / per-thread grids over the coloured scatter's | {vs} |")
        if "tls" in d:
            out.append(f"| TLS reconstruction stage (binning, rebuild, Gauss-point scatter) over direct P2G, 2×2 "
                       f"particles per cell, {n:,} particles | {d['tls']['seconds'] / col['seconds']:.1f}× the time |")
    for kind in ("weights", "stencil"):
        fast, gen = res.get(f"{kind}/2d/quadratic/fast"), res.get(f"{kind}/2d/quadratic/generic")
        if fast and gen:
            out.append(f"| 2D quadratic {kind}: Cox–de Boor time over the fast path's (1 thread) | "
                       f"{fast['items_per_second'] / gen['items_per_second']:.1f}× |")
    return out


def write_readme(path, lines):
    """Replaces what lies between the README's bench markers."""
    begin, end = "<!-- bench:begin -->", "<!-- bench:end -->"
    with open(path) as f:
        text = f.read()
    if begin not in text or end not in text:
        print(f"plot_bench.py: {path} has no {begin} … {end} markers; README not written", file=sys.stderr)
        return False
    head, rest = text.split(begin, 1)
    _, tail = rest.split(end, 1)
    with open(path, "w") as f:
        f.write(head + begin + "\n" + "\n".join(lines) + "\n" + end + tail)
    return True


def section_step(lines, res):
    rows = step_rows(res)
    if not rows:
        return
    lines.append("## Whole step: `Simulation<Dim>::step()`")
    lines.append("")
    lines.append("Bodies scene (neo-Hookean body filling the grid, uniform velocity, all sides fixed), direct mapping, "
                 "lumped mass, quadratic B-splines (fast path), 4 particles per cell (9 for the *-9PPC schemes). A run is a whole number of "
                 "16-step reorder periods. *2-thr speed-up* = time(1 thread) / time(2 threads); "
                 "*USL/MUSL* = throughput of USL / throughput of MUSL at the same thread count; "
                 "*TLS/direct* = throughput of MUSL with the TLS reconstruction / MUSL with direct mapping, same particle layout; "
                 "*fast/generic* = throughput of USL on the fast path / USL-GENERIC, the same step with the "
                 "Cox–de Boor weights (`grid.basis_path` generic).")
    lines.append("")
    lines.append("| dim | scheme | particles | threads | time / step | particle-steps/s | 2-thr speed-up | USL/MUSL | TLS/direct | fast/generic | runs | cv % | CPU/wall |")
    lines.append("|---|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|")
    order = {"usl": 0, "musl": 1, "musl-tls": 2, "usl-generic": 3, "musl-9ppc": 4, "musl-tls-9ppc": 5}
    for key in sorted(rows, key=lambda k: (k[0], order.get(k[1], 3), k[2], k[3])):
        dim, scheme, n, t = key
        e = rows[key]
        one = rows.get((dim, scheme, n, 1))
        sp = f"{one['seconds'] / e['seconds']:.2f}" if t == 2 and one else ""
        usl, musl = rows.get((dim, "usl", n, t)), rows.get((dim, "musl", n, t))
        ratio = (f"{usl['particle_steps_per_s'] / musl['particle_steps_per_s']:.2f}"
                 if scheme == "usl" and usl and musl else "")
        direct = rows.get((dim, scheme.replace("musl-tls", "musl"), n, t))  # the same layout, direct mapping
        tls = (f"{e['particle_steps_per_s'] / direct['particle_steps_per_s']:.2f}"
               if scheme.startswith("musl-tls") and direct else "")
        generic = (f"{usl['particle_steps_per_s'] / e['particle_steps_per_s']:.2f}"
                   if scheme == "usl-generic" and usl else "")
        lines.append(f"| {dim} | {scheme.upper()} | {int(e.get('particles', n)):,} | {t} | {fmt_time(e['seconds'])} | "
                     f"{fmt_rate(e.get('particle_steps_per_s'))} | {sp} | {ratio} | {tls} | {generic} | {e['reps']} | "
                     f"{fmt_pct(e)} | {busy(e)} |")
    lines.append("")


def section_stream(lines, res):
    rows = []
    for name, e in res.items():
        base, kv = args_of(name)
        if base.startswith("stream/") or base.startswith("peak/"):
            rows.append((base, kv.get("threads"), e))
    if not rows:
        return
    lines.append("## Machine limits (measured)")
    lines.append("")
    lines.append("STREAM-like kernels on 3 × 1 GiB arrays; *STREAM GB/s* counts the bytes the kernel names "
                 "(triad: 24 B/element), *DRAM GB/s* adds the write-allocate read of the written array "
                 "(triad: 32 B/element). FMA peak: 512-bit FMAs, 16 independent chains per thread (fma_avx512), or "
                 "256-bit FMAs, 12 chains (fma_avx2); the one the CPU lacks reports no value.")
    lines.append("")
    lines.append("| kernel | threads | STREAM GB/s | DRAM GB/s (with write-allocate) | GFLOP/s | cv % |")
    lines.append("|---|---:|---:|---:|---:|---:|")
    for base, t, e in sorted(rows, key=lambda r: (r[0].startswith("peak"), r[0], r[1])):
        bw = f"{e['bytes_per_second'] / 1e9:.1f}" if e.get("bytes_per_second") else "–"
        dram = f"{e['dram_bytes'] / 1e9:.1f}" if e.get("dram_bytes") else "–"
        gf = f"{e['flops_per_s'] / 1e9:.1f}" if e.get("flops_per_s") else "–"
        lines.append(f"| {base} | {t} | {bw} | {dram} | {gf} | {fmt_pct(e)} |")
    lines.append("")


def plot(res, png):
    """Throughput against particle count: one panel per dimension, a colour per scheme, solid lines for 2 threads
    and dashed for 1, each panel's legend beneath it (one plot of every series hid lines under the legend)."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    rows = step_rows(res)
    if not rows:
        return False
    series = {}
    for (dim, scheme, n, t), e in rows.items():
        series.setdefault((dim, scheme, t), []).append((e.get("particles", n), e["particle_steps_per_s"]))
    dims = sorted({k[0] for k in series})
    fig, axes = plt.subplots(1, len(dims), figsize=(6 * len(dims), 6.5), sharey=True, squeeze=False)
    palette = plt.get_cmap("tab10").colors
    for ax, dim in zip(axes[0], dims):
        schemes = sorted({k[1] for k in series if k[0] == dim}, key=lambda s: (s != "usl", s != "musl", s))
        for key in sorted((k for k in series if k[0] == dim), key=lambda k: (schemes.index(k[1]), -k[2])):
            _, scheme, t = key
            pts = sorted(series[key])
            ax.plot([p[0] for p in pts], [p[1] / 1e6 for p in pts], marker="s" if t > 1 else "o",
                    linestyle="-" if t > 1 else "--", color=palette[schemes.index(scheme) % len(palette)],
                    label=f"{scheme.upper()}, {t} thread{'s' if t > 1 else ''}")
        ax.set_xscale("log")
        ax.set_xlabel("particles")
        ax.set_title(f"{dim.upper()}")
        ax.grid(True, which="both", alpha=0.3)
        ax.legend(fontsize=8, ncol=2, loc="upper center", bbox_to_anchor=(0.5, -0.12))
    axes[0][0].set_ylabel("particle-steps / s  (millions)")
    axes[0][0].set_ylim(bottom=0)
    fig.suptitle("Simulation::step() throughput (quadratic B-splines, fast path unless GENERIC, neo-Hookean)")
    fig.tight_layout()
    fig.savefig(png, dpi=110)
    plt.close(fig)
    return True


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--results", default="build-bench/results")
    ap.add_argument("--build-dir", default=None, help="to find the compiler when run_meta.txt is missing")
    ap.add_argument("--table", default="docs/bench_table.md")
    ap.add_argument("--png", default="docs/throughput.png")
    ap.add_argument("--readme", default=None, help="README whose bench markers get the headline tables")
    a = ap.parse_args()

    res, contexts = {}, []
    for prog in ("bench_basis", "bench_transfer", "bench_step", "bench_stream"):
        ctx, r = load(os.path.join(a.results, prog + ".json"))
        contexts.append(ctx)
        res.update(r)
    if not res:
        print(f"plot_bench.py: no results in {a.results}", file=sys.stderr)
        return 1
    meta, runs = read_meta(a.results)
    meta = machine_fallback(meta, a.build_dir)

    lines = []
    section_header(lines, meta, runs, contexts)
    section_step(lines, res)
    section_weights(lines, res)
    section_p2g(lines, res)
    section_other_kernels(lines, res)
    section_schedule(lines, res)
    section_stream(lines, res)
    os.makedirs(os.path.dirname(os.path.abspath(a.table)), exist_ok=True)
    with open(a.table, "w") as f:
        f.write("\n".join(lines))
    print(f"wrote {a.table}")
    if a.readme and write_readme(a.readme, readme_tables(res, meta)):
        print(f"wrote the headline tables of {a.readme}")
    if plot(res, a.png):
        print(f"wrote {a.png}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
