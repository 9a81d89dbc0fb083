#!/usr/bin/python3
"""Stability suite: which method survives which hard case. Writes docs/STABILITY.md.

Runs every case (tools/scenes/stability/*.json plus --set overrides) for every method x scheme through the `mpm`
command line, two runs at a time (one thread each), and tabulates per case whether the run completed, where and
why it failed, the maximum energy drift, the conservation errors, the reconstruction fallbacks and the wall time.

    python3 tools/stability.py                      # the whole suite (about 10 min on 2 cores), writes docs/STABILITY.md
    python3 tools/stability.py --family critical    # one family only (the page then holds only that family)
    python3 tools/stability.py --list               # the cases and the exact command of each run

Methods (columns): MPM-P1 = grid.basis=linear + direct mapping; DDMPM / MPM-maxent = grid.basis=ddmpm / maxent + direct;
BSMPM = bspline2 + direct; BSMPM-MLS / BSMPM-TLS = bspline2 + algorithm.mapping=mls / tls; each with
algorithm.update=usl and musl. OTM-P1 / OTM-maxent / unified: algorithm.update=otm / otm / unified with linear /
maxent / bspline2 and the consistent mass. A run the engine refuses because the
method is not built yet (exit 2, "only direct ...") is "n/a"; it starts counting once the engine accepts it.

Outcomes of one run: "ok" (exit 0), "exit 3 @ step N: why" (unstable, the engine's reason), "refused (exit 2)"
(a case that expects refusal, e.g. a time step above the critical one: the correct outcome), "exit 2: why" (an
unexpected refusal), "timeout", "exit 1" / "signal" (an engine error: the runner's exit status is then 1).

The page keeps a hand-written block between <!-- conclusions:begin --> and <!-- conclusions:end --> across
regenerations: update it when the results change.
"""
from __future__ import annotations

import argparse
import concurrent.futures as futures
import copy
import datetime
import json
import math
import os
import platform
import re
import shlex
import subprocess
import sys
import tempfile
import time
from dataclasses import dataclass, field

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
SCENES = os.path.join("tools", "scenes", "stability")

DRIFT_WARN = 0.1  # energy drift that flags a completed run of a case without external work

SCHEMES = ["usl", "musl"]
# the basis carried by the body (thesis Algorithms 3-4): the update is the method, with the consistent mass
MOVING = ["algorithm.mapping=direct", "algorithm.mass=consistent"]
METHODS = [  # (label, overrides, schemes)
    ("MPM-P1", ["grid.basis=linear", "algorithm.mapping=direct"], SCHEMES),
    ("DDMPM", ["grid.basis=ddmpm", "algorithm.mapping=direct"], SCHEMES),
    ("MPM-maxent", ["grid.basis=maxent", "algorithm.mapping=direct"], SCHEMES),
    ("BSMPM", ["grid.basis=bspline2", "algorithm.mapping=direct"], SCHEMES),
    ("BSMPM-MLS", ["grid.basis=bspline2", "algorithm.mapping=mls"], SCHEMES),
    ("BSMPM-TLS", ["grid.basis=bspline2", "algorithm.mapping=tls"], SCHEMES),
    ("OTM-P1", ["grid.basis=linear"] + MOVING, ["otm"]),
    ("OTM-maxent", ["grid.basis=maxent"] + MOVING, ["otm"]),
    ("unified", ["grid.basis=bspline2"] + MOVING, ["unified"]),
]


def column_of(method: str, scheme: str) -> str:
    """A table column: method and scheme, or the method alone where the update is the method (OTM, unified)."""
    return method if scheme in ("otm", "unified") else f"{method} {scheme.upper()}"


# ---------------------------------------------------------------------------------------------------------------
# Scenes: just enough of the scene contract to compute the critical time step and the plate's period.

def load_scene(name: str) -> dict:
    with open(os.path.join(ROOT, SCENES, name)) as f:
        return json.load(f)


def apply_sets(scene: dict, sets: list[str]) -> dict:
    """The --set semantics of the CLI for the plain dotted keys used here (JSON value, else a bare string)."""
    s = copy.deepcopy(scene)
    for a in sets:
        key, text = a.split("=", 1)
        try:
            value = json.loads(text)
        except ValueError:
            value = text
        parts = key.split(".")
        node = s
        for p in parts[:-1]:
            node = node[int(p)] if isinstance(node, list) else node.setdefault(p, {})
        last = parts[-1]
        if isinstance(node, list):
            node[int(last)] = value
        elif value is None:
            node.pop(last, None)
        else:
            node[last] = value
    return s


