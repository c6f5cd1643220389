"""Closed-form periodic N-1 motions (eq. 11-16) and their stability (eq. 17-25)."""

from __future__ import annotations

import dataclasses
import functools
import logging
import math
import warnings
import weakref

import numpy as np

from impactcont.errors import (
    IllConditionedWarning,
    LowImpactVelocityWarning,
    NearFoldWarning,
    NearResonanceWarning,
    ParameterError,
    ResonanceError,
    UnresolvedMotionWarning,
)
from impactcont.kernel import arrays as _arrays
from impactcont.kernel.arrays import ModalArrays
from impactcont.model.oscillator import ImpactOscillator
from impactcont.model.stops import require_paper_stops
from impactcont.orbit import general
from impactcont.orbit.dense import (
    COND_WARN,
    VELOCITY_POLISH,
    impact_map_jacobian,
    periodic_matrix,
    polished_velocity,
    velocity_bound,
    warn_ill_conditioned,
)
from impactcont.orbit.flow import Flow
from impactcont.vocabulary import check_positive_integer

__all__ = [
    "IllConditionedWarning",  # defined in impactcont.errors, re-exported here
    "PeriodicOrbit",
    "impact_map_jacobian",
    "impact_states",
    "modal_arrays",
    "modal_jacobian",
    "orbit_at_phase",
    "periodic_matrix",  # defined in impactcont.orbit.dense, re-exported here
    "periodic_orbits",
]

log = logging.getLogger(__name__)

_EPS = float(np.finfo(float).eps)
# warn when G of eq. (25) may carry a relative error above ~1e-8 (eps |v| / |h2|)
_H2_REL_ERROR_WARN = 1e-8
# warn when the forced amplitude of a mode is known to worse than this (relative)
_RESONANCE_REL_ERROR_WARN = 1e-8
# warn when the impact phase of eq. (15) may carry an error above ~1e-10 (eps r / sqrt(r^2-b^2))
_FOLD_ERROR_WARN = 1e-10
# the kernel's fold error takes r^2 = c^2 + s^2 exact to an ulp; c and s carry a few ulp each
# (measured: up to 7.4 times the one-ulp error under 1-ulp changes of K and M), so the error
# stated is this many times it
_FOLD_ULPS = 16.0


def _one_impact(scalar: str, doc: str) -> property:
    """A per-impact array of the motion protocol for a motion with one impact: the property
    ``[self.<scalar>]``, shape (1,), documented by ``doc``."""
    def value(self: PeriodicOrbit) -> np.ndarray:
        return np.array([getattr(self, scalar)])
    return property(value, doc=doc)


