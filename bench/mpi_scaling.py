#!/usr/bin/env python3
"""Strong and weak scaling of `mpirun -n N swmpm solve` (issue 28), side by side in one run.

A 3D dry box under gravity (GIMP, linear elastic, 2 points per cell per axis, rollers and a fixed
base), long along x, the axis the ranks cut:
  strong: the same box on 1 rank (no mpirun) and on 2 ranks (mpirun -n 2), one thread each;
          efficiency E = T1 / (2 T2) of the time loop;
  weak:   the box on 1 rank, and a box twice as long on 2 ranks; E = T1 / T2.
  4 ranks oversubscribed on the 2 cores: a correctness check only (the last frame must be the
          1-rank one bit for bit; its time means nothing).
Each case runs --repeat times, interleaved (1 rank, 2 ranks, 1 rank, ...), and the table gives the
fastest (noise on a shared machine only adds). Every 2-rank run's last frame is compared with the
1-rank run's (build/bench/frame_diff: points matched by id).

Usage: bench/mpi_scaling.py [--swmpm build/app/swmpm] [--cells 60x20x20] [--steps 100] [--repeat 3]
                            [--formulation dry|explicit-single-point]
                            [--out bench/results/mpi-scaling-<date>.md]
explicit-single-point: the box saturated (porosity 0.4, water K_f = 2.2 GPa, impermeable faces).
semi-implicit-single-point: the same box, its pressure a Poisson solve each step (one rank CHOLMOD,
several ranks PETSc CG + BoomerAMG); its top a free surface; the frames agree to the solver's
tolerance, not bit for bit (frame_diff counts the values that differ).
"""
import argparse, datetime, json, os, platform, subprocess, tempfile

MPI_ENV = dict(os.environ, OMPI_ALLOW_RUN_AS_ROOT="1", OMPI_ALLOW_RUN_AS_ROOT_CONFIRM="1",
               OMPI_MCA_rmaps_base_oversubscribe="1")


def scene(name, nx, ny, nz, steps, h=0.1, formulation="dry"):
    E, rho = 1.0e7, 2000.0
    dt = 0.4 * h / (E / rho) ** 0.5
    if formulation in ("explicit-single-point", "semi-implicit-single-point"):
        # Saturated (n = 0.4): the P-wave with the saturated density sets dt. Explicit: undrained,
        # water K_f = 2.2e9 Pa, c = sqrt((K' + 4G/3 + K_f / n) / rho_sat); semi-implicit: the
        # pressure is implicit (incompressible water), only the skeleton's K' + 4G/3.
        nu, n, Kf, rho_s, rho_w = 0.3, 0.4, 2.2e9, 2650.0, 1000.0
        M = E * (1 - nu) / ((1 + nu) * (1 - 2 * nu)) + (Kf / n if formulation == "explicit-single-point" else 0.0)
        dt = 0.4 * h / (M / ((1 - n) * rho_s + n * rho_w)) ** 0.5
    ext = [nx * h, ny * h, nz * h]
    sc = {
        "name": name, "dimension": 3, "formulation": "dry", "gravity": [0.0, -9.81, 0.0],
        "grid": {"cell_size": h, "min": [0.0, 0.0, 0.0], "max": [ext[0] + 2 * h, ext[1] + 2 * h, ext[2] + 2 * h],
                 "shape_function": "gimp"},
        "materials": [{"name": "m", "model": "linear-elastic", "density": rho, "youngs_modulus": E,
                       "poisson_ratio": 0.3}],
        "bodies": [{"name": "box", "geometry": {"type": "box", "min": [0.0, 0.0, 0.0], "max": ext},
                    "solid": "m", "particles_per_cell": 2}],
        "boundaries": [{"on": f, "solid": "roller"} for f in ["x_min", "x_max", "z_min", "z_max"]]
                      + [{"on": "y_min", "solid": "fixed"}],
        "time": {"end": steps * dt * (1 - 1e-9), "dt": dt},
        "output": {"interval": 0.0},
    }
    if formulation in ("explicit-single-point", "semi-implicit-single-point"):
        sc["formulation"] = formulation
        sc["materials"] = [{"name": "m", "model": "linear-elastic", "grain_density": 2650.0, "porosity": 0.4,
                            "youngs_modulus": E, "poisson_ratio": 0.3, "hydraulic_conductivity": 1e-4},
                           {"name": "w", "model": "fluid", "density": 1000.0, "bulk_modulus": 2.2e9}]
        sc["bodies"][0]["fluid"] = "w"
        for b in sc["boundaries"]:
            b["fluid"] = "impermeable"
    return sc


def prepare(swmpm, sc, work):
    path = os.path.join(work, sc["name"] + ".json")
    with open(path, "w") as f:
        json.dump(sc, f)
    rd = os.path.join(work, sc["name"])
    subprocess.run([swmpm, "-q", "preprocess", path, "-o", rd, "--overwrite"], check=True)
    return rd