def wave_speed(material: dict) -> float:
    """P-wave speed sqrt((lambda + 2 mu) / rho), as engine/material.hpp computes the critical step."""
    E, nu, rho = material["E"], material.get("nu", 0.0), material["density"]
    lam = E * nu / ((1 + nu) * (1 - 2 * nu))
    mu = E / (2 * (1 + nu))
    return math.sqrt((lam + 2 * mu) / rho)


def critical_dt(scene: dict) -> float:
    """h_min / c of the scene's material (the engine's start-up check, engine/simulation.cpp)."""
    d = scene["dimension"]
    h = min(scene["grid"]["length"][i] / scene["grid"]["cells"][i] for i in range(d))
    return h / wave_speed(scene["material"])


def fmt(x: float) -> str:
    return f"{x:.3g}"


# ---------------------------------------------------------------------------------------------------------------
# Cases

@dataclass
class Case:
    family: str
    name: str              # row label
    scene: str             # file in tools/scenes/stability/
    sets: list[str] = field(default_factory=list)
    expect_refusal: bool = False
    conserves_energy: bool = False  # no body force, no gravity: kinetic + strain energy should stay constant
    drift_warn: float | None = None   # a completed run whose energy drift exceeds this is flagged (default: 0.1
                                      # when conserves_energy)
    u_warn: float | None = None       # ... or whose RMS displacement error exceeds this (the plate: its amplitude A)
    u_warn_why: str = "u error > A"   # the flag's words (e.g. the known cause)

    def __post_init__(self):
        if self.drift_warn is None and self.conserves_energy:
            self.drift_warn = DRIFT_WARN


@dataclass
class Family:
    key: str
    title: str
    text: str              # what the family tests and how
    cases: list[Case] = field(default_factory=list)


# kinetic + strain energy of the falling blocks may grow by the work of gravity: at most ~3 E(0) here (40 kg
# falling 0.1 m after starting at 1 m/s; the block-falling scene drops 0.5 m: ~10 E(0)). Far above that it blew up.
GRAVITY_DRIFT_WARN = 30.0


