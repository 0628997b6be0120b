#!/usr/bin/env python3
"""Threads on a busy machine (issue 27, item 9): the wall time of one scene with --threads 1 and
--threads 2, on an idle machine and with a competing load that keeps one core busy (a Python busy
loop, or --load swmpm: another `swmpm solve --threads 2` of the same scene). The goal: with one core
taken, --threads 2 is no slower than 1.5 x the one-thread time. The time loop reads the other
processes' load every 2 s (solver/cpu_load.hpp) and runs fewer threads while they keep cores busy;
run.json's threads_fewest says how few.

usage: bench/loaded_threads.py [--swmpm build/app/swmpm] [--scene examples/terzaghi/scene.json]
                               [--load busy|swmpm] [--out bench/results/loaded-threads-<date>.md]
"""
import argparse, datetime, json, os, platform, shutil, subprocess, sys, tempfile, time


def solve(swmpm, run_dir, threads):
    t0 = time.monotonic()
    subprocess.run([swmpm, "solve", run_dir, "--threads", str(threads), "-q"], check=True)
    wall = time.monotonic() - t0
    rj = json.load(open(os.path.join(run_dir, "run.json")))
    return wall, rj.get("threads_fewest", threads)


def start_load(kind, swmpm, run_dir):
    if kind == "busy":
        return subprocess.Popen([sys.executable, "-c", "while True: pass"])
    return subprocess.Popen(["sh", "-c", f"while true; do {swmpm} solve {run_dir} --threads 2 -q; done"],
                            stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, start_new_session=True)


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--swmpm", default="build/app/swmpm")
    ap.add_argument("--scene", default="examples/terzaghi/scene.json")
    ap.add_argument("--load", default="busy", choices=["busy", "swmpm"])
    ap.add_argument("--out", default=f"bench/results/loaded-threads-{datetime.date.today()}.md")
    a = ap.parse_args()
    tmp = tempfile.mkdtemp(prefix="swmpm-loaded-")
    runs = {}
    for name in ("main", "load"):
        runs[name] = os.path.join(tmp, name)
        subprocess.run([a.swmpm, "preprocess", a.scene, "-o", runs[name], "-q"], check=True)
    rows = []
    for loaded in (False, True):
        load = start_load(a.load, a.swmpm, runs["load"]) if loaded else None
        if load:
            time.sleep(1.0)
        try:
            for threads in (1, 2):
                wall, fewest = solve(a.swmpm, runs["main"], threads)
                rows.append((loaded, threads, wall, fewest))
                print(f"{'loaded' if loaded else 'idle'} threads {threads}: {wall:.2f} s (fewest threads {fewest})")
        finally:
            if load:
                os.killpg(load.pid, 15) if a.load == "swmpm" else load.kill()
                load.wait()
    one = {l: w for l, t, w, f in rows if t == 1}
    lines = [f"# Threads on a busy machine, {datetime.datetime.now():%Y-%m-%d %H:%M}",
             "", f"Machine: {platform.node()}, {os.cpu_count()} cores; scene {a.scene}; load: {a.load}",
             "(a Python busy loop on one core, or another `swmpm solve --threads 2` of the same scene).", "",
             "| machine | --threads | wall [s] | / one thread | fewest threads used |", "|---|---|---|---|---|"]
    for loaded, threads, wall, fewest in rows:
        lines.append(f"| {'one core taken' if loaded else 'idle'} | {threads} | {wall:.2f} | "
                     f"{wall / one[loaded]:.2f} | {fewest} |")
    os.makedirs(os.path.dirname(a.out), exist_ok=True)
    open(a.out, "w").write("\n".join(lines) + "\n")
    print("\n".join(lines))
    shutil.rmtree(tmp)


if __name__ == "__main__":
    main()
