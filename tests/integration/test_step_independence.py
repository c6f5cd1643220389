"""Detection does not depend on the step (issue 11, items 5 and 6).

Halving ``ds_max`` changes neither the set of special (codim-2) points nor their
values beyond 1e-9; points are named by what they are.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

import impactcont as ic

PAPER = dict(M=np.eye(2), K=[[1.0, -1.0], [-1.0, 2.0]], F=[1.0, 0.0], R=0.6, eta=0.1)
SN_START = {"omega": 1.0, "b": 1.3204359424}
BOX = {"omega": (0.6, 2.0), "b": (0.0, 2.0)}


def _points(ds, prefix):
    dim = prefix.rstrip("_")
    return sorted((str(ds[prefix + "label"].values[k]), float(ds[prefix + "omega"].values[k]),
                   float(ds[prefix + "b"].values[k]), str(ds[prefix + "status"].values[k]))
                  for k in range(ds.sizes[dim]))


def _same(a, b):
    assert [p[0] for p in a] == [p[0] for p in b]
    for p, q in zip(a, b, strict=True):
        assert p[3] == q[3] == "located", (p, q)
        assert abs(p[1] - q[1]) < 1e-9 and abs(p[2] - q[2]) < 1e-9, (p, q)


@pytest.fixture(scope="module")
def osc():
    return ic.ImpactOscillator(b=SN_START["b"], omega=SN_START["omega"], **PAPER)


def test_sn_curve_codim2_points_do_not_depend_on_ds_max(osc):
    runs = [ic.curve(osc, 1, "SN", start=SN_START, bounds=BOX, ds_max=d, ds=s)
            for s, d in ((0.01, 0.05), (0.01, 0.025), (0.02, 0.05))]
    a, *others = (_points(c, "codim2_") for c in runs)
    for b in others:
        _same(a, b)
    labels = [p[0] for p in a]
    # the PD and the ZV of one step are both kept; the double multipliers +1 are 1:1
    # resonances (R1), not Neimark-Sacker points
    assert "SN+PD" in labels and "SN+ZV" in labels and "SN+NS" not in labels
    for k in np.flatnonzero(runs[0].codim2_label.values == "R1"):
        mu = runs[0].codim2_multipliers.values[k]
        # at a Jordan block a multiplier moves as the square root of the location error
        assert np.sort(np.abs(mu - 1.0))[1] < 1e-5  # two multipliers at +1


def test_omega_branch_special_points_do_not_depend_on_ds_max(osc):
    runs = [ic.continuation(osc.replace(b=0.5), 1, "omega", (0.5, 3.0), ds_max=d)
            for d in (0.05, 0.025)]
    _same(*(_points(r, "special_") for r in runs))


def test_located_points_lie_in_their_bracket_or_are_bracketed(osc):
    ds = ic.continuation(osc.replace(b=0.5), 1, "omega", (0.5, 3.0))
    for k in range(ds.sizes["special"]):
        row = ds.isel(special=k)
        if str(row.special_label.values) == "SN":
            continue  # a fold is extremal in omega: its bracket is in arclength
        w = float(row.special_omega)
        assert float(row.special_bracket_lo) <= w <= float(row.special_bracket_hi) or \
            str(row.special_status.values) == "bracketed", (row.special_label.values, w)
        assert math.isfinite(w)


def test_pd_curve_codim2_points_do_not_depend_on_the_step(osc):
    """Through a zero-velocity impact the PD system uses G + I with its 1/h2 pole set apart;
    with G + I itself ds = 0.02 found a spurious PD+NS and only bracketed PD+ZV."""
    branch = ic.continuation(osc.replace(b=0.5), 1, "omega", (0.5, 3.0))
    box = {"omega": (0.6, 2.0), "b": (0.0, 2.0)}
    runs = [ic.curve(osc.replace(b=0.5), 1, "PD", start=branch, bounds=box, ds=s, ds_max=d)
            for s, d in ((0.02, 0.05), (0.01, 0.05), (0.005, 0.025))]
    a, *others = (_points(c, "codim2_") for c in runs)
    for b in others:
        _same(a, b)
    assert [p[0] for p in a] == ["PD+NS", "PD+SN", "PD+ZV", "R2"]
    labels = runs[0].codim2_label.values.tolist()
    mu = runs[0].codim2_multipliers.values[labels.index("R2")]
    assert np.sort(np.abs(mu + 1.0))[1] < 1e-5  # two multipliers at -1 (a Jordan block)
    # the ZV point is a zero of the impact velocity, recomputed from scratch
    k = labels.index("PD+ZV")
    with pytest.warns(ic.LowImpactVelocityWarning):  # G's 1/h2 pole: the library says so
        zv = ic.periodic_orbits(osc.replace(omega=float(runs[0].codim2_omega[k]),
                                            b=float(runs[0].codim2_b[k])), 1)
    assert min(abs(o.impact_velocity) for o in zv) < 1e-9


def test_ns_curve_ends_at_the_strong_resonances_found_by_the_sn_and_pd_curves(osc):
    """The NS system is singular at its 1:1 / 1:2 ends (theta -> 0, pi): they used to be
    'located' 1e-5 apart for two step sizes; now they are the double multipliers +1 / -1
    located on a regular system, equal to the R1 of the SN curve and the R2 of the PD curve."""
    at_half = osc.replace(b=0.5)
    branch = ic.continuation(at_half, 1, "omega", (0.5, 3.0))
    box = {"omega": (0.6, 2.0), "b": (0.0, 2.0)}
    runs = [ic.curve(at_half, 1, "NS", start=branch, bounds=box, ds=s, ds_max=d)
            for s, d in ((0.02, 0.05), (0.01, 0.05), (0.005, 0.025))]
    a, *others = (_points(c, "codim2_") for c in runs)
    for b in others:
        _same(a, b)
    ends = {p[0]: p for p in a if p[0] in ("R1", "R2")}
    assert set(ends) == {"R1", "R2"}
    pd = ic.curve(at_half, 1, "PD", start=branch, bounds=box)
    sn = ic.curve(osc, 1, "SN", start=SN_START, bounds=BOX)
    for curve, end in ((pd, "R2"), (sn, "R1")):
        twins = [p for p in _points(curve, "codim2_") if p[0] == end]
        nearest = min(twins, key=lambda p: abs(p[1] - ends[end][1]) + abs(p[2] - ends[end][2]))
        assert abs(nearest[1] - ends[end][1]) < 1e-9 and abs(nearest[2] - ends[end][2]) < 1e-9


# -- issue 28, items 1.3 and 1.4: the impact damper ------------------------------------------

def _damper(**changes) -> ic.ImpactOscillator:
    """The impact damper of issue 28: a primary on a spring, a free ball of mass 0.2 in a
    clearance +-1 (mirrored stops of x2 - x1)."""
    osc = ic.ImpactOscillator(M=np.diag([1.0, 0.2]), K=np.diag([1.0, 0.0]), F=[1, 0], R=0.8,
                              b=1.0, omega=1.5, eta=0.05,
                              stops=ic.Stops(mass=2, relative_to=1, mirror=True))
    return osc.replace(**changes)


def _specials(ds, parameter):
    return [(str(ds.special_label.values[k]), float(ds[f"special_{parameter}"].values[k]),
             str(ds.special_status.values[k]), float(ds.special_precision.values[k]))
            for k in range(ds.sizes["special"])]


def _same_within_precision(runs):
    first, *others = runs
    for other in others:
        assert [p[0] for p in other] == [p[0] for p in first], (first, other)
        for p, q in zip(first, other, strict=True):
            assert p[2] == q[2] == "located", (p, q)
            assert abs(p[1] - q[1]) <= p[3] + q[3], (p, q)


@pytest.fixture(scope="module")
def damper_ul():
    """The damper's symmetric UL motion (one impact on each wall per forcing period)."""
    osc = _damper()
    return ic.multi_impact_orbit(osc, 1, 2, ic.simulate(osc, np.array([0, 0, 0, 1.0]), 0.0, 150))


