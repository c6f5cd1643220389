"""Chatter and sticking in the simulator (issue 30): the published closed forms it meets
and the convergence of the accumulation jump. Prints the tables of README.md.

Run: ``python studies/chatter_sticking/run.py`` (about half a minute).
"""

from __future__ import annotations

import math
import time

import numpy as np

import impactcont as ic
from impactcont.model.stops import Stops


def ball(R, g, A, omega):
    """Height y of a ball over a table vibrating as A cos(theta): y'' = -g + A w^2 cos."""
    return ic.ImpactOscillator(M=[[1.0]], K=[[0.0]], F=[A * omega**2], F_static=[-g], R=R,
                               b=1e3, omega=omega, eta=0.0, stops=Stops(b_low=0.0, R_low=R))


def locked_ball() -> list[str]:
    """Luck & Mehta 1993: after complete chatter the ball locks on the table and leaves it
    where the table's acceleration is -g, theta_r = -arccos(1 / Gamma)."""
    rows = ["| Gamma | R | releases | theta_r (closed form) | largest deviation |",
            "|---|---|---|---|---|"]
    for gamma, R in ((1.2, 0.5), (1.5, 0.5), (2.0, 0.3), (3.0, 0.6)):
        res = ic.simulate(ball(R, 1.0, gamma, 1.0), [0.0, 0.0], -0.5 * math.pi, 8.0)
        theta_r = -math.acos(1.0 / gamma)
        ends = [p.end - 0.5 * math.pi for p in res.sticking if p.ended_by == "release"]
        dev = max((abs(math.remainder(t - theta_r, 2 * math.pi)) for t in ends), default=math.nan)
        rows.append(f"| {gamma} | {R} | {len(ends)} | {theta_r:.15f} | {dev:.1e} |")
    return rows


def preloaded() -> list[str]:
    """One mass pushed into its stop b = 0 by F_static = 1, forced 3 cos(omega t): held from
    rest at t = 0, released at omega t_r = arccos(-1/3)."""
    rows = ["| omega | t_r (closed form) | simulated | difference |", "|---|---|---|---|"]
    for omega in (0.2, 0.7, 2.0):
        osc = ic.ImpactOscillator(M=[[1.0]], K=[[1.0]], F=[3.0], F_static=[1.0], R=0.5,
                                  b=0.0, omega=omega, eta=0.05)
        res = ic.simulate(osc, [0.0, 0.0], 0.0, 1.0)
        t_r = math.acos(-1.0 / 3.0) / omega
        rows.append(f"| {omega} | {t_r:.15f} | {res.sticking[0].end:.15f} | "
                    f"{res.sticking[0].end - t_r:.1e} |")
    return rows


def floor_ball() -> list[str]:
    """A ball dropped from h = 0.5 on a fixed floor (g = 1): the accumulation at
    t_1 + 2 R v_1 / (g (1 - R)), t_1 = sqrt(2 h / g), v_1 = sqrt(2 g h)."""
    rows = ["| R | impacts resolved | t_inf (closed form) | simulated | difference |",
            "|---|---|---|---|---|"]
    for R in (0.3, 0.6, 0.9):
        res = ic.simulate(ball(R, 1.0, 0.0, 1.0), [0.5, 0.0], 0.0, 10.0)
        t_inf = 1.0 + 2 * R / (1 - R)
        rows.append(f"| {R} | {res.impact_times.size} | {t_inf:.15f} | "
                    f"{res.chatter[0].time:.15f} | {res.chatter[0].time - t_inf:.1e} |")
    return rows


def convergence() -> list[str]:
    """The paper's two masses, mass 1 pushed into its stop b = 0 by F_static = 0.5 (omega
    0.5, R 0.6, eta 0.1): chatter, stick, release, impacts; the jump taken at larger v_k
    (looser chatter_tolerance) against one at v_k ~ 6e-6."""
    osc = ic.ImpactOscillator(M=np.eye(2), K=[[1, -1], [-1, 2]], F=[1, 0], R=0.6, b=0.0,
                              omega=0.5, eta=0.1, F_static=[0.5, 0.0])

    def run(tol):
        start = time.perf_counter()
        res = ic.simulate(osc, [-0.5, 0, 0, 0], 0.0, 2.0, chatter_tolerance=tol)
        return res, time.perf_counter() - start

    ref, _ = run(1e-5)
    rows = ["| chatter_tolerance | impacts | v_k | v_k^2 | error of t_inf | error of the "
            "release | error of the final state | time (s) |",
            "|---|---|---|---|---|---|---|---|"]
    for tol in (1e-1, 1e-2, 1e-3, 1e-4, 1e-5):
        res, seconds = run(tol)
        v = res.chatter[0].last_velocity
        rows.append(f"| {tol:g} | {res.impact_times.size} | {v:.2e} | {v * v:.1e} | "
                    f"{abs(res.chatter[0].time - ref.chatter[0].time):.1e} | "
                    f"{abs(res.sticking[0].end - ref.sticking[0].end):.1e} | "
                    f"{np.abs(res.final_state - ref.final_state).max():.1e} | {seconds:.2f} |")
    return rows


if __name__ == "__main__":
    for title, table in (("Locked ball (Luck & Mehta 1993)", locked_ball),
                         ("Preloaded oscillator", preloaded),
                         ("Ball on a fixed floor", floor_ball),
                         ("Convergence of the accumulation jump", convergence)):
        print(f"\n## {title}\n")
        print("\n".join(table()))
