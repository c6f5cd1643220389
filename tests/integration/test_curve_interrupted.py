"""Ctrl-C while the codim-2 points of a curve are located (issue 31): the curve comes back
with the points located before it, marked interrupted, on N-1 curves (closed form) and on
curves of N-p motions alike."""

from __future__ import annotations

import json

import numpy as np
import pytest

import impactcont as ic
import impactcont.detection.codim2 as codim2_module
from impactcont.analysis.curves import multi_impact_curve

BOX = {"omega": (0.6, 2.0), "b": (0.0, 0.6)}


@pytest.fixture(scope="module")
def system() -> ic.ImpactOscillator:
    return ic.ImpactOscillator(M=np.eye(2), K=[[1.0, -1.0], [-1.0, 2.0]], F=[1.0, 0.0], R=0.6,
                               b=0.0, omega=1.75, eta=0.1)


@pytest.fixture(scope="module")
def branch(system):
    return ic.continuation(system, 1, "omega", (1.6, 1.9), detect=("PD",), progress=False)


def _interrupt_the_location_at(monkeypatch, call: int) -> list[str]:
    """Ctrl-C at the `call`-th location of a codim-2 point (and at every later one)."""
    locate = codim2_module._codim2_in
    calls: list[str] = []

    def interrupted(problem, step, test, *args):
        calls.append(str(test))
        if len(calls) >= call:
            raise KeyboardInterrupt
        return locate(problem, step, test, *args)

    monkeypatch.setattr(codim2_module, "_codim2_in", interrupted)
    return calls


def _check_kept(full, cut, caplog) -> None:
    kept = cut.sizes["codim2"]
    assert 0 < kept < full.sizes["codim2"]
    assert cut.sizes["point"] == full.sizes["point"]  # the curve itself is whole
    for k in range(kept):  # the points located before Ctrl-C, as located without it
        label = str(cut.codim2_label.values[k])
        twin = int(np.flatnonzero(full.codim2_label.values == label)[0])
        for name in ("omega", "b", "precision"):
            assert float(cut[f"codim2_{name}"].values[k]) == pytest.approx(
                float(full[f"codim2_{name}"].values[twin]), rel=1e-9, abs=1e-12)
    options = json.loads(cut.attrs["options"])
    assert options["interrupted"] is True and options["interrupted_while"] == "location"
    assert cut.attrs["interrupted"] == 1 and "interrupted" not in full.attrs
    assert any("those located before are kept" in r.getMessage() for r in caplog.records
               if r.levelname == "WARNING")


def test_ctrl_c_while_locating_keeps_the_codim2_points_of_an_n1_curve(branch, monkeypatch,
                                                                       caplog):
    full = ic.curve(None, None, "PD", start=branch, bounds=BOX, progress=False)
    assert full.sizes["codim2"] == 4
    calls = _interrupt_the_location_at(monkeypatch, 2)
    cut = ic.curve(None, None, "PD", start=branch, bounds=BOX, progress=False)
    assert len(calls) == 2
    _check_kept(full, cut, caplog)


def test_ctrl_c_while_locating_keeps_the_codim2_points_of_an_np_curve(system, monkeypatch,
                                                                       caplog):
    physical = next(q for q in ic.periodic_orbits(system, 1) if q.physical)
    branch = ic.multi_impact_continuation(ic.multi_impact_orbit(system, 1, 1, physical),
                                          "omega", (1.6, 1.9), detect=("PD",),
                                          both_directions=True, progress=False)
    full = multi_impact_curve(branch, "PD", 0, parameter="b", bounds=BOX, progress=False)
    assert full.sizes["codim2"] == 4
    calls = _interrupt_the_location_at(monkeypatch, 2)
    cut = multi_impact_curve(branch, "PD", 0, parameter="b", bounds=BOX, progress=False)
    assert len(calls) == 2
    _check_kept(full, cut, caplog)
