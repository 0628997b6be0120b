#!/usr/bin/env python3
"""mpm-fem's cost (issue: mpm-fem, "Speed"). Runs seed 004's cases from their example folders for a
fixed number of steps, one after the other in one invocation (these machines drift by +-10 %, so
compare rows of one table, not tables of different days), and tabulates from each run.json:

  * microseconds per particle-step (soil points) and per fluid node-step (every grid node is a
    fluid node: water and air), time loop only;
  * the split of the loop among the stages the formulation reports (fluid assembly, LU
    factorisation, the Krylov solve with the old factor, the phase field, the MPM stages), in
    per cent and in microseconds per fluid node-step;
  * factorisations and Krylov iterations per step;
  * the cost of the whole case at the run's step (time.end / dt steps), extrapolated.

Beside mpm-fem's dam break it runs explicit-double-point's (examples/dam-break-double-point, its own
automatic step) to the same end time: both fronts are within 10 % of Martin & Moyce (the tests),
so this is the cost at the same accuracy.

Cases (--cases, comma-separated):
  dam-break      examples/dam-break-mpm-fem (dt 1 ms) and explicit-double-point's, to 0.2 s
  d3             examples/column-in-water-and-air-mpm-fem (the analysis: no initialisation phase)
  d2             examples/underwater-collapse-mpm-fem (seed 004's D2 grid, dt 1e-5 s)
  d4-grid        D4's grid (2.2 x 0.3 m, h = 0.004 m) with water to 0.148 m and no soil: the
                 fluid's cost alone at the seed's resolution

Usage: bench/mpm_fem_cost.py [--swmpm build/app/swmpm] [--threads 1] [--steps 200]
                             [--cases dam-break,d3,d2,d4-grid] [--out bench/results/mpm-fem-cost-<date>.md]
"""
import argparse, copy, datetime, json, os, platform, subprocess, sys, tempfile

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(HERE)
STAGES = ["soil p2g", "fluid assembly", "fluid factorisation", "fluid solve", "phase field",
          "soil grid update", "g2p + musl remap", "stress and porosity"]  # mpm-fem's stages


def load(example, name="scene.json"):
    with open(os.path.join(ROOT, "examples", example, name)) as f:
        return json.load(f)


def d4_grid():
    """D4's tank at the seed's cells with its water at rest (the fluid's cost alone)."""
    s = load("dam-break-mpm-fem")
    s["name"] = "d4-grid"
    s["grid"].update({"cell_size": 0.004, "min": [0.0, 0.0], "max": [2.2, 0.3]})
    s["bodies"][0]["geometry"] = {"type": "box", "min": [0.0, 0.0], "max": [2.2, 0.148]}
    s["time"]["dt"] = 1e-4
    s["time"]["end"] = 2.0  # the seed's D4 (the whole-case column extrapolates to it)
    s["output"] = {"interval": 1.0}
    return s


def cases(names):
    out = []
    for name in names:
        if name == "dam-break":
            out.append(("dam break", "mpm-fem", load("dam-break-mpm-fem"), None))
            edp = load("dam-break-double-point")
            edp["time"]["end"] = 0.2
            out.append(("dam break", "explicit-double-point", edp, "whole"))
        elif name == "d3":
            s = load("column-in-water-and-air-mpm-fem")
            s.pop("initialisation", None)
            for b in s["bodies"]:
                if b.get("solid"):  # the phase's end state, roughly: geostatic (and hydrostatic below the water)
                    b["initial"] = {"stress": "geostatic", "k0": 0.5}
                    if b.get("fluid"):
                        b["initial"].update({"pore_pressure": "hydrostatic", "water_table": 0.06})
            out.append(("D3 column in water and air", "mpm-fem", s, None))
        elif name == "d2":
            out.append(("D2 underwater collapse", "mpm-fem", load("underwater-collapse-mpm-fem"), None))
        elif name == "d4-grid":
            out.append(("D4 grid, water only", "mpm-fem", d4_grid(), None))
        else:
            sys.exit(f"unknown case {name}")
    return out


