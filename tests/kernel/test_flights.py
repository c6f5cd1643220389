"""The flights of :mod:`impactcont.kernel.flights` against independent witnesses.

- ``mode_transfer``, ``mode_period``: ``scipy.linalg.expm`` of the mode's first-order
  system ``[[0, 1], [-w^2, -2a]]`` (eq. 9), every damping class;
- ``forced``: a direct solve of the forced response ``q'' + 2a q' + w^2 q = f cos(omega t)``
  (eq. 7) for ``gamma cos + beta sin``;
- ``transition``, ``transfer_into``: ``expm`` of the physical first-order system
  ``P A P^-1`` (``P = blockdiag(U, U)``);
- the complex variants (the complex step of ``closed_form.amplitude_derivative``): the
  imaginary part over the step against a central finite difference of the expm witness.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.linalg import expm

from impactcont.kernel.flights import forced, mode_period, mode_transfer, transfer_into, transition

# (w, a): under-, critically, lightly over- and heavily over-damped (the two forms of h)
MODES = {
    "undamped": (1.3, 0.0),
    "under": (1.3, 0.1),
    "critical": (1.5, 1.5),
    "over-light": (1.0, 1.1),  # k = 0.46 < a / 2
    "over-heavy": (1.0, 3.0),  # k = 2.83 >= a / 2
}


def _system(w, a):
    return np.array([[0.0, 1.0], [-w * w, -2.0 * a]])


def _expm_transfer(w, a, t):
    return expm(_system(w, a) * t)


@pytest.mark.parametrize("t", [0.0, 0.3, 2.0, 7.5])
@pytest.mark.parametrize("mode", list(MODES))
def test_mode_transfer_is_the_exponential_of_the_mode(mode, t):
    w, a = MODES[mode]
    W = np.array(mode_transfer(w, a, t)).reshape(2, 2)
    np.testing.assert_allclose(W, _expm_transfer(w, a, t), rtol=1e-12, atol=1e-13)


@pytest.mark.parametrize("mode", list(MODES))
def test_mode_period_is_det_and_h_of_the_exponential(mode):
    w, a = MODES[mode]
    T = 2.0 * math.pi / 0.7
    w11, w12, w21, w22, d, h, one_m_w11, cond = mode_period(w, a, T)
    W = _expm_transfer(w, a, T)
    np.testing.assert_allclose([[w11, w12], [w21, w22]], W, rtol=1e-12, atol=1e-13)
    det = np.linalg.det(np.eye(2) - W)
    assert d == pytest.approx(det, rel=1e-11)
    assert one_m_w11 == pytest.approx(1.0 - W[0, 0], rel=1e-11)
    # h = (1 - det W + W22 - W11) / (2 det(I - W)), det W = exp(-2 a T) (Liouville)
    assert h == pytest.approx((1.0 - np.linalg.det(W) + W[1, 1] - W[0, 0]) / (2.0 * det),
                              rel=1e-10)
    assert cond >= 1.0


def test_mode_period_cond_grows_near_an_undamped_resonance():
    """``cond`` bounds the relative error of ``d`` from the rounding of ``omega_d T``:
    large when ``omega_d T`` is near a multiple of 2 pi, 1 + O(1) away from it."""
    w = 1.0
    far = mode_period(w, 0.0, 2.0 * math.pi / 0.7)[7]
    near = mode_period(w, 0.0, 2.0 * math.pi * (1.0 + 1e-6))[7]
    assert far < 10.0
    assert near > 1e5


@pytest.mark.parametrize("omega", [0.4, 1.25, 3.0])
def test_forced_solves_the_forced_mode(omega):
    w = np.array([0.8, 1.3, 2.0, 1.0])
    a = np.array([0.05, 0.0, 0.4, 3.0])
    f = np.array([1.0, -0.5, 0.2, 0.7])
    gamma, beta, worst = forced(w, a, f, omega, np.zeros(4))
    for i in range(4):
        # q = gamma cos(omega t) + beta sin(omega t) in q'' + 2a q' + w^2 q = f cos(omega t)
        A = np.array([[w[i] ** 2 - omega ** 2, 2.0 * a[i] * omega],
                      [-2.0 * a[i] * omega, w[i] ** 2 - omega ** 2]])
        expected = np.linalg.solve(A, [f[i], 0.0])
        np.testing.assert_allclose([gamma[i], beta[i]], expected, rtol=1e-13, atol=1e-15)
    assert 0.0 <= worst < 1e-12


def test_forced_at_an_undamped_resonance_is_nan_and_flagged():
    """No forced response at ``omega = w`` without damping: NaN and ``worst = inf``; a
    mode that is not forced there stays 0."""
    gamma, beta, worst = forced(np.array([1.0, 1.0]), np.zeros(2), np.array([1.0, 0.0]), 1.0,
                                np.zeros(2))
    assert np.isnan(gamma[0]) and np.isnan(beta[0])
    assert gamma[1] == 0.0 and beta[1] == 0.0
    assert worst == math.inf


def test_forced_worst_error_grows_near_a_resonance():
    w, a, f = np.array([1.0]), np.array([0.0]), np.array([1.0])
    _, _, far = forced(w, a, f, 0.5, np.array([1e-15]))
    _, _, near = forced(w, a, f, 1.0 - 1e-9, np.array([1e-15]))
    assert near > 1e6 * far


def _physical(n, seed):
    rng = np.random.default_rng(seed)
    U = rng.standard_normal((n, n)) + n * np.eye(n)
    w = 0.5 + 2.0 * rng.random(n)
    a = np.array([0.0, 0.1, 1.5, 2.0, 0.05][:n])
    w[2 % n] = a[2 % n] if n > 2 else w[2 % n]  # a critically damped mode
    return U, np.linalg.inv(U), w, a


@pytest.mark.parametrize("n", [1, 3, 5])
def test_transition_is_the_exponential_of_the_physical_system(n):
    U, Ui, w, a = _physical(n, n)
    t = 1.7
    modal = np.zeros((6, n))
    for i in range(n):
        modal[2:6, i] = mode_transfer(w[i], a[i], t)
    A = np.zeros((2 * n, 2 * n))
    A[:n, n:] = np.eye(n)
    A[n:, :n] = -np.diag(w * w)
    A[n:, n:] = -np.diag(2.0 * a)
    P = np.block([[U, np.zeros((n, n))], [np.zeros((n, n)), U]])
    expected = P @ expm(A * t) @ np.linalg.inv(P)
    np.testing.assert_allclose(transition(modal, U, Ui), expected, rtol=1e-11,
                               atol=1e-12 * np.abs(expected).max())
    # transfer_into takes the four rows from any first row
    W = np.vstack([np.full((1, n), np.nan), modal[2:6]])
    tr = np.empty((2 * n, 2 * n))
    transfer_into(W, 1, U, Ui, tr)
    np.testing.assert_array_equal(tr, transition(modal, U, Ui))


# -- the complex variants: d/dp by a complex step against a central difference of expm ---------
H = 1e-20  # the complex step
FD = 1e-6  # the central difference of the witness


@pytest.mark.parametrize("mode", ["under", "over-light", "over-heavy"])
def test_mode_transfer_complex_step_is_the_derivative(mode):
    w, a = MODES[mode]
    t = 2.0
    dW = np.array(mode_transfer(complex(w, H), complex(a), complex(t))).imag / H
    fd = (_expm_transfer(w + FD, a, t) - _expm_transfer(w - FD, a, t)) / (2 * FD)
    np.testing.assert_allclose(dW.reshape(2, 2), fd, rtol=1e-7, atol=1e-8)
    dW = np.array(mode_transfer(complex(w), complex(a), complex(t, H))).imag / H
    np.testing.assert_allclose(dW.reshape(2, 2), _system(w, a) @ _expm_transfer(w, a, t),
                               rtol=1e-12, atol=1e-13)


@pytest.mark.parametrize("mode", ["under", "over-light", "over-heavy"])
def test_mode_period_complex_step_is_the_derivative(mode):
    w, a = MODES[mode]
    T = 2.0 * math.pi / 0.7

    def real(om):
        return np.array(mode_period(om, a, T)[:7])

    got = np.array(mode_period(complex(w, H), complex(a), complex(T))[:7]).imag / H
    fd = (real(w + FD) - real(w - FD)) / (2 * FD)
    np.testing.assert_allclose(got, fd, rtol=1e-6, atol=1e-8)


def test_forced_complex_step_is_the_derivative():
    w = np.array([0.8, 1.3, 2.0])
    a = np.array([0.05, 0.0, 0.4])
    f = np.array([1.0, -0.5, 0.2])
    omega = 1.1
    g, b, _ = forced(w + 0j, a + 0j, f, complex(omega, H), np.zeros(3))
    gp, bp, _ = forced(w, a, f, omega + FD, np.zeros(3))
    gm, bm, _ = forced(w, a, f, omega - FD, np.zeros(3))
    np.testing.assert_allclose(g.imag / H, (gp - gm) / (2 * FD), rtol=1e-7)
    np.testing.assert_allclose(b.imag / H, (bp - bm) / (2 * FD), rtol=1e-7, atol=1e-9)
