"""Continuation loop: run the stepper, stop on bounds, loops, failures and the driver's rules.

:func:`follow` computes a whole branch or curve (both directions joined); every
driver of impactcont runs on it. :func:`iter_points` runs one direction lazily
and yields every accepted point, for callers that watch the stream of points.

The problem may provide an ``accept(u, lam)`` hook: the core calls it with the
start guess before each direction and with every accepted point, before the
next step (problems with borders or reference vectors renew them there).

Ctrl-C during :func:`follow`, inside a call of :func:`impactcont.progress.interruptible`
(every driver of impactcont runs in one), ends the run with the points accepted so far
and the status ``INTERRUPTED``; the other direction is not computed.
"""

from __future__ import annotations

import dataclasses
import logging
import math
from collections.abc import Callable, Iterator, Sequence
from dataclasses import dataclass

import numpy as np

from impactcont.core.events import (
    ContinuationStatus,
    Stop,
    StopRule,
    StopRuleFactory,
    parameter_name,
)
from impactcont.core.locate import Event, EventPoint, locate_events
from impactcont.core.options import ContinuationOptions
from impactcont.core.point import ContinuationPoint
from impactcont.core.problem import FloatArray, Problem
from impactcont.core.stepper import (
    BoundReachedError,
    NewtonConvergenceError,
    PalcStepper,
    StepSizeBelowMinimumError,
)
from impactcont.errors import ParameterError
from impactcont.progress import interrupted, take_interrupt

__all__ = [
    "BranchRun",
    "ContinuationResult",
    "ContinuationStatus",
    "continue_branch",
    "follow",
    "iter_points",
]

logger = logging.getLogger(__name__)

LOOP_CLOSING_DISTANCE = 1.0
"""A loop closes when the last chord passes within this many steps ``ds`` of the start."""
LOOP_AWAY_DISTANCE = 3.0
"""The branch must first have gone this many steps ``ds`` away from the start."""


def _accept(problem: Problem, u: FloatArray, lam: float) -> None:
    """Call the problem's optional ``accept`` hook."""
    accept = getattr(problem, "accept", None)
    if accept is not None:
        accept(u, lam)


