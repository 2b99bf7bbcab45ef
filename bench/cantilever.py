#!/usr/bin/env python3
"""A cantilever bar bent by a small load and released: how much of its vibration each integrator keeps.

The bar (length L, square section a, clamped at x = 0, hexes of side a / n) is first bent quasi-statically
by a weak gravity, then released with gravity off, undamped, by backward Euler, BDF2 and TR-BDF2 at the
same dt (a twentieth of the measured period), and by BDF2 at a tenth of that dt. The tip's vertical offset is
recorded; the period is the mean spacing of its downward zero crossings, the amplitude after five periods
the largest |offset| over the fifth period, against the start. Euler–Bernoulli's first bending mode of the
same bar (E from μ and λ) gives the period a slender, unlocked bar would have.

  PYTHONPATH=build/release/python python3 bench/cantilever.py [--cells-through 2] [--plot docs/cantilever.png]
"""
import argparse
import math
import sys
import time

import numpy as np

import snh


def bar(length, side, n):
    """Hexes of side `side / n`: (vertices (k, 3), cells (m, 8)) in snh.box's corner order."""
    nx, ny, nz = round(length / side * n), n, n
    xs, ys, zs = np.linspace(0, length, nx + 1), np.linspace(-side / 2, side / 2, ny + 1), np.linspace(-side / 2, side / 2, nz + 1)
    V = np.array([[x, y, z] for z in zs for y in ys for x in xs])
    index = lambda i, j, k: i + (nx + 1) * (j + (ny + 1) * k)
    _, box_cells, _ = snh.box("hex8", 1)  # the corner order of a unit lattice cell, as offsets
    box_vertices, _, _ = snh.box("hex8", 1)
    offsets = ((box_vertices[box_cells[0]] + 1) / 2).astype(int)
    cells = [[index(i + o[0], j + o[1], k + o[2]) for o in offsets] for k in range(nz) for j in range(ny) for i in range(nx)]
    return V, np.array(cells, dtype=np.int32)


def crossings(t, y):
    """Times where y goes from above zero to below (linear interpolation)."""
    out = []
    for k in range(1, len(y)):
        if y[k - 1] > 0 >= y[k]:
            out.append(t[k - 1] + (t[k] - t[k - 1]) * y[k - 1] / (y[k - 1] - y[k]))
    return out


def main():
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--cells-through", type=int, default=2, help="hexes across the bar's thickness (default 2)")
    p.add_argument("--periods", type=int, default=5, help="periods to run (default 5)")
    p.add_argument("--plot", help="write a PNG of the tip's offset over time")
    a = p.parse_args()
    L, side, mu, lam, rho = 2.0, 0.2, 300.0, 1200.0, 1.0
    V, C = bar(L, side, a.cells_through)
    material = snh.material("stable_neo_hookean", mu=mu, lam=lam)
    clamp = np.flatnonzero(V[:, 0] == 0.0)
    tip = int(np.argmin(np.linalg.norm(V - [L, 0, 0], axis=1)))
    E = mu * (3 * lam + 2 * mu) / (lam + mu)
    I, A = side ** 4 / 12, side ** 2
    period_eb = 2 * math.pi / (1.8751 ** 2 * math.sqrt(E * I / (rho * A * L ** 4)))
    statics = snh.Simulation(V, C, material, clamp, integrator="quasi_static", density=rho, gravity=[0, -0.3, 0], tolerance=1e-9)
    statics.step()
    bent = statics.positions
    print(f"bar {L} x {side} x {side}, {len(C)} hexes ({a.cells_through} through), mu {mu}, lambda {lam}, density {rho}: "
          f"tip bent {bent[tip, 1] - V[tip, 1]:.4g}; Euler-Bernoulli period {period_eb:.4g} s")

    def release(integrator, dt, end):
        sim = snh.Simulation(V, C, material, clamp, integrator=integrator, dt=dt, density=rho, initial=bent, tolerance=1e-9)
        t, y = [0.0], [bent[tip, 1] - V[tip, 1]]
        start = time.perf_counter()
        steps = round(end / dt)
        for k in range(1, steps + 1):
            sim.step(k * dt)
            t.append(k * dt)
            y.append(sim.positions[tip, 1] - V[tip, 1])
        return np.array(t), np.array(y), time.perf_counter() - start

    # The period from a fine BDF2 run, then every integrator at a twentieth of it.
    t, y, _ = release("bdf2", period_eb / 400, 2.2 * period_eb)
    c = crossings(t, y)
    period = c[1] - c[0]
    dt = period / 20
    end = a.periods * period
    runs = {}
    print(f"measured period {period:.4g} s ({period / period_eb:.3f} of Euler-Bernoulli's); dt = period / 20 = {dt:.4g} s")
    print(f"{'integrator':<22} {'dt':>8} {'period':>8} {'amplitude after ' + str(a.periods) + ' periods':>28} {'seconds':>8}")
    for name, integrator, step in [("backward Euler", "backward_euler", dt), ("BDF2", "bdf2", dt), ("TR-BDF2", "tr_bdf2", dt),
                                  ("BDF2, dt / 10", "bdf2", dt / 10)]:
        t, y, seconds = release(integrator, step, end)
        c = crossings(t, y)
        measured = (c[-1] - c[0]) / (len(c) - 1) if len(c) >= 2 else float("nan")
        last = (t >= end - period - 1e-12)
        kept = np.max(np.abs(y[last])) / abs(y[0])
        runs[name] = (t, y)
        print(f"{name:<22} {step:8.4g} {measured:8.4g} {kept:28.3f} {seconds:8.2f}")
    if a.plot:
        import matplotlib
        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
        fig, ax = plt.subplots(figsize=(8, 3.6), dpi=110)
        for name, (t, y) in runs.items():
            ax.plot(t / period, y / abs(runs[name][1][0]), label=name, lw=1.4 if name != "BDF2, dt / 10" else 0.9)
        ax.set_xlabel("time (periods)")
        ax.set_ylabel("tip offset / initial")
        ax.set_title(f"A released cantilever, undamped: dt = period / 20 ({len(C)} hexes)")
        ax.axhline(0, color="0.6", lw=0.6)
        ax.legend(loc="upper right", fontsize=8)
        fig.tight_layout()
        fig.savefig(a.plot)
        print(f"wrote {a.plot}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
