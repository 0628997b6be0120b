#!/usr/bin/env python3
"""What migration costs a step under mpirun when the particles cross the cut every step, side by
side for two builds (issue 28): a 3D dry box (bench/mpi_scaling.py's, GIMP) sliding along the cut
axis at `--speed` m/s over frictionless rollers, on 2 ranks, one thread each. The rows: loop
seconds, the "shape functions" stage (evaluation, migration, rebalancing), the particle moves
between ranks; fastest of --repeat, the builds interleaved.

Usage: bench/mpi_migration.py --swmpm build/app/swmpm --other /tmp/old/build/app/swmpm
                              [--cells 60x20x20] [--steps 100] [--speed 20] [--repeat 3] [--out FILE]
"""
import argparse, datetime, json, os, platform, subprocess, tempfile

import mpi_scaling


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--swmpm", default="build/app/swmpm")
    ap.add_argument("--other", required=True, help="the build to compare with (its swmpm)")
    ap.add_argument("--cells", default="60x20x20")
    ap.add_argument("--steps", type=int, default=100)
    ap.add_argument("--speed", type=float, default=20.0, help="m/s along x")
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--out", default="")
    a = ap.parse_args()
    nx, ny, nz = [int(v) for v in a.cells.split("x")]
    work = tempfile.mkdtemp(prefix="swmpm-migration-")
    sc = mpi_scaling.scene("slide", nx, ny, nz, a.steps)
    sc["bodies"][0]["initial"] = {"velocity": [a.speed, 0.0, 0.0]}
    sc["grid"]["max"][0] += nx * 0.1  # room to slide
    sc["boundaries"] = [{"on": f, "solid": "roller"} for f in ["y_min", "z_min", "z_max"]]
    sc["gravity"] = [0.0, 0.0, 0.0]
    rds = {name: mpi_scaling.prepare(exe, dict(sc, name=f"slide-{name}"), work)
           for name, exe in (("this", a.swmpm), ("other", a.other))}
    runs = {"this": [], "other": []}
    for _ in range(a.repeat):
        for name, exe in (("this", a.swmpm), ("other", a.other)):
            runs[name].append(mpi_scaling.solve(exe, rds[name], 2))
    lines = ["# Migration every step, 2 ranks (bench/mpi_migration.py)", "",
             f"{datetime.date.today()}, {platform.node()}, {os.cpu_count()} cores; 3D dry box {a.cells} cells (GIMP, "
             f"8 points per cell) sliding at {a.speed} m/s along the cut axis, {a.steps} steps, one thread per rank, "
             f"fastest of {a.repeat} (interleaved).", "",
             "| build | loop s | shape functions s (rank 0) | particle moves | us per particle-step x 2 |", "|---|---|---|---|---|"]
    for name, exe in (("this", a.swmpm), ("other", a.other)):
        best = min(runs[name], key=lambda r: r["loop_seconds"])
        stages = best.get("stage_seconds", {})
        n = best["particles"]["solid"]
        lines.append(f"| {name} ({exe}) | {best['loop_seconds']:.3f} | {stages.get('shape functions', float('nan')):.3f} | "
                     f"{best['counters'].get('particles migrated', 0):.0f} | "
                     f"{1e6 * best['loop_seconds'] * 2 / (n * best['steps']):.3f} |")
    mpi_scaling.emit("\n".join(lines) + "\n", a.out)


if __name__ == "__main__":
    main()
