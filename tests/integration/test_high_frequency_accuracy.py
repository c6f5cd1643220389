"""Accuracy far above the lowest natural frequency, and the two paths against each other.

- the damping-matrix (first-order) path and the modal path on the same system
  (``C = 2 eta K`` given as a matrix and as ``eta``) over omega in [1e-6, 1e8]: the same
  motions and the same warnings, points and stability maps; the first-order path
  against the 60-digit reference :mod:`reference_mp` where eq. (12) cancels
  (``1/(lambda T)`` terms: ``(I - Phi(T))^-1`` in closed form, eq. 12-14);
- the impact velocity far above the lowest natural frequency (``|c, s| >> b``): its
  kernel form ``x1p'(delta) / Delta`` cancels there, its impact-condition form does not
  (:func:`impactcont.orbit.dense.impact_velocity`); orbits, maps and G against
  :mod:`reference_mp` for omega / omega_1 up to 1e4, and the fast path untouched;
- the positive-definiteness check of the first-order basis is invariant to the units of
  each coordinate (a graded chain ``M = diag(1e-12, 1, 1e12)``).
"""

from __future__ import annotations

import math
import warnings

import mpmath
import numpy as np
import pytest

import impactcont as ic
from impactcont.errors import IllConditionedWarning, ParameterError
from impactcont.kernel import closed_form, roots
from impactcont.model.first_order import coth_remainder
from impactcont.orbit import batched, general, periodic
from impactcont.orbit.periodic import orbit_at_phase
from tests import reference_mp as ref

K2 = np.array([[1.0, -1.0], [-1.0, 2.0]])
K3 = np.array([[1.0, -1.0, 0.0], [-1.0, 2.0, -1.0], [0.0, -1.0, 2.0]])
EPS = float(np.finfo(float).eps)


def _paper(omega: float, matrix: bool) -> ic.ImpactOscillator:
    """The paper's system (C = 0.2 K), on the modal path or as a damping matrix."""
    damping = {"C": 0.2 * K2} if matrix else {"eta": 0.1}
    return ic.ImpactOscillator(M=np.eye(2), K=K2, F=[1.0, 0.0], R=0.6, b=0.6, omega=omega,
                               **damping)


def _far(omega: float = 300.0, matrix: bool = False) -> ic.ImpactOscillator:
    """Issue 19's example: omega / omega_1 = 670, |c, s| ~ 1e9 against b = 0.3."""
    damping = {"C": 0.02 * K3} if matrix else {"eta": 0.01}
    return ic.ImpactOscillator(M=np.eye(3), K=K3, F=[omega**2, 0.0, 0.0], R=1.0, b=0.3,
                               omega=omega, **damping)


def _orbits(osc: ic.ImpactOscillator) -> tuple[list, set]:
    """The motions and the warning classes of periodic_orbits."""
    with warnings.catch_warnings(record=True) as record:
        warnings.simplefilter("always")
        orbits = ic.periodic_orbits(osc, 1)
    return orbits, {w.category for w in record}


def _relative(a: np.ndarray, b: np.ndarray) -> float:
    b = np.asarray(b)
    return float(np.max(np.abs(np.asarray(a) - b)) / max(float(np.max(np.abs(b))), 1e-300))


def _against_reference(orbits, osc, beta: float, dps: int = 60) -> float:
    """Worst relative error of delta, impact velocity, state and multipliers (against
    max(1, rho): G's entries are sums of terms of order one) over the roots."""
    system = ref.MPSystem(M=osc.M, K=osc.K, F=np.real(osc.F), R=osc.R, b=osc.b, beta=beta,
                          dps=dps)
    reference = ref.to_float(ref.closed_form(system, osc.omega, 1, gap=False))
    assert len(orbits) == len(reference["orbits"]) == 2
    worst = 0.0
    for orbit in orbits:
        r = next(o for o in reference["orbits"] if o["root"] == orbit.root)
        mu = np.asarray(r["multipliers"])
        worst = max(worst, abs(orbit.delta - r["delta"]),
                    abs(orbit.impact_velocity / r["impact_velocity"] - 1.0),
                    _relative(orbit.state, r["state"]),
                    ref.matched_error(orbit.multipliers, mu) / max(1.0, np.abs(mu).max()))
    return worst


