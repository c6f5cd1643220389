"""Periodic motions with sticking phases in closed form, in mpmath (30 digits).

Three machines whose periodic motion with a plastic impact (``R = 0``) and a sticking phase
can be written down from the equation of motion alone, independently of the package (no
``impactcont`` import: this module is the witness of the simulator and of the shooting path).
Between contacts every machine obeys eq. (1) with a static force,

    M x'' + C x' + K x = F cos(theta) + F_static,        theta = omega t + delta,

and each degree of freedom that matters here reduces to the scalar equation

    m y'' + c y' + k y = f cos(theta0 + omega tau) + f0                          (S1)

whose solution from ``(y0, y0')`` at phase ``theta0`` is the forced response plus the free
damped one (:func:`response`). A plastic impact leaves the stop coordinate's speed zero
(eq. 4 with ``R = 0``; at a clearance between masses momentum is conserved); the stop then
holds its coordinate while the contact force presses it, and lets go where that force falls
to zero with a negative slope (the release).

The three cases (every phase in radians, every time in the units of eq. (1)):

(a) :func:`preloaded_motion`: one mass on a spring (``m = k = 1``, ``c = 2 eta``) pushed
    into its upper stop ``x = b = 0`` by ``F_static = f0 > 0`` and forced ``F cos(theta)``.
    Held at ``x = 0`` the stop's pressing force is ``p = F cos(theta) + f0`` (eq. (1) with
    ``x = x' = x'' = 0``); it is released at ``theta_r = arccos(-f0 / F)`` (``sin(theta_r)
    > 0``: ``p`` decreasing), flies from rest at the stop (S1), lands at the first return
    to ``x = 0``, where it is held again (``p > 0`` there). The release phase does not
    depend on the history: the motion is explicit and every multiplier is zero.
(b) :func:`locked_ball_motion`: Luck & Mehta's ball on a table vibrating as
    ``-A cos(theta)`` (J. M. Luck and A. Mehta, Phys. Rev. E 48, 3988 (1993)), with
    ``R = 0``: in the table's frame ``y'' = -g + A omega^2 cos(theta)`` over a lower stop
    ``y = 0``. Locked on the table it is pressed by ``p = g - A omega^2 cos(theta)``, and is
    released where ``cos(theta_r) = 1 / Gamma`` with ``sin(theta_r) < 0``
    (``Gamma = A omega^2 / g``); the flight is a parabola relative to the table's
    oscillation, the landing its first return to ``y = 0``. Explicit, every multiplier zero.
(c) :func:`riding_damper_motion`: the impact damper of ``docs/machines.md`` (a primary of
    mass 1 on a spring 1 with a damper ``c = 2 eta``, forced ``cos(theta)``; a free ball of
    mass ``m`` in the clearance ``|x2 - x1| <= b``) with a plastic ball. Riding a wall the
    ball moves with the primary, ``(1 + m) x1'' + c x1' + x1 = cos(theta)``, and the wall
    presses it with ``p_U = -m x1''`` (upper) or ``p_L = m x1''`` (lower); it is released
    where ``x1'' = 0`` (``x1 = cos(theta) - c x1'`` there), flies across the clearance at
    constant speed while the primary moves on alone (S1 with ``m = 1``), lands plastically
    on the other wall (momentum conserved, ``v = (x1' + m x2') / (1 + m)``), rides it, is
    released, flies back. The release state ``(theta, x1')`` of one ride determines the
    next: the periodic motion is the fixed point of that return map, solved with
    ``mpmath.findroot``; its nonzero multipliers are the eigenvalues of the map's Jacobian
    (central differences at 30 digits), the stick adds zeros.

Every motion is reported per impact ``k`` as the package's periodic motions are: the phase
of impact k, the stick after it, the release, the flight after the release (to impact
k + 1), with ``sum(stick_times) + sum(flight_times) = 2 pi N / omega``.
"""

from __future__ import annotations

import dataclasses
import functools
import itertools
from collections.abc import Callable

import mpmath

