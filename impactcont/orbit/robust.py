"""Robust stability of a periodic motion over a box of parameters, eq. (26)-(29).

Over the uncertain parameters ``q`` in a closed box ``Q`` the Jacobian of the
impact map is ``G(q) = G0 + dG(q)`` (eq. 26) with ``G0 = G(q0)`` Schur stable.
With ``P`` the solution of the discrete Lyapunov equation
``G0^T P G0 - P = -I`` (eq. 27) and the entrywise bound
``|dG(q)| <= eps Gamma`` (eq. 28), the motion is robustly stable over ``Q``
when ``eps < eps0`` (eq. 29; Theorem 3.2, after Kolla, Yedavalli & Farison
1989).

:func:`robust_bound` is the pure matrix part (eq. 27, 29);
:func:`robust_stability` follows one motion over the box, bounds ``dG`` and
applies the test: an N-1 motion of the closed form (eq. 11-16, G of eq. 25 exact at
every point), or any N-p motion (:class:`~impactcont.orbit.multi_impact.MultiImpactOrbit`:
p impacts, both stops, extra stops, any damping matrix), whose ``G`` at every point of
the box is that of the motion re-solved there by Newton. The bound of eq. (29) holds
for any matrix ``G0`` and perturbation pattern, so the test is the same for both.
"""

from __future__ import annotations

import dataclasses
import itertools
import logging
import math
from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np
import scipy.linalg
from scipy.optimize import minimize, minimize_scalar

from impactcont.errors import NoPeriodicMotionError, ParameterError
from impactcont.model.oscillator import ImpactOscillator
from impactcont.model.parameters import ModelParameter, model_parameter
from impactcont.model.stops import require_paper_stops
from impactcont.orbit.flow import Flow
from impactcont.orbit.multi_impact import MultiImpactOrbit, multi_impact_orbit
from impactcont.orbit.periodic import (
    PeriodicOrbit,
    impact_map_jacobian,
    orbit_at_phase,
    periodic_matrix,
    periodic_orbits,
)
from impactcont.progress import ProgressOption, reporter
from impactcont.threads import blas_limited
from impactcont.vocabulary import (
    CONTINUABLE_PARAMETERS,
    ELEMENT_FAMILIES,
    PARAMETERS,
    check_positive_integer,
    damping_kind,
    element_name,
)

__all__ = [
    "RobustStability",
    "check_robust_arguments",
    "lyapunov_matrix",
    "robust_bound",
    "robust_stability",
]

log = logging.getLogger(__name__)

#: Parameters of the vocabulary robust stability of an N-1 motion of the closed form cannot
#: vary: they move a lower stop, and the closed form has one stop above mass 1 (eq. 3). An
#: N-p motion (:class:`~impactcont.orbit.multi_impact.MultiImpactOrbit`) may vary them.
LOWER_STOP_PARAMETERS = ("b_low", "R_low", "gap")
# Relative (to the box width) x-tolerance of the 1-D bounded refinement. Near a
# smooth interior maximum the value error is of order xtol^2, far below 1e-12.
_XTOL_1D = 1e-9
_MAX_GRID_POINTS = 1_000_000


# ---------------------------------------------------------------------------------------------
# eq. (27), (29): the matrix bound
# ---------------------------------------------------------------------------------------------
def _square_matrix(name: str, value: Any) -> np.ndarray:
    try:
        a = np.array(value, dtype=float)
    except (TypeError, ValueError) as exc:
        raise TypeError(f"{name} must be a real square matrix (array_like); "
                        f"got {value!r}") from exc
    if a.ndim != 2 or a.shape[0] != a.shape[1] or a.shape[0] == 0:
        raise ParameterError(f"{name} must be a non-empty square matrix; got shape {a.shape}")
    if not np.all(np.isfinite(a)):
        raise ParameterError(f"{name} must be finite; got {a.tolist()}")
    return a


def _schur_stable_matrix(name: str, value: Any) -> np.ndarray:
    a = _square_matrix(name, value)
    rho = float(np.abs(np.linalg.eigvals(a)).max())
    if not rho < 1.0:
        raise ParameterError(f"{name} must be Schur stable (spectral radius < 1) for eq. (27) "
                             f"to have a positive definite solution; got spectral radius "
                             f"{rho:.12g}")
    return a


def lyapunov_matrix(G0: Any) -> np.ndarray:
    """Solution ``P`` of the discrete Lyapunov equation ``G0^T P G0 - P = -I`` (eq. 27).

    Parameters
    ----------
    G0 : array_like, shape (m, m)
        Schur stable matrix (spectral radius < 1).

    Returns
    -------
    ndarray, shape (m, m)
        The unique solution; symmetric positive definite.

    Raises
    ------
    ParameterError
        ``G0`` is not square, not finite or not Schur stable.
    """
    G0 = _schur_stable_matrix("G0", G0)
    # solve_discrete_lyapunov(a, q) solves a X a^H - X + q = 0; eq. (27) needs a = G0^T.
    P = scipy.linalg.solve_discrete_lyapunov(G0.T, np.eye(G0.shape[0]))
    return 0.5 * (P + P.T)


def _sigma(a: np.ndarray) -> float:
    """Largest singular value."""
    return float(np.linalg.norm(a, 2))


