#!/usr/bin/python3
"""Stress profiles of the plate on the 1056-triangle mesh, each method beside the exact solution.

Usage: tools/plot_triangles.py [--mpm build/tools/mpm] [--out docs/results]
Writes triangles_6_8.png (thesis Fig 6.8: σ22 of the particles with X1 ≈ 0.5 m against X2, MPM-P1 and MPM-TLS, 24
particles per triangle, MUSL, dt = 1.25e-4, T = 0.015) and triangles_3_9.png (thesis Fig 3.9: σ11 of the particles
with X2 ≈ 0.5 m against X1 at t = 0.016 s, MPM-P1 and PS-MPM (lumped mass, and the consistent mass for the velocities) on the 162-triangle mesh, dt = 2.25e-4). Each run is `mpm run
tools/scenes/plate-triangles.json --set ... --out F.h5`; the band of particles is |X − 0.5| < 0.01 m. The exact
stress is the vibrating plate's (engine/problem.cpp, PROBLEMS.md).
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

SCENE = "tools/scenes/plate-triangles.json"
E, NU, RHO, A = 1e7, 0.3, 1000.0, 0.05
FIG_6_8 = [("MPM-P1", ["algorithm.mapping=direct"]), ("MPM-TLS", ["algorithm.mapping=tls"])]
FIG_3_9 = [("MPM-P1", ["algorithm.mapping=direct"]),
           ("PS-MPM, lumped", ["algorithm.mapping=direct", "grid.basis=powell-sabin"]),
           ("PS-MPM, projection", ["algorithm.mapping=direct", "grid.basis=powell-sabin", "algorithm.mass=projection"])]
# the thesis' dt exceeds the critical step h/c of the 1056-triangle mesh (1.7e-4 s): its Fig 3.6 mesh was coarser,
# so this figure runs on the 162-triangle mesh
FIG_3_9_TIME = ["time.dt=2.25e-4", "time.end=0.016", 'grid.mesh="tools/meshes/unit_square_coarse.msh"']


def exact_stress(X1, X2, t, component):
    """σ11 or σ22 of the plate (neo-Hookean, u_d = A sin(2π X_d) sin(cπt + (d − 1)π))."""
    lam, mu = E * NU / ((1 + NU) * (1 - 2 * NU)), E / (2 * (1 + NU))
    wt = math.sqrt(E / RHO) * math.pi * t
    F11 = 1 + 2 * math.pi * A * math.cos(2 * math.pi * X1) * math.sin(wt)
    F22 = 1 + 2 * math.pi * A * math.cos(2 * math.pi * X2) * math.sin(wt + math.pi)
    J = F11 * F22
    F = F11 if component == 0 else F22
    return (lam * math.log(J) + mu * (F * F - 1)) / J


def band(mpm, sets, folder, across, component):
    """Runs one scene; returns (X along, σ) of the particles with |X_across − 0.5| < 0.01, sorted, and the time."""
    out = os.path.join(folder, "run.h5")
    argv = [mpm, "run", SCENE, "--quiet", "--out", out] + [a for s in sets for a in ("--set", s)]
    subprocess.run(argv, check=True, stdout=subprocess.DEVNULL)
    with h5py.File(out, "r") as f:
        last = f["snapshots"][sorted(f["snapshots"], key=int)[-1]]
        t = float(last.attrs["time"])
        X = [list(last["X0"]), list(last["X1"])]
        s = list(last["s00" if component == 0 else "s11"])
    along = 1 - across
    rows = sorted((X[along][p], s[p]) for p in range(len(s)) if abs(X[across][p] - 0.5) < 0.01)
    return [r[0] for r in rows], [r[1] for r in rows], t


def figure(mpm, folder, methods, extra, across, component, title, path):
    fig, ax = plt.subplots(figsize=(6.4, 4.2))
    t = None
    for label, sets in methods:
        x, s, t = band(mpm, sets + extra, folder, across, component)
        ax.plot(x, s, ".", ms=3, label=label)
    xs = [i / 200 for i in range(201)]
    ex = [exact_stress(0.5, x, t, component) if across == 0 else exact_stress(x, 0.5, t, component) for x in xs]
    ax.plot(xs, ex, "k-", lw=1, label="exact")
    ax.set_xlabel(f"X{2 - across} (m)")
    ax.set_ylabel(f"σ{component + 1}{component + 1} (Pa)")
    ax.set_title(f"{title}, t = {t:g} s")
    ax.legend()
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)
    print("wrote", path)


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--mpm", default="build/tools/mpm")
    ap.add_argument("--out", default="docs/results")
    a = ap.parse_args()
    os.makedirs(a.out, exist_ok=True)
    with tempfile.TemporaryDirectory() as folder:
        figure(a.mpm, folder, FIG_6_8, [], 0, 1, "Thesis Fig 6.8: σ22 at X1 ≈ 0.5 m, 1056 triangles",
               os.path.join(a.out, "triangles_6_8.png"))
        figure(a.mpm, folder, FIG_3_9, FIG_3_9_TIME, 1, 0, "Thesis Fig 3.9: σ11 at X2 ≈ 0.5 m, 162 triangles",
               os.path.join(a.out, "triangles_3_9.png"))


if __name__ == "__main__":
    main()
