"""Codim-2 points on curves of N-p motions (:func:`impactcont.multi_impact_curve`), located by
the same code as on the N-1 curves of :func:`impactcont.curve`.

Witnesses: the closed form (an N-1 motion followed by shooting as a 1-1 motion has the
codim-2 points of the closed-form curve, each within the two stated precisions), and for a
genuine N-p motion (the 2-2 motion of the paper's system at b = 0) the motion re-solved by
shooting at the located point, whose multipliers (numpy's eigenvalues of G, not the curve's
test functions) hold both critical values there.
"""

from __future__ import annotations

import numpy as np
import pytest

import impactcont as ic
from impactcont.analysis.curves import multi_impact_curve
from impactcont.orbit.multi_impact import multi_impact_orbit

BOX = {"omega": (0.6, 2.0), "b": (0.0, 0.6)}


@pytest.fixture(scope="module")
def system() -> ic.ImpactOscillator:
    return ic.ImpactOscillator(M=np.eye(2), K=[[1.0, -1.0], [-1.0, 2.0]], F=[1.0, 0.0], R=0.6,
                               b=0.0, omega=1.75, eta=0.1)


def _points(ds) -> list[tuple[str, float, float, float, str]]:
    return list(zip(ds.codim2_label.values.tolist(), ds.codim2_omega.values,
                    ds.codim2_b.values, ds.codim2_precision.values,
                    ds.codim2_status.values.tolist(), strict=True))


def test_codim2_points_of_an_n1_motion_by_shooting_are_those_of_the_closed_form(system,
                                                                             tmp_path):
    closed = ic.curve(None, None, "PD", start=ic.continuation(system, 1, "omega", (1.6, 1.9),
                                                              detect=("PD",)), bounds=BOX)
    physical = next(q for q in ic.periodic_orbits(system, 1) if q.physical)
    branch = ic.multi_impact_continuation(ic.multi_impact_orbit(system, 1, 1, physical),
                                          "omega", (1.6, 1.9), detect=("PD",),
                                          both_directions=True)
    by_shooting = ic.curve(None, None, "PD", start=branch, parameters=("omega", "b"),
                           bounds=BOX)
    expected, found = _points(closed), _points(by_shooting)
    assert sorted(p[0] for p in expected) == ["PD+NS", "PD+SN", "PD+ZV", "R2"]
    assert sorted(p[0] for p in found) == sorted(p[0] for p in expected)
    for label, omega, b, precision, status in expected:
        (twin,) = [p for p in found if p[0] == label]
        assert status == twin[4] == "located"
        # both located within their stated precisions (in the plane of the parameters)
        assert max(abs(omega - twin[1]), abs(b - twin[2])) <= precision + twin[3], label
    # the shooting test's rounding noise sets the precision (1.14e-9 on one processor,
    # below 1e-9 on others): what the method guarantees is well below 1e-8
    assert max(p[3] for p in found) < 1e-8
    # the variables of an N-1 curve's codim-2 points, on the same dimension, kept by a file
    names = [k for k in closed.data_vars if k.startswith("codim2_")]
    assert set(names) <= set(by_shooting.data_vars)
    back = ic.load(ic.save(by_shooting, tmp_path / "curve.nc"))
    for name in names:
        assert back[name].dims == by_shooting[name].dims == closed[name].dims
        np.testing.assert_array_equal(back[name].values, by_shooting[name].values)


def test_a_codim2_point_of_a_2_2_motion_holds_both_critical_multipliers(branch_22):
    """The PD curve of the 2-2 motion meets the fold of the 2-2 branches (PD+SN): at the
    located point the motion re-solved by shooting has a multiplier -1 and one +1."""
    cv = multi_impact_curve(branch_22, "PD", 0, parameter="b",
                            bounds={"omega": (1.7, 1.85), "b": (0.0, 0.15)})
    labels = cv.codim2_label.values.tolist()
    assert {"R2", "PD+ZV", "PD+SN"} <= set(labels)
    k = labels.index("PD+SN")
    point = cv.isel(codim2=k)
    assert str(point.codim2_status.values) == "located"
    assert float(point.codim2_precision) < 1e-10
    omega, b = float(point.codim2_omega), float(point.codim2_b)
    nearest = int(point.codim2_point)
    osc = ic.dataset.oscillator_from_dataset(cv, nearest).replace(omega=omega, b=b)
    guess = {"delta": float(cv.delta_k.values[nearest, 0]),
             "flight_times": cv.flight_time_k.values[nearest],
             "states": cv.state_k.values[nearest]}
    orbit = multi_impact_orbit(osc, 2, 2, guess)
    mu = np.linalg.eigvals(orbit.G)
    # at a fold the motion moves as the square root of the distance to it: a point known
    # to 1e-13 gives the multipliers to about 1e-7 (measured 2e-8 and 9e-8); the others
    # are far from +-1
    assert np.sum(np.abs(mu + 1.0) < 1e-5) == 1 and np.sum(np.abs(mu - 1.0) < 1e-5) == 1, mu
    assert np.sort(np.minimum(np.abs(mu + 1.0), np.abs(mu - 1.0)))[2] > 0.1, mu
    # the multipliers stored with the point are the motion's
    stored = point.codim2_multipliers.values
    assert np.min(np.abs(stored + 1.0)) < 1e-5 and np.min(np.abs(stored - 1.0)) < 1e-5
