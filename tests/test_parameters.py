"""Continuation in every parameter the API accepts, each point checked independently.

Every point of a branch in omega, b, R, eta, alpha, beta or the forcing amplitude F0 is
recomputed with ``periodic_orbits`` on a freshly built oscillator (its own modal basis,
F written out for F0) at the point's parameter value: the branch's phase must be one of
its roots and the multipliers must agree.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

import impactcont as ic

PAPER = {"M": np.eye(2), "K": [[1.0, -1.0], [-1.0, 2.0]], "F": [1.0, 0.0], "R": 0.6, "b": 0.6,
         "omega": 1.0}
CASES = [
    ("omega", {"eta": 0.1}, (0.8, 2.5)),
    ("b", {"eta": 0.1}, (-0.5, 1.0)),
    ("R", {"eta": 0.1}, (0.0, 1.0)),
    ("eta", {"eta": 0.1}, (0.0, 0.4)),
    ("alpha", {"alpha": 0.05, "beta": 0.1}, (0.0, 0.5)),
    ("beta", {"alpha": 0.05, "beta": 0.1}, (0.0, 0.5)),
    ("F0", {"eta": 0.1}, (0.3, 3.0)),
]


def _fresh(damping: dict, parameter: str, value: float) -> ic.ImpactOscillator:
    """The oscillator at one parameter value, built from scratch (F written out for F0)."""
    if parameter == "F0":
        return ic.ImpactOscillator(**{**PAPER, **damping, "F": [value, 0.0]})
    return ic.ImpactOscillator(**{**PAPER, **damping, parameter: value})


@pytest.mark.parametrize(("parameter", "damping", "bounds"), CASES)
def test_branch_in_every_parameter_matches_periodic_orbits(parameter, damping, bounds):
    osc = ic.ImpactOscillator(**PAPER, **damping)
    branch = ic.continuation(osc, N=1, parameter=parameter, bounds=bounds)
    values = branch[parameter].values
    assert values.min() >= bounds[0] and values.max() <= bounds[1]
    statuses = branch.attrs["options"]
    assert "STEP_BELOW_MINIMUM" not in statuses and "NEWTON" not in statuses
    for i in range(0, branch.sizes["point"], max(1, branch.sizes["point"] // 8)):
        pt = branch.isel(point=i)
        fresh = _fresh(damping, parameter, float(pt[parameter]))
        orbits = ic.periodic_orbits(fresh, 1)
        d = [abs(math.remainder(o.delta - float(pt.delta), 2 * math.pi)) for o in orbits]
        k = int(np.argmin(d))
        assert d[k] < 1e-9, (parameter, float(pt[parameter]), d)
        np.testing.assert_allclose(np.sort_complex(orbits[k].multipliers),
                                   np.sort_complex(pt.multipliers.values), atol=1e-8)
        assert orbits[k].impact_velocity == pytest.approx(float(pt.impact_velocity), rel=1e-8,
                                                          abs=1e-10)
    for label, value in zip(branch.special_label.values, branch[f"special_{parameter}"].values,
                            strict=True):
        assert bounds[0] <= value <= bounds[1], label


def test_branch_reaches_both_ends_of_the_restitution_range():
    branch = ic.continuation(ic.ImpactOscillator(**PAPER, eta=0.1), 1, "R", (0.0, 1.0))
    assert branch.R.values.min() == 0.0 and branch.R.values.max() == 1.0


@pytest.mark.parametrize(("parameter", "bounds", "match"), [
    ("R", (0.0, 1.5), "R is in \\[0, 1\\]"), ("omega", (0.0, 2.0), "omega is finite and > 0"),
    ("eta", (-0.1, 0.2), "eta is finite and >= 0"), ("omega", (0.5,), "two numbers")])
def test_bounds_outside_the_parameter_range_are_refused(parameter, bounds, match):
    with pytest.raises(ic.ParameterError, match=match):
        ic.continuation(ic.ImpactOscillator(**PAPER, eta=0.1), 1, parameter, bounds)


@pytest.mark.parametrize("eta", [0.1, 0.0])
def test_a_branch_that_closes_modulo_two_pi_stops_with_each_special_point_once(eta):
    """In b the branch is a closed curve in (delta mod 2 pi, b); it used to run to max_points."""
    osc = ic.ImpactOscillator(**{**PAPER, "omega": 1.2, "b": 0.0}, eta=eta)
    branch = ic.continuation(osc, N=1, parameter="b", bounds=(-3.0, 3.0))
    options = branch.attrs["options"]
    assert '"status": ["CLOSED_LOOP", "CLOSED_LOOP"]' in options
    assert branch.sizes["point"] < 500
    assert np.ptp(branch.delta.values) < 2 * math.pi + 0.5
    found = sorted(zip(branch.special_label.values.tolist(),
                       np.round(branch.special_b.values, 6).tolist(), strict=True))
    assert len(found) == len(set(found)) > 0
    # the solution set is symmetric under (b, delta) -> (-b, delta + pi): so are its points
    # (undamped, the PD next to the pole of G at ZV used to be found on one side only)
    for label, b in found:
        assert (label, round(-b, 6)) in found or label == "GR"


def test_special_points_do_not_depend_on_the_step():
    """A PD and a ZV in one step: det(G + I) had a pole between them and the PD was lost."""
    osc = ic.ImpactOscillator(**PAPER, eta=0.1)
    runs = [ic.continuation(osc.replace(b=0.5), 1, "omega", (0.6, 2.0), ds_max=ds_max)
            for ds_max in (0.05, 0.02, 0.005)]
    reference = sorted(zip(runs[-1].special_label.values.tolist(),
                           runs[-1].special_omega.values.tolist(), strict=True))
    assert {"GR", "NS", "PD", "SN", "ZV"} <= {label for label, _ in reference}
    for run in runs[:-1]:
        found = sorted(zip(run.special_label.values.tolist(), run.special_omega.values.tolist(),
                           strict=True))
        assert [label for label, _ in found] == [label for label, _ in reference]
        for (_, a), (_, b) in zip(found, reference, strict=True):
            assert a == pytest.approx(b, abs=1e-9)


def test_first_step_adapts_to_a_small_ds_max():
    """ds_max below the default first step used to raise unless ds was given too."""
    osc = ic.ImpactOscillator(**PAPER, eta=0.1)
    fine = ic.continuation(osc, 1, "omega", (0.8, 1.2), ds_max=0.004)
    coarse = ic.continuation(osc, 1, "omega", (0.8, 1.2))
    assert '"ds": 0.004' in fine.attrs["options"]
    assert fine.sizes["point"] > 2 * coarse.sizes["point"]


def test_every_component_in_the_range_is_returned():
    """N = 2 at b = 0.5 from omega = 1: the physical motions at omega 1.3-2.1 are a separate
    component, which the branch through the start alone misses."""
    osc = ic.ImpactOscillator(**{**PAPER, "b": 0.5}, eta=0.1)
    branch = ic.continuation(osc, N=2, parameter="omega", bounds=(0.5, 6.0))
    alone = ic.continuation(osc, N=2, parameter="omega", bounds=(0.5, 6.0), components="start")
    assert not alone.physical.values.any()
    parts = branch.connected_component.values
    assert set(parts.tolist()) == {0, 1, 2}
    first = branch.isel(point=np.flatnonzero(parts == 0))
    np.testing.assert_array_equal(first.omega.values, alone.omega.values)
    # the independent witness: every root of eq. (15) on a grid lies on some component
    for w in np.linspace(0.55, 5.95, 41):
        for orbit in ic.periodic_orbits(osc.replace(omega=float(w)), 2):
            near = np.abs(branch.omega.values - w) < 0.06
            gaps = np.abs(np.remainder(branch.delta.values[near] - orbit.delta + np.pi,
                                       2 * np.pi) - np.pi)
            assert gaps.size and gaps.min() < 0.3, (w, orbit)
            if orbit.physical:
                assert branch.physical.values[near].any()


def test_forcing_amplitude_scales_the_forcing_and_keeps_the_modes():
    osc = ic.ImpactOscillator(**{**PAPER, "F": [0.5, -0.25]}, eta=0.1)
    assert osc.F0 == 0.5
    stronger = osc.replace(F0=2.0)
    np.testing.assert_array_equal(stronger.F, [2.0, -1.0])
    assert stronger.F0 == 2.0
    np.testing.assert_allclose(stronger.modes.modal_forces, 4.0 * osc.modes.modal_forces,
                               rtol=1e-15)
    np.testing.assert_array_equal(stronger.modes.u, osc.modes.u)
    for bad, match in ((0.0, "F0 must be finite and > 0"), (-1.0, "F0 must be finite and > 0"),
                       (math.inf, "F0")):
        with pytest.raises(ic.ParameterError, match=match):
            osc.replace(F0=bad)
    with pytest.raises(ic.ParameterError, match="F or F0"):
        osc.replace(F0=1.0, F=[1.0, 0.0])


def test_branch_in_forcing_amplitude_at_zero_gap_keeps_its_phase():
    """With b = 0 eq. (14) is homogeneous in F: the motion scales, its phase does not."""
    osc = ic.ImpactOscillator(**{**PAPER, "b": 0.0, "omega": 1.2}, eta=0.1)
    branch = ic.continuation(osc, N=1, parameter="F0", bounds=(0.5, 2.0), components="start")
    assert np.ptp(branch.delta.values) < 1e-12
    scale = branch.F0.values / osc.F0
    reference = ic.periodic_orbits(osc, 1)
    k = int(np.argmin([abs(o.delta - float(branch.delta[0])) for o in reference]))
    np.testing.assert_allclose(branch.impact_velocity.values,
                               scale * reference[k].impact_velocity, rtol=1e-12)


def test_period_doubling_curve_in_forcing_amplitude_at_zero_gap_is_vertical():
    """At b = 0 the motion scales with F0 and G does not change: PD sits at one omega."""
    osc = ic.ImpactOscillator(**{**PAPER, "b": 0.0, "omega": 1.5}, eta=0.1)
    branch = ic.continuation(osc, N=1, parameter="omega", bounds=(0.5, 3.0), detect=("PD",),
                             components="start")
    pd_omega = float(branch.special_omega.values[0])
    curve = ic.curve(osc, 1, "PD", start=branch, parameters=("omega", "F0"),
                     bounds={"omega": (0.5, 3.0), "F0": (0.2, 3.0)})
    assert float(curve.F0.min()) == pytest.approx(0.2) and float(curve.F0.max()) == 3.0
    np.testing.assert_allclose(curve.omega.values, pd_omega, rtol=1e-10)


def test_fold_in_forcing_amplitude_is_where_the_amplitude_reaches_the_gap():
    """c, s are linear in F0, so the fold of eq. (15) sits at F0 = b / sqrt(c^2 + s^2)."""
    osc = ic.ImpactOscillator(**{**PAPER, "b": 0.3, "omega": 1.5}, eta=0.1)
    branch = ic.continuation(osc, N=1, parameter="F0", bounds=(0.1, 5.0), detect=("SN",))
    expected = 0.3 / math.sqrt(ic.amplitude_squared(osc, 1))
    assert branch.special_F0.values.tolist() == pytest.approx([expected], rel=1e-14)