# -- item 2: the damping-matrix path against the modal path over omega in [1e-6, 1e8] ----------
def test_damping_matrix_path_matches_the_modal_path_from_1e_minus6_to_1e8():
    """Same motions within the modal path's own error bound (its condition estimate times
    eps, which it states when large), and the same warnings (ill-conditioning, low impact
    velocity, the capped x1 search at tiny omega)."""
    for omega in np.geomspace(1e-6, 1e8, 15):
        (modal, w_modal), (matrix, w_matrix) = (_orbits(_paper(omega, m)) for m in (0, 1))
        assert w_modal == w_matrix, (omega, w_modal, w_matrix)
        arrays = periodic.modal_arrays(_paper(omega, False))
        cond = closed_form.omega_setup(arrays.w, arrays.a, arrays.f, arrays.u0, arrays.ui0,
                                       arrays.eig_err, 0.6, omega, 1)[1][7]
        tol = 1e-11 + 10.0 * EPS * cond
        assert [o.root for o in modal] == [o.root for o in matrix]
        for p, q in zip(modal, matrix, strict=True):
            assert abs(p.delta - q.delta) <= tol, omega
            assert abs(p.impact_velocity - q.impact_velocity) <= tol * abs(p.impact_velocity)
            scale = max(1.0, float(np.abs(p.multipliers).max()))
            assert ref.matched_error(p.multipliers, q.multipliers) <= tol * scale, omega


@pytest.mark.parametrize("omega", [1e3, 1e5, 1e7])
def test_damping_matrix_path_against_mpmath_at_high_omega(omega):
    """The closed form of eq. (12) no longer cancels the 1/(lambda T) terms (it lost
    omega^2 digits: 0.47 % at 1e7): full accuracy, whatever the condition estimate says."""
    osc = _paper(omega, True)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", IllConditionedWarning)  # stated where cond is large
        orbits = ic.periodic_orbits(osc, 1)
    assert _against_reference(orbits, osc, beta=0.2) < 1e-12


@pytest.mark.parametrize("omega", [2.0**13, 2.0**20])
def test_nonproportional_c_s_against_mpmath_at_high_omega(omega):
    """A damper on mass 1 only (exact binary fractions: the mpmath system is the float
    one): c, s of eq. (14) from the 60-digit expm of the augmented system."""
    from tests.orbit.test_general import _mp_fixed_point

    osc = ic.ImpactOscillator(M=np.diag([1.0, 2.0]), K=K2, C=[[0.25, 0.0], [0.0, 0.0]],
                              F=[1.0, 0.0], R=0.625, b=0.25, omega=omega)
    S, _ = _mp_fixed_point(osc, 1, dps=60)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", IllConditionedWarning)
        c, s = general.amplitude(osc, 1)[:2]
    assert c == pytest.approx(S[0, 0], rel=1e-12, abs=0)
    assert s == pytest.approx(S[0, 1], rel=1e-12, abs=0)


@pytest.mark.parametrize(("which", "omega"), [("omega", 1e3), ("R", 1e5)])
def test_damping_matrix_amplitude_derivative_at_high_omega(which, omega):
    """dc, ds of eq. (14) (continuation) against the kernel's complex step on the same
    system: the dense solve of I - D Phi(T) lost 3.5e-8 of d/d omega at omega = 1e3 and
    3.6e-7 of d/dR at 1e5."""
    R = 0.6
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", IllConditionedWarning)  # stated above omega ~ 3e4
        _, _, dc, ds = general.amplitude(_paper(omega, True), 1, which)
    arrays = periodic.modal_arrays(_paper(omega, False))
    w, a, f, u0, ui0 = arrays.w, arrays.a, arrays.f, arrays.u0, arrays.ui0
    h = 1e-30 * (omega if which == "omega" else 1.0)
    step = {"omega": (R + 0j, omega + 1j * h), "R": (R + 1j * h, omega + 0j)}[which]
    c, s = closed_form.amplitude(w.astype(complex), a.astype(complex), f.astype(complex), u0, ui0,
                            *step, 1)
    assert dc == pytest.approx(c.imag / h, rel=1e-9, abs=0)
    assert ds == pytest.approx(s.imag / h, rel=1e-9, abs=0)


