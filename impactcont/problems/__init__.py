"""Problems the continuation core follows: branches of periodic motions."""

from impactcont.problems.periodic_branch import CONTINUABLE_PARAMETERS, PeriodicBranchProblem

__all__ = ["CONTINUABLE_PARAMETERS", "PeriodicBranchProblem"]
