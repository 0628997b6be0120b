#!/usr/bin/env python3
"""Peak memory of each rank of `mpirun -n N swmpm solve` over a short run, two builds side by side
(issue 28: a fresh start under mpirun reads the particles on rank 0 and deals them out in slices;
before, every rank read all of them and built the formulation from them).

The scene is bench/mpi_scaling.py's 3D dry box (GIMP, 2 points per cell per axis), a few steps, no
frames but the first and the last. Each build runs on 1 rank (no mpirun) and on each of `--ranks` (4 on this 2-core VM: memory only, its times mean nothing),
`--repeat` rounds interleaved; each rank runs under `/usr/bin/time -f %M` (its peak resident set,
KB). The time of the start is run.json's wall_seconds less loop_seconds.

Usage: bench/mpi_start_memory.py --swmpm build/app/swmpm --base /tmp/base/build/app/swmpm
                                 [--cells 120x20x20] [--steps 5] [--ranks 2,4] [--repeat 2]
                                 [--out bench/results/mpi-start-memory-<date>.md]
"""
import argparse, datetime, json, os, platform, re, subprocess, tempfile

from mpi_scaling import MPI_ENV, emit, prepare, scene


def peak_rss_mb(swmpm, rd, ranks):
    """Each rank's peak RSS (MB, in rank order of their reports) and run.json."""
    cmd = ["/usr/bin/time", "-f", "peak-kb %M", swmpm, "-q", "solve", rd, "--threads", "1"]
    if ranks > 1:
        cmd = ["mpirun", "-n", str(ranks)] + cmd
    r = subprocess.run(cmd, env=MPI_ENV, capture_output=True, text=True, check=True)
    peaks = sorted((int(m) / 1024.0 for m in re.findall(r"peak-kb (\d+)", r.stderr)), reverse=True)
    with open(os.path.join(rd, "run.json")) as f:
        return peaks, json.load(f)


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--swmpm", default="build/app/swmpm")
    ap.add_argument("--base", required=True, help="the build before, to run side by side")
    ap.add_argument("--cells", default="120x20x20")
    ap.add_argument("--steps", type=int, default=5)
    ap.add_argument("--ranks", default="2,4", help="rank counts besides 1 (more than the cores: memory only)")
    ap.add_argument("--repeat", type=int, default=2)
    ap.add_argument("--out", default="")
    a = ap.parse_args()
    nx, ny, nz = (int(v) for v in a.cells.split("x"))
    builds = {"before": a.base, "this": a.swmpm}
    rows = []
    with tempfile.TemporaryDirectory() as work:
        rds = {name: prepare(exe, scene(f"box-{name}", nx, ny, nz, a.steps), work) for name, exe in builds.items()}
        counts = [1] + [int(r) for r in a.ranks.split(",")]
        results = {(name, r): [] for name in builds for r in counts}
        for _ in range(a.repeat):
            for name, exe in builds.items():
                for ranks in counts:
                    results[(name, ranks)].append(peak_rss_mb(exe, rds[name], ranks))
        for (name, ranks), runs in results.items():
            points = runs[0][1]["particles"]["solid"]
            peaks = [max(p[0]) for p in runs]
            others = [min(p[0]) for p in runs]
            start = [rj["wall_seconds"] - rj["loop_seconds"] for _, rj in runs]
            rows.append(f"| {name} | {ranks} | {points:,} | {min(peaks):.0f} | {min(others):.0f} | "
                        f"{min(start):.2f} |")
    head = (f"# Peak memory per rank at the start under mpirun\n\n{datetime.date.today()}, "
            f"{platform.node()} ({os.cpu_count()} cores), `bench/mpi_start_memory.py --cells {a.cells} "
            f"--steps {a.steps} --ranks {a.ranks} --repeat {a.repeat}`; before: {a.base}, this: {a.swmpm}; "
            "smallest of the rounds.\n\n"
            "| build | ranks | points | largest rank's peak RSS, MB | smallest rank's peak RSS, MB | start s |\n"
            "|---|---|---|---|---|---|\n")
    emit(head + "\n".join(rows) + "\n", a.out)


if __name__ == "__main__":
    main()
