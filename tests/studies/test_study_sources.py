"""The published single-harmonic closed form of a free mass in the cavity of a forced
primary (Weidemann, Bergman, Vakakis & Krack, Nonlinear Dyn. 2025, as written in their
public code; ``studies/vi_nes/source_formula.py``) against the studies' exact closed forms
(``studies/vi_nes/closed_form.py``, ``studies/impact_damper/closed_form.py``) and the
package's ``multi_impact_orbit``.

The source's formula is asymptotic, not exact: what it guarantees is its order, so that
is what is tested. In its own limit (mass ratio ``mu -> 0`` with damping, detuning of
order ``mu`` and the clearance over the resonance amplitude fixed) its difference from the
exact motion vanishes like ``mu`` (halving ``mu`` halves it); at a fixed frequency and
damping the particle's amplitude is first order and the primary's fundamental second
order in ``mu``. A mis-stated formula (a wrong factor, sign or root) breaks the order."""

from __future__ import annotations

import importlib.util
import itertools
import math
import sys
from pathlib import Path

import pytest

# the repository root, wherever this file sits under tests/
STUDIES = next(p / "studies" for p in Path(__file__).resolve().parents
               if (p / "studies" / "vi_nes" / "source_formula.py").is_file())


def _load(name: str, path: Path):
    if name in sys.modules:
        return sys.modules[name]
    spec = importlib.util.spec_from_file_location(name, path)
    module = importlib.util.module_from_spec(spec)
    sys.modules[name] = module
    spec.loader.exec_module(module)
    return module


@pytest.fixture(scope="module")
def vi():
    return _load("vi_nes_sources_compare", STUDIES / "vi_nes" / "source_compare.py")


@pytest.fixture(scope="module")
def dmp():
    return _load("impact_damper_sources_compare", STUDIES / "impact_damper" / "source_compare.py")


KEYS = ("xi", "theta", "phase")


@pytest.mark.parametrize("r0", [0.9, 1.0, 1.2])
def test_vi_nes_source_converges_at_first_order_in_its_limit(vi, r0):
    """mu = 0.05 s, zeta = 0.02 s, b = 5/s, r = 1 + (r0 - 1) s, s = 1, 1/2, 1/4: each
    halving of s halves the difference in the primary's fundamental, the ball's amplitude
    and the phase (first order: ratio 0.5 within the next order's share), and at s = 1
    (the study's machine) the difference is below mu itself."""
    rows = [vi.limit_row(r0, s) for s in (1.0, 0.5, 0.25)]
    for a, c in itertools.pairwise(rows):
        for k in KEYS:
            assert 0.35 < c[k] / a[k] < 0.65, (r0, k, a, c)
    for row in rows:
        for k in KEYS:
            assert row[k] < vi.MU * row["s"], (r0, row)


@pytest.mark.parametrize("r", [0.9, 1.0, 1.1, 1.2])
def test_vi_nes_source_against_exact_and_package(vi, r):
    """The study's machine (mu = 0.05): every motion of the source's formula has an exact
    symmetric root and the package's motion within O(mu) (below mu), the package equal to
    the exact root to Newton's accuracy, and the two differences the same."""
    rows = vi.compare(r)
    assert len(rows) == 1
    row = rows[0]
    assert row["exact"] is not None
    assert row["package"]["error_estimate"] < 1e-10
    assert row["package_vs_exact"] < 1e-9
    for k in KEYS:
        assert row["source_vs_package"][k] < vi.MU
        assert abs(row["source_vs_package"][k] - row["source_vs_exact"][k]) < 1e-9


@pytest.mark.parametrize("r", [0.85, 1.1, 1.2])
def test_vi_nes_other_root_of_the_quadratic_is_the_second_exact_root(vi, r):
    """The root of (W2) the source discards (sign -1) describes the exact closed form's
    other symmetric root: a different root from the source's, within O(mu)."""
    (plus,) = vi.compare(r, package=False)
    (minus,) = vi.compare(r, package=False, sign=-1)
    assert plus["exact_index"] != minus["exact_index"]
    for k in KEYS:
        assert minus["source_vs_exact"][k] < vi.MU


@pytest.mark.parametrize("r, d", [(0.7, 2.0), (1.5, 2.0)])
def test_impact_damper_source_orders_in_the_mass_ratio(dmp, r, d):
    """The impact damper (zeta = 0.05, e = 0.8), mu = 0.2, 0.1, 0.05, 0.025: the particle's
    amplitude converges at first order (ratio 1/2), the primary's fundamental and phase at
    second order (ratio 1/4) at each halving."""
    rows = []
    for mu in (0.2, 0.1, 0.05, 0.025):
        got = dmp.compare(r, d, mu, package=False)
        assert len(got) == 1 and got[0]["exact"] is not None
        rows.append(got[0]["source_vs_exact"])
    for a, c in itertools.pairwise(rows):
        assert 0.4 < c["theta"] / a["theta"] < 0.65, (a, c)
        assert 0.15 < c["xi"] / a["xi"] < 0.35, (a, c)
        assert 0.15 < c["phase"] / a["phase"] < 0.35, (a, c)


def test_impact_damper_source_against_package(dmp):
    """At the study's stable motion (omega = 1.5, d = 2, mu = 0.2) the package's motion is
    the exact root and the source's formula is within its order (below mu)."""
    (row,) = dmp.compare(1.5, 2.0)
    assert row["physical"] and row["stable"]
    assert row["package_vs_exact"] < 1e-9
    for k in KEYS:
        assert row["source_vs_package"][k] < dmp.MU


def test_source_formula_bad_input(vi):
    sf = vi.sf
    with pytest.raises(ValueError, match="e_N"):
        sf.rho(1.5)
    with pytest.raises(ValueError, match="xi"):
        sf.theta(0.5 * sf.xi_min(0.6), 0.6)
    with pytest.raises(ValueError, match="mu"):
        sf.mapping(1.0, 0.0, 0.02)
    with pytest.raises(ValueError, match="zeta"):
        sf.mapping(1.0, 0.05, 1.0)
    with pytest.raises(ValueError, match="sign"):
        sf.theta(1.0, 0.6, sign=0)
    with pytest.raises(ValueError, match="b"):
        sf.motions(1.0, 0.05, 0.02, -1.0, 0.6)
    assert math.isclose(sf.theta(sf.xi_min(0.6), 0.6), 1.0 / (1.0 + sf.rho(0.6) ** 2))