def build_families() -> list[Family]:
    fams: list[Family] = []

    # -- stiff materials: E from 1e6 to 1e11, time step from time.cfl; the plate for 1.625 of its periods 2L/c
    plate = load_scene("plate.json")
    f = Family("stiff", "Stiff materials (E = 1e6 … 1e11 Pa, time step from time.cfl = 0.5)",
               "The vibrating plate (`plate.json`: 16×16 cells, 2×2 particles per cell, A = 0.05, neo-Hookean, ν = 0.3) "
               "with `time.cfl = 0.5` instead of a fixed step, run for 1.625 periods 2L/c of the exact solution "
               "(c = √(E/ρ)), so every E takes the same number of steps and ends where all exact fields are non-zero. "
               "The drift is |E(t) − E(0)|/E(0) of kinetic + strain energy; the plate is driven by a body force, so "
               "it measures work done, not a conservation error. The plate's motion scales with c, so its rows should be "
               "identical for every E (a check of round-off and scaling). `block-impact.json` does not scale: a "
               "0.2 m block (20×20 cells, cfl 0.5) falls at 1 m/s under gravity onto the fixed floor 0.1 m below "
               "and bounces (T = 0.15 s; 220 steps at E = 1e6, 70 000 at 1e11); strain ≈ v/c shrinks with E. Its "
               "drift includes the work of gravity (≈ 1–3 E(0)); above 30 E(0) the run is flagged.")
    for E in [1e6, 1e7, 1e8, 1e9, 1e10, 1e11]:
        c = math.sqrt(E / plate["material"]["density"])
        end = 1.625 * 2 * plate["grid"]["length"][0] / c
        f.cases.append(Case(f.key, f"plate, E = {E:.0e}", "plate.json",
                            [f"material.E={E:.1e}", "time.dt=null", "time.cfl=0.5", f"time.end={end:.6g}"],
                            u_warn=0.05))
    for E in [1e6, 1e7, 1e8, 1e9, 1e10, 1e11]:
        f.cases.append(Case(f.key, f"block impact, E = {E:.0e}", "block-impact.json", [f"material.E={E:.1e}"],
                            drift_warn=GRAVITY_DRIFT_WARN))
    fams.append(f)

    # -- near-incompressible
    f = Family("nu", "Near-incompressible (ν = 0.3 … 0.499, time step from time.cfl = 0.5 and 0.25)",
               "The plate (`plate.json`, 16×16 cells, A = 0.05, E = 1e7) to T = 0.0075 s, past the first maximum "
               "compression (t = 0.005 s), with growing Poisson's ratio; the P-wave "
               "speed √((λ+2μ)/ρ) grows from 116 to 1293 m/s, and `time.cfl` shrinks the step with it. Under "
               "compression a nearly incompressible neo-Hookean material stiffens fast, so the step fixed at the "
               "start from cfl 0.5 can fall behind the current critical step (the engine then stops with “CFL "
               "violated”); cfl 0.25 leaves room for it. ν = 0.3 is the reference row. Exact solution and body "
               "force follow ν (PROBLEMS.md). At ν = 0.499 the runs that complete are stable but inaccurate: "
               "volumetric locking of the fully integrated basis (no B-bar / F-bar), flagged “u error > A: "
               "locking” — the energy balance holds (gain 0: the energy only falls behind the body force's work), "
               "J stays above 0.3, and the error barely falls with the cell size (BSMPM USL, cfl 0.25: RMS u error "
               "0.129 at 16×16 and 0.113 at 32×32 cells, against 0.029 → 0.022 at ν = 0.49 and 0.0026 at ν = 0.3).")
    for cfl in [0.5, 0.25]:
        for nu in [0.3, 0.45, 0.49, 0.499]:
            f.cases.append(Case(f.key, f"ν = {nu}, cfl {cfl}", "plate.json",
                                [f"material.nu={nu}", "time.dt=null", f"time.cfl={cfl}", "time.end=0.0075"],
                                u_warn=0.05, u_warn_why="u error > A: locking" if nu >= 0.499 else "u error > A"))
    fams.append(f)

    # -- large deformation: plate amplitude
    f = Family("amplitude", "Large deformation: the vibrating plate at growing amplitude",
               "The plate (`plate-fine.json`: 32×32 cells, 2×2 particles per cell, dt = 5e-5 ≈ 0.19 h/c) for "
               "T = 0.0325 s = 1.625 periods: maximum compression is passed three times (in x at t = 0.005 and "
               "0.025 s, in y at 0.015 s). The smallest exact J = (1 − 2πA)² is given per row. The exact "
               "displacement amplitude is A: a completed run whose RMS displacement error exceeds A is flagged. "
               "The parser caps A at 0.15.")
    for A in [0.05, 0.08, 0.10, 0.12, 0.15]:
        jmin = (1 - 2 * math.pi * A) ** 2
        f.cases.append(Case(f.key, f"A = {A:.2f} (J ≥ {jmin:.2g})", "plate-fine.json",
                            [f"problem.amplitude={A}"], u_warn=A))
    fams.append(f)

    # -- particles per cell
    f = Family("ppc", "Particles per cell (1, 2, 4)",
               "2D: the plate at A = 0.1 (`plate-fine.json`, as in the amplitude table) with 1, 2 and 4 particles per cell "
               "(1×1, 2×1, 2×2): a linear least-squares fit in 2D needs 3 particles in a cell, so 1 and 2 force "
               "the reconstructions to fall back. "
               "1D: the large-deformation bar (`bar-large.json`, thesis Table 5.4: E = 4e4, ρ = 2000, v0 = 0.8, "
               "20 cells, T = 0.5 s; its particles cross cells many times) with 1, 2 and 4 particles per cell.")
    for layout in [[1, 1], [2, 1], [2, 2]]:
        n = layout[0] * layout[1]
        f.cases.append(Case(f.key, f"plate A = 0.1, {n} per cell ({layout[0]}×{layout[1]})", "plate-fine.json",
                            ["problem.amplitude=0.1", f"particles.per_cell={json.dumps(layout, separators=(',', ':'))}"],
                            u_warn=0.1))
    for n in [1, 2, 4]:
        f.cases.append(Case(f.key, f"bar (large), {n} per cell", "bar-large.json", [f"particles.per_cell=[{n}]"],
                            conserves_energy=True))
    fams.append(f)

    # -- cells that empty and refill
    f = Family("empty", "Cells that empty and refill",
               "`bar-traction.json`: thesis §4.6.2 (neo-Hookean bar with end traction in a longer grid; cells empty "
               "during the run). `block-falling.json`: a 0.2 × 0.2 m block "
               "falling under gravity through empty grid (40×40 cells, cfl 0.5) and hitting the fixed floor at "
               "t ≈ 0.23 s (T = 0.4 s); its drift includes the work of gravity (the energy has no potential term). "
               "`block-moving-1d/2d.json`: a free block moving at constant velocity across empty cells for 0.5 s "
               "(its energy must stay constant). `bar-large.json` at 8 per cell: the particles cross cell "
               "boundaries and leave cells partly empty.")
    f.cases += [
        Case(f.key, "bar with traction (1D)", "bar-traction.json"),
        Case(f.key, "block falling under gravity (2D)", "block-falling.json", drift_warn=GRAVITY_DRIFT_WARN),
        Case(f.key, "block moving across empty cells (1D)", "block-moving-1d.json", conserves_energy=True),
        Case(f.key, "block moving across empty cells (2D)", "block-moving-2d.json", conserves_energy=True),
        Case(f.key, "bar (large), 8 per cell", "bar-large.json", conserves_energy=True),
    ]
    fams.append(f)

    # -- long run
    f = Family("long", "Long run (1e5 steps)",
               "The small bar (`bar-long.json`: thesis Table 5.2 material, 10 cells, 12 particles per cell, "
               "dt = 1e-5, T = 1 s ≈ 30 periods, 100 000 steps). No body force: the drift is the energy error of "
               "the scheme.")
    f.cases.append(Case(f.key, "bar, 10 cells, 1e5 steps", "bar-long.json", conserves_energy=True))
    fams.append(f)

    # -- time step near the critical one
    bar = load_scene("bar-critical.json")
    f = Family("critical", "Time step near, at and just above the critical one",
               "The engine's critical step is h / max_p (c(J_p) + |v_p|) (cell size over the fastest signal: "
               "the tangent P-wave speed at the particle's J plus its speed), one definition for the start and "
               "every step. The rows give dt in units of h/c of the undeformed material at rest. "
               "`bar-critical.json` (20 cells, 4 per cell, T = 0.1 s) and the plate (`plate.json`, 16×16, "
               "T = 0.0225 s). A `time.dt` above the critical step of the initial state must be refused at start "
               "(exit 2) and `time.cfl` above 1 is refused by the parser (exit 2): both are marked “refused (exit "
               "2)”, the correct outcome. With `time.cfl` the engine also checks every step that dt stays below the "
               "current critical step and stops the run (exit 3, “CFL violated”) when it does not; a `time.dt` "
               "given explicitly is not watched that way, so the dt = 0.9 and 0.99 h/c rows show whether the "
               "scheme itself stays stable just below the start-up limit.")
    for label, scene_name, base, cfls in [("bar", "bar-critical.json", bar, [0.9, 1.0]),
                                          ("plate", "plate.json", plate, [0.8, 0.9, 1.0])]:
        dtc = critical_dt(base)
        cons = label == "bar"
        uw = None if cons else 0.05
        for c in cfls:
            f.cases.append(Case(f.key, f"{label}: cfl = {c}", scene_name, ["time.dt=null", f"time.cfl={c}"],
                                conserves_energy=cons, u_warn=uw))
        for k in [0.9, 0.99]:
            # the plate starts moving (|v| ≈ 0.19 c): its critical step h/(c + |v|) is 0.84 h/c, so a time.dt of
            # 0.9 h/c is above it and must be refused; the bar starts with |v| ≪ c
            f.cases.append(Case(f.key, f"{label}: dt = {k} h/c = {fmt(k * dtc)} s", scene_name,
                                ["time.cfl=null", f"time.dt={k * dtc:.6g}"], conserves_energy=cons, u_warn=uw,
                                expect_refusal=label == "plate"))
        f.cases += [
            Case(f.key, f"{label}: dt = 1.01 h/c = {fmt(1.01 * dtc)} s", scene_name,
                 ["time.cfl=null", f"time.dt={1.01 * dtc:.6g}"], expect_refusal=True),
            Case(f.key, f"{label}: cfl = 1.01", scene_name, ["time.dt=null", "time.cfl=1.01"], expect_refusal=True),
        ]
    fams.append(f)
    return fams


