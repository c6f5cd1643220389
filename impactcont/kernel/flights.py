"""Flights between impacts in modal form: the free transfer of a mode and the forced response.

Over a flight of duration t each mode of the mass-normalised system evolves by the
exact 2 x 2 transfer ``W_i(t)`` of eq. (9) (under-, critically and over-damped
modes, written without cancellation: ``expm1``, half-angle sines, the slow and fast
rates of an over-damped mode); the harmonic forcing adds the forced response
``gamma_i cos(omega t) + beta_i sin(omega t)`` of eq. (7). :func:`mode_period` gives
``W_i(T)`` over a forcing period with ``det(I - W_i)`` and the ``h_i`` of the N-1
closed form (:mod:`impactcont.kernel.closed_form`); :func:`transition` assembles
the physical transition ``U W(T) U^-1``.

Every function is usable with complex arguments (the complex step of
:func:`impactcont.kernel.closed_form.amplitude_derivative`).
"""

from __future__ import annotations

import math

import numba as nb
import numpy as np
from numba.extending import overload

from impactcont.kernel.jit import entry as _jit
from impactcont.kernel.jit import inner as _inner

__all__ = ["forced", "mode_period", "mode_transfer", "transfer_into", "transition"]


_EPS = 2.220446049250313e-16


# -- scalar helpers usable for float and complex (complex step) ---------------------------------
def _expm1(x):  # pragma: no cover - replaced by the overload inside compiled code
    return math.expm1(x)


@overload(_expm1)
def _expm1_overload(x):
    if isinstance(x, nb.types.Complex):
        def impl(x):
            # expm1(x + iy) = e^x (cos y + i sin y) - 1, accurate for the tiny y of a complex step
            ex = math.exp(x.real)
            return complex(math.expm1(x.real) - 2.0 * ex * math.sin(0.5 * x.imag) ** 2,
                           ex * math.sin(x.imag))
        return impl
    return lambda x: math.expm1(x)


@_inner
def _re(x):
    return x.real


# -- one mode: the exact free transfer W(t) of eq. (9) ------------------------------------------
@_jit
def mode_transfer(w, a, t):
    """``W11, W12, W21, W22`` of one mode at time t, every damping class (eq. 9)."""
    d = (w - a) * (w + a)
    if _re(d) > 0.0:
        wd = np.sqrt(d)
        e = np.exp(-a * t)
        ec = e * np.cos(wd * t)
        es = e * np.sin(wd * t) / wd
        w22 = ec - a * es
    elif _re(d) == 0.0:
        e = np.exp(-a * t)
        ec = e
        es = e * t
        w22 = e * (1.0 - a * t)
    else:
        k = np.sqrt(-d)
        e_slow = np.exp(-(w * w / (a + k)) * t)
        e_fast = np.exp(-(a + k) * t)
        ec = 0.5 * (e_slow + e_fast)
        es = e_slow * (-_expm1(-2.0 * k * t)) / (2.0 * k)
        if _re(k * t) < 1.0:
            w22 = ec - a * es
        else:
            w22 = 0.5 * (-(w * w) / ((a + k) * k) * e_slow + (1.0 + a / k) * e_fast)
    return ec + a * es, es, -(w * w) * es, w22


@_jit
def mode_period(w, a, T):
    """One mode over a period: ``W(T)``, ``d = det(I - W)``, ``h`` and ``1 - W11``.

    Returns ``(W11, W12, W21, W22, d, h, one_minus_w11, cond)`` where
    ``h = (1 - det W + W22 - W11) / (2 d)`` and ``cond`` bounds the relative error
    of ``d`` caused by the rounding of ``omega_d T`` (large only close to an undamped
    resonance of the free mode, ``omega_d T`` near a multiple of 2 pi).
    """
    w11, w12, w21, w22 = mode_transfer(w, a, T)
    d = (w - a) * (w + a)
    aT = a * T
    em1 = _expm1(-aT)
    cond = 1.0
    if _re(d) > 0.0:
        wd = np.sqrt(d)
        th = wd * T
        e = np.exp(-aT)
        sh = np.sin(0.5 * th)
        det = em1 * em1 + 4.0 * e * sh * sh
        one_m_w11 = -em1 + 2.0 * e * sh * sh - a * w12
        h = (-_expm1(-2.0 * aT) - 2.0 * a * w12) / (2.0 * det)
        if _re(det) > 0.0:
            cond = 1.0 + _re(th) * abs(_re(e * np.sin(th))) / abs(_re(det))
    elif _re(d) == 0.0:
        det = em1 * em1
        one_m_w11 = -em1 - aT * np.exp(-aT)
        h = (-_expm1(-2.0 * aT) - 2.0 * a * w12) / (2.0 * det)
    else:
        k = np.sqrt(-d)
        ls = w * w / (a + k)
        lf = a + k
        ems = _expm1(-ls * T)
        emf = _expm1(-lf * T)
        det = ems * emf
        if _re(k) >= 0.5 * _re(a):
            # heavy damping: W11 = (lf e_s - ls e_f)/(lf - ls) and the divided difference of
            # phi(l) = l coth(l T / 2), free of the cancellation of 1 - e_s against a/k
            one_m_w11 = (-lf * ems + ls * emf) / (lf - ls)
            phi_f = lf * (2.0 + emf) / (-emf)
            phi_s = ls * (2.0 + ems) / (-ems)
            h = (phi_f - phi_s) / (2.0 * (lf - ls))
        else:
            one_m_w11 = -0.5 * (ems + emf) - a * w12
            h = (-_expm1(-2.0 * aT) - 2.0 * a * w12) / (2.0 * det)
    return w11, w12, w21, w22, det, h, one_m_w11, cond


