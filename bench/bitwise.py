#!/usr/bin/env python3
"""Bitwise regression check for refactors that must not move results (issue 23: "Results do not
move"). Runs short versions of every example scene, plus variants that switch on each runtime
choice the formulations have (pressure stabilisations, continuity, drag integration, escaped
water, shape functions, F-bar) and 3D boxes of every formulation, with one binary, and records a
SHA-256 of every frame (output/*.vtu), output/results.pvd and monitors.csv. `compare` tells which cases differ and
in which files.

  bench/bitwise.py record BINARY OUTDIR [--cases SUBSTRING,...] [--threads 2]
  bench/bitwise.py compare OUTDIR_A OUTDIR_B

Short runs: fixed dt: at most --steps steps (default 120) after an initialisation phase cut to at
most 40 steps; dt auto: 2 % of the scene's end time. Three frames per run, monitors every step.
Runs that stop early (diverged, bad input) are recorded with their exit code: the code must match
too.
"""
import argparse, copy, glob, hashlib, json, os, subprocess, sys

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(HERE)
sys.path.insert(0, HERE)
from dry_box import scene as box_scene  # noqa: E402
from speed_vs_error import apply_set  # noqa: E402

# (example scene, name suffix, [KEY.PATH=VALUE, ...]) beyond each example as it is.
VARIANTS = [
    ("terzaghi/scene.json", "none", ["solver.stabilisation.pressure=none"]),
    ("terzaghi/scene.json", "mfvp0", ["solver.stabilisation.pressure=mfvp-constant"]),
    ("terzaghi/scene.json", "mfvp2", ["solver.stabilisation.pressure=mfvp-quadratic"]),
    ("terzaghi/scene.json", "cell", ["solver.stabilisation.pressure=cell-constant"]),
    ("terzaghi/scene.json", "cons", ["solver.continuity=conservative"]),
    ("terzaghi/scene.json", "cell-cons", ["solver.stabilisation.pressure=cell-constant", "solver.continuity=conservative"]),
    ("terzaghi/scene.json", "nosmooth", ["solver.stabilisation.strain_smoothing=false"]),
    ("terzaghi/scene.json", "bspline2", ["grid.shape_function=bspline2"]),
    ("terzaghi/scene.json", "linear", ["grid.shape_function=linear"]),
    ("terzaghi/scene.json", "fbar", ["solver.stabilisation.fbar=standard"]),
    ("terzaghi-semi-implicit/scene.json", "none", ["solver.stabilisation.pressure=none"]),
    ("terzaghi-semi-implicit/scene.json", "mfvp1", ["solver.stabilisation.pressure=mfvp-linear"]),
    ("terzaghi-semi-implicit/scene.json", "noncons", ["solver.continuity=non-conservative"]),
    ("terzaghi-semi-implicit/scene.json", "semidrag", ["solver.drag_integration=semi-implicit"]),
    ("terzaghi-semi-implicit/scene.json", "linear", ["grid.shape_function=linear"]),
    ("terzaghi-semi-implicit/scene.json", "bspline2", ["grid.shape_function=bspline2"]),
    ("terzaghi-semi-implicit/scene.json", "bspline3", ["grid.shape_function=bspline3"]),
    ("terzaghi-semi-implicit/scene-double-point.json", "none", ["solver.stabilisation.pressure=none"]),
    ("terzaghi-semi-implicit/scene-double-point.json", "mfvp1", ["solver.stabilisation.pressure=mfvp-linear"]),
    ("terzaghi-semi-implicit/scene-double-point.json", "noncons", ["solver.continuity=non-conservative"]),
    ("terzaghi-semi-implicit/scene-double-point.json", "semidrag", ["solver.drag_integration=semi-implicit"]),
    ("terzaghi-semi-implicit/scene-double-point.json", "escaped", ["solver.escaped_water=remove"]),
    ("terzaghi-semi-implicit/scene-double-point.json", "linear", ["grid.shape_function=linear"]),
    ("terzaghi-semi-implicit/scene-double-point.json", "bspline2", ["grid.shape_function=bspline2"]),
    ("terzaghi-semi-implicit/scene-double-point.json", "fbar", ["solver.stabilisation.fbar=modified"]),
    ("elastic-column/scene.json", "bspline3", ["grid.shape_function=bspline3"]),
    ("elastic-column/scene.json", "fbar", ["solver.stabilisation.fbar=modified"]),
]
FORMULATIONS_3D = ["dry", "explicit-single-point", "semi-implicit-single-point", "semi-implicit-double-point"]


