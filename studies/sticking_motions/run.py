"""Periodic motions with sticking phases: three closed forms against the simulator.

Issue 30, items 4 and 6. Three machines whose periodic motion with a plastic impact
(``R = 0``) and a sticking phase is known in closed form (:mod:`closed_form`, mpmath at 30
digits, no package code): (a) a preloaded oscillator held on its stop, (b) Luck & Mehta's
completely inelastic ball locked on its table, (c) an impact damper whose plastic ball rides
each wall in turn. Each is held against the event-driven simulator (``ic.simulate``) run to
its steady state: the phases of every landing and release, the stick and flight times, the
state after the landing and the pressing force there; the multipliers of (c) against the
simulator's finite differences of its period map. Prints the README's tables
and draws ``figures/riding_period.png``.

Run: ``python studies/sticking_motions/run.py [--figures-only | --cost]`` (about three
minutes; ``--cost`` only the cost table).
"""

from __future__ import annotations

import argparse
import functools
import logging
import math
import sys
import time
from pathlib import Path

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
sys.path.insert(0, str(HERE))
import closed_form as cf  # noqa: E402

log = logging.getLogger("sticking_motions")

WIDTH = 7.0  # inches: a journal's double column
#: Case (a): F cos(theta) + F_static with F = 3, F_static = 1 into the stop b = 0, eta 0.05.
PRELOAD_F, PRELOAD_STATIC, PRELOAD_ETA = 3.0, 1.0, 0.05
#: Case (c): ball mass, half clearance and the primary's damping (docs/machines.md's damper
#: with a plastic ball and a damped primary, as studies/chatter_sticking rides it).
BALL_MASS, GAP, DAMPER_ETA = 0.2, 0.3, 0.3
PRELOAD_OMEGAS = (0.5, 0.7, 1.0, 1.5, 2.0)
GAMMAS = (1.2, 1.5, 2.0, 2.5, 3.0)
DAMPER_OMEGAS = (0.1, 0.2, 0.3, 0.5)
#: The omega sweep of case (c): from 0.2 to 2.35 in steps of 0.05 (the motion ends at 2.393).
SWEEP_OMEGAS = tuple(round(0.2 + 0.05 * k, 2) for k in range(44))


def preloaded(omega: float) -> ic.ImpactOscillator:
    """Case (a): one mass on a spring, pushed into its stop ``b = 0`` by ``F_static``."""
    return ic.ImpactOscillator(M=[[1.0]], K=[[1.0]], F=[PRELOAD_F], F_static=[PRELOAD_STATIC],
                               R=0.0, b=0.0, omega=omega, eta=PRELOAD_ETA)


def ball(gamma: float) -> ic.ImpactOscillator:
    """Case (b) in the table's frame (``g = omega = 1``): ``y'' = -1 + Gamma cos(theta)``
    over the lower stop ``y = 0`` (the upper stop out of reach)."""
    return ic.ImpactOscillator(M=[[1.0]], K=[[0.0]], F=[gamma], F_static=[-1.0], R=0.0,
                               b=1e3, omega=1.0, eta=0.0, stops=Stops(b_low=0.0, R_low=0.0))


def damper(omega: float) -> ic.ImpactOscillator:
    """Case (c): the primary (1, spring 1, ``C = 2 eta K``) and the plastic ball in the
    clearance ``|x2 - x1| <= b``."""
    return ic.ImpactOscillator(M=np.diag([1.0, BALL_MASS]), K=np.diag([1.0, 0.0]),
                               F=[1.0, 0.0], R=0.0, b=GAP, omega=omega, eta=DAMPER_ETA,
                               stops=Stops(mass=2, relative_to=1, mirror=True))


def riding_start(osc: ic.ImpactOscillator) -> np.ndarray:
    """The ball on the upper wall and the pair on the held system's forced response at
    phase 0 (where the wall presses the ball): not the periodic motion, a start near it."""
    m, c, omega = osc.M[1, 1], osc.C[0, 0], osc.omega
    amplitude = 1.0 / (1.0 - (1.0 + m) * omega**2 + 1j * c * omega)
    x1, v1 = amplitude.real, (1j * omega * amplitude).real
    return np.array([x1, x1 + osc.b, v1, v1])


