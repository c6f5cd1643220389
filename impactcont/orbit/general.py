"""Periodic N-1 motions with any damping matrix C or complex F: the dense exact path.

The proportional system's closed form (:mod:`impactcont.kernel.closed_form`) relies on the
real 2x2 modal blocks of eq. (9). With a general damping matrix C, or with forcing
phases that differ between masses (complex F), the same equations are solved from the
first-order complex modes ``A = V diag(lambda) V^-1``
(:class:`impactcont.model.first_order.FirstOrderBasis`), still in closed form and in
the kernel's rank-one form (:class:`PeriodicForm`):

- the impact (eq. 4) changes only ``x1'``: ``D = I - kappa e e^T`` (``e = e_{n+1}``,
  ``kappa = 1 + R``), so eq. (12)-(13) give ``X(0) = P(0) e_d + kappa sigma y`` with
  ``P(0) = [Re Z, -Im Z]`` the forced state's columns, ``e_d = [cos delta, sin delta]``,
  ``sigma = x1'(T^-)`` the impact velocity and ``y = -(I - Phi(T))^-1 e``;
- ``y = V diag(1/expm1(lambda T)) V^-1 e = A^-1 e / T - e / 2 + Re(V diag(s(lambda T))
  V^-1 e)`` with the bounded ``s`` of :func:`impactcont.model.first_order.coth_remainder`:
  the large ``1/(lambda T)`` terms of a high forcing frequency sum to ``A^-1 e / T``
  exactly instead of cancelling in floating point (``Phi(T) - I`` and ``(I - Phi) P(0)``
  likewise from ``expm1``);
- eq. (14): ``c, s = Gam - rho B, B + rho Gam`` with ``Gam - i B = Z_1``,
  ``rho = kappa omega g / Delta``, ``g = -y_1``, ``Delta = (1 - R)/2 - kappa Re(V_{n+1}
  diag(s) V^-1 e)``; eq. (15) for the phases;
- ``sigma`` from the better of its two exact forms
  (:func:`impactcont.orbit.dense.impact_velocity`), then ``X(0)``, and G of eq. (25)
  from ``D Phi(T)``, ``D (I - Phi(T)) P(0)`` and ``X'(T^-) = P'(0) e_d + kappa sigma
  A (y + e)``; its eigenvalues as the kernel's (:func:`impactcont.kernel.stability.
  multipliers`: QR of the balanced Hessenberg form for small G, LAPACK otherwise);
- eq. (16) by the kernel's search (:func:`impactcont.kernel.contact.x1_maximum`) on the
  scalar pairs of modes (:attr:`FirstOrderBasis.scalar_pairs`);
- the condition estimate of eq. (12) is the kernel's, summed over the scalar pairs of
  modes, so both paths warn alike.

All of it runs compiled (:mod:`impactcont.kernel.general`: one call for the
pieces of a frequency, :func:`periodic_form`, and one for the motions of its roots,
:func:`orbit_values`); :func:`reference_form` and :func:`reference_orbit_values` are
the same equations in numpy, kept as the reference the tests compare with. The
parameter derivatives of ``c, s`` used by continuation are exact too
(:func:`amplitude`).
"""

from __future__ import annotations

import dataclasses
import functools
import math
import types
import warnings
import weakref

import numpy as np

from impactcont.errors import ParameterError, UnresolvedMotionWarning
from impactcont.kernel.arrays import FirstOrderArrays
from impactcont.model.first_order import FirstOrderBasis, coth_remainder
from impactcont.model.oscillator import ImpactOscillator
from impactcont.orbit.dense import (
    impact_velocity,
    second_form,
    velocity_errors,
    warn_ill_conditioned,
)
from impactcont.orbit.flow import GeneralFlow, flow_of

__all__ = ["PeriodicForm", "amplitude", "amplitude_derivative", "orbit_pieces",
           "orbit_values", "orbit_values_many", "periodic_form", "phase_matrices", "roots",
           "x1_maximum"]


def _refuse_elastic(osc: ImpactOscillator) -> None:
    """Refuse ``R = 1`` without damping: ``I - D Phi(T)`` of eq. (12) is singular there.

    The modal path solves that case (a family of motions, :mod:`impactcont.kernel.closed_form`);
    the message names what put the oscillator on the first-order path instead: a damping
    matrix ``C = 0`` (give ``eta=0``), or a complex F (per-mass phases).
    """
    if osc.R != 1.0 or np.any(osc.C):
        return
    why, fix = [], []
    if osc.general_damping:
        why.append(f"the damping matrix C={osc.C.tolist()} (given as a matrix)")
        fix.append("give the undamped case as eta=0 instead of C")
    if osc.F.dtype.kind == "c":
        why.append(f"the complex F={osc.F.tolist()} (per-mass phases)")
        fix.append("a real F")
    raise ParameterError(
        f"R=1.0 without damping is singular on the first-order path of eq. (1) (taken for "
        f"{' and '.join(why)}): eq. (12) has no unique solution for elastic impacts without "
        f"damping. Use R < 1, add damping, or {' and '.join(fix)}: the modal path solves "
        "that case")


