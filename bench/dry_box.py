#!/usr/bin/env python3
"""MPM speed benchmark (issues: core, explicit-single-point). Writes scenes for a 2D GIMP
linear-elastic box of ~10k, 100k and 1M particles and a 3D box, runs `swmpm preprocess` +
`swmpm solve --threads N`, and tabulates microseconds per particle-step and memory per particle
from each run.json.

--formulation dry (default): a dry box under gravity.
--formulation semi-implicit-single-point|semi-implicit-double-point: the same box saturated, incompressible
  constituents, free drained top, dt = 0.4 of the soil's P-wave limit (the pressure is implicit).
  Particles counted: soil points plus water points (double-point).
--shape linear|gimp|bspline2|bspline3 (default gimp).
--formulation explicit-double-point: the same box saturated as solid and liquid points (K_L = 21.5 MPa).
--formulation explicit-single-point: the same box saturated (n = 0.3, k = 1e-3 m/s, K_f = 2.2 GPa),
  geostatic and hydrostatic initial state, impermeable sides and base, with the scene's default
  stabilisation (cell-average strain smoothing + node-based MFVP, linear basis); dt = 0.4 of the
  undrained P-wave limit.

--fbar none,standard,modified,modified:1.5 (dry): one row per F-bar variant (solver.stabilisation.fbar,
  and fbar_patch after the colon), with --shape gimp|bspline2 and --material linear-elastic|hencky.

--set KEY.PATH=VALUE (repeatable): change every scene, e.g. solver.continuity=conservative
  --set solver.stabilisation.pressure=cell-constant (explicit-single-point's large-strain scheme).

Usage: bench/dry_box.py [--swmpm build/app/swmpm] [--sizes 10k,100k,1M,3d] [--threads 1,2]
                        [--steps 100] [--formulation dry] [--out bench/results/dry-box-<date>.md]
                        [--fbar none,...] [--shape gimp] [--material linear-elastic] [--set K=V ...]
Memory per particle = (peak RSS of the run - peak RSS of a 1-particle run) / particles.
"""
import argparse, datetime, json, os, platform, subprocess, sys, tempfile

from speed_vs_error import apply_set

SIZES = {  # name: (dimension, cells per side along x/y(/z), extent)
    "10k": (2, 50, 5.0),
    "100k": (2, 158, 15.8),
    "1M": (2, 500, 50.0),
    "3d-100k": (3, 30, 3.0),
}

def scene(dim, n, extent, steps, formulation="dry", fbar="none", shape="gimp", material="linear-elastic"):
    h = extent / n
    lo = [0.0] * dim
    hi_grid = [extent + 2 * h] * dim
    hi_body = [extent] * dim
    g = [0.0] * dim
    g[1] = -9.81
    faces = ["x_min", "x_max", "z_min", "z_max"][: 2 * (dim - 1)]
    E, rho = 1.0e7, 2000.0
    c = ((E / rho)) ** 0.5
    dt = 0.4 * h / c
    if formulation != "dry":
        nu, n_por, Kf, rho_s, rho_w = 0.3, 0.3, 2.2e9, 2650.0, 1000.0
        M = E * (1 - nu) / ((1 + nu) * (1 - 2 * nu))
        rho_sat = (1 - n_por) * rho_s + n_por * rho_w
        # explicit: the undrained P-wave; semi-implicit: the soil's own (the pressure is implicit)
        explicit = formulation == "explicit-single-point"
        dt = 0.4 * h / ((M + Kf / n_por if explicit else M) / rho_sat) ** 0.5
        if formulation == "explicit-double-point":
            # the seed's K_L = 21.5 MPa; the step of the formulation's own bound (solid on its
            # partial density plus the liquid's storage acting on both phases)
            Kf = 2.15e7
            c2 = M / ((1 - n_por) * rho_s) + Kf * ((1 - n_por) / (n_por * rho_s) + 1 / rho_w)
            dt = 0.4 * h / c2 ** 0.5
        return {
            "name": f"bench-{'esp' if explicit else 'edp' if formulation == 'explicit-double-point' else 'si'}-{dim}d-{n}",
            "dimension": dim,
            "formulation": formulation,
            "gravity": g,
            "grid": {"cell_size": h, "min": lo, "max": hi_grid, "shape_function": shape},
            "materials": [{"name": "soil", "model": "linear-elastic", "grain_density": rho_s, "porosity": n_por,
                           "youngs_modulus": E, "poisson_ratio": nu, "hydraulic_conductivity": 1e-3},
                          {"name": "water", "model": "fluid", "density": rho_w, "bulk_modulus": Kf}],
            "bodies": [{"name": "box", "geometry": {"type": "box", "min": lo, "max": hi_body},
                        "solid": "soil", "fluid": "water", "particles_per_cell": 2,
                        "initial": {"stress": "geostatic", "k0": 0.5, "pore_pressure": "hydrostatic"}}],
            "boundaries": [{"on": f, "solid": "roller", "fluid": "impermeable"} for f in faces]
                          + [{"on": "y_min", "solid": "fixed", "fluid": "impermeable"}],
            "time": {"end": steps * dt * (1 - 1e-9), "dt": dt},
            "output": {"interval": 0.0},
        }
    sc = {
        "name": f"bench-{dim}d-{n}",
        "dimension": dim,
        "formulation": "dry",
        "gravity": g,
        "grid": {"cell_size": h, "min": lo, "max": hi_grid, "shape_function": shape},
        "materials": [{"name": "m", "model": material, "density": rho,
                        "youngs_modulus": E, "poisson_ratio": 0.3}],
        "bodies": [{"name": "box", "geometry": {"type": "box", "min": lo, "max": hi_body},
                     "solid": "m", "particles_per_cell": 2}],
        "boundaries": [{"on": f, "solid": "roller"} for f in faces] + [{"on": "y_min", "solid": "fixed"}],
        "time": {"end": steps * dt * (1 - 1e-9), "dt": dt},
        "output": {"interval": 0.0},
    }
    if fbar != "none":
        mode, _, ratio = fbar.partition(":")
        sc["solver"] = {"stabilisation": {"fbar": mode}}
        if ratio:
            sc["solver"]["stabilisation"]["fbar_patch"] = float(ratio)
    return sc

