#!/usr/bin/env python3
"""Reference solutions for A2, 1D large-strain consolidation (examples/large-strain-consolidation).

Continuum model (1D strain, no gravity, incompressible grains), Lagrangian coordinate a in [0, H]
(a = 0 the impermeable base, a = H the drained top), J = current / initial volume:

    constitutive     sigma'_yy = E ln J          (--law cauchy, the default: Cauchy effective stress,
                                                  tension positive: Xie & Leo's de/(1+e) = -m_v d sigma',
                                                  m_v = 1/E, and what linear-elastic (Jaumann) gives in 1D)
                     tau'_yy = J sigma'_yy = E ln J   (--law kirchhoff: what hencky gives in 1D)
    equilibrium      sigma'_yy - p = -q          =>  J = exp((p - q) / E)   (cauchy)
                                                     E ln J / J = p - q     (kirchhoff, solved by Newton)
    fluid mass       J (m_v + n / K_f) dp/dt = d/da [ k / (gamma_w J) dp/da ],   n = 1 - (1 - n0) / J
    Darcy            k = k0 (constant)  or  k = k0 J^2 (Xie & Leo's assumption)

With k = k0 J^2 and K_f = infinity the equation is linear in J and gives Xie & Leo's closed form
(eqs. 35-36 of seed 000): S(t) = H (1 - exp(-q/E)) U(Tv), Tv = c_v t / H^2, c_v = k0 E / gamma_w.
The finite-volume solver below reproduces that (checked by --self-test) and solves the constant-k
case (what swmpm's explicit-single-point models: k does not change with porosity) for any K_f.

Usage:
    reference.py --k-law constant --Kf 2.2e9 --out reference-settlement.csv        (t, settlement)
    reference.py --k-law xie-leo --Kf inf --closed-form --out ...                   (the series)
    reference.py --self-test
Standard library only. Finite volumes in a (N cells), backward Euler with Picard iterations on
the coefficients, time steps growing geometrically from dt0.
"""
import argparse, math, sys

GAMMA_W = 1000.0 * 9.81  # rho_w g, the solver's g = 9.81 in k = rho_f g kappa / mu


def tridiag(a, b, c, d):
    n = len(d)
    cp, dp = [0.0] * n, [0.0] * n
    cp[0], dp[0] = c[0] / b[0], d[0] / b[0]
    for i in range(1, n):
        m = b[i] - a[i] * cp[i - 1]
        cp[i] = c[i] / m if i < n - 1 else 0.0
        dp[i] = (d[i] - a[i] * dp[i - 1]) / m
    x = [0.0] * n
    x[-1] = dp[-1]
    for i in range(n - 2, -1, -1):
        x[i] = dp[i] - cp[i] * x[i + 1]
    return x


def volume_ratio(s, E, law):
    """J for the effective stress s = p - q (<= 0) and its derivative dJ/ds."""
    if law == "cauchy":
        J = math.exp(s / E)
        return J, J / E
    J = math.exp(s / E)  # Newton on g(J) = E ln J - s J = 0 from the Cauchy value
    for _ in range(50):
        g, dg = E * math.log(J) - s * J, E / J - s
        step = g / dg
        J -= step
        if abs(step) < 1e-15:
            break
    return J, J * J / (E * (1.0 - math.log(J)))  # d(E ln J / J)/dJ = E (1 - ln J) / J^2


def solve(H=1.0, E=1e6, q=2e5, n0=0.3, k0=1e-4, Kf=2.2e9, k_law="constant", t_end=300.0, N=200,
          dt0=1e-5, growth=1.005, dt_max=0.05, times=None, law="cauchy"):
    """Returns [(t, settlement S(t), p profile [p at cell centres])] at the requested times."""
    da = H / N
    p = [q] * N
    t = 0.0
    dt = dt0
    times = sorted(times or [])
    out = []
    ti = 0

    def coeffs(pv):
        JdJ = [volume_ratio(x - q, E, law) for x in pv]
        J = [j for j, _ in JdJ]
        n = [1.0 - (1.0 - n0) / j for j in J]
        cap = [dj + (j * ni / Kf if Kf != float("inf") else 0.0) for (j, dj), ni in zip(JdJ, n)]
        kk = [k0 * (j * j if k_law == "xie-leo" else 1.0) for j in J]
        cond = [ki / (GAMMA_W * j) for ki, j in zip(kk, J)]  # k / (gamma_w J)
        return cap, cond

    def settlement(pv):
        return sum(1.0 - volume_ratio(x - q, E, law)[0] for x in pv) * da

    while ti < len(times):
        step = min(dt, times[ti] - t)
        p_old = p[:]
        p_new = p[:]
        for _ in range(50):  # Picard on the coefficients at the new level
            cap, cond = coeffs(p_new)
            a, b, c, d = [0.0] * N, [0.0] * N, [0.0] * N, [0.0] * N
            for i in range(N):
                b[i] = cap[i] * da / step
                d[i] = cap[i] * da / step * p_old[i]
                if i > 0:  # face i-1/2 (impermeable base below cell 0)
                    kf = 2.0 / (1.0 / cond[i] + 1.0 / cond[i - 1]) / da
                    a[i] -= kf
                    b[i] += kf
                if i < N - 1:
                    kf = 2.0 / (1.0 / cond[i] + 1.0 / cond[i + 1]) / da
                    c[i] -= kf
                    b[i] += kf
                else:  # drained top: p = 0 at a = H, half a cell away
                    b[i] += cond[i] / (0.5 * da)
            nxt = tridiag(a, b, c, d)
            change = max(abs(x - y) for x, y in zip(nxt, p_new))
            p_new = nxt
            if change < 1e-7 * q:
                break
        p = p_new
        t += step
        if abs(t - times[ti]) < 1e-12:
            out.append((t, settlement(p), p[:]))
            ti += 1
        else:
            dt = min(dt * growth, dt_max)
    return out


