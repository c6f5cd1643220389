"""Forcing on several masses with their own phases: complex F.

The forcing is ``Re(F e^{i(omega t + delta)})``: a real F keeps the paper's meaning
``F cos(omega t + delta)`` exactly, and ``F_j = |F_j| e^{i phi_j}`` forces mass j with
``|F_j| cos(omega t + delta + phi_j)``. Witnesses:

- superposition: ``F = F_a + i F_b`` is ``F_a`` at phase delta plus ``F_b`` at phase
  ``delta + pi/2``, each computed by the proportional modal kernel (real forces);
- a common phase ``F e^{i phi}`` is a shift of the impact phase by ``-phi``;
- the event-driven simulator, which integrates the phased forcing itself;
- the modal forced amplitudes against the physical dynamic-stiffness solve.
"""

from __future__ import annotations

import cmath
import math

import numpy as np
import pytest

import impactcont as ic
from impactcont.errors import ParameterError
from impactcont.model.modal import forced_coefficients
from impactcont.orbit import general
from tests.orbit.test_general import assert_simulation_repeats

K2 = np.array([[1.0, -1.0], [-1.0, 2.0]])
FA = np.array([1.0, 0.3])
FB = np.array([0.2, -0.5])


def _osc(F, **params) -> ic.ImpactOscillator:
    base = {"M": np.diag([1.0, 1.3]), "K": K2, "R": 0.6, "b": 0.2, "omega": 1.2, "eta": 0.08}
    base.update(params)
    return ic.ImpactOscillator(F=F, **base)


def _wrap(x: float) -> float:
    return math.remainder(x, 2.0 * math.pi)


def test_real_F_keeps_the_modal_path_and_its_meaning():
    real = _osc(FA)
    as_complex = _osc(FA + 0j)
    assert not real.general and not as_complex.general
    assert as_complex.F.dtype == float
    for a, b in zip(ic.periodic_orbits(real, 1), ic.periodic_orbits(as_complex, 1), strict=True):
        assert a.delta == b.delta
        np.testing.assert_array_equal(a.state, b.state)


@pytest.mark.parametrize("N", [1, 2])
def test_complex_F_is_the_superposition_of_its_real_and_imaginary_parts(N):
    osc = _osc(FA + 1j * FB)
    assert osc.general and not osc.general_damping
    osc_a, osc_b = _osc(FA), _osc(FB)
    orbits = ic.periodic_orbits(osc, N)
    assert len(orbits) == 2
    for orbit in orbits:
        # eq. (13) is linear in the forcing:
        # S(F) cs(delta) = S(F_a) cs(delta) + S(F_b) cs(delta + pi/2), with the states of the
        # modal kernel at those phases (whether or not they solve eq. 14)
        X_a = ic.orbit.periodic.orbit_at_phase(osc_a, N, orbit.delta, check=False).state
        X_b = ic.orbit.periodic.orbit_at_phase(osc_b, N, orbit.delta + math.pi / 2,
                                               check=False).state
        np.testing.assert_allclose(orbit.state, X_a + X_b, rtol=0,
                                   atol=1e-12 * np.abs(orbit.state).max())
        assert orbit.state[0] == pytest.approx(osc.b, abs=1e-12)
    # the flow from any state: X(t; X0, F) = X(t; X0, F_a, delta) + X(t; 0, F_b, delta + pi/2)
    X0 = np.array([0.1, -0.2, 0.3, 0.05])
    t = np.array([0.0, 0.7, 4.0])
    expected = (ic.Flow(osc_a).state(t, X0, 0.4)
                + ic.Flow(osc_b).state(t, np.zeros(4), 0.4 + math.pi / 2))
    np.testing.assert_allclose(ic.Flow(osc).state(t, X0, 0.4), expected, rtol=0, atol=1e-13)


@pytest.mark.parametrize("damping", [{"eta": 0.08}, {"eta": None, "C": [[0.3, 0.0], [0.0, 0.0]]}])
def test_a_common_phase_shifts_the_impact_phase(damping):
    F = FA + 1j * FB
    phi = 0.9
    base = _osc(F, **damping)
    shifted = _osc(F * cmath.exp(1j * phi), **damping)
    for a, b in zip(ic.periodic_orbits(base, 1), ic.periodic_orbits(shifted, 1), strict=True):
        assert _wrap(b.delta - (a.delta - phi)) == pytest.approx(0.0, abs=1e-12)
        np.testing.assert_allclose(b.state, a.state, rtol=0, atol=1e-12)
        assert b.impact_velocity == pytest.approx(a.impact_velocity, rel=1e-12)
        np.testing.assert_allclose(b.G, a.G, rtol=0, atol=1e-11 * np.abs(a.G).max())
        assert b.gap_min == pytest.approx(a.gap_min, abs=1e-12)


