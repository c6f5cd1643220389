"""Periodic N-p motions: p impacts in N forcing periods, by shooting with the exact flow.

Impacts are numbered ``k = 0 .. p-1``; flight ``k`` runs from impact ``k`` to
impact ``k+1`` (impact ``p`` is impact 0 again, N forcing periods later). On
flight ``k`` the state starts at ``X_k = [b, z_k]`` (right after impact ``k``,
on the section ``x1 = b``) with forcing phase ``theta_k`` and lasts ``tau_k``;
by eq. (9) it arrives at

    X_k^- = U W(tau_k) U^-1 X_k + U E(tau_k) [cos theta_k; sin theta_k]

and the impact law (eq. 4) gives the next post-impact state ``D X_k^-``. The
N-p motion solves, for every flight,

    r_k = D X_k^- - X_{k+1} = 0          (2n equations: x1 = b and the next state)

with ``theta_k = delta + omega (tau_0 + .. + tau_{k-1})`` and the last flight time
fixed by the period, ``tau_{p-1} = 2 pi N / omega - (tau_0 + .. + tau_{p-2})``.
The unknowns

    u = [delta, tau_0 .. tau_{p-2}, z_0 .. z_{p-1}],     z_k = [x2..xn, x1'..xn'] of X_k

are ``2 n p`` numbers for ``2 n p`` equations. Newton uses the exact derivatives
of the flow: ``dX^-/dX_k = U W U^-1``, ``dX^-/dtheta = U E [-sin; cos]`` and
``dX^-/dtau = X'(tau^-)`` (the state derivative). For ``p = 1`` the system is
eq. (12)-(14) written as shooting, and its solution is the closed form.

Stability: each flight-and-impact has the Jacobian ``G_k`` of eq. (25) (with
``T`` replaced by ``tau_k`` and ``delta`` by ``theta_k``); the motion's impact map
over N periods has ``G = G_{p-1} ... G_1 G_0``, multipliers ``eig(G)``.

Two stops, a stop on any mass (``osc.stops``, :mod:`impactcont.model.stops`): the
impacting mass is ``j`` and impact ``k`` hits the stop ``pattern[k]`` (``"U"``:
``x_j = b``, restitution ``R``; ``"L"``: ``x_j = -b_low``, restitution ``R_low``).
Everything above holds with ``x1`` replaced by ``x_j``, ``b`` by the position
``c_k`` of the stop of impact k, and ``D`` by the impact matrix ``D_k`` of that
stop (``-R_k`` on ``x_j'``): ``X_k = [.., x_j = c_k, ..]``, ``z_k`` is ``X_k``
without ``x_j``, ``r_k = D_{k+1} X_k^- - X_{k+1}``, and ``G_k`` is eq. (25) on the
section ``x_j = c_{k+1}`` with ``D_{k+1}``. The product G is taken in the same
coordinates ``[z, theta]`` for both stops, so its eigenvalues are the
multipliers whatever the pattern. A flight must not touch either stop inside
(eq. 16 against both: the interior maxima of ``x_j`` below ``b``, its interior
minima above ``-b_low``), and each impact must arrive towards its stop
(``x_j' > 0`` at ``U``, ``< 0`` at ``L``).
"""

from __future__ import annotations

import dataclasses
import logging
import math
import warnings
import weakref
from collections.abc import Mapping
from typing import Any

import numpy as np

from impactcont.errors import NoPeriodicMotionError, ParameterError, UnresolvedMotionWarning
from impactcont.kernel.arrays import (
    CheckedFlights,
    ContactStops,
    ImpactSequence,
    MotionChecks,
    NewtonResult,
    ShotFlights,
)
from impactcont.model.oscillator import ImpactOscillator
from impactcont.model.stops import (
    LOWER,
    UPPER,
    check_pattern,
    require_forcing,
    sticking_pattern,
)
from impactcont.orbit.flow import Flow, flow_of
from impactcont.orbit.held_flow import held_flow
from impactcont.orbit.periodic import (
    IllConditionedWarning,
    PeriodicOrbit,
    _check_N,
)
from impactcont.orbit.stop_geometry import StopGeometry, stop_geometry
from impactcont.vocabulary import check_positive_integer

__all__ = [
    "MultiImpactOrbit",
    "Shooting",
    "check_impacts",
    "flight_jacobian",
    "initial_unknowns",
    "landing_impacts",
    "multi_impact_orbit",
    "newton",
    "omega_partial",
    "omega_partials",
    "orbit_from_unknowns",
    "primitive_orbit",
    "shooting",
    "shooting_accuracy",
    "split_unknowns",
    "stop_geometry",
]

log = logging.getLogger(__name__)

TWO_PI = 2.0 * math.pi
_EPS = float(np.finfo(float).eps)
# warn when the error estimate of a solution (shooting_accuracy) exceeds this, relative to
# max(1, |u|): the closed form's threshold (cond * eps ~ 1e-6 of eq. 12, orbit.periodic)
_ERROR_WARN = 1e-6
# a failed Newton whose residual is this small (relative) stopped next to a solution
_NEAR_SOLUTION = 1e-6
# an error estimate this large (relative) says nothing about the motion along the null
# direction of the Jacobian: singular, a bifurcation point
_SINGULAR = 1e-3


def check_impacts(p: object) -> int:
    """``p`` as an int ``>= 1`` (impacts per N forcing periods), else :class:`ParameterError`
    (:func:`impactcont.vocabulary.check_positive_integer`)."""
    return check_positive_integer("p", p, "impacts per N forcing periods")


def _wrap(phase: float) -> float:
    """Phase wrapped to ``(-pi, pi]``."""
    return math.atan2(math.sin(phase), math.cos(phase))


def _nans(shape: int | tuple[int, ...]) -> np.ndarray:
    """A new float array of NaN (``np.full`` without its Python-level overhead: every motion
    makes three)."""
    out = np.empty(shape)
    out.fill(np.nan)
    return out


