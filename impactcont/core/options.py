"""Options of the pseudo-arclength continuation."""

from __future__ import annotations

import dataclasses
import functools
import inspect
import math
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from numbers import Integral, Real
from typing import Any

from impactcont.errors import ParameterError

__all__ = [
    "DRIVER_DEFAULTS",
    "ContinuationOptionError",
    "ContinuationOptions",
    "driver_options",
    "option_keywords",
]


class _Unset:
    """Marks an option not given: it takes its default (the step sizes adapt to ds_max)."""

    def __repr__(self) -> str:
        return "<default>"


_UNSET: Any = _Unset()
_CLASS_DEFAULTS: dict[str, Any] = {
    "bounds": None, "ds": 0.01, "ds_min": 1e-6, "ds_max": 0.1, "newton_tol": 1e-10,
    "newton_max_iter": 10, "max_points": 1000, "direction": 1, "both_directions": False,
    "max_angle": 0.3, "target_newton_iter": 3, "theta": 0.5,
}

#: The defaults of every driver (:func:`impactcont.continuation`,
#: :func:`impactcont.multi_impact_continuation`, :func:`impactcont.curve` and the
#: switches); the Newton tolerance is the problem's (its residual's accuracy).
DRIVER_DEFAULTS: Mapping[str, Any] = {"ds": 0.02, "ds_min": 1e-8, "ds_max": 0.05,
                                      "max_points": 5000, "both_directions": True}


class ContinuationOptionError(ParameterError):
    """A continuation option has a value outside the allowed set."""


def _option_error(name: str, value: object, allowed: str) -> ContinuationOptionError:
    """Build the error for option `name` with the received `value` and what is `allowed`."""
    return ContinuationOptionError(f"option {name} = {value!r} is invalid; {allowed}")


def _require_real(name: str, value: object) -> float:
    """Return `value` as a finite float or raise naming option `name`."""
    if isinstance(value, bool) or not isinstance(value, Real) or not math.isfinite(value):
        raise _option_error(name, value, "it must be a finite real number")
    return float(value)


def _require_int(name: str, value: object, minimum: int) -> int:
    """Return `value` as an int ``>= minimum`` or raise naming option `name`."""
    if isinstance(value, bool) or not isinstance(value, Integral) or value < minimum:
        raise _option_error(name, value, f"it must be an integer >= {minimum}")
    return int(value)


