"""Former home of the N-p branch driver: now the one driver of every motion,
:mod:`impactcont.analysis.branch`.

Re-exports for those who import from here (the lead removes this shim):
``multi_impact_continuation`` (an alias of :func:`impactcont.continuation` on the shooting
system), ``run_branch``, ``trace_branch``, ``branch_to_dataset``, ``branch_problem``,
``restart_problem``, ``make_options``, ``as_multi_impact_orbit``,
``user_events_until_interrupted`` and the sample type ``MultiImpactSample``
(:class:`~impactcont.detection.special_points.BranchSample`).
"""

from impactcont.analysis.branch import (  # noqa: F401 - the private two for old tests
    _asymmetry,
    _pd_sign_change,
    as_multi_impact_orbit,
    branch_problem,
    branch_to_dataset,
    make_options,
    multi_impact_continuation,
    restart_problem,
    run_branch,
    trace_branch,
    user_events_until_interrupted,
)
from impactcont.detection.special_points import BranchSample as MultiImpactSample

__all__ = ["MultiImpactSample", "as_multi_impact_orbit", "branch_problem", "branch_to_dataset",
           "make_options", "multi_impact_continuation", "restart_problem", "run_branch",
           "trace_branch", "user_events_until_interrupted"]