@dataclasses.dataclass(frozen=True, eq=False)
class PeriodicOrbit:
    """One periodic N-1 motion: one impact every N forcing periods.

    A thin view over the compiled kernel's arrays (:mod:`impactcont.kernel.closed_form`):
    the phase, impact velocity and interior-contact check are computed with it;
    the state, ``G`` and the multipliers are built on first access.

    Attributes
    ----------
    oscillator : ImpactOscillator
    N : int
        Forcing periods per impact; the period is ``T = 2 pi N / omega``.
    delta : float
        Forcing phase at the impact, in ``(-pi, pi]`` (eq. 15).
    root : int
        +1 or -1: the sign in front of the square root of eq. (15)
        (``sin delta = (b s + root c r) / (c^2 + s^2)``, ``r = sqrt(c^2+s^2-b^2)``);
        for elastic impacts without damping, +1 where the forced motion of mass 1
        is at its maximum at the impact, -1 at its minimum.
    period : float
        ``T``.
    state : ndarray, shape (2n,)
        ``X(0) = [x; x']`` right after the impact (eq. 13).
    impact_velocity : float
        ``x1'(T^-)``, velocity of mass 1 just before impact (``h2`` of eq. 22).
    gap_min : float
        Smallest ``b - x1`` at the interior local maxima of ``x1`` over ``(0, T)``;
        ``+inf`` when ``x1`` has none.
    gap_min_time : float
        Time of that maximum after the impact (NaN when there is none).
    physical : bool
        ``impact_velocity > 0`` (mass 1 arrives towards the stop and leaves it)
        and ``gap_min > 0`` (no contact inside the period, eq. 16). The closed form
        takes the paper's one stop only (:func:`~impactcont.model.stops.require_paper_stops`
        refuses a lower stop, a clearance between masses and further stops), so the impact
        state, ``x1 = b``, has no other stop to check; an N-1 motion of any other system is
        the shooting path's (p = 1), which checks every stop at the impact
        (:func:`impactcont.kernel.shooting.end_clearances`).
    reason : str
        Why the motion is not physical ("" when it is).
    """

    oscillator: ImpactOscillator
    N: int
    delta: float
    root: int
    period: float
    impact_velocity: float
    gap_min: float
    gap_min_time: float
    physical: bool
    reason: str
    state: np.ndarray = dataclasses.field(repr=False)
    """``X(0) = [x; x']`` right after the impact (eq. 13), shape (2n,)."""
    modal: np.ndarray | None = dataclasses.field(repr=False)
    """Per-mode pieces at this frequency (rows of
    :func:`impactcont.kernel.closed_form.omega_setup`); None on the first-order path
    (general damping matrix or complex F), where G and the multipliers are computed with
    the motion."""

    @functools.cached_property
    def G(self) -> np.ndarray:
        """Jacobian of the impact map in ``z = [dx2..dxn, dx1'..dxn', d delta]`` (eq. 25)."""
        return modal_jacobian(self.oscillator, self.modal, self.delta, self.impact_velocity)[0]

    @functools.cached_property
    def multipliers(self) -> np.ndarray:
        """Eigenvalues of G, largest modulus first, shape (2n,) complex.

        From ``n >= secular.SECULAR_MIN`` degrees of freedom by the O(n)-per-root
        secular function of :mod:`impactcont.orbit.secular` (G is not formed; the
        impact velocity as its pole, a polished one included); the dense eigenvalues of G
        where its accuracy guard refuses, and for small systems.
        """
        from impactcont.kernel import stability
        from impactcont.orbit import secular

        osc = self.oscillator
        if osc.n >= secular.SECULAR_MIN:
            arrays = modal_arrays(osc)
            mu, ok = secular.secular_multipliers(self.modal, arrays.w, arrays.a, arrays.f,
                                                 arrays.u0, arrays.ui0, osc.omega, osc.R,
                                                 self.delta, self.impact_velocity)
            if ok:
                return mu
            log.debug("secular multipliers refused by their guard (n = %d, delta = %.12g); "
                      "dense eigenvalues of G instead", osc.n, self.delta)
        return stability.multipliers(self.G)  # NaN when G is not finite

    @property
    def spectral_radius(self) -> float:
        """``rho(G)``, the largest multiplier modulus."""
        return float(np.abs(self.multipliers).max())

    @property
    def stable(self) -> bool:
        """Asymptotically stable by Theorem 3.1: ``rho(G) < 1``."""
        return self.spectral_radius < 1.0

    # -- the per-impact view shared with MultiImpactOrbit (p = 1; the motion protocol of
    # -- impactcont.problems.motion, read by the one branch driver, detector and builder) ---
    p = 1
    """Impacts per motion: one."""
    pattern = "U"
    """The stop of each impact: the paper's one stop, ``"U"``, as an N-p motion's on it."""

    phases = _one_impact(
        "delta", "``[delta]``: the forcing phase at the one impact, shape (1,).")
    flight_times = _one_impact(
        "period", "``[T]``: the one flight lasts the period, shape (1,).")
    impact_velocities = _one_impact(
        "impact_velocity", "``[h2]``: the velocity just before the one impact, shape (1,).")
    flight_gap_min = _one_impact(
        "gap_min", "``[gap_min]``: the clearance of the one flight (eq. 16), shape (1,).")

    @property
    def states(self) -> np.ndarray:
        """``[X(0)]``: the state right after the one impact, shape (1, 2n)."""
        return self.state[None, :]

    def time_series(self, num: int = 400, periods: int = 1) -> tuple[np.ndarray, np.ndarray]:
        """Exact state over ``periods`` repetitions of the motion (for plots).

        Returns
        -------
        t : ndarray, shape (periods*num,)
            Time since the reference impact.
        X : ndarray, shape (periods*num, 2n)
            State; each repetition restarts at ``self.state`` after the impact.
        """
        if periods < 1 or num < 2:
            raise ParameterError(f"need periods >= 1 and num >= 2; got periods={periods!r}, "
                                 f"num={num!r}")
        flow = Flow(self.oscillator)
        tau = np.linspace(0.0, self.period, num)
        X = flow.state(tau, self.state, self.delta)
        t = np.concatenate([k * self.period + tau for k in range(periods)])
        return t, np.tile(X, (periods, 1))

    def __repr__(self) -> str:
        return (f"PeriodicOrbit(N={self.N}, delta={self.delta:.12g}, "
                f"impact_velocity={self.impact_velocity:.6g}, gap_min={self.gap_min:.6g}, "
                f"rho={self.spectral_radius:.6g}, stable={self.stable}, "
                f"physical={self.physical})")


