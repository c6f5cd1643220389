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
from impactcont.analysis.branch import multi_impact_continuation
from impactcont.core import ContinuationOptions, follow
from impactcont.model.parameters import model_parameter
from impactcont.model.stops import Stops
from impactcont.orbit.multi_impact import multi_impact_orbit
from impactcont.problems import PeriodicBranchProblem
from impactcont.problems.multi_impact_branch import MultiImpactBranchProblem

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


# ------------------------------------------------------------------------------------------
# Parameters as objects: the stops' own parameters and every element (issue 21 item 4)
# ------------------------------------------------------------------------------------------

K2 = [[1.0, -1.0], [-1.0, 2.0]]
NEWTON = 1e-8  # a re-solved N-p motion: Newton's residual 1e-12 times the condition (< 1e4)


def _two_sided(b_low: float = 0.8, R_low: float | None = None, b: float = 0.8,
               **more) -> ic.ImpactOscillator:
    """The paper's 2-DOF system with a lower stop, built from scratch."""
    args = {"M": np.eye(2), "K": K2, "F": [1.0, 0.0], "R": 0.6, "b": b, "omega": 0.8,
            "eta": 0.1, **more}
    return ic.ImpactOscillator(**args, stops=Stops(b_low=b_low, R_low=R_low))


@pytest.fixture(scope="module")
def backlash_motion():
    """The 1-2 motion (one impact on each stop) the simulation from rest settles on."""
    osc = _two_sided()
    res = ic.simulate(osc, np.zeros(4), 0.0, 200.0)
    orbit = multi_impact_orbit(osc, 1, 2, res)
    assert sorted(orbit.pattern) == ["L", "U"]
    return orbit


def _resolve(osc: ic.ImpactOscillator, ds, i: int):
    """Point i of an N-p branch re-solved by Newton on `osc` from its stored motion."""
    return multi_impact_orbit(osc, int(ds.attrs["N"]), ds.sizes["impact"], {
        "delta": float(ds["delta_k"].values[i, 0]), "flight_times": ds["flight_time_k"].values[i],
        "states": ds["state_k"].values[i], "pattern": ds.attrs["pattern"]})


@pytest.mark.parametrize(("parameter", "bounds", "fresh"), [
    ("b_low", (0.7, 0.9), lambda v: _two_sided(b_low=v)),
    ("R_low", (0.45, 0.75), lambda v: _two_sided(R_low=v)),
    ("gap", (0.76, 0.86), lambda v: _two_sided(b_low=v, b=v)),
])
def test_np_branch_in_a_stop_parameter_is_solved_on_fresh_oscillators(backlash_motion, parameter,
                                                                     bounds, fresh):
    ds = multi_impact_continuation(backlash_motion, parameter, bounds, max_points=12,
                                   both_directions=True, symmetric=False)
    assert ds.sizes["point"] >= 4 and ds.attrs["parameter"] == parameter
    values = ds[parameter].values
    assert values.min() < values.max()
    for i in range(ds.sizes["point"]):
        again = _resolve(fresh(float(values[i])), ds, i)
        np.testing.assert_allclose(again.states, ds["state_k"].values[i], rtol=0, atol=NEWTON)
        assert again.delta == pytest.approx(float(ds["delta_k"].values[i, 0]), abs=NEWTON)


def test_symmetric_branch_in_gap_keeps_the_system_symmetric(backlash_motion):
    """gap moves both stops: a symmetric motion stays on its half system (BP detectable)."""
    ds = multi_impact_continuation(backlash_motion, "gap", (0.76, 0.86), max_points=8,
                                   both_directions=True)
    assert json_options(ds)["symmetric"] is True
    for i in (0, ds.sizes["point"] - 1):
        v = float(ds["gap"].values[i])
        again = _resolve(_two_sided(b_low=v, b=v), ds, i)
        np.testing.assert_allclose(again.states, ds["state_k"].values[i], rtol=0, atol=NEWTON)
    with pytest.raises(ic.ParameterError, match="breaks the symmetry"):
        multi_impact_continuation(backlash_motion, "b_low", (0.7, 0.9), symmetric=True)


def json_options(ds) -> dict:
    import json
    return json.loads(ds.attrs["options"])