def robust_bound(G0: Any, Gamma: Any) -> float:
    """Largest admissible perturbation size ``eps0`` of eq. (29).

    With ``P`` from eq. (27),
    ``Gamma1 = (Gamma^T |P G0| + |G0^T P| Gamma) / 2``, ``Gamma2 = Gamma^T |P| Gamma``
    and ``sigma`` the largest singular value,

        eps0 = [sqrt(sigma(Gamma1)^2 + sigma(Gamma2)) - sigma(Gamma1)] / sigma(Gamma2).

    Every perturbation with ``|dG| <= eps Gamma`` entrywise and ``eps < eps0``
    keeps ``G0 + dG`` stable (Kolla, Yedavalli & Farison 1989; Theorem 3.2).

    Parameters
    ----------
    G0 : array_like, shape (m, m)
        Nominal Jacobian of the impact map (eq. 25), Schur stable.
    Gamma : array_like, shape (m, m)
        Entrywise perturbation pattern, all entries ``>= 0`` (eq. 28: ``theta / eps``,
        largest entry 1; any scaling is accepted, ``eps0`` then scales inversely).

    Returns
    -------
    float
        ``eps0 > 0``; ``inf`` when ``Gamma = 0`` (no perturbation).

    Raises
    ------
    ParameterError
        Shapes differ, an entry is not finite, an entry of ``Gamma`` is negative
        or ``G0`` is not Schur stable.

    Notes
    -----
    Evaluated as the algebraically equal ``1 / (sqrt(s1^2 + s2) + s1)``, which
    has no cancellation when ``s2 << s1^2``.

    Examples
    --------
    The paper's example (section 4) gives ``eps0 = 0.343455``.
    """
    G0 = _square_matrix("G0", G0)
    Gamma = _square_matrix("Gamma", Gamma)
    if Gamma.shape != G0.shape:
        raise ParameterError(f"Gamma must have the shape of G0 {G0.shape}; "
                             f"got shape {Gamma.shape}")
    if np.any(Gamma < 0):
        raise ParameterError(f"Gamma must be entrywise >= 0 (a bound on |dG|); got minimum entry "
                             f"{Gamma.min():.6g} in {Gamma.tolist()}")
    P = lyapunov_matrix(G0)
    gamma1 = 0.5 * (Gamma.T @ np.abs(P @ G0) + np.abs(G0.T @ P) @ Gamma)
    gamma2 = Gamma.T @ np.abs(P) @ Gamma
    s1, s2 = _sigma(gamma1), _sigma(gamma2)
    if s2 == 0.0:
        # P is positive definite, so Gamma^T |P| Gamma = 0 only for Gamma = 0.
        return math.inf
    return 1.0 / (math.sqrt(s1 * s1 + s2) + s1)


# ---------------------------------------------------------------------------------------------
# Following one motion over the parameter box
# ---------------------------------------------------------------------------------------------
def _real(what: str, value: Any) -> float:
    if isinstance(value, bool) or not isinstance(value, (int, float, np.integer, np.floating)):
        raise ParameterError(f"{what} must be a finite real number; got {value!r}")
    x = float(value)
    if not math.isfinite(x):
        raise ParameterError(f"{what} must be a finite real number; got {value!r}")
    return x


def _allowed(osc: ImpactOscillator) -> str:
    """The names :func:`robust_stability` can vary on `osc`, in words."""
    named = [k for k in CONTINUABLE_PARAMETERS if k not in LOWER_STOP_PARAMETERS
             and PARAMETERS[k].damping in (None, damping_kind(osc))]
    return (f"one of {named} or an element {list(ELEMENT_FAMILIES)} of the oscillator's "
            f"n={osc.n} masses, 1-based as the paper's masses (e.g. 'k2', 'M[1,2]', 'F[2]')")


def _check_name(osc: ImpactOscillator, name: Any) -> ModelParameter:
    """The parameter object of a key of `vary`, or a refusal naming what is allowed."""
    if not isinstance(name, str) or name not in PARAMETERS:
        hint = ""
        if isinstance(name, str) and name.replace(" ", "") == "F[0]":
            hint = " (F[j] is 1-based: 'F[1]' is the forcing of mass 1)"
        raise ParameterError(f"vary key {name!r} is not a parameter robust_stability can vary"
                             f"{hint}; allowed: {_allowed(osc)}")
    if name in LOWER_STOP_PARAMETERS:
        raise ParameterError(f"vary key {name!r} moves a lower stop; robust_stability follows "
                             "an N-1 motion of the closed form, one stop above mass 1 (eq. 3), "
                             f"and cannot vary it; allowed: {_allowed(osc)}")
    return model_parameter(osc, name, "vary key")


def _check_motion_name(osc: ImpactOscillator, name: Any) -> ModelParameter:
    """The parameter object of a key of `vary` for an N-p motion: every parameter of the
    model (:func:`~impactcont.model.parameters.model_parameter`, lower and extra stops
    included), or its refusal naming what is allowed."""
    return model_parameter(osc, name, "vary key")


def _target(param: ModelParameter) -> tuple[str, str, tuple[int, ...]]:
    """What `param` sets on the model: ``(attribute, family, entry)``; two parameters of one
    attribute commute only when they are of one family and set different entries."""
    element = element_name(param.name)
    if element is None:
        return ("F" if param.name == "F0" else param.name), param.name, ()
    family, indices = element
    attribute = "F" if family == "F[j]" else family[0].upper()
    return attribute, family, tuple(sorted(indices))


def _check_independent(params: Sequence[ModelParameter]) -> None:
    """Refuse two parameters whose values depend on the order they are set in (``F0`` and
    ``F[2]`` both set F; ``k2`` and ``K[2,3]`` both an entry of K; ``M[1,2]`` and
    ``M[2,1]`` are one entry): a point of the box would not be the values it names."""
    seen: dict[str, tuple[str, str, tuple[int, ...]]] = {}
    for param in params:
        attribute, family, entry = _target(param)
        other = seen.get(attribute)
        if other is not None and (other[1] != family or other[2] == entry):
            raise ParameterError(
                f"vary keys {other[0]!r} and {param.name!r} both set {attribute} "
                f"({'the same entry' if other[1] == family else 'overlapping entries'}), so a "
                f"point of the box would depend on the order they are set in; vary one of "
                f"them (or entries of one family, e.g. 'F[1]' and 'F[2]', 'k1' and 'k2')")
        if other is None:
            seen[attribute] = (param.name, family, entry)


