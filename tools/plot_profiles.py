#!/usr/bin/python3
"""Stress profiles of the thesis' 1D chapter-4 benchmarks, each method beside the exact solution.

Usage: tools/plot_profiles.py [--mpm build/tools/mpm] [--out docs/results]
Writes profiles_4_6_1.png (thesis Fig 4.6: the fixed-ends bar of §4.6.1, MPM-P1 and OTM-P1 on 512 nodes, the
unified approach on 32) and profiles_4_6_2.png (thesis Fig 4.8: the traction bar of §4.6.2, every method on 85
nodes of the 1.25 m domain) and profiles_4_6_3.png (thesis Fig 4.10: σ11 of the §4.6.3 plate along the row of particles
nearest X2 = 0.07 m). Each run is `mpm run SCENE --set ... --out F.h5`; the stress of the last snapshot is
plotted against the particles' reference positions X0, with the exact solution drawn from the same formulas the
engine's problems use (engine/problem.cpp, engine/reference_1d.cpp; thesis eq. 4.93).
"""
import argparse
import math
import os
import subprocess
import tempfile

import h5py
import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

MOVING = ["algorithm.mass=consistent"]
# (label, scene, overrides); the thesis runs USL for every method of chapter 4
FIXED_ENDS = [
    ("MPM-P1, 512 nodes", ["grid.basis=linear", "grid.cells=[511]", "algorithm.update=usl"]),
    ("OTM-P1, 512 nodes", ["grid.basis=linear", "grid.cells=[511]", "algorithm.update=otm"] + MOVING),
    ("unified, 32 nodes", ["grid.basis=bspline2", "grid.cells=[30]", "algorithm.update=unified"] + MOVING),
]
TRACTION = [  # 85 functions on the 1.25 m grid: 84 cells for P1 and max-ent, 83 for quadratic B-splines
    ("MPM-P1", ["grid.basis=linear", "grid.cells=[84]", "algorithm.update=usl"]),
    ("MPM-maxent", ["grid.basis=maxent", "grid.cells=[82]", "algorithm.update=usl"]),
    ("BSMPM", ["grid.basis=bspline2", "grid.cells=[83]", "algorithm.update=usl"]),
    ("OTM-P1", ["grid.basis=linear", "grid.cells=[84]", "algorithm.update=otm"] + MOVING),
    ("OTM-maxent", ["grid.basis=maxent", "grid.cells=[82]", "algorithm.update=otm"] + MOVING),
    ("unified", ["grid.basis=bspline2", "grid.cells=[83]", "algorithm.update=unified"] + MOVING),
]


PLATE = [  # thesis §4.6.3 on 32×32 cells (33 nodes per axis for P1; USL as the thesis)
    ("MPM-P1", ["grid.basis=linear", "algorithm.update=usl"]),
    ("MPM-maxent", ["grid.basis=maxent", "algorithm.update=usl"]),
    ("BSMPM", ["grid.basis=bspline2", "algorithm.update=usl"]),
    ("OTM-P1", ["grid.basis=linear", "algorithm.update=otm"] + MOVING),
    ("OTM-maxent", ["grid.basis=maxent", "algorithm.update=otm"] + MOVING),
    ("unified", ["grid.basis=bspline2", "algorithm.update=unified"] + MOVING),
]
ROW_X2 = 0.07  # the thesis' x2⁰ of Fig 4.10


def run(mpm, scene, sets, folder):
    """Runs one scene; returns X0 and σ of its last snapshot (2D: σ11 of the particle row nearest X2 = 0.07 m),
    the time, and the command line."""
    out = os.path.join(folder, "run.h5")
    argv = [mpm, "run", scene, "--quiet", "--out", out] + [a for s in sets for a in ("--set", s)]
    subprocess.run(argv, check=True, stdout=subprocess.DEVNULL)
    with h5py.File(out, "r") as f:
        last = f["snapshots"][sorted(f["snapshots"], key=int)[-1]]
        X, s, row = list(last["X0"]), list(last["s00"]), None
        if "X1" in last:
            Y = list(last["X1"])
            row = min(Y, key=lambda y: abs(y - ROW_X2))
            X, s = zip(*sorted((x, v) for x, y, v in zip(X, Y, s) if abs(y - row) < 1e-12))
        return list(X), list(s), row, float(last.attrs["time"]), " ".join(argv[1:3] + argv[6:])