def run(swmpm, sc, threads, work):
    path = os.path.join(work, sc["name"] + ".json")
    with open(path, "w") as f:
        json.dump(sc, f)
    rd = os.path.join(work, sc["name"])
    subprocess.run([swmpm, "-q", "preprocess", path, "-o", rd, "--overwrite"], check=True)
    subprocess.run([swmpm, "-q", "solve", rd, "--threads", str(threads)], check=True)
    with open(os.path.join(rd, "run.json")) as f:
        return json.load(f)

def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--swmpm", default="build/app/swmpm")
    ap.add_argument("--sizes", default="10k,100k,1M,3d-100k")
    ap.add_argument("--threads", default="1,2")
    ap.add_argument("--steps", type=int, default=200)
    ap.add_argument("--out", default="")
    ap.add_argument("--formulation", default="dry", choices=["dry", "explicit-single-point", "semi-implicit-single-point",
                                                             "semi-implicit-double-point", "explicit-double-point"])
    ap.add_argument("--fbar", default="none", help="comma list: none, standard, modified, modified:RATIO (dry)")
    ap.add_argument("--shape", default="gimp", choices=["linear", "gimp", "bspline2", "bspline3"])
    ap.add_argument("--material", default="linear-elastic")
    ap.add_argument("--set", action="append", default=[], metavar="KEY.PATH=VALUE",
                    help="change every scene, e.g. solver.stabilisation.pressure=cell-constant (repeatable)")
    ap.add_argument("--repeat", type=int, default=3,
                    help="runs per case; the table gives the fastest (timing noise on shared machines is additive) and the median")
    a = ap.parse_args()
    work = tempfile.mkdtemp(prefix="swmpm-bench-")
    base = run(a.swmpm, scene(2, 2, 0.2, 2, a.formulation, shape=a.shape, material=a.material), 1, work)["peak_memory_bytes"]
    rows = []
    for name in a.sizes.split(","):
      dim, n, ext = SIZES[name]
      for fb in a.fbar.split(","):
        for t in [int(x) for x in a.threads.split(",")]:
            sc = scene(dim, n, ext, a.steps, a.formulation, fb, a.shape, a.material)
            for assignment in a.set:
                apply_set(sc, assignment)
            runs = [run(a.swmpm, sc, t, work) for _ in range(a.repeat)]
            runs.sort(key=lambda r: r["loop_us_per_particle_step"])
            r = runs[0]
            median = runs[len(runs) // 2]["loop_us_per_particle_step"]
            parts = r["particles"]["solid"] + r["particles"].get("fluid", 0)
            mem = (max(x["peak_memory_bytes"] for x in runs) - base) / parts
            rows.append((name + ("" if fb == "none" else f", fbar {fb}"), dim, parts, t, r["steps"],
                         r["loop_us_per_particle_step"], median, mem, r["stage_seconds"]))
            # The F-bar stage alone: its wall time per particle-step, fastest of the repeats.
            fbar_us = min(x["stage_seconds"].get("f-bar", 0.0) for x in runs) / (parts * r["steps"]) * 1e6
            print(f"{name:8s} fbar {fb:12s} {dim}D {parts:>8d} particles, {t} thread(s): {r['loop_us_per_particle_step']:.4f} us/particle-step "
                  f"(median of {a.repeat}: {median:.4f}; f-bar stage {fbar_us:.4f}), {mem:.0f} B/particle", flush=True)
    title = "Dry MPM" if a.formulation == "dry" else a.formulation
    lines = [f"# {title} speed — {datetime.date.today()}", "",
             f"Machine: {machine()}.",
             f"Scene: {a.shape}, {a.material} box under gravity ({a.formulation}), 2x2(x2) particles per cell, MUSL, {a.steps} steps"
             + "".join(f", `{x}`" for x in a.set) + ". "
             f"Time per particle-step is the time loop's (run.json loop_us_per_particle_step); best and median of {a.repeat} runs.", "",
             "| case | dim | particles | threads | steps | us per particle-step, best | median | bytes per particle |",
             "|---|---|---|---|---|---|---|---|"]
    for (name, dim, parts, t, steps, us, med, mem, _) in rows:
        lines.append(f"| {name} | {dim} | {parts} | {t} | {steps} | {us:.4f} | {med:.4f} | {mem:.0f} |")
    lines += ["", "Stage split (seconds) of each run:", ""]
    for (name, dim, parts, t, steps, us, med, mem, st) in rows:
        total = sum(st.values())
        lines.append(f"- {name}, {t} thread(s): " + ", ".join(f"{k} {100*v/total:.1f}%" for k, v in st.items()))
    emit(lines, a.out)

def machine():
    """The CPU model, cores and platform, for a results file's header."""
    cpu = "unknown"
    try:
        for line in open("/proc/cpuinfo"):
            if line.startswith("model name"):
                cpu = line.split(":", 1)[1].strip(); break
    except OSError:
        pass
    return f"{cpu}, {os.cpu_count()} cores, {platform.platform()}"

def emit(lines, out):
    """Prints a Markdown report and writes it to `out` (if given)."""
    text = "\n".join(lines) + "\n"
    if out:
        with open(out, "w") as f:
            f.write(text)
    print(text)

if __name__ == "__main__":
    main()