# ---------------------------------------------------------------------------------------------------------------
# Running

@dataclass
class Run:
    case: Case
    method: str
    scheme: str
    argv: list[str]
    key: str = ""           # the scene as run (file + every override applied): identical runs are run once
    outcome: str = ""       # ok | unstable | refused | na | invalid | timeout | error
    exit: int | None = None
    summary: dict = field(default_factory=dict)
    message: str = ""
    elapsed: float = 0.0    # process wall time, s

    @property
    def column(self) -> str:
        return column_of(self.method, self.scheme)


def command(mpm: str, case: Case, method_sets: list[str], scheme: str, summary: str, extra: list[str]) -> list[str]:
    argv = [mpm, "run", os.path.join(SCENES, case.scene)]
    for s in method_sets + [f"algorithm.update={scheme}"] + case.sets + extra:
        argv += ["--set", s]
    return argv + ["--threads", "1", "--quiet", "--summary", summary]


# "algorithm.mapping = "mls": only "direct" is available in this build", "problem.name: ... not available in 1D yet"
NOT_BUILT = re.compile(r'only "?direct"? is available|not available', re.I)


def execute(run: Run, timeout: float, workdir: str) -> Run:
    summary_path = run.argv[-1]
    t0 = time.monotonic()
    try:
        p = subprocess.run(run.argv, cwd=ROOT, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                           errors="replace", timeout=timeout)
    except subprocess.TimeoutExpired:
        run.elapsed = time.monotonic() - t0
        run.outcome, run.message = "timeout", f"no result after {timeout:.0f} s"
        return run
    run.elapsed = time.monotonic() - t0
    run.exit = p.returncode
    if os.path.exists(summary_path):
        try:
            with open(summary_path) as f:
                run.summary = json.load(f)
        except ValueError as e:
            run.message = f"unreadable summary: {e}"
        os.remove(summary_path)
    err = (p.stderr or "").strip().splitlines()
    run.message = run.message or (run.summary.get("reason") or (err[-1] if err else "")).strip()
    run.message = re.sub(r"^mpm: ", "", run.message)
    if p.returncode == 0:
        run.outcome = "ok"
    elif p.returncode == 3:
        run.outcome = "unstable"
    elif p.returncode == 2:
        if NOT_BUILT.search(run.message):
            run.outcome = "na"  # checked first: a method that is not built is refused before the time step
        elif run.case.expect_refusal:
            run.outcome = "refused"
        else:
            run.outcome = "invalid"
    else:
        run.outcome = "error"
        if p.returncode < 0:
            run.message = f"killed by signal {-p.returncode}; " + run.message
    return run


