"""The study studies/paper_example/ runs and reproduces the paper's section-4 numbers."""

from __future__ import annotations

import importlib.util
import json
import sys
from pathlib import Path

import pytest

RUN = Path(__file__).resolve().parents[2] / "studies" / "paper_example" / "run.py"


@pytest.fixture(scope="module")
def study():
    name = "paper_example_run"
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
    out = tmp_path_factory.mktemp("paper_example")
    study.main(out, quick=True)
    return out


def test_files_written(outputs):
    for name in ("numbers.json", "checks.json", "figure3.png", "figure4.png"):
        path = outputs / name
        assert path.is_file() and path.stat().st_size > 0, name
    assert (outputs / "figure3.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


def test_paper_numbers(outputs):
    numbers = json.loads((outputs / "numbers.json").read_text())
    assert numbers["amplitude_squared_omega1_N1"] == pytest.approx(1.74355, abs=5e-6)
    robust = numbers["robust"]
    assert robust["G0_max_abs_deviation"] < 5e-7
    assert robust["epsilon0_paper_Gamma_our_G0"] == pytest.approx(0.343455, abs=5e-7)
    assert robust["epsilon0_paper_Gamma_paper_G0"] == pytest.approx(0.343455, abs=5e-7)
    assert robust["robust"] and robust["direct_rho_scan"]["all_stable"]


def test_claims_against_the_simulator(outputs):
    checks = json.loads((outputs / "checks.json").read_text())
    by_point = {(p["omega"], p["b"]): p for p in checks["points"]}
    assert len(by_point) == 6
    for key in [(1.2, 0.0), (2.4, 0.0), (1.0, 0.2), (1.0, 0.6), (1.0, 1.0)]:
        assert by_point[key]["claim_confirmed"], key
    # the paper's stable period-3 motion at omega = 2.6, b = 0 is not there: the simulator
    # settles on the closed form's stable physical 2-1 motion
    p26 = by_point[(2.6, 0.0)]
    assert not p26["claim_confirmed"]
    assert not p26["closed_form_claim_physical"]
    assert p26["c_attractors"]["patterns_found"] == ["2-1"]
    assert checks["omega2.6_b0_physical_stable"] == ["N=2 root -1"]
    for point in checks["points"]:
        assert point["closed_form_stability_agrees_with_simulator"]
        for a in point["a_return"]:
            assert a["returns_to_itself"] == a["physical"]
