#!/usr/bin/env python3
"""A model of swmpm's time per step on P ranks (issue 28), from measured inputs and a stated network.

Per step and rank (explicit formulations; the decomposition of solver/parallel/domain.hpp):
  compute   n_r * c                   c: measured us per particle-step on one rank, one thread
                                      (bench/mpi_scaling.py), n_r = n / P times the load imbalance
                                      the rebalancing allows (5 %)
  exchange  k_x * (alpha + m / beta)  the shared node columns after each colour of each scatter
                                      (k_x = 4 for dry: two scatters, two phases), m = (S - 1) x the
                                      nodes of a cross-section x the bytes a node carries
  migration alpha * P + q / beta      MPI_Alltoall of counts and MPI_Alltoallv of the particles that
                                      cross a cut (pairwise: P messages), q = the crossing
                                      particles' bytes (a slide at speed v moves v dt / h of a
                                      cell layer per step)
  reductions k_r * 2 log2(P) * alpha  allreduces per step (node box, dt: 3, health, interrupt)
The time step does not depend on P. Efficiency E(P) = t(1) / t(P) at fixed particles per rank
(weak), and the per-step time of a fixed problem at P ranks (strong).

The decomposition cuts one axis into slabs of whole stripes (S node columns): at most
ceil(nodes along the axis / S) ranks. The model says where that limit stands for the 10^8-point
slope and what a second cut axis would give.

The semi-implicit-single-point section adds the distributed pressure solve (CG with BoomerAMG,
parallel::GridPoisson) from its measured cost per unknown and iteration growth.

Usage: bench/mpi_model.py --us-per-particle-step 0.45 [--alpha 1.5e-6] [--beta 12e9] [--out FILE]
                          [--sisp-us-other 2.45] [--amg-us-per-unknown 29.5] [--amg-iterations 25] [--amg-growth 0.5]
"""
import argparse, math

import mpi_scaling


