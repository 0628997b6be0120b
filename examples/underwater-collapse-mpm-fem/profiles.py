#!/usr/bin/env python3
"""D2 deposit profiles and the pressure field's checkerboard index of a swmpm run.

usage: profiles.py RUN_DIR [RUN_DIR ...]

For each run and each time 0, 0.5, 1, 1.5 and 2 s (the frame nearest it), from `swmpm postprocess
frame`:
- the deposit's surface height h(x) [mm]: the highest soil point in each 2.5 mm column plus half a
  point spacing, at x = 0, 10, 20, ... mm;
- the runout: the largest x of a soil point plus half a spacing [mm];
- the pressure's checkerboard index: the RMS deviation of each value from the least-squares plane
  through its neighbours within 1.6 spacings, over the field's range (the same definition as the
  run's own stability indicators, docs/verification.md, read from run.json when the run has them).
  mpm-fem: the grid nodes with phi >= 1/2; explicit-double-point: the liquid points. The
  hydrostatic gradient is a plane and does not count.
Prints Markdown tables. Needs only the swmpm on PATH (or $SWMPM).
"""
import csv
import math
import os
import subprocess
import sys

SWMPM = os.environ.get("SWMPM", "swmpm")
TIMES = [0.0, 0.5, 1.0, 1.5, 2.0]
BIN = 0.0025  # m, the grid's cell
STATIONS = [0.0, 0.01, 0.02, 0.03, 0.04, 0.05, 0.06, 0.07, 0.08, 0.10, 0.12]


def frame(run, t, phase):
    out = subprocess.run([SWMPM, "postprocess", run, "frame", "--time", str(t), "--phase", phase, "-q"],
                         capture_output=True, text=True, check=True).stdout
    lines = out.splitlines()
    when = next((l for l in lines if l.startswith("# the frame at t =")), "")
    t_frame = float(when.split("=")[1].split()[0]) if when else float("nan")
    return t_frame, list(csv.DictReader(l for l in lines if not l.startswith("#")))


def profile(rows):
    half = max(float(r["half_size_x"]) for r in rows) if "half_size_x" in rows[0] else 0.0
    if half == 0.0:  # mpm-fem's points: a quarter of a cell apart
        half = BIN / 8
    top = {}
    for r in rows:
        x, y = float(r["x"]), float(r["y"])
        k = int(x / BIN)
        top[k] = max(top.get(k, 0.0), y + half)
    heights = [1000 * top.get(int(s / BIN), 0.0) for s in STATIONS]
    runout = 1000 * (max(float(r["x"]) for r in rows) + half)
    return heights, runout


def checkerboard(points, values, spacing):
    """RMS residual of a local plane fit (radius 1.6 spacings, >= 6 neighbours) over the range."""
    radius = 1.6 * spacing
    bins = {}
    for i, (x, y) in enumerate(points):
        bins.setdefault((int(x // radius), int(y // radius)), []).append(i)
    lo, hi = min(values), max(values)
    scale = max(hi - lo, 0.01 * max(abs(lo), abs(hi)))
    if not scale > 0:
        return 0.0
    sq, fitted = 0.0, 0
    for i, (x, y) in enumerate(points):
        bx, by = int(x // radius), int(y // radius)
        s = [[0.0] * 3 for _ in range(3)]
        b = [0.0] * 3
        count = 0
        for dx in (-1, 0, 1):
            for dy in (-1, 0, 1):
                for j in bins.get((bx + dx, by + dy), ()):
                    qx, qy = points[j][0] - x, points[j][1] - y
                    if qx * qx + qy * qy > radius * radius:
                        continue
                    row = (1.0, qx, qy)
                    for a in range(3):
                        b[a] += row[a] * values[j]
                        for c in range(3):
                            s[a][c] += row[a] * row[c]
                    count += 1
        if count < 6:
            continue
        fit = solve3(s, b)
        if fit is None:
            continue
        sq += (values[i] - fit) ** 2
        fitted += 1
    return math.sqrt(sq / fitted) / scale if fitted else 0.0


def solve3(a, b):
    """The first unknown of a 3 x 3 system (Cramer's rule)."""
    def det(m):
        return (m[0][0] * (m[1][1] * m[2][2] - m[1][2] * m[2][1]) - m[0][1] * (m[1][0] * m[2][2] - m[1][2] * m[2][0])
                + m[0][2] * (m[1][0] * m[2][1] - m[1][1] * m[2][0]))
    d = det(a)
    if abs(d) < 1e-300:
        return None
    m = [[b[r], a[r][1], a[r][2]] for r in range(3)]
    return det(m) / d


def pressure_index(run):
    """The pressure checkerboard index at each of TIMES: the run's own (run.json "stability", swmpm
    from 2026-12-05 on), else computed here from mpm-fem's grid frames."""
    import json
    with open(os.path.join(run, "run.json")) as f:
        r = json.load(f)
    formulation = r.get("formulation", "")
    frames = r.get("stability", {}).get("frames", {})
    if frames.get("pressure_checkerboard"):
        ts, cb = frames["time"], frames["pressure_checkerboard"]
        return formulation, [cb[min(range(len(ts)), key=lambda k: abs(ts[k] - t))] for t in TIMES]
    if formulation != "mpm-fem":
        return formulation, [float("nan")] * len(TIMES)
    out = []
    for t in TIMES:
        _, rows = frame(run, t, "grid")
        rows = [r for r in rows if float(r["phase_field"]) >= 0.5]
        xs = sorted({round(float(r["x"]), 9) for r in rows})
        gaps = sorted(b - a for a, b in zip(xs, xs[1:]))
        pts = [(float(r["x"]), float(r["y"])) for r in rows]
        out.append(checkerboard(pts, [float(r["pressure"]) for r in rows], gaps[len(gaps) // 2]))
    return formulation, out


def main():
    for run in sys.argv[1:]:
        formulation, index = pressure_index(run)
        print(f"\n### {run} ({formulation})\n")
        print("| t [s] | frame [s] | runout [mm] | " + " | ".join(f"h({1000 * s:.0f})" for s in STATIONS)
              + " | p checkerboard |")
        print("|---" * (len(STATIONS) + 4) + "|")
        for t, cb in zip(TIMES, index):
            tf, rows = frame(run, t, "solid")
            h, runout = profile(rows)
            print(f"| {t:.1f} | {tf:.3f} | {runout:.1f} | " + " | ".join(f"{v:.1f}" for v in h) + f" | {cb:.4f} |")


if __name__ == "__main__":
    main()