def _check_vary(osc: ImpactOscillator, vary: Any, check_name: Any = _check_name
                ) -> tuple[dict[str, tuple[float, float]], list[ModelParameter]]:
    if not isinstance(vary, Mapping) or not vary:
        raise ParameterError(f"vary must be a non-empty dict {{name: (lo, hi)}}; got {vary!r}")
    out: dict[str, tuple[float, float]] = {}
    params = []
    for name, interval in vary.items():
        params.append(check_name(osc, name))
        try:
            lo_raw, hi_raw = interval
        except (TypeError, ValueError):
            raise ParameterError(f"vary[{name!r}] must be an interval (lo, hi); "
                                 f"got {interval!r}") from None
        lo = _real(f"vary[{name!r}] lower end", lo_raw)
        hi = _real(f"vary[{name!r}] upper end", hi_raw)
        if not lo < hi:
            raise ParameterError(f"vary[{name!r}] must satisfy lo < hi; got ({lo!r}, {hi!r})")
        info = params[-1].info
        for end in (lo, hi):
            if not info.contains(end):
                raise ParameterError(f"vary[{name!r}] = {(lo, hi)!r} leaves the admissible "
                                     f"parameters: {name} must be {info.allowed}; got {end!r}")
        out[name] = (lo, hi)
    _check_independent(params)
    return out, params


def _check_nominal(vary: dict[str, tuple[float, float]], nominal: Any) -> dict[str, float]:
    centre = {k: 0.5 * (lo + hi) for k, (lo, hi) in vary.items()}
    if nominal is None:
        return centre
    if not isinstance(nominal, Mapping):
        raise ParameterError(f"nominal must be None (box centre) or a dict {{name: value}}; "
                             f"got {nominal!r}")
    extra = sorted(set(nominal) - set(vary), key=str)
    if extra:
        raise ParameterError(f"nominal names parameters that are not in vary: {extra}; "
                             f"allowed: {sorted(vary)} (fix the others with osc.replace)")
    out = dict(centre)
    for name, value in nominal.items():
        x = _real(f"nominal[{name!r}]", value)
        lo, hi = vary[name]
        if not lo <= x <= hi:
            raise ParameterError(f"nominal[{name!r}] must lie in the box [{lo!r}, {hi!r}]; "
                                 f"got {x!r}")
        out[name] = x
    return out


def _fmt_params(params: Mapping[str, float]) -> str:
    return ", ".join(f"{k}={v:.12g}" for k, v in params.items())


def _oscillator_at(osc: ImpactOscillator, params: Sequence[ModelParameter],
                   q: tuple[float, ...]) -> ImpactOscillator:
    """``osc`` with the parameters `params` set to the values ``q``, one after the other
    (they commute: :func:`_check_independent`; validated by the oscillator)."""
    for param, value in zip(params, q, strict=True):
        osc = param.at(osc, value)
    return osc


class _Follower:
    """Evaluates the followed motion (fixed root sign of eq. 15) at parameter points."""

    def __init__(self, osc: ImpactOscillator, N: int, params: list[ModelParameter],
                 root: int, G0: np.ndarray) -> None:
        self.osc = osc
        self.N = N
        self.params_ = params
        self.names = [p.name for p in params]
        self.root = root
        self.G0 = G0
        self.cache: dict[tuple[float, ...], np.ndarray] = {}
        self.evaluations = 0

    def params(self, q: tuple[float, ...]) -> dict[str, float]:
        return dict(zip(self.names, q, strict=True))

    def oscillator(self, q: tuple[float, ...]) -> ImpactOscillator:
        return _oscillator_at(self.osc, self.params_, q)

    def _fail(self, q: tuple[float, ...], why: str) -> NoPeriodicMotionError:
        return NoPeriodicMotionError(
            f"the followed N={self.N} motion (root {self.root:+d} of eq. 15) {why} at "
            f"{_fmt_params(self.params(q))}, inside the box: robust stability over the box "
            f"is not defined; shrink the box")

    def _phase(self, q: tuple[float, ...]):
        osc = self.oscillator(q)
        flow = Flow(osc)
        S, DPhi, T = periodic_matrix(flow, self.N)
        c, s = S[0]
        r2 = c * c + s * s
        b = osc.b
        disc = r2 - b * b
        if not (r2 > 0.0 and disc >= 0.0):
            raise self._fail(q, f"does not exist (c^2 + s^2 = {r2:.6g} < b^2 = {b * b:.6g})")
        r = math.sqrt(disc)
        sin_d = (b * s + self.root * c * r) / r2
        cos_d = (b * c - self.root * s * r) / r2
        return osc, flow, S, DPhi, T, math.atan2(sin_d, cos_d)

    def jacobian(self, q: tuple[float, ...]) -> np.ndarray:
        """G(q) (eq. 25); checks existence and a positive impact velocity."""
        q = tuple(float(v) for v in q)
        G = self.cache.get(q)
        if G is None:
            self.evaluations += 1
            _, flow, S, DPhi, T, delta = self._phase(q)
            state = S @ np.array([math.cos(delta), math.sin(delta)])
            G, h2 = impact_map_jacobian(flow, state, delta, T, DPhi)
            if not h2 > 0:
                raise self._fail(q, f"is not physical (impact velocity {h2:.3g} <= 0)")
            G.setflags(write=False)
            self.cache[q] = G
        return G

    def check_physical(self, q: tuple[float, ...]) -> PeriodicOrbit:
        """Full eq. (16) check (no contact inside the period) and G at q."""
        q = tuple(float(v) for v in q)
        osc, _, _, _, _, delta = self._phase(q)
        orbit = orbit_at_phase(osc, self.N, delta, root=self.root)
        if not orbit.physical:
            raise self._fail(q, f"is not physical ({orbit.reason})")
        if q not in self.cache:
            self.evaluations += 1
            G = orbit.G.copy()
            G.setflags(write=False)
            self.cache[q] = G
        return orbit


