#!/usr/bin/python3
"""Plots the table of an `mpm study`: convergence (error against cell size) and error against wall time.

Usage: tools/plot_study.py DIR/study.h5 [--out DIR]
       tools/plot_study.py DIR/study.csv [--out DIR] [--length L]     (or --csv DIR/study.csv)

Writes DIR/convergence.png: RMS error of displacement, velocity and stress against the cell size h = length/cells
(log-log), one line per combination of the varied keys other than grid.cells, with the fitted convergence order
(least-squares slope of log error against log h) in the legend; and DIR/error_vs_time.png: the same errors against
the wall time, with the accuracy/cost front (runs no other run beats in both error and time) dashed.
Failed runs (status other than ok) are left out of the lines and listed in a note under the figures.
From a CSV, h needs the grid length: taken from study.h5 beside the CSV if there is one, else from --length (1 m).
"""
import argparse
import csv
import json
import math
import os
import sys

RESOLUTION_KEY = "grid.cells"
ERRORS = [("displacement_rms", "displacement"), ("velocity_rms", "velocity"), ("stress_rms", "stress")]


def text(v):
    return v.decode("utf-8") if isinstance(v, bytes) else str(v)


def number(v):
    try:
        x = float(v)
    except (TypeError, ValueError):
        return math.nan
    return x


def read_h5(path):
    import h5py
    with h5py.File(path, "r") as f:
        columns = [text(c) for c in f.attrs["columns"]]
        keys = [text(k) for k in f.attrs["varied_keys"]]
        scene = json.loads(text(f.attrs["scene"]))
        table = f["table"]
        data = {}
        for name in list(table.keys()):
            ds = table[name]
            if ds.dtype.kind in ("O", "S", "U"):
                data[name] = [text(v) for v in ds[()]]
            else:
                data[name] = [float(v) for v in ds[()]]
    n = len(data["status"])
    rows = [{c: data[c][i] for c in data} for i in range(n)]
    return keys, columns, scene, rows


def read_csv(path, length):
    with open(path, newline="") as f:
        reader = csv.DictReader(f)
        columns = reader.fieldnames or []
        rows = list(reader)
    keys = columns[: columns.index("wall_s")] if "wall_s" in columns else []
    scene = None
    beside = os.path.join(os.path.dirname(os.path.abspath(path)), "study.h5")
    if length is None and os.path.exists(beside):
        try:
            scene = read_h5(beside)[2]
        except Exception:  # noqa: BLE001 - any unreadable file: fall back to --length
            scene = None
    if scene is None:
        scene = {"grid": {"length": [length if length is not None else 1.0] * 3}}
    for r in rows:
        for c in columns:
            if c not in keys and c not in ("status", "reason"):
                r[c] = number(r[c])
    return keys, columns, scene, rows


def cell_size(row, scene):
    """Smallest length/cells over the axes (the HDF5 table has it; from a CSV it is computed)."""
    h = number(row.get("cell_size"))
    if math.isfinite(h) and h > 0:
        return h
    cells = row.get(RESOLUTION_KEY)
    if cells is None:
        cells = scene.get("grid", {}).get("cells")
    else:
        try:
            cells = json.loads(cells)
        except ValueError:
            return math.nan
    length = scene.get("grid", {}).get("length", [1.0])
    if isinstance(cells, (int, float)):
        cells = [cells]
    if isinstance(length, (int, float)):
        length = [length]
    try:
        return min(float(length[i]) / float(c) for i, c in enumerate(cells))
    except (TypeError, ValueError, IndexError, ZeroDivisionError):
        return math.nan


def slope(xs, ys):
    """Least-squares slope of log y against log x over the positive, finite points (None for fewer than 2 h)."""
    pts = [(math.log(x), math.log(y)) for x, y in zip(xs, ys) if x > 0 and y > 0 and math.isfinite(x * y)]
    if len({p[0] for p in pts}) < 2:
        return None
    mx = sum(p[0] for p in pts) / len(pts)
    my = sum(p[1] for p in pts) / len(pts)
    sxx = sum((p[0] - mx) ** 2 for p in pts)
    return sum((p[0] - mx) * (p[1] - my) for p in pts) / sxx


def short_names(keys):
    """The last part of each dotted key, unless two keys would then look alike."""
    last = [k.rsplit(".", 1)[-1] for k in keys]
    return last if len(set(last)) == len(last) else list(keys)


def failed_note(rows, keys, limit=8):
    failed = [r for r in rows if r["status"] != "ok"]
    if not failed:
        return ""
    lines = ["%d of %d runs failed and are not plotted:" % (len(failed), len(rows))]
    for r in failed[:limit]:
        where = ", ".join("%s=%s" % (k, r[k]) for k in keys)
        reason = r.get("reason") or ""
        if len(reason) > 110:
            reason = reason[:107] + "..."
        lines.append("  %s: %s%s" % (where, r["status"], (" (" + reason + ")") if reason else ""))
    if len(failed) > limit:
        lines.append("  ... and %d more (see study.csv)" % (len(failed) - limit))
    return "\n".join(lines)