# ---------------------------------------------------------------------------------------------------------------
# Reporting

def sci(x) -> str:
    if x is None:
        return ""
    x = float(x)
    if x == 0:
        return "0"
    return f"{x:.0e}" if abs(x) < 1e-3 or abs(x) >= 1e3 else f"{x:.2g}"


def failure(run: Run) -> tuple[str, str]:
    """(step, short reason) of an unstable run, from the engine's message."""
    m = re.sub(r";\s*last good state.*$", "", run.message)
    step = re.search(r"at step (\d+)", m)
    step_s = step.group(1) if step else str(run.summary.get("steps", "?"))
    if m.startswith("CFL violated"):
        factor = re.search(r"by a factor ([\d.e+-]+)", m)
        return step_s, "CFL violated" + (f" (dt = {float(factor.group(1)):.3g} × current critical)" if factor else "")
    if m.startswith("energy balance violated"):
        gain = re.search(r"= ([\d.e+-]+) x scale", m)
        return step_s, "energy balance" + (f" (gain {float(gain.group(1)):.2g} × max E)" if gain else "")
    tail = re.search(r":\s*([^:]+)$", m)
    why = tail.group(1).strip() if tail else m
    stage = re.search(r"\),\s*([\w\-+ ]+):\s*particle", m)
    if stage:
        why = f"{why} in {stage.group(1).strip()}"
    return step_s, why


def shorten(text: str, n: int = 70) -> str:
    text = text.replace("|", "\\|")
    return text if len(text) <= n else text[: n - 1] + "…"


def silent_blowup(run: Run) -> str:
    """Why a completed run is not a success after all ("" if it is one)."""
    if run.outcome != "ok":
        return ""
    drift = run.summary.get("energy", {}).get("drift_rel_max")
    gain = run.summary.get("energy", {}).get("balance_gain_max")
    u = run.summary.get("errors", {}).get("displacement_rms")
    # without external work only a gain is a blow-up (a loss is the scheme's dissipation): the balance's gain;
    # with gravity the drift, which includes the work of gravity, against a generous bound (a cross-check that
    # does not rely on the engine's own bookkeeping)
    if run.case.conserves_energy and gain is not None and gain > run.case.drift_warn:
        return "energy grew"
    if not run.case.conserves_energy and run.case.drift_warn is not None and drift is not None and drift > run.case.drift_warn:
        return "energy grew"
    if run.case.u_warn is not None and u is not None and u > run.case.u_warn:
        return run.case.u_warn_why
    return ""


def cell(run: Run) -> str:
    s = run.summary
    if run.outcome == "ok":
        drift = s.get("energy", {}).get("drift_rel_max")
        parts = [f"drift {sci(drift)}", f"gain {sci(s.get('energy', {}).get('balance_gain_max'))}"]
        if "errors" in s:
            parts.append(f"u err {sci(s['errors'].get('displacement_rms'))}")
        falls = sum(s.get("fallbacks", {}).values()) if s.get("fallbacks") else 0
        if falls:
            parts.append(f"{falls} fallbacks")
        warn = silent_blowup(run)
        return (f"**ok ⚠ {warn}**" if warn else "ok") + f" ({', '.join(parts)})"
    if run.outcome == "unstable":
        step, why = failure(run)
        return f"**exit 3 @ step {step}**: {shorten(why, 60)}"
    if run.outcome == "refused":
        return "refused (exit 2)"
    if run.outcome == "na":
        return "n/a"
    if run.outcome == "timeout":
        return "**timeout**"
    if run.outcome == "invalid":
        return f"exit 2: {shorten(run.message, 50)}"
    return f"**exit {run.exit}**: {shorten(run.message, 50)}"