@dataclass(frozen=True, kw_only=True)
class ContinuationOptions:
    """Options of the pseudo-arclength continuation (PALC).

    All arclength quantities are measured in the scaled norm
    ``||(du, dlam)||^2 = ||du||^2 / m + theta * dlam^2``, ``m`` being the
    number of unknowns.

    Every option left out takes its default; :attr:`given` names those given.
    A driver of impactcont fills the ones left out with :data:`DRIVER_DEFAULTS`
    (:func:`driver_options`).

    Parameters
    ----------
    bounds : tuple of float, optional
        ``(lam_min, lam_max)``, finite with ``lam_min < lam_max``. The
        continuation stops when the parameter reaches a bound; the last point
        then lies exactly on it. Required by the core; a driver takes it from
        its own ``bounds`` argument when left out.
    ds : float, default min(0.01, ds_max)
        Initial arclength step, ``ds_min <= ds <= ds_max``.
    ds_min : float, default min(1e-6, ds)
        Smallest step; the continuation stops when the step would fall below it.
    ds_max : float, default 0.1
        Largest step.
    newton_tol : float, default 1e-10
        Newton converges when both the max-norm of the residual and the
        max-norm of the last Newton update are at most this value (a guess
        whose residual is already within it is accepted as is).
    newton_max_iter : int, default 10
        Largest number of Newton iterations per point.
    max_points : int, default 1000
        Largest number of points per direction, the start point included.
    direction : int, default 1
        Sign of ``dlam`` at the start point, ``+1`` or ``-1``; at a start on
        a fold, the sign of the largest ``du`` component instead.
    both_directions : bool, default False
        Also continue from the start point in the opposite direction and join
        both parts into one branch.
    max_angle : float, default 0.3
        Largest angle (radians, in ``(0, pi/2]``) between consecutive tangents;
        a step with a larger angle is rejected and retried with half the step.
    target_newton_iter : int, default 3
        The step grows when Newton converged in at most this many iterations
        and the tangent turned by at most half of `max_angle`; it shrinks when
        Newton needed more.
    theta : float, default 0.5
        Weight of the parameter in the scaled arclength norm, in ``(0, 1]``.
    """

    bounds: tuple[float, float] | None = _UNSET
    ds: float = _UNSET
    ds_min: float = _UNSET
    ds_max: float = _UNSET
    newton_tol: float = _UNSET
    newton_max_iter: int = _UNSET
    max_points: int = _UNSET
    direction: int = _UNSET
    both_directions: bool = _UNSET
    max_angle: float = _UNSET
    target_newton_iter: int = _UNSET
    theta: float = _UNSET

    def __post_init__(self) -> None:
        """Fill the defaults, validate every option; raise on the first bad one."""
        given = frozenset(f.name for f in dataclasses.fields(self)
                          if getattr(self, f.name) is not _UNSET)
        object.__setattr__(self, "_given", given)
        for name, default in _CLASS_DEFAULTS.items():
            if name not in given and name not in ("ds", "ds_min"):
                self._set(name, default)
        if "ds" not in given:  # adapts to a smaller ds_max
            ds_max = _require_real("ds_max", self.ds_max)
            self._set("ds", min(_CLASS_DEFAULTS["ds"], ds_max) if ds_max > 0 else 0.01)
        if "ds_min" not in given:
            ds = _require_real("ds", self.ds)
            self._set("ds_min", min(_CLASS_DEFAULTS["ds_min"], ds) if ds > 0 else 1e-6)
        if self.bounds is not None:
            self._check_bounds()
        self._check_step_sizes()
        self._check_newton()
        self._check_walk()
        self._check_adaptive_rule()

    @property
    def given(self) -> frozenset[str]:
        """Names of the options given explicitly (the others are defaults)."""
        return self._given  # type: ignore[attr-defined]

    @property
    def lam_min(self) -> float:
        """Lower parameter bound."""
        return self.bounds[0]

    @property
    def lam_max(self) -> float:
        """Upper parameter bound."""
        return self.bounds[1]

    def _set(self, name: str, value: object) -> None:
        """Store a normalised value on the frozen instance."""
        object.__setattr__(self, name, value)

    def _check_bounds(self) -> None:
        allowed = "it must be a pair (lam_min, lam_max) of finite floats with lam_min < lam_max"
        try:
            lam_min, lam_max = self.bounds
        except (TypeError, ValueError):
            raise _option_error("bounds", self.bounds, allowed) from None
        valid = all(
            not isinstance(value, bool) and isinstance(value, Real) and math.isfinite(value)
            for value in (lam_min, lam_max)
        )
        if not valid or not lam_min < lam_max:
            raise _option_error("bounds", self.bounds, allowed)
        self._set("bounds", (float(lam_min), float(lam_max)))

    def _check_step_sizes(self) -> None:
        for name in ("ds_min", "ds", "ds_max"):
            value = _require_real(name, getattr(self, name))
            if value <= 0.0:
                raise _option_error(name, value, "it must be > 0")
            self._set(name, value)
        if self.ds_min > self.ds_max:
            raise _option_error("ds_min", self.ds_min, f"it must be <= ds_max = {self.ds_max!r}")
        if not self.ds_min <= self.ds <= self.ds_max:
            raise _option_error(
                "ds",
                self.ds,
                f"it must satisfy ds_min <= ds <= ds_max, here "
                f"ds_min = {self.ds_min!r} and ds_max = {self.ds_max!r}",
            )

    def _check_newton(self) -> None:
        newton_tol = _require_real("newton_tol", self.newton_tol)
        if newton_tol <= 0.0:
            raise _option_error("newton_tol", newton_tol, "it must be > 0")
        self._set("newton_tol", newton_tol)
        self._set("newton_max_iter", _require_int("newton_max_iter", self.newton_max_iter, 1))

    def _check_walk(self) -> None:
        self._set("max_points", _require_int("max_points", self.max_points, 2))
        if isinstance(self.direction, bool) or self.direction not in (1, -1):
            raise _option_error("direction", self.direction, "it must be +1 or -1")
        self._set("direction", int(self.direction))
        if not isinstance(self.both_directions, bool):
            raise _option_error("both_directions", self.both_directions, "it must be a bool")

    def _check_adaptive_rule(self) -> None:
        max_angle = _require_real("max_angle", self.max_angle)
        if not 0.0 < max_angle <= math.pi / 2:
            raise _option_error("max_angle", max_angle, "it must be in (0, pi/2] radians")
        self._set("max_angle", max_angle)
        self._set(
            "target_newton_iter", _require_int("target_newton_iter", self.target_newton_iter, 1)
        )
        theta = _require_real("theta", self.theta)
        if not 0.0 < theta <= 1.0:
            raise _option_error("theta", theta, "it must be in (0, 1]")
        self._set("theta", theta)