# modal basis -> (impacting mass, its ModalArrays, their plain tuple)
_BUILT: weakref.WeakKeyDictionary = weakref.WeakKeyDictionary()


def modal_arrays(osc: ImpactOscillator) -> ModalArrays:
    """The oscillator's :class:`~impactcont.kernel.arrays.ModalArrays`, the compiled kernel's
    inputs (eq. 5-7), built and checked once per modal basis and impacting mass.

    The impacting mass is the model's (``osc.stops.mass``): its row of ``u`` and column
    of ``u^-1`` are the ones the impact law of eq. (4) sees. The closed form's G and
    state after the impact are written for the paper's mass 1, which every closed-form
    path requires (:func:`impactcont.model.stops.require_paper_stops`).
    """
    return _built(osc)[1]


def _kernel_tuple(osc: ImpactOscillator) -> tuple[np.ndarray, ...]:
    """:func:`modal_arrays` as the compiled entry points take them
    (:meth:`~impactcont.kernel.arrays.ModalArrays.as_tuple`, kept with them)."""
    return _built(osc)[2]


def _built(osc: ImpactOscillator) -> tuple[int, ModalArrays, tuple[np.ndarray, ...]]:
    basis = osc.modes
    mass = osc.stops.mass - 1
    entry = _BUILT.get(basis)
    if entry is None or entry[0] != mass:
        arrays = _arrays.modal_arrays(basis.natural_frequencies, basis.decay_rates,
                                      basis.modal_forces, basis.u, basis.u_inv,
                                      basis.eigenvalue_errors, mass=mass)
        entry = _BUILT[basis] = (mass, arrays, arrays.as_tuple())
    return entry


def modal_jacobian(osc: ImpactOscillator, modal: np.ndarray, delta: float, sigma: float,
                   *, omega: float | None = None) -> tuple[np.ndarray, float]:
    """G of eq. (25) and ``h2`` from the kernel's modal pieces at one frequency (the
    oscillator's, or `omega`: the frequency `modal` was computed at).

    Assembled as ``G_reg + a b^T / sigma`` (:func:`impactcont.kernel.closed_form.jacobian_split`)
    with the motion's own impact velocity ``sigma`` as the pole: the kernel's
    recomputation of ``h2 = x1'(T^-)`` from the forced velocity at the phase is the form
    that cancels far above the lowest natural frequency (:func:`impactcont.orbit.dense.
    impact_velocity`). The transition ``U W(T) U^-1`` costs O(n^3): plain compiled loops
    for small systems, numpy (BLAS) matrix products above ``closed_form.BLAS_MIN`` degrees of
    freedom.
    """
    from impactcont.kernel import closed_form

    arrays = modal_arrays(osc)
    om = osc.omega if omega is None else omega
    G_reg, av, bv, _ = closed_form.jacobian_split(physical_transition(osc, modal), modal,
                                                  arrays.w, arrays.a, arrays.f, arrays.u,
                                                  arrays.ui0, om, osc.R, delta, sigma)
    with np.errstate(divide="ignore", invalid="ignore", over="ignore"):  # sigma = 0: a pole
        return G_reg + np.outer(av, bv) / sigma, float(sigma)


