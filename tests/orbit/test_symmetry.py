"""Symmetric motions, the symmetry-breaking pitchfork (BP) and switching onto the asymmetric pair.

The system is the paper's 2-DOF chain with mass 1 between two equal stops (backlash,
``b = b_low = 0.5``, ``R = R_low = 0.6``). Independent witnesses: the event-driven
simulator (the half-map by central differences of a simulated flight, the motions of
the switched branches, the stability change across each pitchfork), finite
differences of the half system, and the mirror symmetry itself.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

import impactcont as ic
from impactcont.analysis.branch import multi_impact_continuation
from impactcont.analysis.switching import pitchfork_switch
from impactcont.errors import ParameterError
from impactcont.model.stops import Stops
from impactcont.orbit.flow import Flow
from impactcont.orbit.multi_impact import multi_impact_orbit, orbit_from_unknowns
from impactcont.orbit.symmetry import (
    admits_symmetric_motions,
    half_map,
    mirror_image,
    mirror_pattern,
    pitchfork_test,
    symmetric_system,
    symmetry_defect,
)
from impactcont.plots import bifurcation_diagram
from impactcont.problems.symmetric_branch import SymmetricBranchProblem

K2 = [[1.0, -1.0], [-1.0, 2.0]]
PAPER_C = [[0.2, -0.2], [-0.2, 0.4]]  # 2 eta K, eta = 0.1, as a matrix
OMEGA = (0.9, 1.45)  # both pitchforks of the b = 0.5 system, 0.96405 and 1.33782


def backlash(omega: float, b: float = 0.5, **damping) -> ic.ImpactOscillator:
    return ic.ImpactOscillator(M=np.eye(2), K=K2, F=[1.0, 0.0], R=0.6, b=b, omega=omega,
                               **(damping or {"eta": 0.1}), stops=Stops(b_low=b, R_low=0.6))


def settled(osc: ic.ImpactOscillator, state=None, phase: float = 0.0, periods: float = 150.0):
    """The 1-2 motion the simulator settles on."""
    res = ic.simulate(osc, np.zeros(4) if state is None else state, phase, periods)
    return multi_impact_orbit(osc, 1, 2, res)


@pytest.fixture(scope="module")
def symmetric():
    return settled(backlash(1.6))


@pytest.fixture(scope="module")
def asymmetric():
    return settled(backlash(1.3))


@pytest.fixture(scope="module")
def branch(symmetric):
    return multi_impact_continuation(symmetric, "omega", (OMEGA[0], 1.7), both_directions=True,
                                     ds_max=0.02)


def _bps(ds):
    labels = ds["special_label"].values
    return [k for k, lab in enumerate(labels) if lab == "BP"]


# ------------------------------------------------------------------------------------------
# The symmetry
# ------------------------------------------------------------------------------------------
def test_symmetric_and_asymmetric_motions(symmetric, asymmetric):
    assert symmetric_system(symmetric.oscillator)
    assert admits_symmetric_motions(symmetric.oscillator, 1, 2, symmetric.pattern)
    # Newton stops at a residual of 1e-12 max(1, |u|) (|u| ~ 5 with the flight times) and
    # the shooting Jacobian's condition is ~11: the motion is known to ~1e-10, not to eps
    assert symmetry_defect(symmetric) < 1e-10
    assert symmetry_defect(asymmetric) > 1e-2
    # G = H^2 on the symmetric motion only
    H = half_map(symmetric)
    assert np.max(np.abs(H @ H - symmetric.G)) < 1e-9 * max(1.0, np.max(np.abs(H)) ** 2)
    Ha = half_map(asymmetric)
    assert np.max(np.abs(Ha @ Ha - asymmetric.G)) > 1e-3


def test_mirror_image(symmetric, asymmetric):
    same = mirror_image(symmetric)
    assert np.max(np.abs(same.states - symmetric.states)) < 1e-10
    other = mirror_image(asymmetric)
    assert other.residual < 1e-10  # a motion of the system (Newton's tolerance)
    assert np.max(np.abs(other.states - asymmetric.states)) > 1e-2  # another one
    np.testing.assert_allclose(np.sort_complex(other.multipliers),
                               np.sort_complex(asymmetric.multipliers), atol=1e-10)
    # and the simulator, started on it, reproduces it
    res = ic.simulate(other.oscillator, other.states[0], float(other.phases[0]), 20.0)
    assert other.physical and asymmetric.physical
    assert list(res.impact_stops[:4]) == [other.pattern[(k + 1) % 2] for k in range(4)]
    np.testing.assert_allclose(res.impact_velocities[:4],
                               np.tile(np.roll(other.impact_velocities, -1), 2), atol=1e-9)


def test_which_systems_and_patterns_can_be_symmetric(symmetric):
    osc = symmetric.oscillator
    assert mirror_pattern("UULU") == "LLUL"
    assert not admits_symmetric_motions(osc, 2, 2, "UL")  # N even: the forcing is back
    assert not admits_symmetric_motions(osc, 1, 2, "UU")
    assert not admits_symmetric_motions(osc, 1, 3, "ULU")
    assert admits_symmetric_motions(osc, 3, 4, "ULLU")
    for other in (osc.replace(b=0.4), osc.replace(R=0.5),
                  backlash(1.6).replace(stops=Stops(b_low=0.5, R_low=0.7))):
        assert not symmetric_system(other)
    with pytest.raises(ValueError, match="no mirror image"):
        mirror_image(multi_impact_orbit(osc.replace(b=0.45), 1, 2, symmetric))


# ------------------------------------------------------------------------------------------
# The half system
# ------------------------------------------------------------------------------------------
@pytest.mark.parametrize("parameter", ["omega", "eta", "F0"])
def test_half_system_derivatives_are_exact(symmetric, parameter):
    osc = symmetric.oscillator
    problem = SymmetricBranchProblem(osc, 1, 2, parameter, symmetric.pattern)
    lam = float(getattr(osc, parameter))
    v = problem.half_unknowns(symmetric.unknowns)
    assert np.max(np.abs(problem.residual(v, lam))) < 1e-10  # Newton's tolerance
    np.testing.assert_allclose(problem.full_unknowns(v, lam), symmetric.unknowns, atol=1e-10)
    h = 1e-6
    J_fd = np.column_stack([(problem.residual(v + h * e, lam) - problem.residual(v - h * e, lam))
                            / (2 * h) for e in np.eye(v.size)])
    assert np.max(np.abs(problem.jacobian(v, lam) - J_fd)) < 1e-8
    d_fd = (problem.residual(v, lam + h) - problem.residual(v, lam - h)) / (2 * h)
    assert np.max(np.abs(problem.dparam(v, lam) - d_fd)) < 1e-8


def test_half_system_refuses_what_breaks_the_symmetry(symmetric):
    osc = symmetric.oscillator
    for parameter in ("b", "R"):
        with pytest.raises(ParameterError, match="breaks the symmetry"):
            SymmetricBranchProblem(osc, 1, 2, parameter, symmetric.pattern)
    with pytest.raises(ParameterError, match="cannot be symmetric"):
        SymmetricBranchProblem(osc.replace(b=0.45), 1, 2, "omega", symmetric.pattern)
    with pytest.raises(ParameterError, match="cannot be symmetric"):
        SymmetricBranchProblem(osc, 1, 2, "omega", "UU")


# ------------------------------------------------------------------------------------------
# The pitchforks on the symmetric branch
# ------------------------------------------------------------------------------------------
def _simulated_half_map(orbit, h: float = 1e-6) -> np.ndarray:
    """``S d(impact 0 -> impact 1)/d[z, theta]`` by central differences of the simulator."""
    osc = orbit.oscillator
    j = osc.stops.index
    z0, theta0 = np.delete(orbit.states[0], j), float(orbit.phases[0])
    m = z0.size + 1
    out = np.empty((m, m))
    for c in range(m):
        ends = []
        for sign in (1.0, -1.0):
            z, th = z0.copy(), theta0
            if c < m - 1:
                z[c] += sign * h
            else:
                th += sign * h
            X = np.insert(z, j, osc.stops.position(orbit.pattern[0], osc.b))
            res = ic.simulate(osc, X, th, 10.0, max_impacts=1)
            assert res.impact_stops[-1] == orbit.pattern[1]
            # theta_1 = theta_0 + omega tau_0, about theta_0 + N pi (unwrapped as the shooting)
            ref = theta0 + orbit.N * math.pi
            t = ref + math.remainder(float(res.impact_phases[-1]) - ref, 2 * math.pi)
            ends.append(np.append(np.delete(res.impact_states[-1], j), t))
        out[:, c] = (ends[0] - ends[1]) / (2 * h)
    return np.append(-np.ones(m - 1), 1.0)[:, None] * out


def test_pitchforks_are_located_and_witnessed_by_the_simulator(branch):
    bps = _bps(branch)
    assert branch.attrs["options"].count('"symmetric": true') == 1
    assert len(bps) == 2
    assert all(branch["special_status"].values[k] == "located" for k in bps)
    assert all(branch["special_precision"].values[k] < 1e-10 for k in bps)
    values = branch["special_omega"].values[bps]
    for k, value in zip(bps, values, strict=True):
        orbit = ic.special_orbit(branch, "BP", bps.index(k))
        assert abs(orbit.oscillator.omega - value) < 1e-12
        # the half-map of the simulated flight has a multiplier -1 there
        mu = np.linalg.eigvals(_simulated_half_map(orbit))
        assert np.min(np.abs(mu + 1.0)) < 1e-5
        assert abs(pitchfork_test(orbit)) < 1e-8
    # the branch is symmetric everywhere, and stable exactly outside (0.96405, 1.33782)
    omega, stable = branch["omega"].values, branch["stable"].values
    inside = (omega > values[0] + 1e-6) & (omega < values[1] - 1e-6)
    outside = (omega < values[0] - 1e-6) | (omega > values[1] + 1e-6)
    assert not stable[inside].any() and stable[outside & (omega > 0.93)].all()


def test_the_simulator_leaves_the_symmetric_motion_only_between_the_pitchforks(branch):
    values = branch["special_omega"].values[_bps(branch)]
    for omega, expect_symmetric in ((values[1] + 0.01, True), (values[1] - 0.01, False)):
        osc = backlash(float(omega))
        start = multi_impact_orbit(osc, 1, 2, ic.special_orbit(branch, "BP", 1))
        X = start.states[0] + np.array([0.0, 1e-4, 1e-4, 0.0])  # an asymmetric nudge
        o = settled(osc, X, float(start.phases[0]), 400.0)
        assert (symmetry_defect(o) < 1e-6) == expect_symmetric


def test_symmetric_false_follows_the_general_system_without_bp(symmetric):
    ds = multi_impact_continuation(symmetric, "omega", (1.3, 1.7), both_directions=True,
                                   ds_max=0.02, symmetric=False)
    assert not _bps(ds)
    assert '"symmetric": false' in ds.attrs["options"]
    with pytest.raises(ParameterError, match="not symmetric"):
        multi_impact_continuation(settled(backlash(1.3)), "omega", (1.2, 1.4), symmetric=True)
    with pytest.raises(ParameterError, match="symmetric must be"):
        multi_impact_continuation(symmetric, "omega", (1.3, 1.7), symmetric="yes")
    with pytest.raises(ParameterError, match="breaks the symmetry"):
        multi_impact_continuation(symmetric, "b", (0.4, 0.6), symmetric=True)
    # in b the symmetric start is followed as a general motion (b moves one stop)
    in_b = multi_impact_continuation(symmetric, "b", (0.45, 0.55), max_points=5)
    assert '"symmetric": false' in in_b.attrs["options"]


def test_bp_on_the_first_order_flow_of_a_damping_matrix(branch):
    """The paper's damping given as the matrix C = 2 eta K runs on the first-order flow of a
    general C (complex modes), an independent evaluation of the same motions: same BPs."""
    o = settled(backlash(1.6, C=PAPER_C))
    assert symmetry_defect(o) < 1e-10
    ds = multi_impact_continuation(o, "omega", (OMEGA[0], 1.7), both_directions=True,
                                   ds_max=0.02)
    bps = _bps(ds)
    assert all(ds["special_status"].values[k] == "located" for k in bps)
    np.testing.assert_allclose(ds["special_omega"].values[bps],
                               branch["special_omega"].values[_bps(branch)], atol=1e-9)
    orbit = ic.special_orbit(ds, "BP", 0)
    assert np.min(np.abs(np.linalg.eigvals(_simulated_half_map(orbit)) + 1.0)) < 1e-5


def test_no_bp_on_n1_branches():
    osc = ic.ImpactOscillator(M=np.eye(2), K=K2, F=[1.0, 0.0], R=0.6, b=0.5, omega=2.0, eta=0.1)
    ds = ic.continuation(osc, 1, "omega", (1.9, 2.1), detect=["BP", "PD"])
    assert "BP" not in ds["special_label"].values.tolist()


# ------------------------------------------------------------------------------------------
# Switching onto the asymmetric pair
# ------------------------------------------------------------------------------------------
@pytest.fixture(scope="module")
def pair(branch):
    return pitchfork_switch(branch, 1, bounds=OMEGA, ds_max=0.02, max_points=60)


def test_switch_gives_the_asymmetric_pair(branch, pair):
    bp = float(branch["special_omega"].values[_bps(branch)[1]])
    for ds, side in zip(pair, (1, -1), strict=True):
        assert ds.attrs["born_at"] == "BP" and ds.attrs["switch_side"] == side
        assert abs(ds.attrs["born_at_value"] - bp) < 1e-12
        assert abs(float(ds["omega"].values[0]) - bp) < 1e-4
        assert ds["omega"].values[-1] < bp  # the pair exists below the BP (supercritical)
        last = ic.dataset.oscillator_from_dataset(ds, ds.sizes["point"] - 1)
        o = multi_impact_orbit(last, 1, 2, {
            "delta": float(ds["delta_k"].values[-1, 0]),
            "flight_times": ds["flight_time_k"].values[-1], "states": ds["state_k"].values[-1],
            "pattern": ds.attrs["pattern"]})
        assert symmetry_defect(o) > 1e-2
    # mirror images of each other: the image of side +1 at a common omega is side -1's motion
    omega = 1.3
    motions = []
    for ds in pair:
        i = int(np.argmin(np.abs(ds["omega"].values - omega)))
        motions.append(multi_impact_orbit(backlash(omega), 1, 2, {
            "delta": float(ds["delta_k"].values[i, 0]),
            "flight_times": ds["flight_time_k"].values[i], "states": ds["state_k"].values[i],
            "pattern": ds.attrs["pattern"]}))
    image = mirror_image(motions[0])
    assert np.max(np.abs(image.states - motions[1].states)) < 1e-9
    assert np.max(np.abs(motions[0].states - motions[1].states)) > 1e-2
    # the simulator started on a stable switched motion stays on it
    o = motions[0]
    assert o.stable and o.physical
    res = ic.simulate(o.oscillator, o.states[0], float(o.phases[0]), 30.0)
    np.testing.assert_allclose(res.impact_velocities[:6], np.tile(
        np.roll(o.impact_velocities, -1), 3), atol=1e-9)


def test_switched_branches_round_trip_with_their_labels(tmp_path, branch, pair):
    ic.save({"symmetric": branch, "left": pair[0], "right": pair[1]}, tmp_path / "bp.nc")
    back = {name: node.to_dataset() for name, node in ic.load(tmp_path / "bp.nc").children.items()}
    assert back["symmetric"]["special_label"].values.tolist() == \
        branch["special_label"].values.tolist()
    assert back["left"].attrs["born_at"] == "BP"
    ax = bifurcation_diagram([back["symmetric"], back["left"]])
    assert "BP symmetry-breaking pitchfork" in [t.get_text() for t in ax.get_legend().get_texts()]


def test_bad_switch_requests(branch, symmetric):
    with pytest.raises(ParameterError, match="out of range"):
        pitchfork_switch(branch, 5)
    with pytest.raises(ParameterError, match="epsilon"):
        pitchfork_switch(branch, 0, epsilon=2.0)
    with pytest.raises(TypeError, match="branch must be"):
        pitchfork_switch(symmetric, 0)
    osc = ic.ImpactOscillator(M=np.eye(2), K=K2, F=[1.0, 0.0], R=0.6, b=0.5, omega=2.0, eta=0.1)
    n1 = ic.continuation(osc, 1, "omega", (1.9, 2.1))
    with pytest.raises(ParameterError, match="never symmetric"):
        pitchfork_switch(n1, 0)


# ------------------------------------------------------------------------------------------
# Mirrored stops: a symmetric backlash that stays symmetric in b and R
# ------------------------------------------------------------------------------------------
def mirrored(omega: float, b: float = 0.5) -> ic.ImpactOscillator:
    return ic.ImpactOscillator(M=np.eye(2), K=K2, F=[1.0, 0.0], R=0.6, b=b, omega=omega,
                               eta=0.1, stops=Stops(mirror=True))


def test_mirrored_stops_follow_b_and_r():
    osc = mirrored(1.6)
    assert osc.stops.two_sided and (osc.stops.b_low, osc.stops.R_low) == (0.5, 0.6)
    moved = osc.replace(b=0.4, R=0.7)
    assert (moved.stops.b_low, moved.stops.R_low) == (0.4, 0.7) and symmetric_system(moved)
    assert (osc.stops.b_low, osc.stops.R_low) == (0.5, 0.6)  # the original is unchanged
    back = ic.ImpactOscillator.from_dict(json_round_trip(moved.to_dict()))
    assert back.stops.mirror and (back.stops.b_low, back.stops.R_low) == (0.4, 0.7)
    # the same motions as the equal stops given by value
    o = settled(osc)
    same = multi_impact_orbit(backlash(1.6), 1, 2, o)
    assert np.max(np.abs(o.states - same.states)) < 1e-10
    with pytest.raises(ParameterError, match="give no b_low"):
        Stops(mirror=True, b_low=0.5)
    with pytest.raises(ParameterError, match="need b > 0"):
        mirrored(1.6, b=-0.1)
    with pytest.raises(ParameterError, match="need b > 0"):
        osc.replace(b=0.0)
    with pytest.raises(TypeError, match="mirror must be"):
        Stops(mirror="yes")


def json_round_trip(data):
    import json
    return json.loads(json.dumps(data))


@pytest.mark.parametrize("parameter", ["b", "R"])
def test_mirrored_stops_derivatives_are_exact(parameter):
    o = settled(mirrored(1.6))
    problem = SymmetricBranchProblem(o.oscillator, 1, 2, parameter, o.pattern)
    lam = float(getattr(o.oscillator, parameter))
    v = problem.half_unknowns(o.unknowns)
    h = 1e-6
    for prob, x in ((problem, v), (problem.full, o.unknowns)):  # half and full systems
        d_fd = (prob.residual(x, lam + h) - prob.residual(x, lam - h)) / (2 * h)
        assert np.max(np.abs(prob.dparam(x, lam) - d_fd)) < 1e-8
    assert problem.full.parameter_limits() == (0.0, math.inf) if parameter == "b" else True


def test_bp_in_the_clearance_meets_the_bp_in_omega(branch):
    """A symmetric branch in b (both stops move) at the omega of a BP found in omega has
    its BP at that branch's b = 0.5: the two one-parameter searches meet."""
    omega_bp = float(branch["special_omega"].values[_bps(branch)[1]])
    bp = ic.special_orbit(branch, "BP", 1)  # solved on the half system (regular there)
    # the same motion in the same system, with the stops given as mirrored
    start = orbit_from_unknowns(Flow(mirrored(omega_bp)), 1, 2, bp.unknowns, pattern=bp.pattern)
    assert symmetry_defect(start) < 1e-12
    ds = multi_impact_continuation(start, "b", (0.4, 0.6), both_directions=True, ds_max=0.01)
    assert '"symmetric": true' in ds.attrs["options"]
    bps = _bps(ds)
    assert len(bps) == 1
    assert abs(float(ds["special_b"].values[bps[0]]) - 0.5) < 1e-9


def test_a_constant_force_breaks_the_symmetry_of_a_mirrored_system():
    osc = ic.ImpactOscillator(M=np.eye(1), K=[[1.0]], F=[1.0], eta=0.05, R=0.7, b=0.5,
                              omega=1.2, stops=ic.Stops(mirror=True))
    assert symmetric_system(osc)
    assert not symmetric_system(osc.replace(F_static=[0.05]))