def bar_stress(X, t, row, E=4e3, rho=1.0, v0=0.6, l=1.0):
    """The fixed-ends bar (linear elastic, ν = 0): u = v0/ω sin(ωt) sin(πX/l), σ = E ∂u/∂X."""
    omega = math.pi / l * math.sqrt(E / rho)
    return E * v0 / omega * math.sin(omega * t) * math.pi / l * math.cos(math.pi * X / l)


def traction_stress(X, t, row, l=1.0):
    """Thesis eq. 4.93 (wave speed 1 m/s: E = ρ = 100; τ = sin(ω t) at the end, ω = π / l)."""
    w = math.pi / l
    if t < l - X:
        return 0.0
    if t < l + X:
        return math.sin(w * (t + X))
    if t < 3 * l - X:
        return math.sin(w * (t + X)) + math.sin(w * (t - X))
    if t < 3 * l + X:
        return math.sin(w * (t - X))
    return 0.0


def plate_stress(X, t, row, E=1e7, nu=0.3, rho=1000.0, A=0.005, L=1.0):
    """σ11 of the manufactured plate solution along the row X2 = row (PROBLEMS.md: neo-Hookean, c = sqrt(E/ρ0))."""
    lam, mu = E * nu / ((1 + nu) * (1 - 2 * nu)), E / (2 * (1 + nu))
    w = math.sqrt(E / rho) * math.pi / L
    F11 = 1 + 2 * math.pi * A / L * math.cos(2 * math.pi * X / L) * math.sin(w * t)
    F22 = 1 + 2 * math.pi * A / L * math.cos(2 * math.pi * row / L) * math.sin(w * t + math.pi)
    J = F11 * F22
    return (lam * math.log(J) + mu * (F11 * F11 - 1)) / J


def figure(mpm, scene, cases, exact, title, path, folder):
    fig, ax = plt.subplots(figsize=(7, 4.2))
    commands = []
    t = 0.0
    for label, sets in cases:
        X, s, row, t, cmd = run(mpm, scene, sets, folder)
        ax.plot(X, s, ".", ms=2.5, label=label)
        commands.append(cmd)
    xs = [i / 400 for i in range(401)]
    ax.plot(xs, [exact(x, t, row) for x in xs], "k-", lw=1, label="exact")
    ax.set_xlabel("X (m)")
    ax.set_ylabel("σ11 (Pa)")
    ax.set_title(title, fontsize=9)
    ax.legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)
    print(f"wrote {path}:\n    mpm " + "\n    mpm ".join(commands))


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--mpm", default="build/tools/mpm")
    ap.add_argument("--out", default="docs/results")
    a = ap.parse_args()
    with tempfile.TemporaryDirectory() as folder:
        figure(a.mpm, "tools/scenes/bar-otm.json", FIXED_ENDS, bar_stress,
               "fixed-ends bar, thesis §4.6.1, T = 1e-3 s (thesis Fig 4.6)",
               os.path.join(a.out, "profiles_4_6_1.png"), folder)
        figure(a.mpm, "tools/scenes/bar-traction.json", TRACTION, traction_stress,
               "bar with a traction at its free end, thesis §4.6.2, T = 0.4 s, 85 nodes (thesis Fig 4.8)",
               os.path.join(a.out, "profiles_4_6_2.png"), folder)
        figure(a.mpm, "tools/scenes/plate-unified.json", PLATE, plate_stress,
               "plate of thesis §4.6.3, σ11 along X2 ≈ 0.07 m, T = 3.5e-3 s, 32×32 cells (thesis Fig 4.10)",
               os.path.join(a.out, "profiles_4_6_3.png"), folder)


if __name__ == "__main__":
    main()
