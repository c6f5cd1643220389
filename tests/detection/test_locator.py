"""The locator of special points (:mod:`impactcont.detection.locator`).

``locate_zero`` on analytic test functions whose zeros are known in closed form (the
Dottie number ``cos s = s``, a simple root of a cubic, a double zero) to the tolerance it is
given, and a pole reported as only bracketed; ``is_critical`` on hand-made multipliers; and
``drop_grazing_at_zero_velocity`` on hand-made special points.
"""

from __future__ import annotations

import dataclasses
import logging
import math

import numpy as np
import pytest

from impactcont.detection.locator import (
    COMPANIONS,
    STATUSES,
    TWIN_OF,
    drop_grazing_at_zero_velocity,
    drop_twins,
    is_critical,
    locate_zero,
    watched_labels,
)
from impactcont.vocabulary import STATUSES as VOCABULARY_STATUSES
from impactcont.vocabulary import Label

DOTTIE = 0.7390851332151607  # the root of cos s = s (to 16 digits)


@pytest.mark.parametrize("xtol", [1e-8, 1e-10, 1e-13])
def test_a_simple_zero_is_located_within_the_tolerance(xtol):
    calls = []

    def g(s):
        calls.append(s)
        return math.cos(s) - s

    s, status = locate_zero(g, 0.0, 1.0, xtol)
    assert status == "located"
    assert 0.0 <= s <= 1.0
    assert abs(s - DOTTIE) <= xtol + 4 * np.finfo(float).eps * DOTTIE
    assert len(calls) < 60  # Brent: superlinear, not bisection to the last bit


def test_the_bracket_may_be_given_either_way_round_and_the_zero_lie_at_an_end():
    s, status = locate_zero(lambda s: s ** 3 - 2.0, 2.0, 1.0, 1e-14)  # 2^(1/3)
    assert status == "located"
    assert s == pytest.approx(2.0 ** (1.0 / 3.0), abs=1e-13)
    s, status = locate_zero(lambda s: s - 1.0, 0.0, 1.0, 1e-14)
    assert (s, status) == (1.0, "located")


def test_a_zero_of_odd_multiplicity_is_located():
    """``(s - 1/3)^3``: flat at the zero, still a sign change; located within the
    tolerance on the coordinate."""
    s, status = locate_zero(lambda s: (s - 1.0 / 3.0) ** 3, 0.0, 1.0, 1e-12)
    assert status == "located"
    assert abs(s - 1.0 / 3.0) < 1e-5  # |g| below rounding within (eps)^(1/3) of the zero


def test_a_pole_is_only_bracketed():
    """``1 / (s - 0.3)`` changes sign through its pole: Brent converges on 0.3, where the
    test is huge, not zero."""
    s, status = locate_zero(lambda s: 1.0 / (s - 0.3), 0.0, 1.0, 1e-12)
    assert status == "bracketed"
    assert s == pytest.approx(0.3, abs=1e-9)


def test_no_sign_change_is_an_error():
    with pytest.raises(ValueError, match="different signs"):
        locate_zero(lambda s: 1.0 + s * s, 0.0, 1.0, 1e-12)


def test_the_statuses_are_the_vocabularys():
    assert STATUSES is VOCABULARY_STATUSES
    assert {"located", "bracketed"} <= set(STATUSES)