@dataclasses.dataclass(frozen=True, eq=False)
class MultiImpactOrbit:
    """One periodic N-p motion: p impacts in N forcing periods.

    Per-impact arrays are indexed by the impact ``k = 0 .. p-1``; per-flight
    arrays by the flight ``k`` from impact ``k`` to impact ``k+1``.

    Attributes
    ----------
    oscillator : ImpactOscillator
    N : int
        Forcing periods of the motion, ``period = 2 pi N / omega``.
    p : int
        Impacts per period.
    phases : ndarray, shape (p,)
        Forcing phase ``theta_k`` at impact k, in ``(-pi, pi]``.
    flight_times : ndarray, shape (p,)
        ``tau_k``, time from impact k to impact k+1; they sum to the period.
    states : ndarray, shape (p, 2n)
        State ``X_k = [x; x']`` right after impact k (``x_j`` at the stop of impact k;
        ``x1 = b`` for the paper's stop).
    impact_velocities : ndarray, shape (p,)
        Speed of the impacting mass towards the stop just before impact k: ``x_j'``
        at the upper stop, ``-x_j'`` at the lower (``h2`` of eq. 22 of the flight
        that ends there, signed by the stop).
    flight_gap_min : ndarray, shape (p,)
        Smallest clearance on flight k at the interior extrema of ``x_j`` (eq. 16):
        ``b - x_j`` at its maxima and, with a lower stop, ``x_j + b_low`` at its
        minima; ``+inf`` when there is none. With stops on several coordinates
        (``stops.extra``) the smallest over every stop (each on its own coordinate).
        Both ends of the flight count too: every stop's clearance at its start (but
        the stop impact k hits) and at its end (but the stop impact k+1 hits), so that a
        coordinate past a stop when the flight ends on another stop is seen, and the
        smallest clearance changes sign continuously at such a grazing. Where a sticking
        phase follows impact k, segment k's smallest clearance also covers every other
        stop along its chatter's bounces and its held phase
        (:mod:`impactcont.orbit.sticky`), so that GR sees a grazing there.
    flight_gap_min_times : ndarray, shape (p,)
        Time of that extremum after impact k (NaN when there is none; 0 or ``tau_k``
        for an end of the flight); after the release where a sticking phase follows
        impact k, so negative for a clearance inside the sticking phase.
    jacobians : ndarray, shape (p, 2n, 2n)
        ``G_k``, Jacobian of flight k and the impact ending it (eq. 25) in
        ``z = [dx2..dxn, dx1'..dxn', d theta]``.
    G : ndarray, shape (2n, 2n)
        ``G_{p-1} ... G_0``: the impact map over the whole motion, from impact 0.
    multipliers : ndarray of complex, shape (2n,)
        Eigenvalues of ``G``, largest modulus first.
    physical : bool
        Every flight time ``> 0``, every impact velocity ``> 0``, every interior
        clearance ``> 0`` (no contact inside any flight) and every stop's clearance at
        every impact state ``>= 0`` to the rounding of its evaluation (relative to the
        motion's size, :data:`impactcont.kernel.shooting._END_ULPS`).
    reason : str
        Why the motion is not physical ("" when it is).
    residual : float
        Max-norm of the shooting residual at the solution.
    pattern : str
        The stop of each impact, ``"U"`` (upper) or ``"L"`` (lower), length p.
    flight_gap_lower : ndarray, shape (p,)
        Smallest ``x_j + b_low`` at the interior minima of ``x_j`` on flight k
        (``+inf`` without a lower stop or a minimum): the lower-stop part of
        ``flight_gap_min``.
    condition_number : float
        Condition number (2-norm) of the shooting Jacobian at the solution; large next
        to a bifurcation point with a multiplier +1 (fold, symmetry-breaking pitchfork).
    error_estimate : float
        How far the unknowns ``u`` may be from the exact motion (2-norm), from
        :func:`shooting_accuracy`: ``|J^-1 r| + cond eps max(1, |u|)``.
        :func:`multi_impact_orbit` fills both and warns when the error exceeds 1e-6
        relative; NaN when not computed (:func:`orbit_from_unknowns`, branch points).
    flight_gap_stops : str
        The stop nearest each flight (whose clearance is ``flight_gap_min``): ``"U"``,
        ``"L"`` or an extra stop's name, length p ("" when contact was not checked); the
        stop a grazing point grazes.
    stick_times : ndarray, shape (p,)
        Duration of the sticking phase after impact k (a lowercase letter of `pattern`:
        the impact is plastic and the stop holds its coordinate until the release), 0.0
        where there is none. ``flight_times[k]`` is then the flight after the release, and
        ``sum(stick_times) + sum(flight_times)`` is the period.
    release_states : ndarray, shape (p, 2n)
        The state at the release that ends the sticking phase after impact k (NaN rows
        where there is none).
    pressing_min : ndarray, shape (p,)
        The smallest pressing force inside the sticking phase after impact k, over its
        start and the interior minima (the release at its end, where it is 0, not
        counted; :meth:`impactcont.orbit.held_flow.HeldFlow.pressing_minimum`); ``> 0``
        physical; NaN where there is none (or where the stick time is not positive).
    landing_pressing : ndarray, shape (p,)
        The pressing force right after the plastic impact k that starts a sticking phase
        (the onset test: ``> 0`` where the arrival acceleration points into the stop);
        NaN where no sticking phase follows impact k.
    chatters : tuple of Chatter
        The complete chatter before each sticking phase entered through one (a stop with
        restitution above 0): its resolved bounces and its accumulation point
        (:class:`impactcont.orbit.sticky.Chatter`); empty without one.
    """

    oscillator: ImpactOscillator
    N: int
    p: int
    phases: np.ndarray
    flight_times: np.ndarray
    states: np.ndarray
    impact_velocities: np.ndarray
    flight_gap_min: np.ndarray
    flight_gap_min_times: np.ndarray
    jacobians: np.ndarray
    G: np.ndarray
    multipliers: np.ndarray
    physical: bool
    reason: str
    residual: float
    pattern: str = ""
    flight_gap_lower: np.ndarray | None = None
    condition_number: float = math.nan
    error_estimate: float = math.nan
    flight_gap_stops: str = ""
    stick_times: np.ndarray | None = None
    release_states: np.ndarray | None = None
    pressing_min: np.ndarray | None = None
    landing_pressing: np.ndarray | None = None
    chatters: tuple[Any, ...] = ()

    def __post_init__(self) -> None:
        """A motion without sticking phases reports none (zeros and NaN)."""
        if self.stick_times is None:
            object.__setattr__(self, "stick_times", np.zeros(self.p))
        if self.release_states is None:
            object.__setattr__(self, "release_states", _nans((self.p, np.shape(self.states)[1])))
        if self.pressing_min is None:
            object.__setattr__(self, "pressing_min", _nans(self.p))
        if self.landing_pressing is None:
            object.__setattr__(self, "landing_pressing", _nans(self.p))

    # -- the scalar view shared with PeriodicOrbit (detection and datasets use it) ------------
    @property
    def delta(self) -> float:
        """Forcing phase at impact 0."""
        return float(self.phases[0])

    @property
    def state(self) -> np.ndarray:
        """State right after impact 0, shape (2n,)."""
        return self.states[0]

    @property
    def period(self) -> float:
        """``2 pi N / omega``."""
        return TWO_PI * self.N / self.oscillator.omega

    @property
    def impact_velocity(self) -> float:
        """Smallest impact velocity over the p impacts (the ZV test function)."""
        return float(np.min(self.impact_velocities))

    @property
    def gap_min(self) -> float:
        """Smallest clearance over the p flights, interior extrema and ends (the GR test
        function)."""
        return float(np.min(self.flight_gap_min))

    @property
    def spectral_radius(self) -> float:
        """Largest modulus ``rho(G)`` of the multipliers of the product G of the p maps."""
        return float(np.max(np.abs(self.multipliers)))

    @property
    def stable(self) -> bool:
        """Theorem 3.1 on the product G of the p impact maps: ``rho(G) < 1``."""
        return bool(self.spectral_radius < 1.0)

    @property
    def unknowns(self) -> np.ndarray:
        """The shooting unknowns ``u = [delta, tau_0..tau_{p-2}, z_0..z_{p-1}]``, (2np,);
        with sticking phases ``[delta, tau_0..tau_{p-2}, s_k.., z_0..z_{p-1}]`` (the stick
        times in the order of their impacts,
        :func:`impactcont.orbit.sticky.sticky_shooting`)."""
        impacts, sticks = sticking_pattern(self.oscillator, self.pattern or UPPER * self.p)
        pivots = stop_geometry(self.oscillator, impacts).pivots
        return np.concatenate([[self.delta], self.flight_times[:-1],
                               np.asarray(self.stick_times)[sticks],
                               _section_unknowns(self.states, pivots)])

    @property
    def gap_lower(self) -> float:
        """Smallest lower-stop clearance ``x_j + b_low`` over the p flights (+inf: none)."""
        if self.flight_gap_lower is None:
            return math.inf
        return float(np.min(self.flight_gap_lower))

    def time_series(self, num: int = 200) -> tuple[np.ndarray, np.ndarray]:
        """Exact state over one period of the motion (for plots).

        Parameters
        ----------
        num : int
            Samples per flight (``>= 2``), both ends included.

        Returns
        -------
        t : ndarray, shape ((p + q + c)*num,)
            Time since impact 0 (q sticking phases and the c resolved bounces of their
            chatters, each sampled as a flight is).
        X : ndarray, shape ((p + q + c)*num, 2n)
            State; each flight starts at its post-impact state (at the release after a
            sticking phase). A sticking phase entered through complete chatter
            (:attr:`chatters`) is drawn as its resolved bounces, each from its impact's
            state, then held from the accumulation point to the release (the jumped rest
            of the chatter, below the last bounce's apex, is not sampled).
        """
        if isinstance(num, bool) or not isinstance(num, (int, np.integer)) or num < 2:
            raise ParameterError(f"num must be an integer >= 2; got {num!r}")
        flow = Flow(self.oscillator)
        ts, Xs, start = [], [], 0.0
        impacts = sticking_pattern(self.oscillator, self.pattern or UPPER * self.p)[0]
        omega = self.oscillator.omega
        chatters = {c.impact: c for c in self.chatters}
        for k in range(self.p):
            X0, theta = self.states[k], self.phases[k]
            stick = float(self.stick_times[k])
            if stick > 0.0:  # held on the stop, then the flight from the release
                held = held_flow(self.oscillator, impacts[k])
                chatter = chatters.get(k)
                held_start, hold = start, stick
                if chatter is not None:  # the bounces, then held from the accumulation
                    bounce = start
                    for Y, th, t in zip(chatter.starts, chatter.phases, chatter.times,
                                        strict=True):
                        tau = np.linspace(0.0, t, num)
                        ts.append(bounce + tau)
                        Xs.append(flow.state(tau, Y, th))
                        bounce += t
                    X0, theta = chatter.accumulation, chatter.accumulation_phase
                    held_start, hold = start + chatter.duration, stick - chatter.duration
                s = np.linspace(0.0, hold, num)
                ts.append(held_start + s)
                Xs.append(held.state(s, X0, theta))
                theta = float(self.phases[k])
                start += stick
                X0, theta = self.release_states[k], theta + omega * stick
            tau = np.linspace(0.0, self.flight_times[k], num)
            ts.append(start + tau)
            Xs.append(flow.state(tau, X0, theta))
            start += self.flight_times[k]
        return np.concatenate(ts), np.vstack(Xs)

    def __repr__(self) -> str:
        v = ", ".join(f"{x:.6g}" for x in self.impact_velocities)
        return (f"MultiImpactOrbit(N={self.N}, p={self.p}, pattern={self.pattern!r}, "
                f"delta={self.delta:.12g}, "
                f"impact_velocities=[{v}], gap_min={self.gap_min:.6g}, "
                f"rho={self.spectral_radius:.6g}, stable={self.stable}, "
                f"physical={self.physical})")