def physical_transition(osc: ImpactOscillator, modal: np.ndarray) -> np.ndarray:
    """The physical transition ``U W(T) U^-1`` (eq. 9): compiled loops for small systems,
    numpy (BLAS) matrix products above ``closed_form.BLAS_MIN`` degrees of freedom.

    It is real-linear in the modal transfers: complex (complex-stepped) pieces take two
    real transitions, the same sums as complex loops, and no complex compiled variant."""
    from impactcont.kernel import closed_form, flights

    arrays = modal_arrays(osc)
    u, ui = arrays.u, arrays.ui
    if osc.n <= closed_form.BLAS_MIN and modal.dtype.kind == "c":
        tr = np.empty((2 * osc.n, 2 * osc.n), dtype=complex)
        tr.real = flights.transition(np.ascontiguousarray(modal.real), u, ui)
        tr.imag = flights.transition(np.ascontiguousarray(modal.imag), u, ui)
        return tr
    if osc.n <= closed_form.BLAS_MIN:
        return flights.transition(modal, u, ui)
    return np.block([[(u * modal[2]) @ ui, (u * modal[3]) @ ui],
                     [(u * modal[4]) @ ui, (u * modal[5]) @ ui]])


def _check_N(N: object) -> int:
    return check_positive_integer("N", N, "impact every N forcing periods")


def _check_oscillator(osc: object) -> ImpactOscillator:
    if not isinstance(osc, ImpactOscillator):
        raise ParameterError(f"osc must be an ImpactOscillator; got {osc!r}")
    require_paper_stops(osc, "the N-1 closed form")  # stops: mass 1, one stop only
    return osc


def _warn_setup(osc: ImpactOscillator, scalars: np.ndarray, stacklevel: int) -> None:
    """Refuse an exact resonance; warn when eq. (12)-(13) are inexact at this omega."""
    cond, res_err = scalars[7], scalars[8]
    if res_err == math.inf:
        w = osc.modes.natural_frequencies
        i = int(np.argmin(np.abs(w - osc.omega)))
        raise ResonanceError(
            f"omega={osc.omega!r} equals the natural frequency {w[i]!r} of undamped mode "
            f"{i + 1}: the forced response of eq. (6) does not exist; choose omega != omega_i "
            "or add damping")
    if res_err > _RESONANCE_REL_ERROR_WARN:
        w = osc.modes.natural_frequencies
        i = int(np.argmin(np.abs(w - osc.omega)))
        warnings.warn(
            f"omega={osc.omega!r} is within {abs(osc.omega / w[i] - 1.0):.2g} (relative) of the "
            f"natural frequency {w[i]!r} of a lightly damped mode: its forced amplitude (eq. 7) "
            f"is known only to a relative error of about {res_err:.1g}; move omega away from "
            "omega_i or add damping", NearResonanceWarning, stacklevel=stacklevel)
    if not cond <= COND_WARN:
        warn_ill_conditioned(osc.omega, float(cond), stacklevel=stacklevel + 1)


def _make_orbit(osc: ImpactOscillator, N: int, modal: np.ndarray | None, T: float, delta: float,
                root: int, sigma: float, gap_min: float, gap_time: float, state: np.ndarray,
                G: np.ndarray | None = None, multipliers: np.ndarray | None = None
                ) -> PeriodicOrbit:
    """A :class:`PeriodicOrbit` from the kernel's values (G and multipliers when computed).

    Built without the frozen dataclass's ``__init__`` (one ``object.__setattr__`` per
    field, which costs more than the kernel call for small systems); the fields are
    exactly the dataclass fields.
    """
    reasons = []
    if not sigma > 0:
        reasons.append(f"impact velocity {sigma:.3g} <= 0: mass 1 does not arrive towards the "
                       "stop")
    if not gap_min > 0:
        reasons.append(f"x1 reaches the stop inside the period (gap_min={gap_min:.3g} at "
                       f"t={gap_time:.6g})")
    orbit = object.__new__(PeriodicOrbit)
    orbit.__dict__.update(oscillator=osc, N=N, delta=delta, root=root, period=T,
                          impact_velocity=sigma, gap_min=gap_min, gap_min_time=gap_time,
                          physical=not reasons, reason="; ".join(reasons), state=state,
                          modal=modal)
    if G is not None:  # the cached properties' values
        orbit.__dict__["G"] = G
        orbit.__dict__["multipliers"] = multipliers
    return orbit


