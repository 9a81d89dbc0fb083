#!/usr/bin/python3
"""Runs the verification settings with the `mpm` program and writes the table of docs/VERIFICATION.md.

Usage: tools/results_table.py [--mpm build/tools/mpm] [--out docs/VERIFICATION.md]
Every row is one `mpm run` (the command is printed beside the table); orders are log2 of successive error ratios.
"""
import argparse
import json
import math
import os
import subprocess
import tempfile

# The direct-mapping row each reconstructed mapping's cost is compared with: the same problem, mass matrix and
# particles, particles as integration points.
BAR_DIRECT = "bar, BSMPM, MUSL, projection"
PLATE_05_DIRECT = "plate A=0.05, BSMPM, MUSL, lumped"
CASES = [
    # (label, scene, overrides, resolutions, direct-mapping row to compare the cost with)
    ("bar, MPM-P1, MUSL, lumped", "bar.json", ["grid.basis=linear", "algorithm.mass=lumped"], [10, 20, 40], None),
    ("bar, DDMPM, MUSL, lumped", "bar.json", ["grid.basis=ddmpm", "algorithm.mass=lumped"], [10, 20, 40], None),
    ("bar, MPM-maxent, MUSL, lumped", "bar.json", ["grid.basis=maxent", "algorithm.mass=lumped"], [10, 20, 40], None),
    ("bar, BSMPM, MUSL, lumped", "bar.json", ["grid.basis=bspline2", "algorithm.mass=lumped"], [10, 20, 40], None),
    ("bar, OTM-P1, consistent", "bar.json", ["grid.basis=linear", "algorithm.update=otm", "algorithm.mass=consistent"],
     [10, 20, 40], None),
    ("bar, OTM-maxent, consistent", "bar.json", ["grid.basis=maxent", "algorithm.update=otm",
                                                  "algorithm.mass=consistent"], [10, 20, 40], None),
    ("bar, unified, consistent", "bar.json", ["grid.basis=bspline2", "algorithm.update=unified",
                                               "algorithm.mass=consistent"], [10, 20, 40], None),
    (BAR_DIRECT, "bar.json", ["grid.basis=bspline2", "algorithm.mass=projection"], [10, 20, 40], None),
    ("bar, BSMPM-TLS, MUSL, projection", "bar.json", ["algorithm.mapping=tls", "algorithm.mass=projection"],
     [10, 20, 40], BAR_DIRECT),
    ("bar, BSMPM-CS (cubic spline), MUSL, projection", "bar.json",
     ["algorithm.mapping=cubic-spline", "algorithm.mass=projection"], [10, 20, 40], BAR_DIRECT),
    (PLATE_05_DIRECT, "plate.json", ["algorithm.mass=lumped"], [8, 16, 32], None),
    ("plate A=0.05, DDMPM, MUSL, lumped", "plate.json", ["grid.basis=ddmpm"], [8, 16, 32], None),
    ("plate A=0.05, MPM-maxent, MUSL, lumped", "plate.json", ["grid.basis=maxent"], [8, 16, 32], None),
    ("plate A=0.05, BSMPM, MUSL, projection", "plate.json", ["algorithm.mass=projection"], [8, 16, 32], None),
    ("plate A=0.05, OTM-P1, consistent", "plate.json", ["grid.basis=linear", "algorithm.update=otm",
                                                        "algorithm.mass=consistent"], [8, 16, 32], None),
    ("plate A=0.05, OTM-maxent, consistent", "plate.json", ["grid.basis=maxent", "algorithm.update=otm",
                                                            "algorithm.mass=consistent"], [8, 16, 32], None),
    ("plate A=0.05, unified, consistent", "plate.json", ["algorithm.update=unified", "algorithm.mass=consistent"],
     [8, 16, 32], None),
    ("plate A=0.05, BSMPM-MLS (support 2h), MUSL, lumped", "plate.json", ["algorithm.mapping=mls"], [8, 16],
     PLATE_05_DIRECT),
    ("plate A=0.05, BSMPM-TLS, MUSL, lumped", "plate.json", ["algorithm.mapping=tls"], [8, 16, 32, 64],
     PLATE_05_DIRECT),
    ("plate A=0.1, BSMPM, MUSL, lumped", "plate.json", ["problem.amplitude=0.1"], [16, 32, 64], None),
    ("plate A=0.1, BSMPM-TLS, MUSL, lumped", "plate.json", ["problem.amplitude=0.1", "algorithm.mapping=tls"],
     [16, 32, 64], "plate A=0.1, BSMPM, MUSL, lumped"),
    ("plate A=0.1, BSMPM, MUSL, lumped, 2×2 particles", "plate.json",
     ["problem.amplitude=0.1", "particles.per_cell=[2,2]"], [16, 32, 64], None),
    ("plate A=0.1, BSMPM-TLS, MUSL, lumped, 2×2 particles", "plate.json",
     ["problem.amplitude=0.1", "algorithm.mapping=tls", "particles.per_cell=[2,2]"], [16, 32, 64],
     "plate A=0.1, BSMPM, MUSL, lumped, 2×2 particles"),
]