def expectation_broken(run: Run) -> bool:
    return run.case.expect_refusal and run.outcome not in ("refused", "na")


def row_label(case: Case) -> str:
    return case.name + (" — expect refusal" if case.expect_refusal else "")


def details_row(run: Run) -> str:
    s = run.summary
    cons = s.get("conservation", {})
    falls = s.get("fallbacks", {})
    errs = s.get("errors", {})
    step, why = failure(run) if run.outcome == "unstable" else ("", "")
    fb = ", ".join(f"{k} {v}" for k, v in sorted(falls.items()) if v) or ("0" if falls else "")
    msg = why if run.outcome == "unstable" else ("" if run.outcome == "ok" else run.message)
    return "| " + " | ".join([
        run.case.name, run.column, {"na": "n/a"}.get(run.outcome, run.outcome) + (" ✗" if expectation_broken(run) else ""),
        str(s.get("steps", "")), step, shorten(msg, 90), sci(s.get("energy", {}).get("drift_rel_max")),
        sci(s.get("energy", {}).get("balance_gain_max")), sci(s.get("energy", {}).get("balance_loss_max")),
        sci(cons.get("mass_rel_max")), sci(cons.get("momentum_rel_max")), fb,
        sci(errs.get("displacement_rms")), f"{s['wall_s']:.2f}" if "wall_s" in s else "", f"{run.elapsed:.1f}",
    ]) + " |"


def survival(runs: list[Run], columns: list[str]) -> list[str]:
    lines = ["| method | ran | ok | ok ⚠ (blew up or meaningless) | blew up (J ≤ 0, non-finite, left grid) | stopped by the CFL "
             "check | stopped by the energy guard | other | refused as expected | cases not completed cleanly |",
             "|---|---|---|---|---|---|---|---|---|---|"]
    for col in columns:
        mine = [r for r in runs if r.column == col]
        ran = [r for r in mine if r.outcome != "na" and not r.case.expect_refusal]
        warn = [r for r in ran if silent_blowup(r)]
        ok = [r for r in ran if r.outcome == "ok" and r not in warn]
        cfl = [r for r in ran if r.outcome == "unstable" and r.message.startswith("CFL violated")]
        energy = [r for r in ran if r.outcome == "unstable" and r.message.startswith("energy balance")]
        bad = [r for r in ran if r.outcome == "unstable" and r not in cfl and r not in energy]
        other = [r for r in ran if r.outcome not in ("ok", "unstable")]
        refused = [r for r in mine if r.case.expect_refusal and r.outcome == "refused"]
        exp = [r for r in mine if r.case.expect_refusal and r.outcome != "na"]
        if not ran:
            note = f" (refused as expected: {len(refused)}/{len(exp)})" if exp else ""
            lines.append(f"| {col} | not available{note} | | | | | | | | |")
            continue
        def tag(r: Run) -> str:
            if r in warn:
                return "⚠ " + silent_blowup(r)
            if r in cfl:
                return "CFL"
            if r in energy:
                return "energy"
            if r.outcome == "unstable":
                return failure(r)[1].split(" in ")[0].replace("<=", "≤")
            return r.outcome
        names = "; ".join(f"{r.case.name} ({tag(r)})" for r in bad + warn + cfl + energy + other) or "—"
        lines.append(f"| {col} | {len(ran)} | {len(ok)} | {len(warn)} | {len(bad)} | {len(cfl)} | {len(energy)} | {len(other)} | "
                     f"{len(refused)}/{len(exp)} | {names} |")
    return lines


