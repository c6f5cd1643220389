"""Chatter and sticking in the simulator (issue 30): the published closed forms it meets,
the convergence of the accumulation jump and an impact damper whose ball rides on a wall.
Prints the tables of README.md and draws the figures of ``figures/``.

Run: ``python studies/chatter_sticking/run.py [--figures-only]`` (a few minutes).
"""

from __future__ import annotations

import argparse
import math
import time
from pathlib import Path

import mpmath
import numpy as np
from matplotlib.figure import Figure

import impactcont as ic
from impactcont.model.stops import Stops
from impactcont.plots.series import (
    Series,
    figure_legend,
    fit_labels,
    markers_whole,
    panel_figure,
    time_history,
)

HERE = Path(__file__).resolve().parent
FIGURES = HERE / "figures"
WIDTH = 7.0  # inches: a journal's double column
# the riding impact damper: docs/machines.md's (ball mass 0.2 in a clearance +-0.3, F = 1 on a
# primary of mass 1 on a spring 1) with its primary damped at eta = 0.3 and R = 0.3
RIDE_MASS, RIDE_GAP, RIDE_R, RIDE_ETA = 0.2, 0.3, 0.3, 0.3


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


def two_mass_release_rows(periods: float = 6.0) -> list[str]:
    """The paper's two masses in series (mass 1 pushed into its stop b = 0 by F_static =
    0.5, omega 0.5, R 0.6, eta 0.1), from x1 = -0.5 at rest: every sticking phase of mass 1
    against the closed form of the held system. Held, ``x1 = 0``: mass 2 is a damped
    oscillator of its own, ``x2'' + 0.4 x2' + 2 x2 = 0`` (C = 2 eta K), and the stop presses
    mass 1 with ``p = 0.5 + cos(theta) + x2 + 0.2 x2'`` (row 1 of eq. (1) with x1'' = 0); the
    release is the first zero of p (mpmath, 30 digits)."""
    osc = ic.ImpactOscillator(M=np.eye(2), K=[[1, -1], [-1, 2]], F=[1, 0], R=0.6, b=0.0,
                              omega=0.5, eta=0.1, F_static=[0.5, 0.0])
    res = ic.simulate(osc, [-0.5, 0, 0, 0], 0.0, periods)
    mp = mpmath.mp
    rows = ["| phase | start | end (simulated) | release (closed form) | difference | "
            "largest relative force difference |", "|---|---|---|---|---|---|"]
    for k, p in enumerate(res.sticking):
        x0, v0 = mp.mpf(float(p.start_state[1])), mp.mpf(float(p.start_state[3]))
        th0, om = mp.mpf(float(p.start_phase)), mp.mpf(0.5)
        wn, zeta = mp.sqrt(2), mp.mpf(0.4) / (2 * mp.sqrt(2))
        wd = wn * mp.sqrt(1 - zeta**2)
        B = (v0 + zeta * wn * x0) / wd

        def pressing(tau, x0=x0, B=B, th0=th0, om=om, wn=wn, zeta=zeta, wd=wd):
            tau = mp.mpf(tau)
            e = mp.exp(-zeta * wn * tau)
            x = e * (x0 * mp.cos(wd * tau) + B * mp.sin(wd * tau))
            v = e * ((B * wd - zeta * wn * x0) * mp.cos(wd * tau)
                     - (x0 * wd + zeta * wn * B) * mp.sin(wd * tau))
            return mp.mpf(0.5) + mp.cos(th0 + om * tau) + x + mp.mpf(0.2) * v

        pick = np.unique(np.linspace(0, p.times.size - 1, 50).astype(int))
        exact = np.array([float(pressing(float(t - p.start))) for t in p.times[pick]])
        err = float(np.abs(p.forces[pick, 0] - exact).max() / np.abs(exact).max())
        t_r = held_release(pressing, p.end - p.start) if p.ended_by == "release" else math.nan
        rows.append(f"| {k} ({p.ended_by}) | {p.start:.12f} | {p.end:.15f} | "
                    f"{p.start + t_r:.15f} | {p.end - p.start - t_r:.1e} | {err:.1e} |")
    return rows


def damper(omega: float, *, R: float = RIDE_R, eta: float = RIDE_ETA) -> ic.ImpactOscillator:
    """The impact damper of docs/machines.md (a primary of mass 1 on a spring 1, forced
    cos(omega t); a free ball of mass 0.2 in a clearance |x2 - x1| <= 0.3), C = 2 eta K."""
    return ic.ImpactOscillator(M=np.diag([1.0, RIDE_MASS]), K=np.diag([1.0, 0.0]), F=[1, 0],
                               R=R, b=RIDE_GAP, omega=omega, eta=eta,
                               stops=Stops(mass=2, relative_to=1, mirror=True))


def riding_start(osc: ic.ImpactOscillator) -> np.ndarray:
    """The ball on the upper wall (x2 = x1 + b) and the pair on the forced response of the
    held system (mass 1 + m) at phase 0, where the primary's acceleration presses the ball."""
    m, c, omega = osc.M[1, 1], osc.C[0, 0], osc.omega
    amplitude = 1.0 / (1.0 - (1.0 + m) * omega**2 + 1j * c * omega)
    x1, v1 = amplitude.real, (1j * omega * amplitude).real
    return np.array([x1, x1 + osc.b, v1, v1])


