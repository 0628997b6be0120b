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
  --metric terzaghi
                Terzaghi consolidation (examples/terzaghi, explicit-single-point; C1,
                examples/consolidation-double-point, explicit-double-point or its single-point twin; or B1,
                examples/terzaghi-semi-implicit, either semi-implicit variant, against the series
                with incompressible water and p0 = q): RMS over all
                particles of p/p0 - the series at the end time (z = depth of the particle's initial
                position below the top, Tv = c_v t / H^2, c_v = k / (gamma_w (1/E_oed + n/K_f)));
                p0, E, nu, n, k, K_f, rho_w, H are read from the scene.
  --metric large-strain
                1D large-strain consolidation (examples/large-strain-consolidation): signed relative
                error of the top particle's settlement at the end time against the constant-k
                finite-volume reference (examples/large-strain-consolidation/reference.py, for the
                scene's E, q, k, K_f and the particle's initial height); the RMS of p/q against the
                same reference is reported alongside.

Usage:
  bench/speed_vs_error.py --swmpm build/app/swmpm [--scene examples/elastic-column/scene.json]
      [--cell-sizes 0.1,0.05,0.025,0.0125] [--ppc 1,2,3] [--shapes linear,gimp,bspline2]
      [--cfl 0.5,0.25 | --dt 2e-4,1e-4] [--threads 1] [--end T] [--max-wall SECONDS]
      [--metric column|terzaghi|large-strain]
      [--set materials.0.youngs_modulus=1e8 ...] [--reference REF.csv --monitor NAME.Q]
      --table OUT.md --chart OUT.png