# ------------------------------------------------------------------------------------------
# The shooting system
# ------------------------------------------------------------------------------------------
@dataclasses.dataclass(frozen=True, eq=False)
class Shooting:
    """The shooting system of an N-p motion evaluated at one ``u``.

    Attributes
    ----------
    phases : ndarray, shape (p,)
        ``theta_k`` (not wrapped).
    flight_times : ndarray, shape (p,)
        ``tau_k``.
    starts : ndarray, shape (p, 2n)
        ``X_k = [b, z_k]``.
    arrivals : ndarray, shape (p, 2n)
        ``X_k^-``, state just before the impact that ends flight k.
    arrival_rates : ndarray, shape (p, 2n)
        ``X'(tau_k^-)``.
    transitions : ndarray, shape (p, 2n, 2n)
        ``U W(tau_k) U^-1``.
    phase_columns : ndarray, shape (p, 2n)
        ``U E(tau_k) [-sin theta_k; cos theta_k]`` (``dX^-/dtheta_k``).
    residual : ndarray, shape (2np,)
        ``[r_0, .., r_{p-1}]``, ``r_k = D X_k^- - X_{k+1}``.
    jacobian : ndarray, shape (2np, 2np) or None
        ``dr/du``, exact.
    """

    phases: np.ndarray
    flight_times: np.ndarray
    starts: np.ndarray
    arrivals: np.ndarray
    arrival_rates: np.ndarray
    transitions: np.ndarray
    phase_columns: np.ndarray
    residual: np.ndarray
    jacobian: np.ndarray | None


def split_unknowns(u: np.ndarray, n: int, p: int, period: float, b: float | np.ndarray,
                   index: int = 0, *, normals: np.ndarray | None = None
                   ) -> tuple[float, np.ndarray, np.ndarray]:
    """``delta``, the p flight times and the p post-impact states ``X_k`` from ``u``.

    ``b`` is the stop position (one for every impact, or one per impact, shape
    (p,)), ``index`` the 0-based index ``j`` of the position eliminated on the sections
    and ``normals`` (shape (n,) or (p, n)) the normal of the stop coordinate of each
    impact (``e_j`` by default): ``x_j = (c_k - sum_{i != j} n_i x_i) / n_j``.
    """
    u = np.asarray(u, dtype=float)
    if u.shape != (2 * n * p,):
        raise ParameterError(f"u must have shape ({2 * n * p},) = (2 n p,) for n={n}, p={p}; "
                             f"got shape {u.shape}")
    taus = np.empty(p)
    taus[:-1] = u[1:p]
    taus[-1] = period - np.sum(u[1:p])
    starts = np.empty((p, 2 * n))
    rest = np.delete(np.arange(2 * n), index)
    starts[:, rest] = u[p:].reshape(p, 2 * n - 1)
    if normals is None:
        starts[:, index] = b
    else:
        nrm = np.broadcast_to(np.asarray(normals, dtype=float), (p, n))
        others = np.einsum("ki,ki->k", np.delete(nrm, index, axis=1),
                           np.delete(starts[:, :n], index, axis=1))
        starts[:, index] = (np.broadcast_to(b, (p,)) - others) / nrm[:, index]
    return float(u[0]), taus, starts


def shooting(flow: Flow, N: int, p: int, u: np.ndarray, *, jacobian: bool = True,
             pattern: str | None = None) -> Shooting:
    """Residual (and exact Jacobian) of the N-p shooting system at ``u``.

    Parameters
    ----------
    flow : Flow
        Flow of the oscillator (gives omega, the stops and their restitutions).
    N, p : int
        Forcing periods and impacts of the motion.
    u : ndarray, shape (2np,)
        ``[delta, tau_0..tau_{p-2}, z_0..z_{p-1}]``.
    jacobian : bool
        Also build ``dr/du``.
    pattern : str, optional
        The stop of each impact (``"U"``/``"L"``); all ``"U"`` by default.

    Returns
    -------
    Shooting
    """
    _, geo, x = _system_input(flow, p, pattern, u, "u")
    out = _kernel().shooting_system(flow.flight_arrays(), tuple(flow.forcing_arrays()),
                                    tuple(impact_sequence(geo)), TWO_PI * N / flow.osc.omega,
                                    x, jacobian)
    return _as_shooting(ShotFlights._make(out), jacobian)


def _system_input(flow: Flow, p: int, pattern: str | None, u: Any, argument: str
                  ) -> tuple[str, StopGeometry, np.ndarray]:
    """The checked impact pattern, its stop geometry and the unknowns `u` as the kernel
    takes them (:func:`_writable`), for :func:`shooting` and :func:`newton`.

    Raises
    ------
    ParameterError
        `pattern` as :func:`~impactcont.orbit.stop_geometry.check_pattern` refuses it, or
        `u` not of shape (2np,) (the message names `argument`).
    """
    osc = flow.osc
    pattern = check_pattern(pattern, p, osc.stops)
    x = np.asarray(u, dtype=float)
    if x.shape != (2 * osc.n * p,):
        raise ParameterError(f"{argument} must have shape ({2 * osc.n * p},) = (2 n p,) for "
                             f"n={osc.n}, p={p}; got shape {x.shape}")
    return pattern, _geometry(flow, pattern), _writable(x)


def _kernel() -> Any:
    """:mod:`impactcont.kernel.shooting`, imported on first use (numba is not imported
    with :mod:`impactcont`) and kept (:data:`_KERNEL`: a solve asks for it several times)."""
    if not _KERNEL:
        from impactcont.kernel import shooting as shooting_kernel

        _KERNEL.append(shooting_kernel)
    return _KERNEL[0]


#: :func:`_kernel`'s module once imported.
_KERNEL: list[Any] = []


def _writable(a: np.ndarray) -> np.ndarray:
    """``a`` as a writable, contiguous float array (the kernel's argument types: one compile)."""
    if type(a) is np.ndarray and (a.dtype is _FLOAT64 or a.dtype == _FLOAT64):
        flags = a.flags
        if flags.c_contiguous and flags.writeable:
            return a
    return np.array(a, dtype=float, order="C")


#: The native float64 dtype (most arrays' own is this very object, :func:`_writable` tests
#: that first; the kernel's are equal to it).
_FLOAT64 = np.dtype(np.float64)


def _section_unknowns(states: np.ndarray, pivots: np.ndarray) -> np.ndarray:
    """``z_0..z_{p-1}`` flattened: each ``X_k`` without its pivot ``x_{j_k}`` (row by row,
    as ``np.delete`` of each would give them)."""
    states = np.asarray(states)
    kept = np.arange(states.shape[1]) != np.asarray(pivots)[:, None]
    return states[kept]


def _readonly(a: np.ndarray) -> np.ndarray:
    """A read-only view of `a`: the kernel's argument type for the stop geometry whatever
    the geometry's own flags (a geometry unpickled in a process pool has writable arrays,
    which numba would compile the shooting path for a second time)."""
    view = a.view()
    view.flags.writeable = False
    return view


def impact_sequence(geo: StopGeometry) -> ImpactSequence:
    """The impacts of `geo` as the shooting kernel takes them (built once per geometry)."""
    seq = _SEQUENCES.get(geo)
    if seq is None:
        seq = _SEQUENCES[geo] = ImpactSequence(
            pivots=_readonly(geo.pivots), normals=_readonly(geo.normals),
            signs=_readonly(geo.signs), positions=_readonly(geo.positions),
            matrices=_readonly(geo.matrices))
    return seq


def contact_stops(geo: StopGeometry) -> ContactStops:
    """The stops of the contact check of eq. (16) in `geo`, as the kernel takes them (built
    once per geometry)."""
    stops = _STOPS.get(geo)
    if stops is None:
        stops = _STOPS[geo] = ContactStops(
            normal=_readonly(geo.normal), two_sided=geo.two_sided, b=geo.b, b_low=geo.b_low,
            extra_normals=_readonly(geo.extra_normals), extra_signs=_readonly(geo.extra_signs),
            extra_positions=_readonly(geo.extra_positions))
    return stops


#: :func:`impact_sequence` and :func:`contact_stops` of each live stop geometry.
_SEQUENCES: weakref.WeakKeyDictionary[StopGeometry, ImpactSequence] = \
    weakref.WeakKeyDictionary()
_STOPS: weakref.WeakKeyDictionary[StopGeometry, ContactStops] = weakref.WeakKeyDictionary()

#: The Jacobian field of a :class:`ShotFlights` that has none (its type fixed: one compile).
_NO_JACOBIAN = np.zeros((0, 0))


def shot_flights(sh: Shooting) -> ShotFlights:
    """`sh` as the kernel takes it: contiguous writable float arrays, the Jacobian (0, 0)
    when it has none."""
    return ShotFlights(
        phases=_writable(sh.phases), flight_times=_writable(sh.flight_times),
        starts=_writable(sh.starts), arrivals=_writable(sh.arrivals),
        arrival_rates=_writable(sh.arrival_rates), transitions=_writable(sh.transitions),
        phase_columns=_writable(sh.phase_columns), residual=_writable(sh.residual),
        jacobian=_NO_JACOBIAN if sh.jacobian is None else _writable(sh.jacobian))