def test_a_real_F_rotated_by_a_common_phase_matches_the_modal_path():
    """F e^{i phi} with real F: the first-order path against the modal kernel at delta + phi."""
    phi = -1.3
    real = _osc(FA)
    rotated = _osc(FA * cmath.exp(1j * phi))
    assert rotated.general
    for a, b in zip(ic.periodic_orbits(real, 1), ic.periodic_orbits(rotated, 1), strict=True):
        assert _wrap(b.delta + phi - a.delta) == pytest.approx(0.0, abs=1e-12)
        np.testing.assert_allclose(b.state, a.state, rtol=0, atol=1e-12)
        np.testing.assert_allclose(b.G, a.G, rtol=0, atol=1e-12 * np.abs(a.G).max())
        np.testing.assert_allclose(np.sort_complex(b.multipliers), np.sort_complex(a.multipliers),
                                   atol=1e-12)


def test_simulator_honours_the_phases():
    osc = _osc(FA + 1j * FB, b=0.1, omega=1.0)
    orbit = next(o for o in ic.periodic_orbits(osc, 1) if o.physical)
    assert_simulation_repeats(osc, orbit)
    # ignoring the phases (|F| in phase) gives another motion: the simulator sees the difference
    wrong = ic.simulate(_osc(np.abs(FA + 1j * FB), b=0.1, omega=1.0), orbit.state, orbit.delta,
                        1.5)
    assert abs(wrong.impact_times[0] - orbit.period) > 1e-3


def test_forced_coefficients_honour_complex_modal_forces():
    osc = _osc(FA)
    modes = osc.modes
    F = FA + 1j * FB
    f = modes.u.T @ F
    g, b = forced_coefficients(modes.natural_frequencies, modes.decay_rates, f, osc.omega)
    # physical steady response x = Re(x_hat e^{i theta}) with (K - w^2 M + i w C) x_hat = F
    x_hat = np.linalg.solve(osc.K - osc.omega**2 * osc.M + 1j * osc.omega * osc.C, F)
    theta = np.linspace(0.0, 6.0, 7)
    y = g[None, :] * np.cos(theta)[:, None] + b[None, :] * np.sin(theta)[:, None]
    np.testing.assert_allclose(y @ modes.u.T, (x_hat[None, :] * np.exp(1j * theta)[:, None]).real,
                               rtol=0, atol=1e-14)


def test_F0_is_the_largest_modulus_and_scales_keeping_phases():
    F = FA + 1j * FB
    osc = _osc(F)
    largest = float(np.abs(F).max())
    assert largest == osc.F0
    double = osc.replace(F0=2.0 * osc.F0)
    np.testing.assert_allclose(double.F, 2.0 * F, rtol=1e-15)
    branch = ic.continuation(osc, 1, "F0", (0.5, 2.0))
    assert branch.sizes["point"] > 5
    for k in range(0, branch.sizes["point"], 7):
        at = osc.replace(F0=float(branch["F0"][k]))
        deltas = [o.delta for o in ic.periodic_orbits(at, 1)]
        assert min(abs(_wrap(d - float(branch["delta"][k]))) for d in deltas) < 1e-10


def test_omega_branch_with_phases_against_point_orbits():
    osc = _osc(FA + 1j * FB)
    branch = ic.continuation(osc, 1, "omega", (0.8, 2.5))
    assert branch.sizes["point"] > 10
    for k in range(0, branch.sizes["point"], 11):
        at = osc.replace(omega=float(branch["omega"][k]))
        c, s = general.amplitude(at, 1)[:2]
        d = float(branch["delta"][k])
        assert c * math.cos(d) + s * math.sin(d) == pytest.approx(at.b, abs=1e-10)


def test_json_round_trip_keeps_the_phases():
    osc = _osc(FA + 1j * FB)
    data = osc.to_dict()
    assert data["F"] == FA.tolist() and data["F_imag"] == FB.tolist()
    back = ic.ImpactOscillator.from_json(osc.to_json())
    np.testing.assert_array_equal(back.F, osc.F)
    with pytest.raises(ParameterError, match="F_imag must be a real vector"):
        ic.ImpactOscillator.from_dict({**data, "F_imag": ["x", 1]})


def test_complex_inputs_other_than_F_are_refused():
    with pytest.raises(TypeError, match="complex values"):
        _osc(FA, M=np.diag([1.0, 1.3]) + 0j * np.eye(2) + 1e-3j)
    with pytest.raises(ParameterError, match="F must be finite"):
        _osc(np.array([1.0, np.nan + 1j]))
    with pytest.raises(ParameterError, match=r"F must have shape \(2,\)"):
        _osc(np.array([1.0 + 1j]))
