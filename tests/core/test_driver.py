"""Known-answer tests of the generic pseudo-arclength continuation core."""

from __future__ import annotations

import dataclasses
import itertools
import logging
import math

import numpy as np
import pytest

from impactcont.core import (
    ContinuationOptions,
    ContinuationPoint,
    ContinuationResult,
    ContinuationStatus,
    NewtonConvergenceError,
    PalcStepper,
    Problem,
    continue_branch,
    iter_points,
)
from impactcont.errors import ParameterError

CUBIC_FOLD_LAM = 2.0 / (3.0 * math.sqrt(3.0))


PLASTIC_NUMBER = 1.324717957244746  # real root of u^3 - u - 1


class Circle:
    """``u^2 + lam^2 = 1``: folds at ``lam = +-1``, a closed loop."""

    def residual(self, u: np.ndarray, lam: float) -> np.ndarray:
        return np.array([u[0] ** 2 + lam**2 - 1.0])

    def jacobian(self, u: np.ndarray, lam: float) -> np.ndarray:
        return np.array([[2.0 * u[0]]])

    def dparam(self, u: np.ndarray, lam: float) -> np.ndarray:
        return np.array([2.0 * lam])


class Cubic:
    """``u^3 - u - lam = 0``: folds at ``lam = +-2/(3 sqrt 3)``, with a monitor."""

    def residual(self, u: np.ndarray, lam: float) -> np.ndarray:
        return np.array([u[0] ** 3 - u[0] - lam])

    def jacobian(self, u: np.ndarray, lam: float) -> np.ndarray:
        return np.array([[3.0 * u[0] ** 2 - 1.0]])

    def dparam(self, u: np.ndarray, lam: float) -> np.ndarray:
        return np.array([-1.0])

    def monitors(self, u: np.ndarray, lam: float) -> dict[str, float]:
        return {"u_squared": float(u[0] ** 2)}


class TiltedCircle:
    """Unit sphere cut by the plane ``u1 = lam``.

    On it ``u2^2 = 1 - 2 lam^2``: a closed loop with folds at ``lam = +-1/sqrt 2``.
    """

    def residual(self, u: np.ndarray, lam: float) -> np.ndarray:
        return np.array([u[0] ** 2 + u[1] ** 2 + lam**2 - 1.0, u[0] - lam])

    def jacobian(self, u: np.ndarray, lam: float) -> np.ndarray:
        return np.array([[2.0 * u[0], 2.0 * u[1]], [1.0, 0.0]])

    def dparam(self, u: np.ndarray, lam: float) -> np.ndarray:
        return np.array([2.0 * lam, -1.0])


class Helix:
    """``u = (cos lam, sin lam)``: no fold, tests exact landing with ``m = 2``."""

    def residual(self, u: np.ndarray, lam: float) -> np.ndarray:
        return np.array([u[0] - math.cos(lam), u[1] - math.sin(lam)])

    def jacobian(self, u: np.ndarray, lam: float) -> np.ndarray:
        return np.eye(2)

    def dparam(self, u: np.ndarray, lam: float) -> np.ndarray:
        return np.array([math.sin(lam), -math.cos(lam)])


class SquareRootEnd:
    """``u - sqrt(lam) = 0``: the branch ends at ``(0, 0)``, where dF/dlam is infinite."""

    def residual(self, u: np.ndarray, lam: float) -> np.ndarray:
        return np.array([u[0] - math.sqrt(lam) if lam >= 0.0 else math.nan])

    def jacobian(self, u: np.ndarray, lam: float) -> np.ndarray:
        return np.array([[1.0]])

    def dparam(self, u: np.ndarray, lam: float) -> np.ndarray:
        return np.array([-0.5 / math.sqrt(lam) if lam > 0.0 else math.nan])


class Parabola:
    """``u^2 - lam = 0``: a fold at the origin."""

    def residual(self, u: np.ndarray, lam: float) -> np.ndarray:
        return np.array([u[0] ** 2 - lam])

    def jacobian(self, u: np.ndarray, lam: float) -> np.ndarray:
        return np.array([[2.0 * u[0]]])

    def dparam(self, u: np.ndarray, lam: float) -> np.ndarray:
        return np.array([-1.0])


