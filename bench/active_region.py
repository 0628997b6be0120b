#!/usr/bin/env python3
"""Empty-space overhead (issue 26 item 2, "an active region"): what a grid larger than the scene
costs. For each formulation, a small representative scene is run on its own grid (1x) and on grids
enlarged with empty space to 4x and 16x the area (2x and 4x per axis, towards +x and +y, so the
node positions, the walls the scene touches and the particles' shape data stay the same), for
--steps steps on --threads 1. The runs are interleaved (1x, 4x, 16x, 1x, 4x, 16x, ...) and each
size keeps the fastest of --repeat runs (timing noise on a shared machine only adds); the spread
(slowest / fastest - 1) is reported beside it. Two times: the time loop's wall time (run.json
loop_seconds: steps plus the first and last frame), and the CPU time (user + system) of the whole
`swmpm solve` process (reading the particles, building the formulation and its grid, the loop),
which a busy machine disturbs much less: time another process holds the core does not count.
Peak memory is run.json's peak_memory_bytes.

Results bitwise: the last frame of every particle set (output/solid_*.vtu, fluid_*.vtu) of the 4x
and 16x runs is compared byte for byte with the 1x run's; `--record FILE` writes their SHA-256 per
formulation and size, `--compare FILE` checks them against a recording of another binary (before
and after a change).

Scenes (2D, gravity):
  dry, explicit-single-point, semi-implicit-single-point, semi-implicit-double-point,
  explicit-double-point: a column 1.25 m wide and 4 m high, h = 1/32 m, 2 x 2 points per cell
  (20,480 soil points; the double-point formulations as many water points again), GIMP, linear
  elastic (saturated: n = 0.3, k = 1e-3 m/s, geostatic and hydrostatic start), a roller on x_min
  and a fixed, impermeable base; its own grid leaves two empty cells right of and above it (the
  right side and the top are free). The box scenes of bench/dry_box.py, reshaped.
  mpm-fem: a saturated column 0.1 m wide and 0.2 m high (h = 0.01 m, quadratic B-splines, 2 x 2
  points per cell: 800 points) in air. Its fluid (water in the column's pores, air around it) is
  solved on the active region (solver.air.domain "active", the default): the cells of the water
  (phi > 0.01: the initial phase field's tail reaches 2 cells beyond the column) and the soil,
  widened by 3 cells. Its own grid leaves FEM_MARGIN = 5 cells right of and above the column, so
  that it is the region a larger grid solves on.

Usage: bench/active_region.py [--swmpm build/app/swmpm] [--formulations dry,...] [--areas 1,4,16]
                              [--steps 200] [--fem-steps 20] [--repeat 3] [--out FILE.md]
                              [--record FILE.json] [--compare FILE.json] [--keep DIR]
"""
import argparse, copy, datetime, glob, hashlib, json, os, resource, subprocess, sys, tempfile

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)
from dry_box import emit, machine, scene as box_scene  # noqa: E402

MPM_FORMULATIONS = ["dry", "explicit-single-point", "semi-implicit-single-point", "semi-implicit-double-point",
                    "explicit-double-point"]
ALL = MPM_FORMULATIONS + ["mpm-fem"]

H = 1.0 / 32.0               # m, cell size of the MPM columns
WIDTH, HEIGHT = 1.25, 4.0    # m, the MPM column
MARGIN = 2                   # empty cells right of and above the scene on its own grid
FEM_MARGIN = 5               # the same for mpm-fem: the phase field's tail (2) and the fluid region's halo (3)


def mpm_scene(formulation, steps):
    """The column of the formulation (bench/dry_box.py's box reshaped), grid 1x."""
    cells = round(WIDTH / H)
    sc = box_scene(2, cells, WIDTH, steps, formulation)
    sc["name"] = f"active-{formulation}"
    sc["bodies"][0]["geometry"]["max"] = [WIDTH, HEIGHT]
    sc["grid"]["max"] = [WIDTH + MARGIN * H, HEIGHT + MARGIN * H]
    sc["boundaries"] = [b for b in sc["boundaries"] if b["on"] != "x_max"]  # the right side is free
    sc["output"] = {"interval": 0.0}
    return sc