@pytest.mark.parametrize(("label", "mu", "critical"), [
    ("PD", [-1.0 + 1e-9, 0.3, 0.1j], True),
    ("PD", [-1.0 + 1e-5, 0.3], False),  # det(G + I) through the pole of G, not -1
    ("PD", [-0.5, 1.0], False),
    ("NS", [np.exp(1j * 1.2) * (1 + 1e-9), np.exp(-1j * 1.2) * (1 + 1e-9), 0.2], True),
    # |mu| - 1 = 1e-5: the pair is off the circle (issue 28, 1.3: an 'NS' 2e-4 from a
    # zero-velocity impact had this; sqrt(unit_tol) = 3e-4 let it pass)
    ("NS", [np.exp(1j * 1.2) * (1 + 1e-5), np.exp(-1j * 1.2) * (1 + 1e-5), 0.2], False),
    ("NS", [np.exp(1j * 1.2) * 1.01, np.exp(-1j * 1.2) * 1.01, 0.2], False),
    ("NS", [2.0, 0.5, 0.1], False),  # a real reciprocal pair: a neutral saddle
    ("NS", [1.0 + 1e-10, 0.3], False),  # on the circle but real: not a pair
    ("SN", [0.1, 0.2], True),  # any other label: the zero is the point
    ("GR", [], True),
])
def test_is_critical(label, mu, critical):
    assert is_critical(label, np.array(mu, dtype=complex), 1e-7) is critical


@dataclasses.dataclass
class _Point:
    label: str
    value: float
    precision: float
    bracket: tuple[float, float]
    status: str = "located"


def test_a_grazing_at_a_zero_velocity_impact_is_reported_once_as_zv(caplog):
    zv = _Point("ZV", 1.2345, 1e-14, (1.2, 1.3))
    twin = _Point("GR", 1.2345 + 5e-9, 1e-8, (1.2, 1.3))  # its square-root precision
    other_step = _Point("GR", 1.2345, 1e-8, (1.3, 1.4))
    far = _Point("GR", 1.25, 1e-12, (1.2, 1.3))
    pd = _Point("PD", 1.2345, 1e-14, (1.2, 1.3))
    with caplog.at_level(logging.INFO, logger="impactcont.detection.locator"):
        kept = drop_grazing_at_zero_velocity([pd, zv, twin, other_step, far], parameter="omega")
    assert kept == [pd, zv, other_step, far]
    assert "reported once, as ZV" in caplog.text and "omega=" in caplog.text


def test_release_grazing_and_sticking_onset_at_the_end_of_a_sticking_phase_are_the_se(caplog):
    """Where a stick time passes through 0 the landing is the release: the RG and SO tests
    vanish there too; one point, reported once, as SE (an RG elsewhere is kept)."""
    se = _Point("SE", 2.3934, 1e-13, (2.3, 2.4))
    rg = _Point("RG", 2.3934 + 1e-13, 1e-13, (2.3, 2.4))
    so = _Point("SO", 2.3934, 1e-13, (2.3, 2.4))
    lone = _Point("RG", 0.052, 1e-14, (0.05, 0.06))
    with caplog.at_level(logging.INFO, logger="impactcont.detection.locator"):
        kept = drop_twins([lone, se, rg, so], parameter="omega")
    assert kept == [lone, se]
    assert caplog.text.count("reported once, as SE") == 2
    assert COMPANIONS[Label.SO] == (Label.SE, Label.FT)
    assert COMPANIONS[Label.RG] == (Label.SE, Label.SO, Label.FT)
    assert watched_labels(["RG"]) == ["RG", "SE", "SO", "FT"]


def test_the_twins_are_the_kinds_own():
    """Issue 29, 2: which kind a point at another is, is declared by the kind that absorbs
    it (Label.absorbs), not listed in the locator."""
    assert TWIN_OF == {Label.GR: (Label.ZV, Label.FT), Label.ZV: (Label.FT,),
                       Label.RG: (Label.SE, Label.SO, Label.FT),
                       Label.SO: (Label.SE, Label.FT)}