@_inner
def _period_slope(w, a, T, w12, w22, det, h):
    """``d/dT`` of ``W12``, ``det(I - W)`` and ``h`` of :func:`mode_period`, exact (real).

    ``dW/dT = A W`` with ``A = [[0, 1], [-w^2, -2a]]`` (eq. 9) and ``det W = exp(-2aT)``
    (Liouville) give, with ``X = W22 - exp(-2aT)`` and ``W21 = -w^2 W12``,
    ``d W12 = W22``, ``d det = 2 w^2 W12 + 2a X`` and ``d (2 h det) = -2a X``, the same
    form for every damping class (no branch, no complex step).
    """
    x = w22 - math.exp(-2.0 * a * T)
    d_det = 2.0 * w * w * w12 + 2.0 * a * x
    d_h = -(a * x * (1.0 + 2.0 * h) + 2.0 * h * w * w * w12) / det
    return w22, d_det, d_h


# -- one frequency: S of eq. (13) in modal form ---------------------------------------------------
@_jit
def forced(w, a, f, omega, eig_err):
    """``gamma_i, beta_i`` of eq. (7) and the worst relative error near a resonance."""
    n = w.size
    gamma = np.empty_like(w * (a[0] * omega))  # complex when any input is (complex step)
    beta = np.empty_like(gamma)
    worst = 0.0
    for i in range(n):
        detune = (w[i] - omega) * (w[i] + omega)
        damp = 2.0 * a[i] * omega
        den = detune * detune + damp * damp
        if _re(den) == 0.0:
            gamma[i] = np.nan if f[i] != 0.0 else 0.0
            beta[i] = gamma[i]
            if f[i] != 0.0:
                worst = np.inf
            continue
        gamma[i] = detune * f[i] / den
        beta[i] = damp * f[i] / den
        if f[i] != 0.0:
            scale = 4.0 * eig_err[i] + 4.0 * _EPS * _re(w[i] * w[i])
            rel = scale * abs(_re(detune)) / _re(den)
            if rel > worst:
                worst = rel
    return gamma, beta, worst


@_inner
def _forced_slope(w, a, f, omega):
    """``d gamma / d omega, d beta / d omega`` of one mode (eq. 7, :func:`forced`), exact."""
    detune = (w - omega) * (w + omega)
    damp = 2.0 * a * omega
    den = detune * detune + damp * damp
    if den == 0.0:
        return (np.nan, np.nan) if f != 0.0 else (0.0, 0.0)
    d_den = 4.0 * (a * damp - omega * detune)
    return (f * (-2.0 * omega * den - detune * d_den) / (den * den),
            f * (2.0 * a * den - damp * d_den) / (den * den))


@_jit
def transition(modal, u, ui):
    """Physical transition ``U W(T) U^-1`` (eq. 9), shape (2n, 2n), by plain loops.

    For small systems (no BLAS call on tiny arrays); above ``BLAS_MIN`` degrees of
    freedom :func:`impactcont.orbit.periodic.modal_jacobian` forms it with numpy
    matrix products instead.
    """
    n = modal.shape[1]
    tr = np.empty((2 * n, 2 * n), dtype=modal.dtype)
    _transition_into(modal, u, ui, tr)
    return tr


@_inner
def _transition_into(modal, u, ui, tr):
    """:func:`transition` into ``tr`` (2n, 2n), no allocation."""
    transfer_into(modal, 2, u, ui, tr)


@_inner
def _physical_into(u, y, v, X):
    """The physical state ``X = [u y; u v]`` (2n,) of the modal displacements ``y`` and
    velocities ``v`` (n,), into ``X``, by plain loops (``x = U y`` of eq. 9's modal form).

    Parameters
    ----------
    u : ndarray, shape (n, n)
        The mass-normalised mode shapes ``U``, one per column.
    y, v : ndarray, shape (n,)
        Modal displacements and velocities.
    X : ndarray, shape (2n,)
        Overwritten with ``[U y; U v]``.
    """
    n = u.shape[0]
    for r in range(n):
        sx = 0.0
        sv = 0.0
        for i in range(n):
            sx += u[r, i] * y[i]
            sv += u[r, i] * v[i]
        X[r] = sx
        X[n + r] = sv


@_jit
def transfer_into(W, first, u, ui, tr):
    """``U W U^-1`` into ``tr`` (2n, 2n): the modal transfers ``W11, W12, W21, W22`` of
    eq. (9) are the rows ``first .. first + 3`` of ``W`` (n columns, one per mode)."""
    n = W.shape[1]
    for r in range(n):
        for col in range(n):
            s11 = 0.0
            s12 = 0.0
            s21 = 0.0
            s22 = 0.0
            for i in range(n):
                p = u[r, i] * ui[i, col]
                s11 += p * W[first, i]
                s12 += p * W[first + 1, i]
                s21 += p * W[first + 2, i]
                s22 += p * W[first + 3, i]
            tr[r, col] = s11
            tr[r, n + col] = s12
            tr[n + r, col] = s21
            tr[n + r, n + col] = s22