def step_time(n_r, P, cross_nodes, c_us, alpha, beta, S=3, node_bytes=56, particle_bytes=420,
              crossing_fraction=0.0, k_x=4, k_r=6, imbalance=1.05):
    if P == 1:
        return n_r * c_us * 1e-6, 0.0
    compute = n_r * imbalance * c_us * 1e-6
    m = (S - 1) * cross_nodes * node_bytes
    exchange = k_x * (alpha + m / beta)
    q = crossing_fraction * n_r * particle_bytes
    migration = alpha * P + q / beta
    reductions = k_r * 2 * math.log2(P) * alpha
    return compute, exchange + migration + reductions


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--us-per-particle-step", type=float, required=True,
                    help="measured: 3D dry GIMP, one rank, one thread (bench/mpi_scaling.py)")
    ap.add_argument("--alpha", type=float, default=1.5e-6, help="s, message latency (InfiniBand HDR class)")
    ap.add_argument("--beta", type=float, default=12e9, help="bytes/s, link bandwidth per rank")
    ap.add_argument("--sisp-us-other", type=float, default=2.45,
                    help="measured: semi-implicit-single-point, 3D GIMP, one rank, us per particle-step without the pressure solve")
    ap.add_argument("--amg-us-per-unknown", type=float, default=29.5,
                    help="measured: parallel::GridPoisson one solve per unknown, 3D (tests/parallel Poisson.*)")
    ap.add_argument("--amg-iterations", type=float, default=25.0, help="measured CG iterations at 8,400 unknowns (3D)")
    ap.add_argument("--amg-growth", type=float, default=0.5, help="measured: more iterations per doubling of unknowns")
    ap.add_argument("--out", default="")
    a = ap.parse_args()
    c = a.us_per_particle_step
    lines = ["# swmpm scaling model (bench/mpi_model.py)", "",
             f"Inputs: c = {c} us per particle-step (measured, 3D dry, GIMP, one thread); network alpha = "
             f"{a.alpha * 1e6:.1f} us, beta = {a.beta / 1e9:.0f} GB/s; S = 3 (GIMP), 56 B per node "
             "(mass, momentum, force), 420 B per migrating particle, 5 % load imbalance, 4 exchanges and "
             "6 allreduces per step, a slide moving 1 % of a rank's particles across a cut per step.", ""]

    # Weak scaling at 1e6 particles per rank: each rank a slab of a cube-ish block, 8 points per cell:
    # 1.25e5 cells per rank, e.g. 50 cells thick along the cut axis and 50 x 50 across.
    n_r = 1e6
    cross = 52 * 52  # nodes of the cross-section (GIMP: cells + 1, plus the margin)
    lines += ["## Weak scaling, 10^6 particles per rank (a slab of 50 x 50 x 50 cells per rank)", "",
              "| ranks | compute s/step | communication s/step | efficiency |", "|---|---|---|---|"]
    t1, _ = step_time(n_r, 1, cross, c, a.alpha, a.beta)
    for P in (1, 2, 16, 128, 1024):
        comp, comm = step_time(n_r, P, cross, c, a.alpha, a.beta, crossing_fraction=0.01)
        lines.append(f"| {P} | {comp:.4f} | {comm:.6f} | {t1 / (comp + comm):.3f} |")

    # The 1e8-point 3D slope: 8 points per cell, the soil filling half a grid of 1000 x 250 x 100 cells.
    n = 1e8
    nx, ny, nz = 1000, 250, 100
    stripes = math.ceil((nx + 2) / 3)
    lines += ["", "## Strong scaling, a 10^8-point 3D slope (grid 1000 x 250 x 100 cells, soil in half of it)", "",
              f"Slabs along x: at most {stripes} ranks (stripes of 3 node columns). "
              "Beyond that, a second cut axis (pencils) is modelled: the cross-section of a rank's block shrinks "
              "by the number of cuts across, and the messages double (two neighbour directions).", "",
              "| ranks | decomposition | particles per rank | compute s/step | communication s/step | efficiency vs 1 rank |",
              "|---|---|---|---|---|---|"]
    t_one, _ = step_time(n, 1, 0, c, a.alpha, a.beta)
    for P in (1, 64, 256, stripes, 1024):
        if P <= stripes:
            kind, cross_nodes, k_x = "slabs", (ny + 2) * (nz + 2), 4
        else:
            across = math.ceil(P / stripes)
            kind, cross_nodes, k_x = f"pencils ({stripes} x {across})", (ny + 2) * (nz + 2) / across + (nx + 2) / stripes * (nz + 2), 8
        comp, comm = step_time(n / P, P, cross_nodes, c, a.alpha, a.beta, crossing_fraction=0.01, k_x=k_x)
        lines.append(f"| {P} | {kind} | {n / P:.3g} | {comp:.4f} | {comm:.6f} | {t_one / (P * (comp + comm)):.3f} |")
    lines += ["", "The pencils row is a model of a decomposition swmpm does not have yet (one cut axis today)."]

    # semi-implicit-single-point: the explicit stages as above (its own measured us per
    # particle-step without the pressure solve), plus the distributed pressure solve
    # (parallel::GridPoisson: CG with BoomerAMG, setup every step).
    cs, ca = a.sisp_us_other, a.amg_us_per_unknown
    lines += ["", "## semi-implicit-single-point, weak scaling at 10^6 particles per rank (modelled; it does not run on "
              "several ranks yet)", "",
              f"Inputs (measured 2026-12-06 on one rank, 3D GIMP box of 192,000 points, 50 steps): {cs} us per "
              "particle-step without the pressure solve; the pressure solve of parallel::GridPoisson (3D quadratic "
              f"B-splines, tests/parallel Poisson.*): {ca} us per unknown (coordinate assembly, BoomerAMG's setup every "
              f"solve, CG), {a.amg_iterations:.0f} iterations at 8,400 unknowns, {a.amg_growth} more per doubling "
              "of the unknowns (24, 25, 26 measured from 1,248 to 8,400). One unknown per 8 points. Per CG iteration: "
              "the SpMV's halo (two neighbours, (S - 1) node layers of a cross-section, 8 B per node) and two "
              "allreduces; per V-cycle level (8x coarser per level) two halo exchanges, from 2 neighbours on the fine "
              "levels to 6 on the coarse ones; the coarsest level gathered (log2 P latencies); the setup as 5 messages "
              "per level. Imbalance 5 %. The whole solve's compute is scaled by the iterations (conservative: "
              "the setup does not grow with them).", "",
              "| ranks | compute s/step (other stages + solve) | CG iterations | communication s/step | efficiency |",
              "|---|---|---|---|---|"]
    n_r = 1e6
    u_r = n_r / 8  # unknowns per rank
    cross = 52 * 52
    def sisp_time(P):
        N = u_r * P
        its = a.amg_iterations + a.amg_growth * math.log2(N / 8400)
        imb = 1.0 if P == 1 else 1.05
        comp = imb * (n_r * cs + u_r * ca * its / a.amg_iterations) * 1e-6
        if P == 1:
            return comp, 0.0, its
        halo = 2 * (a.alpha + 2 * cross * 8 / a.beta)
        levels = max(1, math.ceil(math.log(N, 8)) - 1)
        vcycle = 0.0
        for l in range(levels):
            nb = 2 if l < levels - 2 else 6
            vcycle += 2 * (nb * a.alpha + 2 * cross * 8 / a.beta / 4 ** l)
        coarse = math.log2(P) * a.alpha
        per_it = halo + 2 * 2 * math.log2(P) * a.alpha + vcycle + coarse
        setup = 5 * levels * a.alpha + 2 * 2 * cross * 8 * 125 / a.beta
        explicit_comm = step_time(n_r, P, cross, cs, a.alpha, a.beta, crossing_fraction=0.01, k_x=8)[1]
        return comp, its * per_it + setup + explicit_comm, its
    t1 = sum(sisp_time(1)[:2])
    for P in (1, 2, 16, 128, 1024):
        comp, comm, its = sisp_time(P)
        lines.append(f"| {P} | {comp:.3f} | {its:.1f} | {comm:.5f} | {t1 / (comp + comm):.3f} |")
    lines += ["", "The solve's compute grows with the iterations (slowly: BoomerAMG); its communication stays below a "
              "percent of the step. Against one rank's own path (CHOLMOD's factor reused as CG's preconditioner, "
              "0.19 s per step at 30,000 nodes here), BoomerAMG's setup every step is the cost to cut (reuse its setup "
              "across steps as the one-rank path reuses its factor)."]
    mpi_scaling.emit("\n".join(lines) + "\n", a.out)


if __name__ == "__main__":
    main()