def _select_nominal_orbit(osc: ImpactOscillator, N: int, root: int | None,
                          nominal: dict[str, float]) -> PeriodicOrbit:
    where = _fmt_params(nominal)
    orbits = periodic_orbits(osc, N)
    if not orbits:
        raise NoPeriodicMotionError(f"no N={N} motion exists at the nominal parameters "
                                    f"({where}): c^2 + s^2 < b^2 in eq. (15)")
    listing = "; ".join(f"root {o.root:+d}: physical={o.physical}, rho={o.spectral_radius:.6g}"
                        + (f" ({o.reason})" if o.reason else "") for o in orbits)
    if root is not None:
        chosen = [o for o in orbits if o.root == root]
        if not chosen:
            raise NoPeriodicMotionError(f"root {root:+d} of eq. (15) does not exist at the "
                                        f"nominal parameters ({where}); roots: {listing}")
        orbit = chosen[0]
        if not orbit.physical:
            raise NoPeriodicMotionError(f"root {root:+d} of eq. (15) is not a physical motion at "
                                        f"the nominal parameters ({where}): {orbit.reason}")
        return orbit
    good = [o for o in orbits if o.physical and o.stable]
    if not good:
        raise NoPeriodicMotionError(f"no physical, stable N={N} motion at the nominal "
                                    f"parameters ({where}); roots: {listing}. Pass root=+1 or "
                                    f"-1 to follow a particular one")
    if len(good) > 1:
        raise ParameterError(f"two physical, stable N={N} motions at the nominal parameters "
                             f"({where}); choose one with root=+1 or root=-1")
    return good[0]


@dataclasses.dataclass(frozen=True, eq=False)
class RobustStability:
    """Result of :func:`robust_stability` (eq. 26-29).

    Attributes
    ----------
    N : int
        Forcing periods per impact.
    root : int
        Sign (+1/-1) of the square root of eq. (15) followed over the box; 0 for an
        N-p motion.
    vary : dict of str to (float, float)
        The box ``Q``: parameter name -> ``(lo, hi)``.
    nominal : dict of str to float
        ``q0``.
    orbit : PeriodicOrbit or MultiImpactOrbit
        The motion at ``q0``.
    G0 : ndarray, shape (2n, 2n)
        ``G(q0)`` (eq. 25; for an N-p motion the product of its flights' ``G_k``).
    P : ndarray, shape (2n, 2n) or None
        Solution of eq. (27); None when ``G0`` is not Schur stable.
    theta : ndarray, shape (2n, 2n)
        ``theta_ij = max_Q |dG_ij|`` (eq. 28), the larger of grid and refined maxima.
    grid_theta : ndarray, shape (2n, 2n)
        The maxima over the sampled grid alone.
    refinement : ndarray, shape (2n, 2n)
        ``theta - grid_theta >= 0``: what the local refinement added per entry.
    refinement_gain : float
        ``max(refinement)``.
    argmax : dict of (int, int) to dict of str to float
        Per entry ``(i, j)``, the parameter values where ``theta_ij`` is attained.
    epsilon : float
        ``max_ij theta_ij`` (eq. 28).
    Gamma : ndarray, shape (2n, 2n)
        ``theta / epsilon`` (zeros when ``epsilon = 0``).
    epsilon0 : float
        Bound of eq. (29); NaN when ``G0`` is not Schur stable.
    robust : bool
        ``G0`` Schur stable and ``epsilon < epsilon0`` (Theorem 3.2).
    samples : int
        Grid points per parameter.
    evaluations : int
        Number of distinct parameter points at which G was computed.
    message : str
        The verdict in words.
    p : int
        Impacts per period of the motion (1 for the closed form).
    """

    N: int
    root: int
    vary: dict[str, tuple[float, float]]
    nominal: dict[str, float]
    orbit: PeriodicOrbit | MultiImpactOrbit
    G0: np.ndarray
    P: np.ndarray | None
    theta: np.ndarray
    grid_theta: np.ndarray
    refinement: np.ndarray
    refinement_gain: float
    argmax: dict[tuple[int, int], dict[str, float]]
    epsilon: float
    Gamma: np.ndarray
    epsilon0: float
    robust: bool
    samples: int
    evaluations: int
    message: str
    p: int = 1

    @property
    def margin(self) -> float:
        """``epsilon0 / epsilon``: > 1 means robustly stable (inf when epsilon = 0)."""
        if self.epsilon == 0.0:
            return math.inf
        return self.epsilon0 / self.epsilon

    def _motion_words(self) -> str:
        if isinstance(self.orbit, MultiImpactOrbit):
            return f"N={self.N}, p={self.p} motion (pattern {self.orbit.pattern})"
        return f"N={self.N} motion (root {self.root:+d})"

    def summary(self) -> str:
        """Multi-line human-readable report."""
        def mat(a: np.ndarray) -> str:
            return np.array2string(a, precision=6, suppress_small=False, floatmode="fixed",
                                   max_line_width=120)
        box = ", ".join(f"{k} in [{lo:.6g}, {hi:.6g}]" for k, (lo, hi) in self.vary.items())
        i, j = np.unravel_index(int(np.argmax(self.theta)), self.theta.shape)
        lines = [
            f"Robust stability of the {self._motion_words()} over {box}",
            f"nominal: {_fmt_params(self.nominal)}; rho(G0) = {self.orbit.spectral_radius:.6g}",
            "G0 =", mat(self.G0),
            "Gamma =", mat(self.Gamma),
            f"epsilon  = {self.epsilon:.6f} (entry ({i}, {j}) at "
            f"{_fmt_params(self.argmax[(int(i), int(j))])})",
            f"epsilon0 = {self.epsilon0:.6f}",
            f"max over a grid of {self.samples} points per parameter, refined locally; "
            f"largest refinement gain {self.refinement_gain:.3g}",
            f"robust: {self.robust} -- {self.message}",
        ]
        return "\n".join(lines)

    def __repr__(self) -> str:
        box = ", ".join(f"{k}=[{lo:.6g}, {hi:.6g}]" for k, (lo, hi) in self.vary.items())
        which = (f"p={self.p}, pattern={self.orbit.pattern}" if isinstance(
            self.orbit, MultiImpactOrbit) else f"root={self.root:+d}")
        return (f"RobustStability(N={self.N}, {which}, {box}, "
                f"epsilon={self.epsilon:.6g}, epsilon0={self.epsilon0:.6g}, "
                f"robust={self.robust}, refinement_gain={self.refinement_gain:.3g})")