class BranchRun:
    """One continuation run in one direction, iterated lazily.

    Iterating yields every accepted :class:`ContinuationPoint`, the start point
    first (``index == 0``). When the iteration ends, :attr:`status` and
    :attr:`message` tell why. A run can be iterated once.

    Parameters
    ----------
    problem : Problem
        The system ``F(u, lam) = 0``.
    u0 : array_like, shape (m,)
        Guess of the unknowns at the start.
    lam0 : float
        Parameter of the start point, within ``options.bounds``.
    options : ContinuationOptions
        Continuation options.
    direction : int, optional
        Sign of ``dlam`` at the start, ``+1`` or ``-1``; defaults to
        ``options.direction``.
    stop : StopRule, optional
        The driver's rule, shown every accepted point (the start with
        ``previous=None``) before it is yielded.
    start : ContinuationPoint, optional
        The corrected start of the run from the same guess in the other direction
        (its :attr:`start`): taken with its tangent reversed instead of correcting the
        guess again (:meth:`~impactcont.core.stepper.PalcStepper.init_reversed`).

    Attributes
    ----------
    start : ContinuationPoint or None
        The corrected start point, once the run has it.
    """

    def __init__(
        self,
        problem: Problem,
        u0: FloatArray | Sequence[float],
        lam0: float,
        options: ContinuationOptions,
        direction: int | None = None,
        stop: StopRule | None = None,
        start: ContinuationPoint | None = None,
    ) -> None:
        self.u0, self.lam0 = _validated_start(u0, lam0, options)
        self.problem = problem
        self.options = options
        self.direction = options.direction if direction is None else direction
        if self.direction not in (1, -1):
            raise ParameterError(f"direction = {direction!r} is invalid; it must be +1 or -1")
        self.stop = stop
        self.name = parameter_name(problem)  # of lam, in the stop reasons
        self.status: ContinuationStatus | None = None
        self.message = "not run yet"
        self._started = False
        self._reversed = start
        self.start: ContinuationPoint | None = None

    def __iter__(self) -> Iterator[ContinuationPoint]:
        if self._started:
            raise RuntimeError("a BranchRun can be iterated only once; create a new one")
        self._started = True
        return self._run()

    def _finish(self, status: ContinuationStatus, detail: str) -> None:
        self.status = status
        self.message = f"{status.value}: {detail}"
        logger.info("continuation (direction %+d) stopped, %s", self.direction, self.message)

    def interrupt(self, points: Sequence[ContinuationPoint]) -> None:
        """Finish the run as interrupted by the user after `points` (those accepted)."""
        self.status = ContinuationStatus.INTERRUPTED
        last = f", last at {self.name} = {points[-1].lam:.10g}" if points else ""
        self.message = f"{self.status.value} after {len(points)} points{last}"
        logger.info("continuation (direction %+d) stopped, %s", self.direction, self.message)

    def _emit(self, previous: ContinuationPoint | None, current: ContinuationPoint
              ) -> Iterator[ContinuationPoint]:
        """Yield `current` as the stop rule decides (kept, replaced or left out).

        When the rule stops the run, it is finished here (:attr:`status` is set).
        """
        stop: Stop | None = None if self.stop is None else self.stop(previous, current)
        if stop is None:
            yield current
            return
        if stop.keep:
            yield stop.point if stop.point is not None else current
        self._finish(stop.status, stop.detail)

    def _run(self) -> Iterator[ContinuationPoint]:
        _accept(self.problem, self.u0, self.lam0)
        stepper = PalcStepper(self.problem, self.options, self.direction)
        if self._reversed is not None:
            start = stepper.init_reversed(self._reversed)
        else:
            try:
                start = stepper.init(self.u0, self.lam0)
            except NewtonConvergenceError as error:
                self._finish(ContinuationStatus.NEWTON_FAILED_AT_START, str(error))
                return
        self.start = start
        yield from self._emit(None, start)
        if self.status is not None:
            return
        _accept(self.problem, start.u, start.lam)
        farthest_from_start = 0.0
        previous = start
        while True:
            if previous.index + 1 >= self.options.max_points:
                self._finish(
                    ContinuationStatus.MAX_POINTS_REACHED,
                    f"{self.options.max_points} points, last at {self.name} = {previous.lam:.10g}",
                )
                return
            try:
                current = stepper.step()
            except StepSizeBelowMinimumError as error:
                self._finish(ContinuationStatus.STEP_BELOW_MINIMUM, str(error))
                return
            except BoundReachedError as error:  # the start lies on a bound, no step past it
                self._finish(ContinuationStatus.BOUNDS_REACHED,
                             f"{self.name} = {error.bound:.10g}")
                return
            bound = self._crossed_bound(current.lam)
            if bound is not None:
                yield from self._land_on_bound(stepper, previous, current, bound)
                return
            yield from self._emit(previous, current)
            if self.status is not None:
                return
            _accept(self.problem, current.u, current.lam)
            if self._closes_loop(stepper, start, previous, current, farthest_from_start):
                self._finish(
                    ContinuationStatus.CLOSED_LOOP,
                    f"branch returned to the start {self.name} = {start.lam:.10g} "
                    f"after {current.index + 1} points",
                )
                return
            farthest_from_start = max(
                farthest_from_start, stepper.scaled_norm(current.state - start.state)
            )
            previous = current

    def _crossed_bound(self, lam: float) -> float | None:
        """The bound that `lam` reached or crossed, ``None`` when inside."""
        lam_min, lam_max = self.options.bounds
        if lam <= lam_min:
            return lam_min
        if lam >= lam_max:
            return lam_max
        return None

    def _land_on_bound(
        self,
        stepper: PalcStepper,
        previous: ContinuationPoint,
        current: ContinuationPoint,
        bound: float,
    ) -> Iterator[ContinuationPoint]:
        """Yield the point exactly on `bound` (if new) and finish the run."""
        detail = f"{self.name} = {bound:.10g}"
        landed: ContinuationPoint | None = None
        if current.lam == bound:
            landed = current
        elif previous.lam != bound:
            try:
                landed = stepper.land_on_parameter(previous, current, bound)
            except NewtonConvergenceError as error:
                logger.warning("could not land on the bound lam = %.10g: %s", bound, error)
                detail = (
                    f"{self.name} = {bound:.10g} crossed, but the point on it was not found "
                    f"({error}); last point at {self.name} = {previous.lam:.10g}"
                )
        if landed is not None:
            yield from self._emit(previous, landed)
            if self.status is not None:
                return
        self._finish(ContinuationStatus.BOUNDS_REACHED, detail)

    @staticmethod
    def _closes_loop(
        stepper: PalcStepper,
        start: ContinuationPoint,
        previous: ContinuationPoint,
        current: ContinuationPoint,
        farthest_from_start: float,
    ) -> bool:
        """Whether the chord ``previous -> current`` passes by the start point again.

        The branch must first have gone more than ``LOOP_AWAY_DISTANCE`` steps
        away from the start; the chord must then pass within
        ``LOOP_CLOSING_DISTANCE`` steps of the start, travelling in the
        direction of the start tangent.
        """
        if farthest_from_start <= LOOP_AWAY_DISTANCE * current.ds:
            return False
        if stepper.scaled_dot(current.tangent, start.tangent) <= 0.0:
            return False
        chord = current.state - previous.state
        to_start = start.state - previous.state
        # unknowns that are angles (a phase): the branch closes when it returns to the
        # start modulo the period, not only to the start itself
        periods = getattr(stepper.problem, "periods", None)
        if periods is not None:
            periods = np.append(np.asarray(periods, dtype=float), 0.0)
            wrap = periods > 0
            to_start[wrap] -= periods[wrap] * np.round(to_start[wrap] / periods[wrap])
        chord_length_squared = stepper.scaled_dot(chord, chord)
        if chord_length_squared == 0.0:
            return False
        fraction = stepper.scaled_dot(to_start, chord) / chord_length_squared
        if not 0.0 <= fraction <= 1.0:
            return False
        distance = stepper.scaled_norm(to_start - fraction * chord)
        return distance <= LOOP_CLOSING_DISTANCE * current.ds


