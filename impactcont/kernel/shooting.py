"""Compiled shooting of N-p motions: flights, residual, exact Jacobian, G and contact search.

The numba counterpart of :mod:`impactcont.orbit.multi_impact` (which documents the
shooting system, its unknowns ``u = [delta, tau_0..tau_{p-2}, z_0..z_{p-1}]`` and G).
Everything is a function of floats and arrays (``cache=True``), written for both flows
of :mod:`impactcont.orbit.flow`, each diagonal in its own modal coordinates:

- modal (proportional damping): the exact 2 x 2 transfer ``W_i(t)`` of each mode
  (:func:`impactcont.kernel.flights.mode_transfer`, every damping class without
  cancellation), ``Phi = U W U^-1`` and the forcing block of eq. (9) from the steady
  modal amplitudes ``gamma_i, beta_i``;
- first order (any C, complex F): ``Phi = Re(V diag(exp(lambda t)) V^-1) + t N`` (``N``
  the polynomial part of the free modes C leaves undamped, found in the basis by
  :func:`_nilpotent`; zero without one) and the forcing block ``P(t) - Phi P(0)`` from the
  complex steady amplitude ``Z``.

``flow.general`` selects the flow; the arrays of the other are passed empty, so that each
entry point compiles once. Arguments are the named structures of
:mod:`impactcont.kernel.arrays`: the flow (:class:`~impactcont.kernel.arrays.ShootingFlow`,
:meth:`impactcont.orbit.flow.Flow.shooting_arrays`), the forcing at omega
(:class:`~impactcont.kernel.arrays.Forcing`), the motion's impacts
(:class:`~impactcont.kernel.arrays.ImpactSequence`), the stops of the contact check
(:class:`~impactcont.kernel.arrays.ContactStops`) and the shot flights
(:class:`~impactcont.kernel.arrays.ShotFlights`); results are named records of the same
module. An entry point takes each structure as its plain tuple (typed in numba's C
dispatcher) and names it again on entry; compiled code passes the named structures.

The interior-contact check of eq. (16) against both stops is the compiled kernel's
search (:func:`impactcont.kernel.contact.stop_maximum` on its grid): for the modal flow
with the weights ``n^T U`` of the stop coordinate, for the first-order flow on the
scalar pairs of :attr:`impactcont.model.first_order.FirstOrderBasis.scalar_pairs`
with unit weights (as :mod:`impactcont.orbit.general`). A constant force adds a constant
level (held modes, ``X_s``) and, where it pushes a free mode the stop coordinate sees, a
polynomial in time (:func:`impactcont.kernel.contact.drift_x1`), both exact in the search.
The lower stop is the same search on ``-s`` (forced, free and polynomial parts negated).

Entry points (each compiled once): :func:`shooting_system`, :func:`newton_solve`,
:func:`motion_checks`, :func:`omega_partials`, :func:`frequency_column`,
:func:`branch_linearization`, :func:`palc_correct` and, for motions with sticking phases
only, :func:`sticky_system`, :func:`sticky_newton_solve`, :func:`sticky_jacobians` and
:func:`sticky_frequency_column`
(their corrector is :func:`impactcont.kernel.sticky.sticky_palc_correct`), and for those
entered through complete chatter only, :func:`chatter_bounces`.
An entry point that compiled code calls too is called there with the plain tuples Python
passes, so one compiled function serves both (no entry point wraps an inner twin: numba
compiles a wrapper's callee code again into it). Importing :mod:`impactcont` does not
import this module.
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np
from numba import types
from numba.extending import overload

from impactcont.kernel.arrays import (
    BranchLinearization,
    CheckedFlights,
    ContactStops,
    CorrectorSettings,
    CorrectorStep,
    Embedding,
    FirstOrderFlight,
    FlightArrays,
    FlightFlow,
    ForcedAmplitudes,
    Forcing,
    ForcingDerivatives,
    HeldSegments,
    ImpactSequence,
    ModalFlight,
    PalcResult,
    ShootingFlow,
    ShotFlights,
    StickyFlights,
    StopSeries,
)
from impactcont.kernel.contact import (
    WORK_ROWS,
    drift_on_grid,
    free_on_grid,
    stop_maximum,
    time_grid,
)
from impactcont.kernel.flights import mode_transfer, transfer_into
from impactcont.kernel.jit import entry as _jit
from impactcont.kernel.jit import inner as _inner
from impactcont.kernel.linalg import _product_into, _solve_in_place
from impactcont.kernel.newton_rules import FLOOR, TAKE, _converged, _trial_outcome
from impactcont.kernel.stability import multipliers

__all__ = ["branch_linearization", "chatter_bounces", "end_clearances", "forced_amplitudes",
           "frequency_column", "held_pressing", "jacobian_product", "motion_checks",
           "newton_solve",
           "omega_partials", "palc_correct", "shooting_system", "sticky_frequency_column",
           "sticky_jacobians", "sticky_newton_solve", "sticky_system"]


#: ``newton_solve`` status: converged, or stopped without convergence
CONVERGED = 0
FAILED = 1


# -- one flight -------------------------------------------------------------------------------
@_inner
def _static_mode(w, a, g, free, t):
    """A mode's response to the constant modal force ``g``: ``(Q, s_y, s_v)``, its state
    ``Q + W(t) (Y(0) - [Q; 0]) + [s_y; s_v]`` (:func:`impactcont.model.modal.static_response`):
    held ``Q = g / w^2``, ``s = 0``; free ``Q = 0``, ``s_y = g t^2 phi(2at) / 2``,
    ``s_v = g t psi(2at)`` (``g t^2 / 2``, ``g t`` undamped)."""
    if g == 0.0:
        return 0.0, 0.0, 0.0
    if not free:
        return g / (w * w), 0.0, 0.0
    x = 2.0 * a * t
    if x < 1e-4:  # phi(x) = 2 (x - 1 + e^-x) / x^2, psi(x) = (1 - e^-x) / x by their series
        phi = 1.0 - x / 3.0 + x * x / 12.0
        psi = 1.0 - x / 2.0 + x * x / 6.0
    else:
        phi = 2.0 * (x + math.expm1(-x)) / (x * x)
        psi = -math.expm1(-x) / x
    return 0.0, 0.5 * g * t * t * phi, g * t * psi


class FlightWork(NamedTuple):
    """Scratch of one modal flight (:func:`_flight_modal_into`), reused from flight to
    flight by a caller that shoots many (a map's sweep)."""

    transfer: np.ndarray
    """The modes' transfer matrices ``W(t)``, shape (4, n)."""
    modal: np.ndarray
    """The modal forcing columns, velocities and accelerations, shape (6, n)."""


@_inner
def _flight_work(n):
    """A :class:`FlightWork` for `n` modes."""
    return FlightWork(np.empty((4, n)), np.empty((6, n)))


@_inner
def _flight_modal(modal, forcing, t, X0, theta, tr, arr, pcol, rate):
    """Flight of the modal flow (:class:`~impactcont.kernel.arrays.ModalFlight`): ``Phi``,
    ``X^-``, ``dX^-/dtheta`` and ``X'(t^-)`` in place (the constant force ``modal.g``
    included: ``X(t) = Phi (X0 - P(0)) + P(t)`` with the particular solution ``P`` of the
    forcing and of the constant force)."""
    _flight_modal_into(modal, forcing, t, X0, theta, tr, arr, pcol, rate,
                       _flight_work(modal.w.size))


@_inner
def _flight_modal_into(modal, forcing, t, X0, theta, tr, arr, pcol, rate, work):
    """:func:`_flight_modal` with its scratch `work` (a :class:`FlightWork`)."""
    w, a, f, u, ui = modal.w, modal.a, modal.f, modal.u, modal.ui
    g_static, free = modal.g, modal.free
    gam, bet, omega = forcing.gamma, forcing.beta, forcing.omega
    n = w.size
    W = work.transfer
    for i in range(n):
        W[0, i], W[1, i], W[2, i], W[3, i] = mode_transfer(w[i], a[i], t)
    transfer_into(W, 0, u, ui, tr)
    ct = math.cos(omega * t)
    st = math.sin(omega * t)
    c0 = math.cos(theta)
    s0 = math.sin(theta)
    cth = math.cos(omega * t + theta)
    sth = math.sin(omega * t + theta)
    # rows of work.modal, indexed in place (a view of each would be six more arrays whose
    # references numba counts): 0, 1 the modal forcing block times [cos theta, sin theta],
    # 2, 3 times [-sin theta, cos theta], 4, 5 the modal velocity and acceleration at t
    V = work.modal
    static = g_static.size > 0
    for i in range(n):
        g = gam[i]
        b = bet[i]
        w11, w12, w21, w22 = W[0, i], W[1, i], W[2, i], W[3, i]
        phi = g * ct + b * st
        psi = b * ct - g * st
        # E = P(t) - W(t) P(0), P(0) = [[g, b], [om b, -om g]] (Flow.matrices)
        eyc = phi - w11 * g - w12 * omega * b
        eys = psi - w11 * b + w12 * omega * g
        evc = omega * psi - w21 * g - w22 * omega * b
        evs = -omega * phi - w21 * b + w22 * omega * g
        V[0, i] = eyc * c0 + eys * s0
        V[1, i] = evc * c0 + evs * s0
        V[2, i] = -eyc * s0 + eys * c0
        V[3, i] = -evc * s0 + evs * c0
        y, v = _mode_state(ui, X0, i, omega, (g, b), (c0, s0, cth, sth), (w11, w12, w21, w22))
        force = f[i] * cth
        if static and g_static[i] != 0.0:
            sty, stv = _static_state(w[i], a[i], g_static[i], free[i], t, w11, w21)
            V[0, i] += sty
            V[1, i] += stv
            y += sty
            v += stv
            force += g_static[i]
        V[4, i] = v
        V[5, i] = force - 2.0 * a[i] * v - w[i] * w[i] * y
    m = 2 * n
    for r in range(m):
        s = 0.0
        for c in range(m):
            s += tr[r, c] * X0[c]
        arr[r] = s
    for r in range(n):
        ay = 0.0
        av = 0.0
        qy = 0.0
        qv = 0.0
        ry = 0.0
        rv = 0.0
        for i in range(n):
            ay += u[r, i] * V[0, i]
            av += u[r, i] * V[1, i]
            qy += u[r, i] * V[2, i]
            qv += u[r, i] * V[3, i]
            ry += u[r, i] * V[4, i]
            rv += u[r, i] * V[5, i]
        arr[r] += ay
        arr[n + r] += av
        pcol[r] = qy
        pcol[n + r] = qv
        rate[r] = ry
        rate[n + r] = rv


@_inner
def _mode_state(ui, X0, i, omega, amplitude, phases, transfer):
    """Mode i's state ``(y, v)`` at `t` of the flight from ``X0``: the steady motion at `t`
    and the deviation of the start from it carried by the mode's ``W(t)`` (`transfer`), for
    :func:`_flight_modal_into` and :func:`_modal_gap` (the constant force's part is
    :func:`_static_state`). `amplitude` is the mode's ``(gamma, beta)`` of eq. (7),
    `phases` ``(cos theta, sin theta, cos(omega t + theta), sin(omega t + theta))``."""
    g, b = amplitude
    c0, s0, cth, sth = phases
    w11, w12, w21, w22 = transfer
    n = ui.shape[0]
    y0 = 0.0
    v0 = 0.0
    for c in range(n):
        y0 += ui[i, c] * X0[c]
        v0 += ui[i, c] * X0[n + c]
    dy = y0 - (g * c0 + b * s0)
    dv = v0 - omega * (b * c0 - g * s0)
    return (g * cth + b * sth + w11 * dy + w12 * dv,
            omega * (b * cth - g * sth) + w21 * dy + w22 * dv)


@_inner
def _static_state(w, a, g, free, t, w11, w21):
    """The part ``(s_y, s_v)`` of a mode's state at `t` that its constant modal force `g`
    adds from rest (:func:`_static_mode`; `w11`, `w21` its ``W(t)``)."""
    q, s_y, s_v = _static_mode(w, a, g, free, t)
    return (1.0 - w11) * q + s_y, -w21 * q + s_v


@_inner
def _generalized(lam, V, k):
    """Whether column k of the first-order basis is the generalized eigenvector ``[0; u] /
    |u|`` of an undamped free mode (eigenvalue 0, zero position part:
    :attr:`impactcont.model.first_order.FirstOrderBasis.generalized`)."""
    if lam[k] != 0.0:
        return False
    n = V.shape[0] // 2
    position = False
    for r in range(n):
        if V[r, k] != 0.0:
            position = True
            break
    return not position


@_inner
def _nilpotent(lam, V, Vi):
    """``N = sum_k [V_{n:,k}; 0] Re(V^-1_{k,:})`` over the generalized vectors k
    (:func:`_generalized`): the polynomial part of ``Phi(t) = Re(V diag(e^{lambda t}) V^-1)
    + t N`` (:attr:`impactcont.model.first_order.FirstOrderBasis.nilpotent`, the drift of
    the undamped free modes), shape (2n, 2n); shape (0, 0) without one (nothing allocated
    beyond it: the flights of every other C pay one scan of the zero eigenvalues)."""
    m = lam.size
    n = m // 2
    count = 0
    for k in range(m):
        if _generalized(lam, V, k):
            count += 1
    if count == 0:
        return np.zeros((0, 0))
    N = np.zeros((m, m))
    for k in range(m):
        if not _generalized(lam, V, k):
            continue
        for r in range(n):
            vr = V[n + r, k].real
            for c in range(m):
                N[r, c] += vr * Vi[k, c].real
    return N


@_inner
def _flight_general(first_order, forcing, t, X0, theta, tr, arr, pcol, rate):
    """Flight of the first-order flow (:class:`~impactcont.kernel.arrays.FirstOrderFlight`):
    as :func:`_flight_modal` (``GeneralFlow.matrices``); the constant force adds ``X_s - Phi
    X_s + d t`` (``first_order.xs``, ``first_order.xd``: its offset and drift, empty without
    one). Undamped free modes add the polynomial part: ``t N`` to ``Phi`` (:func:`_nilpotent`)
    and ``N d t^2 / 2`` to the constant force's part (``GeneralFlow.accel``)."""
    lam, V, Vi = first_order.lam, first_order.V, first_order.Vi
    xs, xd = first_order.xs, first_order.xd
    Z, omega = forcing.Z, forcing.omega
    m = lam.size
    e = np.exp(lam * t)
    for r in range(m):
        for c in range(m):
            s = 0j
            for k in range(m):
                s += V[r, k] * e[k] * Vi[k, c]
            tr[r, c] = s.real
    N = _nilpotent(lam, V, Vi)
    chains = N.shape[0] > 0
    if chains:
        for r in range(m):
            for c in range(m):
                tr[r, c] += t * N[r, c]
    c0 = math.cos(theta)
    s0 = math.sin(theta)
    rot_t = complex(math.cos(omega * t), math.sin(omega * t))
    rot_0 = complex(c0, s0)
    # columns multiplying cos theta, sin theta: P(t) - Phi P(0), P(t) = [Re, -Im](Z e^{i om t})
    for r in range(m):
        fc = 0.0
        fs = 0.0
        for c in range(m):
            fc += tr[r, c] * Z[c].real
            fs -= tr[r, c] * Z[c].imag
        zt = Z[r] * rot_t
        ec = zt.real - fc
        es = -zt.imag - fs
        s = 0.0
        for c in range(m):
            s += tr[r, c] * X0[c]
        arr[r] = s + ec * c0 + es * s0
        pcol[r] = -ec * s0 + es * c0
    static = xs.size > 0
    accel = np.zeros(m)  # N d: the t^2 / 2 coefficient on the undamped free modes
    if static and chains:
        for r in range(m):
            for c in range(m):
                accel[r] += N[r, c] * xd[c]
    if static:
        for r in range(m):
            s = xs[r] + xd[r] * t + 0.5 * t * t * accel[r]
            for c in range(m):
                s -= tr[r, c] * xs[c]
            arr[r] += s
    # X'(t) = Re(i om Z e^{i(om t + theta)}) + Re(V diag(lam e^{lam t}) V^-1 (X0 - X_p(0)))
    dev = np.empty(m)
    for c in range(m):
        dev[c] = X0[c] - (Z[c] * rot_0).real
        if static:
            dev[c] -= xs[c]
    zeta = np.empty(m, dtype=np.complex128)
    for k in range(m):
        s = 0j
        for c in range(m):
            s += Vi[k, c] * dev[c]
        zeta[k] = s * lam[k] * e[k]
    rot = rot_t * rot_0
    for r in range(m):
        s = 0j
        for k in range(m):
            s += V[r, k] * zeta[k]
        rate[r] = (1j * omega * Z[r] * rot).real + s.real
        if static:
            rate[r] += xd[r] + t * accel[r]
        if chains:  # d/dt of t N dev
            for c in range(m):
                rate[r] += N[r, c] * dev[c]


@_inner
def _flight(flight, forcing, t, X0, theta, tr, arr, pcol, rate):
    """One flight of either flow (``flight.general``, a
    :class:`~impactcont.kernel.arrays.FlightFlow`), the constant force included."""
    if flight.general:
        _flight_general(flight.first_order, forcing, t, X0, theta, tr, arr, pcol, rate)
    else:
        _flight_modal(flight.modal, forcing, t, X0, theta, tr, arr, pcol, rate)


@_inner
def _flight_into(flight, forcing, t, X0, theta, tr, arr, pcol, rate, work):
    """:func:`_flight` with the modal flight's scratch `work` (a :class:`FlightWork`)."""
    if flight.general:
        _flight_general(flight.first_order, forcing, t, X0, theta, tr, arr, pcol, rate)
    else:
        _flight_modal_into(flight.modal, forcing, t, X0, theta, tr, arr, pcol, rate, work)


@_inner
def _flights(flow):
    """:class:`~impactcont.kernel.arrays.FlightFlow` of a structure with the flow's fields
    (:class:`~impactcont.kernel.arrays.ShootingFlow` or
    :class:`~impactcont.kernel.arrays.FlightArrays`): each flight function then takes the
    part it reads, and compiles for that alone."""
    return FlightFlow(flow.general,
                      ModalFlight(flow.w, flow.a, flow.f, flow.u, flow.ui, flow.g, flow.free),
                      FirstOrderFlight(flow.lam, flow.V, flow.Vi, flow.xs, flow.xd))


@_inner
def _shot_tuple(shot):
    """`shot` (:class:`~impactcont.kernel.arrays.ShotFlights`) as the plain tuple an entry
    point returns (Python names it with ``ShotFlights._make``: numba boxes a named tuple
    through a Python call of its class, about 0.7 us)."""
    return (shot.phases, shot.flight_times, shot.starts, shot.arrivals, shot.arrival_rates,
            shot.transitions, shot.phase_columns, shot.residual, shot.jacobian)


# -- the shooting system ------------------------------------------------------------------------
@_inner
def _section_starts(x, first, p, m, pivots, normals, positions):
    """``X_k`` from the unknowns: ``z_k`` (from ``x[first]`` on, ``m - 1`` each) in every
    component but ``x_j`` (``j = pivots[k]``, the stop's own mass), and ``x_j`` from the
    section ``n_k . x = c_k`` of impact k."""
    starts = np.empty((p, m))
    _section_starts_into(x, first, p, m, pivots, normals, positions, starts)
    return starts


@_inner
def _section_starts_into(x, first, p, m, pivots, normals, positions, starts):
    """:func:`_section_starts` into ``starts`` (p, m)."""
    n = m // 2
    for k in range(p):
        j = pivots[k]
        col = first + k * (m - 1)
        for c in range(m):
            if c != j:
                starts[k, c] = x[col]
                col += 1
        s = positions[k]
        for c in range(n):
            if c != j:
                s -= normals[k, c] * starts[k, c]
        starts[k, j] = s / normals[k, j]


@_inner
def _apply(D, v, out):
    """``out = D v`` skipping the zeros of ``D`` (an impact matrix is mostly identity)."""
    m = v.size
    for r in range(m):
        s = 0.0
        for c in range(m):
            d = D[r, c]
            if d != 0.0:
                s += d * v[c]
        out[r] = s


@_inner
def _apply_matrix(D, A, out):
    """``out = D A`` skipping the zeros of ``D``."""
    m = A.shape[0]
    q = A.shape[1]
    for r in range(m):
        first = True
        for i in range(m):
            d = D[r, i]
            if d != 0.0:
                if first:
                    for c in range(q):
                        out[r, c] = d * A[i, c]
                    first = False
                else:
                    for c in range(q):
                        out[r, c] += d * A[i, c]
        if first:
            for c in range(q):
                out[r, c] = 0.0


@_inner
def _is_diagonal(matrices):
    """Every impact matrix is diagonal (stops on one mass: eq. 4)."""
    m = matrices.shape[1]
    for k in range(matrices.shape[0]):
        for r in range(m):
            for c in range(m):
                if r != c and matrices[k, r, c] != 0.0:
                    return False
    return True



@_inner
def _jacobian_wanted(x):
    """True, as a value of run time (type ``bool``): a literal ``True`` from compiled code
    would make numba compile :func:`shooting_system` a second time, for
    ``Literal[bool](True)``, beside the ``bool`` its Python callers pass (about 2 s)."""
    return x.size >= 0

@_jit
def shooting_system(flight, forcing, impacts, period, x, want_jacobian):
    """Residual (and exact Jacobian) of the N-p shooting system at the unknowns ``x``.

    Parameters
    ----------
    flight, forcing, impacts : tuple
        :class:`~impactcont.kernel.arrays.FlightArrays`
        (:meth:`~impactcont.kernel.arrays.ShootingFlow.flight_arrays`),
        :class:`~impactcont.kernel.arrays.Forcing` and
        :class:`~impactcont.kernel.arrays.ImpactSequence` as plain tuples: the flow, the
        forcing at omega and, for each impact, the 0-based index ``j_k`` of the position
        eliminated on its section (the mass of the stop hit), the normal ``n_k``, stop
        position ``c_k`` and impact matrix ``D_k``.
    period : float
        The motion's ``2 pi N / omega``.
    x : ndarray, shape (2np,)
        The unknowns.
    want_jacobian : bool
        Build the Jacobian (else it has shape (0, 0)).

    Returns
    -------
    tuple
        The fields of :class:`~impactcont.kernel.arrays.ShotFlights` (``ShotFlights._make``
        names them), those of :class:`impactcont.orbit.multi_impact.Shooting`.
    """
    return _shot_tuple(_shooting_system(_flights(FlightArrays(*flight)), Forcing(*forcing),
                                        ImpactSequence(*impacts), period, x, want_jacobian))


@_inner
def _shooting_system(flight, forcing, impacts, period, x, want_jacobian):
    """:func:`shooting_system` on the named structures (what compiled callers call; `flight`
    a :class:`~impactcont.kernel.arrays.FlightFlow`, :func:`_flights`)."""
    p = impacts.positions.size
    m = impacts.matrices.shape[1]
    size = p * m if want_jacobian else 0
    out = ShotFlights(np.empty(p), np.empty(p), np.empty((p, m)), np.empty((p, m)),
                      np.empty((p, m)), np.empty((p, m, m)), np.empty((p, m)),
                      np.empty(p * m), np.empty((size, size)))
    return _shooting_system_into(flight, forcing, impacts, period, x, want_jacobian, out,
                                 _shooting_work(m))


class ShootingWork(NamedTuple):
    """Scratch of :func:`_shooting_system_into`, reused from call to call by a caller that
    shoots many times (a map's sweep)."""

    flight: FlightWork
    """The modal flight's (:func:`_flight_modal_into`)."""
    row: np.ndarray
    """A row of ``D_{k+1} Phi_k``, shape (2n,)."""
    no_jacobian: np.ndarray
    """The Jacobian of a system evaluated without it, shape (0, 0)."""


@_inner
def _shooting_work(m):
    """A :class:`ShootingWork` for states of size `m`."""
    return ShootingWork(_flight_work(m // 2), np.empty(m), np.zeros((0, 0)))


@_inner
def _shooting_system_into(flight, forcing, impacts, period, x, want_jacobian, out, work):
    """:func:`_shooting_system` into the arrays of `out` (a
    :class:`~impactcont.kernel.arrays.ShotFlights` of p impacts, its Jacobian (2np, 2np)
    when `want_jacobian`) with the scratch `work` (:class:`ShootingWork`): the same
    arithmetic, no array allocated. Returns the
    :class:`~impactcont.kernel.arrays.ShotFlights` of `out`'s arrays, its Jacobian
    ``work.no_jacobian`` when not wanted."""
    pivots, normals = impacts.pivots, impacts.normals
    positions, matrices = impacts.positions, impacts.matrices
    omega = forcing.omega
    p = positions.size
    m = matrices.shape[1]
    n = m // 2
    taus = out.flight_times
    elapsed = 0.0
    for k in range(p - 1):
        taus[k] = x[1 + k]
        elapsed += x[1 + k]
    taus[p - 1] = period - elapsed
    starts = out.starts
    _section_starts_into(x, p, p, m, pivots, normals, positions, starts)
    diagonal = _is_diagonal(matrices)
    phases = out.phases
    phases[0] = x[0]
    elapsed = 0.0
    for k in range(1, p):
        elapsed += taus[k - 1]
        phases[k] = x[0] + omega * elapsed
    transitions = out.transitions
    arrivals = out.arrivals
    rates = out.arrival_rates
    pcols = out.phase_columns
    residual = out.residual
    general = flight.general
    modal, first_order = flight.modal, flight.first_order  # each flight reads its own part
    fwork = work.flight
    for k in range(p):
        if general:  # _flight_into's branches: a call fewer per flight, 13 arrays fewer
            _flight_general(first_order, forcing, taus[k], starts[k], phases[k],
                            transitions[k], arrivals[k], pcols[k], rates[k])
        else:
            _flight_modal_into(modal, forcing, taus[k], starts[k], phases[k], transitions[k],
                               arrivals[k], pcols[k], rates[k], fwork)
        nxt = (k + 1) % p
        for r in range(m):
            if diagonal:
                s = matrices[nxt, r, r] * arrivals[k, r]
            else:
                s = 0.0
                for c in range(m):
                    s += matrices[nxt, r, c] * arrivals[k, c]
            residual[k * m + r] = s - starts[nxt, r]
    if not want_jacobian:
        return ShotFlights(phases, taus, starts, arrivals, rates, transitions, pcols, residual,
                           work.no_jacobian)
    J = out.jacobian
    J[:, :] = 0.0
    row_dphi = work.row  # row r of D_{k+1} Phi_k
    zcol = p  # first column of z_0
    for k in range(p):
        nxt = (k + 1) % p
        j = pivots[k]
        jn = pivots[nxt]
        col0 = zcol + k * (m - 1)
        ncol = zcol + nxt * (m - 1)
        for r in range(m):
            row = k * m + r
            if diagonal:
                d = matrices[nxt, r, r]
                q = d * pcols[k, r]  # (D dX^-/dtheta)_r
                g = d * rates[k, r]  # (D X')_r
                for c in range(m):
                    row_dphi[c] = d * transitions[k, r, c]
            else:
                q = 0.0
                g = 0.0
                for c in range(m):
                    row_dphi[c] = 0.0
                for i in range(m):
                    d = matrices[nxt, r, i]
                    if d != 0.0:
                        q += d * pcols[k, i]
                        g += d * rates[k, i]
                        for c in range(m):
                            row_dphi[c] += d * transitions[k, i, c]
            J[row, 0] = q  # d theta_k / d delta = 1
            for i in range(k):  # theta_k depends on tau_i, i < k
                J[row, 1 + i] += omega * q
            if k < p - 1:
                J[row, 1 + k] += g
            else:  # tau_{p-1} = period - sum(tau_0..tau_{p-2})
                for i in range(p - 1):
                    J[row, 1 + i] -= g
            # dX_k/dz_k: unit columns, and x_j = (c_k - sum n_c x_c) / n_j on the section
            col = col0
            for c in range(m):
                if c != j:
                    v = row_dphi[c]
                    if c < n and normals[k, c] != 0.0:
                        v -= row_dphi[j] * normals[k, c] / normals[k, j]
                    J[row, col] += v
                    col += 1
            # - dX_{k+1}/dz_{k+1}
            if r != jn:
                J[row, ncol + (r if r < jn else r - 1)] -= 1.0
            else:
                for c in range(n):
                    if c != jn and normals[nxt, c] != 0.0:
                        J[row, ncol + (c if c < jn else c - 1)] += (normals[nxt, c]
                                                                    / normals[nxt, jn])
    return ShotFlights(phases, taus, starts, arrivals, rates, transitions, pcols, residual, J)


# -- motions with sticking phases ---------------------------------------------------------------
@_inner
def _held_start(held, k, omega, X0):
    """``(flight, forcing, Y0)`` of the sticking phase after impact k: the held system's
    first-order flight (:class:`~impactcont.kernel.arrays.FirstOrderFlight`), its forcing
    at `omega` and the reduced start ``Y0 = L^+ (X0 - X_c)`` (at least one coordinate
    free)."""
    Li, Xc = held.inverses[k], held.offsets[k]
    m = Xc.size
    r = Li.shape[0]
    Y0 = np.zeros(r)
    for i in range(r):
        s = 0.0
        for c in range(m):
            s += Li[i, c] * (X0[c] - Xc[c])
        Y0[i] = s
    empty = np.zeros(0)
    return (FirstOrderFlight(held.lam[k], held.V[k], held.Vi[k], held.xs[k], held.xd[k]),
            Forcing(omega, empty, empty, held.Z[k]), Y0)


@_inner
def _held_segment(held, k, omega, t, X0, theta, X, dX0, dtheta, rate):
    """The sticking phase after impact k (:class:`~impactcont.kernel.arrays.HeldSegments`)
    held for `t` from ``X0`` at phase `theta`: ``X(t)``, ``dX/dX0 = L Phi_r L^+``,
    ``dX/dtheta`` and ``dX/dt`` in place (the held system's first-order flight,
    :func:`_flight_general`, lifted by ``X = X_c + L Y``)."""
    L, Li, Xc = held.lifts[k], held.inverses[k], held.offsets[k]
    m = Xc.size
    r = Li.shape[0]
    for i in range(m):
        X[i] = Xc[i]
        dtheta[i] = 0.0
        rate[i] = 0.0
        for c in range(m):
            dX0[i, c] = 0.0
    if r == 0:  # one mass held: the state stays
        return
    flight, forcing, Y0 = _held_start(held, k, omega, X0)
    tr = np.empty((r, r))
    Y = np.empty(r)
    pcol = np.empty(r)
    yr = np.empty(r)
    _flight_general(flight, forcing, t, Y0, theta, tr, Y, pcol, yr)
    TLi = np.empty((r, m))  # Phi_r L^+
    _product_into(tr, Li, TLi)
    for i in range(m):
        for q in range(r):
            lq = L[i, q]
            if lq != 0.0:
                X[i] += lq * Y[q]
                dtheta[i] += lq * pcol[q]
                rate[i] += lq * yr[q]
                for c in range(m):
                    dX0[i, c] += lq * TLi[q, c]


@_inner
def _pressing(held, k, X, theta):
    """The pressing force of the stop held after impact k at ``X``, phase `theta`, and
    ``dp/dtheta``."""
    return _pressing_at(held.grads[k], held.levels[k], held.forces[k], X, theta)


@_inner
def _pressing_at(g, level, force, X, theta):
    """:func:`_pressing` from the held stop's ``dp/dX`` (`g`), constant part (`level`) and
    complex forcing amplitude (`force`): ``p = level + g . X + Re(force e^{i theta})``
    (what :func:`held_pressing` evaluates at every sample, without the 16 arrays of
    :class:`~impactcont.kernel.arrays.HeldSegments` counted in and out each time)."""
    s = level
    for i in range(g.size):
        s += g[i] * X[i]
    e = complex(math.cos(theta), math.sin(theta)) * force
    return s + e.real, (1j * e).real


# -- complete chatter ---------------------------------------------------------------------------
#: Newton iterations of one bounce's return time (:func:`_chatter_map`).
_BOUNCE_ITERATIONS = 60
#: A bounce whose apex ``u^2 / (2 a)`` lies within this many ulps of the stop position is not
#: resolved: the jump to the accumulation point is taken from it.
_BOUNCE_ULPS = 1e3
_CHATTER_EPS = 2.220446049250313e-16


@_inner
def _stop_speed(normal, sign, rate, n):
    """``(u, a)``: the speed of the stop coordinate away from the stop and its acceleration
    into it, from a state derivative ``rate``."""
    u = 0.0
    a = 0.0
    for c in range(n):
        u -= sign * normal[c] * rate[c]
        a += sign * normal[c] * rate[n + c]
    return u, a


@_inner
def _acceleration_gradient(flow, forcing, normal, sign, theta, grad):
    """``grad[:m] = da/dX``, ``grad[m] = da/dtheta`` of the acceleration ``a`` of the stop
    coordinate into the stop: the state derivative is affine in the state, ``X' = A X +
    f(theta)``, so ``A e_c = X'(e_c) - X'(0)`` and ``f'(theta) = f(theta + pi/2) - (f(theta)
    + f(theta + pi)) / 2`` (the constant force cancels), each from a flight of length 0."""
    m = grad.size - 1
    n = m // 2
    tr = np.empty((m, m))
    arr = np.empty(m)
    pcol = np.empty(m)
    rate = np.empty(m)
    work = _flight_work(n)
    general = flow.general
    modal, first_order = flow.modal, flow.first_order  # each flight reads its own part
    X = np.zeros(m)
    acc = np.empty(m + 3)  # at e_c (c < m), at 0, at 0 with theta + pi/2, theta + pi
    for j in range(m + 3):
        th = theta
        if j == m + 1:
            th = theta + 0.5 * math.pi
        elif j == m + 2:
            th = theta + math.pi
        if j < m:
            X[j] = 1.0
        if general:  # _flight_into's branches: a call fewer per flight, 13 arrays fewer
            _flight_general(first_order, forcing, 0.0, X, th, tr, arr, pcol, rate)
        else:
            _flight_modal_into(modal, forcing, 0.0, X, th, tr, arr, pcol, rate, work)
        if j < m:
            X[j] = 0.0
        _, aj = _stop_speed(normal, sign, rate, n)
        acc[j] = aj
    a0 = acc[m]
    for c in range(m):
        grad[c] = acc[c] - a0
    grad[m] = acc[m + 1] - 0.5 * (a0 + acc[m + 2])


@_inner
def _gap(flow, forcing, t, Y, th, stop, scratch):
    """``(g, g')`` at `t` of the flight from `Y`: the clearance ``sign (c - n . x)`` of the
    stop `stop` (the plain tuple ``(normal, sign, position)``; ``>= 0`` free) and its rate.
    The modal flow's from its modes' states alone (:func:`_modal_gap`: no transition
    matrix), the first-order flow's from its flight into `scratch` (``(tr, arr, pcol,
    rate)``)."""
    normal, sign, position = stop
    if not flow.general:
        return _modal_gap(flow.modal, forcing, t, Y, th, normal, sign, position)
    tr, arr, pcol, rate = scratch
    _flight_general(flow.first_order, forcing, t, Y, th, tr, arr, pcol, rate)
    g = position
    gd = 0.0
    for c in range(normal.size):
        g -= normal[c] * arr[c]
        gd -= normal[c] * rate[c]
    return sign * g, sign * gd


@_inner
def _modal_gap(modal, forcing, t, Y, th, normal, sign, position):
    """:func:`_gap` of the modal flow: the stop coordinate ``n . x = sum_i (n . u_i) y_i``
    and its rate from each mode's state at `t` (the modal state of
    :func:`_flight_modal_into`, the constant force included), without the flight's
    transition matrix, phase column and forced columns: :func:`_gap_terms` then
    :func:`_modal_gap_at`."""
    terms = np.empty((_GAP_ROWS, modal.w.size))
    _gap_terms(modal, forcing, Y, th, normal, terms)
    return _modal_gap_at(terms, forcing.omega, t, th, sign, position)


#: Rows of :func:`_gap_terms`: each mode's w, a, gamma, beta, constant force, free (1.0
#: or 0.0), ``n . u_i`` and its deviation ``(dy, dv)`` from the steady motion at the start.
_GAP_ROWS = 9


@_inner
def _gap_terms(modal, forcing, Y, th, normal, terms):
    """What :func:`_modal_gap_at` reads of the modal flight from `Y` at phase `th` and the
    stop coordinate ``n . x`` (`normal`), into `terms` (:data:`_GAP_ROWS`, n): the same for
    every time of the flight, so a chatter's return search (a few clearances per bounce)
    computes the modes' start deviations (:func:`_mode_state`'s ``dy, dv``) and ``n . u_i``
    once per bounce, and its clearances read one array (numba counts a reference to every
    array of every structure a compiled call is given, as it starts and as it returns)."""
    w, a, u, ui = modal.w, modal.a, modal.u, modal.ui
    g_static, free = modal.g, modal.free
    gam, bet, omega = forcing.gamma, forcing.beta, forcing.omega
    c0 = math.cos(th)
    s0 = math.sin(th)
    n = w.size
    static = g_static.size > 0
    for i in range(n):
        g = gam[i]
        b = bet[i]
        y0 = 0.0
        v0 = 0.0
        for c in range(n):
            y0 += ui[i, c] * Y[c]
            v0 += ui[i, c] * Y[n + c]
        nu = 0.0
        for c in range(n):
            nu += normal[c] * u[c, i]
        terms[0, i] = w[i]
        terms[1, i] = a[i]
        terms[2, i] = g
        terms[3, i] = b
        terms[4, i] = g_static[i] if static else 0.0
        terms[5, i] = 1.0 if static and free[i] else 0.0
        terms[6, i] = nu
        terms[7, i] = y0 - (g * c0 + b * s0)
        terms[8, i] = v0 - omega * (b * c0 - g * s0)


@_inner
def _modal_gap_at(terms, omega, t, th, sign, position):
    """The clearance ``sign (c - n . x)`` and its rate at `t` of the modal flight whose
    :func:`_gap_terms` are `terms`: each mode's state as :func:`_mode_state` and
    :func:`_static_state` give it (the same arithmetic), summed as :func:`_modal_gap`."""
    cth = math.cos(omega * t + th)
    sth = math.sin(omega * t + th)
    x = position
    xd = 0.0
    for i in range(terms.shape[1]):
        w = terms[0, i]
        a = terms[1, i]
        g = terms[2, i]
        b = terms[3, i]
        dy = terms[7, i]
        dv = terms[8, i]
        w11, w12, w21, w22 = mode_transfer(w, a, t)
        y = g * cth + b * sth + w11 * dy + w12 * dv
        v = omega * (b * cth - g * sth) + w21 * dy + w22 * dv
        if terms[4, i] != 0.0:
            sty, stv = _static_state(w, a, terms[4, i], terms[5, i] != 0.0, t, w11, w21)
            y += sty
            v += stv
        nu = terms[6, i]
        x -= nu * y
        xd -= nu * v
    return sign * x, sign * xd


@_inner
def _bounce_return(flow, forcing, Y, th, stop, guess, scratch, terms):
    """The first return to its stop of the flight from `Y` (on the stop, leaving it), or
    ``-1.0``: one Newton step from the parabola's `guess` (a small bounce's return lands
    within the clearance's rounding), the clearance bracketed from there (marching forward
    in quarters of `guess`, at most two forcing periods, or halving back while the
    clearance is not positive), then safeguarded Newton (bisection where a Newton step
    leaves the bracket) to a few ulps of the time or of the clearance. `stop` and
    `scratch` as :func:`_gap` takes them; `terms` the modal flight's scratch of
    :func:`_gap_terms`, shape (:data:`_GAP_ROWS`, n) (shape (:data:`_GAP_ROWS`, 0) for the
    first-order flow, whose clearances are :func:`_gap`'s): the clearances of the modal
    flow are :func:`_modal_gap_at` of it (:func:`_modal_gap`'s arithmetic)."""
    normal, sign, position = stop
    omega = forcing.omega
    period = 2.0 * math.pi / omega
    modal = terms.shape[1] > 0
    if modal:
        _gap_terms(flow.modal, forcing, Y, th, normal, terms)
    # the clearance's rounding: a few ulps of the stop coordinate's terms
    level = abs(position)
    for c in range(normal.size):
        level += abs(normal[c] * Y[c])
    level *= 4.0 * _CHATTER_EPS
    g, gd = (_modal_gap_at(terms, omega, guess, th, sign, position) if modal
             else _gap(flow, forcing, guess, Y, th, stop, scratch))
    lo = -1.0
    hi = -1.0
    if g > 0.0:
        lo = guess
    else:
        hi = guess
    t = guess  # a time in [lo, hi] whose clearance g, gd are known
    if gd < 0.0:  # Newton from the guess, no further than the march's first quarter
        t1 = guess - g / gd
        if t1 > 0.0 and abs(t1 - guess) <= 0.25 * guess:
            g1, gd1 = (_modal_gap_at(terms, omega, t1, th, sign, position) if modal
                       else _gap(flow, forcing, t1, Y, th, stop, scratch))
            if g1 > 0.0:
                lo = t1
            else:
                hi = t1
            t, g, gd = t1, g1, gd1
    if hi < 0.0:  # not returned by lo: march forward
        step = 0.25 * guess
        while lo < 2.0 * period:
            t = lo + step
            g, gd = (_modal_gap_at(terms, omega, t, th, sign, position) if modal
                     else _gap(flow, forcing, t, Y, th, stop, scratch))
            if not g > 0.0:
                hi = t
                break
            lo = t
            step *= 1.5
        if hi < 0.0:
            return -1.0
    elif lo < 0.0:  # returned by hi: halve back
        lo = 0.5 * hi
        for _ in range(200):
            g, gd = (_modal_gap_at(terms, omega, lo, th, sign, position) if modal
                     else _gap(flow, forcing, lo, Y, th, stop, scratch))
            if g > 0.0:
                break
            hi = lo
            lo *= 0.5
        if not g > 0.0:
            return -1.0
        t = lo
    for _ in range(_BOUNCE_ITERATIONS):
        if abs(g) <= level:  # at the stop to rounding: the time is as good as it gets
            return t
        if g > 0.0:
            lo = t
        else:
            hi = t
        new = t - g / gd if gd != 0.0 else 0.5 * (lo + hi)
        if not lo < new < hi:
            new = 0.5 * (lo + hi)
        if abs(new - t) <= 8.0 * _CHATTER_EPS * t or hi - lo <= 8.0 * _CHATTER_EPS * hi:
            return new
        t = new
        g, gd = (_modal_gap_at(terms, omega, t, th, sign, position) if modal
                 else _gap(flow, forcing, t, Y, th, stop, scratch))
    return -1.0


@_inner
def _forced_vectors(general, u, forcing, dgamma, dbeta, dZ):
    """``(Zp, dZp)``: the complex amplitude of the steady forced state ``X_p(t) = Re(Zp
    e^{i(omega t + theta)})`` and its omega derivative, shape (2n,) each. For the modal flow
    ``Zp = [U A; i omega U A]`` with ``A = gamma - i beta`` (eq. 7), ``dA = dgamma - i
    dbeta``; for a first-order flow ``Z`` and ``dZ`` as given."""
    if general:
        return forcing.Z.copy(), dZ.copy()
    gam, bet, omega = forcing.gamma, forcing.beta, forcing.omega
    n = u.shape[0]
    Zp = np.empty(2 * n, dtype=np.complex128)
    dZp = np.empty(2 * n, dtype=np.complex128)
    for r in range(n):
        s = 0j
        ds = 0j
        for i in range(n):
            s += u[r, i] * complex(gam[i], -bet[i])
            ds += u[r, i] * complex(dgamma[i], -dbeta[i])
        Zp[r] = s
        Zp[n + r] = 1j * omega * s
        dZp[r] = ds
        dZp[n + r] = 1j * s + 1j * omega * ds
    return Zp, dZp


@_inner
def _flight_omega_partial(Zp, dZp, omega, t, theta, tr, out):
    """``dX(t)/d omega`` of a flight at fixed ``t``, start state and start phase into
    `out`: only its steady forced state moves, ``D(t) - Phi(t) D(0)`` with ``D(t) =
    Re((dZp + i t Zp) e^{i(omega t + theta)})`` (:func:`omega_partials`, one flight)."""
    m = out.size
    rot_0 = complex(math.cos(theta), math.sin(theta))
    rot_t = complex(math.cos(omega * t + theta), math.sin(omega * t + theta))
    for r in range(m):
        s = ((dZp[r] + 1j * t * Zp[r]) * rot_t).real
        for c in range(m):
            s -= tr[r, c] * (dZp[c] * rot_0).real
        out[r] = s


@_inner
def _held_omega_partial(held, k, dZr, omega, t, theta, htr, out):
    """``dX(t)/d omega`` of the held flow of the sticking phase after impact k at fixed
    ``t``, start state and start phase into `out`: ``L Re((dZ_r + i t Z_r) e^{i(omega t +
    theta)}) - (L Phi_r L^+) L Re(dZ_r e^{i theta})`` (`htr` the held transition
    ``L Phi_r L^+``, `dZr` ``dZ_r/d omega``; :func:`sticky_frequency_column`)."""
    L, Zr = held.lifts[k], held.Z[k]
    m = out.size
    r = L.shape[1]
    rot_0 = complex(math.cos(theta), math.sin(theta))
    rot_t = complex(math.cos(omega * t + theta), math.sin(omega * t + theta))
    d0 = np.zeros(m)
    for i in range(m):
        a = 0.0
        b = 0.0
        for c in range(r):
            lc = L[i, c]
            if lc != 0.0:
                a += lc * (dZr[c] * rot_0).real
                b += lc * ((dZr[c] + 1j * t * Zr[c]) * rot_t).real
        d0[i] = a
        out[i] = b
    for i in range(m):
        s = 0.0
        for c in range(m):
            s += htr[i, c] * d0[c]
        out[i] -= s


@_inner
def _bounces(flow, forcing, impacts, k, count, Y, theta, J, dT, log, forced):
    """The chatter's bounces after the landing impact k resolved one by one, at most
    `count`: from ``Y`` (right after the landing, on the stop's section, leaving it; updated
    in place to the state after the last resolved impact) at phase `theta`, each flight
    with :func:`_flight`, its return to the stop by :func:`_bounce_return` from the
    parabola's ``2 u / a``, the impact law ``D`` of impact k of `impacts`; stopped where a
    bounce's apex falls within :data:`_BOUNCE_ULPS` ulps of the stop.

    The one loop of :func:`_chatter_map` (with its Jacobian) and :func:`chatter_bounces`
    (with its log), so that the bounces the check replays are bitwise the shooting path's.
    With `J` of shape ``(2n + 1, 2n + 1)`` (``d[Y, theta] / d[X0, theta0]`` so far) and `dT`
    (``dT/d[X0, theta0]``), each bounce's chain rule (its transition, the return time's
    saltation, the impact) is applied to both; with shape (0, 0) and (0,) it is skipped.
    With `J` of shape ``(2n + 1, 2n + 2)`` and `dT` of ``2n + 2`` the last column is
    ``d/d omega`` at fixed ``[X0, theta0]``: each flight's explicit omega dependence (its
    steady forced state, :func:`_flight_omega_partial` of `forced`, the plain tuple ``(Zp,
    dZp)`` of :func:`_forced_vectors`) and the phase's ``t`` join the chain rule.
    `log` is the plain tuple ``(starts, phases, times, arrivals, transitions,
    phase_columns, rates)`` whose row ``i`` each resolved bounce ``i`` fills (the state
    after its impact, its phase, its duration and, at its end, ``X^-``, ``Phi``,
    ``dX^-/dtheta``, ``X'``), or empty arrays (no log).

    Returns ``(status, theta, T)``: the impacts resolved (``-2`` where a return is not
    found), the phase after the last and the time they took.
    """
    starts, phases, times, arrivals, transitions, pcols, rates = log
    D = impacts.matrices[k]
    pivot = impacts.pivots[k]
    normal = impacts.normals[k]
    sign = impacts.signs[k]
    position = impacts.positions[k]
    omega = forcing.omega
    m = Y.size
    n = m // 2
    chain = J.shape[0] > 0
    w = J.shape[1]
    by_omega = w == m + 2  # the last column: d/d omega
    Zp, dZp = forced
    logged = starts.shape[0] > 0
    tr = np.empty((m, m))
    arr = np.empty(m)
    pcol = np.empty(m)
    rate = np.empty(m)
    explicit = np.empty(m)
    work = _flight_work(n)
    stop = (normal, sign, position)
    scratch = (tr, arr, pcol, rate)
    general = flow.general
    modal, first_order = flow.modal, flow.first_order  # each flight reads its own part
    terms = np.empty((_GAP_ROWS, 0 if general else n))
    B = np.empty((m, w))
    dt = np.empty(w)
    th = theta
    T = 0.0
    floor = _BOUNCE_ULPS * _CHATTER_EPS * max(1.0, abs(position))
    status = 0
    for _ in range(count):
        if general:  # _flight_into's branches: a call fewer per flight, 13 arrays fewer
            _flight_general(first_order, forcing, 0.0, Y, th, tr, arr, pcol, rate)
        else:
            _flight_modal_into(modal, forcing, 0.0, Y, th, tr, arr, pcol, rate, work)
        u, a = _stop_speed(normal, sign, rate, n)
        if a > 0.0 and u * u < 2.0 * a * floor:
            break
        # the parabola's return time (an eighth of a period where the stop does not press)
        guess = 2.0 * u / a if a > 0.0 else 0.25 * math.pi / omega
        t = _bounce_return(flow, forcing, Y, th, stop, guess, scratch, terms)
        if not t > 0.0:
            return -2, th, T
        if general:
            _flight_general(first_order, forcing, t, Y, th, tr, arr, pcol, rate)
        else:
            _flight_modal_into(modal, forcing, t, Y, th, tr, arr, pcol, rate, work)
        hd = 0.0
        for c in range(n):
            hd += normal[c] * rate[c]
        if not sign * hd > 0.0:
            return -2, th, T
        if chain:
            for i in range(m):
                for c in range(w):
                    s = pcol[i] * J[m, c]
                    for q in range(m):
                        s += tr[i, q] * J[q, c]
                    B[i, c] = s
            if by_omega:
                _flight_omega_partial(Zp, dZp, omega, t, th, tr, explicit)
                for i in range(m):
                    B[i, m + 1] += explicit[i]
            for c in range(w):
                s = 0.0
                for r in range(n):
                    s += normal[r] * B[r, c]
                dt[c] = -s / hd
            for i in range(m):
                for c in range(w):
                    B[i, c] += rate[i] * dt[c]
            for i in range(m):
                for c in range(w):
                    s = 0.0
                    for q in range(m):
                        s += D[i, q] * B[q, c]
                    J[i, c] = s
            for c in range(w):
                J[m, c] += omega * dt[c]
                dT[c] += dt[c]
            if by_omega:  # th + omega t
                J[m, m + 1] += t
        if logged:
            for c in range(m):
                starts[status, c] = Y[c]
                arrivals[status, c] = arr[c]
                pcols[status, c] = pcol[c]
                rates[status, c] = rate[c]
                for q in range(m):
                    transitions[status, c, q] = tr[c, q]
            phases[status] = th
            times[status] = t
        _apply(D, arr, Y)
        s = position
        for c in range(n):
            if c != pivot:
                s -= normal[c] * Y[c]
        Y[pivot] = s / normal[pivot]
        th += omega * t
        T += t
        status += 1
    return status, th, T


@_inner
def _chatter_map(flow, forcing, impacts, held, k, X0, theta0, X, dX, dtheta, dT, frequency):
    """The chatter map of the stop held after impact k: the state ``X0`` right after the
    landing impact (restitution ``R = held.restitutions[k] > 0``, on the stop's section,
    leaving it) at phase `theta0` to the accumulation point of the chatter it starts.

    The chatter's impacts are resolved one by one, ``held.chatter_impacts[k]`` of them
    (fewer when a bounce's apex falls within :data:`_BOUNCE_ULPS` ulps of the stop): each
    flight with this module's exact flight (:func:`_flight`), its return to the stop by
    Newton from the parabola's ``2 u / a``, the impact law ``D``. From the last impact (the
    stop coordinate leaving at ``u``, pressed at ``a > 0``) the rest of the chatter is
    jumped over (Nordmark & Piiroinen 2009, eq. C1 of :mod:`impactcont.simulate.chatter`,
    derived again here): it accumulates after ``2 u / (a (1 - R))``, and the state there is
    the held flow from the state with the stop coordinate's speed removed by the stop's
    plastic law, ``(D + R I) / (1 + R)``, run for that long: ``O(u^2)`` off the resolved
    chatter.

    Writes ``X`` (the state at the accumulation point), ``dX = dX/dX0``, ``dtheta =
    dX/dtheta0`` and ``dT = [dT/dX0, dT/dtheta0]`` (``T`` the chatter's duration) by the chain
    rule through every resolved flight (its transition, the return time's saltation) and
    impact and through the jump (``u``, ``a`` and the held flow). Returns ``(status, T,
    theta)``: ``status`` the impacts resolved (``>= 0``), ``-1`` where the acceleration of
    the stop coordinate does not point into the stop at the jump (the chatter does not
    accumulate: incomplete), ``-2`` where a bounce's return is not found within two forcing
    periods; on a failure the map is the plastic impact at ``X0`` (``T = 0``) and the status
    says so. The stop and its impact law are impact k's of `impacts`
    (:class:`~impactcont.kernel.arrays.ImpactSequence`).

    `frequency` is the plain tuple ``(Zp, dZp, dZr, dW)``: where ``dW`` has ``2n + 1``
    entries it receives ``[dX/d omega, dT/d omega]`` at fixed ``X0``, `theta0` (exact: each
    resolved flight's steady forced state ``Zp`` and its derivative ``dZp``
    (:func:`_forced_vectors`), its return time and impact, the jump's ``u``, ``a`` (no
    explicit omega: ``a`` is the state derivative at time 0) and the held flow's forced
    amplitude, ``dZr = dZ_r/d omega``; the accumulation phase is ``theta0 + omega T``).
    """
    D = impacts.matrices[k]
    pivot = impacts.pivots[k]
    normal = impacts.normals[k]
    sign = impacts.signs[k]
    m = X0.size
    n = m // 2
    omega = forcing.omega
    R = held.restitutions[k]
    Zp, dZp, dZr, dW = frequency
    by_omega = dW.size > 0
    w = m + 2 if by_omega else m + 1
    J = np.zeros((m + 1, w))  # d[Y, th] / d[X0, theta0(, omega)]
    for c in range(m + 1):
        J[c, c] = 1.0
    Y = X0.copy()
    dTv = np.zeros(w)
    tr = np.empty((m, m))
    arr = np.empty(m)
    pcol = np.empty(m)
    rate = np.empty(m)
    no_log = (np.zeros((0, m)), np.zeros(0), np.zeros(0), np.zeros((0, m)),
              np.zeros((0, m, m)), np.zeros((0, m)), np.zeros((0, m)))
    status, th, T = _bounces(flow, forcing, impacts, k, held.chatter_impacts[k], Y, theta0,
                             J, dTv, no_log, (Zp, dZp))
    dtj = 0.0
    ddt = np.zeros(w)
    if status >= 0:
        _flight(flow, forcing, 0.0, Y, th, tr, arr, pcol, rate)
        u, a = _stop_speed(normal, sign, rate, n)
        if not a > 0.0:
            status = -1
        else:
            dtj = 2.0 * u / (a * (1.0 - R))
            grad = np.empty(m + 1)
            _acceleration_gradient(flow, forcing, normal, sign, th, grad)
            dyn = np.zeros(m + 1)  # d dtj / d[Y, th]
            for c in range(m + 1):
                dyn[c] = -dtj / a * grad[c]
            for c in range(n):
                dyn[n + c] -= 2.0 * sign * normal[c] / (a * (1.0 - R))
            for c in range(w):
                s = 0.0
                for q in range(m + 1):
                    s += dyn[q] * J[q, c]
                ddt[c] = s
    if status < 0:  # the plastic impact at X0
        for i in range(m):
            Y[i] = X0[i]
            for c in range(w):
                J[i, c] = 1.0 if i == c else 0.0
        for c in range(w):
            J[m, c] = 1.0 if c == m else 0.0
            dTv[c] = 0.0
        th = theta0
        T = 0.0
    # the plastic law of the stop, (D + R I) / (1 + R), then s' = 0 exactly
    Q = np.empty((m, m))
    for i in range(m):
        for c in range(m):
            Q[i, c] = (D[i, c] + (R if i == c else 0.0)) / (1.0 + R)
    for c in range(m):
        s = 0.0
        for r in range(n):
            if r != pivot:
                s -= normal[r] * Q[n + r, c]
        Q[n + pivot, c] = s / normal[pivot]
    Yp = np.empty(m)
    for i in range(m):
        s = 0.0
        for c in range(m):
            s += Q[i, c] * Y[c]
        Yp[i] = s
    htr = np.empty((m, m))
    hcol = np.empty(m)
    hrate = np.empty(m)
    _held_segment(held, k, omega, dtj, Yp, th, X, htr, hcol, hrate)
    QJ = np.empty((m, w))
    for i in range(m):
        for c in range(w):
            s = 0.0
            for q in range(m):
                s += Q[i, q] * J[q, c]
            QJ[i, c] = s
    explicit = np.zeros(m)
    if by_omega:  # the held flow's own omega: its forced amplitude
        _held_omega_partial(held, k, dZr, omega, dtj, th, htr, explicit)
    for i in range(m):
        for c in range(w):
            s = hcol[i] * J[m, c] + hrate[i] * ddt[c]
            for q in range(m):
                s += htr[i, q] * QJ[q, c]
            if c < m:
                dX[i, c] = s
            elif c == m:
                dtheta[i] = s
            else:
                dW[i] = s + explicit[i]
    for c in range(m + 1):
        dT[c] = dTv[c] + ddt[c]
    if by_omega:
        dW[m] = dTv[m + 1] + ddt[m + 1]
    return status, T + dtj, th + omega * dtj


@_jit
def held_pressing(held, k, omega, X0, theta, times):
    """The pressing force of the stop held after impact k along its held flow from ``X0``
    at phase `theta`, at each of `times` after the start, shape like `times`: the held
    flow of :func:`_held_segment` (the shooting path's, at the forcing frequency `omega`)
    and :func:`_pressing`. `held` the plain tuple of
    :class:`~impactcont.kernel.arrays.HeldSegments`. Compiled only where a motion with
    sticking phases is checked (``HeldFlow.pressing_minimum``'s samples,
    :func:`impactcont.orbit.sticky.chatter_bounces`'s module); no other entry point calls
    it. The held state of each sample is :func:`_held_segment`'s ``X_c + L Y(t)`` (the same
    arithmetic, without its derivatives)."""
    named = HeldSegments(*held)
    L, Li, Xc = named.lifts[k], named.inverses[k], named.offsets[k]
    g, level, force = named.grads[k], named.levels[k], named.forces[k]
    m = Xc.size
    r = Li.shape[0]
    X = Xc.copy()
    out = np.empty(times.size)
    if r == 0:  # one mass held: the state stays
        for i in range(times.size):
            out[i], _ = _pressing_at(g, level, force, X, theta + omega * times[i])
        return out
    flight, forcing, Y0 = _held_start(named, k, omega, X0)
    tr = np.empty((r, r))
    Y = np.empty(r)
    pcol = np.empty(r)
    yr = np.empty(r)
    for j in range(times.size):
        _flight_general(flight, forcing, times[j], Y0, theta, tr, Y, pcol, yr)
        for i in range(m):
            X[i] = Xc[i]
            for q in range(r):
                lq = L[i, q]
                if lq != 0.0:
                    X[i] += lq * Y[q]
        out[j], _ = _pressing_at(g, level, force, X, theta + omega * times[j])
    return out


@_jit
def chatter_bounces(flight, forcing, impacts, held, k, X0, theta0):
    """The bounces :func:`_chatter_map` resolves after the landing impact k, replayed with
    the same flights, returns and impacts (its Jacobian left out, so the bounces are
    bitwise those of the shooting path): the state right after each resolved impact
    (the landing's first, on the stop's section), its phase and the bounce's duration.
    Compiled only where a chatter-entered motion is checked or drawn
    (:func:`impactcont.orbit.sticky.chatter_bounces`); no other entry point calls it.

    Returns
    -------
    starts : ndarray, shape (K, 2n)
    phases, times : ndarray, shape (K,)
    arrivals, transitions, phase_columns, rates : ndarray
        Each bounce's ``X^-`` (K, 2n), ``Phi`` (K, 2n, 2n), ``dX^-/dtheta`` and ``X'``
        (K, 2n) at its end (as a flight's, for :func:`motion_checks` and
        :func:`end_clearances`).
    count : int
        The bounces resolved (the first ``count`` rows; fewer than K where a bounce's apex
        falls within :data:`_BOUNCE_ULPS` ulps of the stop), ``-2`` where a return is not
        found (the rows before it are still the bounces resolved).
    """
    log, count = _bounce_log(_flights(FlightArrays(*flight)), Forcing(*forcing),
                             ImpactSequence(*impacts), HeldSegments(*held), k, X0, theta0)
    starts, phases, times, arrivals, transitions, pcols, rates = log
    return starts, phases, times, arrivals, transitions, pcols, rates, count


@_inner
def _bounce_log(flow, forcing, impacts, held, k, X0, theta0):
    """The bounces of impact k's chatter replayed from ``(X0, theta0)`` with their log (the
    seven arrays of :func:`chatter_bounces`, K rows) and the count resolved
    (:func:`_bounces` without the Jacobian): for :func:`chatter_bounces` and
    :func:`impactcont.kernel.sticky.chatter_checks`."""
    m = X0.size
    K = held.chatter_impacts[k]
    log = (np.zeros((K, m)), np.zeros(K), np.zeros(K), np.zeros((K, m)), np.zeros((K, m, m)),
           np.zeros((K, m)), np.zeros((K, m)))
    empty = np.zeros(0, dtype=np.complex128)
    count, _, _ = _bounces(flow, forcing, impacts, k, K, X0.copy(), theta0,
                           np.zeros((0, 0)), np.zeros(0), log, (empty, empty))
    return log, count


@_jit
def sticky_system(flight, forcing, impacts, held, period, x, want_jacobian, frequency):
    """Residual (and exact Jacobian) of the shooting system of a motion with sticking
    phases (:func:`impactcont.orbit.sticky.sticky_shooting` documents it).

    `flight`, `forcing`, `impacts` as :func:`shooting_system` takes them, `held` the plain
    tuple of :class:`~impactcont.kernel.arrays.HeldSegments`. Compiled only where a motion
    with sticking phases is solved (no other entry point calls it).

    `frequency` is the plain tuple ``(dgamma, dbeta, dZ, held_dZ, out)``: where ``out``
    (shape (p, 2n)) has rows, row k of each sticking phase entered through complete
    chatter receives ``dX_r/d omega`` of its release state at fixed ``X_k``, ``theta_k``
    and ``s_k`` (through the chatter map, :func:`_chatter_map`, and the held flow after
    it), what :func:`sticky_frequency_column` takes as `chatter_omega`; ``dgamma``,
    ``dbeta``, ``dZ`` as :class:`~impactcont.kernel.arrays.ForcingDerivatives` names them
    and ``held_dZ`` as :func:`sticky_frequency_column` takes it. Empty arrays: not asked.

    Returns
    -------
    tuple
        The fields of :class:`~impactcont.kernel.arrays.StickyFlights`
        (``StickyFlights._make`` names them).
    """
    arrays = FlightArrays(*flight)
    flow = _flights(arrays)
    forcing = Forcing(*forcing)
    impacts = ImpactSequence(*impacts)
    held = HeldSegments(*held)
    pivots, normals = impacts.pivots, impacts.normals
    positions, matrices = impacts.positions, impacts.matrices
    sticks = held.sticks
    omega = forcing.omega
    p = positions.size
    m = matrices.shape[1]
    n = m // 2
    q = 0
    rank = np.zeros(p, dtype=np.int64)
    for k in range(p):
        if sticks[k]:
            rank[k] = q
            q += 1
    size = m * p + q
    z0 = p + q
    stimes = np.zeros(p)
    taus = np.empty(p)
    elapsed = 0.0
    for k in range(p):
        if sticks[k]:
            stimes[k] = x[p + rank[k]]
            elapsed += stimes[k]
        if k < p - 1:
            taus[k] = x[1 + k]
            elapsed += taus[k]
    taus[p - 1] = period - elapsed
    phases = np.empty(p)
    theta = x[0]
    for k in range(p):
        phases[k] = theta
        theta += omega * (stimes[k] + taus[k])
    starts = _section_starts(x, z0, p, m, pivots, normals, positions)
    releases = starts.copy()
    release_phases = phases.copy()
    h_tr = np.zeros((p, m, m))
    h_col = np.zeros((p, m))
    h_rate = np.zeros((p, m))
    arrivals = np.empty((p, m))
    rates = np.empty((p, m))
    transitions = np.empty((p, m, m))
    pcols = np.empty((p, m))
    residual = np.empty(size)
    accumulations = starts.copy()
    accumulation_phases = phases.copy()
    chatter_times = np.zeros(p)
    chatter_status = np.zeros(p)
    dgamma, dbeta, dZ, held_dZ, d_omega = frequency
    by_omega = d_omega.shape[0] > 0
    Zp, dZp = _forced_vectors(arrays.general, arrays.u, forcing, dgamma, dbeta, dZ) if by_omega \
        else (np.zeros(0, dtype=np.complex128), np.zeros(0, dtype=np.complex128))
    dW = np.zeros(m + 1 if by_omega else 0)
    for k in range(p):
        nxt = (k + 1) % p
        if sticks[k] and held.restitutions[k] > 0.0:
            # entered through complete chatter: s_k runs from the landing impact k to the
            # release, the held flow from the accumulation point (dX_r/dX_k and dX_r/dtheta_k
            # through the chatter map and its duration)
            cX = np.empty((m, m))
            cth = np.empty(m)
            cT = np.empty(m + 1)
            status, Tc, th_inf = _chatter_map(
                flow, forcing, impacts, held, k, starts[k], phases[k], accumulations[k], cX,
                cth, cT, (Zp, dZp, held_dZ[k] if by_omega else Zp, dW))
            chatter_status[k] = status
            chatter_times[k] = Tc
            accumulation_phases[k] = th_inf
            Htr = np.empty((m, m))
            Hcol = np.empty(m)
            _held_segment(held, k, omega, stimes[k] - Tc, accumulations[k], th_inf,
                          releases[k], Htr, Hcol, h_rate[k])
            for i in range(m):
                w = Hcol[i] * omega - h_rate[k, i]
                s = Hcol[i] * (1.0 + omega * cT[m]) - h_rate[k, i] * cT[m]
                for q in range(m):
                    s += Htr[i, q] * cth[q]
                h_col[k, i] = s
                for c in range(m):
                    s = w * cT[c]
                    for q in range(m):
                        s += Htr[i, q] * cX[q, c]
                    h_tr[k, i, c] = s
            if by_omega:  # the held flow's own omega, then through its start and duration
                _held_omega_partial(held, k, held_dZ[k], omega, stimes[k] - Tc, th_inf, Htr,
                                    d_omega[k])
                for i in range(m):
                    s = Hcol[i] * (Tc + omega * dW[m]) - h_rate[k, i] * dW[m]
                    for q in range(m):
                        s += Htr[i, q] * dW[q]
                    d_omega[k, i] += s
            release_phases[k] = phases[k] + omega * stimes[k]
            force, _ = _pressing(held, k, releases[k], release_phases[k])
            residual[p * m + rank[k]] = force
        elif sticks[k]:
            _held_segment(held, k, omega, stimes[k], starts[k], phases[k], releases[k],
                          h_tr[k], h_col[k], h_rate[k])
            release_phases[k] = phases[k] + omega * stimes[k]
            force, _ = _pressing(held, k, releases[k], release_phases[k])
            residual[p * m + rank[k]] = force
        else:
            for i in range(m):
                h_tr[k, i, i] = 1.0
        _flight(flow, forcing, taus[k], releases[k], release_phases[k], transitions[k],
                arrivals[k], pcols[k], rates[k])
        for r in range(m):
            s = 0.0
            for c in range(m):
                s += matrices[nxt, r, c] * arrivals[k, c]
            residual[k * m + r] = s - starts[nxt, r]
    # the contact search of a flight from a release starts held.shifts[k] after it
    search_shifts = np.zeros(p)
    search_starts = releases.copy()
    search_phases = release_phases.copy()
    work_tr = np.empty((m, m))
    work_col = np.empty(m)
    work_rate = np.empty(m)
    for k in range(p):
        if sticks[k]:
            shift = min(held.shifts[k], 0.5 * taus[k])
            if shift > 0.0:
                search_shifts[k] = shift
                search_phases[k] += omega * shift
                _flight(flow, forcing, shift, releases[k], release_phases[k], work_tr,
                        search_starts[k], work_col, work_rate)
    J = np.zeros((0, 0))
    if want_jacobian:
        J = np.zeros((size, size))
        d_theta = np.zeros(size)  # d theta_k / du, built along the segments
        d_theta[0] = 1.0
        dXr = np.empty((m, size))
        dXm = np.empty((m, size))
        for k in range(p):
            nxt = (k + 1) % p
            d_tau = np.zeros(size)
            if k < p - 1:
                d_tau[1 + k] = 1.0
            else:
                for c in range(1, z0):
                    d_tau[c] = -1.0
            d_stick = np.zeros(size)
            if sticks[k]:
                d_stick[p + rank[k]] = 1.0
            # dX_r/du: the held flow of dX_k/du (the section's lift of z_k), theta_k, s_k
            j = pivots[k]
            col0 = z0 + k * (m - 1)
            for i in range(m):
                for c in range(size):
                    dXr[i, c] = h_col[k, i] * d_theta[c] + h_rate[k, i] * d_stick[c]
                _add_lifted_row(h_tr[k], normals[k], j, i, dXr, col0)
            # dX^-/du = Phi dX_r + dX^-/dtheta (d theta_k + omega ds_k) + X' dtau_k
            for i in range(m):
                for c in range(size):
                    s = pcols[k, i] * (d_theta[c] + omega * d_stick[c]) + rates[k, i] * d_tau[c]
                    for a in range(m):
                        s += transitions[k, i, a] * dXr[a, c]
                    dXm[i, c] = s
            jn = pivots[nxt]
            ncol = z0 + nxt * (m - 1)
            for r in range(m):
                row = k * m + r
                for c in range(size):
                    s = 0.0
                    for a in range(m):
                        s += matrices[nxt, r, a] * dXm[a, c]
                    J[row, c] = s
                if r != jn:  # - dX_{k+1}/dz_{k+1}
                    J[row, ncol + (r if r < jn else r - 1)] -= 1.0
                else:
                    for c in range(n):
                        if c != jn and normals[nxt, c] != 0.0:
                            J[row, ncol + (c if c < jn else c - 1)] += (normals[nxt, c]
                                                                        / normals[nxt, jn])
            if sticks[k]:
                row = p * m + rank[k]
                _, gth = _pressing(held, k, releases[k], release_phases[k])
                g = held.grads[k]
                for c in range(size):
                    s = gth * (d_theta[c] + omega * d_stick[c])
                    for a in range(m):
                        s += g[a] * dXr[a, c]
                    J[row, c] = s
            for c in range(size):
                d_theta[c] += omega * (d_stick[c] + d_tau[c])
    return (phases, stimes, taus, starts, releases, release_phases, h_tr, h_col, h_rate,
            arrivals, rates, transitions, pcols, residual, J, search_shifts, search_starts,
            search_phases, accumulations, accumulation_phases, chatter_times, chatter_status)


@_inner
def _add_lifted_row(tr, normal, j, i, out, first):
    """Row i of ``tr dX/dz`` added to ``out[i, first:first + 2n - 1]``: ``dX/dz`` the lift
    of the section ``normal . x = c`` (pivot j) to the state, the unit columns but j's and
    the pivot's row ``-n_c / n_j`` (:func:`sticky_system`'s ``dX_r/du``,
    :func:`sticky_jacobians`)."""
    m = tr.shape[0]
    n = m // 2
    col = first
    for c in range(m):
        if c == j:
            continue
        v = tr[i, c]
        if c < n and normal[c] != 0.0:
            v -= tr[i, j] * normal[c] / normal[j]
        out[i, col] += v
        col += 1


@_jit
def sticky_frequency_column(flow, forcing, derivatives, impacts, held, held_dZ, period, shot,
                            chatter_omega):
    """``dr/d omega`` of the shooting system of a motion with sticking phases at fixed
    unknowns, shape (2np + q,): :func:`frequency_column` with the sticking phases.

    `flow`, `forcing`, `derivatives`, `impacts` as :func:`frequency_column` takes them,
    `held` as :func:`sticky_system`, `held_dZ` ``dZ/d omega`` of each held system's
    steady amplitude (``(p, 2n - 2)`` complex, zeros where no stick follows an impact;
    :meth:`impactcont.orbit.flow.GeneralFlow.omega_arrays` of the held system), `period`
    the motion's ``2 pi N / omega`` and `shot` the plain tuple
    :func:`sticky_system` returns at the unknowns (the Jacobian is not read), and
    `chatter_omega` (p, 2n) what :func:`sticky_system` writes into its ``frequency``'s
    ``out`` there: ``dX_r/d omega`` at fixed ``X_k``, ``theta_k``, ``s_k`` of each sticking
    phase entered through complete chatter (the chatter map's omega, exact; the rows of
    the others are not read). Compiled only where a motion with sticking phases is
    continued in omega.

    Notes
    -----
    At fixed unknowns omega moves four things (:func:`sticky_system`): the phases
    ``theta_k = delta + omega sum_{i<k} (s_i + tau_i)`` (``d theta_k / d omega =
    sum_{i<k} (s_i + tau_i)``) and the release phases ``theta_k + omega s_k``; the last
    flight time ``tau_{p-1} = period - sum`` (``-period / omega``); the steady forced
    state of each flight (:func:`omega_partials`, from the release); and that of each held
    system, ``Y_p = Re(Z_r e^{i(omega t + theta)})``, so that at fixed ``t``, ``Y(0)`` and
    ``theta`` the held state moves by ``L (Re((dZ_r + i t Z_r) e^{i(omega s_k + theta_k)})
    - Phi_r(s_k) Re(dZ_r e^{i theta_k}))`` (``L Phi_r = (L Phi_r L^+) L``, the held
    transition the shot carries). The release row ``p = grad . X_r + Re(force e^{i
    theta_r}) + level`` moves with ``X_r`` and ``theta_r`` (its force and level do not
    depend on omega). Each flight's change reaches row k through ``D_{k+1}``.
    """
    named = HeldSegments(*held)
    sticks, lifts, Zr = named.sticks, named.lifts, named.Z
    omega = Forcing(*forcing).omega
    matrices = ImpactSequence(*impacts).matrices
    sf = StickyFlights(*shot)
    stimes, taus, rphases = sf.stick_times, sf.flight_times, sf.release_phases
    h_tr, h_col, pcols, rates = (sf.held_transitions, sf.held_phase_columns, sf.phase_columns,
                                 sf.arrival_rates)
    transitions = sf.transitions
    p = taus.size
    m = matrices.shape[1]
    r = lifts.shape[2]
    explicit = omega_partials(flow, forcing, derivatives,
                              (rphases, taus, sf.releases, sf.arrivals, rates, transitions,
                               pcols, sf.residual, np.zeros((0, 0))))
    q = 0
    for k in range(p):
        if sticks[k]:
            q += 1
    out = np.zeros(m * p + q)
    d_release = np.zeros(m)  # dX_r / d omega
    moved = np.zeros(m)
    d0 = np.empty(m)
    dt = np.empty(m)
    elapsed = 0.0  # d theta_k / d omega
    row = m * p
    for k in range(p):
        nxt = (k + 1) % p
        d_phase = elapsed + stimes[k]  # d theta_r / d omega
        for i in range(m):
            d_release[i] = 0.0
        if sticks[k] and named.restitutions[k] > 0.0:  # through the chatter map
            for i in range(m):
                d_release[i] = chatter_omega[k, i] + h_col[k, i] * elapsed
        elif sticks[k]:
            s = stimes[k]
            theta = rphases[k] - omega * s
            rot_0 = complex(math.cos(theta), math.sin(theta))
            rot_t = complex(math.cos(rphases[k]), math.sin(rphases[k]))
            for i in range(m):  # L Re(dZ e^{i theta}) and L Re((dZ + i s Z) e^{i theta_r})
                a = 0.0
                b = 0.0
                for c in range(r):
                    lc = lifts[k, i, c]
                    if lc != 0.0:
                        a += lc * (held_dZ[k, c] * rot_0).real
                        b += lc * ((held_dZ[k, c] + 1j * s * Zr[k, c]) * rot_t).real
                d0[i] = a
                dt[i] = b
            for i in range(m):
                v = dt[i] + h_col[k, i] * elapsed
                for c in range(m):
                    v -= h_tr[k, i, c] * d0[c]
                d_release[i] = v
        if sticks[k]:  # the release row
            g = named.grads[k]
            e = complex(math.cos(rphases[k]), math.sin(rphases[k])) * named.forces[k]
            v = (1j * e).real * d_phase
            for i in range(m):
                v += g[i] * d_release[i]
            out[row] = v
            row += 1
        for i in range(m):
            v = explicit[k, i] + pcols[k, i] * d_phase
            if k == p - 1:
                v -= rates[k, i] * period / omega
            for c in range(m):
                v += transitions[k, i, c] * d_release[c]
            moved[i] = v
        for i in range(m):
            v = 0.0
            for c in range(m):
                v += matrices[nxt, i, c] * moved[c]
            out[k * m + i] = v
        elapsed += stimes[k] + taus[k]
    return out


@_jit
def unknowns_scale(x):
    """``max(1, |delta|, |tau|, |z|)``, Newton's tolerance scale, the phase ``x[0]`` counted
    at most pi (the residual is 2 pi periodic in it: a phase run off to 1e14 must not
    loosen the test); :func:`impactcont.orbit.multi_impact.unknowns_scale` in Python."""
    return max(1.0, min(abs(x[0]), math.pi), _max_abs(x[1:]))


@_inner
def _max_abs(v):
    """``max |v|``, NaN when any entry is NaN (as ``np.max(np.abs(v))``)."""
    out = 0.0
    for x in v:
        if x != x:
            return np.nan
        if abs(x) > out:
            out = abs(x)
    return out


@_jit
def _solve(A, rhs):
    """``A^-1 rhs`` by Gaussian elimination with partial pivoting; ``ok`` False when a
    pivot is exactly zero (a singular matrix, as LAPACK's ``getrf`` reports it)."""
    x = rhs.copy()
    return x, _solve_in_place(A.copy(), x)


@_jit
def newton_solve(flight, forcing, impacts, period, x0, tol, max_iter):
    """Newton's method with backtracking on :func:`shooting_system` from ``x0``.

    The iteration of :func:`impactcont.orbit.multi_impact.newton` (which documents the
    stopping rules), compiled (:func:`_newton`); `flight`, `forcing`, `impacts` and
    `period` as :func:`shooting_system` takes them.

    Returns
    -------
    tuple
        The fields of :class:`~impactcont.kernel.arrays.NewtonResult`
        (``NewtonResult.from_kernel`` names them): ``status`` :data:`CONVERGED` or
        :data:`FAILED`, ``shot`` the :func:`shooting_system` at ``x`` (with its Jacobian).
    """
    return _newton(_flights(FlightArrays(*flight)), Forcing(*forcing), ImpactSequence(*impacts),
                   None, period, None, x0, tol, max_iter)


@_jit
def sticky_newton_solve(flight, forcing, impacts, held, period, x0, tol, max_iter):
    """:func:`newton_solve` on :func:`sticky_system`: the same iteration and stopping rules
    (:func:`_newton`) for a motion with sticking phases (`held` the plain tuple of
    :class:`~impactcont.kernel.arrays.HeldSegments`).

    Returns
    -------
    tuple
        ``(x, status, iterations, residual_norm, step_norm, shot)`` as :func:`newton_solve`,
        ``shot`` the plain tuple of :class:`~impactcont.kernel.arrays.StickyFlights` at
        ``x`` (with its Jacobian).
    """
    empty = np.zeros(0)
    empty_c = np.zeros(0, dtype=np.complex128)
    frequency = (empty, empty, empty_c, np.zeros((0, 0), dtype=np.complex128),
                 np.zeros((0, 0)))  # no omega column
    return _newton(flight, forcing, impacts, held, period, frequency, x0, tol, max_iter)


def _newton_system(flight, forcing, impacts, held, period, frequency, x):
    """``(residual, jacobian, shot)`` at ``x`` for :func:`_newton`, in compiled code only
    (numba takes :func:`_shooting_residual` where `held` is None, else
    :func:`_sticky_residual`: :func:`_newton_system_of`)."""
    raise TypeError("_newton_system is called from compiled code only")


@overload(_newton_system, jit_options=dict(error_model="numpy"))  # the kernel's x / 0
def _newton_system_of(flight, forcing, impacts, held, period, frequency, x):
    """:func:`_newton_system` for the types of a call: one Newton loop, each entry point
    compiles it with its own system."""
    return _shooting_residual if isinstance(held, types.NoneType) else _sticky_residual


def _shooting_residual(flight, forcing, impacts, held, period, frequency, x):
    """:func:`_newton_system` of :func:`_shooting_system` (`flight`, `forcing` and
    `impacts` named; `held` and `frequency` None): the shot the plain tuple
    :func:`newton_solve` returns."""
    sh = _shooting_system(flight, forcing, impacts, period, x, _jacobian_wanted(x))
    return sh.residual, sh.jacobian, _shot_tuple(sh)


def _sticky_residual(flight, forcing, impacts, held, period, frequency, x):
    """:func:`_newton_system` of :func:`sticky_system` (its arguments)."""
    out = sticky_system(flight, forcing, impacts, held, period, x, _jacobian_wanted(x),
                        frequency)
    named = StickyFlights(*out)
    return named.residual, named.jacobian, out


@_inner
def _newton(flight, forcing, impacts, held, period, frequency, x0, tol, max_iter):
    """Newton's method with backtracking from ``x0`` on :func:`_newton_system` (its
    arguments but ``x``): the one loop of :func:`newton_solve` (`held` and `frequency`
    None) and :func:`sticky_newton_solve`.

    The stopping rules of :func:`impactcont.orbit.multi_impact.newton`: converged when
    ``max|r| <= tol * scale`` and the last step's max-norm too (or at `max_iter`), or when
    within tol a step does not lower the residual (its rounding floor); each step halved
    until the residual falls (down to a thousandth). Returns ``(x, status, iterations,
    residual_norm, step_norm, shot)``, the shot at ``x``."""
    x = x0.copy()
    residual, J, shot = _newton_system(flight, forcing, impacts, held, period, frequency, x)
    norm = _max_abs(residual)
    step_norm = np.inf
    it = 0
    for it in range(max_iter + 1):
        bound = tol * unknowns_scale(x)
        small, converged = _converged(norm, step_norm, bound, it, max_iter)
        if converged:
            return (x, CONVERGED, it, norm, step_norm, shot)
        if it == max_iter:
            break
        if not np.all(np.isfinite(J)):
            break
        step, ok = _solve(J, -residual)
        if not ok:
            break
        lam_step = 1.0
        while True:
            trial = x + lam_step * step
            t_residual, t_J, t_shot = _newton_system(flight, forcing, impacts, held, period,
                                                     frequency, trial)
            tnorm = _max_abs(t_residual)
            outcome = _trial_outcome(tnorm, norm, small, bound, lam_step)
            if outcome == FLOOR:  # within tol, the update does not lower the residual
                return (x, CONVERGED, it, norm, step_norm, shot)
            if outcome == TAKE:
                break
            lam_step *= 0.5
        step_norm = lam_step * _max_abs(step)
        x = trial
        residual, J, shot = t_residual, t_J, t_shot
        norm = tnorm
    return (x, FAILED, it, norm, step_norm, shot)


@_jit
def sticky_jacobians(impacts, held, omega, segments):
    """``G_k`` of each segment of a motion with sticking phases (impact k's section to
    impact ``k + 1``'s, in ``[z, theta]``) and their product ``G``, from its shot:
    :func:`impactcont.orbit.sticky.sticky_jacobians` (which documents them), compiled.

    `impacts` and `held` as :func:`sticky_system` takes them, `segments` the plain tuple
    ``(releases, release_phases, held_transitions, held_phase_columns, held_rates,
    transitions, phase_columns, arrival_rates)`` of the shot
    (:class:`~impactcont.kernel.arrays.StickyFlights`). A sticking phase's duration moves
    by the release row's saltation ``ds = -(dp/dX dX_r + dp/dtheta dtheta_r) / (dp/dt)``
    (:func:`_pressing`'s gradient, as :func:`sticky_system`'s release row), each flight's
    by eq. (25)'s ``dtau = -(n . B) / (n . X')``.

    Returns
    -------
    jacobians : ndarray, shape (p, 2n, 2n)
    G : ndarray, shape (2n, 2n)
    """
    sequence = ImpactSequence(*impacts)
    named = HeldSegments(*held)
    releases, rphases, h_tr, h_col, h_rate, transitions, pcols, rates = segments
    matrices, normals, pivots = sequence.matrices, sequence.normals, sequence.pivots
    p = pivots.size
    m = matrices.shape[1]
    n = m // 2
    jacs = np.empty((p, m, m))
    G = np.eye(m)
    cols = np.empty((m, m))  # dX_r / d[z_k, theta_k]
    th = np.empty(m)  # d theta_r / d[z_k, theta_k]
    B = np.empty((m, m))
    dtau = np.empty(m)
    for k in range(p):
        nxt = (k + 1) % p
        j = pivots[k]
        for i in range(m):  # the held transition times the section's lift, the phase column
            for c in range(m - 1):
                cols[i, c] = 0.0
            _add_lifted_row(h_tr[k], normals[k], j, i, cols, 0)
            cols[i, m - 1] = h_col[k, i]
        for c in range(m):
            th[c] = 0.0
        th[m - 1] = 1.0
        if named.sticks[k]:
            grad = named.grads[k]
            _, gth = _pressing(named, k, releases[k], rphases[k])
            rate = omega * gth
            for i in range(m):
                rate += grad[i] * h_rate[k, i]
            for c in range(m):
                s = gth * th[c]
                for i in range(m):
                    s += grad[i] * cols[i, c]
                ds = -s / rate
                for i in range(m):
                    cols[i, c] += h_rate[k, i] * ds
                th[c] += omega * ds
        for i in range(m):
            for c in range(m):
                s = pcols[k, i] * th[c]
                for q in range(m):
                    s += transitions[k, i, q] * cols[q, c]
                B[i, c] = s
        h2 = 0.0
        for r in range(n):
            h2 += normals[nxt, r] * rates[k, r]
        for c in range(m):
            s = 0.0
            for r in range(n):
                s += normals[nxt, r] * B[r, c]
            dtau[c] = -s / h2
        jn = pivots[nxt]
        for i in range(m):
            if i == jn:
                continue
            row = i if i < jn else i - 1
            for c in range(m):
                s = 0.0
                for q in range(m):
                    s += matrices[nxt, i, q] * (B[q, c] + rates[k, q] * dtau[c])
                jacs[k, row, c] = s
        for c in range(m):
            jacs[k, m - 1, c] = th[c] + omega * dtau[c]
        G = jacs[k] @ G
    return jacs, G


# -- G, multipliers and the interior-contact check ----------------------------------------------
@_inner
def _flight_jacobian(tr, pcol, rate, D, j, j_end, n_start, n_end, omega, G):
    """``G_k`` of eq. (25) into ``G`` (as ``multi_impact.flight_jacobian``); returns
    ``h2 = n_end . x'(tau^-)``, the arrival velocity of the stop coordinate.

    The flight starts on the section ``n_start . x = c`` (coordinates ``z``: ``X``
    without ``x_j``) and ends on ``n_end . x = c'`` (coordinates ``X`` without
    ``x_{j_end}``, the next stop's own mass): with ``B = Phi dX/dz``,
    ``h0 = n_end . B``, ``h1 = n_end . E'``, ``h2 = n_end . X'`` the impact time moves by
    ``dtau = -(h0 dz + h1 dtheta) / h2`` and the state after the impact by
    ``D (B dz + E' dtheta + X' dtau)``.
    """
    m = D.shape[0]
    n = m // 2
    h2 = 0.0
    h1 = 0.0
    for c in range(n):
        h2 += n_end[c] * rate[c]
        h1 += n_end[c] * pcol[c]
    B = np.empty((m, m))  # columns: dX^-/dz (m - 1 of them), then dX^-/dtheta
    col = 0
    for c in range(m):
        if c == j:
            continue
        for r in range(m):
            v = tr[r, c]
            if c < n:
                v -= tr[r, j] * n_start[c] / n_start[j]
            B[r, col] = v
        col += 1
    for r in range(m):
        B[r, m - 1] = pcol[r]
    h = np.empty(m)
    for c in range(m):
        s = 0.0
        for r in range(n):
            s += n_end[r] * B[r, c]
        h[c] = s
    h[m - 1] = h1
    for c in range(m):
        for r in range(m):
            B[r, c] -= rate[r] * h[c] / h2
    DB = np.empty((m, m))
    _apply_matrix(D, B, DB)
    row = 0
    for r in range(m):
        if r == j_end:
            continue
        for c in range(m):
            G[row, c] = DB[r, c]
        row += 1
    for c in range(m - 1):
        G[m - 1, c] = -omega * h[c] / h2
    G[m - 1, m - 1] = 1.0 - omega * h1 / h2
    return h2


@_inner
def _search_inputs(flow, forcing, normal, X0, theta):
    """:class:`~impactcont.kernel.arrays.StopSeries` of ``s = n . x`` along a
    flight for the kernel's search: the forced part ``Gamma cos + B sin`` of the phase, the
    free deviation (modal weights ``n^T U``; for the first-order flow ``n^T`` of the
    position rows of ``V`` and ``Z``), the constant ``level`` the constant force adds to
    ``s`` and its polynomial part in time (:func:`impactcont.kernel.contact.drift_x1`):
    ``pg, pd``, the weighted static force ``(n^T U)_i g_i`` and decay ``a_i`` of each free
    mode it pushes (modal flow), ``p1 = n . d`` the drift per unit time (first-order
    flow)."""
    omega = forcing.omega
    c0 = math.cos(theta)
    s0 = math.sin(theta)
    level = 0.0
    if flow.general:
        lam, V, Vi, Z = flow.lam, flow.V, flow.Vi, forcing.Z
        pk, pj = flow.pk, flow.pj
        m = lam.size
        n = m // 2
        rot = complex(c0, s0)
        xs = flow.xs
        xd = flow.xd
        dev = np.empty(m)
        for c in range(m):
            dev[c] = X0[c] - (Z[c] * rot).real
        drift = 0.0
        N = _nilpotent(lam, V, Vi)
        chains = N.shape[0] > 0
        quadratic = 0.0  # n . N d: an undamped free mode's g t^2 / 2
        if xs.size > 0:
            for c in range(m):
                dev[c] -= xs[c]
            for r in range(n):
                level += normal[r] * xs[r]
                drift += normal[r] * xd[r]
                if chains:
                    for c in range(m):
                        quadratic += normal[r] * N[r, c] * xd[c]
        coef = np.empty(m, dtype=np.complex128)  # (n^T V)_k zeta_k
        zeta = np.empty(m, dtype=np.complex128)
        zn = 0j
        for r in range(n):
            zn += normal[r] * Z[r]
        for k in range(m):
            s = 0j
            for c in range(m):
                s += Vi[k, c] * dev[c]
            vn = 0j
            for r in range(n):
                vn += normal[r] * V[r, k]
            coef[k] = vn * s
            zeta[k] = s
        npair = flow.pw.size
        dy = np.empty(npair)
        dv = np.empty(npair)
        for i in range(npair):
            k = pk[i]
            q = pj[i]
            if chains and _generalized(lam, V, q):  # a Jordan chain: y0 + v0 t (w = a = 0)
                dy[i] = (coef[k] + coef[q]).real
                vq = 0j  # n . (the velocity part of [0; u] moved up) zeta_q: the t term
                for r in range(n):
                    vq += normal[r] * V[n + r, q]
                dv[i] = (vq * zeta[q]).real
            elif lam[k].imag != 0.0:  # a conjugate pair: Re((c_k + conj c_q) e^{lam_k t})
                total = coef[k] + np.conj(coef[q])
                dy[i] = total.real
                dv[i] = (total * lam[k]).real
            else:  # two real eigenvalues
                dy[i] = (coef[k] + coef[q]).real
                dv[i] = (coef[k] * lam[k] + coef[q] * lam[q]).real
        pg = np.zeros(1 if quadratic != 0.0 else 0)
        if quadratic != 0.0:
            pg[0] = quadratic
        return StopSeries(flow.pw, flow.pa, np.ones(npair), zn.real, -zn.imag, dy, dv, level,
                          pg, np.zeros(pg.size), drift)
    w, a, u, ui = flow.w, flow.a, flow.u, flow.ui
    gam, bet = forcing.gamma, forcing.beta
    n = w.size
    g_static = flow.g
    free = flow.free
    u0 = np.zeros(n)
    for r in range(n):
        if normal[r] != 0.0:
            for i in range(n):
                u0[i] += normal[r] * u[r, i]
    dy = np.empty(n)
    dv = np.empty(n)
    Gam = 0.0
    B = 0.0
    pushed = 0
    for i in range(n):
        y0 = 0.0
        v0 = 0.0
        for c in range(n):
            y0 += ui[i, c] * X0[c]
            v0 += ui[i, c] * X0[n + c]
        dy[i] = y0 - (gam[i] * c0 + bet[i] * s0)
        dv[i] = v0 - omega * (bet[i] * c0 - gam[i] * s0)
        Gam += u0[i] * gam[i]
        B += u0[i] * bet[i]
        if g_static.size > 0 and g_static[i] != 0.0 and u0[i] != 0.0:
            if free[i]:
                pushed += 1
            else:
                q = g_static[i] / (w[i] * w[i])
                dy[i] -= q
                level += u0[i] * q
    # a free mode's state is W(t) (Y(0) - forced) + S(t), S(0) = 0: dy, dv stay its
    # deviation and S, the polynomial part, goes to the search's drift terms
    pg = np.empty(pushed)
    pd = np.empty(pushed)
    k = 0
    for i in range(n):
        if pushed > 0 and g_static[i] != 0.0 and u0[i] != 0.0 and free[i]:
            pg[k] = u0[i] * g_static[i]
            pd[k] = a[i]
            k += 1
    return StopSeries(w, a, u0, Gam, B, dy, dv, level, pg, pd, 0.0)


@_inner
def _series_extrema(series, omega, theta, tau, sign, both):
    """``(top, time, low, time_low, capped)``: the highest maximum of ``sign s`` on a flight
    of duration `tau` (:func:`impactcont.kernel.contact.stop_maximum`, the constant level
    left out) and, with `both`, that of ``-sign s`` on the same grid (``-inf`` and NaN
    without); ``capped`` as :func:`impactcont.kernel.contact.time_grid` says. The grid,
    the free part of `series` and the forcing's cosine and sine on it are built once."""
    times, capped = time_grid(series.w, series.a, series.weights, omega, tau)
    free = drift_on_grid(times, series.pg, series.pd, series.p1,
                         free_on_grid(times, series.w, series.a, series.weights, series.dy,
                                      series.dv))
    cw = np.cos(omega * times)
    sw = np.sin(omega * times)
    work = np.empty((WORK_ROWS, 2 * times.size))
    top, t_top = stop_maximum(times, free, cw, sw, sign * series.gamma, sign * series.beta,
                              omega, theta, sign, series.w, series.a, series.weights, series.dy,
                              series.dv, series.pg, series.pd, series.p1, work, np.nan)
    low = -np.inf
    t_low = np.nan
    if both:
        low, t_low = stop_maximum(times, free, cw, sw, -sign * series.gamma,
                                  -sign * series.beta, omega, theta, -sign, series.w, series.a,
                                  series.weights, series.dy, series.dv, series.pg, series.pd,
                                  series.p1, work, np.nan)
    return top, t_top, low, t_low, capped


@_inner
def _clearances(flow, forcing, stops, X0, theta, tau):
    """Eq. (16) on one flight against both stops U, L of ``s = stops.normal . x``:
    ``(gap_upper, time_upper, gap_lower, time_lower, capped)`` (a gap ``+inf`` and its time
    NaN where there is no extremum). The constant force's level and polynomial part (a free
    mode it pushes) are in the searched coordinate, so every flight is checked."""
    omega = forcing.omega
    series = _search_inputs(flow, forcing, stops.normal, X0, theta)
    # the highest maximum of -s is the lowest minimum of s
    top, t_top, low, t_low, capped = _series_extrema(series, omega, theta, tau, 1.0,
                                                     stops.two_sided)
    gap_l = np.inf
    t_l = np.nan
    if stops.two_sided:
        gap_l = stops.b_low - low + series.level
        t_l = t_low
    return stops.b - top - series.level, t_top, gap_l, t_l, capped


@_inner
def _stop_clearance(flow, forcing, stops, i, X0, theta, tau):
    """Eq. (16) on one flight against the further stop `i` of `stops`, met with ``sign s' >
    0`` at ``s = position`` (``s = n . x``): ``(gap, time, capped)``, ``gap = sign
    (position - s)`` at the extremum of ``s`` nearest the stop (``+inf`` and time NaN where
    there is none)."""
    omega = forcing.omega
    sign = stops.extra_signs[i]
    series = _search_inputs(flow, forcing, stops.extra_normals[i], X0, theta)
    # a run-time False (i >= 0): a literal False would compile _series_extrema a second time
    top, t_top, _, _, capped = _series_extrema(series, omega, theta, tau, sign, i < 0)
    return sign * stops.extra_positions[i] - top - sign * series.level, t_top, capped


#: A stop's clearance at an impact state, ``sign (c - n . x)``, is judged against the
#: rounding of its own evaluation, relative to the motion's size along that coordinate: the
#: positions at a flight's end come from the flow (modal sums, each exact to a few ulps of
#: its terms) and ``n . x`` adds one ulp per term, so a clearance above ``-64 eps (|c| + sum
#: |n_i x_i|)`` cannot be told from 0 (the motion is at its grazing point) and one below it
#: is a stop crossed. An absolute bound would be wrong at either end of the scale: it would
#: hide a real crossing on a motion of size 1e-6 and call rounding a crossing at size 1e6.
_END_ULPS = 64.0
_EPS = 2.220446049250313e-16


@_inner
def _at_state(x, normal, sign, position):
    """``(sign (position - normal . x), |position| + sum |normal_i x_i|)``: a stop's clearance
    at the positions ``x`` (the first ``n`` entries of a state) and the size it is summed
    from."""
    s = 0.0
    size = abs(position)
    for i in range(normal.size):
        t = normal[i] * x[i]
        s += t
        size += abs(t)
    return sign * (position - s), size


@_inner
def _same_stop(normal, sign, own_normal, own_sign):
    """The stop ``(normal, sign)`` is the one an impact with ``(own_normal, own_sign)``
    hits: the same coordinate met from the same side (two such stops are refused by
    :meth:`impactcont.model.stops.Stops.check`, so this names one stop)."""
    same = sign == own_sign
    for i in range(normal.size):
        same = same and normal[i] == own_normal[i]
    return same


@_inner
def _candidate(x, normal, sign, position, own_normal, own_sign):
    """``(clearance, size, own)`` of one stop at the positions ``x`` (:func:`_at_state`) and
    whether it is the stop the impact hits (:func:`_same_stop`; its clearance is then
    not computed)."""
    if _same_stop(normal, sign, own_normal, own_sign):
        return 0.0, 0.0, True
    e, size = _at_state(x, normal, sign, position)
    return e, size, False


@_inner
def _state_clearance(x, own_normal, own_sign, normal, two_sided, b, b_low, extra_normals,
                     extra_signs, extra_positions):
    """Every stop's clearance at the state ``x`` of an impact on the stop ``(own_normal,
    own_sign)``, but that stop's own (0 by construction): ``(clearance, stop, tol)``, the
    smallest clearance, which stop has it (0: U, 1: L, ``2 + i``: extra stop i; -1 and
    ``+inf`` when no other stop exists) and the rounding ``tol`` of that clearance
    (:data:`_END_ULPS`): a clearance below ``-tol`` is a stop crossed at the impact.

    The U and L of ``s = normal . x`` sit at ``s = b`` (met with ``s' > 0``) and ``s =
    -b_low`` (met with ``s' < 0``); the opposite side of the impact's own coordinate is
    checked as any other stop.
    """
    best = np.inf
    which = -1
    tol = 0.0
    for i in range(extra_signs.size + 2):
        if i == 0:
            e, size, own = _candidate(x, normal, 1.0, b, own_normal, own_sign)
        elif i == 1:
            if not two_sided:
                continue
            e, size, own = _candidate(x, normal, -1.0, -b_low, own_normal, own_sign)
        else:
            e, size, own = _candidate(x, extra_normals[i - 2], extra_signs[i - 2],
                                      extra_positions[i - 2], own_normal, own_sign)
        if own:
            continue
        if which < 0 or e < best:
            best = e
            which = i
            tol = _END_ULPS * _EPS * size
    return best, which, tol


@_jit
def end_clearances(normal, two_sided, b, b_low, normals, signs, extra_normals, extra_signs,
                   extra_positions, starts, arrivals):
    """Every stop's clearance at both ends of every flight (the impact states).

    The search of eq. (16) looks at the interior extrema of each stop coordinate; a
    coordinate still moving towards a stop when the flight ends on another stop has
    none there. Here flight k is checked at its start ``starts[k]`` (just after impact
    k) against every stop but the one impact k hits, and at its end ``arrivals[k]``
    (just before impact ``k + 1``) against every stop but the one impact ``k + 1`` hits.
    Positions do not jump at an impact, so both ends see the same positions of an impact
    state (up to the shooting residual); each is computed from its own flight, so that
    the smallest clearance over a flight, interior extrema and ends, changes
    continuously as an extremum leaves the flight through an end (the GR test function).

    Parameters
    ----------
    normal, two_sided, b, b_low
        The stop coordinate of U and L and their positions (``s = b``, ``s = -b_low``).
    normals, signs : ndarray, shape (p, n), (p,)
        The stop coordinate and side of each impact's stop (which is skipped there).
    extra_normals, extra_signs, extra_positions : ndarray, shape (q, n), (q,), (q,)
        The further stops.
    starts, arrivals : ndarray, shape (p, 2n)
        ``X_k`` just after impact k and ``X_k^-`` at the end of flight k.

    Returns
    -------
    tuple
        ``(gap, stop, tol)``, each shape (p, 2): column 0 the start of flight k, column 1
        its end; ``stop`` 0 (U), 1 (L), ``2 + i`` (extra stop i) or -1 (no other stop,
        gap ``+inf``); ``tol`` the rounding of each gap (:func:`_state_clearance`).
    """
    p = signs.size
    gap = np.full((p, 2), np.inf)
    stop = np.full((p, 2), -1, dtype=np.int64)
    tol = np.zeros((p, 2))
    for k in range(p):
        nxt = (k + 1) % p
        g, s, t = _state_clearance(starts[k], normals[k], signs[k], normal, two_sided, b,
                                   b_low, extra_normals, extra_signs, extra_positions)
        gap[k, 0] = g
        stop[k, 0] = s
        tol[k, 0] = t
        g, s, t = _state_clearance(arrivals[k], normals[nxt], signs[nxt], normal, two_sided,
                                   b, b_low, extra_normals, extra_signs, extra_positions)
        gap[k, 1] = g
        stop[k, 1] = s
        tol[k, 1] = t
    return gap, stop, tol


@_jit
def motion_checks(flow, forcing, impacts, stops, shot, checks):
    """Per-flight ``G_k``, their product G, its multipliers and the contact check (eq. 16).

    Parameters
    ----------
    flow, forcing, impacts : tuple
        As :func:`shooting_system` takes them.
    stops : tuple
        :class:`~impactcont.kernel.arrays.ContactStops`: the stop coordinate of U and L
        and the further stops (on other coordinates), each flight checked against every one.
    shot : tuple
        :class:`~impactcont.kernel.arrays.CheckedFlights` at the solution
        (:meth:`~impactcont.kernel.arrays.ShotFlights.checked`).
    checks : bool
        Search the flights for contact.

    Returns
    -------
    tuple
        The fields of :class:`~impactcont.kernel.arrays.MotionChecks`
        (``MotionChecks._make`` names them). Multipliers largest modulus first (NaN when
        G is not finite); the gaps are those
        of :func:`impactcont.simulate.contact.flight_clearances` (NaN when ``checks`` is
        False, ``+inf`` when the flight time is not positive), ``capped`` whether a
        search grid was capped.
    """
    flow = ShootingFlow(*flow)
    forcing = Forcing(*forcing)
    impacts = ImpactSequence(*impacts)
    stops = ContactStops(*stops)
    shot = CheckedFlights(*shot)
    omega = forcing.omega
    pivots, normals, matrices = impacts.pivots, impacts.normals, impacts.matrices
    phases, taus, starts = shot.phases, shot.flight_times, shot.starts
    transitions, pcols, rates = shot.transitions, shot.phase_columns, shot.arrival_rates
    p = taus.size
    m = matrices.shape[1]
    jacs = np.empty((p, m, m))
    h2 = np.empty(p)
    G = np.eye(m)
    tmp = np.empty((m, m))
    for k in range(p):
        nxt = (k + 1) % p
        h2[k] = _flight_jacobian(transitions[k], pcols[k], rates[k], matrices[nxt], pivots[k],
                                 pivots[nxt], normals[k], normals[nxt], omega, jacs[k])
        for r in range(m):
            for c in range(m):
                s = 0.0
                for i in range(m):
                    s += jacs[k, r, i] * G[i, c]
                tmp[r, c] = s
        G[:, :] = tmp
    mu = multipliers(G)
    gap_u = np.full(p, np.nan)
    t_u = np.full(p, np.nan)
    gap_l = np.full(p, np.nan)
    t_l = np.full(p, np.nan)
    q = stops.extra_signs.size
    gap_x = np.full((p, q), np.nan)
    t_x = np.full((p, q), np.nan)
    capped = False
    if checks:
        for k in range(p):
            if not taus[k] > 0.0:
                gap_u[k] = np.inf
                gap_l[k] = np.inf
                for i in range(q):
                    gap_x[k, i] = np.inf
                continue
            for i in range(q):
                gx, tx, cap = _stop_clearance(flow, forcing, stops, i, starts[k], phases[k],
                                              taus[k])
                gap_x[k, i] = gx
                t_x[k, i] = tx
                capped = capped or cap
            gu, tu, gl, tl, cap = _clearances(flow, forcing, stops, starts[k], phases[k],
                                              taus[k])
            gap_u[k] = gu
            t_u[k] = tu
            gap_l[k] = gl
            t_l[k] = tl
            capped = capped or cap
    return jacs, h2, G, mu, gap_u, t_u, gap_l, t_l, gap_x, t_x, capped


@_jit
def omega_partials(flow, forcing, derivatives, shot):
    """``dX_k^-/d omega`` of every flight at fixed flight time, start and start phase.

    `flow`, `forcing`: as :func:`shooting_system` takes them; `derivatives`: the plain
    tuple of :class:`~impactcont.kernel.arrays.ForcingDerivatives`; `shot`: of
    :class:`~impactcont.kernel.arrays.ShotFlights` (its flight times, starts, phases and
    transitions are read). One compiled function for Python and compiled callers
    (:func:`frequency_column` passes its plain tuples on): an entry point beside an inner
    function of the same body would compile that body twice.

    Only the steady forced state ``X_p(t) = Re(Z e^{i(omega t + theta)})`` depends on
    omega: ``dX/d omega = D(t) - Phi(t) D(0)``, ``D(t) = Re((dZ + i t Z) e^{i(omega t +
    theta)})`` (``Flow.omega_partial``). For the modal flow ``Z = [U A; i omega U A]``
    with ``A = gamma - i beta`` (eq. 7), ``dA = dgamma - i dbeta`` given.

    Returns
    -------
    ndarray, shape (p, 2n)
    """
    named = ShootingFlow(*flow)
    forced, partials, flights = (Forcing(*forcing), ForcingDerivatives(*derivatives),
                                 ShotFlights(*shot))
    general, u = named.general, named.u
    omega = forced.omega
    dgam, dbet, dZ = partials.dgamma, partials.dbeta, partials.dZ
    taus, starts, phases = flights.flight_times, flights.starts, flights.phases
    transitions = flights.transitions
    p = taus.size
    m = starts.shape[1]
    Zp, dZp = _forced_vectors(general, u, forced, dgam, dbet, dZ)
    out = np.empty((p, m))
    d0 = np.empty(m)
    for k in range(p):
        t = taus[k]
        rot_0 = complex(math.cos(phases[k]), math.sin(phases[k]))
        rot_t = complex(math.cos(omega * t + phases[k]), math.sin(omega * t + phases[k]))
        for c in range(m):
            d0[c] = (dZp[c] * rot_0).real
        for r in range(m):
            s = 0.0
            for c in range(m):
                s += transitions[k, r, c] * d0[c]
            out[k, r] = ((dZp[r] + 1j * t * Zp[r]) * rot_t).real - s
    return out


@_jit
def frequency_column(flow, forcing, derivatives, impacts, period, shot):
    """``dr/d omega`` of the shooting residual at fixed unknowns, shape (p 2n,).

    Arguments as :func:`omega_partials` and :func:`shooting_system` take them (plain
    tuples; :func:`branch_linearization` passes its own on, so one compiled function
    serves both).

    The forced part of eq. (9) at fixed flight times (:func:`omega_partials`), the phases
    ``theta_k = delta + omega (tau_0 + .. + tau_{k-1})`` (``pcols``, ``dX^-/dtheta``) and
    the last flight time ``tau_{p-1} = period - (tau_0 + .. + tau_{p-2})`` (``rates``,
    ``X'(tau^-)``, times ``-period / omega``), each through the impact matrix ``D_{k+1}``
    that ends flight k (``MultiImpactBranchProblem.dparam`` of
    :mod:`impactcont.problems.multi_impact_branch`).
    """
    omega, matrices = Forcing(*forcing).omega, ImpactSequence(*impacts).matrices
    flights = ShotFlights(*shot)
    taus, pcols, rates = flights.flight_times, flights.phase_columns, flights.arrival_rates
    p = taus.size
    m = flights.starts.shape[1]
    explicit = omega_partials(flow, forcing, derivatives, shot)
    out = np.zeros(p * m)
    elapsed = 0.0
    for k in range(p):
        nxt = (k + 1) % p
        for r in range(m):
            s = 0.0
            for c in range(m):
                v = explicit[k, c] + elapsed * pcols[k, c]
                if k == p - 1:
                    v -= rates[k, c] * period / omega
                s += matrices[nxt, r, c] * v
            out[k * m + r] = s
        elapsed += taus[k]
    return out


@_jit
def forced_amplitudes(w, a, f, errors, omega):
    """The steady modal amplitudes of eq. (7) and their omega derivatives, O(n).

    ``gamma_i - i beta_i = f_i / (w_i^2 - omega^2 + 2 i a_i omega)`` and
    ``d(gamma_i - i beta_i)/d omega = (gamma_i - i beta_i) (2 omega - 2 i a_i) / (w_i^2 -
    omega^2 + 2 i a_i omega)`` (:func:`impactcont.model.modal.forced_coefficients`,
    :meth:`impactcont.orbit.flow.Flow.omega_arrays`, real ``f``), with what that function
    refuses or warns about: ``resonant`` (an undamped forced mode at ``omega_i = omega``)
    and ``worst``, its relative error bound of the amplitudes from the eigenvalue errors.

    Returns
    -------
    ForcedAmplitudes
    """
    n = w.size
    gam = np.empty(n)
    bet = np.empty(n)
    dgam = np.empty(n)
    dbet = np.empty(n)
    worst = 0.0
    resonant = False
    eps = np.finfo(np.float64).eps
    for i in range(n):
        detune = (w[i] - omega) * (w[i] + omega)
        damp = 2.0 * a[i] * omega
        delta = detune * detune + damp * damp
        if delta == 0.0:  # an undamped mode at omega: refused when forced, else zero
            if f[i] != 0.0:
                resonant = True
            gam[i] = bet[i] = dgam[i] = dbet[i] = 0.0
            continue
        gam[i] = detune * f[i] / delta
        bet[i] = damp * f[i] / delta
        den = complex(detune, damp)
        dA = complex(gam[i], -bet[i]) * complex(2.0 * omega, -2.0 * a[i]) / den
        dgam[i] = dA.real
        dbet[i] = -dA.imag
        if f[i] != 0.0:
            rel = (4.0 * errors[i] + 4.0 * eps * w[i] * w[i]) * abs(detune) / delta
            if rel > worst or rel != rel:
                worst = rel
    return ForcedAmplitudes(gam, bet, dgam, dbet, worst, resonant)


@_jit
def branch_linearization(flow, forcing, derivatives, impacts, period, x):
    """The shooting system at ``x`` and its linearization in ``[x, omega]``, one call.

    :func:`shooting_system` (with the Jacobian) and :func:`frequency_column`: a corrector
    step of the continuation in omega needs the residual, ``dr/dx`` and ``dr/d omega``
    at one point (``MultiImpactBranchProblem.linearize`` of
    :mod:`impactcont.problems.multi_impact_branch`). Arguments as those functions take them.

    Returns
    -------
    BranchLinearization

    Notes
    -----
    :func:`palc_correct` calls this entry point with plain tuples of the types Python
    passes, so it is compiled once for both (an inner twin on the named structures was a
    second compile of the same body, about 2 s of a cold first N-p branch).
    """
    sh = _shooting_system(_flights(ShootingFlow(*flow)), Forcing(*forcing),
                          ImpactSequence(*impacts), period, x, _jacobian_wanted(x))
    col = frequency_column(flow, forcing, derivatives, impacts, period, _shot_tuple(sh))
    size = x.size
    extended = np.empty((size, size + 1))
    J = sh.jacobian
    for r in range(size):
        for c in range(size):
            extended[r, c] = J[r, c]
        extended[r, size] = col[r]
    return BranchLinearization(sh, extended)


@_jit
def jacobian_product(impacts, omega, shot, count):
    """``G_{count-1} .. G_1 G_0``, the product of the first `count` flights' Jacobians
    (eq. 25, as :func:`motion_checks` builds them): G itself for ``count = p``, the
    half-map's product for ``count = p / 2`` (:func:`impactcont.orbit.symmetry.half_map`).

    `impacts` and `shot`: the plain tuples of
    :class:`~impactcont.kernel.arrays.ImpactSequence` (all p impacts) and
    :class:`~impactcont.kernel.arrays.ShotFlights` (its transitions, phase columns and
    arrival rates are read).
    """
    impacts = ImpactSequence(*impacts)
    m = impacts.matrices.shape[1]
    G = np.empty((m, m))
    _jacobian_product_into(impacts, omega, ShotFlights(*shot), count, G, np.empty(count))
    return G


@_inner
def _jacobian_product_into(impacts, omega, shot, count, G, h2):
    """:func:`jacobian_product` into ``G`` (m, m), with ``h2[k]`` the velocity of the stop
    coordinate at the end of flight k (the pole of its Jacobian, ``(count,)``)."""
    pivots, normals, matrices = impacts.pivots, impacts.normals, impacts.matrices
    transitions, pcols, rates = shot.transitions, shot.phase_columns, shot.arrival_rates
    p = pivots.size
    m = matrices.shape[1]
    Gk = np.empty((m, m))
    tmp = np.empty((m, m))
    for r in range(m):
        for c in range(m):
            G[r, c] = 1.0 if r == c else 0.0
    for k in range(count):
        nxt = (k + 1) % p
        h2[k] = _flight_jacobian(transitions[k], pcols[k], rates[k], matrices[nxt], pivots[k],
                                 pivots[nxt], normals[k], normals[nxt], omega, Gk)
        for r in range(m):
            for c in range(m):
                s = 0.0
                for i in range(m):
                    s += Gk[r, i] * G[i, c]
                tmp[r, c] = s
        G[:, :] = tmp


#: ``palc_correct`` statuses besides :data:`CONVERGED` and :data:`FAILED` (no convergence)
REFUSED = 2  # omega <= 0, not finite, or at an undamped resonance: the problem refuses it
NONFINITE_RESIDUAL = 3
NONFINITE_SYSTEM = 4
SINGULAR = 5  # a pivot exactly zero
NONFINITE_UPDATE = 6


@_inner
def _frobenius_condition(A):
    """``|A|_F |A^-1|_F`` (``inf`` when a pivot is exactly zero): an upper bound of the
    2-norm condition number, at most ``size`` times it."""
    size = A.shape[0]
    inv_sq = 0.0
    e = np.zeros(size)
    for c in range(size):
        e[:] = 0.0
        e[c] = 1.0
        col, ok = _solve(A, e)
        if not ok:
            return np.inf
        for r in range(size):
            inv_sq += col[r] * col[r]
    a_sq = 0.0
    for r in range(size):
        for c in range(size):
            a_sq += A[r, c] * A[r, c]
    return math.sqrt(a_sq) * math.sqrt(inv_sq)


#: :func:`_bordered_newton`'s status where the corrector goes on to its next iterate.
GOING = -1


@_inner
def _bordered_newton(A, residual, border, state, predicted, it, settings, last_update,
                     flagged):
    """Iterate `it` of the pseudo-arclength corrector from its bordered matrix: the tests,
    the update and the tangent of :func:`palc_correct`, shared by
    :func:`impactcont.kernel.sticky.sticky_palc_correct`.

    `A` is ``[dF/dx | dF/domega]`` on its first ``m = A.shape[0] - 1`` rows (``m`` the
    unknowns ``x`` but omega); its last row is set here to the border ``W t`` (`border`);
    `residual`
    ``F`` (its first ``m`` entries read) at `state` ``[x, omega]``; `predicted` the
    predicted point; `settings` the plain tuple of
    :class:`~impactcont.kernel.arrays.CorrectorSettings`; `last_update` and `flagged` as
    the previous iterate left them. A non-finite residual is :data:`NONFINITE_RESIDUAL`
    (its norm the first non-finite entry); converged (not on the hyperplane) when ``max|F|
    <= tol`` and, after an update, the last update's max-norm too, then the tangent
    solves ``A t = e_m``; else the update of ``A d = [-F; -<W t, state - predicted>]`` is
    added to `state` (in place).

    Returns ``(status, iterations, residual_norm, tangent, last_update, flagged)``:
    :data:`GOING` to go on (the other fields as they stand), or the fields of
    :class:`~impactcont.kernel.arrays.PalcResult` (the tangent zeros unless converged).
    """
    tol, max_iter, singular, hyperplane = CorrectorSettings(*settings)
    size = A.shape[0] - 1
    for k in range(size + 1):
        A[size, k] = border[k]
    norm = 0.0
    for r in range(size):
        v = abs(residual[r])
        if not v < np.inf:
            return (NONFINITE_RESIDUAL, it, v, np.zeros(size + 1), last_update, flagged)
        if v > norm:
            norm = v
    finite = True
    for r in range(size + 1):
        for k in range(size + 1):
            if not abs(A[r, k]) < np.inf:
                finite = False
    converged = not hyperplane and norm <= tol and (it == 0 or last_update <= tol)
    if (not hyperplane and finite and (converged or it < max_iter)
            and flagged.shape[0] == 0 and _frobenius_condition(A) > singular):
        flagged = A.copy()
    if converged:
        if not finite:
            return (NONFINITE_SYSTEM, it, norm, np.zeros(size + 1), last_update, flagged)
        e = np.zeros(size + 1)
        e[size] = 1.0
        t, ok = _solve(A, e)
        if not ok:
            return (SINGULAR, it, norm, np.zeros(size + 1), last_update, flagged)
        return (CONVERGED, it, norm, t, last_update, flagged)
    if it == max_iter:
        return (FAILED, max_iter, norm, np.zeros(size + 1), last_update, flagged)
    if not finite:
        return (NONFINITE_SYSTEM, it, norm, np.zeros(size + 1), last_update, flagged)
    rhs = np.empty(size + 1)
    for r in range(size):
        rhs[r] = -residual[r]
    s = 0.0
    for k in range(size + 1):
        s += border[k] * (state[k] - predicted[k])
    rhs[size] = -s
    if not abs(s) < np.inf:
        return (NONFINITE_SYSTEM, it, norm, np.zeros(size + 1), last_update, flagged)
    update, ok = _solve(A, rhs)
    if not ok:
        return (SINGULAR, it, norm, np.zeros(size + 1), last_update, flagged)
    last_update = 0.0
    for k in range(size + 1):
        v = abs(update[k])
        if not v < np.inf:
            return (NONFINITE_UPDATE, it, norm, np.zeros(size + 1), last_update, flagged)
        if v > last_update:
            last_update = v
    for k in range(size + 1):
        state[k] += update[k]
    if hyperplane and last_update <= tol:
        return (CONVERGED, it + 1, norm, np.zeros(size + 1), last_update, flagged)
    return (GOING, it, norm, update, last_update, flagged)


@_inner
def _corrector_start(predicted, tangent, weights):
    """The pseudo-arclength corrector's state before its first iterate (:func:`palc_correct`
    and :func:`impactcont.kernel.sticky.sticky_palc_correct`): ``(state, border, raw,
    last_update, worst, worst_omega, flagged, norm)``, the iterate a copy of `predicted`,
    the border ``W t``, a zero tangent, no update, no amplitude error, no flagged matrix
    and no residual yet."""
    state = predicted.copy()
    return (state, weights * tangent, np.zeros(state.size), np.inf, 0.0, np.nan,
            np.zeros((0, 0)), np.nan)


@_inner
def _corrector_amplitudes(w, a, f, errors, state, worst, worst_omega):
    """The forced amplitudes of eq. (7) (:func:`forced_amplitudes`) at the omega of a
    pseudo-arclength corrector's iterate `state` (its last entry), with the largest error
    bound so far (`worst` at `worst_omega`) updated: ``(ok, omega, gamma, beta, dgamma,
    dbeta, worst, worst_omega)``, ``ok`` False where omega is not positive and finite or a
    mode is at an undamped resonance (the corrector refuses the step)."""
    omega = state[state.size - 1]
    if not (omega > 0.0 and omega < np.inf):
        none = np.zeros(0)
        return False, omega, none, none, none, none, worst, worst_omega
    gam, bet, dgam, dbet, bound, resonant = forced_amplitudes(w, a, f, errors, omega)
    if resonant:
        return False, omega, gam, bet, dgam, dbet, worst, worst_omega
    if bound > worst or bound != bound:
        worst = bound
        worst_omega = omega
    return True, omega, gam, bet, dgam, dbet, worst, worst_omega


@_jit
def palc_correct(flow, errors, impacts, N, embedding, step, settings):
    """The pseudo-arclength corrector of an N-p branch in omega (modal flow), compiled.

    `flow` and `impacts` as :func:`shooting_system` takes them, `errors` the rounding
    errors of ``omega_i^2`` (:func:`forced_amplitudes`), `N` the motion's forcing periods;
    `embedding` (``E, c, rows``), `step` (``predicted, tangent, weights``) and `settings`
    (``tol, max_iter, singular, hyperplane``) the plain tuples of
    :class:`~impactcont.kernel.arrays.Embedding`,
    :class:`~impactcont.kernel.arrays.CorrectorStep` and
    :class:`~impactcont.kernel.arrays.CorrectorSettings`.

    Newton on ``[F(v, omega); <W t, x - x_pred>] = 0`` from ``x = x_pred`` with the
    arithmetic and tests of ``PalcStepper._correct_on_hyperplane`` (converged when
    ``max|F| <= tol`` and, after an update, the last update's max-norm too), then the
    tangent at the point (``PalcStepper._tangent_at``, not normalised): the bordered
    system with the last row ``W t`` and the right-hand side ``e_m``. ``F`` is the first
    `rows` rows of the shooting residual (:func:`branch_linearization`) at the full
    unknowns ``u = E v + c / omega`` (the identity and zero for any N-p motion, the
    half-motion's embedding for a symmetric one, :class:`impactcont.orbit.symmetry.HalfUnknowns`),
    with the forced amplitudes of eq. (7) at each omega (:func:`forced_amplitudes`).

    With `hyperplane` it is instead the Newton of
    :func:`impactcont.core.corrector.solve_on_hyperplane` (``weights`` ones, ``tangent``
    the normal, ``predicted`` the target): converged when an update's max-norm is at most
    `tol` (the point after that update, no residual test, no tangent), else after
    `max_iter` updates; a non-finite residual is reported, not solved.

    Returns
    -------
    PalcResult
        ``(state, iterations, status, omega, residual_norm, tangent, worst, worst_omega,
        flagged, last_update)``: the last iterate, the updates taken, :data:`CONVERGED`,
        :data:`FAILED` or a refusal (:data:`REFUSED`, ...), the last omega evaluated, the
        last residual's max-norm, the raw tangent (converged only), the largest
        amplitude error bound of :func:`forced_amplitudes` and its omega, the first
        bordered matrix whose Frobenius condition bound exceeds `singular` (shape (0, 0)
        when none: the caller checks its 2-norm condition number), and the last update's
        max-norm.
    """
    modal = ShootingFlow(*flow)
    E, c, rows = Embedding(*embedding)
    predicted, tangent, weights = CorrectorStep(*step)
    max_iter = CorrectorSettings(*settings).max_iter
    w, a, f = modal.w, modal.a, modal.f
    size = predicted.size - 1
    full = E.shape[0]
    empty_c = np.zeros(0, dtype=np.complex128)
    state, border, raw, last_update, worst, worst_omega, flagged, norm = _corrector_start(
        predicted, tangent, weights)
    omega = state[size]
    for it in range(max_iter + 1):
        ok, omega, gam, bet, dgam, dbet, worst, worst_omega = _corrector_amplitudes(
            w, a, f, errors, state, worst, worst_omega)
        if not ok:
            return PalcResult(state, it, REFUSED, omega, norm, raw, worst, worst_omega, flagged,
                              last_update)
        x = np.empty(full)
        for r in range(full):
            s = c[r] / omega
            for k in range(size):
                s += E[r, k] * state[k]
            x[r] = s
        period = 2.0 * math.pi * N / omega
        sh, ext = branch_linearization(flow, (omega, gam, bet, empty_c),
                                       (dgam, dbet, empty_c), impacts, period, x)
        residual = sh.residual
        # [J E | dF/domega - J c / omega^2] on the first rows (the border: _bordered_newton)
        A = np.empty((size + 1, size + 1))
        for r in range(rows):
            for k in range(size):
                s = 0.0
                for i in range(full):
                    s += ext[r, i] * E[i, k]
                A[r, k] = s
            s = ext[r, full]
            for i in range(full):
                s -= ext[r, i] * c[i] / (omega * omega)
            A[r, size] = s
        status, done, norm, column, last_update, flagged = _bordered_newton(
            A, residual, border, state, predicted, it, settings, last_update, flagged)
        if status != GOING:
            return PalcResult(state, done, status, omega, norm, column, worst, worst_omega,
                              flagged, last_update)
    return PalcResult(state, max_iter, FAILED, omega, norm, raw, worst, worst_omega, flagged,
                      last_update)