def simulated(case: str, value: float, periods: float):
    """The simulator's run of a case to its steady state: ``(osc, delta, result)``."""
    if case == "a":
        osc, state, delta = preloaded(value), [0.0, 0.0], 0.0
    elif case == "b":
        osc, state, delta = ball(value), [0.0, 0.0], -0.5 * math.pi
    else:
        osc = damper(value)
        state, delta = riding_start(osc), 0.0
    return osc, delta, ic.simulate(osc, state, delta, periods)


@functools.cache
def closed(case: str, value: float) -> cf.StickyMotion:
    """The closed form of a case."""
    if case == "a":
        return cf.preloaded_motion(value, F=PRELOAD_F, F_static=PRELOAD_STATIC,
                                   eta=PRELOAD_ETA)
    if case == "b":
        return cf.locked_ball_motion(value)
    return cf.riding_damper_motion(value, m=BALL_MASS, b=GAP, eta=DAMPER_ETA)


def apart(t: float, phase, omega: float, delta: float) -> float:
    """Time between `t` (of a run started at phase `delta`) and the closed form's `phase`,
    modulo a forcing period."""
    return abs(math.remainder(delta + omega * t - float(phase), 2 * math.pi)) / omega


def versus_simulator(motion: cf.StickyMotion, osc, delta: float, res, *, last: int) -> dict:
    """The last `last` sticking phases of `res` that end in a release, against `motion`:
    the largest differences (time) of the landings, releases, stick and flight times, of
    the state after the landing and of the pressing force there (relative); ``extra``: the
    impacts the simulator records from the first of them to its end besides the landings
    (each starts a sticking phase)."""
    omega = osc.omega
    held = [p for p in res.sticking if p.ended_by == "release"][-last:]
    out = dict.fromkeys(("landing", "release", "stick", "flight", "state", "pressing"), 0.0)
    out["extra"] = (int((res.impact_times >= held[0].start).sum())
                    - sum(p.start >= held[0].start for p in res.sticking))
    for p, after in zip(held, [*held[1:], None], strict=True):
        k = motion.pattern.index(p.stops.lower())
        out["landing"] = max(out["landing"], apart(p.start, motion.phases[k], omega, delta))
        out["release"] = max(out["release"], apart(p.end, motion.release_phases[k], omega,
                                                   delta))
        out["stick"] = max(out["stick"], abs(p.duration - float(motion.stick_times[k])))
        if after is not None:
            out["flight"] = max(out["flight"],
                                abs(after.start - p.end - float(motion.flight_times[k])))
        state = np.asarray(motion.floats("landing_states")[k])
        out["state"] = max(out["state"], float(np.abs(p.start_state - state).max()))
        pressing = float(motion.landing_pressing[k])
        out["pressing"] = max(out["pressing"], abs(p.forces[0, 0] - pressing) / pressing)
    return out


def shooting(case: str, value: float, res) -> ic.MultiImpactOrbit:
    """The package's motion: ``multi_impact_orbit`` seeded from the simulation `res`, with
    the lowercase (sticking) pattern of the impacts it is seeded from (``"u"``, ``"l"``, ``"lu"`` or
    ``"ul"``)."""
    osc = {"a": preloaded, "b": ball, "c": damper}[case](value)
    p = 2 if case == "c" else 1
    pattern = "".join(s.lower() for s in res.impact_stops[-(p + 1):-1])
    return ic.multi_impact_orbit(osc, 1, p, res, pattern=pattern)


def versus_shooting(motion: cf.StickyMotion, orbit) -> dict:
    """The largest differences of the shooting's motion from the closed form: phases,
    stick and flight times, release and landing states, impact speeds, smallest pressing
    forces; the nonzero multipliers; the largest modulus of the collapsed ones."""
    motion = motion.rotated(orbit.pattern)
    phases = np.array(motion.floats("phases"))
    out = {"phase": float(np.abs(np.remainder(orbit.phases - phases + np.pi, 2 * np.pi)
                                 - np.pi).max())}
    for key, mine in (("stick_times", "stick_times"), ("flight_times", "flight_times"),
                      ("release_states", "release_states"), ("states", "landing_states"),
                      ("impact_velocities", "impact_velocities"),
                      ("pressing_min", "pressing_min")):
        out[key] = float(np.abs(getattr(orbit, key) - np.array(motion.floats(mine))).max())
    mu = sorted(orbit.multipliers, key=lambda z: (-abs(z), z.imag))
    exact = sorted((complex(z) for z in motion.multipliers), key=lambda z: (-abs(z), z.imag))
    live = [k for k, z in enumerate(exact) if z != 0]
    out["multipliers"] = max((abs(mu[k] - exact[k]) for k in live), default=0.0)
    out["collapsed"] = max((abs(mu[k]) for k in range(len(mu)) if k not in live), default=0.0)
    out["error_estimate"] = orbit.error_estimate
    return out