def fem_scene(steps):
    """A saturated column in air (mpm-fem), grid 1x."""
    h, w, ht, dt = 0.01, 0.1, 0.2, 1e-4
    return {
        "name": "active-mpm-fem", "dimension": 2, "formulation": "mpm-fem", "gravity": [0.0, -9.81],
        "grid": {"cell_size": h, "min": [0.0, 0.0], "max": [w + FEM_MARGIN * h, ht + FEM_MARGIN * h],
                 "shape_function": "bspline2"},
        "materials": [{"name": "beads", "model": "linear-elastic", "grain_density": 2650.0, "porosity": 0.4,
                       "youngs_modulus": 1e6, "poisson_ratio": 0.3, "grain_diameter": 0.001},
                      {"name": "water", "model": "fluid", "density": 1000.0, "dynamic_viscosity": 0.001}],
        "bodies": [{"name": "column", "geometry": {"type": "box", "min": [0.0, 0.0], "max": [w, ht]},
                    "solid": "beads", "fluid": "water", "particles_per_cell": 2}],
        "boundaries": [{"on": "x_min", "solid": "roller", "fluid": "impermeable"},
                       {"on": "y_min", "solid": "fixed", "fluid": "impermeable"}],
        "time": {"end": steps * dt * (1 - 1e-9), "dt": dt},
        "output": {"interval": 0.0},
    }


def enlarged(sc, area):
    """The scene on a grid of `area` times the area: each axis k = sqrt(area) times as long, from
    the same min (whole cells: node positions unchanged)."""
    k = round(area ** 0.5)
    if k * k != area:
        sys.exit(f"--areas: {area} is not a square number")
    s = copy.deepcopy(sc)
    lo, hi = s["grid"]["min"], s["grid"]["max"]
    s["grid"]["max"] = [lo[a] + k * (hi[a] - lo[a]) for a in range(len(lo))]
    s["name"] += f"-{area}x"
    return s


def sha(path):
    with open(path, "rb") as f:
        return hashlib.sha256(f.read()).hexdigest()


