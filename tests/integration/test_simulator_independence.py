"""The simulator is an independent witness: it reads the model only, with its own flight.

Issue 29, 4: ``simulate/`` imported ``orbit/`` (``Flow``, the extrema search), the very
code it checks. Now it evaluates the flight itself (:mod:`impactcont.simulate.flight`,
the matrix exponential of the forced system) and imports nothing but the model and the
package's generic helpers. Held three ways: the imports written in its source, the
modules a fresh interpreter loads to simulate with the motion code out of reach, and the
oscillator's bases (modal, first-order), which the simulator never asks for.
"""

from __future__ import annotations

import ast
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

import impactcont as ic
from impactcont.model.oscillator import ImpactOscillator
from impactcont.simulate import flight as flight_module
from impactcont.simulate import simulate

SIMULATE = Path(flight_module.__file__).resolve().parent
#: What the witness may import from impactcont: the model and generic helpers.
ALLOWED = ("impactcont.model", "impactcont.errors", "impactcont.threads",
           "impactcont.vocabulary", "impactcont.simulate")
#: What it must never reach: the code it witnesses and everything built on it.
FORBIDDEN = ("impactcont.orbit", "impactcont.kernel", "impactcont.core",
             "impactcont.problems", "impactcont.detection", "impactcont.analysis")


def _imports(path: Path) -> list[tuple[int, str]]:
    """``(line, module)`` of every import in a file, function bodies included; relative
    imports resolved against ``impactcont.simulate``, ``from a import b`` read as ``a.b``."""
    out = []
    for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
        if isinstance(node, ast.Import):
            out += [(node.lineno, alias.name) for alias in node.names]
        elif isinstance(node, ast.ImportFrom):
            base = node.module or ""
            if node.level:
                parts = ["impactcont", "simulate"][: 2 - (node.level - 1)]
                base = ".".join([*parts, base] if base else parts)
            out += [(node.lineno, f"{base}.{alias.name}") for alias in node.names]
    return out


def test_the_import_reader_sees_every_form():
    source = ("import impactcont.orbit.flow\nfrom impactcont import kernel\n"
              "def f():\n    from ..orbit import extrema\n    from . import search\n")
    path = Path(__file__).with_name("_imports_probe.py")
    try:
        path.write_text(source, encoding="utf-8")
        found = [name for _, name in _imports(path)]
    finally:
        path.unlink()
    assert found == ["impactcont.orbit.flow", "impactcont.kernel",
                     "impactcont.orbit.extrema", "impactcont.simulate.search"]


def test_simulate_imports_the_model_and_generic_helpers_only():
    bad = []
    for path in sorted(SIMULATE.glob("*.py")):
        for line, name in _imports(path):
            if not name.startswith("impactcont"):
                continue
            if any(name == f or name.startswith(f + ".") for f in FORBIDDEN) or not any(
                    name == a or name.startswith(a + ".") for a in ALLOWED):
                bad.append(f"{path.name}:{line} imports {name}")
    assert not bad, "the witness reaches beyond the model: " + "; ".join(bad)


_OUT_OF_REACH = """
import sys
import numpy as np
# the motion code and everything above it cannot be imported (the model needs only the
# kernel's array containers, impactcont.kernel.arrays)
for name in ("impactcont.orbit", "impactcont.core", "impactcont.problems",
             "impactcont.detection", "impactcont.analysis", "impactcont.kernel.closed_form",
             "impactcont.kernel.general", "impactcont.kernel.shooting",
             "impactcont.kernel.contact", "impactcont.kernel.sweep"):
    sys.modules[name] = None
from impactcont.model.oscillator import ImpactOscillator
from impactcont.model.stops import Stops
from impactcont.simulate import simulate
machines = [
    ImpactOscillator(M=np.eye(2), K=[[1.0, -1.0], [-1.0, 2.0]], F=[1.0, 0.0], R=0.6, b=0.6,
                     omega=1.0, eta=0.1),
    ImpactOscillator(M=np.eye(2), K=[[1.0, -1.0], [-1.0, 2.0]], F=[1.0, 0.5j], R=0.6, b=0.6,
                     omega=1.0, C=[[0.3, -0.1], [-0.1, 0.05]]),
    ImpactOscillator(M=np.diag([1.0, 0.2]), K=np.diag([1.0, 0.0]), F=[1.0, 0.0], R=0.8,
                     b=1.0, omega=1.5, eta=0.05, stops=Stops(mass=2, relative_to=1,
                                                             mirror=True)),
]
counts = [simulate(osc, np.zeros(4), 0.0, 5.0).impact_times.size for osc in machines]
assert all(counts), counts
loaded = sorted(m for m in sys.modules if m.startswith("impactcont.") and sys.modules[m])
print(" ".join(loaded))
"""


def test_the_simulator_runs_with_the_motion_code_out_of_reach():
    done = subprocess.run([sys.executable, "-c", _OUT_OF_REACH], capture_output=True,
                          text=True, timeout=300, check=False)
    assert done.returncode == 0, done.stderr[-2000:]
    loaded = done.stdout.split()
    reached = [m for m in loaded if m.startswith(FORBIDDEN) and m != "impactcont.kernel"
               and m != "impactcont.kernel.arrays"]
    assert not reached, reached
    assert "impactcont.simulate.flight" in loaded


def _refuse(self):
    raise AssertionError("the witness asked the oscillator for a basis of the orbit code")


@pytest.mark.parametrize("params", [
    {"eta": 0.1},
    {"C": [[0.3, -0.1], [-0.1, 0.05]]},
    {"eta": 0.1, "F": [1.0, 0.4 - 0.3j], "F_static": [0.1, -0.2]},
    {"eta": 0.1, "stops": ic.Stops(b_low=0.5, R_low=0.8)},
], ids=["modal", "any-C", "complex-F-static", "two-sided"])
def test_the_simulator_reads_no_basis_of_the_oscillator(monkeypatch, params):
    """The modal basis (eq. 5-7) and the first-order basis are the orbit code's ingredients:
    the witness builds its own flight from M, C, K, F and F_static."""
    osc = ImpactOscillator(**{"M": np.eye(2), "K": [[1.0, -1.0], [-1.0, 2.0]], "F": [1.0, 0.0],
                              "R": 0.6, "b": 0.2, "omega": 1.3, **params})
    monkeypatch.setattr(ImpactOscillator, "modes", property(_refuse))
    monkeypatch.setattr(ImpactOscillator, "first_order", property(_refuse))
    res = simulate(osc, np.zeros(4), 0.0, 20.0)
    assert res.impact_times.size > 5
