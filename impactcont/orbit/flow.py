"""The exact state flow between impacts, eq. (9), and its time derivative.

In modal coordinates each mode is its steady forced response plus the free
decay of the deviation from it:

    y_i(t) = y_p,i(t) + W_i(t) ([y_i; y_i'](0) - [y_p,i; y_p,i'](0))

with ``y_p,i(t) = gamma_i cos(omega t + delta) + beta_i sin(omega t + delta)``
(eq. 7). Collecting the ``delta`` terms gives exactly the paper's
``X(t) = U W(t) U^-1 X(0) + U E(t) [cos delta; sin delta]``; ``E`` is built
here as ``P(t) - W(t) P(0)`` from the forced columns ``P = [[phi, psi], [phi', psi']]``.

A constant force ``F_static`` (modal ``g = u^T F_static``) adds the exact term
``U [(1 - W11) g/w^2 + s_y; -W21 g/w^2 + s_v]`` (:func:`~impactcont.model.modal.static_response`:
a held mode's constant offset ``g / w^2``, a free mode's ``g t^2 / 2`` or drift
``g t / (2 a)``), :meth:`Flow.static_term`. A free mode (``w = 0``) has the exact
transfer ``W = [[1, (1 - e^{-2at})/(2a)], [0, e^{-2at}]]`` (``[[1, t], [0, 1]]``
undamped) of eq. (9) in its over-damped and critical forms.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from impactcont.errors import ParameterError
from impactcont.kernel.arrays import Forcing, ForcingDerivatives, ShootingFlow
from impactcont.model.modal import forced_coefficients, free_transfer, static_response
from impactcont.model.oscillator import ImpactOscillator

__all__ = ["Flow", "GeneralFlow", "GeneralMass1Motion", "Mass1Motion", "coordinate_row",
           "flow_of"]

_CHUNK = 1 << 20  # time-mode pairs per vectorised evaluation of x1 (about 100 MB of work arrays)


def _kernel_array(x: Any, dtype: type) -> np.ndarray:
    """``x`` as a new contiguous, writable array of ``dtype`` (one argument type per kernel)."""
    return np.array(x, dtype=dtype, order="C")


def coordinate_row(n: int, row: Any = None, normal: Any = None) -> np.ndarray:
    """The coordinate ``r . x`` whose time scales are asked: ``e_{row}`` or ``normal``.

    Parameters
    ----------
    n : int
        Degrees of freedom.
    row : int, optional
        0-based index of a mass (``x_{row+1}``); the default, with no `normal`, is mass 1.
    normal : array_like, shape (n,), optional
        A stop coordinate ``s = normal . x`` (:meth:`~impactcont.model.stops.Stops.normal`:
        ``e_j``, or ``e_j - e_k`` for a clearance between two masses).

    Returns
    -------
    ndarray, shape (n,)

    Raises
    ------
    TypeError
        Both `row` and `normal` are given, or `row` is not an integer.
    ParameterError
        `row` is out of ``0 .. n-1``, or `normal` is not a finite real vector of length n
        with a non-zero entry.
    """
    if normal is not None:
        if row is not None:
            raise TypeError(f"give row (a mass) or normal (a stop coordinate), not both; got "
                            f"row={row!r}, normal={normal!r}")
        try:
            r = np.array(normal, dtype=float)
        except (TypeError, ValueError) as exc:
            raise ParameterError(f"normal must be a real vector of length {n} (the stop "
                                 f"coordinate s = normal . x); got {normal!r}") from exc
        if r.shape != (n,) or not np.all(np.isfinite(r)) or not np.any(r):
            raise ParameterError(f"normal must be a finite real vector of length {n} with a "
                                 f"non-zero entry (the stop coordinate s = normal . x); got "
                                 f"{normal!r}")
        return r
    if row is None:
        row = 0
    if isinstance(row, bool) or not isinstance(row, (int, np.integer)):
        raise TypeError(f"row must be an integer (the 0-based index of a mass); got {row!r}")
    if not 0 <= row < n:
        raise ParameterError(f"row must be in 0 .. {n - 1} (the 0-based index of a mass); "
                             f"got {row!r}")
    r = np.zeros(n)
    r[row] = 1.0
    return r


def flow_of(osc: ImpactOscillator) -> Flow:
    """``Flow(osc)``, built once per oscillator and kept by it (released with it).

    A flow holds only what its oscillator fixes (and caches of it), so the motions of
    one oscillator can share one; :func:`impactcont.orbit.multi_impact.multi_impact_orbit`
    solved repeatedly on one oscillator then builds its flow and the kernel's arrays once.
    The oscillator holds it (``ImpactOscillator.replace`` does not pass it on): a weak-key
    table would have kept every oscillator alive, its flow holding it.
    """
    flow = osc.__dict__.get("_flow")
    if flow is None:
        flow = Flow(osc)
        object.__setattr__(osc, "_flow", flow)
    return flow


def _empty_flow(cls: type) -> Flow:
    """A flow of class `cls` with no attributes yet (:meth:`Flow.__reduce__`)."""
    return object.__new__(cls)


class Flow:
    """Exact flow of eq. (1) between impacts for one oscillator.

    Parameters
    ----------
    osc : ImpactOscillator
        The oscillator; its modal basis is reused.

    Notes
    -----
    States are ``X = [x; x']`` of length 2n; ``delta`` is the forcing phase at
    ``t = 0``. All time arguments accept arrays and are evaluated at once.
    ``Flow(osc)`` of an oscillator with a general damping matrix or a complex F
    (:attr:`ImpactOscillator.general`) is a :class:`GeneralFlow`, with the same
    interface, from the first-order complex modes.
    """

    #: What a flow computes once from the rest on first use (the kernel's arrays, the last
    #: matrices): neither pickled nor copied, rebuilt by the copy when it needs them.
    _CACHES = ("_arrays", "_flight_arrays", "_forcing", "_static_arrays", "_omega_arrays",
               "_last")

    def __new__(cls, osc: ImpactOscillator) -> Flow:
        if cls is Flow and isinstance(osc, ImpactOscillator) and osc.general:
            return super().__new__(GeneralFlow)
        return super().__new__(cls)

    def __reduce__(self) -> tuple[Any, ...]:
        """Pickle (and ``copy.deepcopy``) a flow without calling ``__new__(osc)``.

        An oscillator keeps its flow (:func:`flow_of`) and the flow its oscillator: the
        default protocol called ``Flow.__new__(cls)`` without `osc` (``TypeError``), so no
        oscillator or motion the shooting path had used could go to a process pool or
        dask. The flow is rebuilt empty and given its attributes (the oscillator's
        reference resolved by pickle's memo, cycle included), its caches left out.
        """
        state = {key: (None if key in self._CACHES else value)
                 for key, value in self.__dict__.items()}
        return _empty_flow, (type(self),), state

    def __init__(self, osc: ImpactOscillator) -> None:
        modes = osc.modes
        self.osc = osc
        self.n = osc.n
        self.omega = osc.omega
        self.u = modes.u
        self.u_inv = modes.u_inv
        self.w = modes.natural_frequencies
        self.a = modes.decay_rates
        self.f = modes.modal_forces
        self.gamma, self.beta = forced_coefficients(self.w, self.a, self.f, self.omega,
                                                    eigenvalue_errors=modes.eigenvalue_errors)
        self.free = np.asarray(modes.free, dtype=bool)
        self.g = self.u.T @ osc.F_static  # modal static force (u^T M u = I)
        self.static_offset = static_response(self.w, self.a, self.g, self.free, 0.0)[0]
        self._arrays: ShootingFlow | None = None
        self._forcing: Forcing | None = None
        self._static_arrays: tuple[np.ndarray, ...] | None = None
        self._omega_arrays: ForcingDerivatives | None = None

    def shooting_arrays(self) -> ShootingFlow:
        """The flow's input of :mod:`impactcont.kernel.shooting` (built once).

        The modal arrays, the constant force (:meth:`static_arrays`), empty first-order
        arrays and the scalar pairs of the contact search (here the modes themselves),
        each contiguous with a fixed dtype so that the kernel compiles once for both flows.
        The forcing at omega is :meth:`forcing_arrays`.
        """
        if self._arrays is None:
            n = self.n
            w, a, f = (_kernel_array(x, float) for x in (self.w, self.a, self.f))
            g, free, xs, xd = self.static_arrays()
            self._arrays = ShootingFlow(
                general=False, w=w, a=a, f=f, u=_kernel_array(self.u, float),
                ui=_kernel_array(self.u_inv, float), lam=np.zeros(0, complex),
                V=np.zeros((0, 0), complex), Vi=np.zeros((0, 0), complex), pw=w, pa=a,
                pk=np.arange(n, dtype=np.int64), pj=np.arange(n, dtype=np.int64), g=g,
                free=free, xs=xs, xd=xd)
        return self._arrays

    def flight_arrays(self) -> tuple[Any, ...]:
        """:meth:`ShootingFlow.flight_arrays <impactcont.kernel.arrays.ShootingFlow.flight_arrays>`
        of :meth:`shooting_arrays` as the plain tuple the shooting entry points take (built
        once: :func:`~impactcont.orbit.multi_impact.newton` passes it on every call)."""
        cached = self.__dict__.get("_flight_arrays")
        if cached is None:
            cached = tuple(self.shooting_arrays().flight_arrays())
            self._flight_arrays = cached
        return cached

    def forcing_arrays(self) -> Forcing:
        """The forcing at omega as :mod:`impactcont.kernel.shooting` takes it (built once):
        the steady modal amplitudes ``gamma, beta`` of eq. (7) (``Z`` empty)."""
        if self._forcing is None:
            self._forcing = Forcing(omega=float(self.omega),
                                    gamma=_kernel_array(self.gamma, float),
                                    beta=_kernel_array(self.beta, float),
                                    Z=np.zeros(0, complex))
        return self._forcing

    def static_arrays(self) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """The constant force and the free modes (built once; the last four fields of
        :meth:`shooting_arrays`, by these names).

        Returns
        -------
        g : ndarray, float, shape (n,)
            Modal static force ``u^T F_static`` (modal flow; empty for the first-order flow).
        free : ndarray, bool, shape (n,)
            The free modes (``w_i = 0`` exactly; modal flow; empty for the first-order flow).
            Each mode's state with the constant force is
            ``Q + W(t) (Y(0) - Q) + S(t)``, :func:`~impactcont.model.modal.static_response`:
            held ``Q = [g/w^2, 0]``, ``S = 0``; free ``Q = 0``,
            ``S = [g t^2 phi(2at)/2, g t psi(2at)]``.
        xs : ndarray, float, shape (2n,)
            First-order flow: the constant part ``X_s`` of the static response (empty for
            the modal flow), ``X(t) = X_p(t) + X_s + Phi(t) (X(0) - X_p(0) - X_s) + d t``.
        xd : ndarray, float, shape (2n,)
            First-order flow: ``d``, the drift of the damped free modes per unit time
            (zero without one; empty for the modal flow).
        """
        if self._static_arrays is None:
            self._static_arrays = (_kernel_array(self.g, float),
                                   np.array(self.free, dtype=np.bool_), np.zeros(0),
                                   np.zeros(0))
        return self._static_arrays

    def omega_arrays(self) -> ForcingDerivatives:
        """``d gamma / d omega``, ``d beta / d omega`` (modal flow; empty for the first-order
        flow) and ``dZ / d omega`` (first-order flow; empty for the modal flow), the inputs
        of :func:`impactcont.kernel.shooting.omega_partials` (built once)."""
        if self._omega_arrays is None:
            om = self.omega
            den = (self.w - om) * (self.w + om) + 2j * self.a * om
            dA = (self.gamma - 1j * self.beta) * (2.0 * om - 2j * self.a) / den
            self._omega_arrays = ForcingDerivatives(dgamma=_kernel_array(dA.real, float),
                                                    dbeta=_kernel_array(-dA.imag, float),
                                                    dZ=np.zeros(0, complex))
        return self._omega_arrays

    def time_scales(self, row: int | None = None, *, normal: Any = None
                    ) -> tuple[float, float]:
        """Fastest oscillation frequency and fastest decay rate seen by one coordinate.

        The coordinate is mass ``row + 1`` (``x_{row+1}``, the default mass 1) or, with
        `normal`, the stop coordinate ``s = normal . x`` (a clearance between two masses,
        ``x_j - x_k``): the modes it sees are those of non-zero weight ``normal^T U``
        (eq. 9), as in the contact search of :mod:`impactcont.kernel.shooting`. A mode
        that mass j does not see but the other mass of a pair does (or one that cancels in
        ``x_j`` and not in ``x_j - x_k``) counts for the pair.

        Parameters
        ----------
        row : int, optional
            0-based index of a mass.
        normal : array_like, shape (n,), optional
            The stop coordinate (:meth:`~impactcont.model.stops.Stops.normal`); not with
            `row`.

        Returns
        -------
        rate, decay : float
            ``max(omega, fastest damped frequency)`` and the fastest decay rate of the
            modes the coordinate sees.
        """
        part = np.abs(coordinate_row(self.n, row, normal) @ self.u) > 0
        w, a = self.w[part], self.a[part]
        d = (w - a) * (w + a)
        wd = np.sqrt(np.maximum(d, 0.0))
        fast = a + np.sqrt(np.maximum(-d, 0.0))
        return float(max(self.omega, wd.max(initial=0.0))), float(fast.max(initial=0.0))

    # -- modal pieces ---------------------------------------------------------------------------
    def transfer(self, t: np.ndarray) -> tuple[np.ndarray, ...]:
        """Free modal transfer blocks ``W11, W12, W21, W22``, each (nt, n)."""
        return free_transfer(self.w, self.a, np.atleast_1d(t))

    def forced(self, t: np.ndarray, delta: float) -> tuple[np.ndarray, np.ndarray]:
        """Steady forced modal displacement and velocity at times t, each (nt, n)."""
        theta = self.omega * np.atleast_1d(np.asarray(t, dtype=float))[:, None] + delta
        c, s = np.cos(theta), np.sin(theta)
        y = self.gamma * c + self.beta * s
        v = self.omega * (self.beta * c - self.gamma * s)
        return y, v

    def static(self, t: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """The constant force's modal offset ``g / w^2`` (n,) and the free modes' response
        from rest ``s_y, s_v`` (nt, n) (:func:`~impactcont.model.modal.static_response`)."""
        return static_response(self.w, self.a, self.g, self.free, np.atleast_1d(t))

    def to_modal(self, X: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Modal displacement and velocity of a physical state ``X`` (2n,)."""
        X = np.asarray(X, dtype=float)
        return self.u_inv @ X[: self.n], self.u_inv @ X[self.n:]

    # -- physical state --------------------------------------------------------------------------
    def modal_state(self, t: np.ndarray, X0: np.ndarray, delta: float
                    ) -> tuple[np.ndarray, np.ndarray]:
        """Modal displacement and velocity ``y(t), y'(t)``, each (nt, n)."""
        y0, v0 = self.to_modal(X0)
        yp0, vp0 = self.forced(0.0, delta)
        offset, s_y, s_v = self.static(t)
        dy, dv = y0 - yp0[0] - offset, v0 - vp0[0]
        W11, W12, W21, W22 = self.transfer(t)
        yp, vp = self.forced(t, delta)
        return yp + offset + W11 * dy + W12 * dv + s_y, vp + W21 * dy + W22 * dv + s_v

    def state(self, t: np.ndarray, X0: np.ndarray, delta: float) -> np.ndarray:
        """State ``X(t) = [x; x'](t)`` of eq. (9), shape (nt, 2n)."""
        y, v = self.modal_state(t, X0, delta)
        return np.hstack([y @ self.u.T, v @ self.u.T])

    def state_derivative(self, t: np.ndarray, X0: np.ndarray, delta: float) -> np.ndarray:
        """Time derivative ``X'(t) = [x'; x''](t)``, shape (nt, 2n)."""
        y, v = self.modal_state(t, X0, delta)
        theta = self.omega * np.atleast_1d(np.asarray(t, dtype=float))[:, None] + delta
        acc = self.f * np.cos(theta) + self.g - 2.0 * self.a * v - self.w**2 * y
        return np.hstack([v @ self.u.T, acc @ self.u.T])

    # -- matrices of eq. (9) --------------------------------------------------------------------
    def transition_matrix(self, t: float) -> np.ndarray:
        """``U W(t) U^-1``, the free state transition over time t, shape (2n, 2n)."""
        return self.matrices(t)[0]

    def forcing_matrix(self, t: float) -> np.ndarray:
        """``U E(t)`` of eq. (9), shape (2n, 2): columns multiply ``cos delta, sin delta``."""
        return self.matrices(t)[1]

    def static_term(self, t: float) -> np.ndarray:
        """The constant force's part of ``X(t)`` from ``X(0) = 0``, (2n,):
        ``U [(1 - W11) g/w^2 + s_y; -W21 g/w^2 + s_v]`` (exact; zero without ``F_static``),
        so that ``X(t) = U W U^-1 X(0) + U E [cos delta; sin delta] + static_term(t)``."""
        W11, _, W21, _ = (blk[0] for blk in self.transfer(t))
        offset, s_y, s_v = self.static(t)
        return np.concatenate([self.u @ (offset - W11 * offset + s_y[0]),
                               self.u @ (-W21 * offset + s_v[0])])

    def matrices(self, t: float, static: bool = False
                 ) -> tuple[np.ndarray, ...]:
        """``U W(t) U^-1`` (2n, 2n) and ``U E(t)`` (2n, 2) of eq. (9) from one modal transfer;
        with ``static``, :meth:`static_term` (2n,) as a third item."""
        W11, W12, W21, W22 = (blk[0] for blk in self.transfer(t))
        u, ui = self.u, self.u_inv
        transition = np.block([[(u * W11) @ ui, (u * W12) @ ui],
                               [(u * W21) @ ui, (u * W22) @ ui]])
        om = self.omega
        ct, st = np.cos(om * t), np.sin(om * t)
        g, b = self.gamma, self.beta
        phi, psi = g * ct + b * st, b * ct - g * st
        dphi, dpsi = om * (b * ct - g * st), -om * (g * ct + b * st)
        # E = P(t) - W(t) P(0) with P(0) = [[g, b], [om b, -om g]]
        e_y_cos = phi - W11 * g - W12 * om * b
        e_y_sin = psi - W11 * b + W12 * om * g
        e_v_cos = dphi - W21 * g - W22 * om * b
        e_v_sin = dpsi - W21 * b + W22 * om * g
        forcing = np.vstack([u @ np.column_stack([e_y_cos, e_y_sin]),
                             u @ np.column_stack([e_v_cos, e_v_sin])])
        if static:
            return transition, forcing, self.static_term(t)
        return transition, forcing

    def mass1(self, X0: np.ndarray, delta: float) -> Mass1Motion:
        """Fast evaluator of ``x1, x1', x1''`` along the flow from ``X0`` at phase ``delta``."""
        return Mass1Motion(self, X0, delta)

    def motion(self, X0: np.ndarray, delta: float, index: int = 0, sign: float = 1.0,
               normal: np.ndarray | None = None) -> Mass1Motion:
        """Fast evaluator of ``sign * x_j`` and its derivatives, ``j = index + 1``, or of
        ``sign * normal . x`` (a stop coordinate, :meth:`Stops.normal`) when given."""
        return Mass1Motion(self, X0, delta, index, sign, normal)

    def omega_partial(self, t: float, X0: np.ndarray, theta: float) -> np.ndarray:
        """``dX(t)/d omega`` at fixed ``t``, start state ``X0`` and start phase ``theta``.

        Only the forced part of eq. (9) depends on omega: with the modal steady
        amplitudes ``gamma - i beta = f / (w^2 - omega^2 + 2 i a omega)`` (eq. 7) and
        ``P(t) = [y_p; y_p'](t)``, ``X(t) = U [P(t) + W(t) (Y0 - P(0))]`` gives
        ``dX/d omega = U [dP(t) - W(t) dP(0)]``.

        Returns
        -------
        ndarray, shape (2n,)
        """
        om = self.omega
        den = (self.w - om) * (self.w + om) + 2j * self.a * om
        A = self.gamma - 1j * self.beta
        dA = A * (2.0 * om - 2j * self.a) / den
        dg, db = dA.real, -dA.imag
        g, b = self.gamma, self.beta

        def dP(time: float) -> tuple[np.ndarray, np.ndarray]:
            c, s = math.cos(om * time + theta), math.sin(om * time + theta)
            y = g * c + b * s
            dy = dg * c + db * s + time * (b * c - g * s)
            dv = (b * c - g * s) + om * (db * c - dg * s) - om * time * y
            return dy, dv

        dy_t, dv_t = dP(t)
        dy_0, dv_0 = dP(0.0)
        W11, W12, W21, W22 = (blk[0] for blk in self.transfer(np.array([t])))
        dy = dy_t - (W11 * dy_0 + W12 * dv_0)
        dv = dv_t - (W21 * dy_0 + W22 * dv_0)
        return np.concatenate([self.u @ dy, self.u @ dv])


class Mass1Motion:
    """``x1(t), x1'(t), x1''(t)`` along one flight, vectorised over t.

    Used to locate impacts and interior maxima: it evaluates only the first
    row of ``u``, O(n) per time instead of O(n^2). With ``index`` and ``sign`` it
    evaluates ``sign * x_j`` of mass ``j = index + 1`` instead (a stop on another
    mass, or the lower stop met moving down).
    """

    def __init__(self, flow: Flow, X0: np.ndarray, delta: float, index: int = 0,
                 sign: float = 1.0, normal: np.ndarray | None = None) -> None:
        self.flow = flow
        self.delta = float(delta)
        y0, v0 = flow.to_modal(X0)
        yp0, vp0 = flow.forced(0.0, delta)
        self.dy = y0 - yp0[0] - flow.static_offset
        self.dv = v0 - vp0[0]
        row = flow.u[index] if normal is None else np.asarray(normal, dtype=float) @ flow.u
        self.u0 = row if sign == 1.0 else sign * row  # the weights normal^T U of the modes
        self.static = bool(np.any(flow.g))

    def __call__(self, t: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Return ``x1, x1', x1''`` at times t (each shape (nt,))."""
        return self.derivatives(t)[:3]

    def derivatives(self, t: np.ndarray
                    ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """Return ``x1`` and its first three time derivatives at times t (each (nt,)).

        Evaluated in chunks of at most ``_CHUNK`` time-mode pairs, so that the dense
        grids of stiff, lightly damped chains (up to 2e6 times) with many modes keep a
        bounded memory footprint (about 12 arrays of ``nt x n`` floats per chunk).
        """
        t = np.atleast_1d(np.asarray(t, dtype=float))
        step = max(1, _CHUNK // max(self.flow.n, 1))
        if t.size <= step:
            return self._derivatives(t)
        parts = [self._derivatives(t[k:k + step]) for k in range(0, t.size, step)]
        return tuple(np.concatenate([p[i] for p in parts]) for i in range(4))  # type: ignore[return-value]

    def _derivatives(self, t: np.ndarray
                     ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        fl = self.flow
        W11, W12, W21, W22 = fl.transfer(t)
        theta = fl.omega * t[:, None] + self.delta
        c, s = np.cos(theta), np.sin(theta)
        y = fl.gamma * c + fl.beta * s + W11 * self.dy + W12 * self.dv
        v = fl.omega * (fl.beta * c - fl.gamma * s) + W21 * self.dy + W22 * self.dv
        if self.static:
            offset, s_y, s_v = fl.static(t)
            y = y + offset + s_y
            v = v + s_v
        acc = fl.f * c + fl.g - 2.0 * fl.a * v - fl.w**2 * y
        jerk = -fl.omega * fl.f * s - 2.0 * fl.a * acc - fl.w**2 * v
        return y @ self.u0, v @ self.u0, acc @ self.u0, jerk @ self.u0


class GeneralFlow(Flow):
    """Exact flow of eq. (1) with any damping matrix C and complex F, from the complex modes.

    With ``A = V diag(lambda) V^-1`` (:class:`impactcont.model.first_order.FirstOrderBasis`)
    and the steady forced state ``X_p(t) = Re(Z e^{i(omega t + delta)})``,

        X(t) = X_p(t) + Re(V diag(exp(lambda t)) V^-1 (X(0) - X_p(0)))         (eq. 9)

    in closed form (no integration). Same interface as :class:`Flow`.

    A free mode that C leaves undamped adds the polynomial part ``t N (X(0) - X_p(0) -
    X_s)`` (:attr:`FirstOrderBasis.nilpotent <impactcont.model.first_order.FirstOrderBasis.
    nilpotent>`: its drift ``q0 + v0 t``), and a constant force on it ``N d t^2 / 2`` (its
    ``g t^2 / 2``, :attr:`accel`).
    """

    def __init__(self, osc: ImpactOscillator) -> None:
        basis = osc.first_order
        self.osc = osc
        self.n = osc.n
        self.omega = osc.omega
        self.basis = basis
        self.lam = basis.eigenvalues
        self.V = basis.V
        self.V_inv = basis.V_inv
        self.Z = basis.forced_amplitude(osc.F, osc.omega)
        self.static_offset, self.drift = self._static(osc)
        self.nilpotent = basis.nilpotent
        self.polynomial = basis.polynomial
        self.accel = self.nilpotent @ self.drift  # the t^2 / 2 coefficient of the constant force
        self._last: tuple[float, tuple[np.ndarray, np.ndarray]] | None = None  # matrices(T)
        self._arrays: ShootingFlow | None = None
        self._forcing: Forcing | None = None
        self._static_arrays: tuple[np.ndarray, ...] | None = None
        self._omega_arrays: ForcingDerivatives | None = None

    def shooting_arrays(self) -> ShootingFlow:
        """The flow's input of :mod:`impactcont.kernel.shooting` (built once,
        :meth:`Flow.shooting_arrays`): empty modal arrays, the first-order arrays, the
        scalar pairs of :attr:`FirstOrderBasis.scalar_pairs` (the contact search's modes)
        and the constant force's ``X_s``, ``d``.
        """
        if self._arrays is None:
            none, empty = np.zeros(0), np.zeros((0, 0))
            pw, pa, pk, pj = self.basis.scalar_pairs
            lam, V, Vi = (_kernel_array(x, complex) for x in (self.lam, self.V, self.V_inv))
            g, free, xs, xd = self.static_arrays()
            self._arrays = ShootingFlow(
                general=True, w=none, a=none, f=none, u=empty, ui=empty, lam=lam, V=V, Vi=Vi,
                pw=_kernel_array(pw, float), pa=_kernel_array(pa, float),
                pk=_kernel_array(pk, np.int64), pj=_kernel_array(pj, np.int64), g=g,
                free=free, xs=xs, xd=xd)
        return self._arrays

    def forcing_arrays(self) -> Forcing:
        """The forcing at omega (:meth:`Flow.forcing_arrays`): the complex steady amplitude
        ``Z`` (``gamma, beta`` empty)."""
        if self._forcing is None:
            self._forcing = Forcing(omega=float(self.omega), gamma=np.zeros(0),
                                    beta=np.zeros(0), Z=_kernel_array(self.Z, complex))
        return self._forcing

    def _static(self, osc: ImpactOscillator) -> tuple[np.ndarray, np.ndarray]:
        """``X_s`` and ``d`` of the constant force: ``X' = A X + b``, ``b = [0; M^-1 F_s]``,
        ``h = V^-1 b``; ``X_s = Re(sum_{lambda_k != 0} -V_k h_k / lambda_k)`` (constant) and
        ``d = Re(sum_{lambda_k = 0} V_k h_k)`` (the free modes' drift per unit time; ``A X_s
        + b = d`` and ``A d = N d``, ``A N d = 0`` (:attr:`FirstOrderBasis.nilpotent`, zero
        without an undamped free mode), so ``X_s + d t + N d t^2 / 2`` is a particular
        solution: an undamped free mode's ``g t^2 / 2``)."""
        n = self.n
        if not np.any(osc.F_static):
            return np.zeros(2 * n), np.zeros(2 * n)
        rhs = np.concatenate([np.zeros(n), np.linalg.solve(osc.M, osc.F_static)])
        h = self.V_inv @ rhs
        zero = (np.zeros(2 * n, bool) if self.basis.zero is None
                else np.asarray(self.basis.zero, bool))
        lam = np.where(zero, 1.0, self.lam)
        offset = (self.V @ np.where(zero, 0.0, -h / lam)).real
        drift = (self.V @ np.where(zero, h, 0.0)).real
        return offset, drift

    def static_arrays(self) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """:meth:`Flow.static_arrays` of the first-order flow: empty ``g``, ``free``, then
        ``X_s`` and ``d`` (2n,) (built once)."""
        if self._static_arrays is None:
            self._static_arrays = (np.zeros(0), np.zeros(0, dtype=np.bool_),
                                   _kernel_array(self.static_offset, float),
                                   _kernel_array(self.drift, float))
        return self._static_arrays

    def static_term(self, t: float) -> np.ndarray:
        """The constant force's part of ``X(t)`` from ``X(0) = 0``: ``X_s - Phi(t) X_s + d t
        + N d t^2 / 2``."""
        t = float(np.asarray(t).reshape(-1)[0])
        return (self.static_offset - self.basis.transition(t) @ self.static_offset
                + self.drift * t + self.accel * (0.5 * t * t))

    def omega_arrays(self) -> ForcingDerivatives:
        """Empty modal derivatives and ``dZ / d omega`` (:meth:`Flow.omega_arrays`)."""
        if self._omega_arrays is None:
            dZ = self.basis.forced_amplitude_derivative(self.Z, self.omega)
            self._omega_arrays = ForcingDerivatives(dgamma=np.zeros(0), dbeta=np.zeros(0),
                                                    dZ=_kernel_array(dZ, complex))
        return self._omega_arrays

    def time_scales(self, row: int | None = None, *, normal: Any = None
                    ) -> tuple[float, float]:
        """Fastest oscillation frequency and fastest decay rate seen by one coordinate
        (:meth:`Flow.time_scales`): the complex modes of non-zero weight ``normal^T V_x``
        (``V_x`` the position rows of ``V``), mass ``row + 1``'s row by default."""
        part = np.abs(coordinate_row(self.n, row, normal) @ self.V[: self.n]) > 0
        lam = self.lam[part]
        return (float(max(self.omega, np.abs(lam.imag).max(initial=0.0))),
                float((-lam.real).max(initial=0.0)))

    def forced_state(self, t: np.ndarray, delta: float) -> np.ndarray:
        """Steady forced state ``Re(Z e^{i(omega t + delta)})``, shape (nt, 2n)."""
        theta = self.omega * np.atleast_1d(np.asarray(t, dtype=float))[:, None] + delta
        return (self.Z * np.exp(1j * theta)).real

    def _deviation(self, X0: np.ndarray, delta: float) -> np.ndarray:
        """``X(0) - X_p(0) - X_s``, the free part's start (2n,)."""
        return (np.asarray(X0, dtype=float) - self.forced_state(0.0, delta)[0]
                - self.static_offset)

    def modal_deviation(self, X0: np.ndarray, delta: float) -> np.ndarray:
        """Complex modal coordinates ``V^-1 (X(0) - X_p(0) - X_s)`` of the free part, (2n,)."""
        return self.V_inv @ self._deviation(X0, delta)

    def state(self, t: np.ndarray, X0: np.ndarray, delta: float) -> np.ndarray:
        """State ``X(t) = [x; x'](t)`` of eq. (9), shape (nt, 2n)."""
        t = np.atleast_1d(np.asarray(t, dtype=float))
        zeta = self.modal_deviation(X0, delta)
        free = (np.exp(t[:, None] * self.lam) * zeta) @ self.V.T
        out = (self.forced_state(t, delta) + free.real + self.static_offset
               + t[:, None] * self.drift)
        if self.polynomial:  # t N (X(0) - X_p(0) - X_s) + N d t^2 / 2
            out += t[:, None] * (self.nilpotent @ self._deviation(X0, delta))
            out += (0.5 * t * t)[:, None] * self.accel
        return out

    def state_derivative(self, t: np.ndarray, X0: np.ndarray, delta: float) -> np.ndarray:
        """Time derivative ``X'(t) = [x'; x''](t)``, shape (nt, 2n)."""
        t = np.atleast_1d(np.asarray(t, dtype=float))
        zeta = self.modal_deviation(X0, delta)
        free = (np.exp(t[:, None] * self.lam) * (self.lam * zeta)) @ self.V.T
        theta = self.omega * t[:, None] + delta
        out = (1j * self.omega * self.Z * np.exp(1j * theta)).real + free.real + self.drift
        if self.polynomial:
            out += self.nilpotent @ self._deviation(X0, delta) + t[:, None] * self.accel
        return out

    def transition_matrix(self, t: float) -> np.ndarray:
        """``Phi(t) = Re(V diag(exp(lambda t)) V^-1) + t N``, shape (2n, 2n)."""
        return self.matrices(t)[0]

    def matrices(self, t: float, static: bool = False) -> tuple[np.ndarray, ...]:
        """``Phi(t)`` (2n, 2n) and the forcing columns ``P(t) - Phi(t) P(0)`` (2n, 2) of
        eq. (9), ``P(t) = [Re(Z e^{i omega t}), -Im(Z e^{i omega t})]`` (columns multiply
        ``cos delta, sin delta``); with ``static``, :meth:`static_term` (2n,) as a third item."""
        t = float(np.asarray(t).reshape(-1)[0])
        if static:
            return (*self.matrices(t), self.static_term(t))
        if self._last is not None and self._last[0] == t:  # eq. (12) and G use the same T
            return self._last[1]
        transition = self.basis.transition(t)
        zt = self.Z * np.exp(1j * self.omega * t)
        P_t = np.column_stack([zt.real, -zt.imag])
        P_0 = np.column_stack([self.Z.real, -self.Z.imag])
        out = (transition, P_t - transition @ P_0)
        for x in out:
            x.setflags(write=False)  # shared by the next call at the same t
        self._last = (t, out)
        return out

    def transfer(self, t: np.ndarray) -> tuple[np.ndarray, ...]:
        raise NotImplementedError("a general damping matrix has no real 2x2 modal blocks; use "
                                  "state, matrices or the first-order basis")

    def mass1(self, X0: np.ndarray, delta: float) -> GeneralMass1Motion:
        """Fast evaluator of ``x1, x1', x1''`` along the flow from ``X0`` at phase ``delta``."""
        return GeneralMass1Motion(self, X0, delta)

    def motion(self, X0: np.ndarray, delta: float, index: int = 0, sign: float = 1.0,
               normal: np.ndarray | None = None) -> GeneralMass1Motion:
        """Fast evaluator of ``sign * x_j`` and its derivatives, ``j = index + 1``, or of
        ``sign * normal . x`` when given."""
        return GeneralMass1Motion(self, X0, delta, index, sign, normal)

    def omega_partial(self, t: float, X0: np.ndarray, theta: float) -> np.ndarray:
        """``dX(t)/d omega`` at fixed ``t``, start state ``X0`` and start phase ``theta``.

        Only the forced state depends on omega: ``X(t) = X_p(t) + Phi(t) (X0 - X_p(0))``
        with ``X_p(t) = Re(Z e^{i(omega t + theta)})`` gives ``dX/d omega = dX_p(t) -
        Phi(t) dX_p(0)``, ``dX_p(t) = Re((dZ/d omega + i t Z) e^{i(omega t + theta)})``
        (``dZ/d omega`` exact from the dynamic stiffness,
        :meth:`FirstOrderBasis.forced_amplitude_derivative`).

        Returns
        -------
        ndarray, shape (2n,)
        """
        dZ = self.basis.forced_amplitude_derivative(self.Z, self.omega)
        rot_t = np.exp(1j * (self.omega * t + theta))
        d_t = ((dZ + 1j * t * self.Z) * rot_t).real
        d_0 = (dZ * np.exp(1j * theta)).real
        return d_t - self.transition_matrix(t) @ d_0


class GeneralMass1Motion(Mass1Motion):
    """``x1(t)`` and its derivatives along one flight of a :class:`GeneralFlow`, O(n) per time:

        x1^(j) = Re((i omega)^j Z_1 e^{i theta}) + Re(sum_k lambda_k^j V_1k zeta_k e^{lambda_k t})

    plus the constant force's ``X_s + d t`` and the polynomial part of undamped free modes,
    ``(r N dev) t + (r N d) t^2 / 2`` (:class:`GeneralFlow`).
    """

    def __init__(self, flow: GeneralFlow, X0: np.ndarray, delta: float, index: int = 0,
                 sign: float = 1.0, normal: np.ndarray | None = None) -> None:
        self.flow = flow
        self.delta = float(delta)
        n = flow.n
        r = np.zeros(2 * n)
        if normal is None:
            r[index] = sign
        else:
            r[:n] = sign * np.asarray(normal, dtype=float)
        self.c = (r @ flow.V) * flow.modal_deviation(X0, delta)  # (r V)_k zeta_k
        self.z = complex(r @ flow.Z)
        self.offset = float(r @ flow.static_offset)  # the constant force's constant part
        self.rate = float(r @ flow.drift)  # and its drift per unit time
        # undamped free modes: the drift t r N dev and the constant force's r N d t^2 / 2
        self.linear = (float(r @ (flow.nilpotent @ flow._deviation(X0, delta)))
                       if flow.polynomial else 0.0)
        self.quadratic = float(r @ flow.accel) if flow.polynomial else 0.0

    def _derivatives(self, t: np.ndarray
                     ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        fl = self.flow
        e = np.exp(t[:, None] * fl.lam) * self.c
        forced = self.z * np.exp(1j * (fl.omega * t + self.delta))
        iw = 1j * fl.omega
        out = []
        for j in range(4):
            out.append((forced * iw**j).real + (e @ fl.lam**j).real)
        out[0] = out[0] + self.offset + self.rate * t
        out[1] = out[1] + self.rate
        if self.linear or self.quadratic:
            out[0] = out[0] + (self.linear + 0.5 * self.quadratic * t) * t
            out[1] = out[1] + self.linear + self.quadratic * t
            out[2] = out[2] + self.quadratic
        return tuple(out)  # type: ignore[return-value]