def _general_orbit(osc: ImpactOscillator, N: int, form: general.PeriodicForm, delta: float,
                   root: int, warn: bool) -> PeriodicOrbit:
    """The motion at phase delta on the first-order path (:mod:`impactcont.orbit.general`),
    with its G and multipliers; `warn`: the low-impact-velocity warning of the single-point
    API."""
    v = general.orbit_values(form, float(delta))
    orbit = _make_orbit(osc, N, None, form.T, float(delta), root, v.h2, v.gap_min,
                        v.gap_min_time, v.state, v.G, v.multipliers)
    if warn:
        _warn_low_impact_velocity(orbit, v.velocity_scale, v.h2_error)
    return orbit


def _velocity_bound(osc: ImpactOscillator, scalars: np.ndarray) -> float:
    """:func:`impactcont.orbit.dense.velocity_bound` at one frequency; zero for elastic
    undamped impacts, whose velocity the kernel takes from the impact condition."""
    _, Gam, B, _, Delta, _, _, _, _, elastic = scalars.tolist()
    return 0.0 if elastic != 0.0 else float(velocity_bound(Gam, B, Delta, osc.omega))


def _polished_velocity(osc: ImpactOscillator, scalars: np.ndarray, delta: float,
                       sigma: float) -> tuple[float | None, float]:
    """:func:`impactcont.orbit.dense.polished_velocity` of a motion from the kernel's
    scalars of its frequency."""
    Gam, B, g, Delta = (float(x) for x in scalars[1:5])
    return polished_velocity(Gam, B, g, Delta, osc.omega, osc.R, osc.b, delta, sigma)


def _repolish(osc: ImpactOscillator, modal: np.ndarray, scalars: np.ndarray, delta: float,
              sigma: float) -> tuple[np.ndarray, float, float, float]:
    """State, velocity scale, gap and its time of the modal motion at phase delta with the
    impact velocity ``sigma`` (a polished one).

    G and the multipliers are not computed here: the orbit builds them on first access
    (:attr:`PeriodicOrbit.G`, :attr:`PeriodicOrbit.multipliers`) with ``sigma`` as the pole
    of eq. (25), as on the unpolished path. Computing them here cost a dense eigenvalue
    solve of G, O(n^3), inside every :func:`periodic_orbits` call that polished a root
    (issue 29: 14-27 s at n = 1600-2000 for a chain, against milliseconds without).
    """
    from impactcont.kernel import closed_form, contact

    arrays = modal_arrays(osc)
    state, scale = closed_form.physical_state(modal, arrays.u, osc.omega, osc.R, delta, sigma)
    best, gap_t = contact.other_maximum(arrays.w, arrays.a, arrays.u0, modal, scalars,
                                        osc.omega, osc.R, delta, sigma, math.nan)
    return state, float(scale), osc.b - float(best), float(gap_t)


def _warn_capped(capped: bool, T: float) -> None:
    if capped:
        warnings.warn(f"x1 search grid capped at 2000000 cells for a period of {T:.3g}: a short "
                      "excursion of mass 1 past the stop (eq. 16) may be missed; damping the "
                      "fastest modes or a shorter period avoids this", UnresolvedMotionWarning,
                      stacklevel=3)


_PHASE_TOL = 1e-7  # relative residual of eq. (14) above which a phase is no motion


