"""The study studies/grazing_boundary/ runs (quick mode) and its checks hold."""

from __future__ import annotations

import importlib.util
import json
import sys
from pathlib import Path

import pytest

import impactcont as ic

RUN = Path(__file__).resolve().parents[2] / "studies" / "grazing_boundary" / "run.py"


@pytest.fixture(scope="module")
def outputs(tmp_path_factory):
    name = "grazing_boundary_run"
    spec = importlib.util.spec_from_file_location(name, RUN)
    module = importlib.util.module_from_spec(spec)
    sys.modules[name] = module  # worker processes find the module's functions by name
    try:
        spec.loader.exec_module(module)
        out = tmp_path_factory.mktemp("grazing_boundary")
        module.main(out, quick=True)
        yield out
    finally:
        sys.modules.pop(name, None)


def test_files_written(outputs):
    for name in ("map.nc", "curves.nc", "checks.json", "timings.json", "grazing_boundary.png"):
        assert (outputs / name).is_file() and (outputs / name).stat().st_size > 0, name
    assert (outputs / "grazing_boundary.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    tree = ic.load(outputs / "curves.nc")
    kinds = {node.attrs["kind"] for node in tree.subtree if node.has_data}
    assert kinds == {"SN", "PD", "NS", "GR", "ZV"}
    assert ic.load(outputs / "map.nc").attrs["impactcont_dataset"] == "map"


def test_checks(outputs):
    checks = json.loads((outputs / "checks.json").read_text())
    closed = checks["closed_form"]
    assert closed["sn_closed_form_max_error"] < 1e-10
    assert closed["zv_linear_response_max_error"] < 1e-10
    assert closed["max_residual"] < 1e-10
    edges = checks["map_edges"]
    assert edges["cells_crossed_once_checked"] > 50
    assert edges["on_an_edge"] >= 0.97 * edges["cells_crossed_once_checked"]
    assert checks["simulation_checked"] >= 5
    assert checks["simulation_confirmed"] == checks["simulation_checked"]
    assert {s["kind"] for s in checks["simulation"]} >= {"SN", "PD", "GR", "ZV"}
    timings = json.loads((outputs / "timings.json").read_text())
    assert timings["curves"] >= 5 and timings["map_serial_seconds"] > 0