__all__ = [
    "DPS",
    "Damper",
    "StickyMotion",
    "first_root",
    "locked_ball_limit",
    "locked_ball_motion",
    "preloaded_motion",
    "pressing_minimum",
    "release_guess",
    "response",
    "riding_damper_motion",
    "riding_end",
    "riding_release_map",
    "wrap",
]

#: Working precision of every closed form (decimal digits).
DPS = 30

mp = mpmath.mp


def _at_dps(function: Callable) -> Callable:
    """Run `function` at :data:`DPS` digits (mpmath's working precision restored after)."""

    @functools.wraps(function)
    def wrapper(*args, **kwargs):
        with mp.workdps(DPS):
            return function(*args, **kwargs)

    return wrapper


def wrap(theta) -> mpmath.mpf:
    """``theta`` reduced to ``(-pi, pi]``."""
    t = theta - 2 * mp.pi * mp.floor(theta / (2 * mp.pi))
    return t - 2 * mp.pi if t > mp.pi else t


def response(m, c, k, f, f0, omega, theta0, y0, v0) -> Callable:
    """The exact solution of (S1) from ``(y0, v0)`` at phase ``theta0``.

    Parameters
    ----------
    m, c, k : number
        Mass ``m > 0``, damping ``c >= 0`` and stiffness ``k >= 0``; either an under-damped
        spring (``k > 0``, ``c^2 < 4 m k``) or ``k = c = 0`` (a free mass).
    f, f0 : number
        Amplitude of the harmonic force and the constant force.
    omega, theta0 : number
        Forcing frequency and the phase at ``tau = 0``.
    y0, v0 : number
        Position and velocity at ``tau = 0``.

    Returns
    -------
    callable
        ``tau -> (y, y', y'')`` in mpmath numbers.

    Notes
    -----
    With ``k > 0`` the forced part is ``f0 / k + Re(H f e^{i theta})``,
    ``H = 1 / (k - m omega^2 + i c omega)``, and the free part
    ``e^{-alpha tau} (A cos(omega_d tau) + B sin(omega_d tau))``, ``alpha = c / 2m``,
    ``omega_d = sqrt(4 m k - c^2) / 2m``. With ``k = c = 0``
    the motion is integrated twice by hand:
    ``y = y0 + v0 tau + f0 tau^2 / 2m + f (cos(theta0) - cos(theta) - omega tau
    sin(theta0)) / (m omega^2)``.
    """
    m, c, k, f, f0, omega, theta0, y0, v0 = (mp.mpf(v) for v in
                                              (m, c, k, f, f0, omega, theta0, y0, v0))
    if m <= 0 or c < 0 or k < 0:
        raise ValueError(f"need m > 0, c >= 0, k >= 0; got m={m}, c={c}, k={k}")
    if k == 0:
        if c != 0:
            raise ValueError(f"a free mass (k = 0) must be undamped here; got c={c}")
        s0, co0 = mp.sin(theta0), mp.cos(theta0)

        def free(tau):
            tau = mp.mpf(tau)
            th = theta0 + omega * tau
            y = (y0 + v0 * tau + f0 * tau**2 / (2 * m)
                 + f * (co0 - mp.cos(th) - omega * tau * s0) / (m * omega**2))
            v = v0 + f0 * tau / m + f * (mp.sin(th) - s0) / (m * omega)
            return y, v, (f0 + f * mp.cos(th)) / m

        return free
    disc = c * c - 4 * m * k
    if disc >= 0:
        raise ValueError(f"only an under-damped spring (c^2 < 4 m k = {4 * m * k}) is written "
                         f"here; got c={c}")
    alpha, wd = c / (2 * m), mp.sqrt(-disc) / (2 * m)
    # the forced part Re(H f e^{i theta}), H = 1 / (k - m omega^2 + i c omega)
    den = (k - m * omega**2) ** 2 + (c * omega) ** 2
    hr, hi = f * (k - m * omega**2) / den, -f * c * omega / den

    def forced(theta):
        cos, sin = mp.cos_sin(theta)
        return f0 / k + hr * cos - hi * sin, -omega * (hr * sin + hi * cos)

    yp0, vp0 = forced(theta0)
    # the free part e^{-alpha tau} (A cos(wd tau) + B sin(wd tau))
    A = y0 - yp0
    B = (v0 - vp0 + alpha * A) / wd

    def solution(tau):
        tau = mp.mpf(tau)
        th = theta0 + omega * tau
        yp, vp = forced(th)
        cos, sin = mp.cos_sin(wd * tau)
        decay = mp.exp(-alpha * tau)
        y = yp + decay * (A * cos + B * sin)
        v = vp + decay * ((B * wd - alpha * A) * cos - (A * wd + alpha * B) * sin)
        return y, v, (f * mp.cos(th) + f0 - c * v - k * y) / m

    return solution


