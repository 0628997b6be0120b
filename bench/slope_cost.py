#!/usr/bin/env python3
"""B4 (seed 001 §5.3, Table 4): cost of the semi-implicit single- and double-point formulations on
the Mohr-Coulomb slope (examples/slope-stability-mohr-coulomb) at cell 1.0 m and dt 0.004 s, over
particles per cell n^2 = 6^2 ... 32^2, next to the paper's CPU times (one AMD Ryzen 9 5950X core).

Every run is the example's scene with the cell size, dt, particles per cell and formulation
replaced; by default it runs the whole paper case (1 s initialisation + 6 s, 1750 steps), or
`--end T` seconds of the analysis (the initialisation is kept: its cost is in every row).
Per run it records the points (soil + water), steps, wall seconds of the time loop,
microseconds per particle-step (run.json's loop_us_per_particle_step: all points counted, as the
paper counts them), the split among stages, and the run's status.

With `--repeat N` every size runs N single-/double-point pairs, alternating (or side by side),
and the table gives the best run of each variant, the ratio of the bests and the median of the
pairs' ratios: on a shared machine whose speed drifts by ±10 % between minutes, one pair cannot
show a 10 % overhead either way.

Usage: bench/slope_cost.py [--swmpm build/app/swmpm] [--ppc 6,8,10,12] [--threads 2]
                           [--end 6] [--shape gimp] [--side-by-side] [--repeat 1]
                           [--out bench/results/slope-cost-<date>.md]
"""
import argparse, datetime, json, os, platform, statistics, subprocess, sys, tempfile

HERE = os.path.dirname(os.path.abspath(__file__))
EXAMPLE = os.path.join(HERE, "..", "examples", "slope-stability-mohr-coulomb", "scene.json")

# Seed 001 Table 4: points (both phases), CPU time single-point, double-point [s], 6 s at dt 0.004.
PAPER = {6: (21540, 1881, 2006), 8: (38320, 3271, 3616), 10: (59900, 5063, 5670), 12: (86280, 7655, 8157),
         18: (194220, 16768, 17716), 24: (345360, 28540, 31553), 32: (614080, 50957, 55598)}
PAPER_STEPS = 1500  # 6 s / 0.004 s


def scene(ppc, formulation, end, shape):
    with open(EXAMPLE) as f:
        s = json.load(f)
    s["name"] = f"b4-{formulation}-{ppc}"
    s["formulation"] = formulation
    s["grid"]["cell_size"] = 1.0
    s["grid"]["shape_function"] = shape
    s["bodies"][0]["particles_per_cell"] = ppc
    s["time"]["dt"] = 0.004
    s["time"]["end"] = end
    s["output"] = {"interval": 0.0, "monitors": []}
    return s


def prepare(swmpm, s, workdir):
    path = os.path.join(workdir, s["name"] + ".json")
    with open(path, "w") as f:
        json.dump(s, f)
    out = os.path.join(workdir, s["name"])
    subprocess.run([swmpm, "preprocess", path, "-o", out, "-q", "--overwrite"], check=True)
    return out


def result(out, rc):
    with open(os.path.join(out, "run.json")) as f:
        r = json.load(f)
    r["rc"] = rc
    return r


def run(swmpm, s, threads, workdir):
    out = prepare(swmpm, s, workdir)
    return result(out, subprocess.run([swmpm, "solve", out, "--threads", str(threads), "-q"]).returncode)


