"""Codim-1 curves in (omega, b): checked against one-parameter special points, closed forms,
the grid map and the simulator."""

from __future__ import annotations

import math
import re

import numpy as np
import pytest
import xarray as xr

import impactcont as ic
from impactcont.analysis.curves import curve, curve_crossings
from impactcont.analysis.maps import stability_map
from impactcont.dataset.simulation import simulation_dataset
from impactcont.orbit.periodic import orbit_at_phase

BOX = {"omega": (0.6, 2.0), "b": (0.0, 0.6)}


#: gaps at which each curve is compared with the one-parameter special points
CHECK_B = {"SN": (0.45, 0.5), "PD": (0.1, 0.3, 0.45), "NS": (0.45, 0.5),
           "GR": (0.1, 0.3, 0.5), "ZV": (0.4, 0.45)}


@pytest.fixture(scope="module")
def paper():
    return ic.ImpactOscillator(M=np.eye(2), K=[[1.0, -1.0], [-1.0, 2.0]], F=[1.0, 0.0], R=0.6,
                               b=0.5, omega=1.0, eta=0.1)


@pytest.fixture(scope="module")
def branches(paper):
    return {0.0: ic.continuation(paper.replace(b=0.0), 1, "omega", (0.6, 2.0), detect=["PD"]),
            0.5: ic.continuation(paper, 1, "omega", (0.6, 2.0),
                                 detect=["SN", "NS", "GR", "ZV"])}


@pytest.fixture(scope="module")
def curves(paper, branches):
    return {kind: curve(paper, None, kind, start=branches[0.0 if kind == "PD" else 0.5],
                        bounds=BOX)
            for kind in ("SN", "PD", "NS", "GR", "ZV")}


def _one_parameter_points(osc, kind, b, omega, root=None):
    ds = ic.continuation(osc.replace(b=b), 1, "omega", (omega - 0.015, omega + 0.015),
                         detect=[kind], root=root or None, ds=0.002, ds_max=0.005)
    rows = (ds.special_label.values == kind) & (ds.special_status.values == "located")
    return ds.special_omega.values[rows]


@pytest.mark.parametrize("kind", ["SN", "PD", "NS", "GR", "ZV"])
def test_curve_agrees_with_one_parameter_special_points(paper, curves, kind):
    c = curves[kind]
    assert float(c.residual.max()) < 1e-10
    compared = 0
    for b in CHECK_B[kind]:
        crossings = curve_crossings(c, "b", b)
        assert crossings, f"{kind} curve does not cross b={b}"
        for cr in crossings:
            assert cr["b"] == b
            found = _one_parameter_points(paper, kind, b, cr["omega"], cr["root"])
            assert found.size, f"no 1-parameter {kind} near omega={cr['omega']} at b={b}"
            assert np.min(np.abs(found - cr["omega"])) < 1e-8, (kind, b, cr, found)
            compared += 1
    assert compared >= 2


def test_fold_curve_is_the_closed_form(paper, curves):
    c = curves["SN"]
    amp = np.array([ic.amplitude_squared(paper.replace(omega=float(w)), 1)
                    for w in c.omega.values])
    assert np.max(np.abs(c.b.values ** 2 - amp)) < 1e-10
    assert c.sizes["point"] > 10 and (c.root.values == 0).all()


def test_zero_velocity_curve_is_the_linear_response_for_every_N(paper, curves):
    c = curves["ZV"]
    for w, b in zip(c.omega.values, c.b.values, strict=True):
        X = np.linalg.solve(paper.K - w**2 * paper.M + 1j * w * paper.C, paper.F)
        assert abs(abs(X[0]) - abs(b)) < 1e-10
    assert np.max(np.abs(c.impact_velocity.values)) < 1e-10
    # the N = 2 curve is the same set
    c2 = curve(paper, 2, "ZV", start={"omega": 1.3012, "b": 0.4}, bounds=BOX, ds_max=0.1)
    for b in (0.4, 0.45):
        w1 = sorted(x["omega"] for x in curve_crossings(c, "b", b))
        w2 = sorted(x["omega"] for x in curve_crossings(c2, "b", b))
        assert np.allclose(w1, w2, atol=1e-9)