def first_root(g: Callable, span, *, cells: int = 100, guard: Callable | None = None,
               what: str = "return to the stop") -> mpmath.mpf:
    """The first zero of ``g`` on ``(0, span]`` where it changes sign from negative to
    non-negative (scanned on `cells` cells, then ``mpmath.findroot`` in the bracket).

    Parameters
    ----------
    g : callable
        ``tau -> mpf``, negative right after ``tau = 0`` (at ``tau = 0`` negative too, or
        zero: then the first cell is left out).
    span : number
        The end of the search.
    cells : int
        Cells of the scan.
    guard : callable, optional
        ``tau -> mpf`` that must stay negative on the scan (after ``tau = 0``) up to the
        bracket (a flight that would meet another stop first).
    what : str
        What the zero is, for the error message.

    Raises
    ------
    ValueError
        No such sign change in ``(0, span]``, or `guard` non-negative before it.
    """
    span = mp.mpf(span)
    grid = [span * i / cells for i in range(cells + 1)]
    prev = g(grid[0])
    if not prev < 0:  # zero at the start (a flight from a release): bracket from the next
        grid, prev = grid[1:], None
    for a, b in itertools.pairwise(grid):
        ga = g(a) if prev is None else prev
        gb = g(b)
        prev = gb
        if guard is not None and a > 0 and guard(a) >= 0:
            raise ValueError(f"another stop is met at tau ~ {mpmath.nstr(a, 6)} before "
                             f"{what}")
        if ga < 0 <= gb:
            return mp.findroot(g, (a, b), solver="anderson", tol=mp.mpf(10) ** (-2 * DPS + 4))
    raise ValueError(f"no {what} within {mpmath.nstr(span, 6)} time units")


def pressing_minimum(p: Callable, duration, *, cells: int = 200) -> mpmath.mpf:
    """The smallest pressing force of a sticking phase: over its start and the interior
    minima of ``p`` on ``(0, duration)`` (the release at the end, where ``p = 0``, not
    counted), each minimum bracketed on `cells` cells and refined as a zero of ``p'``
    (``mpmath.diff``)."""
    duration = mp.mpf(duration)
    t = [duration * i / cells for i in range(cells + 1)]
    values = [p(x) for x in t]
    best = values[0]
    for i in range(1, cells):
        if values[i - 1] > values[i] <= values[i + 1]:
            tmin = mp.findroot(lambda x: mp.diff(p, x), (t[i - 1], t[i + 1]),
                               solver="anderson")
            best = min(best, p(tmin))
    return best


