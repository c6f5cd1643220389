"""Sticking phases: the motion with stop coordinates held at their stops.

A stop ``s_k = n_k . x`` held at its position ``c_k`` (a mass at a stop fixed to the frame,
two masses held together at a clearance, any extra stop) adds the constraint
``G x = c`` (the rows of ``G`` the held stops' normals) and a contact force ``G^T lam``
to eq. (1):

    M x'' + C x' + K x = Re(F e^{i theta}) + F_static + G^T lam,    G x = c,  G x' = 0.

One general constraint serves a frame stop (``n = e_j``) and a relative stop
(``n = e_j - e_k``) alike.

**The reduced system.** Columns ``P`` of ``G`` (chosen by QR with column pivoting, the
stop's own mass for a frame stop) are solved for: ``x = T q + x_0`` with ``q = x_Q`` the
other coordinates, ``T[Q] = I``, ``T[P] = -G_P^-1 G_Q`` and ``x_0[P] = G_P^-1 c``, so
``G x = c`` and ``G x' = 0`` hold by construction. Projected on ``T`` (``T^T G^T = 0``
removes the contact force),

    (T^T M T) q'' + (T^T C T) q' + (T^T K T) q = T^T Re(F e^{i theta}) + T^T (F_static - K x_0),

the same kind of forced linear system as eq. (1), so its exact flow is the matrix
exponential of its first-order matrix with the forcing states
(:class:`~impactcont.simulate.flight.Flight`, which reads it in the oscillator's
coordinates through ``lift``): :class:`HeldFlight`. Several stops may be held at once
(independent normals; a held stop whose normal depends on the others' is refused by
:func:`holding`, which never returns it).

**The contact force.** ``G x'' = 0`` gives

    lam = (G M^-1 G^T)^-1 G M^-1 (C x' + K x - Re(F e^{i theta}) - F_static),

a linear function of the state and the forcing states, evaluated along the exact flow. A
stop met moving up (sign ``sigma = +1``) pushes its coordinate down, ``lam_k <= 0``; the
**pressing force** ``p_k = -sigma_k lam_k >= 0`` is what :class:`StickingPhase` reports.
The stop releases where ``p_k`` reaches zero and changes sign: the first crossing of
``-p_k`` through 0 from below, located by the bracketing search of
:mod:`impactcont.simulate.search` (Newton kept in its bracket, to a few ulps) on the exact
flow, together with the impacts of the stops not held
(:func:`impactcont.simulate.contact.next_contact`).

**Which stops hold** (:func:`holding`): among the stops a state rests on (on the stop, no
speed towards it), the set ``S`` whose constrained motion presses every stop of ``S``
(``p_k > 0``) and moves no other into its stop (the linear complementarity problem of
the accelerations, solved by enumerating the subsets: there are a few stops). An impact
while stops are held (:func:`impact_with_held`) is the impulse law on the stop hit with
the held stops kept (plastic on them) as long as their impulses press them.
"""

from __future__ import annotations

import dataclasses
import itertools
import math
from collections.abc import Sequence

import numpy as np
import scipy.linalg

from impactcont.model.oscillator import ImpactOscillator
from impactcont.model.stops import StopView
from impactcont.simulate.flight import Flight

__all__ = ["HeldFlight", "StickingPhase", "holding", "impact_with_held", "release_name"]

_EPS = float(np.finfo(float).eps)
# a pressing force within this many ulps of the forces' size is zero (rounding)
_FORCE_ULPS = 256
# a held set whose normals' matrix G_P has a condition number above this is dependent
_DEPENDENT = 1e10
_RELEASE = "release:"


def release_name(stop: str) -> str:
    """The event name of the release of a held stop (:func:`next_contact`'s ``releases``)."""
    return _RELEASE + stop


@dataclasses.dataclass(frozen=True, eq=False)
class StickingPhase:
    """One sticking phase of a simulation: a fixed set of stops held from start to end.

    Attributes
    ----------
    start, end : float
        Times since the start of the simulation.
    stops : str
        The stops held (their names, e.g. ``"U"``, ``"A"``, ``"UA"`` for two at once).
    times : ndarray, shape (k,)
        Sample times of the contact force (both ends included).
    forces : ndarray, shape (k, len(stops))
        The pressing force of each held stop there (``>= 0``; the force with which the stop
        pushes its coordinate away from it; zero at a release).
    ended_by : str
        ``"release"`` (a contact force fell to zero), ``"impact"`` (another stop was hit),
        ``"stick"`` (another stop came to hold), ``"end"`` (the end of the simulation) or
        ``"chatter"`` (stopped at an unresolved chatter).
    start_state : ndarray, shape (2n,)
        The state at the start.
    start_phase : float
        The forcing phase at the start.
    """

    start: float
    end: float
    stops: str
    times: np.ndarray
    forces: np.ndarray
    ended_by: str
    start_state: np.ndarray
    start_phase: float
    _flight: HeldFlight | None = dataclasses.field(default=None, repr=False)

    @property
    def duration(self) -> float:
        """``end - start``."""
        return self.end - self.start

    def contact_force(self, t: object) -> np.ndarray:
        """The pressing forces at times `t` (absolute, within the phase), shape (nt, m):
        the exact flow of the reduced system, evaluated anew."""
        if self._flight is None:
            raise ValueError("this sticking phase carries only its samples (times, forces)")
        t = np.atleast_1d(np.asarray(t, dtype=float))
        if np.any((t < self.start) | (t > self.end)):
            raise ValueError(f"t must lie in the phase [{self.start!r}, {self.end!r}]; got "
                             f"{t.min()!r} .. {t.max()!r}")
        return self._flight.pressing(t - self.start, self.start_state, self.start_phase)