def test_a_zero_velocity_curve_is_physical_but_for_its_own_bound(curves):
    """Along a ZV curve the impact velocity is zero to rounding (its sign flipped from point to
    point, +-1e-17, and so did ``physical``: the curve was drawn in random dashes). Its own
    bound is left out, as a GR curve's tangency is: ``physical`` is the gap's test alone."""
    c = curves["ZV"]
    assert np.max(np.abs(c.impact_velocity.values)) < 1e-10  # zero, its sign rounding's
    np.testing.assert_array_equal(c.physical.values, c.gap_min.values > 0)


def test_codim2_points_lie_on_both_curves(curves):
    """PD+NS on the PD curve is NS+PD on the NS curve; SN+ZV is ZV+SN."""
    for a, b, la, lb in (("PD", "NS", "PD+NS", "NS+PD"), ("SN", "ZV", "SN+ZV", "ZV+SN"),
                         ("PD", "SN", "PD+SN", "SN+PD")):
        ca, cb = curves[a], curves[b]
        pa = ca.isel(codim2=np.flatnonzero(ca.codim2_label.values == la))
        pb = cb.isel(codim2=np.flatnonzero(cb.codim2_label.values == lb))
        assert pa.sizes["codim2"] and pb.sizes["codim2"], (la, lb)
        assert (pa.codim2_status.values == "located").all()
        d = np.hypot(pa.codim2_omega.values[:, None] - pb.codim2_omega.values[None, :],
                     pa.codim2_b.values[:, None] - pb.codim2_b.values[None, :])
        assert d.min() < 1e-7, (la, lb, d.min())
    ns = curves["NS"]
    assert "R1" in ns.codim2_label.values  # the NS curve ends at a 1:1 resonance
    r1 = ns.isel(codim2=int(np.flatnonzero(ns.codim2_label.values == "R1")[0]))
    assert np.min(np.abs(r1.codim2_multipliers.values - 1.0)) < 1e-3


def test_curves_lie_on_the_map_edges(paper, curves):
    omega = np.linspace(0.6, 2.0, 71)
    bs = np.array([0.1, 0.3, 0.4, 0.45, 0.5])
    m = stability_map(paper, [1], omega, bs).sel(N=1)
    checked = 0
    for kind, c in curves.items():
        for j, b in enumerate(bs):
            for cr in curve_crossings(c, "b", float(b)):
                i = np.searchsorted(omega, cr["omega"]) - 1
                if not 0 <= i < omega.size - 1:
                    continue
                lo, hi = m.isel(omega=i, b=j), m.isel(omega=i + 1, b=j)
                if kind == "SN":
                    assert bool(lo.exists) != bool(hi.exists), (kind, b, cr)
                    checked += 1
                    continue
                r = 0 if cr["root"] == 1 else 1
                if not (bool(lo.exists) and bool(hi.exists)):
                    continue  # a fold inside the cell: the roots are not both defined
                if kind == "GR":
                    pair = (lo.gap_min[r], hi.gap_min[r])
                elif kind == "ZV":
                    pair = (lo.impact_velocity[r], hi.impact_velocity[r])
                else:
                    point = cr["point"]
                    if not bool(c.stable_side[point]):
                        continue  # another multiplier outside the circle: rho need not cross 1
                    pair = (lo.spectral_radius[r] - 1, hi.spectral_radius[r] - 1)
                    assert bool(lo.stable[r]) != bool(hi.stable[r]), (kind, b, cr)
                assert float(pair[0]) * float(pair[1]) < 0, (kind, b, cr, pair)
                checked += 1
    assert checked >= 12


# -- simulation on both sides -------------------------------------------------------------------
def _orbit(osc, N, root):
    orbits = [o for o in ic.periodic_orbits(osc, N) if o.root == root]
    assert orbits, (osc, root)
    return orbits[0]


def _first_return(osc, orbit):
    res = ic.simulate(osc, orbit.state, orbit.delta, 1.5 * orbit.N)
    return res.impact_times[0] / orbit.period


def _growth(osc, orbit, impacts):
    X = orbit.state.copy()
    X[1] += 1e-7
    X[orbit.oscillator.n] += 1e-7
    res = ic.simulate(osc, X, orbit.delta, float(impacts * orbit.N) + 0.5)
    v = res.impact_velocities - orbit.impact_velocity
    # after the fast transients (impacts 4-7) against the end: the critical multiplier rules
    return np.max(np.abs(v[-4:])) / np.max(np.abs(v[4:8])), v