def render(fams: list[Family], runs: list[Run], argv: list[str], mpm: str, total_s: float, jobs: int,
           conclusions: str) -> str:
    columns = [column_of(m, s) for m, _, schemes in METHODS for s in schemes]
    by_key = {(r.case.family, r.case.name, r.column): r for r in runs}
    out = [
        "# Stability suite",
        "",
        "Which method survives which hard case. Generated by `tools/stability.py`; do not edit by hand except the "
        "conclusions block (kept across regenerations).",
        "",
        f"Generated with: `{' '.join(shlex.quote(a) for a in argv)}`  ",
        f"on {datetime.date.today().isoformat()}, {platform.machine()}, {os.cpu_count()} cores, {jobs} runs at a time "
        f"with `--threads 1`; engine `{os.path.relpath(mpm, ROOT) if os.path.isabs(mpm) else mpm}`; "
        f"{len({r.key for r in runs})} distinct runs in {total_s / 60:.1f} min.",
        "",
        "Columns: **MPM-P1** = `grid.basis=linear`, direct mapping; **DDMPM / MPM-maxent** = `grid.basis=ddmpm / "
        "maxent`, direct; **BSMPM** = `grid.basis=bspline2`, direct; "
        "**BSMPM-MLS / BSMPM-TLS** = bspline2 with `algorithm.mapping=mls / tls`; each with `algorithm.update=usl` "
        "and `musl`; lumped mass. **OTM-P1 / OTM-maxent** = `algorithm.update=otm` with linear / maxent, **unified** = "
        "`algorithm.update=unified` with bspline2, both with `algorithm.mass=consistent` (thesis Algorithms 3–4). Each run is `mpm run tools/scenes/stability/SCENE --set <method> "
        "--set algorithm.update=<scheme> --set <case> --threads 1 --summary S.json` (`--list` prints every command).",
        "",
        "Cells: `ok (drift D, gain G, u err U)` — completed; D = max |E(t) − E(0)| / E(0) of kinetic + strain energy "
        "(sampled 200 times per run; it includes the work of body forces and gravity where there are any); G = the "
        "largest energy gain the external work does not explain, max (E(t) − E(0) − W_ext(t)) / max(E(0), max E), "
        "which the engine's energy guard stops at `time.energy_tolerance` (0.15; “exit 3 … energy balance”); U = RMS "
        "displacement error against the exact solution at the end (where there is one); "
        f"`ok ⚠ energy grew` — completed, but the energy of a case without external work grew by more than "
        f"{DRIFT_WARN:.0%} of its largest value (G > {DRIFT_WARN}; for the falling blocks: a drift above "
        f"{GRAVITY_DRIFT_WARN:.0f} E(0)), a blow-up the engine did not stop; `ok ⚠ u error > A` — completed, but the plate's RMS displacement error exceeds its amplitude: "
        "the result is meaningless; `exit 3 @ step N: why` — the engine stopped the run as unstable (exit 3) at step N; "
        "`refused (exit 2)` — refused at start, the expected outcome of a time step above the critical one; "
        "`n/a` — the engine refuses the method or problem as not available yet (exit 2); `exit 2: …` — an "
        "unexpected refusal; `timeout`; `exit 1` — an engine error. Conservation errors, fallback counts, RMS "
        "errors and wall times of every run are in the details at the end.",
        "",
    ]
    for fam in fams:
        cases = [c for c in fam.cases if any((fam.key, c.name, col) in by_key for col in columns)]
        if not cases:
            continue
        out += [f"## {fam.title}", "", fam.text, "", "| case | " + " | ".join(columns) + " |",
                "|---|" + "---|" * len(columns)]
        for c in cases:
            cells = []
            for col in columns:
                r = by_key.get((fam.key, c.name, col))
                cells.append("" if r is None else cell(r) + (" ✗ not refused" if expectation_broken(r) else ""))
            out.append(f"| {row_label(c)} | " + " | ".join(cells) + " |")
        out.append("")
    out += ["## Who survives what", "",
            "Counted over the cases that are expected to run (the “expect refusal” rows are counted separately).", ""]
    out += survival(runs, columns)
    out += ["", "## Conclusions", "", "<!-- conclusions:begin -->", conclusions.strip() or
            "_(write the conclusions from the tables above)_", "<!-- conclusions:end -->", ""]
    out += ["## Details of every run", "", "<details><summary>one row per run</summary>", "",
            "| case | method | outcome | steps | failed at | reason | drift | gain | loss | mass err | momentum err | "
            "fallbacks | u RMS | stepping s | process s |",
            "|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|"]
    order = {(f.key, c.name): i for i, (f, c) in enumerate((f, c) for f in fams for c in f.cases)}
    for r in sorted(runs, key=lambda r: (order.get((r.case.family, r.case.name), 0), columns.index(r.column))):
        out.append(details_row(r))
    out += ["", "</details>", ""]
    return "\n".join(out)


def old_conclusions(path: str) -> str:
    try:
        text = open(path).read()
    except OSError:
        return ""
    m = re.search(r"<!-- conclusions:begin -->\n(.*?)<!-- conclusions:end -->", text, re.S)
    return m.group(1) if m else ""


# ---------------------------------------------------------------------------------------------------------------