def motion_table(case: str, values) -> list[str]:
    """The closed form's motions, impact by impact."""
    name = {"a": "omega", "b": "Gamma", "c": "omega"}[case]
    rows = [f"| {name} | impact | landing phase | landing speed | stick time | release phase "
            "| flight time | smallest pressing force | multipliers |",
            "|---|---|---|---|---|---|---|---|---|"]
    for value in values:
        motion = closed(case, value)
        mu = ", ".join(_complex(complex(z)) for z in motion.multipliers)
        for k, stop in enumerate(motion.pattern):
            rows.append(f"| {value if k == 0 else ''} | {k}: {stop} | "
                        f"{float(motion.phases[k]):.12f} | "
                        f"{float(motion.impact_velocities[k]):.12f} | "
                        f"{float(motion.stick_times[k]):.12f} | "
                        f"{float(motion.release_phases[k]):.12f} | "
                        f"{float(motion.flight_times[k]):.12f} | "
                        f"{float(motion.pressing_min[k]):.12f} | {mu if k == 0 else ''} |")
    return rows


def _complex(z: complex) -> str:
    return f"{z.real:.9g}" if z.imag == 0 else f"{z.real:.9g}{z.imag:+.9g}i"


def difference_table(case: str, values, periods: float, last: int) -> list[str]:
    """Closed form against the simulator and against the shooting, one row per value."""
    name = {"a": "omega", "b": "Gamma", "c": "omega"}[case]
    rows = [f"| {name} | simulator: landing, release (time) | stick, flight | state after "
            "landing | pressing (rel.) | extra impacts | shooting: phases | stick, flight "
            "times | release, landing states | speeds, pressing_min | multipliers "
            "(nonzero; collapsed) | shooting's error estimate |",
            "|---|---|---|---|---|---|---|---|---|---|---|---|"]
    for value in values:
        motion = closed(case, value)
        osc, delta, res = simulated(case, value, periods)
        d = versus_simulator(motion, osc, delta, res, last=last)
        s = versus_shooting(motion, shooting(case, value, res))
        rows.append(
            f"| {value} | {max(d['landing'], d['release']):.1e} | "
            f"{max(d['stick'], d['flight']):.1e} | {d['state']:.1e} | {d['pressing']:.1e} | "
            f"{d['extra']} | {s['phase']:.1e} | "
            f"{max(s['stick_times'], s['flight_times']):.1e} | "
            f"{max(s['release_states'], s['states']):.1e} | "
            f"{max(s['impact_velocities'], s['pressing_min']):.1e} | "
            f"{s['multipliers']:.1e}; {s['collapsed']:.1e} | {s['error_estimate']:.1e} |")
    return rows


def no_motion_rows() -> list[str]:
    """Where the closed forms say there is no period-1 sticky motion of the kind, and why."""
    rows = ["| case | value | closed form says |", "|---|---|---|"]
    for case, value in (("a", 0.3), ("b", 3.3)):
        try:
            closed(case, value)
            verdict = "a motion"
        except ValueError as exc:
            verdict = str(exc)
        rows.append(f"| ({case}) | {value} | {verdict} |")
    return rows