@pytest.mark.parametrize(("kind", "b"), [("GR", 0.3), ("ZV", 0.4)])
def test_physicality_changes_across_curve_in_simulation(paper, curves, kind, b):
    # on the curve itself the flag is decided by rounding (h2 or gap_min is 0 there): take
    # the crossing whose motions on either side are physical on one side only
    outcome = {}
    for cr in curve_crossings(curves[kind], "b", b):
        outcome = {}
        for eps in (-0.01, 0.01):
            osc = paper.replace(b=b, omega=cr["omega"] + eps)
            o = _orbit(osc, 1, cr["root"])
            outcome[o.physical] = _first_return(osc, o)
        if set(outcome) == {True, False}:
            break
    assert set(outcome) == {True, False}
    assert outcome[True] == pytest.approx(1.0, abs=1e-9)  # returns to itself after T
    assert outcome[False] < 0.999  # the stop is hit inside the period


def _side(paper, b, cr, sign):
    """A physical motion of the crossing's root beside the curve, |rho - 1| >= 0.02."""
    for eps in (0.001, 0.002, 0.004, 0.008, 0.016, 0.032):
        osc = paper.replace(b=b, omega=cr["omega"] + sign * eps)
        orbits = [o for o in ic.periodic_orbits(osc, 1) if o.root == cr["root"]]
        if orbits and orbits[0].physical and abs(orbits[0].spectral_radius - 1) >= 0.02:
            return osc, orbits[0]
    raise AssertionError(f"no usable motion beside {cr} on side {sign}")


@pytest.mark.parametrize(("kind", "b"), [("PD", 0.3), ("NS", 0.47)])
def test_stability_changes_across_curve_in_simulation(paper, curves, kind, b):
    cr = next(x for x in curve_crossings(curves[kind], "b", b)
              if bool(curves[kind].stable_side[x["point"]]))
    growth = {}
    for sign in (-1, 1):
        osc, o = _side(paper, b, cr, sign)
        impacts = min(max(math.ceil(3.0 / abs(math.log(o.spectral_radius))) + 8, 16), 150)
        g, v = _growth(osc, o, impacts)
        growth[o.stable] = g
        if not o.stable and kind == "PD":  # a multiplier beyond -1: the impacts alternate
            steps = np.sign(np.diff(v[-10:]))
            assert np.all(steps[1:] == -steps[:-1])
    assert set(growth) == {True, False}
    assert growth[True] < 0.2 and growth[False] > 5.0, growth


def test_fold_creates_the_motion_in_simulation(paper):
    """SN at b = 1.9 (N = 1): a stable physical motion on one side, none on the other."""
    c = curve(paper, 1, "SN", start={"omega": 0.91, "b": 1.9},
              bounds={"omega": (0.6, 1.2), "b": (1.8, 2.0)}, detect_codim2_points=False)
    (cr,) = curve_crossings(c, "b", 1.9)
    sides = {}
    for eps in (-0.01, 0.01):
        osc = paper.replace(b=1.9, omega=cr["omega"] + eps)
        sides[eps] = ic.periodic_orbits(osc, 1)
    exist = [e for e in sides if sides[e]]
    assert len(exist) == 1
    stable = [o for o in sides[exist[0]] if o.stable and o.physical]
    assert stable
    osc = paper.replace(b=1.9, omega=cr["omega"] + exist[0])
    g, _ = _growth(osc, stable[0], 40)
    assert g < 0.05  # the motion exists and attracts
    # other side: started at the fold motion, the impacts drift away from it
    osc = paper.replace(b=1.9, omega=cr["omega"] - exist[0])
    fold = orbit_at_phase(paper.replace(b=1.9, omega=cr["omega"]), 1, cr["delta"])
    res = ic.simulate(osc, fold.state, fold.delta, 40.0)
    intervals = np.diff(res.impact_times) / (2 * math.pi / osc.omega)
    phase_drift = np.abs(np.remainder(res.impact_phases - fold.delta + math.pi, 2 * math.pi)
                         - math.pi)
    assert np.max(np.abs(intervals[-5:] - 1.0)) > 1e-3 or phase_drift[-1] > 0.05


