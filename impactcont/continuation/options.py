"""Options of the pseudo-arclength continuation."""

from __future__ import annotations

import math
from dataclasses import dataclass
from numbers import Integral, Real

from impactcont.errors import ParameterError

__all__ = ["ContinuationOptionError", "ContinuationOptions"]


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

    Parameters
    ----------
    bounds : tuple of float
        ``(lam_min, lam_max)``, finite with ``lam_min < lam_max``. The
        continuation stops when the parameter reaches a bound; the last point
        then lies exactly on it.
    ds : float, default 0.01
        Initial arclength step, ``ds_min <= ds <= ds_max``.
    ds_min : float, default 1e-6
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

    bounds: tuple[float, float]
    ds: float = 0.01
    ds_min: float = 1e-6
    ds_max: float = 0.1
    newton_tol: float = 1e-10
    newton_max_iter: int = 10
    max_points: int = 1000
    direction: int = 1
    both_directions: bool = False
    max_angle: float = 0.3
    target_newton_iter: int = 3
    theta: float = 0.5

    def __post_init__(self) -> None:
        """Validate every option; raise :class:`ContinuationOptionError` on the first bad one."""
        self._check_bounds()
        self._check_step_sizes()
        self._check_newton()
        self._check_walk()
        self._check_adaptive_rule()

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