def simulated_multipliers(omega: float, h: float = 1e-6) -> tuple[np.ndarray, float]:
    """Case (c): the nonzero multipliers from the simulator alone, and its periodicity
    residual.

    The section is the middle of the ride on the upper wall (phase ``theta0``): there the
    ball is held (``s = b``, ``s' = 0``) and the state is ``(x1, x1')``. The state on the
    section comes from the closed form's landing on that wall, simulated half the ride
    on; one forcing period of the simulator from ``(x1, x1')`` and from states ``h``
    apart (central differences: truncation ``~h^2``, rounding ``~1e-16 / h``) gives the
    2 x 2 Jacobian of the period map on the section, whose eigenvalues are the motion's
    nonzero multipliers (the ride collapses ``s`` and ``s'``: the other two are zero).
    Returns the eigenvalues and ``|P(x) - x|`` at the closed form's state.
    """
    osc, motion = damper(omega), closed("c", omega)
    k = motion.pattern.index("u")
    half = float(motion.stick_times[k]) / 2
    theta0 = float(motion.phases[k]) + omega * half
    landing = np.asarray(motion.floats("landing_states")[k])
    period = 2 * math.pi / omega
    x0 = ic.simulate(osc, landing, float(motion.phases[k]), half / period).final_state

    def period_map(x1: float, v1: float) -> np.ndarray:
        state = np.array([x1, x1 + osc.b, v1, v1])
        end = ic.simulate(osc, state, theta0, 1.0).final_state
        return end[[0, 2]]

    base = np.array([x0[0], x0[2]])
    J = np.empty((2, 2))
    for j in range(2):
        e = np.zeros(2)
        e[j] = h
        J[:, j] = (period_map(*(base + e)) - period_map(*(base - e))) / (2 * h)
    residual = float(np.abs(period_map(*base) - base).max())
    return np.linalg.eigvals(J), residual


def multiplier_rows() -> list[str]:
    """Case (c): the closed form's multipliers (central differences of its return map at 30
    digits) against the simulator's finite differences (:func:`simulated_multipliers`)."""
    rows = ["| omega | nonzero multipliers (closed form) | shooting: difference | its "
            "collapsed pair | simulator's finite differences | difference | simulator's "
            "periodicity residual |", "|---|---|---|---|---|---|---|"]

    def order(values) -> list[complex]:
        return sorted((complex(z) for z in values), key=lambda z: (-abs(z), z.imag))

    for omega in DAMPER_OMEGAS:
        mu = order(closed("c", omega).multipliers)[:2]
        _, _, res = simulated("c", omega, 16.0)
        package = order(shooting("c", omega, res).multipliers)
        sim, residual = simulated_multipliers(omega)
        sim = order(sim)
        rows.append(f"| {omega} | {', '.join(map(_complex, mu))} | "
                    f"{max(abs(a - b) for a, b in zip(mu, package, strict=False)):.1e} | "
                    f"{max(abs(z) for z in package[2:]):.1e} | "
                    f"{', '.join(map(_complex, sim))} | "
                    f"{max(abs(a - b) for a, b in zip(mu, sim, strict=True)):.1e} | "
                    f"{residual:.1e} |")
    return rows


def _next_orbit(orbit, omega: float) -> ic.MultiImpactOrbit:
    """The shooting's motion at `omega` seeded by `orbit` (at a nearby omega) with its times
    scaled by the ratio of the frequencies and its phases kept."""
    scale = orbit.oscillator.omega / omega
    return ic.multi_impact_orbit(damper(omega), 1, orbit.p, {
        "delta": float(orbit.phases[0]), "flight_times": orbit.flight_times * scale,
        "stick_times": orbit.stick_times * scale, "states": orbit.states,
        "pattern": orbit.pattern}, pattern=orbit.pattern)


def omega_sweep(omegas=SWEEP_OMEGAS) -> list[dict]:
    """Case (c) followed in omega, point by point, by the closed form and by the shooting
    path solved alone at every omega (a natural-parameter sweep; the package's own branch
    is :func:`package_branch`); the differences at every point.

    Each closed form is seeded by the last (its velocity scaled by the ratio of the
    frequencies, then two periods of its map), each shooting by the last motion
    (:func:`_next_orbit`).
    """
    res = simulated("c", omegas[0], 16.0)[2]
    orbit = shooting("c", omegas[0], res)
    motion = closed("c", omegas[0])
    out = []
    for omega in omegas:
        if omega == motion.omega:
            out.append({"omega": omega, "motion": motion, "orbit": orbit,
                        **versus_shooting(motion, orbit)})
            continue
        theta, v1 = cf.release_guess(motion)
        motion = cf.riding_damper_motion(omega, m=BALL_MASS, b=GAP, eta=DAMPER_ETA,
                                         guess=(theta, v1 * omega / float(motion.omega)),
                                         iterations=2)
        orbit = _next_orbit(orbit, omega)
        out.append({"omega": omega, "motion": motion, "orbit": orbit,
                    **versus_shooting(motion, orbit)})
    return out