def checked_flights(sh: Shooting) -> CheckedFlights:
    """The fields of `sh` :func:`~impactcont.kernel.shooting.motion_checks` reads, as
    :func:`shot_flights` makes them."""
    return CheckedFlights(
        phases=_writable(sh.phases), flight_times=_writable(sh.flight_times),
        starts=_writable(sh.starts), transitions=_writable(sh.transitions),
        phase_columns=_writable(sh.phase_columns), arrival_rates=_writable(sh.arrival_rates))


def _geometry(flow: Flow, pattern: str) -> StopGeometry:
    """:func:`stop_geometry` of the flow's oscillator, kept on the flow per pattern."""
    cache = flow.__dict__.setdefault("_stop_geometry", {})
    geometry = cache.get(pattern)
    if geometry is None:
        geometry = cache[pattern] = stop_geometry(flow.osc, pattern)
    return geometry


def _coordinate(normal: np.ndarray) -> str:
    """The stop coordinate ``n . x`` in words: ``x2``, ``x1 - x2``, ``2 x1 + x3``."""
    terms = []
    for i, c in enumerate(normal):
        if c == 0.0:
            continue
        size = "" if abs(c) == 1.0 else f"{abs(c):g} "
        sign = ("-" if c < 0 else "+") if terms else ("-" if c < 0 else "")
        terms.append(f"{sign} {size}x{i + 1}".strip() if terms else f"{sign}{size}x{i + 1}")
    return " ".join(terms)


def _as_shooting(out: ShotFlights, jacobian: bool) -> Shooting:
    """:class:`Shooting` from :func:`shooting_kernel.shooting_system`'s record (without the
    frozen dataclass's ``__init__``, one ``object.__setattr__`` per field: a few
    microseconds of every solve and branch point, as :func:`_motion`)."""
    sh = object.__new__(Shooting)
    sh.__dict__.update(phases=out.phases, flight_times=out.flight_times, starts=out.starts,
                       arrivals=out.arrivals, arrival_rates=out.arrival_rates,
                       transitions=out.transitions, phase_columns=out.phase_columns,
                       residual=out.residual, jacobian=out.jacobian if jacobian else None)
    return sh


def flight_jacobian(transition: np.ndarray, phase_column: np.ndarray, rate: np.ndarray,
                    d: np.ndarray, index: int, omega: float, *,
                    normal: np.ndarray | None = None, start_normal: np.ndarray | None = None
                    ) -> tuple[np.ndarray, float]:
    """Jacobian ``G_k`` of one flight and the impact ending it, eq. (22)-(25) on ``n . x = c``.

    The flight starts on the section ``n0 . x = c0`` (`start_normal`; coordinates ``z``:
    ``X`` without ``x_j``, and ``x_j`` from the section) and ends when ``n . x(tau) = c``
    (`normal`), so ``dtau = -(n . dx^-) / (n . x'(tau^-))``; with ``D`` the impact matrix
    of that stop the post-impact state moves by ``D (Phi dX + E' dtheta + X' dtau)``. In
    the section coordinates ``[z, theta]`` this is eq. (25) with row and column ``j`` in
    place of 0 (``n = n0 = e_j``, the stop on mass j).

    Parameters
    ----------
    transition : ndarray, shape (2n, 2n)
        ``Phi = U W(tau) U^-1`` of the flight.
    phase_column : ndarray, shape (2n,)
        ``U E(tau) [-sin theta; cos theta]`` (``dX^-/dtheta``).
    rate : ndarray, shape (2n,)
        ``X'(tau^-)``.
    d : ndarray, shape (2n,) or (2n, 2n)
        Impact matrix ``D`` of the stop that ends the flight, or its diagonal.
    index : int
        0-based index ``j`` of the position eliminated on the sections.
    omega : float
        Forcing frequency.
    normal, start_normal : ndarray, shape (n,), optional
        Normals of the stop coordinates at the end and the start of the flight;
        ``e_j`` by default (`start_normal` defaults to `normal`).

    Returns
    -------
    G : ndarray, shape (2n, 2n)
    h2 : float
        ``n . x'(tau^-)``, the signed arrival velocity (the pole of G at 0).
    """
    m = rate.size
    n = m // 2
    D = np.diag(d) if np.ndim(d) == 1 else np.asarray(d, dtype=float)
    if normal is None:
        normal = np.zeros(n)
        normal[index] = 1.0
    normal = np.asarray(normal, dtype=float)
    start = normal if start_normal is None else np.asarray(start_normal, dtype=float)
    rest = np.delete(np.arange(m), index)
    L = np.eye(m)[:, rest]  # dX/dz on the start section
    L[index, :] = np.concatenate([-start / start[index], np.zeros(n)])[rest]
    B = np.column_stack([transition @ L, phase_column])
    h = normal @ B[:n]
    h2 = float(normal @ rate[:n])
    DB = D @ (B - np.outer(rate, h) / h2)
    G = np.empty((m, m))
    G[:-1] = DB[rest]
    G[-1, :-1] = -omega * h[:-1] / h2
    G[-1, -1] = 1.0 - omega * h[-1] / h2
    return G, h2


def omega_partial(flow: Flow, t: float, X0: np.ndarray, theta: float) -> np.ndarray:
    """``dX(t)/d omega`` at fixed ``t``, start state ``X0`` and start phase ``theta``.

    Only the forced part of eq. (9) depends on omega; the flow gives it exactly
    (:meth:`impactcont.orbit.flow.Flow.omega_partial`, modal or first-order).

    Returns
    -------
    ndarray, shape (2n,)
    """
    return flow.omega_partial(t, X0, theta)


def omega_partials(flow: Flow, sh: Shooting) -> np.ndarray:
    """:func:`omega_partial` of every flight of a shooting system at once (compiled).

    Parameters
    ----------
    flow : Flow
    sh : Shooting
        :func:`shooting` of this flow (its flight times, starts, phases and transitions).

    Returns
    -------
    ndarray, shape (p, 2n)
        ``dX_k^-/d omega`` at fixed ``tau_k``, ``X_k`` and ``theta_k``.
    """
    return _kernel().omega_partials(tuple(flow.shooting_arrays()), tuple(flow.forcing_arrays()),
                                    tuple(flow.omega_arrays()), tuple(shot_flights(sh)))


# ------------------------------------------------------------------------------------------
# Guesses, Newton, the orbit
# ------------------------------------------------------------------------------------------
_SIMULATION_FIELDS = ("impact_times", "impact_phases", "impact_states", "impact_stops")
"""What a simulation guess must carry (:class:`impactcont.simulate.SimulationResult`; the
orbit code does not import the simulator, its independent witness)."""