def _refine(follower: _Follower, i: int, j: int, axes: list[np.ndarray],
            index: tuple[int, ...], lo: np.ndarray, hi: np.ndarray
            ) -> tuple[float, tuple[float, ...]]:
    """Bounded local maximisation of ``|dG_ij|`` in the grid cells around ``index``."""
    G0 = follower.G0

    def value(q: tuple[float, ...]) -> float:
        return abs(float(follower.jacobian(q)[i, j] - G0[i, j]))

    sub_lo = np.array([ax[max(k - 1, 0)] for ax, k in zip(axes, index, strict=True)])
    sub_hi = np.array([ax[min(k + 1, ax.size - 1)] for ax, k in zip(axes, index, strict=True)])
    if len(axes) == 1:
        res = minimize_scalar(lambda x: -value((x,)), bounds=(sub_lo[0], sub_hi[0]),
                              method="bounded",
                              options={"xatol": _XTOL_1D * (hi[0] - lo[0])})
        q = (float(res.x),)
        return value(q), q
    # Several parameters: L-BFGS-B in coordinates scaled to the box, from the grid point.
    width = hi - lo

    def to_q(u: np.ndarray) -> tuple[float, ...]:
        return tuple(float(v) for v in np.clip(lo + u * width, sub_lo, sub_hi))

    u0 = (np.array([ax[k] for ax, k in zip(axes, index, strict=True)]) - lo) / width
    bounds = list(zip((sub_lo - lo) / width, (sub_hi - lo) / width, strict=True))
    res = minimize(lambda u: -value(to_q(u)), u0, method="L-BFGS-B", bounds=bounds,
                   options={"ftol": 1e-15, "gtol": 1e-12, "maxiter": 200})
    q = to_q(res.x)
    return value(q), q


def check_robust_arguments(osc: ImpactOscillator, N: int, vary: Mapping[str, tuple[float, float]],
                           *, nominal: Mapping[str, float] | None = None,
                           root: int | None = None, samples: int = 33
                           ) -> tuple[int, int, dict[str, tuple[float, float]], dict[str, float]]:
    """Validate the arguments of :func:`robust_stability` (same names) before any work.

    One check for two callers, :func:`robust_stability` and ``impactcont run --check`` on a
    scene's entry: an input is refused with the same message by both.

    Parameters
    ----------
    osc : ImpactOscillator
        The system.
    N : int
        Forcing periods of the N-1 motion.
    vary : dict of str to (float, float)
        The box ``Q``.
    nominal : dict of str to float, optional
        ``q0`` (default the box centre).
    root : {None, +1, -1}, optional
        Which root of eq. (15) to follow.
    samples : int, optional
        Grid points per parameter.

    Returns
    -------
    N : int
    samples : int
    box : dict of str to (float, float)
        `vary` with float ends.
    q0 : dict of str to float
        The nominal point, every parameter of the box (the centre where not given).

    Raises
    ------
    TypeError
        `osc` is not an :class:`ImpactOscillator`.
    ParameterError
        `N` not an integer >= 1; `root` not None, +1 or -1; `samples` not an integer
        >= 2 or a grid of more than 1000000 points; `vary` not a non-empty mapping of
        parameters robust stability can vary (every name
        :func:`~impactcont.model.parameters.model_parameter` accepts for `osc` except those
        of a lower stop, :data:`LOWER_STOP_PARAMETERS`; elements 1-based, ``"F[j]"`` of a
        real F; a damping parameter of the oscillator's damping model; no two that set one
        entry or overlapping entries, as ``F0`` and ``F[2]``) to finite intervals
        ``lo < hi`` inside each parameter's range; `nominal` naming a parameter not in
        `vary` or a value outside its interval; an end of an interval (the others at
        nominal) that leaves the oscillator's admissible parameters (an oscillator other
        than the paper's form, one stop above mass 1, is refused by
        :func:`robust_stability` itself, and by a scene's closed-form check).
    """
    return _check_arguments(osc, N, vary, nominal, root, samples, _check_name)