@pytest.mark.parametrize("parameter", ["b", "b_low", "gap", "R", "R_low", "omega", "F0", "F[2]"])
def test_exact_np_derivatives_agree_with_finite_differences(backlash_motion, parameter):
    osc = backlash_motion.oscillator
    problem = MultiImpactBranchProblem(osc, 1, 2, parameter, pattern=backlash_motion.pattern)
    param = problem.param
    assert param.exact_on_shooting
    u = np.concatenate([[backlash_motion.delta], backlash_motion.flight_times[:-1],
                        np.delete(backlash_motion.states, osc.stops.index, axis=1).ravel()])
    lam = param.value(osc)
    assert np.max(np.abs(problem.residual(u, lam))) < 1e-10
    np.testing.assert_allclose(problem.dparam(u, lam), _five_point(problem, u, lam), rtol=0,
                               atol=1e-8)


def _five_point(problem, u, lam, h=1e-3):
    """A wide five-point difference of the residual (error h^4 |f^(5)| / 30, about 1e-12)."""
    r = [problem.residual(u, lam + k * h) for k in (-2, -1, 1, 2)]
    return (r[0] - 8 * r[1] + 8 * r[2] - r[3]) / (12 * h)


ELEMENTS = [  # name, oscillator (2 masses), bounds, fresh oscillator at a value
    ("k1", {}, (0.9, 1.1), lambda v: {"K": [[v, -v], [-v, v + 1.0]]}),
    ("k2", {}, (0.9, 1.1), lambda v: {"K": [[1.0, -1.0], [-1.0, 1.0 + v]]}),
    ("m2", {}, (0.9, 1.1), lambda v: {"M": np.diag([1.0, v])}),
    ("M[1,2]", {}, (-0.05, 0.05), lambda v: {"M": [[1.0, v], [v, 1.0]]}),
    ("K[1,1]", {}, (0.95, 1.05), lambda v: {"K": [[v, -1.0], [-1.0, 2.0]]}),
    ("F[2]", {}, (-0.2, 0.2), lambda v: {"F": [1.0, v]}),
    ("c1", {"eta": None, "C": [[0.2, -0.2], [-0.2, 0.2]]}, (0.15, 0.25),
     lambda v: {"eta": None, "C": [[v, -v], [-v, v]]}),
    ("C[2,2]", {"eta": None, "C": [[0.2, 0.0], [0.0, 0.1]]}, (0.05, 0.15),
     lambda v: {"eta": None, "C": [[0.2, 0.0], [0.0, v]]}),
]


def _np_points(problem, u0, lam0, bounds, npoints=6):
    options = ContinuationOptions(bounds=bounds, ds=0.02, ds_max=0.05, max_points=npoints,
                                  both_directions=True)
    result = follow(problem, u0, lam0, options)
    assert result.lam.size >= 3 and np.ptp(result.lam) > 0
    return result


@pytest.mark.parametrize(("name", "damping", "bounds", "fresh"), ELEMENTS)
def test_np_problem_in_an_element_is_solved_on_fresh_oscillators(backlash_motion, name, damping,
                                                                  bounds, fresh):
    """Every element on the shooting path: each branch point a motion of the oscillator
    built from scratch at its value (the driver's dataset does not hold element columns
    yet: the problem is followed by the core)."""
    base = _two_sided(**damping)
    seed = multi_impact_orbit(base, 1, 2, backlash_motion)
    problem = MultiImpactBranchProblem(base, 1, 2, name, pattern=seed.pattern)
    u0 = np.concatenate([[seed.delta], seed.flight_times[:-1],
                         np.delete(seed.states, 0, axis=1).ravel()])
    result = _np_points(problem, u0, problem.param.value(base), bounds)
    for u, lam in zip(result.u, result.lam, strict=True):
        orbit = problem.orbit(u, lam, checks=False)
        again = multi_impact_orbit(_two_sided(**{**damping, **fresh(float(lam))}), 1, 2, orbit)
        np.testing.assert_allclose(again.states, orbit.states, rtol=0, atol=NEWTON)


@pytest.mark.parametrize(("name", "damping", "bounds", "fresh"), ELEMENTS)
def test_fd_fallback_error_is_what_the_docs_say(backlash_motion, name, damping, bounds, fresh):
    """The one finite-difference fallback against a wide five-point stencil: within 1e-8
    absolute (measured: 1e-10 or below; exact to rounding for F[2], affine in F)."""
    base = _two_sided(**damping)
    seed = multi_impact_orbit(base, 1, 2, backlash_motion)
    problem = MultiImpactBranchProblem(base, 1, 2, name, pattern=seed.pattern)
    u = np.concatenate([[seed.delta], seed.flight_times[:-1],
                        np.delete(seed.states, 0, axis=1).ravel()])
    lam = problem.param.value(base)
    np.testing.assert_allclose(problem.dparam(u, lam), _five_point(problem, u, lam), rtol=0,
                               atol=1e-8)


