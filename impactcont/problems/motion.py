"""The one interface of a motion and of a branch problem over it.

A periodic motion of an impact oscillator is a sequence of segments: p flights
(free motion between contacts, eq. 9) each ended by an impact on a named stop
(eq. 4), repeated every N forcing periods. Sticking phases (issue 30) are a further
kind of segment. Every driver, detector and dataset builder of a one-parameter branch
reads a motion through :class:`Motion` and follows a branch through
:class:`BranchProblem`; nothing else of the motion's evaluator is seen.

*The motion.* Two evaluators give a :class:`Motion`:

- the N-1 closed form of the paper (eq. 12-16, :class:`~impactcont.orbit.periodic.PeriodicOrbit`):
  p = 1, exact to rounding and the fast path; its per-impact view (``phases``,
  ``states``, ...) has one entry;
- the shooting system of any N-p motion (:class:`~impactcont.orbit.multi_impact.MultiImpactOrbit`):
  p flights with the exact flow, any stops.

What the driver and the detectors read:

==========================  ===============================================================
``oscillator``, ``N``, ``p``  the system (its parameters at the point), periods, impacts
``pattern``                   the stop of each impact (``"U"``/``"L"``, or a named stop)
``phases``                    forcing phase ``theta_k`` at each impact, shape (p,)
``flight_times``              ``tau_k``, shape (p,), summing to ``2 pi N / omega``
``states``                    ``X_k`` right after each impact, shape (p, 2n)
``impact_velocities``         velocity towards the stop before each impact, shape (p,)
``flight_gap_min``            smallest clearance of each flight, shape (p,)
``delta``, ``state``          impact 0's phase and state
``impact_velocity``           the smallest of ``impact_velocities`` (the ZV test)
``gap_min``                   the smallest of ``flight_gap_min`` (the GR test)
``G``, ``multipliers``        the impact-map Jacobian (eq. 25; the product of the p maps)
                              and its eigenvalues (the SN, PD, NS tests)
``physical``, ``reason``      the checks of eq. (16) on every flight and stop
``stable``                    Theorem 3.1: ``rho(G) < 1``
==========================  ===============================================================

*The branch problem.* A :class:`BranchProblem` is ``F(u, lam) = 0`` for the continuation core
(:class:`impactcont.core.Problem`: ``residual``, ``jacobian``, ``dparam``) plus:

- ``orbit(u, lam, checks=True)``: the :class:`Motion` at a point (``checks=False`` may
  skip the costly interior-contact search when a test does not need it);
- ``events``: the special-point kinds (:class:`~impactcont.vocabulary.Label`) it declares,
  and ``motion_tests``: the test of each kind but the fold, as functions of the motion
  (:mod:`impactcont.problems.events`); a symmetric motion's problem declares BP;
- ``parameter``, ``param`` (the :class:`~impactcont.model.parameters.ModelParameter`),
  ``osc``, ``N``, ``p``, ``pattern`` and ``oscillator_at(lam)``;
- ``check_bounds(bounds)`` and ``parameter_limits()``: where the parameter may go.

Its seed is a motion: :func:`impactcont.continuation` takes a
:class:`~impactcont.orbit.periodic.PeriodicOrbit`, a
:class:`~impactcont.orbit.multi_impact.MultiImpactOrbit`, or an oscillator and N (the
closed form's roots of eq. 15 then seed the branch).

Optional hooks (an evaluator's own exact shortcuts; the driver uses them when present):

- ``locate_fold(left, right)``: a fold located exactly between two samples (the closed
  form's Newton on ``r = dr/d delta = 0``, eq. 14-15); without it the fold is the sign
  change of ``d lam / ds`` located on the chord like every other kind;
- ``fold_kind(orbits)``: the kind of a located fold from the motions there and at the
  two bracketing points (a fold of a general N-p branch that meets a branch of
  symmetric motions is the pitchfork BP);
- ``component_seeds(bounds)``, ``start_value(bounds, start)``, ``start_root(lam, root)``:
  the N-1 existence scan of eq. (15) (both roots, every connected component);
- ``separate_checks``: False when ``orbit``'s contact checks cost nothing extra (the
  closed form), so the detector keeps one motion per trial point;
- ``motion_in_step``: False when the motion at an accepted point is better evaluated
  after the branch is traced (the closed form: nothing of the corrector's to reuse) than
  as the point is accepted (a shooting problem reuses the corrector's cached shot);
- ``impact_dimension``: True when the branch's dataset has the ``impact`` dimension
  (:mod:`impactcont.dataset.multi`); the closed form's N-1 branches keep the schema of
  the paper (read as p = 1).
"""

from __future__ import annotations

from typing import Any, Protocol, runtime_checkable

import numpy as np

__all__ = ["BranchProblem", "Motion"]


@runtime_checkable
class Motion(Protocol):
    """A periodic motion as a sequence of p flights and impacts (module notes)."""

    oscillator: Any
    N: int
    p: int
    pattern: str
    physical: bool
    reason: str

    @property
    def phases(self) -> np.ndarray: ...

    @property
    def flight_times(self) -> np.ndarray: ...

    @property
    def states(self) -> np.ndarray: ...

    @property
    def impact_velocities(self) -> np.ndarray: ...

    @property
    def flight_gap_min(self) -> np.ndarray: ...

    @property
    def delta(self) -> float: ...

    @property
    def state(self) -> np.ndarray: ...

    @property
    def impact_velocity(self) -> float: ...

    @property
    def gap_min(self) -> float: ...

    @property
    def G(self) -> np.ndarray: ...  # the paper's name (eq. 25)

    @property
    def multipliers(self) -> np.ndarray: ...

    @property
    def stable(self) -> bool: ...


@runtime_checkable
class BranchProblem(Protocol):
    """A one-parameter branch of motions for the continuation core (module notes)."""

    parameter: str
    N: int
    events: tuple[Any, ...]

    def residual(self, u: np.ndarray, lam: float) -> np.ndarray: ...

    def jacobian(self, u: np.ndarray, lam: float) -> np.ndarray: ...

    def dparam(self, u: np.ndarray, lam: float) -> np.ndarray: ...

    def orbit(self, u: Any, lam: float, *, checks: bool = True) -> Motion: ...

    def oscillator_at(self, lam: float) -> Any: ...

    def check_bounds(self, bounds: tuple[float, float]) -> None: ...