def orbit_at_phase(osc: ImpactOscillator, N: int, delta: float, *, root: int = 0,
                   check: bool = True) -> PeriodicOrbit:
    """The periodic N-1 motion with impact phase ``delta`` (which must satisfy eq. 14).

    The impact velocity follows from the phase (``sigma = x1p'(delta) / Delta``, see
    :mod:`impactcont.kernel.closed_form`; for elastic impacts without damping from the gap;
    from the gap too where the first form has lost digits and the phase is a root,
    :func:`impactcont.orbit.dense.impact_velocity`), then the interior-contact check of
    eq. (16); state, G and multipliers on access.

    Raises
    ------
    ParameterError
        With `check` (the default), if ``delta`` does not satisfy eq. (14),
        ``|c cos(delta) + s sin(delta) - b| > 1e-7 max(1, |b|, sqrt(c^2 + s^2))``:
        such a phase is not a periodic motion (its ``x1(0)`` is not ``b``).
        ``check=False`` is for callers that evaluate guesses on purpose.
    """
    from impactcont.kernel import closed_form

    N = _check_N(N)
    _check_oscillator(osc)
    if osc.general:  # a general damping matrix or complex F: the first-order path
        form = general.periodic_form(osc, N)
        if check:
            _check_phase(osc, form.c, form.s, delta)
        return _general_orbit(osc, N, form, float(delta), root, warn=False)
    modal, sc, sigma, gap, gap_t, capped, state = closed_form.phase_orbit(
        _kernel_tuple(osc), osc.R, osc.omega, N, osc.b, float(delta))
    if check and sc[9] == 0.0:  # elastic undamped motions satisfy the impact condition instead
        _check_phase(osc, float(sc[5]), float(sc[6]), delta)
    _warn_capped(capped, sc[0])
    if _velocity_bound(osc, sc) > VELOCITY_POLISH * abs(sigma):
        better, _ = _polished_velocity(osc, sc, float(delta), float(sigma))
        if better is not None:
            sigma = better
            state, _, gap, gap_t = _repolish(osc, modal, sc, float(delta), better)
    return _make_orbit(osc, N, modal, float(sc[0]), float(delta), root, float(sigma),
                       float(gap), float(gap_t), state)


def _check_phase(osc: ImpactOscillator, c: float, s: float, delta: float) -> None:
    """Refuse a phase that does not satisfy eq. (14) (see :func:`orbit_at_phase`)."""
    residual = c * math.cos(delta) + s * math.sin(delta) - osc.b
    scale = max(1.0, abs(osc.b), math.hypot(c, s))
    if not abs(residual) <= _PHASE_TOL * scale:
        raise ParameterError(
            f"delta={delta!r} does not satisfy eq. (14) at omega={osc.omega!r}, b={osc.b!r}: "
            f"c cos(delta) + s sin(delta) - b = {residual:.3g} (allowed: below "
            f"{_PHASE_TOL * scale:.1g}); the phases of the periodic motions are those of "
            "periodic_orbits(osc, N)")


def impact_states(osc: ImpactOscillator, N: int, delta: np.ndarray, sigma: np.ndarray
                  ) -> np.ndarray:
    """The states right after the impact of N-1 motions at one frequency, many at once.

    ``X(0) = [x; x']`` of eq. (13) of the motions with impact phases `delta` (roots of
    eq. 15 at the oscillator's ``omega``) and impact velocities `sigma` (``h2`` of eq. 22,
    as :func:`impactcont.orbit.batched.batched_orbits` gives them): on the modal path the
    modal state of :func:`impactcont.kernel.closed_form.orbit_states` mapped by ``u``,
    with ``x1' = -R sigma`` set exactly (eq. 4), as
    :func:`~impactcont.kernel.closed_form.physical_state` builds one motion's, in numpy
    over all of them; on the first-order path (:attr:`ImpactOscillator.general`) the
    compiled evaluation of :func:`impactcont.orbit.general.orbit_values`.

    Parameters
    ----------
    osc : ImpactOscillator
        Its ``omega`` is the motions'; its ``b`` is not used.
    N : int
        One impact every N forcing periods.
    delta, sigma : ndarray, shape (k,)
        Impact phases and impact velocities.

    Returns
    -------
    ndarray, shape (k, 2n)
    """
    from impactcont.kernel import closed_form

    N = _check_N(N)
    _check_oscillator(osc)
    delta = np.ascontiguousarray(delta, dtype=float)
    sigma = np.asarray(sigma, dtype=float)
    if delta.ndim != 1 or sigma.shape != delta.shape:
        raise ParameterError(f"delta and sigma must be 1-D arrays of the same length; got "
                             f"shapes {delta.shape} and {sigma.shape}")
    n = osc.n
    if delta.size == 0:
        return np.empty((0, 2 * n))
    if osc.general:
        # the first-order path takes the impact velocity from the phase and the gap: the
        # gap of each motion is x1 at its phase, c cos(delta) + s sin(delta) (eq. 14)
        form = general.periodic_form(osc, N, warn=False)
        b = form.c * np.cos(delta) + form.s * np.sin(delta)
        return general._compiled_values(form, delta, np.ascontiguousarray(b))[1]
    arrays = modal_arrays(osc)
    modal, _ = closed_form.omega_setup(arrays.w, arrays.a, arrays.f, arrays.u0, arrays.ui0,
                                       arrays.eig_err, osc.R, osc.omega, N)
    cd, sd = np.cos(delta)[:, None], np.sin(delta)[:, None]
    ks = ((1.0 + osc.R) * sigma)[:, None]
    gm, bt = modal[0], modal[1]
    y = gm * cd + bt * sd + ks * modal[6]
    v = osc.omega * (bt * cd - gm * sd) + ks * modal[7]
    X = np.concatenate([y @ arrays.u.T, v @ arrays.u.T], axis=1)
    X[:, n] = -osc.R * sigma
    return X