@dataclasses.dataclass(frozen=True, eq=False)
class PeriodicForm:
    """Eq. (12)-(15) at one frequency in the impact's rank-one form (see the module).

    ``X(0) = P0 e_d + kappa sigma y`` and ``sigma = P0[n] e_d / Delta``
    (``e_d = [cos delta, sin delta]``); ``S = P0 + kappa y (P0[n] / Delta)`` of eq. (13).
    """

    flow: GeneralFlow
    T: float
    DPhi: np.ndarray
    """``D Phi(T)`` (2n, 2n), ``Phi(T) = I + Re(V diag(expm1(lambda T)) V^-1)``."""
    P0: np.ndarray
    """``[Re Z, -Im Z]`` (2n, 2): the forced state ``P0 e_d`` at the impact."""
    rate0: np.ndarray
    """``[Re(i omega Z), -Im(i omega Z)]`` (2n, 2): its time derivative."""
    E: np.ndarray
    """``(I - Phi(T)) P0`` (2n, 2): the forcing columns of eq. (9) over a period."""
    y: np.ndarray
    """``-(I - Phi(T))^-1 e_{n+1}`` (2n,): the free deviation per unit ``kappa sigma``."""
    y_modal: np.ndarray
    """``V^-1 y = diag(1/expm1(lambda T)) V^-1 e_{n+1}`` (2n,), complex."""
    rate: np.ndarray
    """``A (y + e_{n+1})`` (2n,): the free deviation's derivative before the impact."""
    g: float
    Delta: float
    cond: float
    """The kernel's condition estimate of eq. (12) (relative error about ``cond * eps``)."""
    S: np.ndarray
    """``X(0) = S e_d`` (2n, 2), eq. (13)."""
    # Two private attributes come with the form (set in its __dict__, not fields, so that
    # a form made any other way has none): ``_period_rate``, ``Re(V diag(lambda
    # s'(lambda T)) V^-1 e_{n+1})`` at rows 1 and n+1 (with ``-A^-1 e_{n+1} / T^2`` the
    # T-derivative of ``y`` there, :func:`amplitude_derivative`), and ``_pieces``, the
    # real fields as the rows of :func:`impactcont.kernel.general.periodic_setup`
    # (the fields are views of it).

    def __getattr__(self, name: str) -> np.ndarray:
        """The real fields of a compiled form, made on first access as views of its
        ``_pieces`` (:func:`impactcont.kernel.general.form_rows`): most motions never
        read them (the compiled orbit takes the pieces whole)."""
        pieces = self.__dict__.get("_pieces")
        rows = _FIELD_ROWS.get(name)
        if pieces is None or rows is None:
            raise AttributeError(f"{type(self).__name__!r} object has no attribute {name!r}")
        m = pieces.shape[1]
        start, stop = rows
        view = pieces[m + start:m + stop].T if stop - start == 2 else (
            pieces[:m] if start < 0 else pieces[m + start])
        self.__dict__[name] = view
        return view

    def _orbit_arguments(self) -> tuple:
        """The arguments of :func:`impactcont.kernel.general.orbit_values` before
        the phases and gaps."""
        flow = self.flow
        lam, V0, pw, pa, pk, pj = _first_order_arrays(flow.basis).contact_arguments()
        pieces, y_modal = self.__dict__.get("_pieces"), self.y_modal
        if pieces is None:  # a form built in numpy (reference_form)
            pieces = np.vstack([self.DPhi, self.P0.T, self.rate0.T, self.E.T, self.S.T,
                                self.y, self.rate])
            y_modal = np.ascontiguousarray(y_modal)
        return (pieces, y_modal, V0, lam, pw, pa, pk, pj, float(flow.osc.omega),
                float(flow.osc.R), self.T, self.g, self.Delta)

    @functools.cached_property
    def c(self) -> float:
        """``c`` of eq. (14)."""
        return float(self.S[0, 0])

    @functools.cached_property
    def s(self) -> float:
        """``s`` of eq. (14)."""
        return float(self.S[0, 1])

    def velocity(self, deltas: np.ndarray, b: np.ndarray | float
                 ) -> tuple[np.ndarray, np.ndarray]:
        """Impact velocities and their relative error estimates at the phases ``deltas``
        (roots of eq. 15 at the gaps ``b``): :func:`impactcont.orbit.dense.impact_velocity`."""
        osc = self.flow.osc
        return impact_velocity(float(self.P0[0, 0]), float(self.P0[0, 1]), self.g, self.Delta,
                               osc.omega, osc.R, b, deltas)


    def velocity_at(self, delta: float, b: float) -> tuple[float, float]:
        """:meth:`velocity` at one phase, in scalar arithmetic (no array overhead)."""
        osc = self.flow.osc
        Gam, B = self.P0[0].tolist()
        cd, sd = math.cos(delta), math.sin(delta)
        err_a, err_b = velocity_errors(Gam, B, self.g, self.Delta, osc.omega, osc.R, b, delta,
                                       cd, sd)
        first = osc.omega * (B * cd - Gam * sd) / self.Delta if self.Delta else math.inf
        if err_b < err_a and self.g:
            second = (Gam * cd + B * sd - b) / ((1.0 + osc.R) * self.g)
            if second_form(first, second, err_a, err_b):
                return second, err_b / max(abs(second), 1e-300)
        return first, err_a / max(abs(first), 1e-300)