class Line:
    """``u - lam = 0``."""

    def residual(self, u: np.ndarray, lam: float) -> np.ndarray:
        return np.array([u[0] - lam])

    def jacobian(self, u: np.ndarray, lam: float) -> np.ndarray:
        return np.array([[1.0]])

    def dparam(self, u: np.ndarray, lam: float) -> np.ndarray:
        return np.array([-1.0])


def max_residual(problem: Problem, result: ContinuationResult) -> float:
    return max(
        float(np.max(np.abs(problem.residual(u, lam))))
        for u, lam in zip(result.u, result.lam, strict=True)
    )


def fold_lams(result: ContinuationResult) -> np.ndarray:
    """Parameter values at the points just before a sign change of dlam."""
    dlam = result.tangent[:, -1]
    before_change = np.nonzero(dlam[:-1] * dlam[1:] < 0.0)[0]
    return result.lam[before_change]


def test_circle_goes_round_both_folds_and_closes_the_loop() -> None:
    options = ContinuationOptions(bounds=(-2.0, 2.0), ds=0.05, ds_max=0.1, both_directions=True)
    problem = Circle()

    result = continue_branch(problem, np.array([1.0]), 0.0, options)

    assert result.status is ContinuationStatus.CLOSED_LOOP
    assert result.backward_status is ContinuationStatus.CLOSED_LOOP
    assert max_residual(problem, result) <= options.newton_tol
    assert np.all(np.abs(result.lam) <= 1.0)
    folds = fold_lams(result)
    assert len(folds) == 2
    assert np.sort(folds) == pytest.approx([-1.0, 1.0], abs=options.ds_max)
    # Going round once: the angle of (u, lam) increases monotonically by ~2 pi.
    angle = np.unwrap(np.arctan2(result.lam, result.u[:, 0]))
    assert np.all(np.diff(angle) > 0.0)
    assert 2.0 * math.pi - options.ds_max <= angle[-1] - angle[0] <= 2.0 * math.pi + options.ds_max


def test_circle_in_negative_direction_starts_downwards() -> None:
    options = ContinuationOptions(bounds=(-2.0, 2.0), ds=0.05, direction=-1)

    result = continue_branch(Circle(), [1.0], 0.0, options)

    assert result.lam[1] < 0.0
    assert result.status is ContinuationStatus.CLOSED_LOOP


def test_cubic_passes_both_folds_and_lands_exactly_on_the_bound() -> None:
    options = ContinuationOptions(bounds=(-1.0, 1.0), ds=0.05, ds_max=0.1)
    problem = Cubic()
    u_start = -1.2

    result = continue_branch(problem, [u_start], u_start**3 - u_start, options)

    assert result.status is ContinuationStatus.BOUNDS_REACHED
    assert result.backward_status is None
    assert result.lam[-1] == 1.0
    assert result.u[-1, 0] == pytest.approx(PLASTIC_NUMBER, abs=1e-9)
    assert max_residual(problem, result) <= options.newton_tol
    folds = fold_lams(result)
    assert np.sort(folds) == pytest.approx([-CUBIC_FOLD_LAM, CUBIC_FOLD_LAM], abs=options.ds_max)
    assert np.all(np.diff(result.u[:, 0]) > 0.0)
    assert result.monitors["u_squared"] == pytest.approx(result.u[:, 0] ** 2)


