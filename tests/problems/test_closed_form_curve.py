"""The closed form's curve problems (:mod:`impactcont.problems.closed_form_curve`, the N-1
evaluator of :mod:`impactcont.problems.codim1`): their Jacobians are exact (complex steps,
no finite differences), checked against fourth-order finite differences in every
continuable parameter, every curve kind and damping class; the grazing curve's
second-maximum test against the dense extrema search."""

from __future__ import annotations

import numpy as np
import pytest

import impactcont as ic
from impactcont.kernel import closed_form, contact
from impactcont.orbit.extrema import interior_maxima, sample_times
from impactcont.orbit.flow import Flow
from impactcont.orbit.periodic import modal_arrays, periodic_orbits
from impactcont.problems import codim1

PAIRS = [("omega", "b"), ("b", "omega"), ("omega", "R"), ("R", "b"), ("omega", "F0"),
         ("F0", "omega")]


def _paper(**kw):
    base = dict(M=np.eye(2), K=[[1.0, -1.0], [-1.0, 2.0]], F=[1.5, 0.0], R=0.6, b=0.45,
                omega=1.25, eta=0.1)
    base.update(kw)
    return ic.ImpactOscillator(**base)


def _chain3(**kw):
    # one over-damped, one nearly critical and one light mode (Rayleigh damping)
    K = ic.chain_stiffness([1.0, 2.0, 30.0])
    base = dict(M=np.diag([1.0, 0.5, 0.2]), K=K, F=[1.0, 0.3, 0.0], R=0.7, b=0.2,
                omega=1.1, alpha=0.05, beta=0.08)
    base.update(kw)
    return ic.ImpactOscillator(**base)


def _fd4(problem, x, h):
    """Fourth-order central differences of the residual in x = [u, lam]."""
    m = x.size - 1
    J = np.empty((m, m + 1))
    for j in range(m + 1):
        step = h * max(1.0, abs(x[j]))
        f = []
        for k in (2, 1, -1, -2):
            y = x.copy()
            y[j] += k * step
            f.append(problem.residual(y[:-1], y[-1]))
        J[:, j] = (8.0 * (f[1] - f[2]) - (f[0] - f[3])) / (12.0 * step)
    return J


def _point(problem, osc, kind):
    """Unknowns at the first N = 1 motion of `osc` (not on the curve: the Jacobian is
    defined everywhere)."""
    p1, p2 = problem.parameters
    orbit = periodic_orbits(osc, 1)[0]
    if kind == "GR":
        extras = np.array([0.37 * orbit.period])
    elif kind == "NS":
        rng = np.random.default_rng(3)
        extras = np.concatenate([[0.8], rng.standard_normal(4 * osc.n)])
    else:
        extras = None
    v1, v2 = problem.parameter_value(osc, p1), problem.parameter_value(osc, p2)
    u = problem.initial_unknowns(v1, v2, orbit.delta, extras)
    return np.append(u, v2)


def _jacobian_error(osc, kind, pair):
    """Largest row-relative difference between the problem's Jacobian and _fd4's."""
    problem = codim1.curve_problem(kind, osc, 1, pair)
    x = _point(problem, osc, kind)
    J = problem.full_jacobian(x)
    ref = _fd4(problem, x, 2e-4)
    scale = np.max(np.abs(J), axis=1, keepdims=True)
    return np.max(np.abs(J - ref) / np.maximum(scale, 1e-300))


@pytest.mark.parametrize("kind", ["SN", "PD", "NS", "GR", "ZV"])
@pytest.mark.parametrize("pair", [*PAIRS, ("omega", "eta"), ("eta", "b")])
def test_jacobian_is_exact_paper(kind, pair):
    assert _jacobian_error(_paper(), kind, pair) < 1e-8


@pytest.mark.parametrize("kind", ["SN", "PD", "NS", "GR", "ZV"])
@pytest.mark.parametrize("pair", [("omega", "alpha"), ("beta", "omega"), ("omega", "b")])
def test_jacobian_is_exact_rayleigh_chain(kind, pair):
    assert _jacobian_error(_chain3(), kind, pair) < 1e-7


@pytest.mark.parametrize("kind", ["SN", "PD", "NS", "GR", "ZV"])
@pytest.mark.parametrize("pair", [("omega", "k2"), ("M[1,2]", "b"), ("F[2]", "omega")])
def test_jacobian_in_an_element_is_its_central_difference(kind, pair):
    """Issue 29, item 5: an element of the model as a curve parameter; its column is a
    central difference of step eps^(1/3) scale (error about 1e-10 of the row)."""
    assert _jacobian_error(_paper(), kind, pair) < 1e-7


@pytest.mark.parametrize("pair", [("omega", "b"), ("b", "omega"), ("omega", "R"), ("R", "b")])
@pytest.mark.parametrize("make", [_paper, _chain3])
def test_period_doubling_jacobian_in_real_arithmetic_is_the_complex_steps(make, pair):
    """The PD curve's Jacobian in omega, R and b (the exact slopes of ``c, s`` and of
    ``g``, real arithmetic) against its complex steps, with borders that are not unit
    vectors, at several phases: equal within rounding."""
    osc = make()
    problem = codim1.curve_problem("PD", osc, 1, pair)
    rng = np.random.default_rng(7)
    m = 2 * osc.n + 1
    problem._left, problem._right = rng.standard_normal(m), rng.standard_normal(m)
    x0 = _point(problem, osc, "PD")
    for shift in (0.0, 0.4, -1.3):
        x = x0 + np.r_[0.0, shift, 0.0]
        problem._jac_cache = None
        exact = problem.full_jacobian(x)
        problem._jac_cache = None
        problem._exact_jacobian = lambda pc, x: None  # the generic complex-step columns
        ref = problem.full_jacobian(x)
        del problem._exact_jacobian
        scale = np.max(np.abs(ref), axis=1, keepdims=True)
        assert np.max(np.abs(exact - ref) / scale) < 1e-11