@dataclasses.dataclass(frozen=True)
class StickyMotion:
    """A periodic motion with sticking phases, per impact ``k = 0 .. p - 1``.

    Attributes
    ----------
    omega : mpmath.mpf
    pattern : str
        The stop of each impact, lowercase: plastic and held (``"u"`` upper, ``"l"`` lower).
    phases : list
        Forcing phase of impact k, in ``(-pi, pi]``.
    stick_times : list
        Time held on the stop after impact k, until the release.
    release_phases : list
        Forcing phase of the release after impact k, in ``(-pi, pi]``.
    flight_times : list
        Time from the release after impact k to impact k + 1.
    release_states : list
        The state ``[x; x']`` at the release after impact k (lists of mpf).
    landing_states : list
        The state ``[x; x']`` just after impact k (plastic: the stop coordinate at rest).
    impact_velocities : list
        Speed of the stop coordinate towards the stop just before impact k (``> 0``).
    landing_pressing : list
        The pressing force right after impact k (``> 0``: the stop holds).
    pressing_min : list
        The smallest pressing force of the stick after impact k, over its start and its
        interior minima (:func:`pressing_minimum`; ``> 0``: no release grazing inside).
    multipliers : list
        The motion's Floquet multipliers (2n of them; zeros for the collapsed directions).
    """

    omega: mpmath.mpf
    pattern: str
    phases: list
    stick_times: list
    release_phases: list
    flight_times: list
    release_states: list
    landing_states: list
    impact_velocities: list
    landing_pressing: list
    pressing_min: list
    multipliers: list

    @property
    def period(self) -> mpmath.mpf:
        """``sum(stick_times) + sum(flight_times)``."""
        return mp.fsum(self.stick_times) + mp.fsum(self.flight_times)

    def rotated(self, pattern: str) -> StickyMotion:
        """The same motion with its impacts numbered from another one, so that its pattern
        reads `pattern` (a rotation of :attr:`pattern`)."""
        p = len(self.pattern)
        for k in range(p):
            if self.pattern[k:] + self.pattern[:k] == pattern:
                return dataclasses.replace(self, pattern=pattern, **{
                    name: getattr(self, name)[k:] + getattr(self, name)[:k]
                    for name in ("phases", "stick_times", "release_phases", "flight_times",
                                 "release_states", "landing_states", "impact_velocities",
                                 "landing_pressing", "pressing_min")})
        raise ValueError(f"pattern must be a rotation of {self.pattern!r}; got {pattern!r}")

    def floats(self, name: str) -> list:
        """Attribute `name` as (nested) Python floats."""
        value = getattr(self, name)
        return [[float(v) for v in row] if isinstance(row, list) else float(row)
                for row in value]


@_at_dps
def preloaded_motion(omega, *, F=3, F_static=1, eta="0.05") -> StickyMotion:
    """Case (a): the preloaded oscillator held on its stop ``b = 0``, released, landing.

    Parameters
    ----------
    omega : number
        Forcing frequency.
    F, F_static : number
        Forcing amplitude and the static force into the stop, ``0 < F_static < F`` (else the
        mass is never pressed or never released).
    eta : number
        The paper's damping, ``C = 2 eta K`` (``K = 1``).

    Returns
    -------
    StickyMotion
        Pattern ``"u"``: one plastic impact and one stick per forcing period.

    Raises
    ------
    ValueError
        `F_static` outside ``(0, F)``, the mass not back within one period, or landing where
        the stop does not press it (``p <= 0``: no period-1 sticky motion at this `omega`).

    Notes
    -----
    Held, ``p(theta) = F cos(theta) + F_static`` (eq. (1) at rest on the stop, the stop's
    force ``-p``); release at ``theta_r = arccos(-F_static / F)``; flight from ``x = x' = 0``
    by (S1) with ``m = k = 1``, ``c = 2 eta``; the landing is the first ``tau > 0`` with
    ``x = 0`` (``x'' = 0`` at the release: ``x ~ -F omega sin(theta_r) tau^3 / 6``).
    """
    omega, F, Fs, eta = (mp.mpf(v) for v in (omega, F, F_static, eta))
    if not 0 < Fs < F:
        raise ValueError(f"F_static must lie in (0, F = {F}) for a stick and a release; "
                         f"got {Fs}")
    theta_r = mp.acos(-Fs / F)
    period = 2 * mp.pi / omega
    flight = response(1, 2 * eta, 1, F, Fs, omega, theta_r, 0, 0)
    tau = first_root(lambda t: flight(t)[0], period)
    _, v_land, _ = flight(tau)
    theta_l = theta_r + omega * tau

    def pressing(t):
        return F * mp.cos(theta_l + omega * t) + Fs

    p_land = pressing(0)
    if p_land <= 0:
        raise ValueError(f"lands at theta = {mpmath.nstr(wrap(theta_l), 8)} where the stop "
                         f"does not press (p = {mpmath.nstr(p_land, 6)}): no sticky 1-1 motion")
    zero = mp.mpf(0)
    return StickyMotion(omega=omega, pattern="u", phases=[wrap(theta_l)],
                        stick_times=[period - tau], release_phases=[wrap(theta_r)],
                        flight_times=[tau], release_states=[[zero, zero]],
                        landing_states=[[zero, zero]], impact_velocities=[v_land],
                        landing_pressing=[p_land],
                        pressing_min=[pressing_minimum(pressing, period - tau)],
                        multipliers=[zero, zero])