def test_cubic_both_directions_joins_one_ordered_branch() -> None:
    options = ContinuationOptions(bounds=(-1.0, 1.0), ds=0.05, both_directions=True)
    u_start = -1.2
    lam_start = u_start**3 - u_start

    result = continue_branch(Cubic(), [u_start], lam_start, options)

    assert result.statuses == (
        ContinuationStatus.BOUNDS_REACHED,
        ContinuationStatus.BOUNDS_REACHED,
    )
    assert (result.lam[0], result.lam[-1]) == (-1.0, 1.0)
    assert result.u[0, 0] == pytest.approx(-PLASTIC_NUMBER, abs=1e-9)
    # One ordered branch: u increases strictly, so the start point is not duplicated.
    assert np.all(np.diff(result.u[:, 0]) > 0.0)
    assert result.u[result.start_index, 0] == pytest.approx(u_start, abs=1e-12)
    assert np.count_nonzero(np.isclose(result.u[:, 0], u_start)) == 1
    # Tangents point along the joined order.
    chords = np.diff(np.column_stack([result.u, result.lam]), axis=0)
    assert np.all(np.sum(chords * result.tangent[1:], axis=1) > 0.0)
    assert len(result) == result.u.shape[0] == result.tangent.shape[0] == result.ds.shape[0]


def test_tilted_circle_with_two_unknowns() -> None:
    options = ContinuationOptions(bounds=(-1.0, 1.0), ds=0.05, both_directions=True)
    problem = TiltedCircle()

    result = continue_branch(problem, [0.0, 1.0], 0.0, options)

    assert result.status is ContinuationStatus.CLOSED_LOOP
    assert result.u.shape == (len(result), 2)
    assert result.tangent.shape == (len(result), 3)
    assert max_residual(problem, result) <= options.newton_tol
    assert np.sort(fold_lams(result)) == pytest.approx(
        [-1.0 / math.sqrt(2.0), 1.0 / math.sqrt(2.0)], abs=options.ds_max
    )
    assert np.all(np.abs(result.lam) <= 1.0 / math.sqrt(2.0))


def test_helix_lands_exactly_on_the_bound_with_two_unknowns() -> None:
    options = ContinuationOptions(bounds=(0.0, 2.0 * math.pi), ds=0.05)
    problem = Helix()

    result = continue_branch(problem, [0.9, 0.1], 0.0, options)

    assert result.status is ContinuationStatus.BOUNDS_REACHED
    assert result.lam[-1] == 2.0 * math.pi
    assert result.u[-1] == pytest.approx([1.0, 0.0], abs=1e-9)
    assert result.u[0] == pytest.approx([1.0, 0.0], abs=1e-9)
    assert max_residual(problem, result) <= options.newton_tol
    assert np.all(np.diff(result.lam) > 0.0)


def test_start_outside_bounds_is_rejected() -> None:
    options = ContinuationOptions(bounds=(-1.0, 1.0))

    with pytest.raises(ParameterError, match=r"lam0 = 2\.0 .*within bounds"):
        continue_branch(Line(), [2.0], 2.0, options)


def test_branch_ending_at_a_singularity_stops_with_step_below_minimum() -> None:
    options = ContinuationOptions(
        bounds=(-1.0, 2.0), ds=0.05, ds_min=1e-5, direction=-1, max_points=500
    )
    problem = SquareRootEnd()

    result = continue_branch(problem, [1.0], 1.0, options)

    assert result.status is ContinuationStatus.STEP_BELOW_MINIMUM
    assert "ds_min" in result.message
    assert max_residual(problem, result) <= options.newton_tol
    # The branch was followed down to its end point (0, 0).
    assert result.lam[-1] < 1e-6
    assert 0.0 < result.u[-1, 0] < 1e-3


def test_newton_failure_at_start_is_reported() -> None:
    options = ContinuationOptions(bounds=(-1.0, 1.0), both_directions=True)

    failed = continue_branch(SquareRootEnd(), [1.0], -0.5, options)

    assert failed.statuses == (
        ContinuationStatus.NEWTON_FAILED_AT_START,
        ContinuationStatus.NEWTON_FAILED_AT_START,
    )
    assert len(failed) == 0


def test_singular_jacobian_is_logged_with_its_condition_number(
    caplog: pytest.LogCaptureFixture,
) -> None:
    stepper = PalcStepper(Parabola(), ContinuationOptions(bounds=(-2.0, 2.0)))

    with (
        caplog.at_level(logging.WARNING, logger="impactcont.core"),
        pytest.raises(NewtonConvergenceError, match="singular"),
    ):
        stepper.correct_at_fixed_parameter(np.array([0.0]), -1.0)

    assert "condition number inf" in caplog.text


