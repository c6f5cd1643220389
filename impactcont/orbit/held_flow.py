"""The exact flow of a stop coordinate held on its stop: the sticking segment of a motion.

A sticking phase holds one stop coordinate ``s = n . x`` at its stop ``s = c`` (after a
plastic impact, which leaves ``s' = 0``). With the contact force ``n lambda`` the motion
obeys

    M x'' + C x' + K x = Re(F e^{i theta}) + F_static + n lambda,    n . x = c,   n . x' = 0

(the sticking law of ``docs/chatter_sticking.md``). Writing ``x = x_c + P y`` with
``n . x_c = c`` and the columns of ``P`` (n x (n-1)) spanning ``n . x = 0``, the held
motion is the oscillator of ``n - 1`` masses

    P^T M P y'' + P^T C P y' + P^T K P y = Re(P^T F e^{i theta}) + P^T (F_static - K x_c),

whose exact flow is the flight flow of :mod:`impactcont.orbit.flow` (its first-order form,
any C). ``P`` keeps ``P^T M P`` diagonal for both stop kinds: a stop fixed to the frame
(``n = e_j``) drops coordinate j; a clearance (``n = e_j - e_k``) keeps ``e_i`` for ``i != j,
k`` and ``e_j + e_k`` (the two masses moving together). One mass held (``n = 1``) leaves an
empty system: the state stays ``[c; 0]`` and only the force moves.

``n . x'' = 0`` gives the contact force

    lambda = n^T M^-1 (C x' + K x - Re(F e^{i theta}) - F_static) / (n^T M^-1 n),

and the **pressing force** ``p = -sign lambda`` (``sign = +1`` at a stop met moving up,
which pushes its coordinate down) is positive while the stop holds; the sticking phase
ends at the **release**, where ``p`` falls to zero. The periodic motions that contain such
segments are solved by :func:`impactcont.orbit.multi_impact.multi_impact_orbit` (a
lowercase stop letter in the pattern); the simulator's own sticking model
(:mod:`impactcont.simulate.sticking`) is their independent witness and shares no code
with this module.
"""

from __future__ import annotations

import dataclasses
import math
import warnings
import weakref
from collections.abc import Callable
from typing import Any

import numpy as np

from impactcont.errors import ParameterError, UnresolvedMotionWarning
from impactcont.model.oscillator import ImpactOscillator
from impactcont.orbit.flow import Flow, flow_of

__all__ = ["HeldFlow", "held_flow", "held_flow_at", "held_frame"]


def held_frame(normal: np.ndarray) -> np.ndarray:
    """The columns ``P`` (n x (n-1)) spanning ``normal . x = 0``.

    ``normal = e_j``: every ``e_i``, ``i != j``; ``normal = e_j - e_k``: ``e_i`` for ``i !=
    j, k`` and ``e_j + e_k`` (``P^T M P`` stays diagonal for a diagonal M); any other
    normal: an orthonormal basis of its null space.

    Parameters
    ----------
    normal : array_like, shape (n,)

    Returns
    -------
    ndarray, shape (n, n-1)
    """
    normal = np.asarray(normal, dtype=float)
    n = normal.size
    nonzero = np.flatnonzero(normal)
    if nonzero.size == 1:
        return np.eye(n)[:, [i for i in range(n) if i != nonzero[0]]]
    if nonzero.size == 2 and normal[nonzero[0]] == -normal[nonzero[1]]:
        j, k = nonzero
        cols = [np.eye(n)[:, i] for i in range(n) if i not in (j, k)]
        pair = np.zeros(n)
        pair[j] = pair[k] = 1.0
        return np.column_stack([*cols, pair])
    _, _, vt = np.linalg.svd(normal[None, :])
    return vt[1:].T.copy()