def pareto(points):
    """Points (t, e) not beaten in both t and e by another point, by increasing t."""
    front, best = [], math.inf
    for t, e in sorted(points):
        if e < best:
            front.append((t, e))
            best = e
    return front


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("table", nargs="?", help="study.h5 (or study.csv) written by `mpm study`")
    ap.add_argument("--csv", help="read this study.csv instead of an HDF5 file")
    ap.add_argument("--out", help="directory for the PNGs (default: the table's directory)")
    ap.add_argument("--length", type=float, help="grid length for h = length/cells when reading a CSV")
    args = ap.parse_args()
    path = args.csv or args.table
    if not path:
        ap.error("give study.h5 or --csv study.csv")

    try:
        import matplotlib
        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
    except ImportError as e:
        print("plot_study.py: matplotlib is not available (%s); no plots" % e, file=sys.stderr)
        return 3
    try:
        if args.csv or path.endswith(".csv"):
            keys, _, scene, rows = read_csv(path, args.length)
        else:
            keys, _, scene, rows = read_h5(path)
    except ImportError as e:
        print("plot_study.py: h5py is not available (%s); try --csv study.csv" % e, file=sys.stderr)
        return 3
    except (OSError, KeyError, ValueError) as e:
        print("plot_study.py: cannot read %s: %s" % (path, e), file=sys.stderr)
        return 2

    out = args.out or os.path.dirname(os.path.abspath(path))
    os.makedirs(out, exist_ok=True)
    others = [k for k in keys if k != RESOLUTION_KEY]
    names = dict(zip(others, short_names(others)))
    for r in rows:
        r["_h"] = cell_size(r, scene)
        r["_wall"] = number(r.get("wall_s"))

    # one line per combination of the non-resolution keys, in the order the study ran them
    groups = {}
    for r in rows:
        groups.setdefault(tuple(r[k] for k in others), []).append(r)

    def label_of(combo):
        return ", ".join("%s=%s" % (names[k], v) for k, v in zip(others, combo)) or "all runs"

    note = failed_note(rows, keys)
    problem = scene.get("problem", {}).get("name", "scene") if isinstance(scene.get("problem"), dict) else "scene"
    title = "%s study: %s" % (problem, " x ".join(keys) if keys else "one run")
    markers = "osD^v<>ph*"

    def figure(x_of, xlabel, name, fit, front):
        fig, axes = plt.subplots(1, len(ERRORS), figsize=(5.2 * len(ERRORS), 4.6), squeeze=False)
        axes = axes[0]
        for ax, (col, what) in zip(axes, ERRORS):
            plotted = False
            all_points = []
            for i, (combo, members) in enumerate(groups.items()):
                pts = [(x_of(r), r[col]) for r in members
                       if r["status"] == "ok" and x_of(r) > 0 and number(r[col]) > 0
                       and math.isfinite(x_of(r)) and math.isfinite(number(r[col]))]
                if not pts:
                    continue
                pts.sort()
                all_points += pts
                label = label_of(combo)
                if fit:
                    p = slope([p[0] for p in pts], [p[1] for p in pts])
                    label += " (order %s)" % ("%.2f" % p if p is not None else "n/a")
                ax.loglog([p[0] for p in pts], [p[1] for p in pts], marker=markers[i % len(markers)],
                          label=label)
                plotted = True
            if front and len(all_points) > 1:
                fr = pareto(all_points)
                ax.loglog([p[0] for p in fr], [p[1] for p in fr], "k--", lw=1, alpha=0.5, zorder=0,
                          label="accuracy/cost front")
            ax.set_xlabel(xlabel)
            ax.set_ylabel("%s error (RMS)" % what)
            ax.set_title(what)
            ax.grid(True, which="both", alpha=0.3)
            if plotted:
                ax.legend(fontsize=8)
            else:
                ax.text(0.5, 0.5, "no successful run", ha="center", va="center", transform=ax.transAxes)
        fig.suptitle(title)
        bottom = 0.0
        if note:
            nlines = note.count("\n") + 1
            bottom = min(0.5, 0.035 * nlines + 0.02)
            fig.text(0.01, 0.01, note, fontsize=8, va="bottom", ha="left", family="monospace", color="firebrick")
        fig.tight_layout(rect=(0, bottom, 1, 0.95))
        target = os.path.join(out, name)
        fig.savefig(target, dpi=110)
        plt.close(fig)
        return target

    written = [
        figure(lambda r: r["_h"], "cell size h = length / cells [m]", "convergence.png", True, False),
        figure(lambda r: r["_wall"], "wall time [s]", "error_vs_time.png", False, True),
    ]
    print("plot_study.py: wrote " + ", ".join(written))
    return 0


if __name__ == "__main__":
    sys.exit(main())