def test_curve_in_another_parameter_pair(paper):
    """A PD curve in (omega, R) agrees with one-parameter PD points at fixed R."""
    osc = paper.replace(b=0.3)
    c = curve(osc, 1, "PD", start={"omega": 1.3737, "R": 0.6}, parameters=("omega", "R"),
              bounds={"omega": (1.0, 2.0), "R": (0.5, 0.7)}, detect_codim2_points=False)
    assert c.attrs["parameters"] == "omega,R" and "R" in c
    for R in (0.55, 0.65):
        (cr,) = curve_crossings(c, "R", R)
        found = _one_parameter_points(osc.replace(R=R), "PD", 0.3, cr["omega"], cr["root"])
        assert np.min(np.abs(found - cr["omega"])) < 1e-8


@pytest.mark.parametrize("element, bounds", [("k2", (0.8, 1.3)), ("M[1,2]", (-0.2, 0.2)),
                                             ("F[2]", (-0.2, 0.2))])
def test_a_pd_curve_in_an_element_has_a_multiplier_minus_one_at_its_points(paper, element,
                                                                          bounds):
    """Issue 29, item 5: N-1 curves in an element of the model (its ModelParameter). The
    witness: the closed form's motion with the element replaced (``periodic_orbits``) has
    a multiplier -1 at the curve's points; the curve's file stores the element."""
    from impactcont.model.parameters import model_parameter

    osc = paper.replace(b=0.0, omega=1.75)
    c = curve(osc, 1, "PD", parameters=("omega", element),
              bounds={"omega": (1.4, 2.2), element: bounds}, detect_codim2_points=False,
              progress=False)
    assert c.attrs["parameters"] == f"omega,{element}" and c[element].dims == ("point",)
    assert c[element].values.min() == pytest.approx(bounds[0])
    assert c[element].values.max() == pytest.approx(bounds[1])
    param = model_parameter(osc, element)
    for k in range(0, c.sizes["point"], 3):
        at = param.at(osc, float(c[element].values[k])).replace(omega=float(c.omega.values[k]))
        delta = float(c.delta.values[k])
        near = min(ic.periodic_orbits(at, 1),
                   key=lambda o: abs(math.remainder(o.delta - delta, 2 * math.pi)))
        assert np.min(np.abs(np.asarray(near.multipliers) + 1.0)) < 1e-9


def test_a_curve_starts_from_a_branch_in_an_element(paper):
    osc = paper.replace(b=0.0, omega=1.75)
    branch = ic.continuation(osc, 1, "k2", (0.9, 1.3), detect=["PD"], progress=False)
    c = curve(None, None, "PD", start=branch, parameters=("k2", "omega"),
              bounds={"k2": (0.9, 1.3), "omega": (1.7, 1.8)}, detect_codim2_points=False,
              progress=False)
    first = int(np.flatnonzero(branch.special_label.values == "PD")[0])
    (cross,) = curve_crossings(c, "omega", 1.75)
    assert cross["k2"] == pytest.approx(float(branch.special_k2.values[first]), abs=1e-9)


def test_parameters_the_n1_curves_do_not_have_are_refused(paper):
    box = {"omega": (1.0, 2.0)}
    for name, why in (("gap[A]", "stop other than the paper's one stop"),
                      ("b_low", "stop other than the paper's one stop"),
                      ("k3", "past the oscillator's n=2 masses"),
                      ("foo", "'foo' is no parameter")):
        with pytest.raises(ic.ParameterError, match=r"parameters.*" + re.escape(why)):
            curve(paper, 1, "PD", parameters=("omega", name), bounds={**box, name: (0, 1)})
    with pytest.raises(ic.ParameterError, match=r"bounds\['k2'\]"):
        curve(paper, 1, "PD", parameters=("omega", "k2"), bounds={**box, "k2": (-3.0, 1.0)})


def test_netcdf_round_trip_of_curves_and_maps(paper, curves, tmp_path):
    for kind, c in curves.items():
        back = ic.load(ic.save(c, tmp_path / f"{kind}.nc"))
        xr.testing.assert_identical(back, c)
    m = stability_map(paper, [1, 2], np.linspace(0.6, 2.0, 8), np.linspace(0.0, 0.6, 5))
    xr.testing.assert_identical(ic.load(ic.save(m, tmp_path / "map.nc")), m)
    tree = ic.load(ic.save({"PD": curves["PD"], "map": m}, tmp_path / "all.nc"))
    xr.testing.assert_identical(tree["PD"].to_dataset(), curves["PD"])
    xr.testing.assert_identical(tree["map"].to_dataset(), m)


