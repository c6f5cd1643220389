"""The vocabulary: labels and parameters defined once, used everywhere."""

from __future__ import annotations

import math

import numpy as np
import pytest

import impactcont as ic
from impactcont import vocabulary as vocab
from impactcont.dataset import PARAMETERS, SPECIAL_LABELS
from impactcont.detection import LABELS


def test_labels_are_strings_and_the_old_names_are_the_same_tuple():
    assert vocab.Label.PD == "PD" and f"{vocab.Label.PD}" == "PD" and str(vocab.Label.NS) == "NS"
    assert LABELS == SPECIAL_LABELS == vocab.LABELS == ("SN", "PD", "NS", "GR", "ZV", "BP",
                                                        "SE", "RG", "SO", "FT")
    # every label has its codim-1 curve; BP (symmetric N-p motions) and the points that
    # bound a sticking phase (SE, RG, SO) of their motions only: not among the kinds of
    # curves of every motion, but among those followed by shooting; FT, a singular point of
    # the shooting system, none yet
    assert vocab.CURVE_KINDS == ("SN", "PD", "NS", "GR", "ZV")
    from impactcont.problems.codim1 import CURVE_KINDS, SHOOTING_KINDS
    assert CURVE_KINDS == vocab.CURVE_KINDS
    assert set(SHOOTING_KINDS) == {label for label in LABELS if not vocab.Label(label).singular}
    assert [label for label in vocab.Label if label.singular] == [vocab.Label.FT]
    # every label has its marker and its words, defined with it (figures read them)
    assert set(vocab.LABEL_MARKERS) == set(vocab.LABEL_NAMES) == set(LABELS)
    assert set(vocab.LABEL_COLOURS) == set(LABELS)
    assert set(PARAMETERS) == set(vocab.CONTINUABLE_PARAMETERS)


def test_each_kind_carries_its_marker_words_codimension_and_curves():
    """Issue 29, 2: a kind is an object; the old dicts are views of its attributes."""
    assert vocab.Label.PD.marker == "s" and vocab.Label.NS.words == "Neimark-Sacker"
    assert {label.codimension for label in vocab.Label} == {1}
    assert {label.value: label.marker for label in vocab.Label} == vocab.LABEL_MARKERS
    assert vocab.LABEL_NAMES["BP"] == vocab.Label.BP.words == "symmetry-breaking pitchfork"
    assert tuple(label for label in vocab.Label if label.curves) == vocab.CURVE_KINDS
    assert vocab.CURVE_KINDS[1] is vocab.Label.PD and not vocab.Label.BP.curves
    # the points that bound a sticking phase: their own markers, words, no curves of every
    # motion (curves of motions with sticking phases only); their codim-2 points named
    sticking = (vocab.Label.SE, vocab.Label.RG, vocab.Label.SO)
    assert [kind.words for kind in sticking] == ["end of a sticking phase", "release grazing",
                                                 "sticking onset"]
    assert not any(kind.curves for kind in sticking)
    assert {"SE+PD", "RG+SO", "SO+SE", "PD+SE", "GR+RG"} <= set(vocab.CODIM2_LABELS)
    assert len(set(vocab.CODIM2_LABELS)) == len(vocab.CODIM2_LABELS)
    markers = list(vocab.LABEL_MARKERS.values())
    assert len(set(markers)) == len(markers)  # no two kinds drawn alike
    colours = list(vocab.LABEL_COLOURS.values())
    assert len(set(colours)) == len(colours)  # no two kinds of curves drawn alike
    # the end of a flight: its own marker and words; the ZV, GR, RG and SO at it are it; it
    # bounds the physical motions, and its points are singular points of the shooting
    assert vocab.Label.FT.words == "end of a flight" and not vocab.Label.FT.curves
    assert set(vocab.Label.FT.absorbs) == {"ZV", "GR", "RG", "SO"}
    assert vocab.Label.FT.bounds and vocab.Label.FT.singular
    assert {label for label in vocab.Label if label.bounds} == {"GR", "ZV", "SE", "RG", "SO",
                                                               "FT"}
    # a kind reads as its label in messages, is found by it and hashes as it
    assert repr(vocab.Label.GR) == "'GR'" and vocab.Label("ZV") is vocab.Label.ZV
    assert {"SN": 1}[vocab.Label.SN] == 1


def test_damping_rule_is_one_function():
    eta = ic.ImpactOscillator(M=np.eye(1), K=[[1.0]], F=[1.0], R=0.5, b=0.1, omega=1.5, eta=0.1)
    rayleigh = eta.replace(eta=None, alpha=0.1, beta=0.0)
    vocab.check_damping(eta, "eta")
    vocab.check_damping(rayleigh, "beta")
    with pytest.raises(ic.ParameterError, match="needs Rayleigh damping"):
        ic.continuation(eta, 1, "alpha", (0.0, 0.2))
    with pytest.raises(ic.ParameterError, match="needs the paper's damping"):
        vocab.check_parameter(rayleigh, "eta")
    with pytest.raises(ic.ParameterError, match="must be one of"):
        vocab.check_parameter(eta, "clearance")
    with pytest.raises(ic.ParameterError, match="labels must be a subset"):
        vocab.check_labels(["PD", "XX"])


def test_parameter_ranges():
    assert not vocab.PARAMETERS["omega"].contains(0.0)
    assert vocab.PARAMETERS["R"].contains(1.0) and not vocab.PARAMETERS["R"].contains(1.1)
    assert vocab.PARAMETERS["b"].contains(-3.0)


# -- bounds: one check for every driver (issue 28) -------------------------------------------
@pytest.mark.parametrize(("bounds", "message"), [
    ("0.5,3", "bounds must be two numbers (lo, hi); got '0.5,3'"),
    ((0.5, 2.0, 3.0), "bounds must be two numbers (lo, hi); got (0.5, 2.0, 3.0)"),
    ((2.0, 0.5), "bounds must be two finite numbers with lo < hi; got (2.0, 0.5)"),
    ((0.5, math.nan), "bounds must be two finite numbers with lo < hi; got (0.5, nan)"),
    ((-1.0, 2.0), "bounds for omega must lie where omega is finite and > 0; got (-1.0, 2.0)"),
])
def test_bounds_are_one_shared_check(bounds, message):
    with pytest.raises(ic.ParameterError) as info:
        vocab.check_bounds("omega", bounds)
    assert str(info.value) == message


# -- counts: one refusal of N, p, a mass's number ------------------------------------------------
def test_positive_integer_takes_python_and_numpy_integers():
    assert vocab.check_positive_integer("N", 3) == 3
    value = vocab.check_positive_integer("N", np.int64(2))
    assert value == 2 and type(value) is int


@pytest.mark.parametrize("value", [0, -1, True, np.bool_(True), 1.0, "2", None, np.uint8(0)])
def test_positive_integer_refuses_naming_argument_meaning_and_value(value):
    with pytest.raises(ic.ParameterError) as info:
        vocab.check_positive_integer("N", value, "impact every N forcing periods")
    assert str(info.value) == (f"N must be an integer >= 1 (impact every N forcing periods); "
                               f"got {value!r}")


def test_positive_integer_without_meaning_says_none():
    with pytest.raises(ic.ParameterError, match=r"^max_iter must be an integer >= 1; got 0$"):
        vocab.check_positive_integer("max_iter", 0)