def iter_points(
    problem: Problem,
    u0: FloatArray | Sequence[float],
    lam0: float,
    options: ContinuationOptions,
    direction: int | None = None,
) -> BranchRun:
    """Continue in one direction, yielding the accepted points lazily.

    The arguments are those of :class:`BranchRun` (``options.both_directions``
    is ignored here).

    Returns
    -------
    BranchRun
        Iterable of :class:`ContinuationPoint`; read ``status`` and ``message``
        after the iteration ends.

    Examples
    --------
    >>> run = iter_points(problem, u0, lam0, options)  # doctest: +SKIP
    >>> folds, previous = [], None
    >>> for point in run:  # doctest: +SKIP
    ...     if previous is not None and previous.dlam * point.dlam < 0:
    ...         folds.append((previous, point))
    ...     previous = point
    >>> run.status  # doctest: +SKIP
    """
    return BranchRun(problem, u0, lam0, options, direction)


@dataclass(frozen=True, eq=False)
class ContinuationResult:
    """A computed branch and why its computation stopped.

    With ``both_directions`` the points are ordered along the whole branch:
    the backward part reversed, then the start point, then the forward part.
    All tangents point along this order.

    Attributes
    ----------
    u : ndarray, shape (npoints, m)
        Unknowns of the accepted points.
    lam : ndarray, shape (npoints,)
        Parameter values.
    tangent : ndarray, shape (npoints, m + 1)
        Unit tangents ``(du, dlam)`` in the scaled norm.
    ds : ndarray, shape (npoints,)
        Scaled arclength step that produced each point (0 at the start).
    newton_iterations : ndarray of int, shape (npoints,)
        Newton iterations spent on each point.
    monitors : dict of str to ndarray
        Monitor values per point, shape ``(npoints,)`` each.
    status : ContinuationStatus
        Why the run in ``options.direction`` stopped.
    backward_status : ContinuationStatus or None
        Why the opposite run stopped; ``None`` without ``both_directions``.
        When the forward run closed a loop or Newton failed at the start, the
        backward run is not computed and gets the same status.
    message : str
        Readable summary of both statuses.
    start_index : int
        Index of the start point in the arrays.
    events : tuple of EventPoint
        The events given to :func:`follow`, located along the branch.
    """

    u: FloatArray
    lam: FloatArray
    tangent: FloatArray
    ds: FloatArray
    newton_iterations: np.ndarray
    monitors: dict[str, FloatArray]
    status: ContinuationStatus
    backward_status: ContinuationStatus | None
    message: str
    start_index: int = 0
    events: tuple[EventPoint, ...] = ()

    @property
    def statuses(self) -> tuple[ContinuationStatus, ...]:
        """The status of each direction, forward first."""
        if self.backward_status is None:
            return (self.status,)
        return (self.status, self.backward_status)

    @property
    def interrupted(self) -> bool:
        """Whether Ctrl-C ended a direction (the points are those computed before it)."""
        return ContinuationStatus.INTERRUPTED in self.statuses

    def __len__(self) -> int:
        return int(self.lam.shape[0])