@_at_dps
def locked_ball_motion(Gamma, *, g=1, omega=1) -> StickyMotion:
    """Case (b): Luck & Mehta's completely inelastic ball, locked, released, landing, locked.

    Parameters
    ----------
    Gamma : number
        ``A omega^2 / g > 1`` (else the ball never leaves the table).
    g, omega : number
        Gravity and the table's frequency (``A = Gamma g / omega^2``).

    Returns
    -------
    StickyMotion
        Pattern ``"l"`` (the table is the lower stop ``y = 0`` of the table's frame).

    Raises
    ------
    ValueError
        ``Gamma <= 1``, a flight longer than a period, or a landing where the table does not
        press the ball.

    Notes
    -----
    Release at ``theta_r = -arccos(1 / Gamma)`` (Luck & Mehta's locking/unlocking phase:
    the table's downward acceleration reaches ``g``). From rest there
    ``y(tau) = -g tau^2 / 2 + A (cos(theta_r) - cos(theta_r + omega tau)
    - omega tau sin(theta_r))`` (S1 with ``k = c = 0``, ``f0 = -g``), the ball above the
    table (``y > 0``) until its first return to ``y = 0``, the landing.
    """
    Gamma, g, omega = (mp.mpf(v) for v in (Gamma, g, omega))
    if Gamma <= 1:
        raise ValueError(f"Gamma must exceed 1 for the ball to leave the table; got {Gamma}")
    A = Gamma * g / omega**2
    theta_r = -mp.acos(1 / Gamma)
    period = 2 * mp.pi / omega
    flight = response(1, 0, 0, A * omega**2, -g, omega, theta_r, 0, 0)
    tau = first_root(lambda t: -flight(t)[0], period)
    _, v_land, _ = flight(tau)
    theta_l = theta_r + omega * tau

    def pressing(t):
        return g - A * omega**2 * mp.cos(theta_l + omega * t)

    p_land = pressing(0)
    if p_land <= 0:
        raise ValueError(f"lands at theta = {mpmath.nstr(wrap(theta_l), 8)} where the table "
                         f"does not press (p = {mpmath.nstr(p_land, 6)})")
    zero = mp.mpf(0)
    return StickyMotion(omega=omega, pattern="l", phases=[wrap(theta_l)],
                        stick_times=[period - tau], release_phases=[wrap(theta_r)],
                        flight_times=[tau], release_states=[[zero, zero]],
                        landing_states=[[zero, zero]], impact_velocities=[-v_land],
                        landing_pressing=[p_land],
                        pressing_min=[pressing_minimum(pressing, period - tau)],
                        multipliers=[zero, zero])


@_at_dps
def locked_ball_limit() -> mpmath.mpf:
    """Case (b): the largest ``Gamma`` with the locked motion of one table period,
    ``sqrt(1 + pi^2)``.

    Notes
    -----
    There the flight lasts the whole period and the ball lands at its own release phase
    (the stick shrinks to nothing): ``y(2 pi / omega) = 0`` in :func:`locked_ball_motion`'s
    flight, ``-2 pi^2 g / omega^2 - 2 pi A sin(theta_r) = 0``, with ``cos(theta_r) = 1/Gamma``
    and ``sin(theta_r) < 0``: ``Gamma^2 - 1 = pi^2``. Derived here from the flight; whatever
    ``g`` and ``omega``.
    """
    return mp.sqrt(1 + mp.pi**2)