def run(mpm, scene, sets, cells, dim):
    with tempfile.TemporaryDirectory() as tmp:
        summary = os.path.join(tmp, "s.json")
        grid = "[%d]" % cells if dim == 1 else "[%d,%d]" % (cells, cells)
        args = [mpm, "run", scene, "--quiet", "--summary", summary, "--set", "grid.cells=" + grid,
                "--set", "output.file=null"]
        for s in sets:
            args += ["--set", s]
        subprocess.run(args, check=False)  # exit 3 (unstable) still writes the summary
        with open(summary) as f:
            return json.load(f)


def order(a, b):
    return math.log2(a / b) if a > 0 and b > 0 else float("nan")


def main():
    root = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
    ap = argparse.ArgumentParser()
    ap.add_argument("--mpm", default=os.path.join(root, "build", "tools", "mpm"))
    ap.add_argument("--out", default=os.path.join(root, "docs", "VERIFICATION.md"))
    a = ap.parse_args()
    lines = ["| method | cells | u RMS | v RMS | σ RMS | order u | order σ | mass err | momentum err | fallbacks "
             "| wall s | ns / particle-step | cost ÷ direct |",
             "|---|---|---|---|---|---|---|---|---|---|---|---|---|"]
    step_ns = {}  # (label, cells): time stepping only, ns per particle-step
    for label, scene, sets, resolutions, direct in CASES:
        path = os.path.join(root, "tools", "scenes", scene)
        dim = 1 if scene.startswith("bar") else 2
        prev = None
        for cells in resolutions:
            s = run(a.mpm, path, sets, cells, dim)
            if s["status"] != "ok":
                lines.append("| %s | %d | %s: %s | | | | | | | | | |" % (label, cells, s["status"],
                                                                 s.get("reason", "")[:80]))
                prev = None
                continue
            e = s["errors"]
            ou = "%.2f" % order(prev["displacement_rms"], e["displacement_rms"]) if prev else ""
            os_ = "%.2f" % order(prev["stress_rms"], e["stress_rms"]) if prev else ""
            ns = 1e9 / s["particle_steps_per_s"]
            step_ns[(label, cells)] = ns
            ratio = "%.2f" % (ns / step_ns[(direct, cells)]) if (direct, cells) in step_ns else ""
            lines.append("| %s | %d | %.3e | %.3e | %.3e | %s | %s | %.1e | %.1e | %d | %.2f | %.0f | %s |" % (
                label, cells, e["displacement_rms"], e["velocity_rms"], e["stress_rms"], ou, os_,
                s["conservation"]["mass_rel_max"], s["conservation"]["momentum_rel_max"],
                sum(s["fallbacks"].values()), s["wall_s"], ns, ratio))
            prev = e
    lines.append("")
    lines.append("Generated by `tools/results_table.py` (each row: `mpm run tools/scenes/<scene> --set grid.cells=... "
                 "--set <the row's settings>`). The bar is thesis Table 5.2 (dt = 1e-7, T = 1.9e-6 s, 12 particles "
                 "per cell); the plate is T = 0.0125 s, 3×3 particles per cell unless the row says otherwise, dt = 1e-5. "
                 "*ns / particle-step*: the summary's time stepping alone (`particle_steps_per_s`, without set-up and "
                 "output), on all cores; *cost ÷ direct*: that time over the direct-mapping row of the same problem, "
                 "particles and cells (the bar's TLS and CS rows against its BSMPM projection row). Small runs are "
                 "dominated by fixed per-step costs; the cost at 1e6 particles is measured by `tools/tls_cost.sh`.")
    table = "\n".join(lines)
    with open(a.out) as f:
        text = f.read()
    begin, end = "<!-- results:begin -->", "<!-- results:end -->"
    if begin in text:
        text = text[:text.index(begin) + len(begin)] + "\n" + table + "\n" + text[text.index(end):]
    else:
        text = text.replace("RESULTS_TABLE", begin + "\n" + table + "\n" + end)
    with open(a.out, "w") as f:
        f.write(text)
    print(table)


if __name__ == "__main__":
    main()