def test_kinds_are_labels_and_strings_are_accepted():
    """Issue 29, item 2: the kinds of curves are the Label members; a string names one."""
    from impactcont.vocabulary import Label

    assert codim1.curve_kind("PD") is Label.PD and codim1.curve_kind(Label.NS) is Label.NS
    for kind in codim1.CURVE_KINDS:
        problem = codim1.curve_problem(kind, _paper(), 1)
        assert problem.kind is Label(kind)
        assert problem.kind is codim1.curve_problem(Label(kind), _paper(), 1).kind
    for bad in ("BP", "pd", None, 3):
        with pytest.raises(ic.ParameterError, match=r"kind must be one of \('SN'"):
            codim1.curve_kind(bad)
    # the points that bound a sticking phase have no curves of N-1 motions, and say where
    # theirs are (curves of motions with sticking phases, followed by shooting)
    for bad in ("SE", "RG", "SO"):
        with pytest.raises(ic.ParameterError, match=rf"got '{bad}' \({bad}, .*has curves of "
                           "motions with sticking phases only"):
            codim1.curve_kind(bad)


def test_no_curve_module_compares_kinds_as_strings():
    """Issue 29, item 2: no ``kind == "PD"`` (or ``!=``, ``in ("SN", ...)``) left in the
    curve stack: the kinds are Label members, their behaviour the problems' methods and
    Label-keyed tables."""
    import re
    from pathlib import Path

    root = Path(codim1.__file__).parents[1]
    pattern = re.compile(r"""(==|!=|\bin)\s*\(?\s*["'](SN|PD|NS|GR|ZV|BP)["']""")
    for module in ("analysis/curves.py", "problems/codim1.py", "problems/closed_form_curve.py",
                   "detection/codim2.py"):
        text = (root / module).read_text()
        assert not pattern.findall(text), (module, pattern.findall(text))


@pytest.mark.parametrize("kind", ["SN", "PD", "GR", "ZV"])
def test_jacobian_at_the_elastic_bound(kind):
    """At R = 1 a central difference would leave the parameter's range; a complex step
    does not. Checked against second-order one-sided differences."""
    osc = _paper(R=1.0)
    problem = codim1.curve_problem(kind, osc, 1, ("omega", "R"))
    x = _point(problem, osc, kind)
    J = problem.full_jacobian(x)
    h = 1e-5
    f = [problem.residual(x[:-1], 1.0 - k * h) for k in (0, 1, 2)]
    one_sided = (3.0 * f[0] - 4.0 * f[1] + f[2]) / (2.0 * h)
    assert np.max(np.abs(J[:, -1] - one_sided)) < 1e-7 * max(1.0, np.max(np.abs(J[:, -1])))


def test_curve_newton_uses_no_residual_differences(monkeypatch):
    """The Jacobian never evaluates the real residual (no finite differences)."""
    osc = _paper()
    problem = codim1.curve_problem("PD", osc, 1, ("omega", "b"))
    x = _point(problem, osc, "PD")
    calls = []
    original = problem.residual
    monkeypatch.setattr(problem, "residual", lambda *a: calls.append(a) or original(*a))
    problem.full_jacobian(x)
    assert calls == []


@pytest.mark.parametrize("omega, b", [(0.4, 0.3), (0.6, 0.5), (0.8, 0.0)])
def test_other_maximum_against_the_dense_search(omega, b):
    """The kernel's search with one maximum excluded equals the dense search's runner-up."""
    osc = _paper(omega=omega, b=b)
    for orbit in periodic_orbits(osc, 2):
        flow = Flow(osc)
        times, peaks = interior_maxima(flow.mass1(orbit.state, orbit.delta),
                                       sample_times(flow, 0.0, orbit.period))
        assert len(peaks) >= 2
        order = np.argsort(peaks)[::-1]
        arrays = modal_arrays(osc)
        w, a, eig_err, u0, ui0 = arrays.w, arrays.a, arrays.eig_err, arrays.u0, arrays.ui0
        modal, sc = closed_form.omega_setup(w, a, arrays.f, u0, ui0, eig_err,
                                       osc.R, osc.omega, 2)
        top, t_top = contact.other_maximum(w, a, u0, modal, sc, osc.omega, osc.R, orbit.delta,
                                          orbit.impact_velocity, np.nan)
        assert top == pytest.approx(peaks[order[0]], abs=1e-12)
        assert t_top == pytest.approx(times[order[0]], abs=1e-8)
        second, t_second = contact.other_maximum(w, a, u0, modal, sc, osc.omega, osc.R,
                                                orbit.delta, orbit.impact_velocity, t_top)
        assert second == pytest.approx(peaks[order[1]], abs=1e-12)
        assert t_second == pytest.approx(times[order[1]], abs=1e-8)