def test_bad_inputs_raise_clear_errors(paper, branches):
    with pytest.raises(ic.ParameterError, match=r"kind must be one of.*'XX'"):
        curve(paper, 1, "XX", start={"omega": 1.0, "b": 0.5}, bounds=BOX)
    with pytest.raises(ic.ParameterError, match=r"parameters must be two different.*omega"):
        curve(paper, 1, "PD", parameters=("omega", "omega"), bounds=BOX)
    with pytest.raises(ic.ParameterError, match=r"parameters must be a pair.*'gap'"):
        curve(paper, 1, "PD", parameters=("omega", "gap"), bounds=BOX)
    with pytest.raises(ic.ParameterError, match="bounds must be given"):
        curve(paper, 1, "PD", start={"omega": 1.0, "b": 0.5})
    with pytest.raises(ic.ParameterError, match=r"bounds\['b'\] must be finite with lo < hi"):
        curve(paper, 1, "PD", start={"omega": 1.0, "b": 0.5},
              bounds={"omega": (0.5, 2.0), "b": (1.0, 0.0)})
    with pytest.raises(ic.ParameterError, match=r"start b=0.5 lies outside bounds"):
        curve(paper, 1, "SN", start={"omega": 1.2, "b": 0.5},
              bounds={"omega": (0.5, 2.0), "b": (0.6, 1.0)})
    with pytest.raises(ic.ParameterError, match="special=0 is a SN point, not PD"):
        curve(paper, None, "PD", start=branches[0.5].isel(special=[3, 0, 1, 2]), special=0,
              bounds=BOX)
    with pytest.raises(ic.ParameterError, match="no located PD point"):
        curve(paper, None, "PD", start=branches[0.5], bounds=BOX)
    with pytest.raises(ic.ParameterError, match="N=2 differs from the branch"):
        curve(paper, 2, "GR", start=branches[0.5], bounds=BOX)
    with pytest.raises(ic.ParameterError, match="start must give 'omega' and 'b'"):
        curve(paper, 1, "GR", start={"omega": 1.0}, bounds=BOX)
    with pytest.raises(ic.ParameterError, match="parameter must be one of the curve's"):
        curve_crossings(curve(paper, 1, "SN", start={"omega": 1.2147, "b": 0.5}, bounds=BOX,
                              max_points=3, both_directions=False), "R", 0.5)
    with pytest.raises(ic.ParameterError, match="omega must be strictly increasing"):
        stability_map(paper, [1], [1.0, 0.9], [0.0])
    with pytest.raises(ic.ParameterError, match="omega must be > 0"):
        stability_map(paper, [1], [-1.0, 0.9], [0.0])
    with pytest.raises(ic.ParameterError, match="N must be an integer"):
        stability_map(paper, [0], [1.0], [0.0])
    with pytest.raises(ic.ParameterError, match=r"executor must be None.*'threads'"):
        stability_map(paper, [1], [1.0], [0.0], executor="threads")


def test_a_file_with_the_former_resonance_names_reads_them_as_r1_r2(curves, tmp_path):
    ns = curves["NS"]
    labels = ns.codim2_label.values
    assert {"R1", "R2"} & set(labels.tolist())
    former = labels.copy()
    former[labels == "R1"], former[labels == "R2"] = "SN+SN", "PD+PD"
    old = ns.assign(codim2_label=ns.codim2_label.copy(data=former))
    back = ic.load(ic.save(old, tmp_path / "old.nc", validate=False))
    xr.testing.assert_identical(back, ns)


def test_bounds_outside_a_parameters_range_are_refused_before_computing(paper):
    """The drivers' one bounds check (issue 28): R lives in [0, 1]."""
    with pytest.raises(ic.ParameterError, match=r"bounds\['R'\] for R must lie where R is in "
                                                r"\[0, 1\]; got \(0\.5, 1\.5\)"):
        curve(paper, 1, "PD", parameters=("omega", "R"), start={"omega": 1.0, "R": 0.6},
              bounds={"omega": (0.5, 2.0), "R": (0.5, 1.5)})