def test_stability_maps_of_both_paths_agree_and_warn_alike_at_high_omega():
    omega = np.array([1.0, 1e3, 1e5, 1e6])
    b = np.array([0.3, 0.6])
    maps = []
    for matrix in (False, True):
        with pytest.warns(IllConditionedWarning, match=r"omega = \[100000.0, 1000000.0\]"):
            maps.append(ic.stability_map(_paper(1.0, matrix), 1, omega, b).sel(N=1))
    modal, dense = maps
    np.testing.assert_array_equal(modal.exists.values, dense.exists.values)
    np.testing.assert_array_equal(modal.stable.values, dense.stable.values)
    np.testing.assert_array_equal(modal.physical.values, dense.physical.values)
    np.testing.assert_allclose(dense.amplitude_squared.values, modal.amplitude_squared.values,
                               rtol=1e-9)
    for name in ("delta", "impact_velocity", "spectral_radius"):
        np.testing.assert_allclose(dense[name].values, modal[name].values, rtol=1e-9, atol=0)


# -- item 10: the impact velocity far above the lowest natural frequency ---------------------------
@pytest.mark.parametrize("matrix", [False, True], ids=["modal", "damping_matrix"])
def test_issue_example_far_above_the_first_mode_against_mpmath(matrix):
    """x1(0) - b was 5.6e-8 and the impact velocity and multipliers 8e-8 off (relative),
    with no warning: now both paths agree with 60 digits to 1e-10, and still say nothing."""
    osc = _far(matrix=matrix)
    orbits, warned = _orbits(osc)
    assert not warned
    assert all(abs(o.state[0] - osc.b) <= 1e-12 for o in orbits)
    assert _against_reference(orbits, osc, beta=0.02) < 1e-10


@pytest.mark.parametrize("ratio", [1.3, 13.0, 130.0, 1.3e3, 1.3e4])
def test_both_paths_against_mpmath_up_to_1e4_times_the_first_mode(ratio):
    """omega / omega_1 up to 1e4 (R = 1, light damping: the small Delta of the kernel's
    form): accurate to 1e-10 unless a warning states a larger error."""
    omega_1 = math.sqrt(float(np.linalg.eigvalsh(K3)[0]))
    for matrix in (False, True):
        osc = _far(ratio * omega_1, matrix)
        orbits, warned = _orbits(osc)
        error = _against_reference(orbits, osc, beta=0.02)
        assert error < 1e-10 or warned, (ratio, matrix, error)
        assert error < 1e-9, (ratio, matrix, error)


def test_orbit_at_phase_and_the_maps_give_the_accurate_motion():
    """The point at a phase and both maps (the kernel's block and the first-order one)
    against 60 digits: impact velocity and spectral radius to 1e-10."""
    system = ref.MPSystem(M=np.eye(3), K=K3, F=[300.0**2, 0.0, 0.0], R=1.0, b=0.3,
                          beta=0.02, dps=60)
    reference = ref.to_float(ref.closed_form(system, 300.0, 1, gap=False))
    for matrix in (False, True):
        osc = _far(matrix=matrix)
        m = ic.stability_map(osc, 1, [osc.omega], [osc.b]).sel(N=1)
        for orbit in ic.periodic_orbits(osc, 1):
            r = next(o for o in reference["orbits"] if o["root"] == orbit.root)
            rho = float(np.abs(r["multipliers"]).max())
            at = orbit_at_phase(osc, 1, orbit.delta, root=orbit.root)
            k = 0 if orbit.root == 1 else 1
            for vel, radius in ((at.impact_velocity, at.spectral_radius),
                                (float(m.impact_velocity.values[0, 0, k]),
                                 float(m.spectral_radius.values[0, 0, k]))):
                assert vel == pytest.approx(r["impact_velocity"], rel=1e-10, abs=0)
                assert radius == pytest.approx(rho, rel=1e-10, abs=0)


def test_a_guess_off_eq_14_keeps_the_kernel_velocity():
    """Off a root only the kernel's form solves eq. (12): a guess (check=False) is not
    moved onto the section by the impact-condition form."""
    osc = _far()
    orbit = ic.periodic_orbits(osc, 1)[1]
    delta = orbit.delta + 1e-6
    guess = orbit_at_phase(osc, 1, delta, check=False)
    arrays = periodic.modal_arrays(osc)
    w, a, f, eig_err, u0, ui0 = arrays.w, arrays.a, arrays.f, arrays.eig_err, arrays.u0, arrays.ui0
    sc = closed_form.omega_setup(w, a, f, u0, ui0, eig_err, osc.R, osc.omega, 1)[1]
    assert guess.impact_velocity == roots.phase_sigma(sc, osc.omega, osc.R, osc.b, delta)