def test_start_exactly_at_a_fold_follows_both_sheets() -> None:
    options = ContinuationOptions(bounds=(-1.0, 1.0), ds=0.05, both_directions=True)

    result = continue_branch(Parabola(), [0.0], 0.0, options)

    assert result.statuses == (
        ContinuationStatus.BOUNDS_REACHED,
        ContinuationStatus.BOUNDS_REACHED,
    )
    assert (result.lam[0], result.lam[-1]) == (1.0, 1.0)
    assert sorted([result.u[0, 0], result.u[-1, 0]]) == pytest.approx([-1.0, 1.0], abs=1e-9)
    assert np.all(np.diff(result.u[:, 0]) * np.sign(result.u[-1, 0]) > 0.0)


def test_max_points_status() -> None:
    options = ContinuationOptions(bounds=(-10.0, 10.0), ds=0.01, max_points=7)

    result = continue_branch(Line(), [0.3], 0.0, options)

    assert result.status is ContinuationStatus.MAX_POINTS_REACHED
    assert len(result) == 7
    assert result.u[:, 0] == pytest.approx(result.lam, abs=1e-12)
    assert result.u[0, 0] == pytest.approx(0.0, abs=1e-12)


def test_on_point_and_iter_points_stream_the_accepted_points() -> None:
    options = ContinuationOptions(bounds=(-1.0, 1.0), ds=0.05, both_directions=True)
    seen: list[ContinuationPoint] = []

    result = continue_branch(Cubic(), [-1.2], -0.528, options, on_point=seen.append)

    starts = [point for point in seen if point.index == 0]
    assert [point.direction for point in starts] == [1, -1]
    assert len(seen) == len(result) + 1  # the start point is seen once per direction
    forward = [point for point in seen if point.direction == 1]
    run = iter_points(Cubic(), [-1.2], -0.528, options)
    streamed = list(run)
    assert run.status is ContinuationStatus.BOUNDS_REACHED
    assert [point.lam for point in streamed] == [point.lam for point in forward]
    folds_seen = sum(
        previous.dlam * current.dlam < 0.0 for previous, current in itertools.pairwise(streamed)
    )
    assert folds_seen == 2


class _DomainLimited:
    """u - lam = 0, defined only for lam > -0.05: iterates past it are refused."""

    def _check(self, lam: float) -> None:
        if lam <= -0.05:
            raise ParameterError(f"lam must be > -0.05; got {lam!r}")

    def residual(self, u, lam):
        self._check(lam)
        return np.array([u[0] - lam])

    def jacobian(self, u, lam):
        self._check(lam)
        return np.array([[1.0]])

    def dparam(self, u, lam):
        self._check(lam)
        return np.array([-1.0])


def test_iterate_outside_the_problem_domain_is_a_failed_step_not_a_crash():
    options = ContinuationOptions(bounds=(-1.0, 1.0), ds=0.2, ds_min=1e-4, ds_max=0.2,
                                  direction=-1)
    result = continue_branch(_DomainLimited(), np.array([0.5]), 0.5, options)
    assert result.status is ContinuationStatus.STEP_BELOW_MINIMUM
    assert result.lam.min() > -0.05


class _RefusedPastOne:
    """``u^3 + u - lam = 0``, defined only for ``lam <= 1`` (like a restitution ``R <= 1``).

    Every ``lam`` it was evaluated at is kept in :attr:`lams`.
    """

    def __init__(self) -> None:
        self.lams: list[float] = []

    def _check(self, lam: float) -> None:
        self.lams.append(lam)
        if lam > 1.0:
            raise ParameterError(f"lam must be in [-1, 1]; got {lam!r}")

    def residual(self, u, lam):
        self._check(lam)
        return np.array([u[0] ** 3 + u[0] - lam])

    def jacobian(self, u, lam):
        self._check(lam)
        return np.array([[3.0 * u[0] ** 2 + 1.0]])

    def dparam(self, u, lam):
        self._check(lam)
        return np.array([-1.0])