def test_one_entry_starts_a_curve_from_a_motion_and_crosses_either_evaluator(paper, branches):
    """Issue 29, item 1: ``curve`` takes a motion as its start, the closed form's N-1 motion
    (a PeriodicOrbit) or the same motion as a 1-1 motion to be shot (a MultiImpactOrbit),
    and ``curve_crossings`` reads both evaluators' datasets: the three PD curves cross
    b = 0.05 and -0.05 at the same omega (Newton tolerances 1e-11 and 1e-10)."""
    box = {"omega": (1.0, 3.0), "b": (-0.06, 0.06)}
    branch = branches[0.0]
    k = next(i for i, lab in enumerate(branch.special_label.values) if lab == "PD")
    omega, delta = float(branch.special_omega[k]), float(branch.special_delta[k])
    orbit = min(ic.periodic_orbits(paper.replace(b=0.0, omega=omega), 1),
                key=lambda o: abs(math.remainder(o.delta - delta, 2 * math.pi)))
    from_branch = curve(None, None, "PD", start=branch, bounds=box)
    from_orbit = curve(None, None, "PD", start=orbit, bounds=box)
    assert from_orbit.attrs["kind"] == "PD" and from_orbit.attrs["N"] == 1
    motion = ic.multi_impact_orbit(orbit.oscillator, 1, 1, orbit)
    shot = curve(None, None, "PD", start=motion, parameters=("omega", "b"), bounds=box,
                 detect_codim2_points=False)
    assert shot.attrs["curve_kind"] == "PD" and shot.attrs["parameters"] == "omega,b"
    for b in (-0.05, 0.05):
        omegas = [[c["omega"] for c in curve_crossings(ds, "b", b)]
                  for ds in (from_branch, from_orbit, shot)]
        assert all(len(w) == 1 for w in omegas), omegas
        np.testing.assert_allclose(np.ravel(omegas), omegas[0][0], rtol=0, atol=1e-9)
    with pytest.raises(ic.ParameterError, match=r"root must be left out when the curve "
                                                r"starts from an N-p branch or motion"):
        curve(None, None, "PD", start=motion, root=1, bounds=box)
    with pytest.raises(ic.ParameterError, match=r"N=2 differs from the motion's N=1"):
        curve(None, 2, "PD", start=orbit, bounds=box)


def test_a_curve_by_shooting_ends_on_the_bound_of_its_first_parameter(paper, branches):
    """One stop rule for both evaluators: where the curve leaves the box through a bound of
    ``p1`` (an unknown, unseen by the core) its last point is solved on that bound, by the
    closed form and by shooting alike (before, shooting stopped at the last point inside)."""
    branch = branches[0.0]
    k = next(i for i, lab in enumerate(branch.special_label.values) if lab == "PD")
    omega = float(branch.special_omega[k])
    box = {"omega": (omega - 0.02, omega + 0.02), "b": (-0.3, 0.3)}
    closed = curve(None, None, "PD", start=branch, bounds=box, detect_codim2_points=False)
    start = ic.analysis.switching.special_orbit(branch, "PD", 0)
    shot = curve(None, None, "PD", start=start, parameters=("omega", "b"), bounds=box,
                 detect_codim2_points=False)
    for ds in (closed, shot):
        ends = ds["omega"].values[[0, -1]]
        assert np.min(np.abs(ends[:, None] - np.array(box["omega"])[None, :]), axis=1) \
            .max() < 1e-12, ends
    np.testing.assert_allclose(np.sort(shot["b"].values[[0, -1]]),
                               np.sort(closed["b"].values[[0, -1]]), rtol=0, atol=1e-9)


def test_a_shooting_curve_keeps_the_motion_of_each_point_from_its_run(branches, monkeypatch):
    """Issue 29 (the cost of a curve point): the motion at each point of a curve followed by
    shooting is evaluated when the core accepts the point, from the branch problem and the
    shot its step left at hand; no branch problem is built again after the run (before:
    one per point, with its flow, stop geometry and shot). The dataset is the one built
    from the motions evaluated afresh after the run, to the bit (the same operations)."""
    import impactcont.analysis.curves as curves_module
    from impactcont.problems.multi_impact_branch import MultiImpactBranchProblem

    branch = branches[0.0]
    start = ic.analysis.switching.special_orbit(branch, "PD", 0)
    omega = float(start.oscillator.omega)
    box = {"omega": (omega - 0.5, omega + 0.5), "b": (-0.03, 0.03)}
    built_after_run = []
    follow, moved = curves_module.follow, MultiImpactBranchProblem.moved

    def follow_then_mark(*args, **kwargs):
        result = follow(*args, **kwargs)
        built_after_run.append(0)
        return result

    def counted(self, osc):
        if built_after_run:
            built_after_run[-1] += 1
        return moved(self, osc)

    monkeypatch.setattr(curves_module, "follow", follow_then_mark)
    monkeypatch.setattr(MultiImpactBranchProblem, "moved", counted)

    def shot() -> xr.Dataset:
        ds = curve(None, None, "PD", start=start, parameters=("omega", "b"), bounds=box,
                   detect_codim2_points=False)
        ds.attrs.pop("history")
        return ds

    kept = shot()
    assert kept.sizes["point"] >= 5 and built_after_run == [0]
    monkeypatch.setattr(curves_module, "_keep_orbit", lambda *args: None)
    afresh = shot()
    assert built_after_run[-1] > 0  # the count sees the problems built after a run
    xr.testing.assert_identical(kept, afresh)


