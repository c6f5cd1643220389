"""Free modes that the damping leaves undamped (issue 30, item 5), witnessed across modules.

A damping matrix C that leaves a free (rigid-body) mode of K undamped was refused on the
first-order path ("unless C damps every free mode"), so the usual impact damper (a dashpot
on the primary, none on the free ball) could not be built with a non-proportional C. The
first-order flow now carries the mode's Jordan chain (its polynomial part). Witnesses:

- the modal path, exact for an undamped free mode already, gives the same motion as the
  first-order path for the same proportional C (orbit, G, multipliers to 1e-12);
- the event-driven simulator (which shares no code with the shooting path) repeats the
  motions of a non-proportional C (a dashpot on mass 1 of a two-mass primary, a free ball
  in a cavity of mass 2), for R = 0.8, 0 (plastic) and 1 (elastic), a ball under gravity
  and two free balls: impact times and velocities to 1e-8;
- G against central differences of the simulator's impact map.
"""

from __future__ import annotations

import math
import warnings

import numpy as np
import pytest

import impactcont as ic
from impactcont.model.stops import Stop, Stops
from impactcont.orbit.multi_impact import multi_impact_orbit

# a two-mass primary on springs with a dashpot on mass 1 only, a ball of mass 0.2 in a
# cavity of mass 2 (s = x3 - x2 in [-1, 1]): C is not alpha M + beta K, the ball undamped
_PRIMARY = dict(M=np.diag([1.0, 0.5, 0.2]),
                K=[[2.0, -1.0, 0.0], [-1.0, 1.0, 0.0], [0.0, 0.0, 0.0]],
                C=np.diag([0.1, 0.0, 0.0]), F=[1.0, 0.0, 0.0], R=0.8, b=1.0, omega=2.0,
                stops=Stops(mass=3, relative_to=2, mirror=True))


def _damper(**changes) -> ic.ImpactOscillator:
    return ic.ImpactOscillator(**{**_PRIMARY, **changes})


@pytest.fixture(scope="module")
def damper_orbit():
    """The stable symmetric two-impact motion of the damper, seeded by a simulation."""
    osc = _damper()
    assert osc.general and osc.first_order.polynomial
    res = ic.simulate(osc, np.array([0.0, 0.0, 0.0, 0.0, 0.0, 1.0]), 0.0, 40.0)
    return multi_impact_orbit(osc, 1, 2, res)


def _resimulated(orbit, periods: int = 3):
    """Impact times, velocities and stops of the simulator from the motion's impact 0."""
    osc = orbit.oscillator
    res = ic.simulate(osc, orbit.states[0], float(orbit.phases[0]), float(periods))
    p = orbit.p
    times = np.cumsum(np.tile(orbit.flight_times, periods))
    n = min(res.impact_times.size, times.size)
    assert n == times.size, (res.impact_stops, orbit.pattern)
    expected = (orbit.pattern * (periods + 1))[1:p * periods + 1]
    assert res.impact_stops[:n] == expected
    np.testing.assert_allclose(res.impact_times[:n], times, rtol=0, atol=1e-8)
    velocities = np.roll(np.tile(orbit.impact_velocities, periods), -1)
    np.testing.assert_allclose(res.impact_velocities[:n], velocities, rtol=1e-8, atol=1e-10)
    return res


def test_modal_and_first_order_paths_give_the_same_motion():
    """Witness (a): an undamped free ball with a proportional C (beta K, a dashpot on the
    primary of K = diag(1, 0)) on the modal path (eta) and the same C as a matrix on the
    first-order path (refused before): the same motion, G and multipliers to rounding."""
    base = dict(M=np.diag([1.0, 0.2]), K=np.diag([1.0, 0.0]), F=[1.0, 0.0], R=0.8, b=1.0,
                omega=1.5, stops=Stops(mass=2, relative_to=1, mirror=True))
    modal = ic.ImpactOscillator(**base, eta=0.05)
    general = ic.ImpactOscillator(**base, C=modal.C)
    assert not modal.general and general.general
    res = ic.simulate(modal, np.array([0.0, 0.0, 0.0, 1.0]), 0.0, 40.0)
    ref = multi_impact_orbit(modal, 1, 2, res)
    got = multi_impact_orbit(general, 1, 2, ref)
    assert ref.physical and ref.stable and got.physical and got.stable
    assert got.pattern == ref.pattern
    scale = max(1.0, np.abs(ref.states).max())
    np.testing.assert_allclose(got.states, ref.states, rtol=0, atol=1e-12 * scale)
    np.testing.assert_allclose(got.flight_times, ref.flight_times, rtol=1e-12)
    np.testing.assert_allclose(got.G, ref.G, rtol=0, atol=1e-12 * np.abs(ref.G).max())
    np.testing.assert_allclose(np.sort_complex(got.multipliers),
                               np.sort_complex(ref.multipliers), rtol=0, atol=1e-12)
    np.testing.assert_allclose(got.flight_gap_min, ref.flight_gap_min, rtol=0, atol=1e-10)


@pytest.mark.parametrize("R", [0.8, 0.0, 1.0])
def test_simulator_repeats_the_motion_of_a_non_proportional_damper(damper_orbit, R):
    """Witness (b): the motion found by shooting (any C, the ball undamped), continued in R
    to a plastic (R = 0: one multiplier 0) and an elastic ball (R = 1: the primary's damper
    still dissipates; this motion is unstable there), is repeated by the simulator from its
    impact state over three periods."""
    orbit = damper_orbit
    for r in np.linspace(0.8, R, 5)[1:] if R != 0.8 else []:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", ic.UnresolvedMotionWarning)
            orbit = multi_impact_orbit(orbit.oscillator.replace(R=float(r)), 1, 2, orbit)
    assert orbit.physical and orbit.residual < 1e-12
    assert orbit.stable == (R < 1.0)
    if R == 0.0:
        assert np.abs(orbit.multipliers).min() < 1e-12  # the plastic impact collapses s'
    _resimulated(orbit)


