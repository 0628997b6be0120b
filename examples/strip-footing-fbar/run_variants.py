#!/usr/bin/env python3
"""B6 (seed 001 App. A): runs the variants of this folder's scene.json — shape function gimp or
bspline2 x F-bar none / standard / modified cell-wise (h_patch = h) / modified patch-wise
(h_patch = 1.5 h) — with `swmpm run`, then draws the mean-stress field of each at the end
(`swmpm postprocess RUN plot --field mean_effective_stress`) and copies it here as
field-<shape>-<variant>.png.

Usage: examples/strip-footing-fbar/run_variants.py [--swmpm build/app/swmpm] [--runs runs/b6]
                                                   [--cell 0.2] [--only gimp-none,bspline2-patch]
                                                   [--threads 1]
"""
import argparse, copy, glob, json, os, shutil, subprocess

HERE = os.path.dirname(os.path.abspath(__file__))
VARIANTS = {  # name: solver.stabilisation
    "none": {"fbar": "none"},
    "standard": {"fbar": "standard"},
    "cell": {"fbar": "modified", "fbar_patch": 1.0},
    "patch": {"fbar": "modified", "fbar_patch": 1.5},
}

def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--swmpm", default="build/app/swmpm")
    ap.add_argument("--runs", default="runs/b6")
    ap.add_argument("--cell", type=float, default=0.2)
    ap.add_argument("--only", default="")
    ap.add_argument("--threads", type=int, default=1)
    a = ap.parse_args()
    with open(os.path.join(HERE, "scene.json")) as f:
        base = json.load(f)
    os.makedirs(a.runs, exist_ok=True)
    only = [x for x in a.only.split(",") if x]
    for shape in ("gimp", "bspline2"):
        for name, stab in VARIANTS.items():
            tag = f"{shape}-{name}"
            if only and tag not in only:
                continue
            s = copy.deepcopy(base)
            s["name"] = f"strip-footing-fbar-{tag}"
            s["grid"]["shape_function"] = shape
            s["grid"]["cell_size"] = a.cell
            s["grid"]["max"] = [10.0, 10.0 + 2 * a.cell]
            s["solver"]["stabilisation"] = stab
            path = os.path.join(a.runs, tag + ".json")
            with open(path, "w") as f:
                json.dump(s, f, indent=2)
            run = os.path.join(a.runs, tag)
            subprocess.run([a.swmpm, "-q", "run", path, "-o", run, "--overwrite", "--threads", str(a.threads)], check=True)
            subprocess.run([a.swmpm, "postprocess", run, "plot", "--field", "mean_effective_stress"], check=True,
                           stdout=subprocess.DEVNULL)
            png = sorted(glob.glob(os.path.join(run, "plots", "field_mean_effective_stress_*.png")))[-1]
            suffix = "" if a.cell == 0.2 else f"-h{a.cell:g}"
            shutil.copy(png, os.path.join(HERE, f"field-{tag}{suffix}.png"))
            with open(os.path.join(run, "run.json")) as f:
                r = json.load(f)
            print(f"{tag}: {r['status']}, {r['steps']} steps, {r['us_per_particle_step']:.3f} us/particle-step", flush=True)

if __name__ == "__main__":
    main()
