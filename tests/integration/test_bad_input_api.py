"""Bad input to the library's drivers is refused before anything is computed (issue 19)."""

from __future__ import annotations

import numpy as np
import pytest

import impactcont as ic


def two_stops(**kw) -> ic.ImpactOscillator:
    args = dict(M=np.eye(2), K=[[1.0, -1.0], [-1.0, 2.0]], F=[1.0, 0.0], R=0.6, eta=0.1, b=0.5,
                omega=1.2, stops=ic.Stops(mass=1, b_low=0.5))
    return ic.ImpactOscillator(**{**args, **kw})


@pytest.mark.parametrize("kind", ["SN", "PD", "NS", "GR", "ZV"])
def test_a_curve_refuses_stops_other_than_the_papers(kind):
    """The curve problem did not check the stops: it failed part way through computing."""
    with pytest.raises(ic.ParameterError, match="the codim-1 curves: the closed form"):
        ic.curve(two_stops(), 1, kind, start={"omega": 1.2, "b": 0.5},
                 bounds={"omega": (0.6, 2.0), "b": (0.0, 2.0)})
    with pytest.raises(ic.ParameterError, match="one stop on mass 1 only"):
        ic.curve(two_stops(stops=ic.Stops(mass=2)), 1, kind, start={"omega": 1.2, "b": 0.5},
                 bounds={"omega": (0.6, 2.0), "b": (0.0, 2.0)})


K_FREE = np.array([[2.0, -1.0, -1.0], [-1.0, 1.0, 0.0], [-1.0, 0.0, 1.0]])  # K [1, 1, 1] = 0


@pytest.mark.parametrize("masses", [[1.0, 1.0, 1.0], [1.0, 2.0, 3.0], [1.0, 0.5, 2.0],
                                    [1.5, 1.0, 1.0], [1.0, 1e-3, 1e3]])
@pytest.mark.parametrize("damping", [{"eta": 0.05}, {"C": np.diag([0.2, 0.0, 0.0])}])
def test_a_free_mode_is_refused_whatever_the_masses(masses, damping):
    """The free mode's eigenvalue is rounding noise of either sign (-4.4e-16 with unit
    masses, +7.7e-17 with masses 1, 2, 3, 0.0 with 1.5, 1, 1): the modal path refused it
    only when rounding made it negative."""
    with pytest.raises(ic.ParameterError, match="K must be positive definite"):
        # refused by the constructor's Cholesky for some masses, by the modal basis for others
        osc = ic.ImpactOscillator(M=np.diag(masses), K=K_FREE, F=[1.0, 0.0, 0.0], R=0.5,
                                  b=0.1, omega=1.3, **damping)
        ic.periodic_orbits(osc, 1)


@pytest.mark.parametrize("damping", [{"eta": 0.05}, {"C": np.diag([0.1, 0.0, 0.0])}])
def test_a_graded_chain_is_held_on_both_paths(damping):
    """M = diag(1e-12, 1, 1e12): eigenvalues 1e-12..1e12, every mode held."""
    osc = ic.ImpactOscillator.chain(masses=[1e-12, 1.0, 1e12], springs=[1.0, 1.0, 1.0],
                                    F=[1e-12, 0.0, 0.0], R=0.5, b=0.0, omega=1.3, **damping)
    ic.periodic_orbits(osc, 1)  # refused before on the first-order path


@pytest.mark.parametrize(("K", "C"), [(4.0, 4.0), (1.0, 2.0), (9.0, 6.0), (2.0, 8.0 ** 0.5)])
def test_critical_damping_is_refused_whatever_the_last_digits(K, C):
    """C = 2 sqrt(K M) within a few ulp: rounding splits the defective eigenvalue to a
    condition number ~1/sqrt(eps) = 7e7, either side of the old limit 1e8 (43 of these 52
    were accepted with it)."""
    eps = float(np.finfo(float).eps)
    for k in range(-6, 7):
        osc = ic.ImpactOscillator(M=[[1.0]], K=[[K]], C=[[C * (1 + k * eps)]], F=[1.0], R=0.5,
                                  b=0.1, omega=1.3)
        with pytest.raises(ic.ParameterError, match="defective or nearly so"):
            osc.first_order  # noqa: B018


# -- issue 28: what a new user found ---------------------------------------------------------
def _paper() -> ic.ImpactOscillator:
    return ic.ImpactOscillator(M=np.eye(2), K=[[1.0, -1.0], [-1.0, 2.0]], F=[1.0, 0.0], R=0.6,
                               b=0.6, omega=1.0, eta=0.1)


@pytest.fixture(scope="module")
def paper_np():
    """The paper's N = 1 motion as an N-p motion (the path of multi_impact_continuation)."""
    return ic.multi_impact_orbit(_paper(), 1, 1, ic.periodic_orbits(_paper(), 1)[0])


@pytest.mark.parametrize(("parameter", "bounds", "match"), [
    ("omega", "0.5,3", r"bounds must be two numbers \(lo, hi\); got '0\.5,3'"),
    ("omega", (0.5, 2.0, 3.0), r"bounds must be two numbers \(lo, hi\); got \(0\.5, 2\.0, 3"),
    ("R", (0.5, 1.5), r"bounds for R must lie where R is in \[0, 1\]"),
    ("m2", (-0.5, 1.0), r"bounds for m2 must lie where m2 is finite and > 0"),
    ("K[1,1]", (-1.0, 3.0), r"at K\[1,1\] = -1\.0 the oscillator is refused.*K\[1,1\] in "
                            r"\[0\.5, inf\)"),
])
def test_both_continuations_refuse_the_same_bounds_before_computing(paper_np, parameter,
                                                                    bounds, match):
    with pytest.raises(ic.ParameterError, match=match):
        ic.multi_impact_continuation(paper_np, parameter, bounds)
    with pytest.raises(ic.ParameterError, match=match):
        ic.continuation(_paper(), 1, parameter, bounds)


def test_a_progress_callable_must_take_the_record(paper_np):
    for call in (lambda p: ic.multi_impact_continuation(paper_np, "omega", (0.9, 1.1),
                                                        progress=p),
                 lambda p: ic.continuation(_paper(), 1, "omega", (0.9, 1.1), progress=p)):
        with pytest.raises(TypeError, match=r"progress must be a callable taking one Progress "
                                            r"record .*signature \(\)"):
            call(lambda: None)