def periodic_orbits(osc: ImpactOscillator, N: int) -> list[PeriodicOrbit]:
    """Every root of eq. (15): the candidate periodic N-1 motions.

    Parameters
    ----------
    osc : ImpactOscillator
    N : int
        One impact every N forcing periods.

    Returns
    -------
    list of PeriodicOrbit
        Zero (``c^2 + s^2 < b^2``), one (a double root) or two motions. Each
        carries its ``physical`` flag and ``reason``: a root that is not a
        physical motion is reported, never silently dropped. For elastic impacts
        without damping (``R = 1``, no damping) eq. (12) is singular for every
        omega; the two isolated motions are then those whose forced motion of
        mass 1 is at rest at the impact (see :mod:`impactcont.kernel.closed_form`).

    Raises
    ------
    ParameterError
        If `osc` is not an oscillator, `N` is not an integer >= 1, or the forcing
        does not reach mass 1 so that every phase (or none) would solve eq. (14).
    ResonanceError
        If omega equals the natural frequency of an undamped, forced mode.
    """
    from impactcont.kernel import closed_form

    osc = _check_oscillator(osc)
    N = _check_N(N)
    if osc.general:  # a general damping matrix or complex F: the first-order path
        form = general.periodic_form(osc, N)
        found = general.roots(form.c, form.s, osc.b)
        if len(found) == 2:
            r2 = form.c ** 2 + form.s ** 2
            _warn_fold(r2, osc.b, _EPS * math.sqrt(r2) / math.sqrt(r2 - osc.b ** 2))
        elif found:  # a double root: c^2 + s^2 = b^2 exactly
            _warn_fold(osc.b ** 2, osc.b, math.sqrt(_EPS))
        return [_general_orbit(osc, N, form, delta, root, warn=True) for delta, root in found]
    (modal, sc, count, delta, sigma, fold_error, gap, gap_t, capped, states, scales,
     jacobians, mults) = closed_form.point_orbits(_kernel_tuple(osc), osc.R, osc.omega, N,
                                                  osc.b)
    _warn_setup(osc, sc, stacklevel=2)
    if count == -1:
        raise ParameterError("c = s = 0 and b = 0: every phase satisfies eq. (14); the "
                             "forcing does not reach mass 1 (check F)")
    if count == -2:
        raise ParameterError("elastic impacts without damping and no forced motion of mass 1 "
                             "(check F): eq. (12) does not fix the impact phase")
    if count == 0:
        log.debug("no N=%d motion: c^2 + s^2 = %.6g < b^2 = %.6g", N,
                  sc[5] ** 2 + sc[6] ** 2, osc.b ** 2)
        return []
    if fold_error > _FOLD_ERROR_WARN:
        _warn_fold(sc[5] ** 2 + sc[6] ** 2, osc.b, fold_error)
    _warn_capped(capped, sc[0])
    # the kernel's impact velocity may have lost digits only above this (one bound per
    # frequency, the exact check and the re-evaluation per root only past it)
    limit = _velocity_bound(osc, sc) / VELOCITY_POLISH
    out = []
    for k in range(count):
        sk, h2_error = float(sigma[k]), 0.0
        if abs(sk) < limit:
            better, h2_error = _polished_velocity(osc, sc, float(delta[k]), sk)
            if better is not None:
                state, scale, gk, tk = _repolish(osc, modal, sc, float(delta[k]), better)
                orbit = _make_orbit(osc, N, modal, float(sc[0]), float(delta[k]), (1, -1)[k],
                                    better, gk, tk, state)
                _warn_low_impact_velocity(orbit, scale, h2_error)
                out.append(orbit)
                continue
        orbit = _make_orbit(osc, N, modal, float(sc[0]), float(delta[k]), (1, -1)[k], sk,
                            float(gap[k]), float(gap_t[k]), states[k],
                            *((jacobians[k], mults[k]) if jacobians.shape[1] else ()))
        _warn_low_impact_velocity(orbit, float(scales[k]), h2_error)
        out.append(orbit)
    return out