def series_U(Tv, terms=400):
    if Tv <= 0:
        return 0.0
    return 1.0 - sum(2.0 / M ** 2 * math.exp(-M * M * Tv) for M in ((2 * m + 1) * math.pi / 2 for m in range(terms)))


def closed_form_settlement(t, H=1.0, E=1e6, q=2e5, k0=1e-4):
    cv = k0 * E / GAMMA_W
    return H * (1.0 - math.exp(-q / E)) * series_U(cv * t / H ** 2)


def default_times(t_end):
    ts, t = [], 0.01
    while t < t_end:
        ts.append(round(t, 6))
        t *= 1.1
    return ts + [t_end]


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--k-law", choices=["constant", "xie-leo"], default="constant")
    ap.add_argument("--Kf", type=float, default=2.2e9, help="fluid bulk modulus [Pa] (inf: incompressible)")
    ap.add_argument("--E", type=float, default=1e6)
    ap.add_argument("--q", type=float, default=2e5)
    ap.add_argument("--k", type=float, default=1e-4)
    ap.add_argument("--end", type=float, default=300.0)
    ap.add_argument("--N", type=int, default=200)
    ap.add_argument("--law", choices=["cauchy", "kirchhoff"], default="cauchy",
                    help="sigma' = E ln J (cauchy: linear-elastic) or tau' = E ln J (kirchhoff: hencky)")
    ap.add_argument("--title", default="A2 1D large-strain consolidation", help="first comment line's case name")
    ap.add_argument("--closed-form", action="store_true", help="the Xie-Leo series instead (k = k0 J^2, K_f = inf)")
    ap.add_argument("--height", type=float, default=1.0,
                    help="initial height above the base of the point whose settlement is tabulated (1: the top surface)")
    ap.add_argument("--column", default="top.displacement_y", help="CSV column name (a monitor of swmpm)")
    ap.add_argument("--out", default="")
    ap.add_argument("--self-test", action="store_true")
    a = ap.parse_args()
    if a.self_test:
        ts = [1.0, 10.0, 50.0, 150.0]
        res = solve(k_law="xie-leo", Kf=float("inf"), times=ts, N=a.N)
        worst = 0.0
        for t, S, _ in res:
            ref = closed_form_settlement(t)
            worst = max(worst, abs(S - ref))
            print(f"t = {t:6.1f} s  FV {S:.6f} m  closed form {ref:.6f} m  diff {S - ref:+.2e} m")
        print("self-test", "passed" if worst < 5e-5 else "FAILED", f"(max diff {worst:.2e} m)")
        sys.exit(0 if worst < 5e-5 else 1)
    times = default_times(a.end)
    H = 1.0
    if a.closed_form:
        what = (f"Xie & Leo closed form (k = k0 J^2, K_f = inf): S = H (1 - exp(-q/E)) U(Tv), c_v = k0 E / gamma_w = "
                f"{a.k * a.E / GAMMA_W:.5g} m^2/s, U = 1 - sum 2/M^2 exp(-M^2 Tv); point at initial height {a.height:g} m")
        rows = [(t, closed_form_settlement(t, E=a.E, q=a.q, k0=a.k) * a.height / H) for t in [0.0] + times]
        if a.height != H:
            what += " (scaled by height/H: exact only at the end, when the strain is uniform)"
    else:
        what = (f"finite volumes ({a.N} cells, backward Euler), k = {'k0' if a.k_law == 'constant' else 'k0 J^2'}, "
                f"K_f = {a.Kf:g} Pa, {'sigma' if a.law == 'cauchy' else 'tau'}' = E ln J "
                f"({a.law.capitalize()}); settlement of the point at initial height {a.height:g} m")
        res = solve(E=a.E, q=a.q, k0=a.k, Kf=a.Kf, k_law=a.k_law, times=times, N=a.N, law=a.law)
        rows = [(0.0, 0.0)]
        da = H / a.N
        for t, S, p in res:
            m = min(a.N, int(a.height / da + 1e-9))
            strain = [1.0 - volume_ratio(x - a.q, a.E, a.law)[0] for x in p]
            S = sum(strain[:m]) * da + (strain[m] * (a.height - m * da) if m < a.N else 0.0)
            rows.append((t, S))
    text = (f"# {a.title}, E = {a.E:g} Pa, nu = 0, q = p0 = {a.q:g} Pa, k0 = {a.k:g} m/s, H = 1 m\n"
            f"# {what}\n# generated by examples/large-strain-consolidation/reference.py\n"
            f"time,{a.column}\n" + "".join(f"{t:.6g},{0.0 - S:.8g}\n" for t, S in rows))
    if a.out:
        open(a.out, "w").write(text)
    else:
        sys.stdout.write(text)


if __name__ == "__main__":
    main()