def _force_terms(osc: ImpactOscillator) -> np.ndarray:
    """``[K, C, -Re F, Im F, -F_static]``: ``C x' + K x - f`` as a row map of
    ``[x; x'; cos theta; sin theta; 1]``, shape (n, 2n + 3)."""
    F = np.asarray(osc.F)
    n = osc.n
    return np.hstack([osc.K, osc.C, np.real(F).reshape(n, 1) * -1.0,
                      (np.imag(F) if np.iscomplexobj(F) else np.zeros(n)).reshape(n, 1),
                      -np.asarray(osc.F_static, dtype=float).reshape(n, 1)])


def _views(osc: ImpactOscillator, stops: Sequence[str]) -> list[StopView]:
    return [osc.stops.stop(s, osc.M, osc.b, osc.R) for s in stops]


class HeldFlight(Flight):
    """The exact flow with the stops `held` at their positions (module docstring).

    Parameters
    ----------
    osc : ImpactOscillator
    held : sequence of str
        Names of the stops held (independent normals).

    Attributes
    ----------
    held : tuple of str
    T, x0 : ndarray
        ``x = T q + x_0``.
    force_rows : ndarray, shape (m, N)
        ``lam = force_rows @ Y`` on the internal state ``Y = [q; q'; c; s; 1]``.
    release_rows : dict
        ``release_name(stop) -> sigma_k force_rows[k]`` (``= -p_k``): the release of stop k
        is the first crossing of 0 from below.

    Raises
    ------
    ValueError
        The held stops' normals are dependent.
    """

    def __init__(self, osc: ImpactOscillator, held: Sequence[str]) -> None:
        views = _views(osc, held)
        n, m = osc.n, len(views)
        G = np.array([v.normal for v in views], dtype=float).reshape(m, n)
        c = np.array([v.position for v in views], dtype=float)
        self.held = tuple(held)
        self.signs = np.array([v.sign for v in views], dtype=float)
        _, _, order = scipy.linalg.qr(G, pivoting=True, mode="economic")
        P, Q = np.sort(order[:m]), np.sort(order[m:])
        G_P = G[:, P]
        if m and np.linalg.cond(G_P) > _DEPENDENT:
            raise ValueError(f"the held stops {list(held)} have dependent normals "
                             f"{G.tolist()}")
        r = n - m
        T = np.zeros((n, r))
        T[Q, np.arange(r)] = 1.0
        x0 = np.zeros(n)
        if m:
            T[P] = -np.linalg.solve(G_P, G[:, Q])
            x0[P] = np.linalg.solve(G_P, c)
        self.T, self.x0 = T, x0
        F = np.asarray(osc.F)
        inputs = np.column_stack([T.T @ np.real(F),
                                  -(T.T @ np.imag(F)) if np.iscomplexobj(F) else np.zeros(r),
                                  T.T @ (np.asarray(osc.F_static, dtype=float) - osc.K @ x0)])
        M_r, C_r, K_r = T.T @ osc.M @ T, T.T @ osc.C @ T, T.T @ osc.K @ T
        solved = np.linalg.solve(M_r, np.hstack([K_r, C_r, inputs])) if r else np.zeros((0, 3))
        N = 2 * r + 3
        A = np.zeros((N, N))
        A[:r, r:2 * r] = np.eye(r)
        A[r:2 * r, :r] = -solved[:, :r]
        A[r:2 * r, r:2 * r] = -solved[:, r:2 * r]
        A[r:2 * r, 2 * r:] = solved[:, 2 * r:]
        A[2 * r, 2 * r + 1] = -float(osc.omega)
        A[2 * r + 1, 2 * r] = float(osc.omega)
        lift = np.zeros((2 * n + 3, N))
        lift[:n, :r] = T
        lift[:n, 2 * r + 2] = x0
        lift[n:2 * n, r:2 * r] = T
        lift[2 * n:, 2 * r:] = np.eye(3)
        restrict = np.zeros((N, 2 * n + 3))
        restrict[np.arange(r), Q] = 1.0
        restrict[r + np.arange(r), n + Q] = 1.0
        restrict[2 * r:, 2 * n:] = np.eye(3)
        self._build(osc, A, lift, restrict)
        Minv_GT = np.linalg.solve(osc.M, G.T)
        multiplier = np.linalg.solve(G @ Minv_GT, Minv_GT.T)  # (G M^-1 G^T)^-1 G M^-1
        self.force_rows = (multiplier @ _force_terms(osc)) @ lift
        self.release_rows = {release_name(s): self.signs[k] * self.force_rows[k]
                             for k, s in enumerate(self.held)}

    def pressing(self, t: object, X: np.ndarray, phase: float) -> np.ndarray:
        """The pressing forces ``p_k = -sigma_k lam_k`` at times `t` after a start at state X
        and phase, shape (nt, m)."""
        rows = -self.signs[:, None] * self.force_rows
        return self.evaluate(t, X, phase, rows)


