#!/usr/bin/env python3
"""psi along F = sI (uniform compression and expansion, s from 0.02 to 2) for every energy of snh, with the
same Lame parameters: where each energy has its minimum, whether it stays finite as s -> 0 (a trap or an
escape) or blows up, and which are undefined for J <= 0.

    PYTHONPATH=build/release/python python3 examples/python/compare_energies.py [--out PLOT.png] [--mu 1 --lam 10]

With matplotlib it draws the curves into --out (default compare_energies.png); without it (or with --text)
it prints a table. Either way it prints, per energy, psi(0.1 I), psi(I) and the s of the smallest psi."""
import argparse
import sys

import numpy as np

import snh


def curves(mu, lam, s):
    """{name: psi(s I)} for every energy; the batch of F is evaluated in one call."""
    F = s[:, None, None] * np.eye(3)
    return {name: snh.material(name, mu=mu, lam=lam).psi(F) for name in snh.material_names()}


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", default="compare_energies.png", help="the plot (with matplotlib)")
    ap.add_argument("--mu", type=float, default=1.0)
    ap.add_argument("--lam", type=float, default=10.0)
    ap.add_argument("--text", action="store_true", help="print the table only, even with matplotlib")
    a = ap.parse_args(argv)
    s = np.linspace(0.02, 2.0, 100)
    psi = curves(a.mu, a.lam, s)

    print(f"psi(sI), mu = {a.mu:g}, lambda = {a.lam:g}")
    print(f"{'energy':<24}{'psi(0.1 I)':>14}{'psi(I)':>14}{'argmin s':>10}")
    for name, v in psi.items():
        at = psi_at(a.mu, a.lam, name, 0.1), psi_at(a.mu, a.lam, name, 1.0)
        print(f"{name:<24}{at[0]:>14.6g}{at[1]:>14.6g}{s[np.argmin(v)]:>10.3f}")

    if a.text:
        return 0
    try:
        import matplotlib
        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
    except ImportError:
        print("(matplotlib is not installed: the table above is the result)")
        return 0
    fig, ax = plt.subplots(figsize=(8, 5))
    for name, v in psi.items():
        ax.plot(s, np.where(np.isfinite(v), v, np.nan), label=name)
    ax.set_xlabel("s (F = sI)")
    ax.set_ylabel("psi")
    ax.set_ylim(-5, 30)
    ax.axvline(1.0, color="gray", lw=0.5)
    ax.legend(fontsize=7)
    ax.set_title(f"psi along F = sI (mu = {a.mu:g}, lambda = {a.lam:g})")
    fig.tight_layout()
    fig.savefig(a.out, dpi=100)
    print(f"plot: {a.out}")
    return 0


def psi_at(mu, lam, name, s):
    return float(snh.material(name, mu=mu, lam=lam).psi(s * np.eye(3)))


if __name__ == "__main__":
    sys.exit(main())