def _guess_arrays(guess: Any, osc: ImpactOscillator, N: int, p: int
                  ) -> tuple[float, np.ndarray, np.ndarray, str | None, np.ndarray]:
    """``(delta, flight_times (p,), states (p, 2n), pattern, stick_times (p,))`` from any
    kind of guess.

    ``pattern`` is the guess's own impact sequence (None for a mapping without one),
    lowercase where a sticking phase follows the impact; ``stick_times`` their durations
    (0 where none), ``flight_times`` then the flights from the releases.
    """
    n = osc.n
    if isinstance(guess, (MultiImpactOrbit, PeriodicOrbit)):
        gp = guess.p if isinstance(guess, MultiImpactOrbit) else 1
        if isinstance(guess, MultiImpactOrbit):
            taus, states, delta = guess.flight_times, guess.states, guess.delta
            gpat = guess.pattern or UPPER * gp
            sticks = np.array(guess.stick_times, float)
        else:
            taus, states, delta = np.array([guess.period]), guess.state[None, :], guess.delta
            gpat = UPPER
            sticks = np.zeros(1)
        if guess.oscillator.n != n:
            raise ParameterError(f"guess has n={guess.oscillator.n} degrees of freedom; the "
                                 f"oscillator has n={n}")
        if gp == p and guess.N == N:
            return delta, np.array(taus, float), np.array(states, float), gpat, sticks
        reps, rem = divmod(p, gp)
        if rem == 0 and reps * guess.N == N:  # the guess repeated: e.g. a doubled N-1 orbit
            return (delta, np.tile(taus, reps), np.tile(states, (reps, 1)), gpat * reps,
                    np.tile(sticks, reps))
        raise ParameterError(f"guess is an {guess.N}-{gp} motion; it can seed an N-p motion "
                             f"with p a multiple k*{gp} and N = k*{guess.N}; got N={N}, p={p}")
    if all(hasattr(guess, name) for name in _SIMULATION_FIELDS):  # a SimulationResult
        k = guess.impact_times.size
        if k < p + 1:
            raise ParameterError(f"guess: the simulation has {k} impacts; at least p+1={p + 1} "
                                 "are needed to seed an N-p motion")
        kept, landings = landing_impacts(guess)
        if kept.size < p + 1:
            raise ParameterError(f"guess: the simulation has {kept.size} impacts besides the "
                                 f"chatter's; at least p+1={p + 1} are needed to seed an N-p "
                                 "motion")
        kept = kept[-(p + 1):]
        all_times = np.asarray(guess.impact_times, dtype=float)
        times = all_times[kept]
        _check_sticking_phases(guess, times[0], times[-1])
        stops = guess.impact_stops or UPPER * k
        spat = "".join(stops[i] for i in kept[:-1])
        taus, sticks, letters = np.diff(times), np.zeros(p), list(spat)
        for i in range(p):
            phase = landings.get(int(kept[i]))
            if phase is not None and phase.end <= times[i + 1]:
                sticks[i] = phase.end - times[i]
                taus[i] = times[i + 1] - phase.end
                letters[i] = spat[i].lower()
        return (float(np.asarray(guess.impact_phases)[kept[0]]), taus,
                np.array(np.asarray(guess.impact_states)[kept[:-1]], float), "".join(letters),
                sticks)
    if isinstance(guess, Mapping):
        try:
            delta = float(guess["delta"])
            taus = np.array(guess["flight_times"], dtype=float).reshape(-1)
            states = np.array(guess["states"], dtype=float)
            sticks = np.array(guess.get("stick_times", np.zeros(p)), dtype=float).reshape(-1)
        except KeyError as exc:
            raise ParameterError(f"guess mapping needs keys 'delta', 'flight_times', 'states'; "
                                 f"missing {exc}") from None
        if taus.shape != (p,) or states.shape != (p, 2 * n) or sticks.shape != (p,):
            raise ParameterError(f"guess: flight_times must have shape ({p},) and states "
                                 f"({p}, {2 * n}) (stick_times, if given, ({p},)); got "
                                 f"{taus.shape} and {states.shape} (stick_times "
                                 f"{sticks.shape})")
        return delta, taus, states, guess.get("pattern"), sticks
    raise TypeError(f"guess must be a MultiImpactOrbit, a PeriodicOrbit, a SimulationResult or "
                    f"a mapping with 'delta', 'flight_times', 'states'; got "
                    f"{type(guess).__name__}")


def _check_sticking_phases(res: Any, first: float, last: float) -> None:
    """Refuse a simulation guess whose motion between its impacts at `first` and `last`
    has a sticking phase a periodic motion's segment cannot hold: one holding several stops
    at once, or one ended otherwise than by its release (another stop hit or held while it
    holds). A periodic motion's sticking phase holds one stop from the impact on it to the
    release (a lowercase letter of the pattern)."""
    tol = 1e-9 * max(1.0, abs(last))
    for phase in getattr(res, "sticking", ()):
        if not first - tol <= phase.start < last:
            continue
        if len(phase.stops) > 1 or phase.ended_by != "release":
            why = (f"holds the stops {phase.stops!r} at once" if len(phase.stops) > 1 else
                   f"on stop {phase.stops!r} ends by {phase.ended_by!r}, not by its release")
            raise ParameterError(
                f"guess: the simulated motion's sticking phase at t = {phase.start:.10g}"
                f"..{phase.end:.10g} {why}; the periodic motions solved here hold one stop "
                "at a time, from the impact on it to the release (the simulator holds "
                "several), so this motion is not solved: take a guess where each sticking "
                "phase holds one stop")


def landing_impacts(res: Any) -> tuple[np.ndarray, dict[int, Any]]:
    """The impacts of a simulation that are not inside a chatter, and the sticking phase
    (ended by a release) that follows each landing impact.

    Parameters
    ----------
    res : SimulationResult
        Or any record with its ``impact_times``, ``impact_stops`` and ``sticking``.

    Returns
    -------
    kept : ndarray of int
        The indices of the impacts kept: every impact but a chatter's after its landing
        (a chatter still going on at the end of the run included).
    landings : dict
        The sticking phase that follows each kept landing impact, by its index.

    A sticking phase starts at its landing impact (a plastic stop) or at the accumulation
    point of the chatter the landing starts (restitution above 0): the landing is then the
    first of the impacts on that stop since the last impact on another stop or the last
    release; the chatter's later impacts are part of the segment (the chatter map of
    :func:`impactcont.kernel.shooting._chatter_map` resolves them) and are left out.
    """
    times = np.asarray(res.impact_times, dtype=float)
    count = times.size
    stops = res.impact_stops or UPPER * count
    dropped = np.zeros(count, dtype=bool)
    landings: dict[int, Any] = {}
    chattering: set[str] = set()
    ends = sorted(ph.end for ph in getattr(res, "sticking", ()))
    # where a chatter's impacts accumulated (the simulator's record): a stick that starts
    # there was entered through chatter, however close its last resolved impact (with a
    # small R the accumulation point lies within rounding of it: R = 1e-3, 3e-9 after it)
    accumulations = np.array([c.time for c in getattr(res, "chatter", ())], dtype=float)
    for phase in getattr(res, "sticking", ()):
        if phase.ended_by != "release":
            continue
        tol = 1e-9 * max(1.0, abs(phase.start))
        last = int(np.searchsorted(times, phase.start + tol, side="right")) - 1
        if last < 0 or stops[last] != phase.stops:
            continue
        before = [e for e in ends if e < times[last] - tol]
        boundary = before[-1] if before else -math.inf
        first = last
        if phase.start - times[last] > tol or np.any(np.abs(accumulations - phase.start)
                                                     <= tol):  # back to its landing
            while (first > 0 and stops[first - 1] == phase.stops
                   and times[first - 1] > boundary):
                first -= 1
        dropped[first + 1:last + 1] = True
        landings[first] = phase
        if first < last:
            chattering.add(phase.stops)
    # a chatter still going on at the end of the run: its landing ends the last segment
    last = count - 1
    if last > 0 and stops[last] in chattering:
        before = [e for e in ends if e < times[last]]
        boundary = before[-1] if before else -math.inf
        first = last
        while first > 0 and stops[first - 1] == stops[last] and times[first - 1] > boundary:
            first -= 1
        dropped[first + 1:] = True
    return np.flatnonzero(~dropped), landings


def initial_unknowns(guess: Any, osc: ImpactOscillator, N: int, p: int) -> np.ndarray:
    """Shooting unknowns ``u`` (2np,) seeded by ``guess`` (see :func:`multi_impact_orbit`)."""
    return _seed(guess, osc, N, p, None)[0]


def _seed(guess: Any, osc: ImpactOscillator, N: int, p: int, pattern: str | None
          ) -> tuple[np.ndarray, str]:
    """Unknowns and impact sequence from ``guess``; `pattern` (if given) must match it."""
    N = _check_N(N)
    p = check_impacts(p)
    if pattern is not None:
        pattern = check_pattern(pattern, p, osc.stops, sticking=True)
    delta, taus, states, gpat, sticks = _guess_arrays(guess, osc, N, p)
    if not (math.isfinite(delta) and _all_finite(taus) and _all_finite(states)
            and _all_finite(sticks)):
        raise ParameterError("guess must hold finite phases, flight times, stick times and "
                             "states")
    if gpat is not None:
        gpat = _checked_pattern(osc, gpat, p)
        if pattern is not None and gpat != pattern:
            raise ParameterError(f"pattern={pattern!r} differs from the guess's impact sequence "
                                 f"{gpat!r}; give pattern={gpat!r}, or a guess with the "
                                 "wanted sequence")
        pattern = gpat
    if pattern is None:
        pattern = UPPER * p
    impacts, held = sticking_pattern(osc, pattern)
    pivots = stop_geometry(osc, impacts).pivots
    return np.concatenate([[delta], taus[:-1], sticks[held],
                           _section_unknowns(states, pivots)]), pattern


def _checked_pattern(osc: ImpactOscillator, pattern: str, p: int) -> str:
    """``check_pattern(pattern, p, osc.stops, sticking=True)``, kept on the oscillator's flow
    when it has one (a pure function of the pattern and the stops: a guess solved again at
    one oscillator checks its pattern once)."""
    flow = osc.__dict__.get("_flow")
    if flow is None:
        return check_pattern(pattern, p, osc.stops, sticking=True)
    known = flow.__dict__.setdefault("_checked_patterns", {})
    checked = known.get((pattern, p))
    if checked is None:
        checked = known[(pattern, p)] = check_pattern(pattern, p, osc.stops, sticking=True)
    return checked


def _all_finite(a: np.ndarray) -> bool:
    """Every entry of the float array `a` finite: its sum is finite (a NaN or an infinity
    makes it not), else, the sum having perhaps overflowed, each entry is checked. The sum
    and the maxima below are the ufuncs' reductions themselves (``a.sum()`` and ``a.max()``
    call them through a Python layer)."""
    return math.isfinite(np.add.reduce(a, axis=None)) or bool(np.all(np.isfinite(a)))