def end_rows(points: list[dict]) -> list[str]:
    """Where the riding motion ends: the closed form's end (:func:`closed_form.riding_end`)
    and the shooting's, the zero of its stick time (secant in omega on the shooting path,
    which goes on through the end with negative stick times, flagged non-physical)."""
    omega_end, _, _ = cf.riding_end(points[-1]["motion"], m=BALL_MASS, b=GAP,
                                    eta=DAMPER_ETA)
    omega_end = float(omega_end)
    orbit = points[-1]["orbit"]
    a, fa = orbit.oscillator.omega, orbit.stick_times[0]
    b = omega_end + 0.01
    past = _next_orbit(orbit, b)
    fb = past.stick_times[0]
    for _ in range(30):
        if abs(b - a) < 1e-14:
            break
        c = b - fb * (b - a) / (fb - fa)
        orbit = _next_orbit(orbit, c)
        a, fa, b, fb = b, fb, c, orbit.stick_times[0]
    rows = ["| | omega at the end | stick time there | shooting's verdict just past it |",
            "|---|---|---|---|"]
    rows.append(f"| closed form (landing = release, symmetric) | {omega_end:.15f} | 0 | |")
    rows.append(f"| shooting (secant on the stick time) | {b:.15f} | {fb:.1e} | "
                f"omega {omega_end + 0.01:.4f}: physical = {past.physical}, "
                f"{past.reason} |")
    rows.append(f"| difference | {abs(b - omega_end):.1e} | | |")
    return rows


def sweep_rows(points: list[dict]) -> list[str]:
    """The omega sweep as a table (every fifth point, and the last)."""
    rows = ["| omega | landing phases | stick time | flight time | largest multiplier | "
            "smallest pressing force | shooting - closed form: phases; times; states; "
            "multipliers |", "|---|---|---|---|---|---|---|"]
    for i, row in enumerate(points):
        if i % 5 and i != len(points) - 1:
            continue
        m = row["motion"]
        rows.append(
            f"| {row['omega']:.2f} | {m.pattern[0]} {float(m.phases[0]):.9f}, "
            f"{m.pattern[1]} {float(m.phases[1]):.9f} | {float(m.stick_times[0]):.9f} | "
            f"{float(m.flight_times[0]):.9f} | {abs(complex(m.multipliers[0])):.6f} | "
            f"{float(m.pressing_min[0]):.6f} | {row['phase']:.1e}; "
            f"{max(row['stick_times'], row['flight_times']):.1e}; "
            f"{max(row['release_states'], row['states']):.1e}; {row['multipliers']:.1e} |")
    return rows


def sweep_figure(points: list[dict], width: float = WIDTH) -> Figure:
    """The omega sweep of case (c): the landing phase on the lower wall and the stick time
    (in forcing periods) of the closed form, the shooting's points on top; the largest
    multiplier's modulus."""
    good = points
    omega = np.array([r["omega"] for r in good])
    fig, (ax_t, ax_m) = panel_figure(2, width, ncols=2, aspect=0.75 if width > 5 else 0.9)
    closed_stick = [float(r["motion"].stick_times[0]) * r["omega"] / (2 * math.pi)
                    for r in good]
    shoot_stick = [r["orbit"].stick_times[0] * r["omega"] / (2 * math.pi) for r in good]
    closed_flight = [float(r["motion"].flight_times[0]) * r["omega"] / (2 * math.pi)
                     for r in good]
    shoot_flight = [r["orbit"].flight_times[0] * r["omega"] / (2 * math.pi) for r in good]
    ax_t.plot(omega, closed_stick, "-", color="black", lw=1.0,
              label="ride on a wall (closed form)")
    ax_t.plot(omega, closed_flight, "--", color="black", lw=1.0,
              label="flight across (closed form)")
    ax_t.plot(omega, shoot_stick, "o", color="C0", ms=3.5, mfc="none",
              label="shooting (multi_impact_orbit, a lowercase pattern)")
    ax_t.plot(omega, shoot_flight, "o", color="C0", ms=3.5, mfc="none")
    ax_t.set_xlabel(r"$\omega$")
    ax_t.set_ylabel(r"$\tau\,\omega / 2\pi$")
    closed_mu = [abs(complex(r["motion"].multipliers[0])) for r in good]
    shoot_mu = [float(np.abs(r["orbit"].multipliers).max()) for r in good]
    ax_m.plot(omega, closed_mu, "-", color="black", lw=1.0)
    ax_m.plot(omega, shoot_mu, "o", color="C0", ms=3.5, mfc="none")
    ax_m.set_xlabel(r"$\omega$")
    ax_m.set_ylabel(r"largest $|\mu|$")
    fig.suptitle(rf"Impact damper with a plastic ball ($m = {BALL_MASS:g}$, $b = {GAP:g}$, "
                 rf"$\eta = {DAMPER_ETA:g}$): the motion riding each wall in $\omega$",
                 fontsize="medium")
    figure_legend(fig)
    fit_labels(fig)
    return fig