def riding(omega: float, periods: float, *, chatter_tolerance: float = 1e-6,
           R: float = RIDE_R, eta: float = RIDE_ETA) -> tuple[ic.ImpactOscillator, object]:
    """The riding damper simulated from :func:`riding_start` with its trajectory."""
    osc = damper(omega, R=R, eta=eta)
    res = ic.simulate(osc, riding_start(osc), 0.0, periods, trajectory=True,
                      chatter_tolerance=chatter_tolerance)
    return osc, res


def held_pressing(osc: ic.ImpactOscillator, stop: str, X0: np.ndarray, phase0: float):
    """The closed form of a sticking phase of the ball on a wall: the pressing force p(tau).

    Held, the ball moves with the primary (``x2 = x1 +- b``): one mass ``M = 1 + m`` on the
    spring k = 1 and the damper c, ``M x1'' + c x1' + k x1 = cos(theta)``, whose exact solution
    from ``(x1, x1')`` at phase ``theta0`` is the forced response plus the damped free
    vibration. The wall's force on the ball is ``m x2'' = m x1''``; on the upper wall it
    pushes the ball back, ``p_U = -m x1''``, on the lower ``p_L = m x1''``. The ball is
    released where ``x1''`` changes sign: where the wall's acceleration stops pressing it.
    Evaluated in mpmath (30 digits): a witness sharing nothing with the simulator's matrix
    exponential of the reduced system.
    """
    mp = mpmath.mp
    m, c, k, omega = (mp.mpf(float(v)) for v in (osc.M[1, 1], osc.C[0, 0], osc.K[0, 0],
                                                   osc.omega))
    M = 1 + m
    amplitude = 1 / (k - M * omega**2 + 1j * c * omega)
    wn, zeta = mp.sqrt(k / M), c / (2 * mp.sqrt(k * M))
    wd = wn * mp.sqrt(1 - zeta**2)
    th0 = mp.mpf(float(phase0))

    def forced(tau):
        e = amplitude * mp.expj(th0 + omega * tau)
        return mp.re(e), mp.re(1j * omega * e)

    xp0, vp0 = forced(0)
    A = mp.mpf(float(X0[0])) - xp0
    B = (mp.mpf(float(X0[2])) - vp0 + zeta * wn * A) / wd
    sign = -1 if stop == "U" else 1

    def pressing(tau):
        tau = mp.mpf(tau)
        xp, vp = forced(tau)
        decay = mp.exp(-zeta * wn * tau)
        x = xp + decay * (A * mp.cos(wd * tau) + B * mp.sin(wd * tau))
        v = vp + decay * ((B * wd - zeta * wn * A) * mp.cos(wd * tau)
                          - (A * wd + zeta * wn * B) * mp.sin(wd * tau))
        return sign * m * (mp.cos(th0 + omega * tau) - c * v - k * x) / M

    return pressing


def held_release(pressing, span: float) -> float:
    """The first zero of the closed-form pressing force after the start (within 1.5 times
    the simulated phase's span `span`): bracketed on 400 cells, then solved in mpmath."""
    grid = np.linspace(0.0, 1.5 * span, 401)[1:]
    values = [pressing(float(t)) for t in grid]
    for i in range(len(grid) - 1):
        if values[i] > 0 >= values[i + 1]:
            return float(mpmath.findroot(pressing, (grid[i], grid[i + 1]), solver="anderson",
                                         tol=1e-28))
    return math.nan


def ride_rows(osc: ic.ImpactOscillator, res) -> dict:
    """Every release of the ball from a wall against the closed form of :func:`held_pressing`;
    the contact force along every sticking phase against it too (at 50 of its samples)."""
    releases, force_error, phases = [], 0.0, []
    for p in res.sticking:
        pressing = held_pressing(osc, p.stops, p.start_state, p.start_phase)
        pick = np.unique(np.linspace(0, p.times.size - 1, 50).astype(int))
        tau = p.times[pick] - p.start
        exact = np.array([float(pressing(float(t))) for t in tau])
        force_error = max(force_error, float(np.abs(p.forces[pick, 0] - exact).max()
                                             / max(np.abs(exact).max(), 1e-300)))
        if p.ended_by == "release":
            t_r = held_release(pressing, p.end - p.start)
            releases.append(abs(p.end - p.start - t_r))
            phases.append(math.remainder(p.start_phase + osc.omega * (p.end - p.start),
                                         2 * math.pi))
    return {"releases": releases, "force_error": force_error, "phases": phases}


