"""Branches, curves and large systems far above the lowest natural frequency (issue 19,
item 10), against the 60-digit reference :mod:`reference_mp`.

There ``|c, s| >> b`` (1.2e9 against 0.3 on issue 19's system at omega / omega_1 = 670):

- eq. (14) is a difference of terms of size ``|c, s|``, so its residual cannot reach an
  absolute Newton tolerance: no branch or curve could be started (they now divide it by
  its scale, :func:`impactcont.problems.periodic_branch.residual_scale`);
- the kernel's impact velocity ``x1p'(delta) / Delta`` cancels, and moves with a phase
  error like ``|c, s| / (kappa g)``: a point solved to the corrector's tolerance (a bound
  point, a located point) had it 0.1 % off; the curves' pieces, their G and the
  first-order state ``S e`` lost 8e-8 (they now use the impact condition's form);
- the secular multipliers (n >= 16) see the impact velocity as a sum over the modes that
  cancels the same way (6e-10 relative for a 16-mass chain at 1e4 omega_1): they now
  refuse, and G's dense eigenvalues with the motion's velocity are used.
"""

from __future__ import annotations

import math
import warnings

import mpmath
import numpy as np
import pytest

import impactcont as ic
from impactcont.orbit import secular
from impactcont.orbit.periodic import modal_arrays
from impactcont.problems.codim1 import curve_problem
from tests import reference_mp as ref
from tests.integration.test_high_frequency_accuracy import K3, _far

OMEGA = 300.0  # issue 19's example: omega / omega_1 = 670
BOUNDS = (299.0, 301.0)
PATHS = pytest.mark.parametrize("matrix", [False, True], ids=["modal", "damping_matrix"])


def _far_system(b: float = 0.3) -> ref.MPSystem:
    return ref.MPSystem(M=np.eye(3), K=K3, F=[OMEGA**2, 0.0, 0.0], R=1.0, b=b, beta=0.02,
                        dps=60)


@pytest.fixture(scope="module")
def far_reference() -> dict[float, dict]:
    """The 60-digit motions of issue 19's system at the start and the bounds of a branch."""
    system = _far_system()
    return {omega: ref.to_float(ref.closed_form(system, omega, 1, gap=False))
            for omega in (BOUNDS[0], OMEGA, BOUNDS[1])}


def _forced_amplitude(omega: float) -> complex:
    """``Z_1``, the complex forced amplitude of mass 1, to 60 digits: a zero-velocity
    impact is the forced response touching the stop, ``b = |Z_1|`` at the phase
    ``delta = -arg Z_1`` (eq. 22 with ``h2 = 0``)."""
    system = _far_system()
    with mpmath.workdps(system.dps):
        return complex(system.forced_amplitude(mpmath.mpf(omega))[0])


def _nearest(orbits: list[dict], delta: float) -> dict:
    return min(orbits, key=lambda o: abs(math.remainder(o["delta"] - delta, 2 * math.pi)))


def _relative(a, b) -> float:
    b = np.asarray(b)
    return float(np.max(np.abs(np.asarray(a) - b)) / np.max(np.abs(b)))


# -- a continuation point --------------------------------------------------------------------------
@PATHS
def test_branch_points_far_above_the_first_mode_against_mpmath(matrix, far_reference):
    """No component could be started (residual 5.6e-8 against the tolerance 1e-12); the
    points on the bounds, solved to the corrector's tolerance, had an impact velocity
    0.1 % off. Every point of the branch through the start and on both bounds: 1e-10."""
    branch = ic.continuation(_far(matrix=matrix), 1, "omega", BOUNDS, components="start")
    omega = branch.omega.values
    assert {BOUNDS[0], OMEGA, BOUNDS[1]} <= set(omega.tolist())
    for k in np.flatnonzero(np.isin(omega, list(far_reference))):
        r = _nearest(far_reference[omega[k]]["orbits"], float(branch.delta[k]))
        rho = float(np.abs(r["multipliers"]).max())
        assert abs(math.remainder(float(branch.delta[k]) - r["delta"], 2 * math.pi)) < 1e-12
        assert float(branch.impact_velocity[k]) == pytest.approx(r["impact_velocity"],
                                                                 rel=1e-10, abs=0)
        assert _relative(branch.state.values[k], r["state"]) < 1e-10
        assert float(branch.spectral_radius[k]) == pytest.approx(rho, rel=1e-10, abs=0)