def _check_arguments(osc: ImpactOscillator, N: int, vary: Mapping[str, tuple[float, float]],
                     nominal: Mapping[str, float] | None, root: int | None, samples: int,
                     check_name: Any
                     ) -> tuple[int, int, dict[str, tuple[float, float]], dict[str, float]]:
    """:func:`check_robust_arguments` with the names of `vary` checked by `check_name`
    (:func:`_check_name` for the closed form, :func:`_check_motion_name` for an N-p
    motion)."""
    if not isinstance(osc, ImpactOscillator):
        raise TypeError(f"osc must be an ImpactOscillator; got {type(osc).__name__}")
    N = check_positive_integer("N", N, "impact every N forcing periods")
    if root is not None and (isinstance(root, bool) or root not in (1, -1)):
        raise ParameterError(f"root must be None, +1 or -1 (sign in eq. 15); got {root!r}")
    if (isinstance(samples, bool) or not isinstance(samples, (int, np.integer))
            or samples < 2):
        raise ParameterError(f"samples must be an integer >= 2 (grid points per parameter, "
                             f"both ends included); got {samples!r}")
    samples = int(samples)
    box, params = _check_vary(osc, vary, check_name)
    if samples ** len(box) > _MAX_GRID_POINTS:
        raise ParameterError(f"samples={samples} for {len(box)} parameters gives "
                             f"{samples ** len(box)} grid points; at most "
                             f"{_MAX_GRID_POINTS} allowed")
    q0 = _check_nominal(box, nominal)
    names = list(box)
    # The box must be admissible: every interval end, the others at nominal.
    for k, name in enumerate(names):
        for end in box[name]:
            q = [q0[m] for m in names]
            q[k] = end
            try:
                _oscillator_at(osc, params, tuple(q))
            except ParameterError as exc:
                raise ParameterError(f"vary[{name!r}] = {box[name]!r} leaves the admissible "
                                     f"parameters: {exc}") from None
    return N, samples, box, q0


def _over_box(follower: Any, orbit: PeriodicOrbit | MultiImpactOrbit, G0: np.ndarray,
              names: list[str], lo: np.ndarray, hi: np.ndarray, samples: int,
              progress: ProgressOption, indices: list[tuple[int, ...]]) -> dict[str, Any]:
    """The grid, the refined maxima of eq. (28) and the test of eq. (29) for a followed
    motion (`follower`: :class:`_Follower` or :class:`_MotionFollower`), the grid points
    visited in the order of `indices`; the fields of :class:`RobustStability` they give."""
    # Grid (includes every vertex), with the full physical check at each point.
    axes = [np.linspace(lo[k], hi[k], samples) for k in range(len(names))]
    dG = np.empty((len(indices), *G0.shape))
    with reporter(progress, "robust stability", total=len(indices) + G0.size,
                  unit="steps") as rep:
        for p, idx in enumerate(indices):
            q = tuple(float(axes[k][idx[k]]) for k in range(len(names)))
            follower.check_physical(q)
            dG[p] = np.abs(follower.jacobian(q) - G0)
            rep.advance()
        best = np.argmax(dG, axis=0)
        grid_theta = np.max(dG, axis=0)

        theta = grid_theta.copy()
        argmax: dict[tuple[int, int], dict[str, float]] = {}
        for i, j in itertools.product(range(G0.shape[0]), repeat=2):
            idx = indices[int(best[i, j])]
            q_grid = tuple(float(axes[k][idx[k]]) for k in range(len(names)))
            q_best = q_grid
            if grid_theta[i, j] > 0.0:
                val, q_ref = _refine(follower, i, j, axes, idx, lo, hi)
                if val > grid_theta[i, j]:
                    follower.check_physical(q_ref)
                    theta[i, j], q_best = val, q_ref
            argmax[(i, j)] = follower.params(q_best)
            rep.advance()
    refinement = theta - grid_theta
    refinement_gain = float(refinement.max())
    epsilon = float(theta.max())
    Gamma = theta / epsilon if epsilon > 0 else np.zeros_like(theta)

    if orbit.stable:
        P = lyapunov_matrix(G0)
        epsilon0 = robust_bound(G0, Gamma)
        robust = epsilon < epsilon0
        message = (f"epsilon = {epsilon:.6g} {'<' if robust else '>='} epsilon0 = "
                   f"{epsilon0:.6g}: " + ("robustly stable over the box (Theorem 3.2)"
                                          if robust else "the sufficient condition of eq. (29) "
                                          "fails; robust stability is not established"))
    else:
        P, epsilon0, robust = None, math.nan, False
        message = (f"G0 is not Schur stable (rho = {orbit.spectral_radius:.6g} >= 1): the "
                   f"nominal motion is unstable")
    for a in (theta, grid_theta, refinement, Gamma):
        a.setflags(write=False)
    if P is not None:
        P.setflags(write=False)
    log.debug("robust_stability: %d evaluations, epsilon=%.6g, epsilon0=%.6g",
              follower.evaluations, epsilon, epsilon0)
    return {"P": P, "theta": theta, "grid_theta": grid_theta, "refinement": refinement,
            "refinement_gain": refinement_gain, "argmax": argmax, "epsilon": epsilon,
            "Gamma": Gamma, "epsilon0": epsilon0, "robust": robust, "message": message}