def riding_table(omegas=(0.1, 0.2, 0.3), periods: float = 4.0) -> list[str]:
    """The riding damper at low frequency: how the ball rides, against the closed form."""
    rows = ["| omega | impacts | accumulation points | sticking phases (U, L) | releases | "
            "largest release-time difference | largest relative force difference | release "
            "phases of the last period (U, L) |", "|---|---|---|---|---|---|---|---|"]
    for omega in omegas:
        osc, res = riding(omega, periods)
        found = ride_rows(osc, res)
        up = sum(p.stops == "U" for p in res.sticking)
        last = [(p.stops, math.remainder(p.end * omega, 2 * math.pi)) for p in res.sticking
                if p.ended_by == "release"][-2:]
        phases = ", ".join(f"{name} {phase:.4f}" for name, phase in sorted(last,
                                                                              reverse=True))
        rows.append(f"| {omega} | {res.impact_times.size} | {len(res.chatter)} | "
                    f"{up}, {len(res.sticking) - up} | {len(found['releases'])} | "
                    f"{max(found['releases']):.1e} | {found['force_error']:.1e} | {phases} |")
    return rows


def ride_figure(osc: ic.ImpactOscillator, res, width: float = WIDTH) -> Figure:
    """The riding damper's time history: the ball in the clearance (``s = x2 - x1``) with the
    walls, the sticking phases shaded, the accumulation points marked; the wall's pressing
    force on the ball under it (:func:`impactcont.plots.series.time_history`)."""
    fig, (ax_s, ax_p) = panel_figure(2, width, ncols=1, aspect=0.3 if width > 5 else 0.5)
    scale = osc.omega / (2 * math.pi)
    t = res.t * scale
    s = res.X[:, 1] - res.X[:, 0]
    walls = [Series([t[0], t[-1]], [y, y], "walls $s = \\pm b$", color="0.4",
                    linestyle="--", linewidth=0.8) for y in (osc.b, -osc.b)]
    handles = time_history(
        ax_s, ax_p, [Series(t, s, "ball in the clearance, $s = x_2 - x_1$", color="black",
                            linestyle="-", linewidth=0.9), *walls],
        res.sticking_arrays(), time_scale=scale, xlabel="$t\\,\\omega / 2\\pi$",
        ylabel="$s$", force_label="pressing force $p$", force_entry="force of wall {stop}")
    ax_s.set_xlim(t[0], t[-1])
    fig.suptitle(rf"Impact damper at $\omega = {osc.omega:g}$, $m = {osc.M[1, 1]:g}$, "
                 rf"$b = {osc.b:g}$, $R = {osc.R:g}$, $\eta = {RIDE_ETA:g}$: the ball rides "
                 "on a wall and chatters back", fontsize="medium")
    figure_legend(fig, handles)
    fit_labels(fig)
    markers_whole(ax_s)
    return fig


def preload_figure(res, osc: ic.ImpactOscillator, width: float = WIDTH) -> Figure:
    """The preloaded oscillator of the scene: held, released, chattering back."""
    fig, (ax_x, ax_p) = panel_figure(2, width, ncols=1, aspect=0.3 if width > 5 else 0.5)
    scale = osc.omega / (2 * math.pi)
    t = res.t * scale
    handles = time_history(
        ax_x, ax_p, [Series(t, res.X[:, 0], "$x_1$", color="black", linestyle="-",
                            linewidth=0.9)],
        res.sticking_arrays(), time_scale=scale, xlabel="$t\\,\\omega / 2\\pi$",
        ylabel="$x_1$", force_label="pressing force $p$", force_entry="force of stop {stop}")
    ax_x.set_xlim(t[0], t[-1])
    fig.suptitle(rf"Preloaded oscillator at $\omega = {osc.omega:g}$, "
                 rf"$F_{{static}} = 1$ into the stop $b = 0$, $R = {osc.R:g}$: held, "
                 "released, chattering back", fontsize="medium")
    figure_legend(fig, handles)
    fit_labels(fig)
    markers_whole(ax_x)
    return fig


def preloaded_run(omega: float = 0.7, periods: float = 4.0):
    """The scene's simulation: the preloaded oscillator from rest on its stop."""
    osc = ic.ImpactOscillator(M=[[1.0]], K=[[1.0]], F=[3.0], F_static=[1.0], R=0.6, b=0.0,
                              omega=omega, eta=0.05)
    return osc, ic.simulate(osc, [0.0, 0.0], 0.0, periods, trajectory=True)


def draw_figures(width: float = WIDTH) -> None:
    """The study's figures, in ``figures/``."""
    FIGURES.mkdir(exist_ok=True)
    osc, res = riding(0.2, 3.0)
    ride_figure(osc, res, width).savefig(FIGURES / "riding_damper.png", dpi=150)
    osc, res = preloaded_run()
    preload_figure(res, osc, width).savefig(FIGURES / "preloaded.png", dpi=150)


if __name__ == "__main__":
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--figures-only", action="store_true")
    args = parser.parse_args()
    if not args.figures_only:
        for title, table in (("Locked ball (Luck & Mehta 1993)", locked_ball),
                             ("Preloaded oscillator", preloaded),
                             ("Ball on a fixed floor", floor_ball),
                             ("Convergence of the accumulation jump", convergence),
                             ("Two masses in series: the release of the held mass",
                              two_mass_release_rows),
                             ("Impact damper riding on a wall", riding_table)):
            print(f"\n## {title}\n")
            print("\n".join(table()))
    draw_figures()