def test_a_shooting_curve_refuses_a_box_without_its_start_in_either_parameter(paper, branches):
    """The box must contain the start in p1 as well as p2, as the closed form's curve asks
    (before, a shooting curve from omega outside ``bounds['omega']`` returned points on the
    omega bound far outside ``bounds['b']``), and an unknown kind is named as such (it was
    'special=0 is out of range: the branch has 0 XX point(s)')."""
    start = ic.analysis.switching.special_orbit(branches[0.0], "PD", 0)
    omega = start.oscillator.omega
    with pytest.raises(ic.ParameterError, match=r"bounds\['omega'\].*must contain the start"):
        curve(None, None, "PD", start=start, parameters=("omega", "b"),
              bounds={"omega": (omega + 0.1, omega + 0.5), "b": (-0.3, 0.3)})
    branch = ic.multi_impact_continuation(start, "omega", (omega - 0.05, omega + 0.05))
    with pytest.raises(ic.ParameterError, match="kind must be one of"):
        curve(branch, "XX", parameters=("omega", "b"), bounds={"omega": (0.5, 2.0),
                                                                "b": (-0.3, 0.3)})


def test_special_and_root_are_checked_before_the_start_is_searched(paper, branches):
    """special out of range raised IndexError after the search's branch, 'a' a ValueError
    of int(), 1.5 was truncated to 1; root=5 was taken (and ignored) without start values,
    and with a branch as start."""
    flat = paper.replace(b=0.0)
    with pytest.raises(ic.ParameterError, match=r"special=5 is out of range: the N=1 branch "
                                                r"in omega .* has \d located PD point"):
        curve(flat, 1, "PD", bounds=BOX, special=5)
    for bad in ("a", 1.5, True):
        with pytest.raises(ic.ParameterError, match="special must be an integer index"):
            curve(flat, 1, "PD", bounds=BOX, special=bad)
    with pytest.raises(ic.ParameterError, match=r"root must be \+1, -1 or None; got 5"):
        curve(flat, 1, "PD", bounds=BOX, root=5)
    with pytest.raises(ic.ParameterError, match="root must be left out when start is a branch"):
        curve(paper, None, "PD", start=branches[0.0], bounds=BOX, root=1)
    last = curve(flat, 1, "PD", bounds=BOX, special=-1, detect_codim2_points=False)
    assert last.sizes["point"] > 2


def test_a_curve_map_or_simulation_as_start_is_named(paper, branches):
    """Datasets with impacts that are not branches: a shooting curve's dataset said
    'special=0 is out of range: the branch has 0 SE point(s)', a simulation's 'p1 the
    branch's parameter 'None''."""
    start = ic.analysis.switching.special_orbit(branches[0.0], "PD", 0)
    omega = start.oscillator.omega
    branch = ic.multi_impact_continuation(start, "omega", (omega - 0.05, omega + 0.05))
    box = {"omega": (0.5, 2.0), "b": (-0.3, 0.3)}
    as_curve = branch.assign_attrs(curve_kind="PD", parameters="omega,b")
    with pytest.raises(ic.ParameterError, match="start must be a one-parameter branch dataset "
                                                r".*got a two-parameter curve dataset"):
        curve(as_curve, "PD", parameters=("omega", "b"), bounds=box)
    run = simulation_dataset(ic.simulate(start.oscillator, start.states[0], start.phases[0], 2.0))
    with pytest.raises(ic.ParameterError, match="got a simulation dataset"):
        curve(run, "PD", parameters=("omega", "b"), bounds=box)