Each run writes frames only at the start and the end (output.interval 0), so the wall time is the
computation's. The Markdown file holds the table, the observed order of the error with cell size
(least-squares slope of log|error| against log h) per shape function and particles per cell, and
the cheapest run under 1 % error; the PNG is a log-log chart of wall time against error, one
series per shape function (gnuplot).
"""
import argparse, json, math, os, re, subprocess, sys, tempfile

HERE = os.path.dirname(os.path.abspath(__file__))


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
        node = node.setdefault(k, {}) if isinstance(node, dict) else node[k]  # missing objects are created
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
    subprocess.run([a.swmpm, "-q", "preprocess", path, "-o", rd, "--overwrite"], check=True)
    # A diverged run (exit 3) still writes run.json; its status is reported and the row skipped.
    # A run longer than --max-wall seconds is stopped and reported the same way.
    try:
        r = subprocess.run([a.swmpm, "-q", "solve", rd, "--threads", str(a.threads)], check=False,
                           timeout=a.max_wall or None, stderr=subprocess.PIPE, text=True)
    except subprocess.TimeoutExpired:
        return s, rd, {"status": f"stopped after --max-wall {a.max_wall:g} s"}
    if not os.path.exists(os.path.join(rd, "run.json")):
        if r.returncode == 1:  # a setup error: the solver refused the case (reported, row skipped)
            return s, rd, {"status": "rejected (" + r.stderr.strip().splitlines()[-1] + ")"}
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


def last_frame(swmpm, rd, phase="solid"):
    """The run's last frame as (time, {column: [values]}), read through VTK by
    `swmpm postprocess RUN frame` (columns x, y[, z], then every array: displacement_y, pore_pressure, ...);
    phase "fluid": the water points of a double-point run."""
    # The run's own end time: with --time 1e300 every frame is equally far (1e300 - t == 1e300).
    with open(os.path.join(rd, "run.json")) as f:
        end = json.load(f)["end_time"]
    out = subprocess.run([swmpm, "-q", "postprocess", rd, "frame", "--time", repr(end), "--phase", phase], check=True,
                         capture_output=True, text=True).stdout
    lines = out.splitlines()
    t = float(re.search(r"the frame at t = ([0-9.eE+-]+) s", "\n".join(l for l in lines if l.startswith("#"))).group(1))
    data = [l for l in lines if l and not l.startswith("#")]
    names = data[0].split(",")
    cols = {n: [] for n in names}
    for l in data[1:]:
        for n, v in zip(names, l.split(",")):
            cols[n].append(float(v))
    return t, cols


def saturated_column(scene):
    """Parameters of a saturated 1D column scene (examples/terzaghi, examples/large-strain-consolidation)."""
    solid = next(m for m in scene["materials"] if m["model"] != "fluid")
    fluid = next(m for m in scene["materials"] if m["model"] == "fluid")
    body = scene["bodies"][0]
    geo = body["geometry"]
    # The semi-implicit formulations treat the water as incompressible (B1): K_f -> infinity, and
    # the undrained response to the load q is p = q at once (no initial pore pressure given).
    incompressible = scene["formulation"].startswith("semi-implicit")
    q = -scene["loads"][0]["value"][1]
    k = solid.get("hydraulic_conductivity")
    if k is None:  # seed 003's C1 gives the intrinsic permeability: k = kappa rho_w g / mu
        k = solid["intrinsic_permeability"] * fluid["density"] * 9.81 / fluid.get("dynamic_viscosity", 1e-3)
    return dict(E=solid["youngs_modulus"], nu=solid["poisson_ratio"], n=solid["porosity"],
                k=k, rho_w=fluid["density"],
                K_f=math.inf if incompressible else fluid["bulk_modulus"],
                p0=body["initial"].get("pore_pressure", q) if not incompressible else q, q=q,
                H=geo["max"][1] - geo["min"][1], y_min=geo["min"][1], end=scene["time"]["end"])


def terzaghi_series(z, H, Tv, terms=200):
    total = 0.0
    for m in range(terms):
        M = (2 * m + 1) * math.pi / 2
        total += 2.0 / M * math.sin(M * z / H) * math.exp(-M * M * Tv)
    return total


def terzaghi_error(swmpm, scene, rd):
    """RMS over the particles of p/p0 - Terzaghi's series at the last frame."""
    c = saturated_column(scene)
    E_oed = c["E"] * (1 - c["nu"]) / ((1 + c["nu"]) * (1 - 2 * c["nu"]))
    c_v = c["k"] / (c["rho_w"] * 9.81 * (1.0 / E_oed + c["n"] / c["K_f"]))
    # double-point: the liquid points carry the pressure (examples/consolidation-double-point, C1)
    t, f = last_frame(swmpm, rd, "fluid" if scene["formulation"] == "explicit-double-point" else "solid")
    Tv = c_v * t / c["H"] ** 2
    err2 = 0.0
    for y, uy, p in zip(f["y"], f["displacement_y"], f["pore_pressure"]):
        z = c["H"] - (y - uy - c["y_min"])
        err2 += (p / c["p0"] - terzaghi_series(z, c["H"], Tv)) ** 2
    return math.sqrt(err2 / len(f["y"]))


_large_strain_cache = {}