def run(swmpm, scene, steps, threads, work, tag):
    s = copy.deepcopy(scene)
    s.setdefault("output", {})
    full_end = s["time"]["end"]
    if steps is not None:
        dt = s["time"].get("dt")
        if not isinstance(dt, (int, float)):
            sys.exit(f"{tag}: a fixed time.dt is needed to run a number of steps")
        s["time"]["end"] = steps * dt
        s["output"]["interval"] = s["time"]["end"]
        s["output"]["monitor_interval"] = s["time"]["end"]
        s["output"].pop("monitors", None)
    path = os.path.join(work, tag + ".json")
    with open(path, "w") as f:
        json.dump(s, f)
    out = os.path.join(work, tag)
    subprocess.run([swmpm, "preprocess", path, "-o", out, "-q"], check=True)
    subprocess.run([swmpm, "solve", out, "--threads", str(threads), "-q"], check=True)
    with open(os.path.join(out, "run.json")) as f:
        r = json.load(f)
    r["full_end"] = full_end
    return r


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--swmpm", default=os.path.join(ROOT, "build", "app", "swmpm"))
    ap.add_argument("--threads", type=int, default=1)
    ap.add_argument("--steps", type=int, default=200)
    ap.add_argument("--cases", default="dam-break,d3,d2,d4-grid")
    ap.add_argument("--out")
    a = ap.parse_args()
    rows = []
    with tempfile.TemporaryDirectory() as work:
        for k, (case, form, scene, mode) in enumerate(cases(a.cases.split(","))):
            r = run(a.swmpm, scene, None if mode == "whole" else a.steps, a.threads, work, f"case{k}")
            rows.append((case, form, r))
            print(f"{case} ({form}): {r['steps']} steps in {r['loop_seconds']:.2f} s", file=sys.stderr)

    lines = [f"# mpm-fem cost ({datetime.date.today()}, {platform.node()}, {a.threads} thread(s))", "",
             "| case | formulation | particles | fluid nodes | steps | dt [s] | loop [s] | us / particle-step | "
             "us / fluid node-step | factorisations / step | Krylov its / step | whole case at this dt |",
             "|---|---|---|---|---|---|---|---|---|---|---|---|"]
    for case, form, r in rows:
        parts = r.get("particles", {})
        np_ = sum(v for v in parts.values() if isinstance(v, (int, float)))
        nodes = r.get("fluid_nodes", 0)
        steps = r["steps"]
        c = r.get("counters", {})
        fac = c.get("fluid factorisations", 0) / steps if nodes else 0
        its = c.get("fluid Krylov iterations per step", 0)
        whole = r["loop_seconds"] / r["end_time"] * r["full_end"] if r["end_time"] > 0 else float("nan")
        per_p = r["loop_seconds"] / (np_ * steps) * 1e6 if np_ else float("nan")
        per_n = r.get("loop_us_per_fluid_node_step", float("nan"))
        lines.append(f"| {case} | {form} | {np_} | {nodes} | {steps} | {r['dt']:.3g} | {r['loop_seconds']:.2f} | "
                     f"{per_p:.3g} | {per_n:.3g} | {fac:.3f} | {its:.2f} | {whole / 60:.1f} min |")
    stages = list(STAGES)  # mpm-fem's, then any other formulation's in order of appearance
    for _, _, r in rows:
        stages += [k for k in r.get("stage_seconds", {}) if k not in stages]
    lines += ["", "Stages, per cent of the time loop (and microseconds per fluid node-step):", "",
              "| case | formulation | " + " | ".join(stages) + " |", "|---|---|" + "---|" * len(stages)]
    for case, form, r in rows:
        st = r.get("stage_seconds", {})
        nodes = r.get("fluid_nodes", 0)
        cells = []
        for s in stages:
            if s not in st:
                cells.append("")
                continue
            pct = 100 * st[s] / r["loop_seconds"]
            us = st[s] / (nodes * r["steps"]) * 1e6 if nodes else float("nan")
            cells.append(f"{pct:.1f} % ({us:.2g})" if nodes else f"{pct:.1f} %")
        lines.append(f"| {case} | {form} | " + " | ".join(cells) + " |")
    text = "\n".join(lines) + "\n"
    print(text)
    if a.out:
        with open(a.out, "w") as f:
            f.write(text)


if __name__ == "__main__":
    main()