# the real fields of PeriodicForm as the rows of general_kernel.periodic_setup's pieces,
# (start, stop) after the first 2n rows (D Phi: (-1, 0)); two rows are a field's columns
_FIELD_ROWS = {"DPhi": (-1, 0), "P0": (0, 2), "rate0": (2, 4), "E": (4, 6), "S": (6, 8),
               "y": (8, 9), "rate": (9, 10)}

# the form of the last periodic_form call per flow, for the pieces that callers keep as
# (flow, S, DPhi, T) (phase_matrices, amplitude_derivative), while the form is in use:
# keyed by the flow's identity (the form holds its flow, so the key is unique while the
# entry lives) and weak in the form, so that a form nobody holds is released (a weak key
# would be kept alive by its own value, the form, for the life of the process)
_FORMS: weakref.WeakValueDictionary[int, PeriodicForm] = weakref.WeakValueDictionary()


def periodic_form(osc: ImpactOscillator, N: int, *, warn: bool = True) -> PeriodicForm:
    """Eq. (12)-(14) of the N-1 motions at the oscillator's parameters (first-order path).

    Warns (:class:`~impactcont.errors.IllConditionedWarning`) when the condition
    estimate exceeds :data:`impactcont.orbit.dense.COND_WARN`, unless ``warn=False``
    (the caller reports :attr:`PeriodicForm.cond` itself).

    Raises
    ------
    ParameterError
        ``R = 1`` without damping (eq. 12 singular on this path).
    ResonanceError
        omega at the natural frequency of an undamped mode (no forced response).
    """
    _refuse_elastic(osc)
    flow = flow_of(osc)
    form = _form_at(flow, 2.0 * math.pi * N / osc.omega)
    if warn:
        warn_ill_conditioned(osc.omega, form.cond, stacklevel=2)
    return form


def _form_at(flow: GeneralFlow, T: float) -> PeriodicForm:
    """:class:`PeriodicForm` of `flow` over the period ``T`` (``omega T = 2 pi N``), by
    :func:`impactcont.kernel.general.periodic_setup` (:func:`reference_form` is
    its numpy form)."""
    cached = _FORMS.get(id(flow))
    if cached is not None and cached.flow is flow and cached.T == T:
        return cached
    osc = flow.osc
    omega, R, T = float(osc.omega), float(osc.R), float(T)
    fa = _first_order_arrays(flow.basis)
    kernel = _compiled()
    pieces, y_modal, sc = kernel.periodic_setup(fa.lam, fa.V, fa.V_inv, fa.A, fa.impact_column,
                                                fa.k_p, fa.j_p, flow.Z, omega, R, T)
    m = fa.lam.size
    if m >= kernel.BLAS_MIN:  # D Phi(T) by BLAS, O(n^3)
        pieces[:m] = _transition(flow.basis, T, R)
    g, Delta, cond, d0, dn, c, s = sc.tolist()
    form = object.__new__(PeriodicForm)  # without the frozen __init__'s cost; the real
    form.__dict__.update(flow=flow, T=T, y_modal=y_modal, g=g, Delta=Delta, cond=cond,
                         c=c, s=s, _period_rate=(d0, dn), _pieces=pieces)  # fields: views
    _FORMS[id(flow)] = form
    return form