def run_side_by_side(swmpm, scenes, threads, workdir):
    """Solves the scenes at the same time (one process each): on a machine whose speed drifts (a
    shared VM), both variants then see the same load, and their ratio is what is compared."""
    outs = [prepare(swmpm, s, workdir) for s in scenes]
    procs = [subprocess.Popen([swmpm, "solve", out, "--threads", str(threads), "-q"]) for out in outs]
    return [result(out, p.wait()) for out, p in zip(outs, procs)]


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--swmpm", default="build/app/swmpm")
    ap.add_argument("--ppc", default="6,8,10,12")
    ap.add_argument("--threads", type=int, default=2)
    ap.add_argument("--end", type=float, default=6.0)
    ap.add_argument("--shape", default="gimp")
    ap.add_argument("--out", default="")
    ap.add_argument("--side-by-side", action="store_true",
                    help="solve single- and double-point at the same time (needs 2 x threads cores)")
    ap.add_argument("--repeat", type=int, default=1,
                    help="pairs per size; the table gives the best run of each variant and the median pair ratio")
    a = ap.parse_args()
    if a.repeat < 1:
        ap.error("--repeat: expected a positive number of pairs")
    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        for ppc in [int(x) for x in a.ppc.split(",")]:
            forms = ("semi-implicit-single-point", "semi-implicit-double-point")
            runs = {f: [] for f in forms}  # per variant: one tuple per repetition
            ratios = []
            for rep in range(a.repeat):
                if a.side_by_side:
                    done = dict(zip(forms, run_side_by_side(a.swmpm, [scene(ppc, f, a.end, a.shape) for f in forms],
                                                            a.threads, tmp)))
                for form in forms:
                    r = done[form] if a.side_by_side else run(a.swmpm, scene(ppc, form, a.end, a.shape), a.threads, tmp)
                    pts = r["particles"]["solid"] + r["particles"].get("fluid", 0)
                    runs[form].append((pts, r["steps"], r["loop_seconds"], r["loop_us_per_particle_step"], r["status"],
                                       r.get("stage_seconds", {})))
                    print(f"{ppc}^2 {form} (pair {rep + 1}/{a.repeat}): {pts} points, {r['steps']} steps, "
                          f"{r['loop_seconds']:.1f} s, {r['loop_us_per_particle_step']:.3f} us/particle-step, {r['status']}",
                          file=sys.stderr)
                ratios.append(runs[forms[1]][-1][2] / runs[forms[0]][-1][2])
            best = {f: min(runs[f], key=lambda x: x[2]) for f in forms}
            rows.append((ppc, best, ratios))
    cpu = platform.processor() or platform.machine()
    try:
        with open("/proc/cpuinfo") as f:
            cpu = next(l.split(":", 1)[1].strip() for l in f if l.startswith("model name"))
    except (OSError, StopIteration):
        pass
    mode = ", single- and double-point solved side by side" if a.side_by_side else ""
    if a.repeat > 1:
        mode += f", best of {a.repeat} {'side-by-side' if a.side_by_side else 'alternating'} pairs"
    lines = [f"# B4: semi-implicit slope cost ({datetime.date.today()}, {cpu}, {a.threads} threads, {a.shape}{mode})", "",
             f"Mohr-Coulomb slope of examples/slope-stability-mohr-coulomb at cell 1.0 m, dt 0.004 s, 1 s "
             f"initialisation + {a.end:g} s; points = soil + water (the paper counts both). Paper: seed 001 "
             f"Table 4, 6 s (1500 steps) on one Ryzen 9 5950X core; its µs/particle-step = CPU s / (points × 1500).",
             "", "| ppc | points SP / DP | steps | SP wall s | DP wall s | SP µs/pps | DP µs/pps (all points) | "
             "DP µs per soil-point-step | DP/SP | DP/SP per pair (median; range) | status | paper points | paper SP / DP s | "
             "paper SP / DP µs/pps | paper DP/SP |",
             "|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|"]
    for ppc, res, ratios in rows:
        sp, dp = res["semi-implicit-single-point"], res["semi-implicit-double-point"]
        paper = PAPER.get(ppc)
        ptxt = ("| — | — | — | —" if paper is None else
                f"| {paper[0]:,} | {paper[1]:,} / {paper[2]:,} | {1e6 * paper[1] / (paper[0] * PAPER_STEPS):.1f} / "
                f"{1e6 * paper[2] / (paper[0] * PAPER_STEPS):.1f} | {paper[2] / paper[1]:.2f}")
        dp_soil = 1e6 * dp[2] / (sp[0] * dp[1]) if dp[1] else float("nan")  # the paper counts one phase
        lines.append(f"| {ppc}² | {sp[0]:,} / {dp[0]:,} | {sp[1]} / {dp[1]} | {sp[2]:.1f} | {dp[2]:.1f} | {sp[3]:.3f} | "
                     f"{dp[3]:.3f} | {dp_soil:.3f} | {dp[2] / sp[2]:.3f} | {statistics.median(ratios):.3f}; "
                     f"{min(ratios):.3f}–{max(ratios):.3f} | {sp[4]} / {dp[4]} {ptxt} |")
    lines += ["", "Stage split (DP, last row, % of the loop):", ""]
    st = rows[-1][1]["semi-implicit-double-point"][5]
    tot = sum(st.values()) or 1.0
    lines.append(", ".join(f"{k} {100 * v / tot:.1f} %" for k, v in st.items()))
    text = "\n".join(lines) + "\n"
    print(text)
    if a.out:
        with open(a.out, "w") as f:
            f.write(text)


if __name__ == "__main__":
    main()