def cost_rows(rounds: int = 5, calls: int = 20) -> list[str]:
    """``multi_impact_orbit`` from a simulation: a motion with sticking phases against one
    with the same number of impacts and degrees of freedom and none, side by side in this
    process (interleaved rounds of `calls` solves each, the best round's mean)."""
    one = ic.ImpactOscillator(M=[[1.0]], K=[[1.0]], F=[1.0], R=0.8, b=0.1, omega=1.5,
                              eta=0.05)
    pair = ic.ImpactOscillator(M=np.diag([1.0, BALL_MASS]), K=np.diag([1.0, 0.0]),
                               F=[1.0, 0.0], R=0.8, b=1.0, omega=1.5, eta=0.05,
                               stops=Stops(mass=2, relative_to=1, mirror=True))
    jobs = {
        "(a) 'u', omega 1": (preloaded(1.0), 1, simulated("a", 1.0, 5.0)[2], "u"),
        "one mass 'U' (R 0.8, b 0.1, omega 1.5)":
            (one, 1, ic.simulate(one, [0.0, 0.0], 0.0, 200.0), "U"),
        "(c) 'lu', omega 0.5": (damper(0.5), 2, simulated("c", 0.5, 16.0)[2], "lu"),
        "impact damper 'UL' (R 0.8, b 1, omega 1.5)":
            (pair, 2, ic.simulate(pair, [0.0, 0.0, 0.0, 1.0], 0.0, 150.0), "UL"),
    }
    for osc, p, res, pattern in jobs.values():  # compile and warm up
        ic.multi_impact_orbit(osc, 1, p, res, pattern=pattern)
    best = dict.fromkeys(jobs, math.inf)
    for _ in range(rounds):
        for name, (osc, p, res, pattern) in jobs.items():
            start = time.perf_counter()
            for _ in range(calls):
                ic.multi_impact_orbit(osc, 1, p, res, pattern=pattern)
            best[name] = min(best[name], (time.perf_counter() - start) / calls)
    names = list(jobs)
    rows = ["| motion | n, p | ms per solve (best of 5) | sticking / plain |", "|---|---|---|---|"]
    for sticky, plain in ((names[0], names[1]), (names[2], names[3])):
        n, p = jobs[sticky][0].n, jobs[sticky][1]
        rows.append(f"| {sticky} | {n}, {p} | {best[sticky] * 1e3:.2f} | "
                    f"{best[sticky] / best[plain]:.1f} |")
        rows.append(f"| {plain} | {n}, {p} | {best[plain] * 1e3:.2f} | |")
    return rows


def package_branch(bounds=(0.2, 2.6)):
    """Case (c) continued in omega by the package (``ic.continuation`` of the motion
    solved from the simulation at ``bounds[0]``; a sticky branch detects the points that
    end it, SE the end of a ride, RG release grazing and SO the onset of sticking, as
    special points): the branch dataset and its wall time."""
    res = simulated("c", bounds[0], 16.0)[2]
    orbit = shooting("c", bounds[0], res)
    start = time.perf_counter()
    ds = ic.continuation(orbit, parameter="omega", bounds=bounds)
    return ds, time.perf_counter() - start