@dataclasses.dataclass(frozen=True)
class Damper:
    """Case (c)'s machine: the primary (mass 1, spring 1, damper ``c = 2 eta``, forced
    ``cos(theta)``) and a free ball of mass ``m`` in the clearance ``|x2 - x1| <= b``."""

    omega: mpmath.mpf
    m: mpmath.mpf
    b: mpmath.mpf
    c: mpmath.mpf

    def ride(self, wall: int, theta0, x1, v1):
        """The ball held on wall ``wall`` (``+1`` upper, ``-1`` lower) from the primary's
        ``(x1, v1)`` at phase `theta0`: ``(tau_stick, theta_release, x1, v1, p)`` with
        ``p`` the pressing force along the ride (``p = -wall m x1''``), a function of the
        time since the landing."""
        held = response(1 + self.m, self.c, 1, 1, 0, self.omega, theta0, x1, v1)
        p0 = -wall * self.m * held(0)[2]
        if p0 <= 0:
            raise ValueError(f"the wall {'U' if wall > 0 else 'L'} does not press the ball "
                             f"at the landing (p = {mpmath.nstr(p0, 6)})")
        tau = first_root(lambda t: wall * self.m * held(t)[2], 2 * mp.pi / self.omega,
                         what="release")
        x, v, _ = held(tau)
        return tau, theta0 + self.omega * tau, x, v, lambda t: -wall * self.m * held(t)[2]

    def fly(self, wall: int, theta0, x1, v1):
        """The ball released from wall `wall` with the primary at ``(x1, v1)`` (``x1'' = 0``)
        flies to the other wall: ``(tau_flight, theta_landing, x1, v1, v2)`` just before
        the impact."""
        primary = response(1, self.c, 1, 1, 0, self.omega, theta0, x1, v1)
        x2, v2 = x1 + wall * self.b, v1

        def s(t):
            return x2 + v2 * t - primary(t)[0]

        tau = first_root(lambda t: -wall * (s(t) + wall * self.b), 2 * mp.pi / self.omega,
                         guard=lambda t: wall * (s(t) - wall * self.b), what="landing")
        x, v, _ = primary(tau)
        return tau, theta0 + self.omega * tau, x, v, v2

    def land(self, x1, v1, v2):
        """The plastic impact: momentum kept, the relative speed zero; the common velocity."""
        return (v1 + self.m * v2) / (1 + self.m)

    def release_x1(self, theta, v1):
        """``x1`` at a release: ``x1'' = 0``, i.e. ``x1 = cos(theta) - c x1'``."""
        return mp.cos(theta) - self.c * v1


@_at_dps
def riding_release_map(damper: Damper, theta, v1, *, record: list | None = None):
    """One period of the riding damper from a release from the upper wall at
    ``(theta, x1')``: ``(theta', x1')`` at the next release from the upper wall.

    Parameters
    ----------
    damper : Damper
    theta, v1 : number
        Phase of the release and the primary's (and ball's) velocity there.
    record : list, optional
        Receives one dict per impact (lower wall, then upper): phase, landing state,
        impact speed, pressing force at the landing, stick time, release phase and state,
        flight time (the flight after the release).

    Returns
    -------
    tuple of mpf
        ``(theta', v1')``.
    """
    theta, v1 = mp.mpf(theta), mp.mpf(v1)
    x1, wall = damper.release_x1(theta, v1), 1
    pending = None
    for _ in range(2):
        tau_f, theta, x1, w1, w2 = damper.fly(wall, theta, x1, v1)
        if pending is not None:
            pending["flight_time"] = tau_f
        wall = -wall
        v = damper.land(x1, w1, w2)
        landing = {"phase": theta, "wall": wall, "impact_velocity": wall * (w2 - w1),
                   "landing_state": [x1, x1 + wall * damper.b, v, v]}
        tau_s, theta, x1, v1, pressing = damper.ride(wall, theta, x1, v)
        if record is not None:
            landing.update(pressing=pressing(0),
                           pressing_min=pressing_minimum(pressing, tau_s))
        landing.update(stick_time=tau_s, release_phase=theta,
                       release_state=[x1, x1 + wall * damper.b, v1, v1])
        if record is not None:
            record.append(landing)
        pending = landing
    if record is not None:
        # the flight after the upper release closes the period: measured from this release
        record[-1]["flight_time"] = damper.fly(1, theta, x1, v1)[0]
    return theta, v1