def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--mpm", default=os.path.join("build", "tools", "mpm"), help="the mpm binary (default: %(default)s)")
    ap.add_argument("--jobs", type=int, default=2, help="runs at a time, one thread each (default: %(default)s)")
    ap.add_argument("--timeout", type=float, default=300, help="seconds per run before it counts as a timeout")
    ap.add_argument("--family", action="append", help="run only this family (repeatable): stiff, nu, amplitude, "
                    "ppc, empty, long, critical")
    ap.add_argument("--out", default=os.path.join("docs", "STABILITY.md"), help="the page to write (default: %(default)s)")
    ap.add_argument("--raw", help="also write every run's summary and message as JSON to this file")
    ap.add_argument("--list", action="store_true", help="print the runs and exit")
    ap.add_argument("--set", action="append", default=[], metavar="KEY=VALUE",
                    help="one more override for every run, e.g. time.energy_tolerance=1e9 to measure the energy "
                    "balance with the guard off (repeatable; the page's header records it)")
    args = ap.parse_args()

    mpm = args.mpm if os.path.isabs(args.mpm) else os.path.join(ROOT, args.mpm)
    fams = build_families()
    if args.family:
        unknown = set(args.family) - {f.key for f in fams}
        if unknown:
            ap.error(f"unknown family {', '.join(sorted(unknown))}; known: {', '.join(f.key for f in fams)}")
        fams = [f for f in fams if f.key in args.family]

    tmp = tempfile.mkdtemp(prefix="mpm-stability-")
    runs: list[Run] = []
    for fam in fams:
        for case in fam.cases:
            for method, msets, schemes in METHODS:
                for scheme in schemes:
                    summary = os.path.join(tmp, f"run{len(runs)}.json")
                    sets = msets + [f"algorithm.update={scheme}"] + case.sets + args.set
                    key = json.dumps(apply_sets(load_scene(case.scene), sets), sort_keys=True)
                    runs.append(Run(case, method, scheme, command(mpm, case, msets, scheme, summary, args.set), key))
    if args.list:
        for r in runs:
            print(f"[{r.case.family}] {r.case.name} | {r.column}:\n  " +
                  " ".join(shlex.quote(a) for a in r.argv[:-2]))
        return 0
    if not os.access(mpm, os.X_OK):
        print(f"stability: no mpm binary at {mpm}; build first (bash tools/build.sh) or pass --mpm", file=sys.stderr)
        return 1

    # a case that appears in two families (e.g. the plate at A = 0.1 with 2×2 particles) runs once
    unique: dict[tuple, Run] = {}
    for r in runs:
        unique.setdefault(r.key, r)
    t0 = time.monotonic()
    done = 0
    # the slowest methods first, so that the two workers finish together
    order = sorted(unique.values(), key=lambda r: r.method not in ("BSMPM-MLS",))
    with futures.ThreadPoolExecutor(max_workers=max(1, args.jobs)) as pool:
        pending = [pool.submit(execute, r, args.timeout, tmp) for r in order]
        for fut in futures.as_completed(pending):
            r = fut.result()
            done += 1
            print(f"[{done}/{len(unique)}] {time.monotonic() - t0:6.0f} s  {r.case.family:9s} {r.case.name:40s} "
                  f"{r.column:15s} {cell(r)}  ({r.elapsed:.1f} s)", file=sys.stderr, flush=True)
    for r in runs:
        first = unique[r.key]
        if first is not r:
            r.outcome, r.exit, r.summary, r.message, r.elapsed = (first.outcome, first.exit, first.summary,
                                                                  first.message, first.elapsed)
    total = time.monotonic() - t0
    try:
        os.rmdir(tmp)
    except OSError:
        pass

    out = args.out if os.path.isabs(args.out) else os.path.join(ROOT, args.out)
    argv = ["python3", "tools/stability.py"] + sys.argv[1:]
    page = render(fams, runs, argv, args.mpm, total, args.jobs, old_conclusions(out))
    os.makedirs(os.path.dirname(out), exist_ok=True)
    with open(out + ".partial", "w") as f:
        f.write(page)
    os.replace(out + ".partial", out)
    if args.raw:
        with open(args.raw, "w") as f:
            json.dump([{"family": r.case.family, "case": r.case.name, "method": r.method, "scheme": r.scheme,
                        "command": r.argv[:-2], "outcome": r.outcome, "exit": r.exit, "message": r.message,
                        "elapsed_s": r.elapsed, "summary": r.summary} for r in runs], f, indent=1)
    print(f"stability: {len(runs)} runs in {total / 60:.1f} min; wrote {os.path.relpath(out, ROOT)}", file=sys.stderr)

    errors = [r for r in runs if r.outcome in ("error",)]
    broken = [r for r in runs if expectation_broken(r)]
    for r in errors:
        print(f"stability: ENGINE ERROR: {r.case.name} {r.column}: exit {r.exit}: {r.message}\n  "
              + " ".join(shlex.quote(a) for a in r.argv[:-2]), file=sys.stderr)
    for r in broken:
        print(f"stability: NOT REFUSED: {r.case.name} {r.column}: {r.outcome}\n  "
              + " ".join(shlex.quote(a) for a in r.argv[:-2]), file=sys.stderr)
    return 1 if errors or broken else 0


if __name__ == "__main__":
    sys.exit(main())