class _MotionFollower:
    """Follows an N-p motion over the box: at each parameter point the motion re-solved by
    Newton (:func:`~impactcont.orbit.multi_impact.multi_impact_orbit`, its impact pattern
    kept) from the motion solved at the nearest point so far (in coordinates scaled to the
    box), with the motion's whole physical check."""

    def __init__(self, motion: MultiImpactOrbit, params: list[ModelParameter],
                 width: np.ndarray) -> None:
        self.osc = motion.oscillator
        self.N, self.p, self.pattern = motion.N, motion.p, motion.pattern
        self.params_ = params
        self.names = [p.name for p in params]
        self.width = width
        # the motion given, at its own parameter values: the first guess
        self.points = [np.array([p.value(self.osc) for p in params])]
        self.motions = [motion]
        self.solved: dict[tuple[float, ...], MultiImpactOrbit] = {}
        self.G0: np.ndarray | None = None
        self.evaluations = 0

    def params(self, q: tuple[float, ...]) -> dict[str, float]:
        return dict(zip(self.names, q, strict=True))

    def _fail(self, q: tuple[float, ...], why: str) -> NoPeriodicMotionError:
        return NoPeriodicMotionError(
            f"the followed N={self.N}, p={self.p} motion (pattern {self.pattern}) {why} at "
            f"{_fmt_params(self.params(q))}, inside the box: robust stability over the box "
            f"is not defined; shrink the box")

    def motion(self, q: tuple[float, ...]) -> MultiImpactOrbit:
        """The motion at q, physical (else :class:`NoPeriodicMotionError`)."""
        q = tuple(float(v) for v in q)
        found = self.solved.get(q)
        if found is not None:
            return found
        gaps = np.abs((np.array(self.points) - np.array(q)) / self.width).max(axis=1)
        k = int(np.argmin(gaps))
        guess = self.motions[k]
        try:
            found = multi_impact_orbit(_oscillator_at(self.osc, self.params_, q), self.N,
                                       self.p, guess, pattern=self.pattern)
        except NoPeriodicMotionError as exc:
            raise self._fail(q, f"is not found by Newton from the motion at "
                                f"{_fmt_params(self.params(tuple(self.points[k])))} "
                                f"({exc})") from None
        self.evaluations += 1
        if not found.physical:
            raise self._fail(q, f"is not physical ({found.reason})")
        found.G.setflags(write=False)
        self.solved[q] = found
        self.points.append(np.array(q))
        self.motions.append(found)
        return found

    def jacobian(self, q: tuple[float, ...]) -> np.ndarray:
        """G(q) of the motion (the product of its flights' G_k, eq. 25)."""
        return self.motion(q).G

    def check_physical(self, q: tuple[float, ...]) -> MultiImpactOrbit:
        return self.motion(q)


def _motion_robust_stability(motion: MultiImpactOrbit, N: int | None,
                             vary: Mapping[str, tuple[float, float]] | None, *,
                             nominal: Mapping[str, float] | None, root: int | None,
                             samples: int, progress: ProgressOption) -> RobustStability:
    """:func:`robust_stability` of an N-p motion (see its Notes)."""
    if N is not None and (isinstance(N, bool) or N != motion.N):
        raise ParameterError(f"N must be None or the motion's own N={motion.N} for an N-p "
                             f"motion; got {N!r}")
    if root is not None:
        raise ParameterError(f"root picks a root of eq. (15) of the N-1 closed form; an N-p "
                             f"motion is followed as given: root must be None; got {root!r}")
    osc = motion.oscillator
    N, samples, box, q0 = _check_arguments(osc, motion.N, vary, nominal, None, samples,
                                           _check_motion_name)
    names = list(box)
    params = [model_parameter(osc, name, "vary key") for name in names]  # checked above
    lo = np.array([box[k][0] for k in names])
    hi = np.array([box[k][1] for k in names])
    follower = _MotionFollower(motion, params, hi - lo)
    nominal_q = tuple(q0[m] for m in names)
    try:
        orbit = follower.motion(nominal_q)
    except NoPeriodicMotionError as exc:
        raise NoPeriodicMotionError(f"the N={N}, p={motion.p} motion at the nominal parameters "
                                    f"({_fmt_params(q0)}): {exc}") from None
    G0 = orbit.G
    follower.G0 = G0
    # the grid outwards from the grid point nearest q0: each point has a solved neighbour
    start = [int(np.argmin(np.abs(np.linspace(lo[k], hi[k], samples) - nominal_q[k])))
             for k in range(len(names))]
    indices = sorted(itertools.product(range(samples), repeat=len(names)),
                     key=lambda idx: sum(abs(i - s) for i, s in zip(idx, start, strict=True)))
    fields = _over_box(follower, orbit, G0, names, lo, hi, samples, progress, indices)
    return RobustStability(N=N, root=0, vary=box, nominal=q0, orbit=orbit, G0=G0,
                           samples=samples, evaluations=follower.evaluations, p=motion.p,
                           **fields)