def _jacobian(damper: Damper, theta, v1, h="1e-10") -> mpmath.matrix:
    """``d(theta', x1') / d(theta, x1')`` of :func:`riding_release_map` by central
    differences (step `h`: truncation ``~h^2``, rounding ``~10^-DPS / h``)."""
    h = mp.mpf(h)
    J = mp.matrix(2, 2)
    for j, e in enumerate(((h, 0), (0, h))):
        plus = riding_release_map(damper, theta + e[0], v1 + e[1])
        minus = riding_release_map(damper, theta - e[0], v1 - e[1])
        for i in range(2):
            J[i, j] = (plus[i] - minus[i]) / (2 * h)
    return J


def _newton(damper: Damper, theta, v1, *, iterations: int = 30):
    """Newton's method (the chord variant: the Jacobian of :func:`_jacobian` at the start)
    on ``P(theta, x1') - (theta + 2 pi, x1') = 0``; converged when a step is below
    ``10^(5 - DPS)``. The chord converges linearly at the rate of the Jacobian's change
    over the distance to the solution, which from a start within ``1e-6`` is ``~1e-6`` a
    step."""
    A = _jacobian(damper, theta, v1) - mp.eye(2)
    for _ in range(iterations):
        th, v = riding_release_map(damper, theta, v1)
        step = mp.lu_solve(A, -mp.matrix([th - theta - 2 * mp.pi, v - v1]))
        theta, v1 = theta + step[0], v1 + step[1]
        if mp.norm(step, mp.inf) < mp.mpf(10) ** (5 - DPS):
            return theta, v1
    raise ValueError(f"Newton did not converge from theta={mpmath.nstr(theta, 8)}, "
                     f"x1'={mpmath.nstr(v1, 8)}")


@_at_dps
def riding_damper_motion(omega, *, m="0.2", b="0.3", eta="0.3", guess=None,
                         iterations: int = 4) -> StickyMotion:
    """Case (c): the impact damper whose plastic ball rides each wall once per period.

    Parameters
    ----------
    omega : number
        Forcing frequency.
    m, b, eta : number
        Ball mass, half clearance, the primary's damping (``c = 2 eta``).
    guess : tuple, optional
        ``(theta, x1')`` at a release from the upper wall. Default: the held system's forced
        response where its acceleration changes sign, improved by `iterations` periods of
        the map (the motion attracts).
    iterations : int
        Periods of :func:`riding_release_map` iterated before the Newton solve.

    Returns
    -------
    StickyMotion
        Pattern ``"lu"``: impact 0 on the lower wall, after the release from the upper.

    Raises
    ------
    ValueError
        A ride, flight or landing of the sought kind does not exist along the way.

    Notes
    -----
    The periodic motion solves ``P(theta, x1') = (theta + 2 pi, x1')`` with ``P`` the
    return map of :func:`riding_release_map` (``mpmath.findroot``, multidimensional Newton,
    at 30 digits). Its multipliers are the eigenvalues of ``dP`` (central differences with
    the step ``1e-10``: error ``~1e-20``) and two zeros (the ball at rest on its wall after
    a plastic impact: the stick fixes ``s`` and ``s'``).
    """
    d = Damper(*(mp.mpf(v) for v in (omega, m, b, 2 * mp.mpf(eta))))
    if guess is None:
        M = 1 + d.m
        H = 1 / (1 - M * d.omega**2 + 1j * d.c * d.omega)
        # x1'' = -omega^2 Re(H e^{i theta}) rises through 0 where arg(H) + theta = pi/2
        theta = mp.pi / 2 - mp.arg(H)
        guess = (theta, mp.re(1j * d.omega * H * mp.expj(theta)))
        for _ in range(iterations):
            theta, v1 = riding_release_map(d, *guess)
            guess = (theta - 2 * mp.pi, v1)
    theta, v1 = _newton(d, mp.mpf(guess[0]), mp.mpf(guess[1]))
    record: list = []
    riding_release_map(d, theta, v1, record=record)
    eig = mp.eig(_jacobian(d, theta, v1), left=False, right=False)
    zero = mp.mpf(0)
    multipliers = [*sorted(eig, key=lambda z: -abs(z)), zero, zero]
    return StickyMotion(
        omega=d.omega, pattern="".join("u" if r["wall"] > 0 else "l" for r in record),
        phases=[wrap(r["phase"]) for r in record],
        stick_times=[r["stick_time"] for r in record],
        release_phases=[wrap(r["release_phase"]) for r in record],
        flight_times=[r["flight_time"] for r in record],
        release_states=[r["release_state"] for r in record],
        landing_states=[r["landing_state"] for r in record],
        impact_velocities=[r["impact_velocity"] for r in record],
        landing_pressing=[r["pressing"] for r in record],
        pressing_min=[r["pressing_min"] for r in record], multipliers=multipliers)