def follow(
    problem: Problem,
    u0: FloatArray | Sequence[float],
    lam0: float,
    options: ContinuationOptions,
    on_point: Callable[[ContinuationPoint], None] | None = None,
    *,
    stop: StopRuleFactory | None = None,
    events: Sequence[Event] = (),
) -> ContinuationResult:
    """Compute a branch of ``F(u, lam) = 0`` by pseudo-arclength continuation.

    Every branch and curve of impactcont is computed here: both directions
    from the start, joined into one ordered branch; bounds, ``max_points``,
    closed loops (modulo the problem's ``periods``) and the driver's stop
    rules end a direction. The problem's optional ``accept`` hook is called
    with the start guess and every accepted point.

    Parameters
    ----------
    problem : Problem
        The system ``F(u, lam) = 0``.
    u0 : array_like, shape (m,)
        Guess of the unknowns at the start; corrected at fixed `lam0`.
    lam0 : float
        Parameter of the start point, within ``options.bounds``.
    options : ContinuationOptions
        Continuation options.
    on_point : callable, optional
        Called with every accepted :class:`ContinuationPoint` in the order
        computed: the run in ``options.direction`` first (start point with
        ``index == 0``), then, with ``both_directions``, the opposite run,
        which starts again with the start point (``index == 0``).
    stop : callable, optional
        Called with the direction (``+1``, ``-1``) at the start of each run;
        returns that run's :class:`~impactcont.core.events.StopRule`.
    events : sequence of Event
        Located along the joined branch once it is computed
        (:func:`~impactcont.core.locate.locate_events`), in ``result.events``.

    Returns
    -------
    ContinuationResult
        The accepted points and the stop statuses.

    Raises
    ------
    ParameterError
        If `u0` is not a non-empty 1-D finite array or `lam0` is outside
        ``options.bounds``.
    KeyboardInterrupt
        Ctrl-C outside :func:`impactcont.progress.interruptible`, or a second one.

    Notes
    -----
    The first Ctrl-C (:class:`KeyboardInterrupt`, from the terminal or raised by the
    problem, a stop rule or `on_point`) inside :func:`impactcont.progress.interruptible`
    ends the running direction: the points accepted before it are kept, its status is
    ``ContinuationStatus.INTERRUPTED`` (message ``"interrupted by the user
    (KeyboardInterrupt) after K points, last at ..."``, logged at WARNING), the other
    direction is not computed, and the `events` are located on the points kept (a second
    Ctrl-C aborts that).
    """
    def run(direction: int, start: ContinuationPoint | None = None) -> BranchRun:
        return BranchRun(problem, u0, lam0, options, direction,
                         None if stop is None else stop(direction), start)

    first = run(options.direction)
    forward = _collect(first, on_point)
    if not options.both_directions:
        result = _result_one_direction(forward)
    elif forward.status in _STATUSES_SKIPPING_BACKWARD:
        result = _result_one_direction(
            forward, forward.status, f"skipped, {_STATUSES_SKIPPING_BACKWARD[forward.status]}"
        )
    else:  # from the start the forward run corrected, not corrected again
        result = _result_both_directions(
            forward, _collect(run(-options.direction, first.start), on_point))
    if events and len(result) > 1:
        found = locate_events(problem, result.u, result.lam, result.tangent, events)
        result = dataclasses.replace(result, events=tuple(found))
    return result


continue_branch = follow
"""The former name of :func:`follow`."""


_STATUSES_SKIPPING_BACKWARD = {
    ContinuationStatus.CLOSED_LOOP: "the branch is a closed loop",
    ContinuationStatus.NEWTON_FAILED_AT_START: "Newton failed at the shared start point",
    ContinuationStatus.INTERRUPTED: "interrupted by the user",
}
"""Forward statuses after which the backward run is not computed, with the reason."""