@PATHS
def test_zero_velocity_point_of_a_branch_in_b_against_mpmath(matrix):
    """The ZV point of the branch in b at omega = 300 (``b = |Z_1|``): no branch before."""
    branch = ic.continuation(_far(matrix=matrix), 1, "b", (0.5, 1.5), components="start",
                             detect=["ZV"])
    z1 = _forced_amplitude(OMEGA)
    assert branch.special_label.values.tolist() == ["ZV"]
    assert branch.special_status.values.tolist() == ["located"]
    assert float(branch.special_b[0]) == pytest.approx(abs(z1), rel=1e-12, abs=0)
    assert abs(math.remainder(float(branch.special_delta[0]) + np.angle(z1),
                              2 * math.pi)) < 1e-12


# -- a curve point ---------------------------------------------------------------------------------
@PATHS
def test_zero_velocity_curve_far_above_the_first_mode_against_mpmath(matrix):
    """Every point of the ZV curve in (omega, b): ``b = |Z_1(omega)|`` to 1e-12 (with the
    kernel's velocity form eq. (14) fixed ``b`` only to ``eps |c, s| = 2e-7``), at
    ``delta = -arg Z_1`` with a zero impact velocity."""
    curve = ic.curve(_far(matrix=matrix), 1, "ZV", start={"omega": OMEGA, "b": 1.0},
                     bounds={"omega": BOUNDS, "b": (0.5, 1.5)}, max_points=12,
                     detect_codim2_points=False)
    assert curve.sizes["point"] >= 5
    for k in range(curve.sizes["point"]):
        z1 = _forced_amplitude(float(curve.omega[k]))
        assert float(curve.b[k]) == pytest.approx(abs(z1), rel=1e-12, abs=0), k
        assert abs(math.remainder(float(curve.delta[k]) + np.angle(z1), 2 * math.pi)) < 1e-12
        assert abs(float(curve.impact_velocity[k])) < 1e-15


@PATHS
@pytest.mark.parametrize("kind", ["PD", "NS"])
def test_curve_pieces_far_above_the_first_mode_against_mpmath(matrix, kind, far_reference):
    """The impact velocity and G of a curve's pieces (the PD and NS conditions, GR's
    flight) at the reference's phases: 8e-8 off with the kernel's velocity form."""
    osc = _far(matrix=matrix)
    pieces = curve_problem(kind, osc, 1)._pieces(OMEGA, osc.b)
    system = _far_system()
    with mpmath.workdps(system.dps):
        z = system.forced_amplitude(mpmath.mpf(OMEGA))
    for r in far_reference[OMEGA]["orbits"]:
        mu = np.asarray(r["multipliers"])
        assert pieces.impact_velocity(r["delta"]) == pytest.approx(r["impact_velocity"],
                                                                   rel=1e-10, abs=0)
        G, h2 = pieces.jacobian(r["delta"])
        assert h2 == pytest.approx(r["impact_velocity"], rel=1e-10, abs=0)
        assert ref.matched_error(np.linalg.eigvals(G), mu) <= 1e-10 * np.abs(mu).max()
        x1 = ref._mass1(system, z, mpmath.mpf(OMEGA), mpmath.matrix(r["state"].tolist()),
                        mpmath.mpf(r["delta"]))
        for t in (0.3 * pieces.T, 0.8 * pieces.T):  # x1 along the flight (the GR condition)
            want = [float(v) for v in x1(mpmath.mpf(t))]
            assert np.allclose(pieces.mass1(r["delta"], t), want, rtol=0, atol=1e-12)
    if matrix:  # the first-order state P0 e + kappa sigma y (S e cancels)
        for r in far_reference[OMEGA]["orbits"]:
            assert _relative(pieces.state(r["delta"]), r["state"]) < 1e-10


@PATHS
def test_points_solved_to_the_tolerance_report_the_motion_of_their_root(matrix, far_reference):
    """A branch or curve point solves eq. (14) to the corrector's tolerance only: its
    motion is that of the root nearest its phase (a phase 1e-12 off moved the kernel's
    impact velocity by 0.2 %)."""
    from impactcont.problems import PeriodicBranchProblem

    osc = _far(matrix=matrix)
    branch = PeriodicBranchProblem(osc, 1, "omega")
    curve = curve_problem("PD", osc, 1)
    for r in far_reference[OMEGA]["orbits"]:
        for delta in (r["delta"] - 1e-12, r["delta"] + 1e-12):
            for orbit in (branch.orbit(delta, OMEGA), curve.orbit(np.array([OMEGA, delta]),
                                                                  osc.b)):
                assert orbit.impact_velocity == pytest.approx(r["impact_velocity"], rel=1e-10,
                                                              abs=0)
                assert _relative(orbit.state, r["state"]) < 1e-10