def release_guess(motion: StickyMotion) -> tuple:
    """``(theta, x1')`` at the release from the upper wall of a riding motion: the `guess`
    of :func:`riding_damper_motion` at a nearby omega."""
    k = motion.pattern.index("u")
    return motion.release_phases[k], motion.release_states[k][2]


@_at_dps
def riding_end(guess: StickyMotion | tuple, *, m="0.2", b="0.3", eta="0.3",
               iterations: int = 30) -> tuple:
    """Where the symmetric riding motion of case (c) ends in omega: the ball lands where
    the wall no longer presses it, the stick shrinks to nothing (``p = 0`` at the landing,
    a release grazing at the start of the stick).

    Parameters
    ----------
    guess : StickyMotion or tuple
        The riding motion near the end (of the machine `m`, `b`, `eta`), or
        ``(theta, x1', omega)`` at a release from the upper wall near the end.
    m, b, eta : number
        The machine, as in :func:`riding_damper_motion`.
    iterations : int
        Newton iterations allowed.

    Returns
    -------
    tuple of mpf
        ``(omega*, theta, x1')``: the frequency and the release from the upper wall there.

    Raises
    ------
    ValueError
        Newton does not converge.

    Notes
    -----
    At the end the landing is itself a release (``x1'' = 0`` with the ball held or not:
    ``cos(theta) - c x1' - x1 = 0`` both ways), and the motion, symmetric
    (``X(t + T/2) = -X(t)``), is the flight from a release on the upper wall at
    ``(theta, x1')`` to the lower wall, landing half a period later on the mirror image:
    ``theta_l = theta + pi``, ``x1_l = -x1``, ``v = -x1'`` after the plastic impact (the
    condition ``x1'' = 0`` at the landing then holds by itself). Three equations in
    ``(theta, x1', omega)``, Newton with central differences (step ``1e-12``).
    """
    m, b, c = mp.mpf(m), mp.mpf(b), 2 * mp.mpf(eta)
    if isinstance(guess, StickyMotion):
        guess = (*release_guess(guess), guess.omega)
    x = mp.matrix([mp.mpf(v) for v in guess])

    def residual(u):
        d = Damper(u[2], m, b, c)
        x1 = d.release_x1(u[0], u[1])
        _, theta_l, x1_l, w1, w2 = d.fly(1, u[0], x1, u[1])
        return mp.matrix([theta_l - u[0] - mp.pi, x1_l + x1, d.land(x1_l, w1, w2) + u[1]])

    h = mp.mpf("1e-12")
    for _ in range(iterations):
        r = residual(x)
        J = mp.matrix(3, 3)
        for j in range(3):
            e = mp.matrix(3, 1)
            e[j] = h
            column = (residual(x + e) - residual(x - e)) / (2 * h)
            for i in range(3):
                J[i, j] = column[i]
        step = mp.lu_solve(J, -r)
        x += step
        if mp.norm(step, mp.inf) < mp.mpf(10) ** (5 - DPS):
            return x[2], x[0], x[1]
    raise ValueError(f"Newton did not converge to the end of the riding motion from omega = "
                     f"{mpmath.nstr(mp.mpf(guess[2]), 8)}")
