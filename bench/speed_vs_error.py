#!/usr/bin/env python3
"""Speed against error: runs one scene over cell sizes, particles per cell, shape functions and
(optionally) time steps, and tabulates wall time (run.json) against the error of one quantity.

Error metrics:
  default       the dry elastic column (examples/elastic-column): relative error of the top
                settlement, -(monitor top.displacement_y at the end), against the closed form
                u = rho g (H y - y^2/2) / M at the top particle's height y = H - h / (2 ppc),
                M = E (1-nu) / ((1+nu)(1-2nu)); rho, g, H, E, nu are read from the scene.
  --reference CSV --monitor NAME.QUANTITY
                the relative L2 error of `swmpm postprocess RUN compare` (any scene).

Usage:
  bench/speed_vs_error.py --swmpm build/app/swmpm [--scene examples/elastic-column/scene.json]
      [--cell-sizes 0.1,0.05,0.025,0.0125] [--ppc 1,2,3] [--shapes linear,gimp,bspline2]
      [--cfl 0.5,0.25 | --dt 2e-4,1e-4] [--threads 1] [--end T]
      [--set materials.0.youngs_modulus=1e8 ...] [--reference REF.csv --monitor NAME.Q]
      --table OUT.md --chart OUT.png

Each run writes frames only at the start and the end (output.interval 0), so the wall time is the
computation's. The Markdown file holds the table, the observed order of the error with cell size
(least-squares slope of log|error| against log h) per shape function and particles per cell, and
the cheapest run under 1 % error; the PNG is a log-log chart of wall time against error, one
series per shape function (gnuplot).
"""
import argparse, json, math, os, re, subprocess, sys, tempfile


def floats(text):
    return [float(x) for x in text.split(",") if x.strip()]


def apply_set(scene, assignment):
    """--set a.b.0.c=VALUE: VALUE is read as JSON (a number, "text", [list]) or else as text."""
    path, _, value = assignment.partition("=")
    if not path or not _:
        sys.exit(f"--set {assignment}: expected KEY.PATH=VALUE, e.g. materials.0.youngs_modulus=1e8")
    try:
        value = json.loads(value)
    except json.JSONDecodeError:
        pass
    keys = [int(k) if k.isdigit() else k for k in path.split(".")]
    node = scene
    for k in keys[:-1]:
        node = node[k]
    node[keys[-1]] = value


def run_case(a, base, shape, h, ppc, step, work):
    s = json.loads(json.dumps(base))
    s["grid"]["cell_size"] = h
    s["grid"]["shape_function"] = shape
    for body in s["bodies"]:
        body["particles_per_cell"] = ppc
    if step is not None:
        kind, value = step
        if kind == "cfl":
            s["time"]["dt"] = "auto"
            s["time"]["cfl"] = value
        else:
            s["time"]["dt"] = value
            s["time"].pop("cfl", None)
    if a.end:
        s["time"]["end"] = a.end
    s.setdefault("output", {})["interval"] = 0.0
    # The solver needs two cells across every axis: a grid narrower than 2h (the 0.1 m column at
    # h = 0.1 m) is widened along x, with the bodies that span it. With roller sides the column
    # is in 1D strain whatever its width, so the exact solution does not change.
    g = s["grid"]
    if g["max"][0] - g["min"][0] < 2 * h - 1e-12:
        old_max = g["max"][0]
        g["max"][0] = g["min"][0] + 2 * h
        for body in s["bodies"]:
            geo = body["geometry"]
            if geo.get("type") == "box" and abs(geo["max"][0] - old_max) < 1e-12:
                geo["max"][0] = g["max"][0]
    name = f"{shape}-h{h:g}-ppc{ppc}" + (f"-{step[0]}{step[1]:g}" if step else "")
    path = os.path.join(work, name + ".json")
    with open(path, "w") as f:
        json.dump(s, f, indent=1)
    rd = os.path.join(work, name)
    subprocess.run([a.swmpm, "-q", "preprocess", path, "-o", rd], check=True)
    # A diverged run (exit 3) still writes run.json; its status is reported and the row skipped.
    subprocess.run([a.swmpm, "-q", "solve", rd, "--threads", str(a.threads)], check=False)
    if not os.path.exists(os.path.join(rd, "run.json")):
        sys.exit(f"{name}: swmpm solve wrote no run.json (see {rd})")
    with open(os.path.join(rd, "run.json")) as f:
        rj = json.load(f)
    return s, rd, rj


