"""Construction, validation and serialisation of ImpactOscillator."""

from __future__ import annotations

import math

import numpy as np
import pytest

from impactcont import ImpactOscillator, ParameterError, chain_stiffness


def test_chain_stiffness_matches_eq2():
    K = chain_stiffness([1.0, 2.0, 3.0])
    expected = np.array([[1.0, -1.0, 0.0], [-1.0, 3.0, -2.0], [0.0, -2.0, 5.0]])
    np.testing.assert_array_equal(K, expected)
    np.testing.assert_array_equal(chain_stiffness([1.0, 1.0]), [[1.0, -1.0], [-1.0, 2.0]])


def test_chain_and_matrix_constructors_agree(paper):
    osc = ImpactOscillator.chain(masses=[1, 1], springs=[1, 1], F=[1, 0], R=0.6, b=0.6,
                                 omega=1.0, eta=0.1)
    np.testing.assert_array_equal(osc.M, paper.M)
    np.testing.assert_array_equal(osc.K, paper.K)
    np.testing.assert_allclose(osc.C, 0.2 * paper.K)


def test_damping_forms(paper):
    assert paper.rayleigh == (0.0, 0.2)
    ray = paper.replace(alpha=0.1, beta=0.05)
    assert ray.eta is None
    np.testing.assert_allclose(ray.C, 0.1 * ray.M + 0.05 * ray.K)
    back = ray.replace(eta=0.3)
    assert back.alpha is None and back.beta is None and back.eta == 0.3
    modes = paper.modes
    np.testing.assert_allclose(modes.damping_ratios, 0.1 * modes.natural_frequencies)


def test_modes_are_mass_normalised():
    M = np.array([[2.0, 0.3], [0.3, 1.0]])
    osc = ImpactOscillator(M=M, K=[[3.0, -1.0], [-1.0, 2.0]], F=[1, 0], R=0.5, b=0, omega=1)
    u = osc.modes.u
    np.testing.assert_allclose(u.T @ M @ u, np.eye(2), atol=1e-14)
    np.testing.assert_allclose(u.T @ osc.K @ u, np.diag(osc.modes.natural_frequencies**2),
                               atol=1e-13)


def test_replace_and_json_round_trip(paper):
    osc = paper.replace(omega=2.5, b=-0.3)
    assert (osc.omega, osc.b) == (2.5, -0.3)
    assert paper.omega == 1.0  # immutable
    again = ImpactOscillator.from_json(osc.to_json())
    for name in ("M", "K", "F"):
        np.testing.assert_array_equal(getattr(again, name), getattr(osc, name))
    assert (again.R, again.b, again.omega, again.eta) == (osc.R, osc.b, osc.omega, osc.eta)


BASE = {"M": np.eye(2), "K": [[1.0, -1.0], [-1.0, 2.0]], "F": [1.0, 0.0], "R": 0.6, "b": 0.0,
        "omega": 1.0, "eta": 0.1}


@pytest.mark.parametrize(
    ("change", "match"),
    [
        ({"K": [[1.0, -1.0], [-0.5, 2.0]]}, "K must be symmetric"),
        ({"K": [[1.0, 2.0], [2.0, 1.0]]}, "K must be positive semi-definite"),
        ({"M": [[1.0, 0.0], [0.0, -1.0]]}, "M must be positive definite"),
        ({"M": np.eye(3)}, "M and K must have the same shape"),
        ({"K": [[1.0, np.nan], [np.nan, 2.0]]}, "K must be finite"),
        ({"F": [1.0, 0.0, 0.0]}, r"F must have shape \(2,\)"),
        ({"F": [1.0, math.inf]}, "F must be finite"),
        ({"R": 1.5}, r"R must be in \[0, 1\]; got 1.5"),
        ({"R": -0.1}, r"R must be in \[0, 1\]"),
        ({"omega": 0.0}, "omega must be finite and > 0; got 0.0"),
        ({"omega": -2.0}, "omega must be finite and > 0"),
        ({"b": math.nan}, "b must be a finite real number"),
        ({"eta": -0.1}, "eta must be finite and >= 0; got -0.1"),
        ({"alpha": 0.1}, "give either eta"),
    ],
)
def test_bad_input_raises_with_name_and_value(change, match):
    with pytest.raises(ParameterError, match=match):
        ImpactOscillator(**{**BASE, **change})


def test_bad_types_raise_type_error():
    with pytest.raises(TypeError, match="omega must be a real number"):
        ImpactOscillator(**{**BASE, "omega": "fast"})
    with pytest.raises(TypeError, match="R must be a real number"):
        ImpactOscillator(**{**BASE, "R": True})


def test_bad_chain_and_replace(paper):
    with pytest.raises(ParameterError, match="springs must be finite and >= 0"):
        ImpactOscillator.chain(masses=[1, 1], springs=[1, -1], F=[1, 0], R=0.5, b=0, omega=1)
    with pytest.raises(ParameterError, match="masses must be"):
        ImpactOscillator.chain(masses=[1, 0], springs=[1, 1], F=[1, 0], R=0.5, b=0, omega=1)
    with pytest.raises(ParameterError, match="springs must have the same length"):
        ImpactOscillator.chain(masses=[1, 1], springs=[1, 1, 1], F=[1, 0], R=0.5, b=0, omega=1)
    with pytest.raises(ParameterError, match=r"unknown parameter\(s\) \['gap'\]"):
        paper.replace(gap=0.2)