def test_branch_to_a_bound_the_problem_refuses_past_lands_exactly_on_it():
    """Every step past lam = 1 is refused by the problem; the branch lands on lam = 1 from
    the last accepted point and ends there as at any bound (it ended 'step size fell below
    ds_min' short of the bound). Witness: the real root of u^3 + u - 1 (numpy.roots)."""
    problem = _RefusedPastOne()
    options = ContinuationOptions(bounds=(-1.0, 1.0), ds=0.05, ds_max=0.3, ds_min=1e-8)
    result = continue_branch(problem, [0.0], 0.0, options)
    assert result.status is ContinuationStatus.BOUNDS_REACHED
    assert result.message == "parameter bound reached: lam = 1"
    assert result.lam[-1] == 1.0
    assert np.all(np.diff(result.lam) > 0.0)
    root = next(r.real for r in np.roots([1.0, 0.0, 1.0, -1.0]) if abs(r.imag) < 1e-12)
    # the landing step was corrected at lam = 1 itself: the last evaluations are there
    assert problem.lams[-1] == 1.0
    assert result.ds[-1] <= options.ds_max
    assert result.u[-1, 0] == pytest.approx(root, abs=1e-9)
    assert max_residual(problem, result) <= options.newton_tol


def test_start_on_a_bound_the_problem_refuses_past_ends_there():
    """From a start on lam = 1 every step leaves the bounds and is refused: the direction
    ends at once on the bound, not at ds_min; the other direction runs as usual."""
    options = ContinuationOptions(bounds=(-1.0, 1.0), ds=0.05, ds_max=0.3, ds_min=1e-8,
                                  both_directions=True)
    result = continue_branch(_RefusedPastOne(), [0.5], 1.0, options)
    assert result.statuses == (ContinuationStatus.BOUNDS_REACHED,
                               ContinuationStatus.BOUNDS_REACHED)
    assert result.message == ("forward: parameter bound reached: lam = 1; "
                              "backward: parameter bound reached: lam = -1")
    assert result.lam[0] == -1.0 and result.lam[-1] == 1.0
    assert result.start_index == len(result) - 1


# -- Ctrl-C ---------------------------------------------------------------------------------------
def _interrupting(at: int) -> object:
    """An on_point that raises KeyboardInterrupt at its `at`-th call."""
    calls: list[int] = []

    def on_point(point: ContinuationPoint) -> None:
        calls.append(point.index)
        if len(calls) == at:
            raise KeyboardInterrupt

    return on_point


def test_ctrl_c_in_the_forward_run_keeps_its_points_and_skips_the_backward_one() -> None:
    from impactcont.progress import interruptible

    options = ContinuationOptions(bounds=(-5.0, 5.0), ds=0.1, ds_max=0.1, both_directions=True)
    on_point = _interrupting(7)
    with interruptible("a line") as call:
        result = continue_branch(Line(), [0.0], 0.0, options, on_point)
    assert call.interrupted and result.interrupted
    assert result.statuses == (ContinuationStatus.INTERRUPTED, ContinuationStatus.INTERRUPTED)
    assert len(result) == 7 and result.start_index == 0  # the point it was raised at kept
    assert np.all(np.diff(result.lam) > 0)
    assert "after 7 points, last at lam = " in result.message
    assert "backward: skipped, interrupted by the user" in result.message


def test_ctrl_c_in_the_backward_run_joins_both_parts() -> None:
    from impactcont.progress import interruptible

    options = ContinuationOptions(bounds=(-1.0, 1.0), ds=0.1, ds_max=0.1, both_directions=True)
    forward = continue_branch(Line(), [0.0], 0.0, options)
    n_forward = len(forward) - forward.start_index
    on_point = _interrupting(n_forward + 4)  # the backward start and 3 more
    with interruptible("a line"):
        result = continue_branch(Line(), [0.0], 0.0, options, on_point)
    assert result.statuses == (ContinuationStatus.BOUNDS_REACHED,
                               ContinuationStatus.INTERRUPTED)
    assert result.start_index == 3 and len(result) == n_forward + 3
    assert np.all(np.diff(result.lam) > 0)