def driver_options(options: ContinuationOptions | None, bounds: Any, /, *,
                   defaults: Mapping[str, Any] | None = None, **keywords: Any
                   ) -> ContinuationOptions:
    """The options of a driver run: defaults < `options` given < keywords given.

    Parameters
    ----------
    options : ContinuationOptions or None
        The user's options; only the ones given explicitly count.
    bounds : (float, float)
        The driver's range of the continuation parameter (used unless `options`
        or the keywords give ``bounds``).
    defaults : mapping, optional
        The driver's defaults over :data:`DRIVER_DEFAULTS` (its Newton tolerance,
        or ``both_directions=False`` for a switch).
    **keywords
        Convenience keywords of the driver; ``None`` means not given.

    Returns
    -------
    ContinuationOptions
        With ``ds`` lowered to ``ds_max`` and ``ds_min`` to ``ds`` when only the
        larger one was given.

    Raises
    ------
    ContinuationOptionError
        For a bad value (named) or an `options` that is not a ContinuationOptions.
    """
    if options is not None and not isinstance(options, ContinuationOptions):
        raise ContinuationOptionError(f"options must be a ContinuationOptions; got "
                                      f"{type(options).__name__}")
    values: dict[str, Any] = {**DRIVER_DEFAULTS, **(defaults or {}), "bounds": bounds}
    given = set()
    if options is not None:
        given |= options.given
        values.update({name: getattr(options, name) for name in options.given})
    known = {f.name for f in dataclasses.fields(ContinuationOptions) if f.init}
    unknown = sorted(set(keywords) - known)
    if unknown:
        raise ContinuationOptionError(
            f"unknown keyword argument(s) {', '.join(map(repr, unknown))} (got "
            f"{', '.join(f'{k}={keywords[k]!r}' for k in unknown)}); the continuation "
            f"options are {', '.join(sorted(known))}, besides the function's own arguments")
    extra = {name: value for name, value in keywords.items() if value is not None}
    given |= set(extra)
    values.update(extra)
    if "ds" not in given and isinstance(values["ds_max"], Real) and values["ds_max"] > 0:
        values["ds"] = min(values["ds"], values["ds_max"])
    if "ds_min" not in given and isinstance(values["ds"], Real) and values["ds"] > 0:
        values["ds_min"] = min(values["ds_min"], values["ds"])
    return ContinuationOptions(**values)


def option_keywords(defaults: Mapping[str, Any]
                    ) -> Callable[[Callable[..., Any]], Callable[..., Any]]:
    """Show a driver's option defaults in its signature; pass ``None`` for those not given.

    A driver declares its convenience keywords (``ds``, ``ds_max``, ...) with default
    ``None`` so that it can tell a keyword given from one left out (and let
    ``options=`` decide the latter). This decorator publishes the values the
    left-out ones take (`defaults`) as the signature's defaults, for readers and
    for code that reads them (scenes), while the function still receives ``None``.
    """
    def decorate(func: Callable[..., Any]) -> Callable[..., Any]:
        signature = inspect.signature(func)
        shown = signature.replace(parameters=[
            p.replace(default=defaults[name]) if name in defaults else p
            for name, p in signature.parameters.items()])

        @functools.wraps(func)
        def wrapper(*args: Any, **kwargs: Any) -> Any:
            return func(*args, **kwargs)

        wrapper.__signature__ = shown  # type: ignore[attr-defined]
        return wrapper

    return decorate
