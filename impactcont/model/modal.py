"""Modal decomposition and the exact modal transfer of eq. (5)-(10).

Each mode obeys ``y'' + 2 a y' + w^2 y = f cos(omega t + delta)`` with
``w = omega_i`` (natural frequency) and ``a = xi_i omega_i``. Its free
transfer over a time ``t`` is the 2x2 matrix

    W(t) = exp(-a t) [[C + a S, S], [-w^2 S, C - a S]]

with ``C = cos(w_d t)``, ``S = sin(w_d t) / w_d`` and ``w_d^2 = w^2 - a^2``
(eq. 9; the paper's ``g/w_d`` and ``h``), in three forms that are each
free of cancellation and overflow:

- under-damped (``w_d^2 > 0``, undamped included): the trigonometric form;
  ``sin(w_d t)/w_d`` stays accurate however small ``w_d`` is near ``xi = 1``;
- critically damped: ``C = 1``, ``S = t``;
- over-damped (``w_d^2 = -k^2 < 0``): the two real exponentials
  ``exp(-(a -+ k) t)`` with ``a - k = w^2 / (a + k)`` and ``expm1`` for
  ``sinh(k t)/k``, which never overflow and keep full relative precision
  however heavy the damping.
"""

from __future__ import annotations

import dataclasses
import math
import warnings

import numpy as np
import scipy.linalg

from impactcont.errors import NearResonanceWarning, ParameterError, ResonanceError

__all__ = ["DAMPING_PARAMETERS", "ModalBasis", "check_held_modes", "classify_modes",
           "decay_rate_derivative", "forced_coefficients", "free_transfer", "static_response"]

# warn when the forced amplitude of a mode is known to worse than this (relative) because
# omega sits within the rounding error of omega_i^2 (eigh: about eps * omega_max^2)
_RESONANCE_REL_ERROR_WARN = 1e-8

def classify_modes(stiffness: np.ndarray, modes: np.ndarray, K: np.ndarray
                   ) -> tuple[np.ndarray, np.ndarray]:
    """The rounding scale of each modal eigenvalue, and which modes are free.

    Each eigenvalue ``lam_i`` of ``K u = lam M u`` is known to about
    ``eps |u_i|^T |K| |u_i|`` (componentwise, so invariant to the units of each
    coordinate, ``M -> D M D``, ``K -> D K D``): a graded chain such as
    ``M = diag(1e-12, 1, 1e12)`` holds every mode, while a free (rigid-body) mode has
    an eigenvalue of that size and either sign, decided by rounding. A mode is held
    by the springs when ``lam_i > 4 n`` times its scale, free otherwise (its eigenvalue is
    then exactly 0: ``omega_i = 0``); negative beyond both that and the solver's error
    ``4 n eps max|lam|`` is refused.

    Parameters
    ----------
    stiffness : ndarray, shape (n,)
        The eigenvalues ``lam`` (``omega_i^2``).
    modes : ndarray, shape (n, n)
        The eigenvectors, by column.
    K : ndarray, shape (n, n)

    Returns
    -------
    errors : ndarray, shape (n,)
        The rounding scale of each eigenvalue.
    free : ndarray of bool, shape (n,)
        The free (zero-frequency, rigid-body) modes.

    Raises
    ------
    ParameterError
        When an eigenvalue is negative beyond rounding (K not positive semi-definite).
    """
    n = stiffness.size
    a = np.abs(modes)
    errors = np.finfo(float).eps * np.sum(a * (np.abs(K) @ a), axis=0)  # BLAS, not einsum
    tol = 4 * n * errors
    # a free mode's eigenvalue may come out negative beyond its componentwise scale when M
    # is graded (the solver's own error is relative to the largest eigenvalue): only a
    # negative eigenvalue beyond both is a K that is not positive semi-definite
    solver = 4 * n * np.finfo(float).eps * float(np.max(np.abs(stiffness), initial=0.0))
    if np.any(stiffness < -np.maximum(tol, solver)):
        raise ParameterError(f"K must be positive semi-definite relative to M (a spring "
                             f"stores energy); got modal eigenvalues {stiffness.tolist()} "
                             f"(rounding scale {errors.tolist()})")
    return errors, ~(stiffness > tol)


def check_held_modes(stiffness: np.ndarray, modes: np.ndarray, K: np.ndarray) -> np.ndarray:
    """The rounding scale of each modal eigenvalue; refuse a mode that no spring holds.

    :func:`classify_modes` for paths that need K positive definite.

    Raises
    ------
    ParameterError
        When a mode is not held (K not positive definite relative to M).
    """
    errors, free = classify_modes(stiffness, modes, K)
    if np.any(free):
        raise ParameterError(f"K must be positive definite relative to M; got modal "
                             f"eigenvalues {stiffness.tolist()} (rounding scale "
                             f"{errors.tolist()}): a mode that nothing holds: support the "
                             "chain, e.g. a spring from mass 1 to the frame")
    return errors