# -- n >= 16: the secular multipliers --------------------------------------------------------------
def _chain16() -> ic.ImpactOscillator:
    """A 16-mass chain forced on mass 1 at 1e4 times its lowest natural frequency."""
    n = 16
    K = 2.0 * np.eye(n) - np.eye(n, k=1) - np.eye(n, k=-1)
    K[0, 0] = 1.0
    omega = 1e4 * math.sqrt(float(np.linalg.eigvalsh(K)[0]))
    return ic.ImpactOscillator(M=np.eye(n), K=K, F=[omega**2] + [0.0] * (n - 1), R=0.8,
                               b=0.3, omega=omega, eta=0.01)


@pytest.fixture(scope="module")
def chain16_reference() -> dict:
    """The root -1 motion of :func:`_chain16` with its multipliers, 60 digits (1.5 s)."""
    osc = _chain16()
    system = ref.MPSystem(M=osc.M, K=osc.K, F=np.real(osc.F), R=osc.R, b=osc.b, beta=0.02,
                          dps=60)
    return ref.to_float(ref.closed_form(system, osc.omega, 1, gap=False,
                                        roots=(-1,)))["orbits"][0]


def test_secular_multipliers_refuse_where_the_modal_velocity_cancels(chain16_reference):
    """The secular function saw the impact velocity as ``sum_i u_1i v_i``, 6e-10 off
    (relative) here, and its multipliers with it, accepted by its power-sum guard; it
    now refuses, and the orbit's multipliers (G with the motion's velocity) are exact."""
    osc = _chain16()  # below SECULAR_MIN: the orbit takes the dense path, checked too
    orbit = next(o for o in ic.periodic_orbits(osc, 1) if o.root == -1)
    mu_ref = np.asarray(chain16_reference["multipliers"])
    tol = 1e-10 * np.abs(mu_ref).max()
    arrays = modal_arrays(osc)
    w, a, f, u0, ui0 = arrays.w, arrays.a, arrays.f, arrays.u0, arrays.ui0
    mu, ok = secular.secular_multipliers(orbit.modal, w, a, f, u0, ui0, osc.omega, osc.R,
                                         orbit.delta, orbit.impact_velocity)
    assert not ok or ref.matched_error(mu, mu_ref) <= tol
    assert ref.matched_error(orbit.multipliers, mu_ref) <= tol


def test_branch_of_a_16_mass_chain_far_above_its_first_mode(chain16_reference):
    """A branch of the 16-mass chain landing on omega = 1e4 omega_1 (a point solved to the
    corrector's tolerance): no component could be started before."""
    osc = _chain16()
    bounds = (osc.omega, osc.omega * (1.0 + 1e-4))
    branch = ic.continuation(osc, 1, "omega", bounds, start=osc.omega * (1.0 + 5e-5),
                             root=-1, components="start", detect=[])
    (k,) = np.flatnonzero(branch.omega.values == osc.omega)
    r = chain16_reference
    mu_ref = np.asarray(r["multipliers"])
    assert abs(math.remainder(float(branch.delta[k]) - r["delta"], 2 * math.pi)) < 1e-12
    assert float(branch.impact_velocity[k]) == pytest.approx(r["impact_velocity"], rel=1e-10,
                                                             abs=0)
    assert ref.matched_error(branch.multipliers.values[k], mu_ref) <= (
        1e-10 * np.abs(mu_ref).max())


@PATHS
def test_no_neimark_sacker_point_from_rounding_far_above_the_first_mode(matrix):
    """R = 1 and light damping far above the first mode: a factor mu_big mu_small - 1 of
    the NS test is about -4e-4 while mu_small is known only to eps |mu_big|, so the test
    changed sign by rounding: 5 (modal) and 7 (damping matrix) NS points were reported
    'bracketed' on this branch, none of them a Neimark-Sacker point."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)
        branch = ic.continuation(_far(matrix=matrix), 1, "b", (0.5, 1.5), components="start")
    assert branch.special_label.values.tolist() == ["ZV"]