@pytest.mark.parametrize(("name", "damping", "fresh"), [
    ("k2", {"eta": 0.1}, lambda v: {"K": [[1.0, -1.0], [-1.0, 1.0 + v]]}),
    ("m1", {"eta": 0.1}, lambda v: {"M": np.diag([v, 1.0])}),
    ("K[1,2]", {"eta": 0.1}, lambda v: {"K": [[1.0, v], [v, 2.0]]}),
    ("F[2]", {"eta": 0.1}, lambda v: {"F": [1.0, v]}),
    ("c2", {"C": [[0.2, -0.2], [-0.2, 0.3]]}, lambda v: {"C": [[0.2, -0.2], [-0.2, 0.2 + v]]}),
    ("C[1,1]", {"C": [[0.2, 0.0], [0.0, 0.1]]}, lambda v: {"C": [[v, 0.0], [0.0, 0.1]]}),
])
def test_n1_branch_in_an_element_matches_periodic_orbits(name, damping, fresh):
    """The N-1 closed form takes every element: each point's phase a root of eq. (15) of
    the oscillator built at its value, and dr/dlam against a wide finite difference."""
    osc = ic.ImpactOscillator(**{**PAPER, **damping})
    problem = PeriodicBranchProblem(osc, 1, name)
    lam0 = problem.param.value(osc)
    delta0 = next(o for o in ic.periodic_orbits(osc, 1) if o.physical).delta
    half = 0.2 if lam0 <= 0.0 else min(0.2, 0.5 * lam0)  # inside a positive range
    result = follow(problem, [delta0], lam0, ContinuationOptions(
        bounds=(lam0 - half, lam0 + half), ds=0.02, ds_max=0.05, max_points=8,
        both_directions=True))
    assert result.lam.size >= 5
    for u, lam in zip(result.u, result.lam, strict=True):
        fresh_osc = ic.ImpactOscillator(**{**PAPER, **damping, **fresh(float(lam))})
        d = [abs(math.remainder(o.delta - u[0], 2 * math.pi))
             for o in ic.periodic_orbits(fresh_osc, 1)]
        assert min(d) < 1e-9, (name, lam, d)
        h = 1e-3
        r = [problem.residual(u, lam + k * h)[0] for k in (-2, -1, 1, 2)]
        five = (r[0] - 8 * r[1] + 8 * r[2] - r[3]) / (12 * h)
        assert problem.dparam(u, lam)[0] == pytest.approx(five, abs=1e-8)


def test_setting_an_element_changes_only_that_element():
    osc = ic.ImpactOscillator.chain(masses=[1.0, 2.0, 3.0], springs=[1.0, 2.0, 3.0], F=[1, 0, 0],
                                    R=0.6, b=0.5, omega=1.0, eta=0.1)
    k2 = model_parameter(osc, "k2")
    assert k2.value(osc) == 2.0
    moved = k2.at(osc, 2.5)
    expected = ic.ImpactOscillator.chain(masses=[1.0, 2.0, 3.0], springs=[1.0, 2.5, 3.0],
                                         F=[1, 0, 0], R=0.6, b=0.5, omega=1.0, eta=0.1)
    np.testing.assert_allclose(moved.K, expected.K, rtol=0, atol=1e-15)
    assert model_parameter(osc, "m3").at(osc, 4.0).M[2, 2] == 4.0
    sym = model_parameter(osc, "K[2,3]").at(osc, -1.0).K
    assert sym[1, 2] == sym[2, 1] == -1.0
    assert model_parameter(osc, "F[3]").at(osc, 0.5).F.tolist() == [1.0, 0.0, 0.5]
    mirrored = ic.ImpactOscillator(**PAPER, eta=0.1, stops=Stops(mirror=True))
    assert model_parameter(mirrored, "gap").at(mirrored, 0.9).stops.b_low == 0.9