@dataclasses.dataclass(frozen=True, eq=False)
class ModalBasis:
    """Mass-normalised modes of ``K u = lambda M u`` with proportional damping.

    Attributes
    ----------
    u : ndarray, shape (n, n)
        Modal matrix, columns are modes, ``u.T M u = I``.
    u_inv : ndarray, shape (n, n)
        ``u^{-1} = u.T M``.
    natural_frequencies : ndarray, shape (n,)
        ``omega_i = sqrt(lambda_i)``, ascending.
    decay_rates : ndarray, shape (n,)
        ``a_i = xi_i omega_i = (alpha + beta omega_i^2) / 2``.
    modal_forces : ndarray, shape (n,)
        ``f_i = u.T F`` (eq. 6).
    eigenvalue_errors : ndarray, shape (n,)
        Rounding-error scale of ``omega_i^2``: ``eps |u_i|^T |K| |u_i|`` (componentwise,
        so that graded stiff chains are not charged ``eps * max omega^2`` on every mode).
    free : ndarray of bool, shape (n,)
        The free (rigid-body) modes, ``K u_i = 0``: their ``omega_i`` is exactly 0 (the
        eigenvalue rounding, of either sign, is clamped against ``eigenvalue_errors``).
    """

    u: np.ndarray
    u_inv: np.ndarray
    natural_frequencies: np.ndarray
    decay_rates: np.ndarray
    modal_forces: np.ndarray
    eigenvalue_errors: np.ndarray | None = None
    free: np.ndarray | None = None

    def __post_init__(self) -> None:
        if self.free is None:
            object.__setattr__(self, "free", np.zeros(self.natural_frequencies.shape, bool))

    @classmethod
    def from_matrices(cls, M: np.ndarray, K: np.ndarray, alpha: float, beta: float,
                      F: np.ndarray) -> ModalBasis:
        """Solve the generalised eigenproblem and mass-normalise (eq. 5).

        K may be positive semi-definite: a free mode gets ``omega_i = 0`` exactly
        (:func:`classify_modes`); what holds it is the oscillator's check.
        """
        lam, u = scipy.linalg.eigh(K, M)
        errors, free = classify_modes(lam, u, K)
        lam = np.where(free, 0.0, lam)
        # eigh returns M-orthonormal vectors; fix the sign so that u[0, i] >= 0 (reproducible).
        sign = np.where(u[0] < 0, -1.0, 1.0)
        u = u * sign
        w = np.sqrt(lam)
        return cls(u=u, u_inv=u.T @ M, natural_frequencies=w,
                   decay_rates=0.5 * (alpha + beta * lam), modal_forces=u.T @ F,
                   eigenvalue_errors=errors, free=free)

    @property
    def damping_ratios(self) -> np.ndarray:
        """``xi_i = a_i / omega_i`` (``inf`` for a damped free mode, 0 for an undamped one)."""
        w, a = self.natural_frequencies, self.decay_rates
        with np.errstate(divide="ignore"):
            return np.where(w > 0, a / np.where(w > 0, w, 1.0), np.where(a > 0, np.inf, 0.0))

    @property
    def damped_frequencies(self) -> np.ndarray:
        """``omega_di = omega_i sqrt(1 - xi_i^2)`` for under-damped modes, 0 otherwise."""
        d = (self.natural_frequencies - self.decay_rates) * (
            self.natural_frequencies + self.decay_rates)
        return np.sqrt(np.maximum(d, 0.0))


_DECAY_DIRECTION = {"eta": (0.0, 1.0), "alpha": (0.5, 0.0), "beta": (0.0, 0.5)}
DAMPING_PARAMETERS = tuple(_DECAY_DIRECTION)
"""The damping parameters of proportional damping, which move the decay rates only."""


def decay_rate_derivative(parameter: str, w: np.ndarray) -> np.ndarray:
    """``d a_i / d parameter`` of the decay rates for a damping parameter.

    ``a_i = eta omega_i^2`` (``C = 2 eta K``) and ``a_i = (alpha + beta omega_i^2) / 2``
    (``C = alpha M + beta K``): linear in each parameter, so the derivative is exact at
    every value (the modes themselves do not move).
    """
    p, q = _DECAY_DIRECTION[parameter]
    return p + q * w * w


