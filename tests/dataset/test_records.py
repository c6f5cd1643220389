"""Special-point records (:mod:`impactcont.dataset.records`) carry the motion's impact
velocity and gap (issue 11, item 7)."""

from __future__ import annotations

import math
import warnings

import numpy as np

import impactcont as ic


def test_special_points_store_impact_velocity_and_gap(tmp_path):
    osc = ic.ImpactOscillator(M=np.eye(2), K=[[1.0, -1.0], [-1.0, 2.0]], F=[1.0, 0.0], R=0.6,
                              b=0.5, omega=1.0, eta=0.1)
    ds = ic.continuation(osc, 1, "omega", (0.5, 3.0))
    assert ds.sizes["special"] >= 5
    for k in range(ds.sizes["special"]):
        row = ds.isel(special=k)
        label, v, gap = str(row.special_label.values), float(row.special_impact_velocity), \
            float(row.special_gap_min)
        with warnings.catch_warnings():  # recomputed at ZV: G's warning is expected there
            warnings.simplefilter("ignore", ic.LowImpactVelocityWarning)
            orbits = ic.periodic_orbits(osc.replace(omega=float(row.special_omega)), 1)
        if orbits:  # at a fold rounding may leave no root: the record still has the values
            orbit = min(orbits, key=lambda o: abs(math.remainder(
                o.delta - float(row.special_delta), 2 * math.pi)))
            assert abs(orbit.impact_velocity - v) < 1e-6
        if label == "ZV":
            assert abs(v) < 1e-9
        if label == "GR":
            assert abs(gap) < 1e-9
    ic.save(ds, tmp_path / "b.nc")
    back = ic.load(tmp_path / "b.nc")
    np.testing.assert_array_equal(back.special_gap_min.values, ds.special_gap_min.values)