def test_what_vanishes_at_the_end_of_a_flight_is_the_ft(caplog):
    """Where a flight time passes through 0 (FT, a singular point of the branch's system)
    the landing's velocity vanishes with it: a ZV located there is the FT, and a ZV or RG
    only bracketed on its step too (the locator cannot follow the branch there); a ZV
    bracketed on another step, or located away from the FT on its step, is kept."""
    ft = _Point("FT", 1.0, 4e-12, (1.00002, 1.0000221))
    at = _Point("ZV", 1.0 + 1e-12, 1e-12, (1.00002, 1.0000221))
    loose = _Point("ZV", 1.0000221, 2e-6, (1.00002, 1.0000221), status="bracketed")
    rg = _Point("RG", 1.00001, 2e-6, (1.00002, 1.0000221), status="bracketed")
    elsewhere = _Point("ZV", 1.5, 1e-3, (1.4, 1.6), status="bracketed")
    away = _Point("ZV", 1.00001, 1e-14, (1.00002, 1.0000221))
    with caplog.at_level(logging.INFO, logger="impactcont.detection.locator"):
        kept = drop_twins([ft, at, loose, rg, elsewhere, away], parameter="F0")
    assert kept == [ft, elsewhere, away]
    assert caplog.text.count("reported once, as FT") == 3
    # a bracketed FT absorbs only what is within the precisions
    unsure = _Point("FT", 1.0, 2e-5, (1.00002, 1.0000221), status="bracketed")
    assert drop_twins([unsure, loose]) == [unsure, loose]


def test_release_grazing_at_the_onset_of_complete_chatter_is_the_so(caplog):
    """On a stick entered through chatter the held phase shrinks to nothing where the
    pressing force at the accumulation point passes through 0 (SO), and the RG test
    vanishes there too: one point, reported once, as SO (an SO bracketed only drops
    nothing)."""
    so = _Point("SO", 0.9276948, 5e-15, (0.92, 0.93))
    rg = _Point("RG", 0.9276948 + 2e-15, 5e-15, (0.92, 0.93))
    with caplog.at_level(logging.INFO, logger="impactcont.detection.locator"):
        assert drop_twins([rg, so], parameter="omega") == [so]
    assert "reported once, as SO" in caplog.text
    loose = _Point("SO", 0.9276948, 5e-15, (0.92, 0.93), status="bracketed")
    assert drop_twins([rg, loose]) == [rg, loose]


def test_a_zv_only_bracketed_drops_nothing():
    zv = _Point("ZV", 1.0, 1e-14, (0.9, 1.1), status="bracketed")
    gr = _Point("GR", 1.0, 1e-8, (0.9, 1.1))
    assert drop_grazing_at_zero_velocity([zv, gr]) == [zv, gr]
    assert drop_grazing_at_zero_velocity([]) == []


def test_a_kind_event_is_built_from_the_declared_test_of_the_motion():
    """Issue 29, 2: the detectors build each kind's event from its declared MotionTest
    (test, noise and poles as functions of the motion), and watch ZV with GR."""
    from types import SimpleNamespace

    from impactcont.core.locate import MotionTest
    from impactcont.detection.locator import kind_event, watched_labels
    from impactcont.vocabulary import Label

    motions = [SimpleNamespace(h=-1.0, g=2.0), SimpleNamespace(h=0.5, g=-3.0)]
    test = MotionTest(lambda m: m.g, lambda m: 1e-3 * abs(m.g), poles=lambda m: [m.h])
    event = kind_event(Label.PD, test, lambda u, lam: motions[int(lam)], motions.__getitem__)
    assert event.label is Label.PD
    assert event.test(None, 1.0) == -3.0 and event.at_point(0) == 2.0
    assert event.noise(1) == 3e-3 and event.noise_at(None, 0.0) == 2e-3
    assert event.poles(None, 0.0) == [-1.0] and event.poles_at(1) == [0.5]
    bare = kind_event(Label.ZV, MotionTest(lambda m: m.h), lambda u, lam: motions[0],
                      motions.__getitem__)
    assert bare.noise is None and bare.noise_at is None and bare.poles is None
    assert watched_labels([Label.GR, Label.PD]) == [Label.GR, Label.PD, Label.ZV, Label.FT]
    assert watched_labels(["ZV", "GR"]) == ["ZV", "GR", "FT"]
