"""Modal decomposition and the exact modal transfer of eq. (5)-(10).

Each mode obeys ``y'' + 2 a y' + w^2 y = f cos(omega t + delta)`` with
``w = omega_i`` (natural frequency) and ``a = xi_i omega_i``. Its free
transfer over a time ``t`` is the 2x2 matrix

    W(t) = exp(-a t) [[C + a S, S], [-w^2 S, C - a S]]

with ``C = cos(w_d t)``, ``S = sin(w_d t) / w_d`` and ``w_d^2 = w^2 - a^2``
(eq. 9; the paper's ``g/w_d`` and ``h``). Writing ``z = w_d^2 t^2``,
``C`` and ``S/t`` are entire functions of ``z``, so one formula serves the
undamped, under-, critically and over-damped cases:

- ``|z| <= 1``: Taylor series in ``z`` (exact through ``xi = 1``, no
  cancellation, no division by a small ``w_d``);
- ``z > 1``: the trigonometric form;
- ``z < -1`` (over-damped): the two real exponentials
  ``exp(-(a -+ k) t)`` with ``a - k = w^2 / (a + k)``, which never overflow
  and have no cancellation however heavy the damping.
"""

from __future__ import annotations

import dataclasses

import numpy as np
import scipy.linalg

from impactcont.errors import ParameterError, ResonanceError

__all__ = ["ModalBasis", "forced_coefficients", "free_transfer"]

_SERIES_TERMS = 14  # |z| <= 1: 1/(2*14)! < 1e-29


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
    """

    u: np.ndarray
    u_inv: np.ndarray
    natural_frequencies: np.ndarray
    decay_rates: np.ndarray
    modal_forces: np.ndarray

    @classmethod
    def from_matrices(cls, M: np.ndarray, K: np.ndarray, alpha: float, beta: float,
                      F: np.ndarray) -> ModalBasis:
        """Solve the generalised eigenproblem and mass-normalise (eq. 5)."""
        lam, u = scipy.linalg.eigh(K, M)
        if np.any(lam <= 0):
            raise ParameterError(f"K must be positive definite relative to M; got modal "
                                 f"eigenvalues {lam.tolist()}")
        # eigh returns M-orthonormal vectors; fix the sign so that u[0, i] >= 0 (reproducible).
        sign = np.where(u[0] < 0, -1.0, 1.0)
        u = u * sign
        w = np.sqrt(lam)
        return cls(u=u, u_inv=u.T @ M, natural_frequencies=w,
                   decay_rates=0.5 * (alpha + beta * lam), modal_forces=u.T @ F)

    @property
    def damping_ratios(self) -> np.ndarray:
        """``xi_i = a_i / omega_i``."""
        return self.decay_rates / self.natural_frequencies

    @property
    def damped_frequencies(self) -> np.ndarray:
        """``omega_di = omega_i sqrt(1 - xi_i^2)`` for under-damped modes, 0 otherwise."""
        d = (self.natural_frequencies - self.decay_rates) * (
            self.natural_frequencies + self.decay_rates)
        return np.sqrt(np.maximum(d, 0.0))


def _series(z: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """``cos(sqrt z)`` and ``sin(sqrt z)/sqrt z`` by Taylor series, ``|z| <= 1``."""
    c = np.ones_like(z)
    s = np.ones_like(z)
    term_c = np.ones_like(z)
    term_s = np.ones_like(z)
    for k in range(1, _SERIES_TERMS):
        term_c = term_c * (-z) / ((2 * k - 1) * (2 * k))
        term_s = term_s * (-z) / ((2 * k) * (2 * k + 1))
        c = c + term_c
        s = s + term_s
    return c, s


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
    w = np.asarray(w, dtype=float)[None, :]
    a = np.asarray(a, dtype=float)[None, :]
    d = (w - a) * (w + a)  # w_d^2, signed, without cancellation in w^2 - a^2
    z = d * t * t
    shape = z.shape
    ec = np.empty(shape)  # exp(-a t) C
    es = np.empty(shape)  # exp(-a t) S
    w22 = np.empty(shape)

    series = np.abs(z) <= 1.0
    trig = (~series) & (d > 0)
    hyper = (~series) & (d < 0)

    if np.any(series):
        zs = z[series]
        ts = np.broadcast_to(t, shape)[series]
        as_ = np.broadcast_to(a, shape)[series]
        c, s = _series(zs)
        decay = np.exp(-as_ * ts)
        ec[series] = decay * c
        es[series] = decay * ts * s
        w22[series] = ec[series] - as_ * es[series]
    if np.any(trig):
        tt = np.broadcast_to(t, shape)[trig]
        at = np.broadcast_to(a, shape)[trig]
        wd = np.sqrt(np.broadcast_to(d, shape)[trig])
        decay = np.exp(-at * tt)
        ec[trig] = decay * np.cos(wd * tt)
        es[trig] = decay * np.sin(wd * tt) / wd
        w22[trig] = ec[trig] - at * es[trig]
    if np.any(hyper):
        th = np.broadcast_to(t, shape)[hyper]
        ah = np.broadcast_to(a, shape)[hyper]
        wh = np.broadcast_to(w, shape)[hyper]
        k = np.sqrt(-np.broadcast_to(d, shape)[hyper])
        slow = wh * wh / (ah + k)  # a - k, no cancellation
        e_slow = np.exp(-slow * th)
        e_fast = np.exp(-(ah + k) * th)
        ec[hyper] = 0.5 * (e_slow + e_fast)
        es[hyper] = e_slow * (-np.expm1(-2.0 * k * th)) / (2.0 * k)
        # C - a S = [(1 - a/k) e_slow + (1 + a/k) e_fast] / 2 with 1 - a/k = -w^2/((a+k)k)
        w22[hyper] = 0.5 * (-(wh * wh) / ((ah + k) * k) * e_slow + (1.0 + ah / k) * e_fast)

    w11 = ec + a * es
    w12 = es
    w21 = -(w * w) * es
    return w11, w12, w21, w22


def forced_coefficients(w: np.ndarray, a: np.ndarray, f: np.ndarray, omega: float
                        ) -> tuple[np.ndarray, np.ndarray]:
    """Steady forced amplitudes ``gamma_i, beta_i`` of eq. (7).

    ``y_p = phi cos(delta) + psi sin(delta)`` with
    ``phi = gamma cos(omega t) + beta sin(omega t)``,
    ``psi = beta cos(omega t) - gamma sin(omega t)``.

    Raises
    ------
    ResonanceError
        If an undamped, forced mode has ``omega_i == omega`` (``Delta_i = 0``).
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
    return detune * f / safe, damp * f / safe
