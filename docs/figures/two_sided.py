"""The figure of docs/two_sided.md: the two-sided model and two of its motions.

    PYTHONPATH=. python docs/figures/two_sided.py      (writes docs/figures/two_sided.png)

Left: the paper's 2-DOF chain with a clearance on both sides of mass 1 (upper stop at
x1 = b, restitution R; lower stop at x1 = -b_low, restitution R_low). Right: phase
portraits (x1, x1') of a symmetric and an asymmetric 1-2 motion (one impact on each
stop per forcing period) of the symmetric system b_low = b, each found from the
simulation it settles on and solved by shooting.
"""

from __future__ import annotations

import logging
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt
import numpy as np
from matplotlib.patches import Rectangle

import impactcont as ic
from impactcont.model.stops import Stops

log = logging.getLogger("two_sided_figure")
OUT = Path(__file__).with_suffix(".png")


def paper2(b: float, omega: float) -> ic.ImpactOscillator:
    return ic.ImpactOscillator(M=np.eye(2), K=[[1.0, -1.0], [-1.0, 2.0]], F=[1.0, 0.0],
                               R=0.6, b=b, omega=omega, eta=0.1, stops=Stops(b_low=b))


def spring(ax, x0: float, x1: float, y: float, turns: int = 6) -> None:
    xs = np.linspace(x0, x1, 2 * turns + 3)
    ys = np.full_like(xs, y)
    ys[1:-1:2] += 0.08
    ys[2:-1:2] -= 0.08
    ax.plot(xs, ys, "k-", lw=1)


def schematic(ax) -> None:
    ax.add_patch(Rectangle((-0.15, -0.6), 0.15, 1.2, hatch="////", fill=False, lw=0))
    ax.plot([0, 0], [-0.6, 0.6], "k-", lw=2)
    spring(ax, 0.0, 1.0, 0.0)
    ax.add_patch(Rectangle((1.0, -0.3), 0.6, 0.6, fc="0.85", ec="k"))
    ax.text(1.3, 0.0, "$m_2$", ha="center", va="center")
    spring(ax, 1.6, 2.6, 0.0)
    ax.add_patch(Rectangle((2.6, -0.3), 0.6, 0.6, fc="0.85", ec="k"))
    ax.text(2.9, 0.0, "$m_1$", ha="center", va="center")
    ax.annotate("", xy=(3.75, 0.45), xytext=(3.25, 0.45),
                arrowprops={"arrowstyle": "->"})
    ax.text(3.3, 0.55, r"$F\cos(\omega t + \delta)$", fontsize=8)
    for x, label, side in ((3.75, "upper stop\n$x_1 = b$, $R$", 1),
                           (2.05, "lower stop\n$x_1 = -b_{low}$, $R_{low}$", -1)):
        ax.plot([x, x], [-0.75, -0.35] if side < 0 else [-0.35, 0.35], "k-", lw=3)
        ax.text(x, -0.95 if side < 0 else -0.75, label, ha="center", va="top", fontsize=8)
    ax.plot([2.9, 2.9], [-0.3, -0.75], "k:", lw=0.8)
    ax.annotate("", xy=(2.05, -0.6), xytext=(2.9, -0.6), arrowprops={"arrowstyle": "<->"})
    ax.text(2.47, -0.55, "$b_{low}$", ha="center", fontsize=8)
    ax.annotate("", xy=(3.75, -0.45), xytext=(2.9, -0.45), arrowprops={"arrowstyle": "<->"})
    ax.text(3.32, -0.42, "$b$", ha="center", fontsize=8, va="bottom")
    ax.set_xlim(-0.3, 4.6)
    ax.set_ylim(-1.4, 0.9)
    ax.set_aspect("equal")
    ax.axis("off")
    ax.set_title("Mass 1 between two stops (dotted: $x_1 = 0$)", fontsize=9)


def portrait(ax) -> None:
    for b, omega, style, what in ((0.8, 0.8, "C0-", "symmetric"), (0.5, 1.3, "C3-",
                                                                   "asymmetric")):
        osc = paper2(b, omega)
        res = ic.simulate(osc, np.zeros(4), 0.0, 200.0)
        orbit = ic.multi_impact_orbit(osc, 1, 2, res)
        log.info("%s: %r", what, orbit)
        _, X = orbit.time_series(400)
        ax.plot(X[:, 0], X[:, 2], style, lw=1.2,
                label=rf"{what}, $b = b_{{low}} = {b}$, $\omega = {omega}$; impact velocities "
                      f"{orbit.impact_velocities[0]:.3f}, {orbit.impact_velocities[1]:.3f}")
        for k in range(orbit.p):
            ax.plot(X[(k + 1) * 400 - 1, 0], X[(k + 1) * 400 - 1, 2], "k.", ms=5)
            ax.plot(orbit.states[k, 0], orbit.states[k, 2], "ko", mfc="none", ms=5)
        for x in (b, -b):
            ax.axvline(x, color=style[:2], lw=0.8, ls="--")
    ax.set_xlabel("$x_1$")
    ax.set_ylabel(r"$\dot{x}_1$")
    ax.plot([], [], "k.", ms=5, label="state before an impact")
    ax.plot([], [], "ko", mfc="none", ms=5, label="state after an impact")
    ax.plot([], [], "k--", lw=0.8, label=r"stops $x_1 = \pm b$")
    ax.figure.legend(*ax.get_legend_handles_labels(), fontsize=8, loc="outside lower center",
                     ncols=1, frameon=False)
    ax.set_title("Period-1 motions with 2 impacts, one on each stop", fontsize=9)


def main() -> None:
    logging.basicConfig(level=logging.INFO, format="%(message)s")
    # a journal's page: 7 in wide (figures are at most 7.2 in), the model above its motions
    fig = plt.figure(figsize=(7.0, 7.6), layout="constrained")
    a, b = fig.subplots(2, 1, height_ratios=[1.0, 1.6])
    schematic(a)
    portrait(b)
    fig.savefig(OUT, dpi=110)
    log.info("wrote %s", OUT)


if __name__ == "__main__":
    main()