def _constrained(osc: ImpactOscillator, X: np.ndarray, phase: float,
                 views: list[StopView]) -> tuple[np.ndarray, np.ndarray, float]:
    """Pressing forces of `views` held at state X and the constrained acceleration, with
    the size of the forces (for rounding allowances)."""
    n = osc.n
    x, v = X[:n], X[n:]
    terms = _force_terms(osc)
    Y = np.concatenate([x, v, [math.cos(phase), math.sin(phase), 1.0]])
    rest = terms @ Y  # C x' + K x - f
    size = float(np.max(np.abs(terms) @ np.abs(Y), initial=0.0))
    if not views:
        return np.zeros(0), np.linalg.solve(osc.M, -rest), size
    G = np.array([w.normal for w in views], dtype=float)
    Minv_GT = np.linalg.solve(osc.M, G.T)
    lam = np.linalg.solve(G @ Minv_GT, Minv_GT.T @ rest)
    acc = np.linalg.solve(osc.M, G.T @ lam - rest)
    signs = np.array([w.sign for w in views])
    return -signs * lam, acc, size


def holding(osc: ImpactOscillator, X: np.ndarray, phase: float,
            candidates: Sequence[str]) -> tuple[str, ...]:
    """The stops held at a state resting on `candidates` (on them, no speed towards them).

    The set ``S`` of candidates such that, with ``S`` held, every stop of ``S`` is pressed
    (``p_k`` above rounding) and no other candidate is accelerated into its stop (above
    rounding): the complementarity problem of the contact accelerations, solved by trying
    the subsets from the largest down (the contact matrix ``G M^-1 G^T`` is positive
    definite, so the solution is unique where no force is zero within rounding). A set of
    dependent normals is skipped.

    Parameters
    ----------
    osc : ImpactOscillator
    X : ndarray, shape (2n,)
    phase : float
    candidates : sequence of str
        Stop names.

    Returns
    -------
    tuple of str
        The stops held, in the order of `candidates` (empty: the motion leaves them all).
    """
    views = dict(zip(candidates, _views(osc, candidates), strict=True))
    for size in range(len(candidates), 0, -1):
        for S in itertools.combinations(candidates, size):
            chosen = [views[s] for s in S]
            G = np.array([w.normal for w in chosen])
            if np.linalg.matrix_rank(G) < size:
                continue
            press, acc, scale = _constrained(osc, X, phase, chosen)
            tol = _FORCE_ULPS * _EPS * max(scale, 1e-300)
            if np.any(press <= tol):
                continue
            if all(views[s].sign * float(views[s].normal @ acc) <= tol
                   for s in candidates if s not in S):
                return S
    return ()


def impact_with_held(osc: ImpactOscillator, v_minus: np.ndarray, hit: str,
                     held: Sequence[str]) -> tuple[np.ndarray, tuple[str, ...]]:
    """The velocity after an impact on stop `hit` while the stops `held` are held.

    The impulse acts along the normals of the stop hit and of the held stops kept: the hit
    stop's coordinate speed is reversed times its restitution, the kept ones' stay zero
    (a plastic contact), ``M dv = G^T Lambda``. Kept: the largest subset of `held` whose
    impulses press their stops and after which no other held stop moves into its stop
    (subsets from the largest down). With none kept the law of the stop hit applies alone
    (:meth:`~impactcont.model.stops.Stops.impact_matrix`: eq. 4 at a frame stop).

    Returns
    -------
    v_plus : ndarray, shape (n,)
    kept : tuple of str
    """
    view = osc.stops.stop(hit, osc.M, osc.b, osc.R)
    held_views = dict(zip(held, _views(osc, held), strict=True))
    scale = float(np.abs(v_minus).sum())
    tol = _FORCE_ULPS * _EPS * max(scale, 1e-300)
    for size in range(len(held), 0, -1):
        for S in itertools.combinations(held, size):
            rows = [held_views[s] for s in S]
            G = np.array([view.normal] + [w.normal for w in rows])
            if np.linalg.matrix_rank(G) < size + 1:
                continue
            target = np.zeros(size + 1)
            target[0] = -view.restitution * float(view.normal @ v_minus)
            Minv_GT = np.linalg.solve(osc.M, G.T)
            impulse = np.linalg.solve(G @ Minv_GT, target - G @ v_minus)
            v_plus = v_minus + Minv_GT @ impulse
            signs = np.array([w.sign for w in rows])
            if np.any(-signs * impulse[1:] < -tol):
                continue
            if all(held_views[s].sign * float(held_views[s].normal @ v_plus) <= tol
                   for s in held if s not in S):
                return v_plus, S
    return view.jump @ v_minus, ()