def test_ctrl_c_outside_a_driver_call_or_a_second_one_is_raised() -> None:
    from impactcont.progress import interruptible, take_interrupt

    options = ContinuationOptions(bounds=(-1.0, 1.0), ds=0.1)
    with pytest.raises(KeyboardInterrupt):
        continue_branch(Line(), [0.0], 0.0, options, _interrupting(3))
    with interruptible("a line") as call:
        assert take_interrupt("elsewhere", "a first Ctrl-C")  # taken before the run
        assert call.where == "elsewhere"
        with pytest.raises(KeyboardInterrupt):  # the second
            continue_branch(Line(), [0.0], 0.0, options, _interrupting(1))


def test_a_run_started_after_ctrl_c_was_taken_stops_at_its_first_point() -> None:
    from impactcont.progress import interruptible, take_interrupt

    options = ContinuationOptions(bounds=(-1.0, 1.0), ds=0.1)
    with interruptible("a line"):
        assert take_interrupt("location", "a first Ctrl-C")
        result = continue_branch(Line(), [0.0], 0.0, options)
    assert len(result) == 1 and result.interrupted


class _CountedTiltedCircle(TiltedCircle):
    """:class:`TiltedCircle` counting its residuals at the start's parameter."""

    def __init__(self, lam0: float) -> None:
        self.lam0, self.at_start = lam0, 0

    def residual(self, u: np.ndarray, lam: float) -> np.ndarray:
        self.at_start += lam == self.lam0
        return super().residual(u, lam)


@pytest.mark.parametrize(("problem", "u0", "lam0"), [
    (TiltedCircle, [0.3, 0.9], 0.3), (Parabola, [0.0], 0.0), (Cubic, [-1.1], -0.231)])
def test_the_backward_run_starts_from_the_start_the_forward_run_corrected(problem, u0, lam0
                                                                        ) -> None:
    """Issue 29 (the fixed costs of a short branch): with both directions the start guess
    is corrected once; the backward run takes that point with its tangent reversed (what a
    second correction of the same guess gives, at a fold too: Parabola starts on one). The
    joined branch is the one of two runs each correcting the guess, to the bit (the same
    operations); a problem counting its residuals at the start sees one correction."""
    options = ContinuationOptions(bounds=(-0.5, 0.5), ds=0.05, both_directions=True)
    joined = continue_branch(problem(), u0, lam0, options)
    assert joined.backward_status is ContinuationStatus.BOUNDS_REACHED
    runs = [list(iter_points(problem(), u0, lam0, options, direction))
            for direction in (options.direction, -options.direction)]
    backward = [dataclasses.replace(p, tangent=-p.tangent) for p in reversed(runs[1][1:])]
    separate = backward + runs[0]
    assert joined.start_index == len(backward)
    np.testing.assert_array_equal(joined.u, [p.u for p in separate])
    np.testing.assert_array_equal(joined.lam, [p.lam for p in separate])
    np.testing.assert_array_equal(joined.tangent, [p.tangent for p in separate])
    assert runs[1][0].direction == -1 and np.array_equal(runs[1][0].tangent,
                                                          -runs[0][0].tangent)
    counted = _CountedTiltedCircle(0.3)
    start = list(iter_points(counted, [0.3, 0.9], 0.3, options))[:1]
    corrections = counted.at_start
    assert start and corrections >= 1
    counted.at_start = 0
    continue_branch(counted, [0.3, 0.9], 0.3, options)
    assert counted.at_start == corrections  # the backward run evaluates nothing there


def test_a_reversed_start_must_come_from_the_other_direction() -> None:
    stepper = PalcStepper(Cubic(), ContinuationOptions(bounds=(-1.0, 1.0)), 1)
    start = stepper.init(np.array([-1.2]), -0.528)
    with pytest.raises(ValueError, match=r"the start of a run in direction \+1; this one runs "
                                         r"in \+1"):
        PalcStepper(Cubic(), ContinuationOptions(bounds=(-1.0, 1.0)), 1).init_reversed(start)
    again = PalcStepper(Cubic(), ContinuationOptions(bounds=(-1.0, 1.0)), -1)
    assert np.array_equal(again.init_reversed(start).tangent, -start.tangent)