@functools.cache
def _first_order_arrays(basis: FirstOrderBasis) -> FirstOrderArrays:
    """The basis's kernel arrays by name (:class:`~impactcont.kernel.arrays.FirstOrderArrays`;
    ``_make`` of a FirstOrderArrays is itself, of the basis's plain tuple names its fields)."""
    return FirstOrderArrays._make(basis.kernel_arrays)


def _compiled() -> types.ModuleType:
    """:mod:`impactcont.kernel.general`, imported on first use (numba loads it)."""
    from impactcont.kernel import general as general_kernel

    return general_kernel


def reference_form(flow: GeneralFlow, T: float) -> PeriodicForm:
    """:class:`PeriodicForm` of `flow` over the period ``T`` in numpy: the reference of
    the compiled :func:`impactcont.kernel.general.periodic_setup` (not cached)."""
    osc, basis = flow.osc, flow.basis
    n, R, omega = osc.n, osc.R, osc.omega
    kappa = 1.0 + R
    lam, V, Vi = basis.eigenvalues, basis.V, basis.V_inv
    x = lam * T
    em1 = np.expm1(x)
    w = Vi[:, n]  # V^-1 e_{n+1}
    sw = coth_remainder(x) * w
    part = (V @ sw).real
    y = basis.impact_column / T + part
    y[n] -= 0.5
    Delta = 0.5 * (1.0 - R) - kappa * float(part[n])
    g = -float(y[0])
    Z = flow.Z
    P0 = np.column_stack([Z.real, -Z.imag])
    iwZ = 1j * omega * Z
    rate0 = np.column_stack([iwZ.real, -iwZ.imag])
    E = -(V @ (em1[:, None] * (Vi @ P0))).real
    DPhi = _transition(basis, T, R)
    with np.errstate(divide="ignore", invalid="ignore"):
        y_modal = w / em1
    e = np.zeros(2 * n)
    e[n] = 1.0
    rate = basis.A @ (y + e)
    with np.errstate(divide="ignore", invalid="ignore"):
        S = P0 + kappa * np.outer(y, P0[n] / Delta)
    cond = _condition(basis, x, em1, sw, w, R, omega, g, Delta)
    d_rate = (V @ (lam * coth_remainder(x, derivative=True) * w)).real
    form = PeriodicForm(flow=flow, T=T, DPhi=DPhi, P0=P0, rate0=rate0, E=E, y=y,
                        y_modal=y_modal, rate=rate, g=g, Delta=Delta, cond=cond, S=S)
    form.__dict__["_period_rate"] = (float(d_rate[0]), float(d_rate[n]))
    return form