def last_frames(rd):
    """SHA-256 of the last frame of each particle set."""
    out = {}
    for phase in ("solid", "fluid"):
        frames = sorted(glob.glob(os.path.join(rd, "output", f"{phase}_*.vtu")))
        if frames:
            out[phase] = sha(frames[-1])
    return out


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--swmpm", default="build/app/swmpm")
    ap.add_argument("--formulations", default=",".join(ALL))
    ap.add_argument("--areas", default="1,4,16")
    ap.add_argument("--steps", type=int, default=200, help="steps of the MPM columns")
    ap.add_argument("--fem-steps", type=int, default=20, help="steps of the mpm-fem column")
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--out", default="")
    ap.add_argument("--record", default="", help="write the last frames' SHA-256 here (JSON)")
    ap.add_argument("--compare", default="", help="check the last frames against this recording")
    ap.add_argument("--keep", default="", help="run directories here (default: a temporary folder)")
    a = ap.parse_args()
    swmpm = os.path.abspath(a.swmpm)
    areas = [int(x) for x in a.areas.split(",")]
    work = a.keep or tempfile.mkdtemp(prefix="swmpm-active-")
    os.makedirs(work, exist_ok=True)
    version = subprocess.run([swmpm, "--version"], capture_output=True, text=True).stdout.strip()

    rows, hashes, bitwise = [], {}, []
    for form in a.formulations.split(","):
        base = fem_scene(a.fem_steps) if form == "mpm-fem" else mpm_scene(form, a.steps)
        dirs = {}
        for area in areas:
            sc = enlarged(base, area)
            path = os.path.join(work, sc["name"] + ".json")
            with open(path, "w") as f:
                json.dump(sc, f, indent=1)
            rd = os.path.join(work, sc["name"])
            subprocess.run([swmpm, "-q", "preprocess", path, "-o", rd, "--overwrite"], check=True)
            dirs[area] = rd
        loops = {area: [] for area in areas}
        cpus = {area: [] for area in areas}
        runs = {}
        for _ in range(a.repeat):
            for area in areas:  # interleaved: 1x 4x 16x, 1x 4x 16x, ...
                before = resource.getrusage(resource.RUSAGE_CHILDREN)
                subprocess.run([swmpm, "-q", "solve", dirs[area], "--threads", "1"], check=True)
                after = resource.getrusage(resource.RUSAGE_CHILDREN)
                cpus[area].append(after.ru_utime + after.ru_stime - before.ru_utime - before.ru_stime)
                with open(os.path.join(dirs[area], "run.json")) as f:
                    rj = json.load(f)
                loops[area].append(rj["loop_seconds"])
                runs[area] = rj
        frames = {area: last_frames(dirs[area]) for area in areas}
        hashes[form] = {str(area): frames[area] for area in areas}
        same = all(frames[area] == frames[areas[0]] for area in areas)
        bitwise.append((form, same))
        best1, cpu1, mem1 = min(loops[areas[0]]), min(cpus[areas[0]]), runs[areas[0]]["peak_memory_bytes"]
        for area in areas:
            rj = runs[area]
            best, cpu, mem = min(loops[area]), min(cpus[area]), rj["peak_memory_bytes"]
            spread = max(loops[area]) / best - 1.0
            cpu_spread = max(cpus[area]) / cpu - 1.0
            parts = rj["particles"]["solid"] + rj["particles"].get("fluid", 0)
            same = frames[area] == frames[areas[0]]
            rows.append((form, area, parts, rj["steps"], best, spread, 100.0 * (best / best1 - 1.0), cpu, cpu_spread,
                         100.0 * (cpu / cpu1 - 1.0), mem, 100.0 * (mem / mem1 - 1.0), same))
            print(f"{form:28s} {area:3d}x  loop {best:8.3f} s ({100.0 * (best / best1 - 1.0):+6.1f} %, spread "
                  f"{100 * spread:4.1f} %)  cpu {cpu:8.3f} s ({100.0 * (cpu / cpu1 - 1.0):+6.1f} %, spread "
                  f"{100 * cpu_spread:4.1f} %)  memory {mem / 1e6:6.0f} MB ({100.0 * (mem / mem1 - 1.0):+6.1f} %)  "
                  f"last frame {'same as 1x' if same else 'DIFFERS from 1x'}", flush=True)

    compared = []
    if a.compare:
        with open(a.compare) as f:
            ref = json.load(f)["hashes"]
        for form, per_area in hashes.items():
            for area, h in per_area.items():
                if form in ref and area in ref[form]:
                    compared.append((form, area, ref[form][area] == h))
        for form, area, ok in compared:
            print(f"{form:28s} {area:>3s}x  {'same as' if ok else 'DIFFERS from'} {a.compare}")
    if a.record:
        with open(a.record, "w") as f:
            json.dump({"binary": version, "hashes": hashes}, f, indent=1, sort_keys=True)
            f.write("\n")
    lines = [f"# Empty-space overhead — {datetime.date.today()}", "",
             f"Binary: {version}. Machine: {machine()}.",
             f"One thread; fastest of {a.repeat} interleaved runs per grid; MPM columns {a.steps} steps, "
             f"mpm-fem {a.fem_steps} steps.", "",
             "| formulation | grid area | points | steps | loop wall s (fastest) | spread | vs 1x | solve CPU s (fastest) "
             "| spread | vs 1x | peak memory MB | vs 1x | last frame = 1x |",
             "|---|---|---|---|---|---|---|---|---|---|---|---|---|"]
    for (form, area, parts, steps, best, spread, over, cpu, cpu_spread, cpu_over, mem, mem_over, same) in rows:
        lines.append(f"| {form} | {area}x | {parts} | {steps} | {best:.3f} | {100 * spread:.1f} % | {over:+.1f} % | "
                     f"{cpu:.3f} | {100 * cpu_spread:.1f} % | {cpu_over:+.1f} % | {mem / 1e6:.0f} | {mem_over:+.1f} % | "
                     f"{'yes' if same else 'no'} |")
    if compared:
        lines += ["", f"Last frames against `{os.path.basename(a.compare)}`: "
                  + ("all identical" if all(ok for *_, ok in compared) else
                     "differ: " + ", ".join(f"{f} {ar}x" for f, ar, ok in compared if not ok)) + "."]
    emit(lines, a.out)


if __name__ == "__main__":
    main()
