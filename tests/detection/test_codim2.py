"""Codim-2 points (:mod:`impactcont.detection.codim2`): a strong resonance has one name on
every curve, and every codim-2 label has its standard name in the docs."""

from __future__ import annotations

import numpy as np
import pytest

import impactcont as ic


@pytest.mark.parametrize("kind, multipliers, label", [
    ("SN", [1.0, 1.0 + 1e-5, 0.3], "R1"),          # a double +1: the 1:1 resonance
    ("SN", [1.0, 1.0 + 2e-5j, 0.3], "R1"),         # its Jordan block split into a pair
    ("PD", [-1.0, -1.0 - 1e-5, 0.2], "R2"),        # a double -1: the 1:2 resonance
    ("SN", [1.0, np.exp(0.4j), np.exp(-0.4j)], "SN+NS"),
])
def test_a_strong_resonance_has_one_name_on_every_curve(kind, multipliers, label):
    """The NS curve ends at R1/R2; the SN and PD curves meeting them there name them so."""
    from types import SimpleNamespace

    from impactcont.detection.codim2 import _name
    from impactcont.vocabulary import CODIM2_LABELS

    assert _name(kind, "NS", SimpleNamespace(multipliers=np.array(multipliers))) == label
    assert not {"SN+SN", "PD+PD"} & set(CODIM2_LABELS)


@pytest.mark.parametrize("test, multipliers, label", [
    ("SN", [1.0, 1.0 + 1e-5, 0.3], "R1"),     # the pair of the NS curve met at +1
    ("PD", [-1.0, -1.0 - 1e-5, 0.2], "R2"),   # ... at -1
    ("SN", [1.0, 0.5, 0.2], "NS+SN"),          # one multiplier +1: a fold on the NS curve
])
def test_an_ns_curve_that_goes_on_through_a_strong_resonance_names_it(test, multipliers,
                                                                       label):
    """An NS curve of N-p motions does not end at R1/R2 (its bialternate test goes on as a
    neutral saddle): there its SN or PD test vanishes with a double +1 or -1."""
    from types import SimpleNamespace

    from impactcont.detection.codim2 import _name

    assert _name("NS", test, SimpleNamespace(multipliers=np.array(multipliers))) == label


def test_every_codim2_label_has_its_standard_name_in_the_docs():
    from pathlib import Path

    from impactcont.vocabulary import CODIM2_LABELS

    docs = Path(ic.__file__).resolve().parents[1] / "docs" / "two_parameter.md"
    rows = {line.split("|")[1].strip().strip("`") for line in docs.read_text().splitlines()
            if line.startswith("| `")}
    assert set(CODIM2_LABELS) <= rows, sorted(set(CODIM2_LABELS) - rows)


class _LineCurve:
    """A stand-in curve ``x = (p1, theta, p2)`` along a straight line, with a motion whose
    ``gap_min`` is +inf (no interior maximum) above p1 = 0.42 and ``p1 - 0.3`` below."""

    kind = "SN"
    parameters = ("omega", "b")
    codim2_tests = ("ZV", "GR", "PD", "NS")
    last_step = 0.0

    def codim2_test(self, test, x, orbit):
        from impactcont.problems.events import event_function

        return event_function(test, orbit)

    def plane(self, x):
        return float(x[0]), float(x[-1])

    def on_hyperplane(self, guess, normal):
        return guess

    def end_resonance(self, x):
        return None

    def accept(self, u, lam):
        pass

    def orbit(self, u, lam):
        from types import SimpleNamespace

        p1 = float(u[0])
        return SimpleNamespace(gap_min=np.inf if p1 > 0.42 else p1 - 0.3, impact_velocity=1.0,
                               multipliers=np.array([1.0, 0.5, 0.2]))


def test_a_grazing_test_from_plus_infinity_is_watched_on_curves():
    """Issue 28, 1.4 on curves: a GR test that is +inf at one end of a step (no interior
    maximum yet) and negative at the other changes sign; it was skipped as non-finite."""
    from impactcont.detection.codim2 import detect_codim2, test_values

    problem = _LineCurve()
    xs = [np.array([p1, 0.0, 1.0]) for p1 in (0.2, 0.5)]
    orbits = [problem.orbit(x[:-1], x[-1]) for x in xs]
    tests = [test_values(problem, x, o) for x, o in zip(xs, orbits, strict=True)]
    (point,) = detect_codim2(problem, xs, orbits, tests)
    assert (point.label, point.status) == ("SN+GR", "located")
    assert abs(point.x[0] - 0.3) <= point.precision < 1e-12


class _DipCurve(_LineCurve):
    """``gap_min = (p1 - 0.3)(p1 - 0.32)``: two grazings inside one step of the curve."""

    def orbit(self, u, lam):
        from types import SimpleNamespace

        p1 = float(u[0])
        return SimpleNamespace(gap_min=(p1 - 0.3) * (p1 - 0.32), impact_velocity=1.0,
                               multipliers=np.array([1.0, 0.5, 0.2]))


def test_two_grazings_inside_one_step_of_a_curve_are_both_located():
    from impactcont.detection.codim2 import detect_codim2, test_values

    problem = _DipCurve()
    xs = [np.array([p1, 0.0, 1.0]) for p1 in (0.1, 0.2, 0.4, 0.5)]
    orbits = [problem.orbit(x[:-1], x[-1]) for x in xs]
    tests = [test_values(problem, x, o) for x, o in zip(xs, orbits, strict=True)]
    found = detect_codim2(problem, xs, orbits, tests)
    assert [(p.label, p.status) for p in found] == [("SN+GR", "located")] * 2
    np.testing.assert_allclose(sorted(p.x[0] for p in found), [0.3, 0.32], atol=1e-12)