def shorten(sc, steps):
    """The scene cut to a short run with three frames and monitors every step."""
    t = sc["time"]
    dt = t.get("dt")
    if isinstance(dt, (int, float)):
        t["end"] = min(t["end"], steps * dt)
        init = sc.get("initialisation")
        if init:
            init["duration"] = min(init["duration"], 40 * dt)
            if "gravity_ramp" in init:
                init["gravity_ramp"] = min(init["gravity_ramp"], init["duration"])
    else:
        t["end"] = 0.02 * t["end"]
        init = sc.get("initialisation")
        if init:
            init["duration"] = 0.02 * init["duration"]
            if "gravity_ramp" in init:
                init["gravity_ramp"] = min(init["gravity_ramp"], init["duration"])
    out = sc.setdefault("output", {})
    out["interval"] = t["end"] / 3
    if out.get("monitors"):
        out["monitor_interval"] = 0.0
    out.pop("checkpoint_interval", None)
    return sc


def absolute_files(sc, folder):
    """Geometry and reference files relative to the example's folder made absolute."""
    def walk(node):
        if isinstance(node, dict):
            for k, v in node.items():
                if k == "file" and isinstance(v, str) and not os.path.isabs(v):
                    node[k] = os.path.normpath(os.path.join(folder, v))
                else:
                    walk(v)
        elif isinstance(node, list):
            for v in node:
                walk(v)
    walk(sc)
    return sc


def cases(steps):
    out = []
    for path in sorted(glob.glob(os.path.join(ROOT, "examples", "*", "*.json"))):
        rel = os.path.relpath(path, os.path.join(ROOT, "examples"))
        with open(path) as f:
            sc = json.load(f)
        if "formulation" not in sc:
            continue
        base = absolute_files(shorten(sc, steps), os.path.dirname(path))
        name = rel.replace("/", "__").removesuffix(".json")
        out.append((name, base))
        for ex, suffix, sets in VARIANTS:
            if ex == rel:
                v = copy.deepcopy(base)
                for s in sets:
                    apply_set(v, s)
                out.append((name + "--" + suffix, v))
    for form in FORMULATIONS_3D:
        sc = box_scene(3, 6, 0.6, 30, formulation=form)
        sc["output"] = {"interval": sc["time"]["end"] / 3,
                        "monitors": [{"name": "top", "at": [0.3, 0.55, 0.3],
                                      "quantities": ["displacement_y", "velocity_y"]},
                                     {"name": "energy", "quantities": ["kinetic_energy", "strain_energy"]}]}
        out.append(("box3d__" + form, sc))
    return out


def sha(path):
    """SHA-256 of a file; monitors.csv without its comment lines (they name the build)."""
    with open(path, "rb") as f:
        data = f.read()
    if path.endswith(".csv"):
        data = b"\n".join(l for l in data.split(b"\n") if not l.startswith(b"#"))
    return hashlib.sha256(data).hexdigest()


def record(a):
    binary = os.path.abspath(a.binary)
    os.makedirs(a.outdir, exist_ok=True)
    result = {}
    wanted = [w for w in a.cases.split(",") if w]
    for name, sc in cases(a.steps):
        if wanted and not any(w in name for w in wanted):
            continue
        work = os.path.join(a.outdir, name)
        os.makedirs(work, exist_ok=True)
        scene_path = os.path.join(a.outdir, name + ".json")
        with open(scene_path, "w") as f:
            json.dump(sc, f, indent=1)
        rd = os.path.join(work, "run")
        pre = subprocess.run([binary, "-q", "preprocess", scene_path, "-o", rd, "--overwrite"],
                             capture_output=True, text=True)
        rc = pre.returncode
        err = pre.stderr.strip()
        if rc == 0:
            sol = subprocess.run([binary, "-q", "solve", rd, "--threads", str(a.threads)],
                                 capture_output=True, text=True)
            rc, err = sol.returncode, sol.stderr.strip()
        files = {}
        if os.path.isdir(rd):
            for rel in sorted(glob.glob("output/*.vtu", root_dir=rd)) + ["output/results.pvd", "monitors.csv"]:
                p = os.path.join(rd, rel)
                if os.path.exists(p):
                    files[rel] = sha(p)
        result[name] = {"exit": rc, "files": files, "stderr": err[-400:]}
        print(f"{name:70s} exit {rc}  {len(files)} files", flush=True)
    with open(os.path.join(a.outdir, "hashes.json"), "w") as f:
        json.dump(result, f, indent=1, sort_keys=True)


