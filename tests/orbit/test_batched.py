"""The batched closed form (:func:`impactcont.orbit.batched.batched_orbits`) over a grid.

Independent witness: :func:`impactcont.periodic_orbits` point by point (the roots of eq. (15)
at one ``(omega, b)``, G built from the state and its LAPACK multipliers), on the modal path
(proportional damping) and on the first-order path (a general damping matrix), through
the double root at the edge of the existence region and the velocity polish far above
the lowest natural frequency.
"""

from __future__ import annotations

import math
import warnings

import numpy as np
import pytest

import impactcont as ic
from impactcont.errors import IllConditionedWarning, ParameterError
from impactcont.model.stops import Stops
from impactcont.orbit.batched import batched_orbits
from tests import reference_mp as ref

K2 = [[1.0, -1.0], [-1.0, 2.0]]


def _wrap(x):
    return math.atan2(math.sin(x), math.cos(x))


def _check_grid(osc: ic.ImpactOscillator, N: int, omega, b) -> int:
    """Every cell of the batched map against ``periodic_orbits`` at the same point;
    returns the number of motions compared."""
    out = batched_orbits(osc, N, omega, b)
    compared = 0
    for i, w in enumerate(omega):
        for j, bj in enumerate(b):
            orbits = ic.periodic_orbits(osc.replace(omega=float(w), b=float(bj)), N)
            assert bool(out["exists"][i, j]) == bool(orbits), (w, bj)
            if not orbits:
                assert np.all(np.isnan(out["delta"][i, j]))
                assert not out["physical"][i, j].any() and not out["stable"][i, j].any()
                continue
            for orbit in orbits:
                k = int(np.argmin([abs(_wrap(d - orbit.delta)) for d in out["delta"][i, j]]))
                assert abs(_wrap(out["delta"][i, j, k] - orbit.delta)) < 1e-9
                scale = max(1.0, abs(orbit.impact_velocity))
                assert out["impact_velocity"][i, j, k] == pytest.approx(
                    orbit.impact_velocity, rel=0.0, abs=1e-9 * scale)
                if math.isfinite(orbit.gap_min):
                    assert abs(out["gap_min"][i, j, k] - orbit.gap_min) <= 1e-9
                else:
                    assert out["gap_min"][i, j, k] == math.inf
                assert out["spectral_radius"][i, j, k] == pytest.approx(
                    orbit.spectral_radius, rel=1e-7, abs=1e-9)
                assert bool(out["physical"][i, j, k]) == orbit.physical
                assert bool(out["stable"][i, j, k]) == orbit.stable
                compared += 1
    return compared


def test_modal_grid_is_periodic_orbits_point_by_point(paper):
    omega = np.linspace(0.6, 2.6, 9)
    b = np.array([-0.4, 0.0, 0.3, 0.6, 1.5, 4.0])  # b = 4: beyond |c, s| at some omega
    assert _check_grid(paper, 1, omega, b) > 60


def test_modal_grid_of_n2_motions(paper):
    assert _check_grid(paper, 2, np.linspace(1.5, 3.5, 5), np.array([0.0, 0.2])) > 10


def test_first_order_grid_is_periodic_orbits_point_by_point():
    """A general (non-proportional) damping matrix: the first-order path."""
    osc = ic.ImpactOscillator(M=np.eye(2), K=K2, C=[[0.3, -0.1], [-0.1, 0.05]], F=[1.0, 0.0],
                              R=0.7, b=0.2, omega=1.0)
    assert osc.general
    assert _check_grid(osc, 1, np.linspace(0.6, 2.4, 5), np.array([-0.2, 0.2, 0.5])) > 15


@pytest.mark.parametrize("omega", [300.0, 3000.0])
def test_far_above_the_lowest_frequency_the_velocity_keeps_its_digits(paper, omega):
    """Far above the natural frequencies the first form of the impact velocity cancels
    (relative errors 2e-11 at omega = 300, 3e-9 at 3000 on the paper's system): the grid
    takes its second exact form, as ``periodic_orbits`` does, and keeps the digits of the
    50-digit reference."""
    b = np.array([-1e-4, 0.0])
    assert _check_grid(paper, 1, np.array([omega]), b) == 4
    system = ref.MPSystem(M=np.eye(2), K=K2, F=[1.0, 0.0], R=0.6, b=0.0, beta=0.2)
    expected = ref.to_float(ref.closed_form(system, omega, 1, multipliers=False, gap=False))
    out = batched_orbits(paper, 1, [omega], [0.0])
    for orbit in expected["orbits"]:
        k = int(np.argmin([abs(_wrap(d - orbit["delta"])) for d in out["delta"][0, 0]]))
        assert out["impact_velocity"][0, 0, k] == pytest.approx(orbit["impact_velocity"],
                                                                rel=1e-12, abs=0.0)


def test_amplitude_squared_is_c2_plus_s2(paper):
    """``c^2 + s^2`` (eq. 15): the motion exists exactly where ``b^2 <= c^2 + s^2``."""
    omega = np.linspace(0.6, 2.6, 9)
    b = np.linspace(0.0, 3.0, 13)
    out = batched_orbits(paper, 1, omega, b)
    r2 = out["amplitude_squared"]
    for i, w in enumerate(omega):
        assert r2[i] == pytest.approx(ic.amplitude_squared(paper.replace(omega=float(w)), 1),
                                      rel=1e-12)
        expected = b ** 2 <= r2[i]
        np.testing.assert_array_equal(out["exists"][i], expected)


def test_the_kernel_omits_the_spectral_radius_when_asked(paper):
    out = batched_orbits(paper, 1, [1.0, 1.5], [0.3], spectral_radius=False)
    assert np.all(np.isnan(out["spectral_radius"]))
    full = batched_orbits(paper, 1, [1.0, 1.5], [0.3])
    np.testing.assert_array_equal(out["stable"], full["stable"])


def test_an_ill_conditioned_frequency_is_named_once(paper):
    """omega at an undamped mode's natural frequency: eq. (12) is ill-conditioned."""
    osc = paper.replace(eta=0.0)
    w1 = math.sqrt((3.0 - math.sqrt(5.0)) / 2.0)  # eigenvalue of K2
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        batched_orbits(osc, 1, [0.9, w1 * (1 + 1e-12)], [0.1])
    named = [w for w in caught if issubclass(w.category, IllConditionedWarning)]
    assert len(named) == 1
    assert "ill-conditioned" in str(named[0].message)


def test_a_system_outside_the_paper_form_is_refused(paper):
    osc = paper.replace(stops=Stops(mirror=True))
    with pytest.raises(ParameterError, match="N-1 stability map"):
        batched_orbits(osc, 1, [1.0], [0.3])