def branch_rows(ds, every: int = 10) -> list[str]:
    """Points of the package's branch against the closed form at their omega (every
    `every`-th physical point and the last physical one; the closed form seeded by the
    point's release from the upper wall, solved to 30 digits on its own)."""
    pattern = ds.attrs["pattern"]
    k = pattern.index("u")
    physical = np.flatnonzero(ds.physical.values)
    picks = sorted({*physical[::every].tolist(), int(physical[-1])})
    rows = ["| point | omega | stick time (closed form) | phases | stick, flight times | "
            "release states | largest multiplier |", "|---|---|---|---|---|---|---|"]
    for i in picks:
        omega = float(ds.omega[i])
        theta_r = float(ds.delta_k[i, k]) + omega * float(ds.stick_time_k[i, k])
        motion = cf.riding_damper_motion(
            omega, m=BALL_MASS, b=GAP, eta=DAMPER_ETA,
            guess=(theta_r, float(ds.release_state_k[i, k, 2])), iterations=0)
        motion = motion.rotated(pattern)
        phases = np.array(motion.floats("phases"))
        d_phase = np.abs(np.remainder(ds.delta_k[i].values - phases + np.pi, 2 * np.pi)
                         - np.pi).max()
        d_times = max(np.abs(ds.stick_time_k[i].values
                             - np.array(motion.floats("stick_times"))).max(),
                      np.abs(ds.flight_time_k[i].values
                             - np.array(motion.floats("flight_times"))).max())
        d_release = np.abs(ds.release_state_k[i].values
                           - np.array(motion.floats("release_states"))).max()
        d_mu = abs(float(ds.spectral_radius[i]) - abs(complex(motion.multipliers[0])))
        rows.append(f"| {i} | {omega:.6f} | {float(motion.stick_times[0]):.9f} | "
                    f"{d_phase:.1e} | {d_times:.1e} | {d_release:.1e} | {d_mu:.1e} |")
    return rows


def branch_end_rows(ds, omega_end: float) -> list[str]:
    """Where the package's branch stops being physical, against the closed form's end."""
    physical = ds.physical.values
    flip = int(np.flatnonzero(np.diff(physical.astype(int)))[0])
    a, b = float(ds.omega[flip]), float(ds.omega[flip + 1])
    sa, sb = float(ds.stick_time_k[flip, 0]), float(ds.stick_time_k[flip + 1, 0])
    estimate = a - sa * (b - a) / (sb - sa)
    specials = [str(v) for v in ds.special_label.values] if "special_label" in ds else []
    located = []
    if specials:
        located = [f"| special point {label} ({status}, precision {precision:.1e}) | "
                   f"{omega:.15f} |" for label, omega, precision, status in zip(
                       ds.special_label.values, ds.special_omega.values,
                       ds.special_precision.values, ds.special_status.values, strict=True)]
    return ["| | omega |", "|---|---|", *located,
            f"| last physical point (stick time {sa:.3g}) | {a:.9f} |",
            f"| first non-physical point (stick time {sb:.3g}) | {b:.9f} |",
            f"| zero of the stick time, linear between them | {estimate:.9f} |",
            f"| closed form's end | {omega_end:.9f} |",
            f"| special points the branch reports | {', '.join(specials) or 'none'} |"]