def free_transfer(w: np.ndarray, a: np.ndarray, t: np.ndarray
                  ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Exact free modal transfer ``W(t)`` of eq. (9), every damping regime.

    Parameters
    ----------
    w : ndarray, shape (n,)
        Natural frequencies ``omega_i > 0``.
    a : ndarray, shape (n,)
        Decay rates ``a_i = xi_i omega_i >= 0``.
    t : ndarray, shape (nt,)
        Times ``>= 0``.

    Returns
    -------
    W11, W12, W21, W22 : ndarray, shape (nt, n)
        Entries of the 2x2 block of each mode at each time:
        ``[y; y'](t) = [[W11, W12], [W21, W22]] [y; y'](0)``.
    """
    t = np.asarray(t, dtype=float)[:, None]
    w = np.asarray(w, dtype=float)
    a = np.asarray(a, dtype=float)
    d = (w - a) * (w + a)  # w_d^2, signed, without cancellation in w^2 - a^2
    ec = np.empty((t.shape[0], w.size))  # exp(-a t) C
    es = np.empty_like(ec)  # exp(-a t) S
    w22 = np.empty_like(ec)

    under = d > 0  # sin(w_d t) / w_d is accurate for any w_d > 0: no series needed
    if np.any(under):
        wd, au = np.sqrt(d[under]), a[under]
        decay = np.exp(-au * t)
        ec[:, under] = decay * np.cos(wd * t)
        es[:, under] = decay * np.sin(wd * t) / wd
        w22[:, under] = ec[:, under] - au * es[:, under]
    critical = d == 0
    if np.any(critical):
        decay = np.exp(-a[critical] * t)
        ec[:, critical] = decay
        es[:, critical] = decay * t
        w22[:, critical] = decay * (1.0 - a[critical] * t)
    over = d < 0
    if np.any(over):
        ao, wo = a[over], w[over]
        k = np.sqrt(-d[over])
        e_slow = np.exp(-(wo * wo / (ao + k)) * t)  # a - k = w^2 / (a + k): no cancellation
        e_fast = np.exp(-(ao + k) * t)
        c_over = 0.5 * (e_slow + e_fast)
        s_over = e_slow * (-np.expm1(-2.0 * k * t)) / (2.0 * k)
        ec[:, over] = c_over
        es[:, over] = s_over
        # C - a S: direct while k t < 1; for k t >= 1 (heavy damping: C and a S nearly
        # equal) as [(1 - a/k) e_slow + (1 + a/k) e_fast] / 2, 1 - a/k = -w^2/((a+k)k)
        split = 0.5 * (-(wo * wo) / ((ao + k) * k) * e_slow + (1.0 + ao / k) * e_fast)
        w22[:, over] = np.where(k * t < 1.0, c_over - ao * s_over, split)

    w11 = ec + a * es
    w21 = -(w * w) * es
    return w11, es, w21, w22


def _phi2(x: np.ndarray) -> np.ndarray:
    """``2 (x + expm1(-x)) / x^2`` (1 at 0), without cancellation at small x."""
    x = np.asarray(x, dtype=float)
    out = np.empty_like(x)
    small = np.abs(x) < 0.5
    if np.any(small):  # 2 sum_k (-x)^k / (k + 2)!, 20 terms: converged to eps for |x| < 1/2
        xs = -x[small]
        acc = np.zeros_like(xs)
        for k in range(20, -1, -1):
            acc = acc * xs + 2.0 / math.factorial(k + 2)
        out[small] = acc
    big = ~small
    xb = x[big]
    out[big] = 2.0 * (xb + np.expm1(-xb)) / (xb * xb)
    return out


def _psi1(x: np.ndarray) -> np.ndarray:
    """``-expm1(-x) / x`` (1 at 0)."""
    x = np.asarray(x, dtype=float)
    safe = np.where(x == 0.0, 1.0, x)
    return np.where(x == 0.0, 1.0, -np.expm1(-safe) / safe)


def static_response(w: np.ndarray, a: np.ndarray, g: np.ndarray, free: np.ndarray,
                    t: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The modal response to a constant force ``g`` (eq. 1 with ``F_static``), exact.

    Each mode obeys ``y'' + 2 a y' + w^2 y = ... + g``; its state is
    ``[y; y'](t) = Q + W(t) ([y; y'](0) - Q) + S(t)`` with

    - a held mode (``w > 0``): the constant offset ``Q = [g / w^2; 0]``, ``S = 0``;
    - a free mode (``w = 0``): ``Q = 0`` and the response from rest
      ``S(t) = [g t^2 phi(2 a t) / 2; g t psi(2 a t)]``, ``phi(x) = 2 (x - 1 + e^-x) / x^2``,
      ``psi(x) = (1 - e^-x) / x``: ``g t^2 / 2`` undamped, the drift ``g t / (2 a)`` in
      the long run when damped, in a form free of cancellation at every ``a t``.

    Parameters
    ----------
    w, a, g : ndarray, shape (n,)
        Natural frequencies, decay rates and modal static forces ``u^T F_static``.
    free : ndarray of bool, shape (n,)
    t : ndarray, shape (nt,)

    Returns
    -------
    offset : ndarray, shape (n,)
        ``g / w^2`` of the held modes, 0 for the free ones (``Q``'s displacement).
    s_y, s_v : ndarray, shape (nt, n)
        ``S(t)``: zero for the held modes.
    """
    t = np.atleast_1d(np.asarray(t, dtype=float))[:, None]
    w = np.asarray(w, dtype=float)
    if not np.any(g):  # no constant force (the paper's machine): nothing to compute
        return np.zeros(w.size), np.zeros((t.shape[0], w.size)), np.zeros((t.shape[0], w.size))
    offset = np.where(free, 0.0, g / np.where(free, 1.0, w * w))
    gf = np.where(free, g, 0.0)
    x = 2.0 * a * t
    s_y = 0.5 * gf * t * t * _phi2(x)
    s_v = gf * t * _psi1(x)
    return offset, s_y, s_v


def forced_coefficients(w: np.ndarray, a: np.ndarray, f: np.ndarray, omega: float, *,
                        eigenvalue_errors: np.ndarray | None = None
                        ) -> tuple[np.ndarray, np.ndarray]:
    """Steady forced amplitudes ``gamma_i, beta_i`` of eq. (7).

    ``y_p = phi cos(delta) + psi sin(delta)`` with
    ``phi = gamma cos(omega t) + beta sin(omega t)``,
    ``psi = beta cos(omega t) - gamma sin(omega t)``.

    A complex modal force ``f = f_r + i f_i`` (forcing ``Re(f e^{i(omega t + delta)})``,
    per-mass phases) gives ``gamma = (detune f_r + damp f_i) / Delta_i`` and
    ``beta = (damp f_r - detune f_i) / Delta_i`` (``detune = omega_i^2 - omega^2``,
    ``damp = 2 xi_i omega_i omega``): the same real form of ``y_p``.

    Parameters
    ----------
    w, a, f : ndarray, shape (n,)
        Natural frequencies, decay rates and modal forces (f real or complex).
    omega : float or ndarray broadcasting against (n,)
        Forcing frequency.
    eigenvalue_errors : ndarray, shape (n,), optional
        Rounding-error scale of ``w_i^2`` (:attr:`ModalBasis.eigenvalue_errors`); when
        given, a near-resonance that this error makes inexact warns.

    Raises
    ------
    ResonanceError
        If an undamped, forced mode has ``omega_i == omega`` (``Delta_i = 0``).

    Warns
    -----
    NearResonanceWarning
        If omega is so close to the natural frequency of a lightly damped, forced
        mode that its amplitude is known to worse than 1e-8 (relative): the
        error of ``omega_i^2`` times ``|omega_i^2 - omega^2| / Delta_i``.
    """
    detune = (w - omega) * (w + omega)
    damp = 2.0 * a * omega
    delta = detune * detune + damp * damp
    resonant = (delta == 0.0) & (f != 0.0)
    if np.any(resonant):
        i = int(np.flatnonzero(resonant)[0])
        raise ResonanceError(
            f"omega={omega!r} equals the natural frequency {w[i]!r} of undamped mode {i + 1}: "
            "the forced response of eq. (6) does not exist; choose omega != omega_i or add damping"
        )
    safe = np.where(delta == 0.0, 1.0, delta)
    if np.iscomplexobj(f):  # per-mass phases: Re(f e^{i theta}) = f_r cos - f_i sin
        fr, fi = f.real, f.imag
        out = (detune * fr + damp * fi) / safe, (damp * fr - detune * fi) / safe
        f = np.abs(f)  # the size of the force, for the accuracy warning below
    else:
        out = detune * f / safe, damp * f / safe
    # omega_i^2 carries an absolute error ~ eigenvalue_errors from the eigensolver; the
    # amplitude f / sqrt(Delta_i) then has relative error ~ that * |detune| / Delta_i, which
    # grows without bound at an undamped resonance: say so rather than return it silently
    if eigenvalue_errors is None:
        return out
    scale = 4.0 * eigenvalue_errors + 4.0 * np.finfo(float).eps * w * w
    rel_error = np.where(f != 0.0, scale * np.abs(detune) / safe, 0.0)
    worst = float(np.max(rel_error, initial=0.0))
    if worst > _RESONANCE_REL_ERROR_WARN:
        i = np.unravel_index(int(np.argmax(rel_error)), rel_error.shape)
        w_i = float(np.broadcast_to(w, rel_error.shape)[i])
        om_i = float(np.broadcast_to(omega, rel_error.shape)[i])
        warnings.warn(
            f"omega={om_i!r} is within {abs(om_i / w_i - 1.0):.2g} (relative) of the natural "
            f"frequency {w_i!r} of a lightly damped mode: its forced amplitude (eq. 7) is known "
            f"only to a relative error of about {worst:.1g}; move omega away from omega_i or "
            "add damping", NearResonanceWarning, stacklevel=2)
    return out