def column_error(scene, rd, h, ppc):
    """Signed relative error of the top settlement of the dry elastic column."""
    mat = scene["materials"][0]
    body = scene["bodies"][0]["geometry"]
    rho, E, nu = mat["density"], mat["youngs_modulus"], mat["poisson_ratio"]
    g = -scene["gravity"][1]
    H = body["max"][1] - body["min"][1]
    M = E * (1 - nu) / ((1 + nu) * (1 - 2 * nu))
    y = H - h / (2 * ppc)  # the top row of the lattice (k + 1/2) h / ppc
    exact = rho * g * (H * y - y * y / 2) / M
    with open(os.path.join(rd, "monitors.csv")) as f:
        rows = [l.strip().split(",") for l in f if l.strip() and not l.startswith("#")]
    col = rows[0].index("top.displacement_y")
    return (-float(rows[-1][col]) - exact) / exact


def compare_error(a, rd):
    out = subprocess.run([a.swmpm, "postprocess", rd, "compare", "--monitor", a.monitor, "--reference", a.reference],
                         check=True, capture_output=True, text=True).stdout
    m = re.search(r"relative L2 error\s+([0-9.eE+-]+|inf)", out)
    if not m:
        sys.exit("could not read the relative L2 error from:\n" + out)
    return float(m.group(1))


def fit_order(points):
    """Least-squares slope of log|e| against log h (needs two or more cell sizes)."""
    pts = [(math.log(h), math.log(abs(e))) for h, e in points if e != 0]
    if len(pts) < 2:
        return float("nan")
    mx = sum(x for x, _ in pts) / len(pts)
    my = sum(y for _, y in pts) / len(pts)
    sxx = sum((x - mx) ** 2 for x, _ in pts)
    return sum((x - mx) * (y - my) for x, y in pts) / sxx if sxx > 0 else float("nan")


