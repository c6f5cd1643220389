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