@blas_limited
def robust_stability(osc: ImpactOscillator | MultiImpactOrbit, N: int | None = None,
                     vary: Mapping[str, tuple[float, float]] | None = None, *,
                     nominal: Mapping[str, float] | None = None, root: int | None = None,
                     samples: int = 33, progress: ProgressOption = None) -> RobustStability:
    """Test the robust stability of a periodic motion over a parameter box (eq. 26-29).

    Parameters
    ----------
    osc : ImpactOscillator or MultiImpactOrbit
        The system, whose N-1 motion of the closed form is followed (``N`` and ``root``
        pick it); or an N-p motion (:func:`~impactcont.orbit.multi_impact.
        multi_impact_orbit`: p impacts, one or two stops, extra stops, any damping),
        followed over the box by re-solving it (see Notes). Parameters not in ``vary``
        keep their values from the oscillator (the motion's).
    N : int
        One impact every N forcing periods; for an N-p motion None or its own ``N``.
    vary : dict of str to (float, float)
        The box ``Q``: each uncertain parameter with its interval ``(lo, hi)``,
        ``lo < hi``. Names: the parameter objects' (:func:`~impactcont.model.parameters.
        model_parameter`): ``b``, ``omega``, ``R``, ``F0``, ``eta`` (paper's damping) or
        ``alpha``/``beta`` (Rayleigh damping; the one the oscillator uses), and the
        elements, 1-based as the paper's masses: masses ``"m1"``, springs ``"k2"``,
        dampers ``"c1"`` (a damping matrix C), matrix entries ``"M[1,2]"``,
        ``"K[1,2]"``, ``"C[1,2]"`` and the forcing of one mass ``"F[2]"``. Not the
        parameters of a lower stop (``b_low``, ``R_low``, ``gap``) for the closed form;
        an N-p motion may vary every parameter of its model, those of its lower and extra
        stops included (``gap[A]``, ``R[A]``). The whole box must be admissible for the
        oscillator (e.g. ``0 <= R <= 1``, ``omega > 0``, K positive definite).
    nominal : dict of str to float, optional
        ``q0``; each value inside its interval. Parameters not given (or all,
        by default) take the box centre; the paper takes ``b0 = 0.6`` for
        ``b in [0.2, 1.0]``.
    root : {None, +1, -1}, optional
        Which root of eq. (15) to follow (:attr:`PeriodicOrbit.root`). By
        default the unique physical, stable motion at ``q0``. None for an N-p motion
        (the motion given is the one followed).
    samples : int, optional
        Grid points per parameter (including both ends), ``>= 2``; an odd number
        also samples the centre. The grid has ``samples ** len(vary)`` points.
    progress : None, bool or callable
        A progress bar on stderr over the grid points and the refined entries of
        ``dG`` (``None``: when stderr is a terminal, after 2 s; ``True``: always;
        ``False``: never) or a callable receiving a
        :class:`~impactcont.progress.Progress` record after each
        (:mod:`impactcont.progress`). A call longer than a minute logs a line a minute.

    Returns
    -------
    RobustStability
        ``G0``, ``P`` (eq. 27), ``theta``, ``epsilon``, ``Gamma`` (eq. 28),
        ``epsilon0`` (eq. 29), the verdict ``robust`` and where each maximum was
        found.

    Raises
    ------
    ParameterError
        Bad ``vary``, ``nominal``, ``root``, ``samples``, a box that leaves
        the oscillator's admissible parameters (:func:`check_robust_arguments`), or
        an oscillator other than the paper's form (one stop above mass 1) for the
        closed form; for an N-p motion an ``N`` other than its own or a ``root``.
    NoPeriodicMotionError
        The motion does not exist or is not physical at ``q0`` (or, with
        ``root=None``, no physical stable motion exists there), or it ceases to
        exist (``c^2 + s^2 < b^2``; for an N-p motion: Newton does not converge from
        the neighbouring point) or to be physical (impact velocity ``<= 0``
        or contact inside the period, eq. 16) somewhere in the box. Robust
        stability over the box is then undefined, so no number is returned.

    Notes
    -----
    *The motion followed.* The root sign ``sigma`` of eq. (15) picked at
    ``q0`` is kept over the box; each root is continuous in the parameters
    while ``c^2 + s^2 > b^2``, so this follows one motion.

    *How the maximum of eq. (28) is found, and how sure it is.* ``|dG_ij(q)|``
    is evaluated exactly (closed form) on a tensor grid of ``samples`` points
    per parameter that includes every vertex of the box. Then, for every
    entry separately, a bounded local maximisation starts from the best grid
    point, restricted to the grid cells adjacent to it: Brent's bounded method
    (``minimize_scalar(method='bounded')``) for one parameter, L-BFGS-B in
    box-scaled coordinates for several. ``theta_ij`` is the larger of the grid
    and refined values, so it is never below the grid maximum, and it is a
    true value of ``|dG_ij|`` attained at ``argmax[(i, j)]``. The result is
    the global maximum unless ``|dG_ij|`` has a higher peak narrower than the
    grid spacing away from the best grid point; ``refinement`` (and
    ``refinement_gain``) shows how much the refinement added to the grid value,
    a small gain meaning the grid already resolved the peak. Increase
    ``samples`` to be surer. Existence and a positive impact velocity are
    checked at every evaluation; the full contact check of eq. (16) at every
    grid point and at every refined argmax.

    *An N-p motion.* ``G(q)`` is the motion's own (``G_{p-1} ... G_0``, the product
    of the flights' Jacobians, eq. 25 per flight) re-solved at ``q`` by
    :func:`~impactcont.orbit.multi_impact.multi_impact_orbit` with the motion's impact
    pattern, Newton starting from the motion already solved at the nearest point
    (the grid is visited outwards from the grid point nearest ``q0``, so that point is a
    grid neighbour). No derivative of G in the parameters is needed: eq. (28) takes
    ``dG(q) = G(q) - G0`` itself, as for the closed form, and it is exact to the
    shooting's tolerance (``1e-12`` relative on the unknowns). The whole check of the
    motion (every flight time, impact velocity and clearance against every stop) is
    made at every point. Each evaluation is one Newton solve (about 1 ms for a 2-2 motion
    of the paper's system): one parameter, 9 grid points and the refinement of the 16
    entries (63 solves) take about 0.3 s, as the closed form over the same box.
    """
    if isinstance(osc, MultiImpactOrbit):
        return _motion_robust_stability(osc, N, vary, nominal=nominal, root=root,
                                        samples=samples, progress=progress)
    N, samples, box, q0 = check_robust_arguments(osc, N, vary, nominal=nominal, root=root,
                                                 samples=samples)
    require_paper_stops(osc, "robust_stability")  # the N-1 closed form: one stop, mass 1
    names = list(box)
    params = [model_parameter(osc, name, "vary key") for name in names]  # checked above
    lo = np.array([box[k][0] for k in names])
    hi = np.array([box[k][1] for k in names])
    nominal_q = tuple(q0[m] for m in names)
    orbit = _select_nominal_orbit(_oscillator_at(osc, params, nominal_q), N, root, q0)
    G0 = orbit.G.copy()
    G0.setflags(write=False)
    follower = _Follower(osc, N, params, orbit.root, G0)
    follower.cache[nominal_q] = G0

    fields = _over_box(follower, orbit, G0, names, lo, hi, samples, progress,
                       list(itertools.product(range(samples), repeat=len(names))))
    return RobustStability(N=N, root=orbit.root, vary=box, nominal=q0, orbit=orbit, G0=G0,
                           samples=samples, evaluations=follower.evaluations, **fields)
