#!/usr/bin/env python3
"""The first wave at each gauge of a D4 run (monitors.csv of swmpm): arrival, crest and amplitude.

usage: gauges.py RUN_DIR [GATE_X]

A gauge's first crest is the level's first local maximum that stands 2 mm above the level at t = 0.
Its front's foot is found walking back from the front's steepest point until the level rises slower than 10 mm/s
(the wave's front rises at 30-80 mm/s; the water's slow drift, see README, at about 3 mm/s): the
arrival time is the foot's time and the amplitude is the crest above the foot's level. Prints a
Markdown table.
"""
import csv
import sys


def read(run_dir):
    rows = [r for r in csv.reader(l for l in open(f"{run_dir}/monitors.csv") if not l.startswith("#"))]
    head, data = rows[0], [[float(v) for v in r] for r in rows[1:]]
    return head, data


def first_wave(t, h):
    h0 = h[min(range(len(t)), key=lambda i: abs(t[i]))]  # level at t = 0
    crest = next((i for i in range(1, len(h) - 1) if h[i] >= h[i - 1] and h[i] > h[i + 1] and h[i] > h0 + 0.002), None)
    if crest is None:
        return None
    def rate(i):
        return (h[i] - h[i - 1]) / (t[i] - t[i - 1])

    rise = crest  # the rising segment before the crest, then its steepest point
    while rise > 1 and rate(rise) > 0:
        rise -= 1
    foot = max(range(rise + 1, crest + 1), key=rate)
    while foot > 1 and rate(foot) > 0.010:
        foot -= 1
    return t[foot], h[foot], t[crest], h[crest], h0


def main():
    run_dir = sys.argv[1]
    gate = float(sys.argv[2]) if len(sys.argv) > 2 else 0.3
    head, data = read(run_dir)
    t = [r[0] for r in data]
    gauges = {"G1": 0.75, "G2": 1.05, "G3": 1.35, "G4": 1.65}
    print("| gauge | x [m] (from the gate) | level at t = 0 [m] | arrival [s] | level then [m] | crest [s] | crest level [m] | amplitude [mm] |")
    print("|---|---|---|---|---|---|---|---|")
    for name, x in gauges.items():
        col = head.index(f"{name}.water_level")
        w = first_wave(t, [r[col] for r in data])
        if w is None:
            print(f"| {name} | {x} ({x - gate:.2f}) | — | no crest 2 mm above still water by t = {t[-1]:.2f} s | | | | |")
            continue
        ta, ha, tc, hc, h0 = w
        print(f"| {name} | {x} ({x - gate:.2f}) | {h0:.4f} | {ta:.3f} | {ha:.4f} | {tc:.3f} | {hc:.4f} | {1000 * (hc - ha):.1f} |")


if __name__ == "__main__":
    main()