def chart(rows, path, metric, title):
    shapes = sorted({r["shape"] for r in rows}, key=[r["shape"] for r in rows].index)
    with tempfile.TemporaryDirectory() as tmp:
        plots = []
        for k, shape in enumerate(shapes):
            data = os.path.join(tmp, f"{shape}.dat")
            with open(data, "w") as f:
                for r in rows:
                    if r["shape"] == shape:
                        f.write(f"{max(abs(r['error']), 1e-7)} {r['wall']} {r['ppc']}\n")
            plots.append(f"'{data}' using 1:2 with points pt {[7, 5, 9, 11][k % 4]} ps 1.6 title '{shape}'")
        # The x range always shows the 1 % line, with room for its label.
        errors = [max(abs(r["error"]), 1e-7) for r in rows]
        x_lo = 10 ** math.floor(math.log10(min(errors)))
        x_hi = max(0.03, 10 ** math.ceil(math.log10(max(errors))))
        script = f"""set terminal pngcairo size 900,600 font 'Sans,11' noenhanced
set output '{path}'
set logscale xy
set xrange [{x_lo}:{x_hi}]
set grid xtics ytics lc rgb '#cccccc'
set format x '%g'
set format y '%g'
set xlabel '|error| ({metric})'
set ylabel 'wall time [s]'
set title '{title}'
set key top right box opaque
set arrow from 0.01, graph 0 to 0.01, graph 1 nohead dt 2 lc rgb '#888888'
set label '1 %' at 0.01, graph 0.5 left offset 0.5,0 tc rgb '#555555'
plot {', '.join(plots)}
"""
        subprocess.run(["gnuplot"], input=script, text=True, check=True)


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--swmpm", default="build/app/swmpm")
    ap.add_argument("--scene", default="examples/elastic-column/scene.json")
    ap.add_argument("--cell-sizes", default="0.1,0.05,0.025,0.0125")
    ap.add_argument("--ppc", default="1,2,3")
    ap.add_argument("--shapes", default="linear,gimp,bspline2")
    ap.add_argument("--cfl", default="", help="cfl values for dt auto (comma-separated)")
    ap.add_argument("--dt", default="", help="fixed time steps [s] (comma-separated)")
    ap.add_argument("--end", type=float, default=0.0, help="end time [s] (default: the scene's)")
    ap.add_argument("--threads", type=int, default=1)
    ap.add_argument("--set", action="append", default=[], metavar="KEY.PATH=VALUE",
                    help="change the scene before the sweep, e.g. materials.0.youngs_modulus=1e8 (repeatable)")
    ap.add_argument("--reference", default="", help="reference CSV for `postprocess compare`")
    ap.add_argument("--monitor", default="", help="NAME.QUANTITY compared with --reference")
    ap.add_argument("--table", required=True, help="Markdown output")
    ap.add_argument("--chart", required=True, help="PNG output")
    ap.add_argument("--title", default="Speed against error: one series per shape function (all cell sizes and ppc)")
    ap.add_argument("--work", default="", help="folder for the runs (default: a temporary one)")
    a = ap.parse_args()
    if bool(a.reference) != bool(a.monitor):
        sys.exit("--reference and --monitor go together")
    with open(a.scene) as f:
        base = json.load(f)
    for assignment in a.set:
        apply_set(base, assignment)
    steps = [("cfl", v) for v in floats(a.cfl)] + [("dt", v) for v in floats(a.dt)] or [None]
    metric = f"relative L2 of {a.monitor}" if a.reference else "top settlement, relative"
    work = a.work or tempfile.mkdtemp(prefix="swmpm-speed-error-")
    os.makedirs(work, exist_ok=True)
    rows = []
    for shape in a.shapes.split(","):
        for h in floats(a.cell_sizes):
            for ppc in [int(x) for x in a.ppc.split(",")]:
                for step in steps:
                    scene, rd, rj = run_case(a, base, shape, h, ppc, step, work)
                    if rj["status"] != "completed":
                        print(f"{shape} h={h:g} ppc={ppc}: {rj['status']}", flush=True)
                        continue
                    err = compare_error(a, rd) if a.reference else column_error(scene, rd, h, ppc)
                    rows.append(dict(shape=shape, h=h, ppc=ppc, step=step, dt=rj["dt"], particles=sum(rj["particles"].values()),
                                     steps=rj["steps"], wall=rj["wall_seconds"], error=err))
                    print(f"{shape:9s} h={h:<7g} ppc={ppc} dt={rj['dt']:.3g} particles={rows[-1]['particles']:6d} "
                          f"steps={rj['steps']:6d} wall={rj['wall_seconds']:.3f} s error={100 * err:+.3f} %", flush=True)

    changes = "".join(f", `{x}`" for x in a.set)
    lines = [f"Scene `{a.scene}` ({base.get('name', '')}{changes}), end time {a.end or base['time']['end']} s, "
             f"{a.threads} thread(s), frames only at the start and the end. Error: {metric}"
             + (" (signed: run − exact)." if not a.reference else "."), "",
             "| cells (h) [m] | ppc | shape | dt [s] | particles | steps | wall [s] | error |",
             "|---|---|---|---|---|---|---|---|"]
    sign = "" if a.reference else "+"  # a relative L2 error has no sign
    for r in rows:
        lines.append(f"| {r['h']:g} | {r['ppc']} | {r['shape']} | {r['dt']:.3g} | {r['particles']} | {r['steps']} | "
                     f"{r['wall']:.3f} | {100 * r['error']:{sign}.3f} % |")
    lines += ["", "Observed order of |error| with cell size (least-squares slope of log|error| against log h):", "",
              "| shape | ppc | order |", "|---|---|---|"]
    for shape in a.shapes.split(","):
        for ppc in [int(x) for x in a.ppc.split(",")]:
            for step in steps:
                pts = [(r["h"], r["error"]) for r in rows if r["shape"] == shape and r["ppc"] == ppc and r["step"] == step]
                label = f"{ppc}" + (f" ({step[0]} {step[1]:g})" if step else "")
                lines.append(f"| {shape} | {label} | {fit_order(pts):.2f} |")
        pts = [(r["h"], r["error"]) for r in rows if r["shape"] == shape]
        lines.append(f"| {shape} | all | {fit_order(pts):.2f} |")
    good = [r for r in rows if abs(r["error"]) <= 0.01]
    lines.append("")
    if good:
        best = min(good, key=lambda r: r["wall"])
        lines.append(f"Cheapest run within 1 %: {best['shape']}, h = {best['h']:g} m, {best['ppc']} ppc, "
                     f"{best['wall']:.3f} s wall, error {100 * best['error']:+.3f} %.")
    else:
        lines.append("No run is within 1 %.")
    text = "\n".join(lines) + "\n"
    with open(a.table, "w") as f:
        f.write(text)
    chart(rows, a.chart, metric, a.title)
    print(text)
    print(f"table: {a.table}\nchart: {a.chart}")


if __name__ == "__main__":
    main()