def _transition(basis: FirstOrderBasis, T: float, R: float) -> np.ndarray:
    """``D Phi(T) = D (I + Re(V diag(expm1(lambda T)) V^-1))`` (2n, 2n) by numpy (BLAS)."""
    m = basis.eigenvalues.size
    d = np.ones(m)
    d[m // 2] = -R
    em1 = np.expm1(basis.eigenvalues * T)
    return d[:, None] * (np.eye(m) + ((basis.V * em1) @ basis.V_inv).real)


def _condition(basis, x: np.ndarray, em1: np.ndarray, sw: np.ndarray, w: np.ndarray,
               R: float, omega: float, g: float, Delta: float) -> float:
    """The kernel's condition estimate of eq. (12) (:func:`impactcont.kernel.closed_form.
    omega_setup`) from the scalar pairs of modes: ``mode_cond (1 + |rho| (cond_d +
    cond_g))``, ``cond_d = ((1 - R)/2 + kappa sum |c_i h_i|) / |Delta|``, ``cond_g =
    sum |c_i W12_i / d_i| / |g|``, ``mode_cond`` the worst free-mode resonance
    ``1 + omega_d T |Im e^{lambda T}| / |expm1(lambda T)|^2`` of a mode that moves mass 1.
    For proportional damping each pair is one real mode and the terms are the kernel's."""
    n = basis.M.shape[0]
    V, Vi = basis.V, basis.V_inv
    _, _, k, j = basis.scalar_pairs
    kappa = 1.0 + R
    with np.errstate(divide="ignore", invalid="ignore"):
        ci = (V[0, k] * Vi[k, 0] + V[0, j] * Vi[j, 0]).real
        hi = (V[n, k] * sw[k] + V[n, j] * sw[j]).real
        gi = (V[0, k] * w[k] / em1[k] + V[0, j] * w[j] / em1[j]).real
        resonance = 1.0 + np.abs(x[k].imag) * np.abs(em1[k].imag) / np.abs(em1[k]) ** 2
    coupled = (x[k].imag != 0.0) & (np.abs(ci) > 1e-12 * np.abs(ci).sum())
    mode_cond = float(np.max(resonance[coupled], initial=1.0))
    rho = kappa * omega * g / max(abs(Delta), 1e-300)
    cond_d = (0.5 * (1.0 - R) + kappa * float(np.abs(hi).sum())) / max(abs(Delta), 1e-300)
    cond_g = float(np.abs(gi).sum()) / max(abs(g), 1e-300)
    cond = mode_cond * (1.0 + abs(rho) * (cond_d + cond_g))
    return cond if math.isfinite(cond) else math.inf


def orbit_pieces(osc: ImpactOscillator, N: int) -> tuple[GeneralFlow, np.ndarray, np.ndarray,
                                                             float]:
    """The flow, ``S`` (2n, 2), ``D Phi(T)`` and ``T`` of eq. (12)-(13) at the oscillator's
    parameters (:func:`periodic_form`)."""
    form = periodic_form(osc, N)
    return form.flow, form.S, form.DPhi, form.T


def amplitude(osc: ImpactOscillator, N: int, which: str | None = None
              ) -> tuple[float, float, float, float]:
    """``c, s`` of eq. (14) and their exact derivative in ``which`` (``"omega"``, ``"R"``).

    With ``rho = kappa omega g / Delta`` (:class:`PeriodicForm`), ``c = Gam - rho B``,
    ``s = B + rho Gam``: ``Gam - i B = Z_1`` moves with omega through the dynamic
    stiffness (:meth:`FirstOrderBasis.forced_amplitude_derivative`), ``g`` and ``Delta``
    through ``T = 2 pi N / omega`` (``s'`` of :func:`coth_remainder`), ``Delta`` with R
    (``d Delta / d R = -1/2 - Re(V_{n+1} diag(s) V^-1 e)``).

    Returns
    -------
    c, s, dc, ds : float
        ``dc = ds = 0`` when `which` is None.

    Notes
    -----
    Computed in O(n) after the forced amplitude
    (:func:`impactcont.kernel.general.amplitude_setup`: the scalars of
    :func:`periodic_form`, equal to its ``c, s``); warns as :func:`periodic_form`.
    """
    _refuse_elastic(osc)
    flow = flow_of(osc)
    T = 2.0 * math.pi * N / osc.omega
    fa = _first_order_arrays(flow.basis)
    g, Delta, cond, d0, dn, c, s = _compiled().amplitude_setup(
        fa.lam, fa.V, fa.V_inv, fa.impact_column, fa.k_p, fa.j_p, flow.Z, float(osc.omega),
        float(osc.R), T).tolist()
    warn_ill_conditioned(osc.omega, cond, stacklevel=1)
    if which is None:
        return c, s, 0.0, 0.0
    return (c, s, *_cs_derivative(flow, T, g, Delta, (d0, dn), which))


def amplitude_derivative(flow: GeneralFlow, S: np.ndarray, DPhi: np.ndarray, T: float,
                         which: str) -> tuple[float, float]:
    """``dc, ds`` (eq. 14) in ``which`` (``"omega"``, ``"R"``) at the motion of
    :func:`orbit_pieces` (whose ``S`` and ``D Phi`` are those of ``flow`` at ``T``;
    formulas in :func:`amplitude`)."""
    _check_which(flow.osc, which)
    form = _form_at(flow, float(T))
    return _cs_derivative(flow, float(T), form.g, form.Delta, form.__dict__["_period_rate"],
                          which)


def _check_which(osc: ImpactOscillator, which: str) -> None:
    if which in ("eta", "alpha", "beta"):
        raise ParameterError(
            f"parameter={which!r}: a branch on the first-order path (complex F={osc.F.tolist()}, "
            "per-mass phases) cannot be continued in the damping eta, alpha or beta (eq. 12-14 "
            "have no exact derivative in them there); continue in omega, b, R or F0, follow a "
            f"curve with {which!r} as its second parameter (impactcont.curve), or use a real F")
    if which not in ("omega", "R"):
        raise ParameterError(f"which must be 'omega' or 'R' (the derivative of c, s of eq. 14); "
                             f"got {which!r}")


def _cs_derivative(flow: GeneralFlow, T: float, g: float, Delta: float,
                   period_rate: tuple[float, float], which: str) -> tuple[float, float]:
    """``dc, ds`` in ``which`` from the scalars of eq. (14) at ``T`` (:func:`amplitude`);
    ``period_rate``: the rows 1 and n+1 of ``Re(V diag(lambda s'(lambda T)) V^-1 e)``."""
    _check_which(flow.osc, which)
    osc, basis = flow.osc, flow.basis
    R, omega = osc.R, osc.omega
    kappa = 1.0 + R
    Gam, B = float(flow.Z[0].real), float(-flow.Z[0].imag)
    rho = kappa * omega * g / Delta
    if which == "R":
        part_n = (0.5 * (1.0 - R) - Delta) / kappa  # Re(V_{n+1} diag(s) V^-1 e)
        d_rho = omega * g / Delta - rho * (-0.5 - part_n) / Delta
        return -d_rho * B, d_rho * Gam
    rate_0, rate_n = period_rate
    dT = -T / omega
    d_y0 = (-basis.impact_column[0] / (T * T) + rate_0) * dT
    d_g = -d_y0
    d_Delta = -kappa * rate_n * dT
    dZ = basis.forced_amplitude_derivative(flow.Z, omega)
    d_Gam, d_B = float(dZ[0].real), float(-dZ[0].imag)
    d_rho = kappa * (g + omega * d_g) / Delta - rho * d_Delta / Delta
    return d_Gam - d_rho * B - rho * d_B, d_B + d_rho * Gam + rho * d_Gam


def _pair_coefficients(flow: GeneralFlow, c: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """``y(0), y'(0)`` of each scalar pair (:attr:`FirstOrderBasis.scalar_pairs`) from the
    complex coefficients ``c`` of ``x1``'s free part ``Re sum c e^{lam t}``; ``c`` may
    carry trailing columns (real-linear in them)."""
    _, _, k, j = flow.basis.scalar_pairs
    lam = flow.lam
    conj = (np.abs(lam[k].imag) > 0).reshape((-1,) + (1,) * (c.ndim - 1))
    lk = lam[k].reshape(conj.shape)
    lj = lam[j].reshape(conj.shape)
    # a conjugate pair: Re((c_k + conj c_j) e^{lam_k t}); a real pair: c_k e^.. + c_j e^..
    total = np.where(conj, c[k] + np.conj(c[j]), c[k] + c[j])
    slope = np.where(conj, (c[k] + np.conj(c[j])) * lk, c[k] * lk + c[j] * lj)
    return np.ascontiguousarray(total.real), np.ascontiguousarray(slope.real)


def _search_grid(flow: GeneralFlow, T: float) -> np.ndarray:
    """The kernel's grid on ``[0, T]`` for the x1 search of eq. (16), warning when capped."""
    from impactcont.kernel import contact

    w, a, _, _ = flow.basis.scalar_pairs
    times, capped = contact.time_grid(w, a, np.ones_like(w), flow.omega, T)
    if capped:
        _warn_capped(T, stacklevel=5)
    return times


def _warn_capped(T: float, stacklevel: int) -> None:
    warnings.warn(f"x1 search grid capped at 2000000 cells for a period of {T:.3g}: a short "
                  "excursion of mass 1 past the stop (eq. 16) may be missed",
                  UnresolvedMotionWarning, stacklevel=stacklevel)


def _search(flow: GeneralFlow, times: np.ndarray, free: np.ndarray, dy: np.ndarray,
            dv: np.ndarray, delta: float, exclude: float) -> tuple[float, float]:
    from impactcont.kernel import contact

    w, a, _, _ = flow.basis.scalar_pairs
    work = np.empty((contact.WORK_ROWS, 2 * times.size))
    best, best_t = contact.x1_maximum(times, free, np.cos(flow.omega * times),
                                      np.sin(flow.omega * times), float(flow.Z[0].real),
                                      float(-flow.Z[0].imag), flow.omega, float(delta), 1.0,
                                      w, a, np.ones_like(w), dy, dv, work, float(exclude))
    return float(best), float(best_t)


def _x1_maximum_of(flow: GeneralFlow, coefficients: np.ndarray, delta: float, T: float,
                   exclude: float) -> tuple[float, float]:
    """:func:`x1_maximum` from the complex coefficients of ``x1``'s free part."""
    from impactcont.kernel import contact

    w, a, _, _ = flow.basis.scalar_pairs
    dy, dv = _pair_coefficients(flow, coefficients)
    times = _search_grid(flow, T)
    free = contact.free_on_grid(times, w, a, np.ones_like(w), dy, dv)
    return _search(flow, times, free, dy, dv, delta, exclude)


def x1_maximum(flow: GeneralFlow, state: np.ndarray, delta: float, T: float,
               exclude: float = math.nan) -> tuple[float, float]:
    """Highest interior local maximum of ``x1`` on ``(0, T)`` (eq. 16): ``(value, time)``,
    ``(-inf, nan)`` when there is none. A maximum within ``1e-7 T`` of the time
    ``exclude`` is skipped (NaN: none is), e.g. the tangency of a grazing motion.

    The free part of ``x1`` is a sum over the scalar pairs of
    :attr:`FirstOrderBasis.scalar_pairs`, each ``W11 y(0) + W12 y'(0)`` with the exact
    modal transfer, and the forced part is ``Re(Z_1 e^{i theta})``: the compiled
    kernel's search (:func:`impactcont.kernel.contact.x1_maximum`, with its grid, bounds
    and polish) runs on them unchanged, with unit weights.
    """
    return _x1_maximum_of(flow, flow.V[0] * flow.modal_deviation(state, delta), delta, T,
                          exclude)


def phase_matrices(flow: GeneralFlow, S: np.ndarray, T: float
                   ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The impact-phase-linear pieces of the motion ``X(0) = S e``, ``e = [cos delta,
    sin delta]`` (eq. 13), for G of eq. (22)-(25) and the search of eq. (16), at the
    motion of :func:`orbit_pieces` (``S`` is that of ``flow`` at ``T``):

    - ``J1`` (2n, 2): ``[h1; H1] = D E(T) [-sin delta; cos delta] = J1 e``,
      ``E(T) = (I - Phi(T)) P(0)``;
    - ``Y`` (2n, 2): ``[h2; H2] = D X'(T^-) = Y e``, ``X'(T^-) = P'(0) e + kappa sigma
      A (y + e_{n+1})`` with ``sigma = P(0)[n+1] e / Delta`` (:class:`PeriodicForm`);
    - ``U`` (2n, 2), complex: ``V_1k (V^-1 (S - P(0)))_k``, the coefficients of ``x1``'s
      free part ``Re sum_k (U e)_k e^{lambda_k t}``.
    """
    form = _form_at(flow, float(T))
    osc = flow.osc
    n = osc.n
    kappa = 1.0 + osc.R
    d = np.ones(2 * n)
    d[n] = -osc.R
    sigma_row = form.P0[n] / form.Delta
    Y = d[:, None] * (form.rate0 + kappa * np.outer(form.rate, sigma_row))
    J1 = d[:, None] * np.column_stack([form.E[:, 1], -form.E[:, 0]])  # E [-sin, cos] = J1 e
    U = np.outer(flow.V[0] * form.y_modal, kappa * sigma_row)
    return J1, Y, U


def orbit_values_many(form: PeriodicForm, deltas: np.ndarray, b: np.ndarray
                      ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """:func:`orbit_values` for many impact phases at once, one omega (e.g. the gaps of a
    stability map): ``(h2, multipliers, gap_min, gap_min_time)`` of the motions with
    impact phases ``deltas`` at the gaps ``b`` (each phase a root of eq. 15 at its gap),
    shapes ``(m,)``, ``(m, 2n)`` (largest modulus first), ``(m,)``, ``(m,)``.

    One compiled call (:func:`impactcont.kernel.general.orbit_values`): the search
    tables of eq. (16) are built once per unit impact velocity and shared by every phase.
    """
    deltas = np.array(deltas, dtype=float).reshape(-1)  # new arrays: writable, contiguous
    b = np.array(np.broadcast_to(np.asarray(b, dtype=float), deltas.shape))
    values, _, _, mu = _compiled_values(form, deltas, b)
    return values[0], mu, values[3], values[4]


def _compiled_values(form: PeriodicForm, deltas: np.ndarray, b: np.ndarray) -> tuple:
    """:func:`impactcont.kernel.general.orbit_values` of `form` at the phases
    ``deltas`` and gaps ``b`` (contiguous floats), warning when the search grid of eq.
    (16) was capped."""
    *values, capped = _compiled().orbit_values(*form._orbit_arguments(), deltas, b)
    if capped:
        _warn_capped(form.T, stacklevel=4)
    return tuple(values)


def roots(c: float, s: float, b: float) -> list[tuple[float, int]]:
    """The phases of eq. (15) with their root signs (+1 first), as the kernel orders them."""
    r2 = c * c + s * s
    if r2 == 0.0:
        if b == 0.0:
            raise ParameterError("c = s = 0 and b = 0: every phase satisfies eq. (14); the "
                                 "forcing does not reach mass 1 (check F)")
        return []
    disc = r2 - b * b
    if disc < 0.0:
        return []
    root_r = math.sqrt(disc)
    out = []
    for sg in ((1, -1) if root_r > 0.0 else (1,)):
        sin_d = (b * s + sg * c * root_r) / r2
        cos_d = (b * c - sg * s * root_r) / r2
        out.append((math.atan2(sin_d, cos_d), sg))
    return out


@dataclasses.dataclass(frozen=True)
class OrbitValues:
    """One motion of :func:`orbit_values`."""

    state: np.ndarray
    """``X(0)`` (eq. 13), with ``x1' = -R h2`` exactly (eq. 4)."""
    h2: float
    """The impact velocity ``x1'(T^-)``."""
    h2_error: float
    """Estimated relative error of ``h2`` (:func:`impactcont.orbit.dense.impact_velocity`)."""
    velocity_scale: float
    """``max(|x'|, omega |x|)`` of ``X(0)``: the rounding scale of ``h2`` in G."""
    G: np.ndarray
    multipliers: np.ndarray
    """Eigenvalues of G, largest modulus first."""
    gap_min: float
    gap_min_time: float


def orbit_values(form: PeriodicForm, delta: float) -> OrbitValues:
    """The motion at phase delta (a root of eq. 15) from :func:`periodic_form`: state,
    impact velocity, G, multipliers and eq. (16), by the compiled
    :func:`impactcont.kernel.general.orbit_values` (:func:`reference_orbit_values`
    is its numpy form).

    When delta is one of the roots of eq. (15) at the oscillator's gap (:func:`roots`),
    every root is evaluated in that one call (the search tables of eq. 16 are shared) and
    kept with the form: the other root's motion is then a lookup.
    """
    delta = float(delta)
    pending = form.__dict__.setdefault("_pending", None)
    if pending is not None and delta in pending:
        return pending.pop(delta)  # handed out once: no two motions share arrays
    b = float(form.flow.osc.b)
    phases = [delta]
    if pending is None:  # the first motion asked of this form
        form.__dict__["_pending"] = {}
        r2 = form.c ** 2 + form.s ** 2
        found = [d for d, _ in roots(form.c, form.s, b)] if r2 > 0.0 else []
        if delta in found:
            phases = found
    scalars, states, G, mu = _compiled_values(form, np.array(phases), np.array([b] * len(phases)))
    motions = {}
    for i, (h2, rel, scale, gap, gap_t) in enumerate(zip(*scalars.tolist(), strict=True)):
        values = object.__new__(OrbitValues)  # the fields, without the frozen __init__'s cost
        values.__dict__.update(state=states[i], h2=h2, h2_error=rel, velocity_scale=scale,
                               G=G[i], multipliers=mu[i], gap_min=gap, gap_min_time=gap_t)
        motions[phases[i]] = values
    out = motions.pop(delta)
    form.__dict__["_pending"].update(motions)
    return out


def reference_orbit_values(form: PeriodicForm, delta: float) -> OrbitValues:
    """:func:`orbit_values` in numpy: the reference of the compiled path."""
    flow = form.flow
    osc = flow.osc
    n, R, omega = osc.n, osc.R, osc.omega
    h2, rel = form.velocity_at(float(delta), osc.b)
    cd, sd = math.cos(delta), math.sin(delta)
    d = np.ones(2 * n)
    d[n] = -R
    # G of eq. (25) (as _jacobians, for one phase)
    dE = d * (form.E[:, 1] * cd - form.E[:, 0] * sd)
    dX = d * (form.rate0[:, 0] * cd + form.rate0[:, 1] * sd + (1.0 + R) * h2 * form.rate)
    h0_p = form.DPhi[0, 1:]
    G = np.empty((2 * n, 2 * n))
    with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
        G[:-1, :-1] = form.DPhi[1:, 1:] - np.outer(dX[1:], h0_p) / h2
        G[:-1, -1] = dE[1:] - dX[1:] * dE[0] / h2
        G[-1, :-1] = -omega * h0_p / h2
        G[-1, -1] = 1.0 - omega * dE[0] / h2
    state = form.P0[:, 0] * cd + form.P0[:, 1] * sd + (1.0 + R) * h2 * form.y
    state[n] = -R * h2  # eq. (4), as the kernel sets it
    scale = float(max(np.abs(state[n:]).max(), omega * np.abs(state[:n]).max()))
    mu = np.linalg.eigvals(G) if np.all(np.isfinite(G)) else np.full(G.shape[0], np.nan + 0j)
    mu = mu[np.argsort(-np.abs(mu), kind="stable")]
    best, gap_t = _x1_maximum_of(flow, flow.V[0] * form.y_modal * ((1.0 + R) * h2), delta,
                                 form.T, math.nan)
    return OrbitValues(state=state, h2=h2, h2_error=rel, velocity_scale=scale, G=G,
                       multipliers=mu, gap_min=osc.b - best, gap_min_time=gap_t)