def test_the_fast_path_pays_nothing_at_ordinary_omega(monkeypatch):
    """The paper's system at omega = 1: one bound per frequency, no exact check, no
    re-evaluation (points and maps)."""
    def refuse(*args, **kwargs):
        raise AssertionError("the velocity polish ran on the fast path")

    monkeypatch.setattr(periodic, "_polished_velocity", refuse)
    monkeypatch.setattr(periodic, "_repolish", refuse)
    monkeypatch.setattr(batched, "polished_velocity", refuse)
    osc = _paper(1.0, False)
    assert len(ic.periodic_orbits(osc, 1)) == 2
    ic.stability_map(osc, 1, np.linspace(0.5, 6.0, 12), np.linspace(0.0, 1.0, 5))


def test_coth_remainder_against_mpmath():
    """s(x) = 1/expm1(x) + 1/2 - 1/x and s'(x) on both sides of the series radius."""
    x = np.array([1e-12 + 1e-9j, -1e-6 + 0.3j, -0.2 + 0.9j, -0.7 + 0.7j, -0.999, -1.001,
                  -0.3 + 1.2j, -5.0 + 30.0j, -700.0 + 1j, 1e-3j])
    for derivative in (False, True):
        got = coth_remainder(x, derivative)
        with mpmath.workdps(40):
            for xi, gi in zip(x, got, strict=True):
                z = mpmath.mpc(xi.real, xi.imag)
                want = (1 / z**2 - mpmath.exp(z) / mpmath.expm1(z) ** 2 if derivative
                        else 1 / mpmath.expm1(z) + mpmath.mpf(1) / 2 - 1 / z)
                # the platform's complex exp/expm1 set the last bits (0.64 of 4 eps seen)
                assert abs(gi - complex(want)) <= 16 * EPS * max(1.0, abs(complex(want)))


# -- item 8: the stiffness check of the first-order basis is invariant to units ----------------
def test_graded_masses_pass_the_positive_definiteness_check():
    """M = diag(1e-12, 1, 1e12) on a supported chain, a damper on mass 1: every modal
    eigenvalue is positive (1e-12, 1, 1e12); it was refused against 4 n eps x the largest.
    The motion solves eq. (12)-(13): one exact flight and impact return to its state."""
    M = np.diag([1e-12, 1.0, 1e12])
    osc = ic.ImpactOscillator(M=M, K=K3, C=np.diag([0.1, 0.0, 0.0]), F=[1.0, 0.0, 0.0],
                              R=0.5, b=0.1, omega=1.3)
    orbits = ic.periodic_orbits(osc, 1)
    assert len(orbits) == 2
    flow = ic.Flow(osc)
    for orbit in orbits:
        arrival = flow.state(orbit.period, orbit.state, orbit.delta)[0]
        arrival[osc.n] *= -osc.R  # eq. (4)
        np.testing.assert_allclose(arrival, orbit.state, rtol=0,
                                   atol=1e-9 * np.abs(orbit.state).max())


def test_the_stiffness_check_ignores_units_and_still_refuses_a_free_mode():
    """M -> D M D, K -> D K D is the same machine in other units: the verdict holds (a
    held machine; a chain with one free mode, held by the stop on mass 1 and damped by C),
    and a free mode that nothing holds is refused."""
    free = np.array([[2.0, -1.0, -1.0], [-1.0, 1.0, 0.0], [-1.0, 0.0, 1.0]])
    D = np.diag([1e-5, 1.0, 1e5])
    for K, zeros in ((K3, 0), (free, 1)):
        for scale in (np.eye(3), D):
            osc = ic.ImpactOscillator(M=scale @ np.eye(3) @ scale, K=scale @ K @ scale,
                                      C=np.diag([0.1, 0.0, 0.0]), F=[1.0, 0.0, 0.0], R=0.5,
                                      b=0.1, omega=1.3)
            assert osc.first_order.eigenvalues.size == 6
            assert int(osc.first_order.zero.sum()) == zeros
    # the free mode [1, 1, 1] does not move x2 - x3: a stop there holds nothing
    with pytest.raises(ParameterError, match="held by nothing"):
        ic.ImpactOscillator(M=np.eye(3), K=free, C=np.diag([0.1, 0.0, 0.0]),
                            F=[1.0, 0.0, 0.0], R=0.5, b=0.1, omega=1.3,
                            stops=ic.Stops(mass=2, relative_to=3))