def monitor_difference(dir_a, dir_b, name):
    """Largest difference between the two runs' monitors.csv, relative to each column's largest
    magnitude (a round-off change shows as ~1e-15..1e-12; a changed result as much more)."""
    rows = []
    for d in (dir_a, dir_b):
        p = os.path.join(d, name, "run", "monitors.csv")
        if not os.path.exists(p):
            return ""
        with open(p) as f:
            lines = [l for l in f.read().splitlines() if l and not l.startswith("#")]
        rows.append([l.split(",") for l in lines[1:]])
    if len(rows[0]) != len(rows[1]) or not rows[0]:
        return f" (monitors: {len(rows[0])} vs {len(rows[1])} rows)"
    worst = 0.0
    for c in range(len(rows[0][0])):
        try:
            x = [float(r[c]) for r in rows[0]]
            y = [float(r[c]) for r in rows[1]]
        except (ValueError, IndexError):
            continue
        scale = max(max(abs(v) for v in x), max(abs(v) for v in y))
        if scale > 0:
            worst = max(worst, max(abs(u - v) for u, v in zip(x, y)) / scale)
    return f" (monitors: max relative difference {worst:.2e})"


def frame_difference(dir_a, dir_b, name, files, tool):
    """Largest relative difference over the differing frames (bench/frame_diff.cpp)."""
    if not tool or not os.path.exists(tool):
        return ""
    worst = 0.0
    for rel in files:
        if not rel.endswith(".vtu"):
            continue
        pa, pb = (os.path.join(d, name, "run", rel) for d in (dir_a, dir_b))
        if not (os.path.exists(pa) and os.path.exists(pb)):
            return " (frames: missing)"
        out = subprocess.run([tool, pa, pb], capture_output=True, text=True).stdout.split()
        worst = max(worst, float(out[-1]) if out and out[-2] == "max_relative" else float("inf"))
    return f" (frames: max relative difference {worst:.2e})"


def compare(a):
    with open(os.path.join(a.a, "hashes.json")) as f:
        A = json.load(f)
    with open(os.path.join(a.b, "hashes.json")) as f:
        B = json.load(f)
    bad = 0
    for name in sorted(set(A) | set(B)):
        if name not in A or name not in B:
            print(f"{name}: only in {'A' if name in A else 'B'}")
            bad += 1
            continue
        x, y = A[name], B[name]
        diffs = []
        if x["exit"] != y["exit"]:
            diffs.append(f"exit {x['exit']} vs {y['exit']}")
        for rel in sorted(set(x["files"]) | set(y["files"])):
            if x["files"].get(rel) != y["files"].get(rel):
                diffs.append(rel)
        if diffs:
            bad += 1
            print(f"DIFFERS {name}: {', '.join(diffs[:6])}{' ...' if len(diffs) > 6 else ''}"
                  f"{monitor_difference(a.a, a.b, name)}{frame_difference(a.a, a.b, name, diffs, a.frame_diff)}")
    print(f"{len(set(A) & set(B))} cases compared, {bad} differ")
    return 1 if bad else 0


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    sub = ap.add_subparsers(dest="cmd", required=True)
    r = sub.add_parser("record")
    r.add_argument("binary")
    r.add_argument("outdir")
    r.add_argument("--cases", default="", help="comma list of substrings of case names (default: all)")
    r.add_argument("--threads", type=int, default=2)
    r.add_argument("--steps", type=int, default=120)
    c = sub.add_parser("compare")
    c.add_argument("a")
    c.add_argument("b")
    c.add_argument("--frame-diff", default=os.path.join(ROOT, "build", "bench", "frame_diff"),
                   help="the frame_diff tool (built with the project) that measures differing frames")
    a = ap.parse_args()
    if a.cmd == "record":
        record(a)
        return 0
    return compare(a)


if __name__ == "__main__":
    sys.exit(main())
