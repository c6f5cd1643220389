"""Robust stability (eq. 26-29) of N-p motions: two impacts per period on one stop, and
one on each of two stops with a damping matrix (issue 29, item 9).

The bound of eq. (29) holds for any G; for an N-p motion G(q) is the motion re-solved
at q. The independent witness: the motion re-solved by Newton at random points of the
box (not the grid :func:`robust_stability` evaluates) and the eigenvalues of its G.
"""

from __future__ import annotations

import numpy as np
import pytest

import impactcont as ic
from impactcont.errors import NoPeriodicMotionError, ParameterError
from impactcont.model.parameters import model_parameter
from impactcont.model.stops import Stops
from impactcont.orbit.multi_impact import multi_impact_orbit
from tests._multi_impact_cases import orbit_at_point

K2 = [[1.0, -1.0], [-1.0, 2.0]]


@pytest.fixture(scope="module")
def motion_22(branch_22):
    """The most stable physical 2-2 motion of the period-doubling branch at b = 0."""
    rho = np.where(branch_22.physical.values, branch_22.spectral_radius.values, np.inf)
    return orbit_at_point(branch_22, int(np.argmin(rho)))


@pytest.fixture(scope="module")
def damper_12():
    """A 1-2 motion between two stops (b = b_low = 0.8) with a damper on mass 1 only (a
    damping matrix C, the first-order flow), as the simulation from rest settles on it."""
    osc = ic.ImpactOscillator(M=np.eye(2), K=K2, F=[1.0, 0.0], R=0.6, b=0.8, omega=0.8,
                              C=[[0.3, 0.0], [0.0, 0.0]], stops=Stops(b_low=0.8))
    res = ic.simulate(osc, np.zeros(4), 0.0, 200.0)
    orbit = multi_impact_orbit(osc, 1, 2, res)
    assert orbit.physical and orbit.stable and sorted(orbit.pattern) == ["L", "U"]
    return orbit


def _witness(motion, vary, count, seed):
    """Spectral radius and |G(q) - G0| of the motion re-solved at random points of the box,
    each from the motion given (numpy's eigenvalues of the re-solved G)."""
    rng = np.random.default_rng(seed)
    params = [model_parameter(motion.oscillator, name) for name in vary]
    out = []
    for _ in range(count):
        osc = motion.oscillator
        for param, (lo, hi) in zip(params, vary.values(), strict=True):
            osc = param.at(osc, float(lo + (hi - lo) * rng.random()))
        m = multi_impact_orbit(osc, motion.N, motion.p, motion, pattern=motion.pattern)
        assert m.physical
        out.append((float(np.abs(np.linalg.eigvals(m.G)).max()), m.G))
    return out


@pytest.mark.parametrize(("case", "vary"), [
    ("motion_22", {"R": (0.58, 0.62)}),
    ("motion_22", {"omega": (-0.002, 0.002), "b": (-0.005, 0.005)}),
    ("damper_12", {"b_low": (0.79, 0.81), "R_low": (0.58, 0.62)}),
])
def test_robust_np_motion_stays_stable_where_the_bound_says(case, vary, request):
    """Where eq. (29) holds, every re-solved motion in the box has rho(G) < 1, and its
    |G(q) - G0| stays within theta (the maximum of eq. 28, by grid and refinement)."""
    motion = request.getfixturevalue(case)
    osc = motion.oscillator
    if "omega" in vary:  # a box about the motion's own frequency
        vary = {**vary, "omega": tuple(osc.omega + d for d in vary["omega"])}
    nominal = {name: model_parameter(osc, name).value(osc) for name in vary}
    result = ic.robust_stability(motion, vary=vary, nominal=nominal, samples=5)
    assert result.p == motion.p and result.N == motion.N and result.root == 0
    np.testing.assert_allclose(result.G0, motion.G, rtol=1e-9, atol=1e-12)
    assert result.robust, result.summary()
    assert result.epsilon < result.epsilon0
    assert f"p={motion.p}" in result.summary()
    for rho, G in _witness(motion, vary, 12, seed=len(vary)):
        assert rho < 1.0
        # theta is the maximum of |dG| over the box: what the witness sees is below it
        # (smooth entries, the refinement's and Newton's tolerance)
        assert np.all(np.abs(G - result.G0) <= result.theta * (1 + 1e-6) + 1e-9)


def test_robust_np_motion_refused_past_its_period_doubling(motion_22):
    """A box reaching past where the 2-2 motion loses stability (rho(G) > 1 at its far
    end, seen by the witness): the bound is exceeded, robust stability not established."""
    osc = motion_22.oscillator
    far = osc.omega + 0.08
    ahead = multi_impact_orbit(osc.replace(omega=osc.omega + 0.04), 2, 2, motion_22)
    end = multi_impact_orbit(osc.replace(omega=far), 2, 2, ahead)
    assert end.physical and end.spectral_radius > 1.0  # the witness: unstable in the box
    result = ic.robust_stability(motion_22, vary={"omega": (osc.omega - 0.01, far)},
                                 nominal={"omega": osc.omega}, samples=17)
    assert not result.robust
    assert result.epsilon >= result.epsilon0


def test_np_motion_arguments_are_checked(motion_22, damper_12):
    osc = motion_22.oscillator
    with pytest.raises(ParameterError, match="root must be None"):
        ic.robust_stability(motion_22, vary={"R": (0.5, 0.7)}, root=1)
    with pytest.raises(ParameterError, match="N must be None or the motion's own N=2"):
        ic.robust_stability(motion_22, 1, {"R": (0.5, 0.7)})
    with pytest.raises(ParameterError, match="b_low"):  # no lower stop on this system
        ic.robust_stability(motion_22, vary={"b_low": (0.5, 0.7)})
    with pytest.raises(ParameterError, match="leaves the admissible"):
        ic.robust_stability(motion_22, vary={"R": (0.5, 1.2)})
    assert ic.robust_stability(damper_12, 1, {"R_low": (0.59, 0.61)}, samples=3).robust
    with pytest.raises(NoPeriodicMotionError, match="N=2, p=2 motion"):  # b far from b = 0
        ic.robust_stability(motion_22, vary={"b": (osc.b - 0.01, osc.b + 3.0)}, samples=3)