def unknowns_scale(u: np.ndarray) -> float:
    """The size ``max(1, |delta|, |tau|, |z|)`` of the unknowns that Newton's tolerance is
    relative to, with the phase counted at most pi (the residual is 2 pi periodic in it):
    a phase that ran off to 1e14 would otherwise loosen the test until a residual of
    order 1 passed (a bouncing ball at Gamma = 1.06 from a poor guess did).
    """
    u = np.asarray(u, dtype=float)
    return max(1.0, min(abs(float(u[0])), math.pi),
               float(np.maximum.reduce(np.abs(u[1:]), axis=None, initial=0.0)))


def shooting_accuracy(jacobian: np.ndarray, residual: np.ndarray, u: np.ndarray
                      ) -> tuple[float, float]:
    """Condition number of the shooting Jacobian and the error it allows in ``u``.

    A solution ``u`` of the shooting system with residual ``r`` is off the exact one by
    about the Newton correction it still lacks, ``|J^-1 r|``, plus the rounding of the
    flow's evaluation amplified by the inverse Jacobian, ``cond eps max(1, |u|)``
    (``cond = s_max / s_min``, the singular values of ``J``). Both grow like the
    condition number next to a bifurcation point with a multiplier +1 (``|J^-1 r| <=
    cond |r| / |J|``).

    Parameters
    ----------
    jacobian : ndarray, shape (m, m)
    residual : ndarray, shape (m,)
    u : ndarray, shape (m,)

    Returns
    -------
    cond : float
        ``s_max / s_min`` (2-norm; ``inf`` when ``J`` is exactly singular or not finite).
    error : float
        The error estimate above, in the 2-norm of ``u`` (``inf`` likewise).
    """
    if not (_all_finite(jacobian) and _all_finite(residual)):
        return math.inf, math.inf
    s, step = _values_and_step(jacobian, residual)
    if not s[-1] > 0:
        return math.inf, math.inf
    cond = float(s[0] / s[-1])
    if step is None:
        try:
            step = _solve(jacobian, residual)
        except np.linalg.LinAlgError:  # an exact zero pivot where s_min > 0 only by rounding
            return math.inf, math.inf
    correction = math.sqrt(float(step @ step))  # |J^-1 r|, as np.linalg.norm computes it
    return cond, correction + cond * _EPS * max(1.0, float(np.maximum.reduce(np.abs(u),
                                                                             axis=None)))


def _lapack(name: str, signature: str) -> Any:
    """The LAPACK gufunc `name` of numpy's ``linalg`` with its `signature`, or None.

    ``np.linalg.svd`` and ``np.linalg.solve`` call these after checks and inside an
    ``np.errstate`` whose handler raises on a LAPACK failure: several microseconds of
    Python around each call of a solve's accuracy (:func:`shooting_accuracy`).
    :func:`_singular_values` and :func:`_solve` call them directly on float64 input and
    hand any non-finite result to the public function (which raises as it always did).
    None (the public functions then) where numpy names them otherwise.
    """
    from numpy.linalg import _umath_linalg

    gufunc = getattr(_umath_linalg, name, None)
    return gufunc if getattr(gufunc, "signature", None) == signature else None


_SVD_VALUES = _lapack("svd", "(m,n)->(p)")
_SOLVE_VECTOR = _lapack("solve1", "(m,m),(m)->(m)")


def _singular_values(a: np.ndarray) -> np.ndarray:
    """``np.linalg.svd(a, compute_uv=False)`` of a float64 matrix: the same values."""
    if _SVD_VALUES is not None and a.dtype == _FLOAT64 and a.ndim == 2:
        with np.errstate(invalid="ignore"):  # a failure gives NaN: the public call below
            s = _SVD_VALUES(a, signature="d->d")
        if _all_finite(s):
            return s
    return np.linalg.svd(a, compute_uv=False)


def _values_and_step(a: np.ndarray, b: np.ndarray) -> tuple[np.ndarray, np.ndarray | None]:
    """:func:`_singular_values` of `a` and, when it is finite, :func:`_solve`'s ``a^-1 b``
    (else None: the caller takes :func:`_solve`, which raises as it does), both LAPACK
    calls inside one ``np.errstate`` (entering one costs a few microseconds: every solve's
    :func:`shooting_accuracy` makes them). The same values as the two functions give."""
    if (_SVD_VALUES is None or _SOLVE_VECTOR is None or a.dtype != _FLOAT64
            or b.dtype != _FLOAT64 or a.ndim != 2 or b.ndim != 1):
        return _singular_values(a), None
    with np.errstate(all="ignore"):  # a failure gives NaN: the public calls
        s = _SVD_VALUES(a, signature="d->d")
        x = _SOLVE_VECTOR(a, b, signature="dd->d")
    if not _all_finite(s):
        s = np.linalg.svd(a, compute_uv=False)
    return s, (x if _all_finite(x) else None)