def large_strain_error(swmpm, scene, rd):
    """Signed relative error of the top particle's settlement and RMS of p/q, both against the
    constant-k finite-volume reference at the run's end time."""
    sys.path.insert(0, os.path.join(HERE, "..", "examples", "large-strain-consolidation"))
    import reference  # noqa: E402
    c = saturated_column(scene)
    t, f = last_frame(swmpm, rd)
    key = (c["E"], c["q"], c["k"], c["K_f"], c["n"], c["H"], round(t, 9))
    if key not in _large_strain_cache:
        N = 400
        _, _, prof = reference.solve(H=c["H"], E=c["E"], q=c["q"], n0=c["n"], k0=c["k"], Kf=c["K_f"], times=[t], N=N)[0]
        _large_strain_cache[key] = prof
    prof = _large_strain_cache[key]
    N = len(prof)
    da = c["H"] / N
    strain = [1.0 - math.exp((p - c["q"]) / c["E"]) for p in prof]  # 1 - J per cell

    def settlement(a):  # of the point at initial height a above the base
        m = min(N, int(a / da))
        s = sum(strain[:m]) * da
        return s + (strain[m] * (a - m * da) if m < N else 0.0)

    def pressure(a):
        return prof[min(N - 1, int(a / da))]

    y, uy = f["y"], f["displacement_y"]
    top = max(range(len(y)), key=lambda i: y[i] - uy[i])
    a_top = y[top] - uy[top] - c["y_min"]
    exact = settlement(a_top)
    err = (-uy[top] - exact) / exact
    rms = math.sqrt(sum((p - pressure(yi - ui - c["y_min"])) ** 2 for yi, ui, p in
                        zip(y, uy, f["pore_pressure"])) / len(y)) / c["q"]
    return err, rms


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
            colour = ["#1f77b4", "#ff7f0e", "#2ca02c", "#d62728", "#9467bd", "#8c564b", "#e377c2", "#7f7f7f",
                      "#bcbd22", "#17becf"][k % 10]
            plots.append(f"'{data}' using 1:2 with points pt {[7, 5, 9, 11][k % 4]} ps 1.6 lc rgb '{colour}' title '{shape}'")
        # The x range always shows the 1 % line, with room for its label.
        errors = [max(abs(r["error"]), 1e-7) for r in rows]
        x_lo = min(10 ** math.floor(math.log10(min(errors))), 0.003)
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