def solve(swmpm, rd, ranks, threads=1):
    cmd = [swmpm, "-q", "solve", rd, "--threads", str(threads)]
    if ranks > 1:
        cmd = ["mpirun", "-n", str(ranks)] + cmd
    subprocess.run(cmd, check=True, env=MPI_ENV)
    with open(os.path.join(rd, "run.json")) as f:
        return json.load(f)


def emit(text, out=""):
    """Prints a report and writes it to `out` (if given)."""
    print(text)
    if out:
        with open(out, "w") as f:
            f.write(text)


def last_frame(rd):
    with open(os.path.join(rd, "output", "results.pvd")) as f:
        files = [l.split('file="')[1].split('"')[0] for l in f if 'file="' in l]
    return os.path.join(rd, "output", files[-1])


def same(frame_diff, a, b):
    out = subprocess.run([frame_diff, a, b], capture_output=True, text=True).stdout.strip().splitlines()
    return out[-1] if out else "?"


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--swmpm", default="build/app/swmpm")
    ap.add_argument("--frame-diff", default="build/bench/frame_diff")
    ap.add_argument("--cells", default="60x20x20")
    ap.add_argument("--steps", type=int, default=100)
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--formulation", default="dry", choices=["dry", "explicit-single-point", "semi-implicit-single-point"])
    ap.add_argument("--out", default="")
    a = ap.parse_args()
    nx, ny, nz = [int(v) for v in a.cells.split("x")]
    work = tempfile.mkdtemp(prefix="swmpm-mpi-")
    f = a.formulation
    base = prepare(a.swmpm, scene("box", nx, ny, nz, a.steps, formulation=f), work)
    # Each rank count solves its own copy of the run directory (a solve replaces its outputs).
    runs = {r: prepare(a.swmpm, scene(f"box-{r}", nx, ny, nz, a.steps, formulation=f), work) for r in (2, 4)}
    weak1 = base
    weak2 = prepare(a.swmpm, scene("box-weak", 2 * nx, ny, nz, a.steps, formulation=f), work)
    t = {"strong1": [], "strong2": [], "weak2": [], "threads2": []}
    last = {}
    for _ in range(a.repeat):
        last["strong1"] = solve(a.swmpm, base, 1)
        t["strong1"].append(last["strong1"])
        last["strong2"] = solve(a.swmpm, runs[2], 2)
        t["strong2"].append(last["strong2"])
        last["weak2"] = solve(a.swmpm, weak2, 2)
        t["weak2"].append(last["weak2"])
        t["threads2"].append(solve(a.swmpm, base, 1, threads=2))
    four = solve(a.swmpm, runs[4], 4)
    best = {k: min(v, key=lambda r: r["loop_seconds"]) for k, v in t.items()}
    T1, T2, W2 = best["strong1"]["loop_seconds"], best["strong2"]["loop_seconds"], best["weak2"]["loop_seconds"]
    n1 = best["strong1"]["particles"]["solid"]
    nw = best["weak2"]["particles"]["solid"]
    steps = best["strong1"]["steps"]
    TT = best["threads2"]["loop_seconds"]
    rows = [
        ("strong, 1 rank", n1, 1, T1, best["strong1"], 1.0),
        ("reference: 1 rank, 2 OpenMP threads", n1, 2, TT, best["threads2"], T1 / (2 * TT)),
        ("strong, 2 ranks", n1, 2, T2, best["strong2"], T1 / (2 * T2)),
        ("weak, 2 ranks (2x box)", nw, 2, W2, best["weak2"], T1 / W2),
    ]
    lines = [f"# MPI scaling, 3D {'dry' if f == 'dry' else 'saturated (' + f + ')'} box (bench/mpi_scaling.py)", "",
             f"{datetime.date.today()}, {platform.node()}, {os.cpu_count()} cores, {a.cells} cells "
             f"(GIMP, 8 points per cell), {steps} steps, one thread per rank, fastest of {a.repeat} (interleaved).", "",
             "| case | particles | ranks (cores) | loop s | us per particle-step (x cores) | communication s, busiest rank: all (collectives / exchange / migration) | particles per rank | efficiency |",
             "|---|---|---|---|---|---|---|---|"]
    for name, n, r, T, rj, eff in rows:
        cs = rj.get("communication_seconds", {})
        comm = (f"{cs['max']:.3f} ({cs['collectives_max']:.3f} / {cs['exchange_max']:.3f} / {cs['migration_max']:.3f})"
                if cs else "-")
        ppr = rj.get("particles_per_rank", {}).get("each", [n])
        lines.append(f"| {name} | {n} | {r} | {T:.3f} | {1e6 * T * r / (n * steps):.3f} | {comm} | {ppr} | {eff:.2f} |")
    lines += ["", "Last frame against the 1-rank run (frame_diff, points by id): "
              f"2 ranks {same(a.frame_diff, last_frame(base), last_frame(runs[2]))}, "
              f"4 ranks oversubscribed {same(a.frame_diff, last_frame(base), last_frame(runs[4]))} "
              f"(4 ranks: {four['particles_per_rank']['each']} particles, a correctness check only)."]
    emit("\n".join(lines) + "\n", a.out)


if __name__ == "__main__":
    main()