@dataclasses.dataclass(frozen=True, eq=False)
class HeldFlow:
    """The exact flow of `oscillator` with the stop coordinate ``normal . x`` held at
    ``position``, and the pressing force along it.

    Attributes
    ----------
    oscillator : ImpactOscillator
    normal : ndarray, shape (n,)
    position : float
        ``c``: the stop at ``s = c``.
    sign : float
        ``+1`` for a stop met moving up, ``-1`` moving down.
    frame : ndarray, shape (n, n-1)
        ``P`` (:func:`held_frame`).
    offset : ndarray, shape (n,)
        ``x_c = c n / |n|^2``, a point of the stop.
    reduced : Flow or None
        The flow of the held system of ``n - 1`` masses (None for ``n = 1``).
    """

    oscillator: ImpactOscillator
    normal: np.ndarray
    position: float
    sign: float
    frame: np.ndarray
    offset: np.ndarray
    reduced: Flow | None

    @property
    def n(self) -> int:
        """Degrees of freedom of the oscillator."""
        return self.oscillator.n

    def _lift(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """``L = diag(P, P)`` (2n, 2n-2), its M-weighted left inverse ``diag(P^+, P^+)``,
        ``P^+ = (P^T M P)^-1 P^T M``, and ``X_c = [x_c; 0]``.

        Notes
        -----
        ``P P^+`` is the plastic impact's matrix (``D`` at R = 0, the M-orthogonal
        projection on ``n . v = 0``): a start state whose stop coordinate still moves
        (``s' != 0``, a direction of G) is held with the velocity a plastic impact leaves,
        momentum conserved.
        """
        cached = self.__dict__.get("_lifted")
        if cached is None:
            P = self.frame
            M = self.oscillator.M
            Pi = (np.linalg.solve(P.T @ M @ P, P.T @ M) if P.size
                  else np.zeros((0, self.n)))
            n, r = P.shape
            L = np.zeros((2 * n, 2 * r))
            L[:n, :r] = P
            L[n:, r:] = P
            Li = np.zeros((2 * r, 2 * n))
            Li[:r, :n] = Pi
            Li[r:, n:] = Pi
            Xc = np.concatenate([self.offset, np.zeros(n)])
            cached = (L, Li, Xc)
            object.__setattr__(self, "_lifted", cached)
        return cached

    def state(self, t: np.ndarray, X0: np.ndarray, theta: float) -> np.ndarray:
        """The held state at times `t` (after the start), from ``X0`` at phase `theta`,
        shape (nt, 2n): ``X_c + L Y(t)``, ``Y(0) = L^+ (X0 - X_c)`` (the start's normal
        position is the stop's, ``c``, and its normal velocity is removed as a plastic
        impact does)."""
        t = np.atleast_1d(np.asarray(t, dtype=float))
        L, Li, Xc = self._lift()
        if self.reduced is None:
            return np.broadcast_to(Xc, (t.size, Xc.size)).copy()
        Y = self.reduced.state(t, Li @ (np.asarray(X0, dtype=float) - Xc), theta)
        return Xc + Y @ L.T

    def segment(self, t: float, X0: np.ndarray, theta: float
                ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """The state after `t` held and its exact derivatives.

        Returns
        -------
        X : ndarray, shape (2n,)
            ``X(t)``.
        dX0 : ndarray, shape (2n, 2n)
            ``dX(t)/dX0 = L Phi_r(t) L^+`` (``Phi_r`` the held system's transition).
        dtheta : ndarray, shape (2n,)
            ``dX(t)/dtheta`` (the start phase).
        rate : ndarray, shape (2n,)
            ``dX(t)/dt``.
        """
        L, Li, Xc = self._lift()
        m = Xc.size
        if self.reduced is None:
            return Xc.copy(), np.zeros((m, m)), np.zeros(m), np.zeros(m)
        Y0 = Li @ (np.asarray(X0, dtype=float) - Xc)
        transition, forcing = self.reduced.matrices(t)[:2]
        Y = self.reduced.state(t, Y0, theta)[0]
        Yr = self.reduced.state_derivative(t, Y0, theta)[0]
        column = forcing @ np.array([-math.sin(theta), math.cos(theta)])
        return Xc + L @ Y, L @ transition @ Li, L @ column, L @ Yr

    def kernel_rows(self) -> tuple[np.ndarray, ...]:
        """This stop's row of :class:`~impactcont.kernel.arrays.HeldSegments` (``sticks``
        left out): ``L``, ``L^+``, ``X_c``, the held system's ``lam, V, V^-1, X_s, d`` and
        ``Z``, and the pressing force's ``grad``, ``force`` and ``level``
        (``p = grad . X + Re(force e^{i theta}) + level``); the held system's arrays empty
        (``r = 0``) for one mass held."""
        cached = self.__dict__.get("_kernel_rows")
        if cached is None:
            rows = self.static_rows()
            Z = self.reduced.Z if self.reduced is not None else np.zeros(0, complex)
            cached = (*rows[:8], Z, *rows[8:])
            object.__setattr__(self, "_kernel_rows", cached)
        return cached

    def static_rows(self) -> tuple[np.ndarray, ...]:
        """:meth:`kernel_rows` but the held system's forced amplitude ``Z``: the parts free
        of omega (``L, L^+, X_c``, ``lam, V, V^-1, X_s, d``, ``grad, force, level``), one
        tuple shared by the held flows :func:`held_flow_at` makes from this one at other
        omegas (the same object: its users may key omega-free caches on it)."""
        cached = self.__dict__.get("_static_rows")
        if cached is None:
            L, Li, Xc = self._lift()
            r = L.shape[1]
            if self.reduced is None:
                flow = (np.zeros(0, complex), np.zeros((0, 0), complex),
                        np.zeros((0, 0), complex), np.zeros(0), np.zeros(0))
            else:
                red = self.reduced
                xs = red.static_offset if np.size(red.static_offset) else np.zeros(r)
                xd = red.drift if np.size(red.drift) else np.zeros(r)
                flow = (red.lam, red.V, red.V_inv, xs, xd)
            k, c, f, g = self._force_rows()
            grad = -self.sign * np.concatenate([k, c])
            cached = (L, Li, Xc, *flow, grad, self.sign * complex(f), self.sign * g)
            object.__setattr__(self, "_static_rows", cached)
        return cached

    def shared(self) -> dict[Any, Any]:
        """A dict shared by this held flow and those :func:`held_flow_at` makes from it at
        other omegas: for its users' caches of what does not depend on omega (keyed on
        :meth:`static_rows`, checked by identity)."""
        found = self.__dict__.get("_shared")
        if found is None:
            found = {}
            object.__setattr__(self, "_shared", found)
        return found

    def _force_rows(self) -> tuple[np.ndarray, np.ndarray, np.ndarray, float]:
        """``(n^T M^-1 K, n^T M^-1 C, n^T M^-1 F, n^T M^-1 F_static)`` over ``n^T M^-1 n``."""
        cached = self.__dict__.get("_rows")
        if cached is None:
            osc = self.oscillator
            w = np.linalg.solve(osc.M, self.normal)  # M symmetric: n^T M^-1 = (M^-1 n)^T
            d = float(w @ self.normal)
            cached = (w @ osc.K / d, w @ osc.C / d, (w @ np.asarray(osc.F, dtype=complex)) / d,
                      float(w @ osc.F_static) / d)
            object.__setattr__(self, "_rows", cached)
        return cached

    def pressing(self, X: np.ndarray, theta: np.ndarray | float) -> np.ndarray | float:
        """The pressing force ``p = -sign lambda`` at the held state(s) `X` (2n,) or
        (nt, 2n) and phase(s) `theta`."""
        k, c, f, g = self._force_rows()
        X = np.asarray(X, dtype=float)
        n = self.n
        theta = np.asarray(theta, dtype=float)
        lam = (X[..., :n] @ k + X[..., n:] @ c - f.real * np.cos(theta)
               + f.imag * np.sin(theta) - g)
        return -self.sign * lam

    def pressing_gradient(self, theta: float) -> tuple[np.ndarray, float]:
        """``dp/dX`` (2n,) and ``dp/dtheta`` at phase `theta` (``p`` is linear in ``X``)."""
        k, c, f, _ = self._force_rows()
        grad = -self.sign * np.concatenate([k, c])
        dtheta = self.sign * float((1j * f * np.exp(1j * theta)).real)
        return grad, dtheta

    def pressing_rate(self, rate: np.ndarray, theta: float) -> float:
        """``dp/dt`` along the held flow where ``X' = rate``, at phase `theta`."""
        grad, dtheta = self.pressing_gradient(theta)
        return float(grad @ rate + self.oscillator.omega * dtheta)

    def stop_clearances(self, duration: float, X0: np.ndarray, theta: float,
                        stops: tuple[np.ndarray, np.ndarray, np.ndarray]
                        ) -> tuple[np.ndarray, np.ndarray]:
        """Each stop's clearance at the turning point of its coordinate nearest it inside a
        sticking phase of `duration` from ``X0`` at phase `theta` (its ends left out).

        Stop i, met with ``sign_i s' > 0`` at ``s = c_i`` on ``s = n_i . x``, has clearance
        ``sign_i (c_i - s)``. Along the held flow ``s = n_i . x_c + (P^T n_i) . y`` is a
        stop coordinate of the held system, whose flow is a flight's: it is searched by
        the flights' contact search of eq. (16)
        (:func:`impactcont.kernel.shooting.motion_checks`, compiled: the extrema bracketed
        on 16 cells per fastest period the coordinate sees, bounded by the tangents of
        concave pieces and polished by safeguarded Newton; not sampled), on the held
        system's flow as one flight against these stops (its ``G`` is not read: the
        flight's impact is a placeholder). A coordinate the hold fixes (``P^T n_i = 0``:
        the held coordinate's other stop) has no turning point.

        Parameters
        ----------
        duration : float
            The held flow's duration.
        X0 : ndarray, shape (2n,)
            The state where the held flow starts.
        theta : float
            The forcing phase there.
        stops : (ndarray, ndarray, ndarray)
            ``n_i`` (q, n), ``sign_i`` (q,) and ``c_i`` (q,).

        Returns
        -------
        gaps, times : ndarray, shape (q,)
            The clearance at that turning point and its time after the start (``+inf``
            and NaN where the coordinate has none inside).
        """
        normals, signs, positions = (np.asarray(a, dtype=float) for a in stops)
        q = signs.size
        gaps, times = np.full(q, np.inf), np.full(q, np.nan)
        if self.reduced is None or not duration > 0.0:
            return gaps, times
        moving, searched, placeholder = self._searched(normals, signs, positions)
        if moving.size == 0:
            return gaps, times
        from impactcont.kernel import shooting as kernel
        from impactcont.kernel.arrays import CheckedFlights, MotionChecks

        _, Li, Xc = self._lift()
        m = 2 * (self.n - 1)
        eye = np.eye(m)[None]
        flight = CheckedFlights(phases=np.array([float(theta)]),
                                flight_times=np.array([float(duration)]),
                                starts=(Li @ (np.asarray(X0, dtype=float) - Xc))[None].copy(),
                                transitions=eye.copy(), phase_columns=np.zeros((1, m)),
                                arrival_rates=np.ones((1, m)))
        # read-only, as the shooting path passes its stop geometry: one compiled version
        checked = MotionChecks._make(kernel.motion_checks(
            tuple(self.reduced.shooting_arrays()), tuple(self.reduced.forcing_arrays()),
            placeholder, searched, tuple(flight), True))
        if checked.capped:
            warnings.warn(f"the contact search of a sticking phase of {duration:.6g} was "
                          "capped at 2000000 cells: a short excursion of another stop "
                          "coordinate past its stop (eq. 16) may be missed",
                          UnresolvedMotionWarning, stacklevel=2)
        gaps[moving] = checked.gap_extra[0]
        times[moving] = checked.time_extra[0]
        return gaps, times

    def _searched(self, normals: np.ndarray, signs: np.ndarray, positions: np.ndarray
                  ) -> tuple[np.ndarray, tuple, tuple]:
        """What :meth:`stop_clearances` searches, free of omega and kept in :meth:`shared`
        per stops: the stops whose coordinate the hold leaves moving, them on the held
        system's coordinates (``P^T n_i``, ``c_i - n_i . x_c``) and the placeholder impact,
        as read-only kernel records."""
        from impactcont.kernel.arrays import ContactStops, ImpactSequence

        key = ("stop_clearances", normals.tobytes(), signs.tobytes(), positions.tobytes())
        cache = self.shared()
        found = cache.get(key)
        if found is None:
            Xc = self._lift()[2]
            rows = normals @ self.frame
            moving = np.flatnonzero(np.any(rows != 0.0, axis=1))
            r = rows.shape[1]
            searched = ContactStops(
                normal=np.zeros(r), two_sided=False, b=math.inf, b_low=0.0,
                extra_normals=np.ascontiguousarray(rows[moving]),
                extra_signs=signs[moving].copy(),
                extra_positions=positions[moving] - normals[moving] @ Xc[:self.n])
            placeholder = ImpactSequence(pivots=np.zeros(1, dtype=np.int64),
                                         normals=np.eye(1, r), signs=np.ones(1),
                                         positions=np.zeros(1),
                                         matrices=np.eye(2 * r)[None].copy())
            # read-only, as the shooting path passes its stop geometry: one compiled version
            found = cache[key] = (moving, _read_only(placeholder), _read_only(searched))
        moving, placeholder, searched = found
        return moving, searched, placeholder

    def _fastest_rate(self) -> float:
        """The largest ``|lambda|`` of the held system's first-order flow (0 without one),
        kept: :meth:`pressing_minimum`'s grid of every sticking phase reads it."""
        cached = self.__dict__.get("_fastest")
        if cached is None:
            cached = 0.0
            if self.reduced is not None:  # a first-order flow: its eigenvalues lambda
                cached = float(np.max(np.abs(self.reduced.lam), initial=0.0))
            object.__setattr__(self, "_fastest", cached)
        return cached

    def pressing_minimum(self, duration: float, X0: np.ndarray, theta: float, *,
                         samples: Callable[[np.ndarray], np.ndarray] | None = None
                         ) -> tuple[float, float]:
        """The smallest pressing force inside a sticking phase of `duration` from ``X0`` at
        phase `theta`: over its start and the interior minima of ``p(t)`` (the release at
        the end, where ``p = 0``, not counted), and its time.

        The pressing force is sampled on a grid of 32 points per period of the fastest
        motion the held system and the forcing have, and each interior minimum of the
        samples is refined by a bounded scalar minimisation (scipy) between its
        neighbours.

        Parameters
        ----------
        duration, X0, theta
            The sticking phase.
        samples : callable, optional
            ``p`` at an array of times after the start, the same held flow computed
            elsewhere (compiled: :func:`impactcont.kernel.shooting.held_pressing`, as
            :func:`impactcont.orbit.sticky.chatter_bounces`'s module passes it); by
            default :meth:`pressing` of :meth:`state`.

        Returns
        -------
        value, time : float
            ``(p(0), 0)`` when ``p`` has no interior minimum.
        """
        omega = self.oscillator.omega
        if not duration > 0.0:
            return float(self.pressing(np.asarray(X0, dtype=float), theta)), 0.0
        rate = max(omega, self._fastest_rate())
        count = int(min(2_000_000, max(64, math.ceil(32.0 * duration * rate / (2 * math.pi)))))
        t = np.linspace(0.0, duration, count + 1)

        def force(times: np.ndarray) -> np.ndarray:
            times = np.atleast_1d(times)
            if samples is not None:
                return samples(times)
            return np.asarray(self.pressing(self.state(times, X0, theta), omega * times + theta))

        values = force(t)
        best, when = float(values[0]), 0.0
        inner = np.flatnonzero((values[1:-1] <= values[:-2]) & (values[1:-1] <= values[2:])) + 1
        if inner.size:  # scipy's import statement only where it refines a minimum
            from scipy.optimize import minimize_scalar
        for i in inner:
            lo, hi = t[i - 1], t[min(i + 1, count)]
            res = minimize_scalar(lambda s: float(force(np.array([s]))[0]), bounds=(lo, hi),
                                  method="bounded", options={"xatol": 1e-14 * max(1.0, hi)})
            value = min(float(res.fun), float(values[i]))
            if value < best:
                best, when = value, float(res.x if res.fun <= values[i] else t[i])
        return best, when


def held_flow(osc: ImpactOscillator, name: str) -> HeldFlow:
    """The :class:`HeldFlow` of the stop `name` (``"U"``, ``"L"`` or an extra stop's) of
    `osc`, built once per oscillator and stop.

    Raises
    ------
    ParameterError
        When the held system of ``n - 1`` masses is not a machine of the package (a free
        motion of it that its stop does not touch).
    """
    known = _HELD.setdefault(osc, {})
    flow = known.get(name)
    if flow is None:
        flow = known[name] = _held_flow(osc, name)
    return flow


def held_flow_at(base: HeldFlow, osc: ImpactOscillator, name: str, reduced: Flow | None
                 ) -> HeldFlow:
    """The :class:`HeldFlow` of stop `name` of `osc`, an oscillator that differs from
    ``base.oscillator`` in omega only, with `reduced` the held system's flow at that omega:
    the frame, the stop, its offset, the lift ``L, L^+`` and the pressing force's rows
    shared (none depends on omega), and kept for
    :func:`held_flow` of `osc` (a branch in omega builds each held system's flow at a new
    omega from the start's, without its modes again).

    Raises
    ------
    ParameterError
        `osc` is not `base`'s oscillator at another omega (its matrices, forcing or stops
        differ), or `reduced` is not at `osc`'s omega.
    """
    old = base.oscillator

    def same(name: str) -> bool:  # the same array (osc.replace keeps it) or equal ones
        a, b = getattr(osc, name), getattr(old, name)
        return a is b or np.array_equal(a, b)

    if osc.n != old.n or not (same("M") and same("K") and same("C") and same("F")
                              and same("F_static") and osc.b == old.b
                              and osc.R == old.R and osc.stops == old.stops):
        raise ParameterError("held_flow_at: osc must be the held flow's oscillator at another "
                             f"omega only; got {osc!r} for {old!r}")
    if (reduced is None) != (base.reduced is None) or (
            reduced is not None and reduced.omega != osc.omega):
        raise ParameterError(f"held_flow_at: reduced must be the held system's flow at omega="
                             f"{osc.omega!r}" + (" (None: one mass held)" if base.reduced is None
                                                 else ""))
    flow = dataclasses.replace(base, oscillator=osc, reduced=reduced)
    base._lift(), base._force_rows(), base.shared()
    caches = ["_lifted", "_rows", "_shared"]  # the lift and the force rows: free of omega
    old_reduced = base.reduced
    if reduced is None or all(getattr(reduced, a, None) is getattr(old_reduced, a, False)
                              for a in ("lam", "V", "V_inv", "static_offset", "drift")):
        base.static_rows()  # the held system's modes and constant force are base's
        caches.append("_static_rows")
    for cache in caches:
        object.__setattr__(flow, cache, base.__dict__[cache])
    _HELD.setdefault(osc, {})[name] = flow
    return flow


#: :func:`held_flow` of each live oscillator, by stop name.
_HELD: weakref.WeakKeyDictionary[ImpactOscillator, dict[str, HeldFlow]] = \
    weakref.WeakKeyDictionary()


def _held_flow(osc: ImpactOscillator, name: str) -> HeldFlow:
    view = osc.stops.stop(name, osc.M, osc.b, osc.R)
    normal = np.asarray(view.normal, dtype=float)
    P = held_frame(normal)
    offset = float(view.position) * normal / float(normal @ normal)
    reduced = None
    if osc.n > 1:
        try:
            held = ImpactOscillator(
                M=P.T @ osc.M @ P, K=P.T @ osc.K @ P, C=P.T @ osc.C @ P,
                F=P.T @ np.asarray(osc.F, dtype=complex), R=1.0, b=1.0, omega=osc.omega,
                F_static=P.T @ (osc.F_static - osc.K @ offset))
        except ParameterError as exc:
            raise ParameterError(f"the system held on stop {name!r} (its n - 1 = {osc.n - 1} "
                                 f"masses, the stop coordinate fixed) is not a machine the "
                                 f"flow can take: {exc}") from None
        reduced = flow_of(held)
    return HeldFlow(oscillator=osc, normal=normal, position=float(view.position),
                    sign=float(view.sign), frame=P, offset=offset, reduced=reduced)


def _read_only(record: tuple) -> tuple:
    """`record`'s fields as a plain tuple, its arrays as read-only views: the argument types
    of :func:`impactcont.kernel.shooting.motion_checks` on the shooting path
    (:func:`impactcont.orbit.multi_impact.impact_sequence`,
    :func:`~impactcont.orbit.multi_impact.contact_stops`), which numba would otherwise
    compile a second time for writable arrays."""
    fields = []
    for value in record:
        if isinstance(value, np.ndarray):
            value = value.view()
            value.flags.writeable = False
        fields.append(value)
    return tuple(fields)