@pytest.mark.parametrize(("name", "osc_args", "match"), [
    ("b_low", {}, r"parameter must be one of .*got 'b_low': 'b_low' needs a lower stop"),
    ("R_low", {"stops": Stops(mirror=True)}, "got 'R_low': the mirrored lower stop follows"),
    ("gap", {"stops": Stops(b_low=0.3)}, "got 'gap': 'gap' moves both stops of a symmetric"),
    ("k3", {}, r"parameter='k3' names an element past the oscillator's n=2 masses .*k1..k2"),
    ("F[3]", {}, r"F\[1\]..F\[2\]"),
    ("eta", {"eta": None, "C": [[0.2, 0.0], [0.0, 0.0]]}, "meaningless with a general damping"),
    ("c1", {}, "not given as a matrix"),
    ("m1", {"M": [[1.0, 0.1], [0.1, 1.0]]}, r"needs a diagonal M.*'M\[1,1\]'"),
    ("k1", {"K": [[2.0, -1.0], [-1.0, 1.0]]}, r"is not such a chain.*'K\[i,j\]'"),
    ("F[1]", {"F": [1.0 + 1.0j, 0.0]}, "has a phase of its own"),
    ("F[2]", {"F": [1.0, 0.5j]}, "has a phase of its own"),
    ("q1", {}, r"parameter must be one of .*got 'q1'"),
])
def test_parameters_that_do_not_apply_are_refused(name, osc_args, match):
    osc = ic.ImpactOscillator(**{**PAPER, "eta": 0.1, **osc_args})
    with pytest.raises(ic.ParameterError, match=match):
        model_parameter(osc, name)


# -- bounds and the finite-difference step inside a parameter's admissible range (issue 28) --
def _damper() -> ic.ImpactOscillator:
    """The impact damper of issue 28: a free ball (K[2,2] = 0) in a cavity of mass 1."""
    return ic.ImpactOscillator(M=np.diag([1.0, 0.2]), K=np.diag([1.0, 0.0]), F=[1, 0], R=0.8,
                               b=1.0, omega=1.5, eta=0.05,
                               stops=Stops(mass=2, relative_to=1, mirror=True))


def test_the_difference_is_one_sided_at_the_edge_of_a_matrix_entrys_range():
    osc = _damper()
    param = model_parameter(osc, "K[2,2]")
    # K[2,2] < 0 makes K indefinite: the step below 0 is not taken; f is affine, so exact
    slope = param.difference(lambda v: 3.0 * v + float(param.at(osc, v).K[1, 1]), 0.0, osc)
    assert slope == pytest.approx(4.0, rel=1e-9)
    # K[1,1] of the paper's K = [[t, -1], [-1, 2]] is PSD for t >= 1/2 only
    paper = ic.ImpactOscillator(**PAPER, eta=0.1)
    edge = model_parameter(paper, "K[1,1]")
    at_edge = edge.at(paper, 0.5)
    assert edge.difference(lambda v: v * v, 0.5, at_edge) == pytest.approx(1.0, rel=1e-4)


def test_a_refused_value_names_the_parameter_and_the_value():
    osc = _damper()
    with pytest.raises(ic.ParameterError, match=r"K must be positive semi-definite.*\(at "
                                                r"K\[2,2\] = -0\.001\)"):
        model_parameter(osc, "K[2,2]").at(osc, -0.001)


@pytest.mark.parametrize(("parameter", "bounds", "allowed"), [
    ("K[1,1]", (-1.0, 3.0), "K[1,1] in [0.5, inf)"),     # K = [[t, -1], [-1, 2]]: t >= 1/2
    ("K[1,2]", (-2.0, 0.0), "K[1,2] in [-1.41421356237, 1.41421356237]"),  # t^2 <= 2
    ("M[1,2]", (0.0, 1.0), "M[1,2] in (-1, 1)"),          # M = [[1, t], [t, 1]] definite
])
def test_bounds_of_a_matrix_entry_are_checked_against_the_rest_of_the_matrix(
        parameter, bounds, allowed):
    osc = ic.ImpactOscillator(**PAPER, eta=0.1)
    param = model_parameter(osc, parameter)
    with pytest.raises(ic.ParameterError) as info:
        param.check_bounds(osc, bounds)
    text = str(info.value)
    assert text.startswith(f"bounds {bounds!r} for {parameter}: ") and allowed in text, text


def test_bounds_reaching_the_edge_of_the_range_are_accepted():
    osc = ic.ImpactOscillator(**PAPER, eta=0.1)
    assert model_parameter(osc, "K[1,1]").check_bounds(osc, (0.5, 3.0)) == (0.5, 3.0)
    damper = _damper()  # K[2,2] = 0: a free ball, held by its cavity
    assert model_parameter(damper, "K[2,2]").check_bounds(damper, (0.0, 0.1)) == (0.0, 0.1)