def test_G_is_the_derivative_of_the_simulated_impact_map(damper_orbit):
    """Witness (c): G of eq. (25) with the polynomial part against central differences of
    the simulator's map from impact 0 to impact p on the section ``[z, theta]`` (z = X
    without x3; x3 = x2 + c on the section)."""
    osc, orbit = damper_orbit.oscillator, damper_orbit
    X0, th0, p = orbit.states[0], float(orbit.phases[0]), orbit.p
    j, k, m = 2, 1, 2 * osc.n  # the pivot x3, the other mass of the pair x2
    rest = np.delete(np.arange(m), j)
    h = 1e-6
    fd = np.empty((m, m))
    for c in range(m):
        out = []
        for sgn in (1.0, -1.0):
            X, th = X0.copy(), th0
            if c < m - 1:
                X[rest[c]] += sgn * h
                X[j] = X0[j] + (X[k] - X0[k])  # stay on the section s = x3 - x2 = c_0
            else:
                th += sgn * h
            res = ic.simulate(osc, X, th, 1.5)
            out.append(np.append(res.impact_states[p - 1][rest], res.impact_phases[p - 1]))
        d = out[0] - out[1]
        d[-1] = math.remainder(d[-1], 2 * math.pi)
        fd[:, c] = d / (2 * h)
    np.testing.assert_allclose(orbit.G, fd, rtol=0, atol=1e-6 * max(1.0, np.abs(fd).max()))


def test_ball_under_gravity_on_the_damped_primary():
    """A constant force on the undamped free mode (its g t^2 / 2, the flow's N d t^2 / 2):
    the motion found by shooting is repeated by the simulator."""
    osc = _damper(F_static=[0.0, 0.0, -0.02])
    res = ic.simulate(osc, np.array([0.0, 0.0, 0.0, 0.0, 0.0, 1.0]), 0.0, 40.0)
    orbit = multi_impact_orbit(osc, 1, 2, res)
    assert orbit.physical and orbit.stable
    _resimulated(orbit)


def test_two_free_balls_with_a_dashpot_on_the_primary():
    """Two undamped free masses (two Jordan chains), each in its own cavity of the primary:
    a stable four-impact motion found by shooting is repeated by the simulator."""
    osc = ic.ImpactOscillator(
        M=np.diag([1.0, 0.3, 0.2]), K=np.diag([1.0, 0.0, 0.0]), C=np.diag([0.05, 0.0, 0.0]),
        F=[1.0, 0.0, 0.0], R=0.8, b=0.4, omega=3.0,
        stops=Stops(mass=2, relative_to=1, mirror=True,
                    extra=(Stop("A", mass=3, gap=0.5, restitution=0.8, relative_to=1),
                           Stop("B", mass=3, gap=0.5, restitution=0.8, side=-1,
                                relative_to=1))))
    assert int(np.sum(osc.first_order.generalized)) == 2
    # its first ~100 periods are a chaotic transient (rounding decides where it goes):
    # the seed is taken long after it, on the stable four-impact motion
    res = ic.simulate(osc, np.array([0.0, 0.0, 0.0, 0.0, 1.0, -1.0]), 0.0, 300.0)
    orbit = multi_impact_orbit(osc, 1, 4, res)
    assert orbit.physical and orbit.stable and sorted(orbit.pattern) == ["A", "B", "L", "U"]
    _resimulated(orbit)


def test_the_docs_example_of_a_dashpot_on_the_primary_only_runs():
    """The example of docs/machines.md (refused before: 'unless C damps every free mode')
    runs, with the imports of the page's first block, and its motion repeats."""
    import re
    from pathlib import Path

    page = (Path(__file__).resolve().parents[2] / "docs" / "machines.md").read_text()
    blocks = re.findall(r"```python\n(.*?)```", page, flags=re.S)
    example = next(b for b in blocks if "a dashpot on the primary only" in b)
    names: dict = {}
    exec(compile(blocks[0].split("\nosc = ")[0], "machines.md", "exec"), names)  # imports
    exec(compile(example, "machines.md", "exec"), names)
    orbit, again = names["orbit"], names["again"]
    assert orbit.physical and orbit.stable
    assert again.impact_stops == (orbit.pattern * 4)[1:7]
    np.testing.assert_allclose(again.impact_times, np.cumsum(np.tile(orbit.flight_times, 3)),
                               rtol=0, atol=1e-8)


def test_map_cells_are_the_motions_solved_one_by_one(damper_orbit):
    """The map sweep (its own compiled loop over the first-order flights and the contact
    search) on the non-proportional damper: each cell found is the motion
    multi_impact_orbit solves there, its spectral radius and flight gap the same."""
    bs = np.array([0.9, 1.0, 1.1])
    mp = ic.multi_impact_map(damper_orbit, ("omega", "b"),
                             {"omega": np.array([2.0, 2.2]), "b": bs})
    assert bool(mp["found"].all())
    for omega in (2.0, 2.2):
        for b in bs:
            cell = mp.sel(omega=omega, b=b)
            direct = multi_impact_orbit(damper_orbit.oscillator.replace(omega=omega, b=float(b)),
                                        1, 2, damper_orbit)
            assert float(cell["spectral_radius"]) == pytest.approx(
                np.abs(direct.multipliers).max(), rel=1e-10)
            assert float(cell["gap_min"]) == pytest.approx(direct.gap_min, rel=0, abs=1e-9)
            assert bool(cell["physical"]) == direct.physical
