"""The study studies/bifurcation_diagram/ runs end to end and writes what it promises."""

from __future__ import annotations

import importlib.util
import json
import math
import sys
from pathlib import Path

import numpy as np
import pytest
import xarray as xr

import impactcont as ic

RUN = Path(__file__).resolve().parents[2] / "studies" / "bifurcation_diagram" / "run.py"
CHECK_KEYS = {"b", "N", "label", "omega", "precision", "status", "offset", "sides", "verdict",
              "agrees", "below_text", "above_text", "expected_change"}


@pytest.fixture(scope="module")
def study():
    name = "bifurcation_diagram_run"
    spec = importlib.util.spec_from_file_location(name, RUN)
    module = importlib.util.module_from_spec(spec)
    sys.modules[name] = module  # the worker processes find the module's functions by name
    try:
        spec.loader.exec_module(module)
        yield module
    finally:
        sys.modules.pop(name, None)


@pytest.fixture(scope="module")
def outputs(study, tmp_path_factory):
    """Quick mode at the gap 0.5 only, with a 4-value brute-force grid (about 30 s)."""
    out = tmp_path_factory.mktemp("bifurcation_diagram")
    summary = study.main(out, quick=True, brute_force=True, n_omega=4, gaps=(0.5,))
    return out, summary


def test_files_written(outputs):
    out, _ = outputs
    for name in ("branches.nc", "brute_force.nc", "bifurcation_b0p5.png",
                 "special_points.json", "special_points.md", "summary.json"):
        path = out / name
        assert path.is_file() and path.stat().st_size > 0, name
    assert (out / "bifurcation_b0p5.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert not list(out.glob(".*.tmp")), "temporary files left behind"


def test_branches_load(outputs):
    out, summary = outputs
    tree = ic.load(out / "branches.nc")
    assert isinstance(tree, xr.DataTree)
    names = sorted(tree.children)
    assert names == sorted(summary["branches"])
    # every N = 1..4 has at least one branch; b = 0.5 has several existence intervals
    for N in (1, 2, 3, 4):
        assert any(n.startswith(f"b0p5_N{N}_") for n in names), N
    assert sum(n.startswith("b0p5_N1_") for n in names) >= 2
    for name in names:
        ds = tree[name].to_dataset(inherit=False)
        assert ds.attrs["parameter"] == "omega"
        assert np.all(ds["b"].values == 0.5)
        assert ds["omega"].min() >= 0.5 - 1e-12 and ds["omega"].max() <= 6.0 + 1e-12


def test_special_points_checked(outputs):
    out, _ = outputs
    data = json.loads((out / "special_points.json").read_text())
    checked = data["checked"]
    assert len(checked) >= 10
    labels = {c["label"] for c in checked}
    assert {"SN", "PD", "NS", "GR", "ZV"} <= labels
    for c in checked:
        assert set(c) >= CHECK_KEYS, c["label"]
        assert c["part"] in ("physical", "boundary")
        assert set(c["sides"]) == {"below", "above"}
        assert c["sides"]["below"]["omega"] < c["omega"] < c["sides"]["above"]["omega"]
        for side in c["sides"].values():
            assert side["runs"], "every side has at least one simulation"
            for run in side["runs"]:
                assert run["attractor"]["text"]
        assert c["verdict"]
        # the checks must never contradict the closed form
        assert c["agrees"], (c["label"], c["omega"], c["below_text"], c["above_text"])
    assert all(s["part"] == "non-physical" for s in data["skipped_non_physical"])
    table = (out / "special_points.md").read_text()
    assert table.count("\n| 0.5 |") == len(checked)


def test_brute_force_dataset(outputs):
    out, summary = outputs
    with xr.open_dataset(out / "brute_force.nc", engine="netcdf4") as bf:
        assert dict(bf.sizes)["omega"] == 4
        assert list(bf["sweep"].values) == ["up", "down"]
        assert bf["impact_velocity"].dims == ("gap", "sweep", "omega", "sample")
        assert bf["pattern_periods"].dims == ("gap", "sweep", "omega")
        v = bf["impact_velocity"].values
        assert np.all(np.isnan(v) | (v > 0))
    timing = summary["timing"]
    assert timing["continuation"]["branches"] == len(summary["branches"])
    assert timing["brute_force"]["seconds"] > 0
    assert math.isfinite(timing["total_seconds"])


def test_brute_force_sweep_through_chatter_at_b0_records_only_arriving_impacts(study):
    """The full run's sweep up at b = 0 (120 omegas) passes omega = 3.042 and 3.088 through
    complete chatter and sticking phases; it stored an impact at speed -5.55e-17 there (a
    crossing of the stop by rounding right after a release, issue 30). Two of its omegas
    with the quick transient reproduce it (about 2 s): every impact arrives towards the
    stop."""
    omegas = np.linspace(*study.OMEGA_RANGE, study.N_OMEGA)[[55, 56]]
    sweep = study.sweep(0.0, "up", omegas, study.TRANSIENT_QUICK, study.RECORD_QUICK)
    for omega, row in sweep["rows"].items():
        assert row["status"] == "COMPLETED", omega
        assert row["v"].size > 0 and np.all(row["v"] > 0), (omega, row["v"].min())


def test_special_points_at_the_end_of_a_physical_part_are_boundary(study):
    """The N = 3 branch at b = 0.5 is physical from its ZV (1.2134624) to its GR (1.2160683);
    its fold (SN, 1.2160739) lies just beyond. GR and SN are bracketed by the last physical
    point before the fold and the first non-physical one after it: the stored bracket ends at
    the located omega (the schema's bracket holds the location), not at an accepted point's
    omega. Both points are on the boundary of the physical part, so they are checked."""
    osc = study.paper_oscillator(0.5, 1.215)
    ds = ic.continuation(osc, 3, "omega", (1.20, 1.23))
    records = {r["label"]: r for r in study.special_records({"b0p5_N3_a": ds})}
    assert set(records) == {"ZV", "GR", "SN"}
    physical = ds["physical"].values
    for label in ("GR", "SN"):
        r = records[label]
        assert r["bracket"][1] == r["omega"]            # the bracket ends at the location
        p, q = r["point"], r["partner"]
        assert abs(p - q) == 1, (label, p, q)
        assert {bool(physical[p]), bool(physical[q])} == {True, False}, label
        assert r["part"] == "boundary", label
    assert records["ZV"]["part"] == "boundary"


def _synthetic_branch(omega, delta, physical, special):
    """A branch dataset with just what special_records reads: points and special points
    given as (label, omega, delta, point, bracket_lo, bracket_hi)."""
    n = len(omega)
    k = len(special)
    col = list(zip(*special, strict=True))
    return xr.Dataset(
        {"omega": ("point", np.asarray(omega, float)),
         "delta": ("point", np.asarray(delta, float)),
         "physical": ("point", np.asarray(physical, bool)),
         "impact_velocity": ("point", np.ones(n)),
         "special_label": ("special", np.array(col[0], dtype="U2")),
         "special_omega": ("special", np.asarray(col[1], float)),
         "special_delta": ("special", np.asarray(col[2], float)),
         "special_point": ("special", np.asarray(col[3], int)),
         "special_bracket_lo": ("special", np.asarray(col[4], float)),
         "special_bracket_hi": ("special", np.asarray(col[5], float)),
         "special_b": ("special", np.full(k, 0.5)),
         "special_precision": ("special", np.full(k, 1e-14)),
         "special_status": ("special", np.full(k, "located", dtype="U9")),
         "special_multipliers": (("special", "multiplier"), np.ones((k, 4), complex))},
        attrs={"N": 3})


def test_bracket_partner_follows_the_stored_bracket(study):
    """Synthetic brackets: a plain pair, a location beyond both points (between the last
    point and a fold), a fold; two folds in one step (both neighbours span the bracket) is
    decided by where the located (omega, delta) lies; a bracket no neighbour spans is an
    error that names it."""
    omega = [1.00, 1.10, 1.20, 1.15, 1.05]
    delta = [0.0, 0.1, 0.2, 0.3, 0.4]
    physical = [True, True, True, False, False]
    ds = _synthetic_branch(omega, delta, physical, [
        ("PD", 1.05, 0.05, 0, 1.00, 1.10),          # between points 0 and 1
        ("GR", 1.22, 0.22, 2, 1.15, 1.22),          # after point 2, before the fold
        ("SN", 1.23, 0.25, 2, 1.15, 1.23),          # the fold between points 2 and 3
        ("NS", 1.08, 0.38, 4, 1.05, 1.15),          # between points 3 and 4, nearer 4
    ])
    assert [study._bracket_partner(ds, k) for k in range(4)] == [1, 3, 3, 3]
    parts = {r["label"]: r["part"] for r in study.special_records({"x": ds})}
    assert parts == {"PD": "physical", "GR": "boundary", "SN": "boundary",
                     "NS": "non-physical"}
    # point 2 at a minimum, both neighbours above it, the location beyond both
    twice = _synthetic_branch([1.10, 1.00, 1.05], [0.0, 0.1, 0.2], [True, True, False],
                              [("GR", 1.12, 0.18, 1, 1.00, 1.12),
                               ("GR", 1.12, 0.02, 1, 1.00, 1.12)])
    assert study._bracket_partner(twice, 0) == 2
    assert study._bracket_partner(twice, 1) == 0
    bad = _synthetic_branch(omega, delta, physical, [("GR", 1.22, 0.22, 2, 1.30, 1.40)])
    with pytest.raises(ValueError, match=r"special point 0 \(GR at omega=1.22\).*bracket"):
        study._bracket_partner(bad, 0)