def _solve(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """``np.linalg.solve(a, b)`` of a float64 matrix and vector: the same solution (and the
    same ``LinAlgError`` when `a` is singular)."""
    if (_SOLVE_VECTOR is not None and a.dtype == _FLOAT64 and b.dtype == _FLOAT64
            and a.ndim == 2 and b.ndim == 1):
        with np.errstate(all="ignore"):  # singular: NaN, the public call below raises
            x = _SOLVE_VECTOR(a, b, signature="dd->d")
        if _all_finite(x):
            return x
    return np.linalg.solve(a, b)


def _parameters(osc: ImpactOscillator) -> str:
    """``omega=.., b=..`` (and the lower stop) for messages."""
    text = f"omega={osc.omega!r}, b={osc.b!r}"
    return text + (f", b_low={osc.stops.b_low!r}" if osc.stops.two_sided else "")


def _bifurcation(N: int, p: int, osc: ImpactOscillator, cond: float, error: float) -> str:
    """The message of a singular shooting Jacobian: a bifurcation point, not a bad guess."""
    return (f"the N={N}, p={p} shooting Jacobian is singular: a bifurcation point at "
            f"{_parameters(osc)} (condition number {cond:.3g}; a multiplier of G at +1: a "
            "fold, or the symmetry-breaking pitchfork of a symmetric motion), where the motion "
            f"is determined only to about {error:.1g}; solve it at a nearby parameter value, or "
            "follow its branch through the point (multi_impact_continuation)")


def newton(flow: Flow, N: int, p: int, u0: np.ndarray, *, tol: float = 1e-12,
           max_iter: int = 40, pattern: str | None = None) -> tuple[np.ndarray, Shooting, int]:
    """Solve the shooting system by Newton's method with a backtracking line search.

    Converged when the max-norm of the residual is ``<= tol * max(1, |u|_max)`` and
    the last update is ``<= tol * max(1, |u|_max)`` (at least one update is made, so
    a guess that already solves the system is polished to working precision). Once
    the residual is within ``tol``, an update is made only if it lowers the residual;
    otherwise the point is returned as it is: the residual is at its rounding floor,
    and the update is that rounding amplified by the inverse Jacobian (large where the
    Jacobian is nearly singular, next to a bifurcation point; see
    :func:`shooting_accuracy` for the error that remains).

    Raises
    ------
    NoPeriodicMotionError
        No convergence within ``max_iter`` iterations, or a singular Jacobian: then
        the message says whether the point is a bifurcation point (a singular Jacobian
        near a solution) or the guess is not near a motion with this impact pattern.
    """
    pattern, geo, x0 = _system_input(flow, p, pattern, u0, "u0")
    return _newton(flow, N, p, x0, geo, pattern, tol, max_iter)


def _newton(flow: Flow, N: int, p: int, x0: np.ndarray, geo: StopGeometry, pattern: str,
            tol: float, max_iter: int) -> tuple[np.ndarray, Shooting, int]:
    """:func:`newton` from checked input: `x0` as :func:`_writable` gives it, `geo` the stop
    geometry of the checked `pattern`."""
    solved = NewtonResult.from_kernel(_kernel().newton_solve(
        flow.flight_arrays(), tuple(flow.forcing_arrays()),
        tuple(impact_sequence(geo)), TWO_PI * N / flow.osc.omega, x0, float(tol),
        int(max_iter)))
    u, it, norm, step_norm = solved.x, solved.iterations, solved.residual_norm, solved.step_norm
    sh = _as_shooting(solved.shot, True)
    if solved.status == 0:
        return u, sh, int(it)
    scale = unknowns_scale(u)
    cond, error = shooting_accuracy(sh.jacobian, sh.residual, u)
    if norm <= _NEAR_SOLUTION * scale and not cond * _EPS <= _ERROR_WARN:
        raise NoPeriodicMotionError(
            f"{_bifurcation(N, p, flow.osc, cond, error)}; Newton stopped at residual "
            f"{norm:.3g} (last update {step_norm:.3g}) after {it} iterations")
    raise NoPeriodicMotionError(
        f"N={N}, p={p}: Newton did not converge in {it} iterations (residual "
        f"{norm:.3g}, last update {step_norm:.3g}"
        + (", singular Jacobian" if not math.isfinite(cond) else "")
        + f") at {_parameters(flow.osc)}"
        + (f" with the impact pattern {pattern!r} (is the guess an N-p motion with this "
           "sequence of stops? a simulation's impact_stops show the one it settled on)"
           if pattern is not None and LOWER in pattern else ""))


def orbit_from_unknowns(flow: Flow, N: int, p: int, u: np.ndarray,
                        sh: Shooting | None = None, *, checks: bool = True,
                        pattern: str | None = None) -> MultiImpactOrbit:
    """The N-p motion at the solution ``u`` of the shooting system, with G and every check.

    Parameters
    ----------
    flow : Flow
    N, p : int
    u : ndarray, shape (2np,)
        A (converged) solution of :func:`shooting`.
    sh : Shooting, optional
        :func:`shooting` at ``u`` (with the same `pattern`) if already computed.
    checks : bool
        Search every flight for interior contact with either stop (eq. 16). Without
        it (a cheap evaluation of the multipliers, e.g. to locate a PD point)
        ``flight_gap_min`` is NaN and the motion is reported not physical with that
        reason.
    pattern : str, optional
        The stop of each impact (``"U"``/``"L"``); all ``"U"`` by default.

    Returns
    -------
    MultiImpactOrbit
        Per-impact states, phases, velocities, per-flight gaps, ``G_k``, ``G``,
        multipliers and the physical checks.
    """
    pattern = check_pattern(pattern, p, flow.osc.stops)
    if sh is None:
        sh = shooting(flow, N, p, u, jacobian=False, pattern=pattern)
    return _orbit(flow, N, p, sh, checks, pattern)


def _orbit(flow: Flow, N: int, p: int, sh: Shooting, checks: bool, pattern: str,
           condition_number: float = math.nan, error_estimate: float = math.nan,
           sticks: Any = None, *, residual: float | None = None) -> MultiImpactOrbit:
    """:func:`orbit_from_unknowns` from the shooting system at the solution (`pattern`
    validated), with the accuracy of the solution when known (and the max-norm of the
    residual, `residual`, when the caller has it).

    With `sticks` (a motion with sticking phases, `pattern` its impacts' stops) `sh` holds
    the flights from the releases: their contact checks and impact velocities are read from
    it, and the impacts' states and phases, G and the sticking phases' checks from
    `sticks`."""
    osc = flow.osc
    geo = _geometry(flow, pattern)
    if residual is None:
        residual = float(np.maximum.reduce(np.abs(sh.residual), axis=None))
    checked = MotionChecks._make(_kernel().motion_checks(
        tuple(flow.shooting_arrays()), tuple(flow.forcing_arrays()), tuple(impact_sequence(geo)),
        tuple(contact_stops(geo)), tuple(checked_flights(sh)), checks))
    gaps, gap_times = checked.gap_upper, checked.time_upper
    gaps_low, times_low = checked.gap_lower, checked.time_lower
    gaps_x, times_x = checked.gap_extra, checked.time_extra
    if checked.capped:
        warnings.warn(f"{_coordinate(geo.normal)} search grid capped at 2000000 cells on a "
                      f"flight of the N={N}, p={p} motion: a short excursion past a stop "
                      "(eq. 16) may be missed",
                      UnresolvedMotionWarning, stacklevel=2)
    reasons = []
    nearest = [UPPER] * p
    if not checks:
        reasons.append("interior contact not checked")
    taus = sh.flight_times.tolist()
    for k in range(p):
        tau = taus[k]
        if not tau > 0:
            reasons.append(f"flight {k} has duration {tau:.3g} <= 0")
        elif checks:
            for i, s in enumerate((LOWER, *geo.extra_names)):  # the nearest stop's gap, time
                gap, when = (gaps_low[k], times_low[k]) if i == 0 else (gaps_x[k, i - 1],
                                                                        times_x[k, i - 1])
                if gap < gaps[k]:
                    gaps[k], gap_times[k], nearest[k] = gap, when, s
    # the interior extrema's part (eq. 16), a crossing iff <= 0, kept for its reason
    interior, interior_times, interior_stops = gaps.copy(), gap_times.copy(), list(nearest)
    if checks:
        _end_checks(sh, geo, pattern, gaps, gap_times, nearest, reasons)
    # velocity before impact k is the arrival velocity of flight k-1, towards its stop
    velocities = checked.h2[np.arange(-1, p - 1)] * geo.signs
    speeds, inside = velocities.tolist(), interior.tolist()
    for k in range(p):
        if not speeds[k] > 0:
            side = {UPPER: "the upper stop", LOWER: "the lower stop"}.get(
                pattern[k], f"stop {pattern[k]!r}")
            reasons.append(f"impact {k}: velocity {velocities[k]:.3g} <= 0, "
                           f"{_coordinate(geo.normals[k])} does not arrive towards {side}")
        if checks and not inside[k] > 0:
            s = interior_stops[k]
            who = (_coordinate(geo.normal) if s in (UPPER, LOWER)
                   else f"{_coordinate(geo.extra_normals[geo.extra_names.index(s)])}"
                   f" (stop {s!r})")
            reasons.append(f"flight {k}: {who} reaches a stop inside the flight (gap_min="
                           f"{interior[k]:.3g} at t={interior_times[k]:.6g})")
    if sticks is not None:  # the times from the releases
        gap_times = gap_times + sticks.shift
    if sticks is None:
        phases = np.array([math.atan2(math.sin(t), math.cos(t)) for t in sh.phases.tolist()])
        states = sh.starts.copy()
        return _motion(
            oscillator=osc, N=N, p=p, phases=phases, flight_times=sh.flight_times.copy(),
            states=states, impact_velocities=velocities, flight_gap_min=gaps,
            flight_gap_min_times=gap_times, jacobians=checked.jacobians, G=checked.G,
            multipliers=checked.multipliers,
            physical=not reasons, reason="; ".join(reasons),
            residual=residual, pattern=pattern,
            flight_gap_lower=gaps_low, condition_number=condition_number,
            error_estimate=error_estimate, flight_gap_stops="".join(nearest) if checks else "")
    reasons.extend(sticks.reasons)
    return _motion(
        oscillator=osc, N=N, p=p, phases=np.array([_wrap(float(t)) for t in sticks.phases]),
        flight_times=sticks.flight_times.copy(), states=sticks.states.copy(),
        impact_velocities=velocities, flight_gap_min=gaps, flight_gap_min_times=gap_times,
        jacobians=sticks.jacobians, G=sticks.G, multipliers=sticks.multipliers,
        physical=not reasons, reason="; ".join(reasons),
        residual=residual, pattern=sticks.pattern,
        flight_gap_lower=gaps_low, condition_number=condition_number,
        error_estimate=error_estimate, flight_gap_stops="".join(nearest) if checks else "",
        stick_times=sticks.stick_times.copy(), release_states=sticks.release_states,
        pressing_min=sticks.pressing_min, landing_pressing=sticks.landing_pressing,
        chatters=sticks.chatters)


def _motion(**fields: Any) -> MultiImpactOrbit:
    """``MultiImpactOrbit(**fields)`` without the frozen dataclass's ``__init__`` (one
    ``object.__setattr__`` per field: a few microseconds of every solve and branch point):
    its defaults (:data:`_DEFAULTS`), `fields`, then ``__post_init__``. `fields` must name
    every field without a default."""
    orbit = object.__new__(MultiImpactOrbit)
    orbit.__dict__.update(_DEFAULTS, **fields)
    orbit.__post_init__()
    return orbit


#: The defaults of the fields of :class:`MultiImpactOrbit` (:func:`_motion`).
_DEFAULTS = {f.name: f.default for f in dataclasses.fields(MultiImpactOrbit)
             if f.default is not dataclasses.MISSING}


def _end_checks(sh: Shooting, geo: StopGeometry, pattern: str, gaps: np.ndarray,
                gap_times: np.ndarray, nearest: list[str], reasons: list[str]) -> None:
    """Every stop's clearance at both ends of every flight (the impact states), folded into
    the per-flight gaps (`gaps`, `gap_times`, `nearest`, in place) and the reasons.

    :func:`impactcont.kernel.shooting.end_clearances`: the start of flight k against every
    stop but impact k's, its end against every stop but impact ``k + 1``'s. A clearance
    smaller than the flight's interior one becomes its gap, at time 0 or ``tau_k``, so
    that the GR test function ``min_k gap_min_k`` changes sign where a stop coordinate
    reaches its stop exactly at another stop's impact. An impact state past a stop by
    more than the rounding of its clearance (relative to the motion's size there,
    :data:`impactcont.kernel.shooting._END_ULPS`) makes the motion not physical, once per
    impact, naming the coordinate and the stop.
    """
    p = len(pattern)
    end_gap, end_stop, end_tol = _kernel().end_clearances(
        geo.normal, geo.two_sided, geo.b, geo.b_low, geo.normals, geo.signs, geo.extra_normals,
        geo.extra_signs, geo.extra_positions, sh.starts, sh.arrivals)
    names = (UPPER, LOWER, *geo.extra_names)
    crossed: dict[int, tuple[float, int, int, int]] = {}  # impact -> (gap, stop, flight, end)
    taus, end_gaps, end_stops, end_tols = (a.tolist() for a in (sh.flight_times, end_gap,
                                                                  end_stop, end_tol))
    for k in range(p):
        if not taus[k] > 0:
            continue
        for end in (0, 1):
            gap, stop = end_gaps[k][end], end_stops[k][end]
            if stop < 0:
                continue
            if gap < gaps[k]:
                gaps[k] = gap
                gap_times[k] = 0.0 if end == 0 else taus[k]
                nearest[k] = names[stop]
            impact = (k + end) % p
            if gap < -end_tols[k][end] and (impact not in crossed
                                            or gap < crossed[impact][0]):
                crossed[impact] = (gap, stop, k, end)
    for impact in sorted(crossed):
        gap, stop, k, end = crossed[impact]
        normal = geo.normal if stop < 2 else geo.extra_normals[stop - 2]
        where = (f"the end of flight {k}: it meets stop {names[stop]!r} before stop "
                 f"{pattern[impact]!r}" if end == 1 else f"the start of flight {k}")
        reasons.append(f"impact {impact} (stop {pattern[impact]!r}): {_coordinate(normal)} is "
                       f"past stop {names[stop]!r} (clearance {gap:.3g}) at {where}")


#: How :func:`multi_impact_orbit` solves a pattern with sticking phases (one entry,
#: :func:`impactcont.orbit.sticky._sticky_orbit`): set by that module when it is imported,
#: because it imports this one (no import circle, even inside a function:
#: tests/integration/test_import_graph.py).
STICKY_SOLVER: list[Any] = []


def _sticky_solver() -> Any:
    """The solver of motions with sticking phases :data:`STICKY_SOLVER` holds (the package
    :mod:`impactcont.orbit` imports :mod:`impactcont.orbit.sticky`, which sets it)."""
    if not STICKY_SOLVER:
        raise RuntimeError("impactcont.orbit.sticky was not imported: it registers the solver "
                           "of motions with sticking phases (impactcont.orbit imports it)")
    return STICKY_SOLVER[0]


def multi_impact_orbit(osc: ImpactOscillator, N: int, p: int, guess: Any, *,
                       tol: float = 1e-12, max_iter: int = 40,
                       pattern: str | None = None) -> MultiImpactOrbit:
    """The periodic N-p motion (p impacts in N forcing periods) near a guess.

    Parameters
    ----------
    osc : ImpactOscillator
    N : int
        Forcing periods of the motion (``>= 1``).
    p : int
        Impacts per motion (``>= 1``).
    guess : MultiImpactOrbit, PeriodicOrbit, SimulationResult or mapping
        Where Newton starts:

        - an N-p motion (e.g. at a nearby parameter value);
        - an N'-p' motion with ``p = k p'`` and ``N = k N'``, repeated k times
          (a doubled N-1 motion seeds a 2N-2 motion);
        - a simulation: its last p+1 impacts (states, phases, flight times);
        - a mapping ``{"delta": float, "flight_times": (p,), "states": (p, 2n)}``
          (optionally ``"pattern"``).
    tol : float
        Newton tolerance on the residual and the last update (relative to
        ``max(1, |u|)``).
    max_iter : int
        Largest number of Newton iterations.
    pattern : str, optional
        The stop of each impact, ``p`` letters ``"U"`` (upper stop ``x_j = b``) and
        ``"L"`` (lower stop ``x_j = -b_low``), e.g. ``"UL"``; by default the
        guess's own sequence (a simulation records it), else all ``"U"``.

    Returns
    -------
    MultiImpactOrbit
        The motion with its stability and physical checks: a solution that is
        not a physical motion is returned flagged, never dropped.

    Raises
    ------
    ParameterError, TypeError
        Bad ``N``, ``p``, ``guess`` or ``pattern``.
    NoPeriodicMotionError
        Newton does not converge from the guess.

    Examples
    --------
    >>> res = simulate(osc, X0, 0.0, 400.0)          # doctest: +SKIP
    >>> orbit = multi_impact_orbit(osc, 2, 2, res)   # doctest: +SKIP
    """
    N = _check_N(N)
    p = check_impacts(p)
    if not isinstance(osc, ImpactOscillator):
        raise TypeError(f"osc must be an ImpactOscillator; got {type(osc).__name__}")
    known = osc.__dict__.get("_flow")
    if known is None or "_forced" not in known.__dict__:  # checked once per oscillator
        require_forcing(osc, "multi_impact_orbit")
    if isinstance(tol, bool) or not isinstance(tol, (int, float)) or not tol > 0:
        raise ParameterError(f"tol must be a real number > 0; got {tol!r}")
    if isinstance(max_iter, bool) or not isinstance(max_iter, (int, np.integer)) or max_iter < 1:
        raise ParameterError(f"max_iter must be an integer >= 1; got {max_iter!r}")
    flow = flow_of(osc)
    flow.__dict__["_forced"] = True
    u0, pattern = _seed(guess, osc, N, p, pattern)
    if pattern != pattern.upper() and np.any(sticking_pattern(osc, pattern)[1]):
        return _sticky_solver()(flow, N, pattern, u0, tol, max_iter)
    # the pattern is checked (_seed) and has no sticking phase; u0 is new, contiguous floats
    u, sh, iterations = _newton(flow, N, p, u0, _geometry(flow, pattern), pattern, tol,
                                max_iter)
    cond, error = shooting_accuracy(sh.jacobian, sh.residual, u)
    scale = unknowns_scale(u)
    residual = float(np.maximum.reduce(np.abs(sh.residual), axis=None))
    if not error <= _ERROR_WARN * scale:
        if not error <= _SINGULAR * scale:
            warnings.warn(f"{_bifurcation(N, p, osc, cond, error)} (residual {residual:.3g})",
                          IllConditionedWarning, stacklevel=2)
        else:
            warnings.warn(f"the N={N}, p={p} shooting Jacobian is nearly singular, next to a "
                          f"bifurcation point at {_parameters(osc)} (condition number "
                          f"{cond:.3g}, residual {residual:.3g}; a multiplier of G close to "
                          "+1: a fold, or the symmetry-breaking pitchfork of a symmetric "
                          f"motion): the motion may carry an error of about {error:.1g} in its "
                          "phases, flight times and states (the Newton correction |J^-1 r| "
                          "plus condition number x eps |u|)", IllConditionedWarning,
                          stacklevel=2)
    log.debug("N=%d p=%d %s motion in %d Newton iterations", N, p, pattern, iterations)
    return _orbit(flow, N, p, sh, True, pattern, cond, error, residual=residual)


def primitive_orbit(orbit: MultiImpactOrbit, *, tol: float = 1e-8) -> MultiImpactOrbit:
    """The shortest motion whose repetition is ``orbit``.

    An N-p motion can be an N'-p' motion repeated ``k`` times (``N = k N'``,
    ``p = k p'``), e.g. a Newton solve of the 4-2 system seeded near a 2-1 motion.
    The repetition is recognised when the impacts ``j`` and ``j + p'`` have the same
    state, flight time and forcing phase within ``tol``; the shorter motion is then
    re-solved by Newton (its multipliers are the k-th roots' own, not their k-th powers).

    Parameters
    ----------
    orbit : MultiImpactOrbit
    tol : float
        Tolerance (max-norm) of the comparison.

    Returns
    -------
    MultiImpactOrbit
        ``orbit`` itself when it is no repetition.
    """
    for k in range(2, math.gcd(orbit.N, orbit.p) + 1):
        if orbit.N % k or orbit.p % k:
            continue
        q = orbit.p // k
        shifted = np.roll(np.arange(orbit.p), -q)
        dphase = np.remainder(orbit.phases - orbit.phases[shifted] + math.pi, TWO_PI) - math.pi
        pattern = orbit.pattern or UPPER * orbit.p
        if (pattern == pattern[q:] + pattern[:q]
                and np.max(np.abs(orbit.states - orbit.states[shifted])) <= tol
                and np.max(np.abs(orbit.flight_times - orbit.flight_times[shifted])) <= tol
                and np.max(np.abs(orbit.stick_times - orbit.stick_times[shifted])) <= tol
                and np.max(np.abs(dphase)) <= tol):
            guess = {"delta": orbit.delta, "flight_times": orbit.flight_times[:q],
                     "states": orbit.states[:q], "pattern": pattern[:q],
                     "stick_times": orbit.stick_times[:q]}
            short = multi_impact_orbit(orbit.oscillator, orbit.N // k, q, guess)
            return primitive_orbit(short, tol=tol)
    return orbit