def riding_figure(omega: float = 0.2, width: float = WIDTH) -> Figure:
    """One period of case (c): the simulator from the closed form's landing on a wall, the
    ball in the clearance ``s = x2 - x1`` and the primary ``x1``, each ride shaded, the
    walls' pressing forces under them (:func:`impactcont.plots.series.time_history`); the
    closed form's landings and releases marked."""
    osc = damper(omega)
    motion = closed("c", omega)
    theta0 = float(motion.phases[0])
    res = ic.simulate(osc, np.asarray(motion.floats("landing_states")[0]), theta0, 1.0,
                      trajectory=True, samples_per_period=400)
    # time in forcing periods, counted from phase 0 before the landing
    offset = theta0 / (2 * math.pi)
    scale = omega / (2 * math.pi)
    t = res.t * scale + offset
    s = res.X[:, 1] - res.X[:, 0]
    walls = [Series([offset, offset + 1.0], [y, y], "walls $s = \\pm b$", color="0.4",
                    linestyle="--", linewidth=0.8) for y in (osc.b, -osc.b)]
    marks = []
    for key, label, marker in (("phases", "landing (closed form)", "v"),
                               ("release_phases", "release (closed form)", "^")):
        times = [offset + ((float(ph) - theta0) % (2 * math.pi)) / (2 * math.pi)
                 for ph in getattr(motion, key)]
        heights = [osc.b if stop == "u" else -osc.b for stop in motion.pattern]
        marks.append(Series(times, heights, label, color="black", linestyle="none",
                            marker=marker))
    events = res.sticking_arrays()
    events = {**events, "sticking_start": np.asarray(events["sticking_start"]) + offset / scale,
              "sticking_end": np.asarray(events["sticking_end"]) + offset / scale,
              "force_time": np.asarray(events["force_time"]) + offset / scale,
              "chatter_time": np.asarray(events["chatter_time"]) + offset / scale}
    fig, (ax_s, ax_p) = panel_figure(2, width, ncols=1, aspect=0.3 if width > 5 else 0.5)
    handles = time_history(
        ax_s, ax_p, [Series(t, s, "ball in the clearance, $s = x_2 - x_1$", color="black",
                            linestyle="-", linewidth=0.9),
                     Series(t, res.X[:, 0], "primary, $x_1$", color="C0", linestyle="-.",
                            linewidth=0.9), *walls, *marks],
        events, time_scale=scale, xlabel="$t\\,\\omega / 2\\pi$",
        ylabel="$s$, $x_1$", force_label="pressing force $p$",
        force_entry="force of wall {stop}")
    ax_s.set_xlim(offset, offset + 1.0)
    fig.suptitle(rf"Impact damper with a plastic ball at $\omega = {omega:g}$, "
                 rf"$m = {BALL_MASS:g}$, $b = {GAP:g}$, $\eta = {DAMPER_ETA:g}$: "
                 "one period of the motion riding each wall", fontsize="medium")
    figure_legend(fig, handles)
    fit_labels(fig)
    markers_whole(ax_s)
    return fig


def draw_figures(width: float = WIDTH, points: list[dict] | None = None) -> None:
    """The study's figures, in ``figures/``."""
    FIGURES.mkdir(exist_ok=True)
    riding_figure(0.2, width).savefig(FIGURES / "riding_period.png", dpi=150)
    sweep_figure(omega_sweep() if points is None else points, width).savefig(
        FIGURES / "riding_in_omega.png", dpi=150)


if __name__ == "__main__":
    logging.basicConfig(level=logging.INFO, format="%(message)s")
    logging.getLogger("impactcont").setLevel(logging.WARNING)
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--figures-only", action="store_true")
    parser.add_argument("--cost", action="store_true",
                        help="only the cost table of a Newton solve (sticking against plain; "
                             "a branch point's: branch_cost.py)")
    args = parser.parse_args()
    points = None
    if args.cost:
        log.info("\n".join(cost_rows()))
        sys.exit(0)
    if not args.figures_only:
        for title, table in (
                ("(a) Preloaded oscillator", lambda: motion_table("a", PRELOAD_OMEGAS)),
                ("(a) differences", lambda: difference_table("a", PRELOAD_OMEGAS, 5.0, 3)),
                ("(b) Completely inelastic ball (Luck & Mehta 1993)",
                 lambda: motion_table("b", GAMMAS)),
                ("(b) differences", lambda: difference_table("b", GAMMAS, 5.0, 3)),
                ("(c) Impact damper riding each wall",
                 lambda: motion_table("c", DAMPER_OMEGAS)),
                ("(c) differences", lambda: difference_table("c", DAMPER_OMEGAS, 16.0, 4)),
                ("Where there is no such motion", no_motion_rows),
                ("(c) Multipliers", multiplier_rows),
                ("Cost of a Newton solve", cost_rows)):
            log.info("\n## %s\n\n%s", title, "\n".join(table()))
        points = omega_sweep()
        log.info("\n## (c) in omega\n\n%s", "\n".join(sweep_rows(points)))
        log.info("\n## (c) where it ends\n\n%s", "\n".join(end_rows(points)))
        ds, seconds = package_branch()
        log.info("\n## (c) continued by the package (%d points, %.1f s)\n\n%s\n\n%s",
                 ds.sizes["point"], seconds, "\n".join(branch_rows(ds)),
                 "\n".join(branch_end_rows(ds, float(cf.riding_end(
                     points[-1]["motion"], m=BALL_MASS, b=GAP, eta=DAMPER_ETA)[0]))))
    draw_figures(points=points)