@dataclass
class _CollectedRun:
    """The points of a finished run with its status."""

    points: list[ContinuationPoint]
    status: ContinuationStatus
    message: str


def _collect(run: BranchRun, on_point: Callable[[ContinuationPoint], None] | None) -> _CollectedRun:
    """The points of `run`; Ctrl-C ends it with those accepted before (see :func:`follow`)."""
    points: list[ContinuationPoint] = []
    try:
        for point in run:
            points.append(point)
            if on_point is not None:
                on_point(point)
            if interrupted():  # Ctrl-C taken elsewhere in the call (a stop rule's location)
                run.interrupt(points)
                break
    except KeyboardInterrupt:
        if not take_interrupt("continuation", "interrupted by the user (KeyboardInterrupt) "
                              "after %d points (direction %+d); the points computed are "
                              "kept", len(points), run.direction):
            raise
        run.interrupt(points)
    if run.status is None:
        raise RuntimeError("continuation run ended without a status")
    return _CollectedRun(points, run.status, run.message)


def _result_one_direction(
    run: _CollectedRun,
    backward_status: ContinuationStatus | None = None,
    backward_message: str = "",
) -> ContinuationResult:
    message = run.message
    if backward_status is not None:
        message = f"forward: {run.message}; backward: {backward_message}"
    return _build_result(run.points, run.status, backward_status, message, start_index=0)


def _result_both_directions(forward: _CollectedRun, backward: _CollectedRun) -> ContinuationResult:
    """Join ``reversed(backward[1:]) + forward`` with tangents along the joined order."""
    reversed_backward = [_reverse_tangent(point) for point in reversed(backward.points[1:])]
    points = reversed_backward + forward.points
    message = f"forward: {forward.message}; backward: {backward.message}"
    return _build_result(
        points, forward.status, backward.status, message, start_index=len(reversed_backward)
    )


def _reverse_tangent(point: ContinuationPoint) -> ContinuationPoint:
    return ContinuationPoint(
        u=point.u,
        lam=point.lam,
        tangent=-point.tangent,
        ds=point.ds,
        newton_iterations=point.newton_iterations,
        index=point.index,
        direction=point.direction,
        monitors=point.monitors,
    )


def _build_result(
    points: list[ContinuationPoint],
    status: ContinuationStatus,
    backward_status: ContinuationStatus | None,
    message: str,
    start_index: int,
) -> ContinuationResult:
    if points:
        u = np.array([point.u for point in points])
        tangent = np.array([point.tangent for point in points])
    else:
        u = np.empty((0, 0))
        tangent = np.empty((0, 0))
    return ContinuationResult(
        u=u,
        lam=np.array([point.lam for point in points], dtype=float),
        tangent=tangent,
        ds=np.array([point.ds for point in points], dtype=float),
        newton_iterations=np.array([point.newton_iterations for point in points], dtype=int),
        monitors=_stack_monitors(points),
        status=status,
        backward_status=backward_status,
        message=message,
        start_index=start_index,
    )


def _stack_monitors(points: list[ContinuationPoint]) -> dict[str, FloatArray]:
    names = list(dict.fromkeys(name for point in points for name in point.monitors))
    return {
        name: np.array([point.monitors.get(name, math.nan) for point in points], dtype=float)
        for name in names
    }


def _validated_start(
    u0: FloatArray | Sequence[float], lam0: float, options: ContinuationOptions
) -> tuple[FloatArray, float]:
    """Check the start point and return it as ``(float array, float)``."""
    u = np.array(u0, dtype=float)
    if u.ndim != 1 or u.size == 0 or not np.all(np.isfinite(u)):
        raise ParameterError(
            f"u0 = {u0!r} is invalid; it must be a non-empty 1-D array of finite floats"
        )
    lam = float(lam0)
    if options.bounds is None:
        raise ParameterError("options.bounds = None is invalid; the core needs the pair "
                             "(lam_min, lam_max)")
    lam_min, lam_max = options.bounds
    if not lam_min <= lam <= lam_max:
        raise ParameterError(
            f"lam0 = {lam0!r} is invalid; it must lie within bounds [{lam_min}, {lam_max}]"
        )
    return u, lam
