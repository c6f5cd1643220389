"""The exact flow, closed-form periodic motions, G and robust stability (eq. 9-29)."""

# multi_impact_orbit solves a pattern with sticking phases through the solver this module
# registers (impactcont.orbit.multi_impact.STICKY_SOLVER): it imports multi_impact, so
# multi_impact cannot import it
from impactcont.orbit import sticky as _sticky  # noqa: F401