def read_table(path, label):
    """The rows of a table this script wrote, each shape renamed "<label> <shape>" (for --combine)."""
    rows = []
    with open(path) as f:
        for line in f:
            cells = [c.strip() for c in line.strip().strip("|").split("|")]
            if len(cells) < 8 or not re.match(r"^[0-9.]+$", cells[0]):
                continue
            rows.append(dict(shape=f"{label} {cells[2]}", h=float(cells[0]), ppc=int(cells[1]),
                             wall=float(cells[6]), error=float(cells[7].rstrip(" %")) / 100))
    return rows


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
    ap.add_argument("--max-wall", type=float, default=0.0,
                    help="stop a run after this many seconds of wall time and report it as not completed (0: no limit)")
    ap.add_argument("--set", action="append", default=[], metavar="KEY.PATH=VALUE",
                    help="change the scene before the sweep, e.g. materials.0.youngs_modulus=1e8 (repeatable)")
    ap.add_argument("--metric", choices=["column", "terzaghi", "large-strain"], default="column",
                    help="error measure (ignored with --reference): see the module docstring")
    ap.add_argument("--reference", default="", help="reference CSV for `postprocess compare`")
    ap.add_argument("--monitor", default="", help="NAME.QUANTITY compared with --reference")
    ap.add_argument("--combine", default="", metavar="TABLE=LABEL,...",
                    help="only draw --chart from tables this script wrote, one series per label and shape")
    ap.add_argument("--table", default="", help="Markdown output (required unless --combine)")
    ap.add_argument("--chart", required=True, help="PNG output")
    ap.add_argument("--title", default="Speed against error: one series per shape function (all cell sizes and ppc)")
    ap.add_argument("--work", default="", help="folder for the runs (default: a temporary one)")
    a = ap.parse_args()
    if a.combine:
        rows = []
        for item in a.combine.split(","):
            path, label = item.split("=")
            rows += read_table(path, label)
        chart(rows, a.chart, "RMS of p/p0 vs series" if a.metric == "terzaghi" else a.metric, a.title)
        print(f"chart: {a.chart} ({len(rows)} runs)")
        return
    if not a.table:
        sys.exit("--table is required (unless --combine)")
    if bool(a.reference) != bool(a.monitor):
        sys.exit("--reference and --monitor go together")
    with open(a.scene) as f:
        base = json.load(f)
    for assignment in a.set:
        apply_set(base, assignment)
    steps = [("cfl", v) for v in floats(a.cfl)] + [("dt", v) for v in floats(a.dt)] or [None]
    metric = (f"relative L2 of {a.monitor}" if a.reference else
              {"column": "top settlement, relative", "terzaghi": "RMS of p/p0 vs series",
               "large-strain": "top settlement vs constant-k reference, relative"}[a.metric])
    signed = not a.reference and a.metric != "terzaghi"
    work = a.work or tempfile.mkdtemp(prefix="swmpm-speed-error-")
    os.makedirs(work, exist_ok=True)
    rows, skipped = [], []
    for shape in a.shapes.split(","):
        for h in floats(a.cell_sizes):
            for ppc in [int(x) for x in a.ppc.split(",")]:
                for step in steps:
                    scene, rd, rj = run_case(a, base, shape, h, ppc, step, work)
                    if rj["status"] != "completed":
                        print(f"{shape} h={h:g} ppc={ppc}: {rj['status']}", flush=True)
                        skipped.append(f"{shape}, h = {h:g} m, {ppc} ppc: {rj['status']}"
                                       + (f" at t = {rj['end_time']:.4g} s" if "end_time" in rj else ""))
                        continue
                    extra = None
                    if a.reference:
                        err = compare_error(a, rd)
                    elif a.metric == "terzaghi":
                        err = terzaghi_error(a.swmpm, scene, rd)
                    elif a.metric == "large-strain":
                        err, extra = large_strain_error(a.swmpm, scene, rd)
                    else:
                        err = column_error(scene, rd, h, ppc)
                    rows.append(dict(shape=shape, h=h, ppc=ppc, step=step, dt=rj["dt"], particles=sum(rj["particles"].values()),
                                     steps=rj["steps"], wall=rj["wall_seconds"], error=err, extra=extra))
                    print(f"{shape:9s} h={h:<7g} ppc={ppc} dt={rj['dt']:.3g} particles={rows[-1]['particles']:6d} "
                          f"steps={rj['steps']:6d} wall={rj['wall_seconds']:.3f} s error={100 * err:{'+' if signed else ''}.3f} %"
                          + (f" p RMS={100 * extra:.2f} %" if extra is not None else ""), flush=True)

    changes = "".join(f", `{x}`" for x in a.set)
    lines = [f"Scene `{a.scene}` ({base.get('name', '')}{changes}), end time {a.end or base['time']['end']} s, "
             f"{a.threads} thread(s), frames only at the start and the end. Error: {metric}"
             + (" (signed: run − exact)." if signed else "."), ""]
    has_extra = any(r["extra"] is not None for r in rows)
    lines += ["| cells (h) [m] | ppc | shape | dt [s] | particles | steps | wall [s] | error |"
              + (" RMS of p/q |" if has_extra else ""),
              "|---|---|---|---|---|---|---|---|" + ("---|" if has_extra else "")]
    sign = "+" if signed else ""  # an RMS or relative L2 error has no sign
    for r in rows:
        lines.append(f"| {r['h']:g} | {r['ppc']} | {r['shape']} | {r['dt']:.3g} | {r['particles']} | {r['steps']} | "
                     f"{r['wall']:.3f} | {100 * r['error']:{sign}.3f} % |"
                     + (f" {100 * r['extra']:.2f} % |" if has_extra else ""))
    if skipped:
        lines += ["", "Not completed (no row above): " + "; ".join(skipped) + "."]
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
                     f"{best['wall']:.3f} s wall, error {100 * best['error']:{sign}.3f} %.")
    else:
        lines.append("No run is within 1 %.")
    text = "\n".join(lines) + "\n"
    with open(a.table, "w") as f:
        f.write(text)
    if rows:
        chart(rows, a.chart, metric, a.title)
    else:
        print(f"no completed run: no chart written to {a.chart}")
    print(text)
    print(f"table: {a.table}\nchart: {a.chart}")


if __name__ == "__main__":
    main()