def _warn_fold(r2: float, b: float, fold_error: float) -> None:
    """Warn when the impact phase of eq. (15) is inexact near a fold.

    ``fold_error`` is the phase error of a one-ulp error of ``c^2 + s^2`` (rad); the
    warning states ``_FOLD_ULPS`` times it, what c and s carry.
    """
    if fold_error > _FOLD_ERROR_WARN:  # (also tested by the caller on the fast path)
        warnings.warn(f"c^2 + s^2 = {r2:.17g} is within {(r2 - b * b) / r2:.2g} (relative) of "
                      f"b^2 = {b * b:.17g}: a fold of eq. (15), where the two roots merge; the "
                      f"impact phase is known only to about {_FOLD_ULPS * fold_error:.1g} rad",
                      NearFoldWarning,
                      stacklevel=3)


def _warn_low_impact_velocity(orbit: PeriodicOrbit, v_scale: float,
                              h2_error: float = 0.0) -> None:
    """Warn when G is inexact because the impact velocity is tiny (G ~ 1/h2, eq. 25).

    ``h2`` is a sum of terms of the size of the velocities of the motion
    (``v_scale = max(|x'|, omega |x|)`` at the impact), so it carries an absolute
    error of about ``eps * v_scale``; G inherits ``eps * v_scale / |h2|``.
    Only the single-point API warns: a branch passes through ``h2 = 0`` at a ZV point
    on purpose, and its detection evaluates G there. ``h2_error`` is the estimated
    relative error of ``h2`` itself (:func:`impactcont.orbit.dense.impact_velocity`):
    both its exact forms are small differences of large terms near a zero-velocity
    impact.
    """
    osc, h2 = orbit.oscillator, orbit.impact_velocity
    if h2_error > _H2_REL_ERROR_WARN:  # both forms lost digits: say how many
        warnings.warn(f"impact velocity h2 = {h2:.3g} is a small difference of large terms "
                      f"in eq. (12)-(15) (either exact form): it is known only to a relative "
                      f"error of about {min(h2_error, 1.0):.1g}, and G of eq. (25) ~ 1/h2 "
                      f"with it (root {orbit.root:+d}, delta={orbit.delta!r}, "
                      f"omega={osc.omega!r}, b={osc.b!r})", LowImpactVelocityWarning,
                      stacklevel=3)
    elif not abs(h2) * _H2_REL_ERROR_WARN >= _EPS * v_scale:
        warnings.warn(f"impact velocity h2 = {h2:.3g} is tiny against the velocity scale "
                      f"{v_scale:.3g} of the motion: G of eq. (25) grows like 1/h2 and may carry "
                      f"a relative error of about {_EPS * v_scale / max(abs(h2), 1e-300):.1g} "
                      f"(root {orbit.root:+d}, delta={orbit.delta!r}, omega={osc.omega!r}, "
                      f"b={osc.b!r})", LowImpactVelocityWarning, stacklevel=3)


def amplitude_squared(osc: ImpactOscillator, N: int) -> float:
    """``c^2 + s^2`` of eq. (14)-(15): motions exist iff it is ``>= b^2``."""
    from impactcont.kernel import closed_form

    osc = _check_oscillator(osc)
    if osc.general:
        c, s = general.amplitude(osc, _check_N(N))[:2]
        return c * c + s * s
    arrays = modal_arrays(osc)
    _, sc = closed_form.omega_setup(arrays.w, arrays.a, arrays.f, arrays.u0, arrays.ui0,
                                    arrays.eig_err, osc.R, osc.omega, _check_N(N))
    _warn_setup(osc, sc, stacklevel=2)
    return float(sc[5] ** 2 + sc[6] ** 2)
