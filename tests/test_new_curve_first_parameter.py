"""A curve of an N-p branch continued in a parameter other than omega or b (an element,
the forcing amplitude): the dataset stores the first parameter's column, and each curve
point is the special point it claims (a multiplier -1 on a PD curve)."""

from __future__ import annotations

import numpy as np
import pytest

import impactcont as ic
from impactcont.model.parameters import model_parameter


@pytest.fixture(scope="module")
def paper_motion():
    osc = ic.ImpactOscillator(M=np.eye(2), K=[[1.0, -1.0], [-1.0, 2.0]], F=[1.0, 0.0],
                              eta=0.1, R=0.6, b=0.6, omega=1.0)
    return next(o for o in ic.periodic_orbits(osc, 1) if o.physical)


@pytest.mark.parametrize("p1", ["k2", "M[1,2]"])
def test_a_pd_curve_in_an_element_and_omega_is_stored_and_exact(paper_motion, p1, tmp_path):
    lo, hi = (0.2, 5.0) if p1 == "k2" else (-0.4, 0.4)
    branch = ic.multi_impact_continuation(paper_motion, parameter=p1, bounds=(lo, hi))
    labels = [str(v) for v in branch.special_label.values]
    if "PD" not in labels:
        pytest.skip(f"no PD on the {p1} branch: {labels}")
    curve = ic.multi_impact_curve(branch, kind="PD", parameter="omega",
                                  bounds={p1: (lo, hi), "omega": (0.5, 3.0)}, max_points=12)
    assert p1 in curve and curve[p1].dims == ("point",)
    assert np.all(np.isfinite(curve[p1].values))
    osc = paper_motion.oscillator
    for k in range(0, curve.sizes["point"], 4):  # the witness: the closed form's G there
        at = model_parameter(osc, p1).at(osc, float(curve[p1].values[k]))
        at = at.replace(omega=float(curve.omega.values[k]))
        orbits = ic.periodic_orbits(at, 1)
        near = min(orbits, key=lambda o: abs(o.delta - float(curve.delta.values[k])))
        assert np.min(np.abs(np.asarray(near.multipliers) + 1.0)) < 1e-6
    path = tmp_path / "curve.nc"
    ic.save(curve, path)
    back = ic.load(path)
    np.testing.assert_array_equal(back[p1].values, curve[p1].values)