def test_the_grazing_of_the_damper_in_r_does_not_depend_on_ds_max(damper_ul):
    """Issue 28, 1.4: towards R = 0 a flight gains an interior extremum that crosses the
    wall. Its GR test was +inf (no extremum) at every point but the last, and a sign
    change from +inf was not watched: no special point at the default step, a GR at
    R = 0.0066 with ds_max = 0.005."""
    runs = [_specials(ic.multi_impact_continuation(damper_ul, "R", (0.0, 0.8), ds_max=d), "R")
            for d in (0.05, 0.02, 0.005)]
    _same_within_precision(runs)
    assert [p[0] for p in runs[0]] == ["GR"]
    assert 0.0 < runs[0][0][1] < 0.01


def test_no_ns_through_the_pole_of_g_at_a_zero_velocity_impact():
    """Issue 28, 1.3: on the undamped damper's symmetric branch the multipliers of G lose
    ~1/h2^2 of their accuracy next to a zero-velocity impact, where the pole-free NS test
    vanishes like h2^3; its sign changed in that noise and an NS was reported 2e-4 from the
    ZV (claimed precision 7e-15, |mu| - 1 = 1e-5 there), at a place that moved with the
    step. The step is split at the ZV: only the ZV remains, the same for every step."""
    osc = _damper(eta=0.0, omega=1.507869444932243)
    guess = {"delta": -0.0175, "pattern": "UL", "flight_times": [2.0835, 2.0835],
             "states": [[-0.83816, 0.16184, 0.01036, -0.15536],
                        [0.83816, -0.16184, -0.01036, 0.15536]]}
    start = ic.multi_impact_orbit(osc, 1, 2, guess)
    runs = [_specials(ic.multi_impact_continuation(start, "omega", (1.35, 1.55), ds_max=d),
                      "omega") for d in (0.05, 0.01)]
    _same_within_precision(runs)
    assert [p[0] for p in runs[0]] == ["ZV"]