@pytest.mark.parametrize("bounds", [(-1.0, 2.0), (0.0, 2.0), (-2.0, 0.0)])
def test_bounds_of_a_forcing_entry_through_no_forcing_are_refused(bounds) -> None:
    """F = 0 builds a machine (simulated from a state) but has no periodic motion: bounds of
    F[j] that reach it are refused up front, naming the entry (issue 28)."""
    osc = ic.ImpactOscillator(M=np.eye(2), K=[[1, -1], [-1, 2]], F=[1, 0], R=0.6, b=0.6,
                              omega=1.0, eta=0.1)
    with pytest.raises(ic.ParameterError, match=r"at F\[1\] = 0\.0 the forcing vanishes"):
        model_parameter(osc, "F[1]").check_bounds(osc, bounds)
    both = osc.replace(F=[1.0, 1.0])  # F[2] keeps the forcing
    assert model_parameter(both, "F[1]").check_bounds(both, bounds) == bounds


def test_parameter_view_resolves_every_vocabulary_name_and_lists_the_given_ones():
    from impactcont.model.parameters import ParameterView
    from impactcont.vocabulary import PARAMETERS

    units = ParameterView(lambda p: p.unit)
    assert list(units) == list(PARAMETERS) and len(units) == len(PARAMETERS)
    assert units["k2"] == PARAMETERS["k2"].unit and units["gap[A]"] == PARAMETERS["gap[A]"].unit
    assert "M[1,2]" in units and "nonsense" not in units and 3 not in units
    with pytest.raises(KeyError):
        units["nonsense"]
    names = ParameterView(lambda p: p.name, ("omega", "b"))
    assert list(names) == ["omega", "b"] and len(names) == 2
    assert names["F[2]"] == "F[2]"  # a lookup is not limited to the names listed


@pytest.mark.parametrize("bounds", [(0.0, 0.5), (-1.0, 0.5)])
def test_a_spring_reaching_zero_is_refused_saying_why(bounds):
    """k_j = 0 takes the spring away (K singular, another oscillator): refused by every
    driver naming the spring, the end and why (it said only 'finite and > 0')."""
    osc = ic.ImpactOscillator(M=np.eye(2), K=[[0.5, -0.5], [-0.5, 1.5]], F=[1.0, 0.0], R=0.6,
                              b=0.0, omega=1.5, eta=0.1)
    match = (rf"bounds \({bounds[0]}, 0\.5\) for k1 reach k1 = {bounds[0]}: a spring of the "
             r"chain at 0 is taken away \(K singular.*allowed: bounds with k1 > 0")
    with pytest.raises(ic.ParameterError, match=match):
        model_parameter(osc, "k1").check_bounds(osc, bounds)
    with pytest.raises(ic.ParameterError, match=match):
        ic.continuation(osc, 1, "k1", bounds, progress=False)
    motion = multi_impact_orbit(osc, 1, 1, next(o for o in ic.periodic_orbits(osc, 1)
                                                 if o.physical))
    with pytest.raises(ic.ParameterError, match=match):
        multi_impact_continuation(motion, "k1", bounds, progress=False)
    curve_match = r"bounds\['k1'\] " + match[len("bounds "):]
    with pytest.raises(ic.ParameterError, match=curve_match):  # a curve's bounds too
        ic.curve(osc, 1, "PD", parameters=("omega", "k1"),
                 bounds={"omega": (1.0, 2.0), "k1": bounds})
    # other refusals of the range keep their words
    with pytest.raises(ic.ParameterError, match=r"bounds must be two finite numbers .*inf"):
        model_parameter(osc, "k1").check_bounds(osc, (0.1, math.inf))


def test_a_spring_branch_from_just_above_zero_reaches_its_bound():
    osc = ic.ImpactOscillator(M=np.eye(2), K=[[0.5, -0.5], [-0.5, 1.5]], F=[1.0, 0.0], R=0.6,
                              b=0.0, omega=1.5, eta=0.1)
    ds = ic.continuation(osc, 1, "k1", (1e-3, 0.5), components="start", progress=False)
    assert float(ds["k1"].min()) == 1e-3 and float(ds["k1"].max()) == 0.5
