"""The compiled paths of N-p branches and curves (issue 20's per-point targets).

The continuation of an N-p motion in omega corrects each step in one compiled call
(``kernel.shooting.palc_correct`` behind ``MultiImpactBranchProblem.palc_step``), each
evaluation in one compiled call (``linearize``: residual, Jacobian and dF/domega), shares
the start's modal basis between omega values, and a curve's BP and PD tests come from one
compiled product of the flights' G_k. Witnesses: central finite differences of the
residual (dF/domega, dF/db), numpy's LAPACK path of the same system (the core's own
Python corrector, ``Flow(osc)`` built from scratch, ``half_map`` and ``orbit.G`` of the
full orbit), and the branch followed by the core's generic path (a wrapper without the
compiled hooks).
"""

from __future__ import annotations

import warnings

import numpy as np
import pytest

import impactcont as ic
from impactcont.core import ContinuationOptions
from impactcont.core.stepper import NewtonConvergenceError, PalcStepper
from impactcont.model.modal import forced_coefficients
from impactcont.model.parameters import model_parameter
from impactcont.model.stops import Stops
from impactcont.orbit.flow import Flow
from impactcont.orbit.multi_impact import multi_impact_orbit, shooting
from impactcont.orbit.symmetry import half_map
from impactcont.problems.codim1 import MultiImpactCurveProblem
from impactcont.problems.multi_impact_branch import MultiImpactBranchProblem
from impactcont.problems.symmetric_branch import SymmetricBranchProblem

K2 = [[1.0, -1.0], [-1.0, 2.0]]


def mirrored(omega: float = 1.6, b: float = 0.5) -> ic.ImpactOscillator:
    return ic.ImpactOscillator(M=np.eye(2), K=K2, F=[1.0, 0.0], R=0.6, eta=0.1, b=b,
                               omega=omega, stops=Stops(mirror=True))


@pytest.fixture(scope="module")
def motion():
    """The symmetric 1-2 motion of the mirrored backlash (pattern UL)."""
    osc = mirrored()
    return multi_impact_orbit(osc, 1, 2, ic.simulate(osc, np.zeros(4), 0.0, 150.0))


class Generic:
    """A problem with only residual, jacobian and dparam: the core's generic path."""

    def __init__(self, problem):
        self.problem = problem

    def residual(self, u, lam):
        return self.problem.residual(u, lam)

    def jacobian(self, u, lam):
        return self.problem.jacobian(u, lam)

    def dparam(self, u, lam):
        return self.problem.dparam(u, lam)


def central(f, x, h):
    return (f(x + h) - f(x - h)) / (2.0 * h)


def test_linearize_is_the_residual_the_jacobian_and_a_finite_difference_in_omega(motion):
    problem = MultiImpactBranchProblem(motion.oscillator, 1, 2, "omega", pattern="UL")
    u = motion.unknowns + 1e-3  # off the motion: every term counts
    lam = 1.6
    residual, extended = problem.linearize(u, lam)
    assert extended.shape == (u.size, u.size + 1)
    # numpy's shooting of a flow built from scratch at that omega
    flow = Flow(motion.oscillator.replace(omega=lam))
    sh = shooting(flow, 1, 2, u, pattern="UL")
    np.testing.assert_allclose(residual, sh.residual, rtol=0, atol=1e-13)
    np.testing.assert_allclose(extended[:, :-1], sh.jacobian, rtol=0, atol=1e-12)
    fd = central(lambda om: shooting(Flow(motion.oscillator.replace(omega=om)), 1, 2, u,
                                     pattern="UL").residual, lam, 1e-6)
    np.testing.assert_allclose(extended[:, -1], fd, rtol=0, atol=1e-7)
    np.testing.assert_allclose(problem.dparam(u, lam), extended[:, -1], rtol=0, atol=0)


def test_the_flow_at_another_omega_is_the_flow_built_from_scratch(motion):
    problem = MultiImpactBranchProblem(motion.oscillator, 1, 2, "omega", pattern="UL")
    fresh = Flow(motion.oscillator.replace(omega=1.37))
    shared = problem.flow_at(1.37)
    assert shared.u is problem.flow_at(1.6).u  # one modal basis for every omega
    gamma, beta = forced_coefficients(fresh.w, fresh.a, fresh.f, 1.37)
    np.testing.assert_allclose(shared.gamma, gamma, rtol=1e-15, atol=0)
    np.testing.assert_allclose(shared.beta, beta, rtol=1e-15, atol=0)
    for mine, theirs in zip(shared.omega_arrays()[:2], fresh.omega_arrays()[:2], strict=True):
        np.testing.assert_allclose(mine, theirs, rtol=1e-13, atol=1e-15)
    assert shared.osc.omega == 1.37


def test_a_branch_in_omega_builds_no_flow_per_parameter_value(motion, monkeypatch):
    built = []
    original = Flow.__init__

    def counting(self, osc):
        built.append(osc.omega)
        original(self, osc)

    monkeypatch.setattr(Flow, "__init__", counting)
    ds = ic.multi_impact_continuation(motion, "omega", (1.5, 1.7), detect=())
    assert ds.sizes["point"] > 5
    assert len(built) <= 2  # the start's flow (and the orbit's); was one per Newton iterate


@pytest.mark.parametrize("symmetric", [False, True])
def test_compiled_step_is_the_core_corrector(motion, symmetric):
    if symmetric:
        problem = SymmetricBranchProblem(motion.oscillator, 1, 2, "omega", "UL")
        u0 = problem.half_unknowns(motion.unknowns)
    else:
        problem = MultiImpactBranchProblem(motion.oscillator, 1, 2, "omega", pattern="UL")
        u0 = motion.unknowns
    opts = ContinuationOptions(bounds=(1.0, 2.0), ds=0.02, newton_tol=1e-11)
    fast, slow = PalcStepper(problem, opts), PalcStepper(Generic(problem), opts)
    fast.init(u0, 1.6)
    slow.init(u0, 1.6)
    for _ in range(4):
        a, b = fast.step(), slow.step()
        np.testing.assert_allclose(a.state, b.state, rtol=0, atol=1e-10)
        np.testing.assert_allclose(a.tangent, b.tangent, rtol=0, atol=1e-8)
        assert np.max(np.abs(problem.residual(a.u, a.lam))) <= 1e-11
    result = problem.palc_step(fast.current.state, fast.current.tangent,
                               fast._metric_weights(), 1e-11, 10)
    assert result is not None and result.status == "converged"


def test_compiled_step_refuses_omega_below_zero(motion):
    problem = MultiImpactBranchProblem(motion.oscillator, 1, 2, "omega", pattern="UL")
    predicted = np.append(motion.unknowns, -0.5)
    tangent = np.append(np.zeros(motion.unknowns.size), 1.0)
    result = problem.palc_step(predicted, tangent, np.ones(tangent.size), 1e-11, 10)
    assert result.status == "refused" and "omega" in result.message
    stepper = PalcStepper(problem, ContinuationOptions(bounds=(-1.0, 2.0), ds=0.02))
    stepper.init(motion.unknowns, 1.6)
    with pytest.raises(NewtonConvergenceError, match=r"refused lam = -0\.5"):
        stepper._problem_step(predicted, stepper.current.tangent)


def test_branch_and_its_pitchforks_as_on_the_generic_path(motion, monkeypatch):
    def branch():
        return ic.multi_impact_continuation(motion, "omega", (0.9, 1.7), both_directions=True,
                                            ds_max=0.02)

    fast = branch()
    # the generic path: the same problems without their compiled hooks
    for cls in (MultiImpactBranchProblem, SymmetricBranchProblem):
        monkeypatch.setattr(cls, "palc_step", None)
        monkeypatch.setattr(cls, "linearize", None)
    slow = branch()
    labels = fast.special_label.values.tolist()
    assert labels == slow.special_label.values.tolist() and labels.count("BP") == 2
    np.testing.assert_allclose(fast.special_omega.values, slow.special_omega.values,
                               rtol=0, atol=1e-9)
    assert fast.sizes["point"] == slow.sizes["point"]
    np.testing.assert_allclose(fast.omega.values, slow.omega.values, rtol=0, atol=1e-9)


def test_moved_problem_is_the_problem_built_at_that_oscillator(motion):
    first = SymmetricBranchProblem(motion.oscillator, 1, 2, "omega", "UL")
    osc = motion.oscillator.replace(b=0.55)
    moved = first.moved(osc)
    fresh = SymmetricBranchProblem(osc, 1, 2, "omega", "UL")
    v = first.half_unknowns(motion.unknowns)
    for lam in (1.6, 1.61):
        np.testing.assert_allclose(moved.residual(v, lam), fresh.residual(v, lam), rtol=0,
                                   atol=1e-14)
        np.testing.assert_allclose(moved.linearize(v, lam)[1], fresh.linearize(v, lam)[1],
                                   rtol=0, atol=1e-12)
    assert moved.oscillator_at(1.6).b == 0.55 and first.oscillator_at(1.6).b == 0.5


def test_derivative_in_the_clearance_is_a_finite_difference(motion):
    problem = SymmetricBranchProblem(motion.oscillator, 1, 2, "omega", "UL")
    v = problem.half_unknowns(motion.unknowns) + 1e-3
    param = model_parameter(motion.oscillator, "b")
    exact = problem.derivative(v, 1.6, param)

    def at(b):
        return SymmetricBranchProblem(motion.oscillator.replace(b=b), 1, 2, "omega",
                                      "UL").residual(v, 1.6)

    np.testing.assert_allclose(exact, central(at, 0.5, 1e-6), rtol=0, atol=1e-7)


def test_bp_and_pd_tests_from_the_compiled_product(motion):
    curve = MultiImpactCurveProblem(motion.oscillator, 1, 2, "UL", "BP", ("omega", "b"),
                                    symmetric=True)
    base = curve.branch_problem(0.5)
    x = np.append(base.half_unknowns(motion.unknowns), 1.6)
    orbit = base.orbit(x[:-1], 1.6)
    H = base.half_map(x[:-1], 1.6)
    np.testing.assert_allclose(H, half_map(orbit), rtol=1e-12, atol=1e-12)
    assert curve.test(x, 0.5) == pytest.approx(curve.test_of(orbit), rel=1e-10, abs=1e-13)
    pd = MultiImpactCurveProblem(motion.oscillator, 1, 2, "UL", "PD", ("omega", "b"),
                                 symmetric=True)
    assert pd.test(x, 0.5) == pytest.approx(pd.test_of(orbit), rel=1e-10, abs=1e-13)
    G = base.full.jacobian_product(base.full_unknowns(x[:-1], 1.6), 1.6, 2)
    np.testing.assert_allclose(G, orbit.G, rtol=1e-12, atol=1e-12)


def test_near_resonance_still_warns_on_the_compiled_path():
    # an undamped mode at omega_1 = 1: the continuation approaches it
    osc = ic.ImpactOscillator(M=np.eye(2), K=K2, F=[1.0, 0.0], R=0.6, eta=0.0, b=0.8,
                              omega=0.8, stops=Stops(b_low=0.8))
    problem = MultiImpactBranchProblem(osc, 1, 2, "omega", pattern="UL")
    w = problem.flow_at(0.8).w
    target = float(w[np.argmin(np.abs(w - 0.8))])
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        problem.flow_at(target * (1.0 + 1e-9))
    with warnings.catch_warnings(record=True) as fresh:
        warnings.simplefilter("always")
        Flow(osc.replace(omega=target * (1.0 + 1e-9)))
    assert [type(c.message) for c in caught] == [type(c.message) for c in fresh]
    with pytest.raises(ic.ParameterError):
        problem.flow_at(target)


def test_each_compiled_entry_has_one_signature(motion):
    """The compiled corrector calls the kernel with the Python callers' types: nothing is
    compiled twice (a literal False made a second shooting_system, 1.9 s of cold compile)."""
    from impactcont.kernel import shooting as kernel

    ic.multi_impact_continuation(motion, "omega", (1.55, 1.65), detect=())
    problem = MultiImpactBranchProblem(motion.oscillator, 1, 2, "omega", pattern="UL")
    problem.linearize(motion.unknowns, 1.6)
    for name in ("branch_linearization", "forced_amplitudes", "palc_correct"):
        assert len(getattr(kernel, name).signatures) == 1, name  # called from Python
    for name in ("shooting_system", "frequency_column", "omega_partials"):
        # compiled code's callees (from the disk cache they are not registered at all)
        assert len(getattr(kernel, name).signatures) <= 1, name


@pytest.mark.parametrize("symmetric", [False, True])
def test_compiled_hyperplane_newton_is_the_core_loop(motion, symmetric):
    """``solve_on_hyperplane`` (special points, chords) through the problem's compiled
    Newton gives the point, the convergence and the iterations of its own numpy loop."""
    from impactcont.core.corrector import solve_on_hyperplane

    if symmetric:
        problem = SymmetricBranchProblem(motion.oscillator, 1, 2, "omega", "UL")
        u0 = problem.half_unknowns(motion.unknowns)
    else:
        problem = MultiImpactBranchProblem(motion.oscillator, 1, 2, "omega", pattern="UL")
        u0 = motion.unknowns
    rng = np.random.default_rng(3)
    for _ in range(3):
        target = np.append(u0 + 1e-4 * rng.standard_normal(u0.size), 1.6)
        normal = np.append(0.1 * rng.standard_normal(u0.size), 1.0)  # across the branch
        fast = solve_on_hyperplane(problem, target, normal, tol=1e-13)
        slow = solve_on_hyperplane(Generic(problem), target, normal, tol=1e-13)
        assert fast.converged and slow.converged
        assert fast.iterations == slow.iterations
        np.testing.assert_allclose(fast.x, slow.x, rtol=0, atol=1e-12)
        assert np.max(np.abs(problem.residual(fast.u, fast.lam))) <= 1e-12
    # one compiled call: no numpy iteration asks the problem's linearize
    calls = []
    original = problem.linearize
    problem.linearize = lambda *a: calls.append(a) or original(*a)
    assert solve_on_hyperplane(problem, target, normal, tol=1e-13).converged
    assert calls == []
    del problem.linearize
    # too few iterations: not converged, the last iterate, as the numpy loop
    fast = solve_on_hyperplane(problem, target, normal, tol=1e-13, max_iter=1)
    slow = solve_on_hyperplane(Generic(problem), target, normal, tol=1e-13, max_iter=1)
    assert not fast.converged and not slow.converged and fast.iterations == 1
    np.testing.assert_allclose(fast.x, slow.x, rtol=0, atol=1e-12)
    assert fast.last_step == pytest.approx(slow.last_step, rel=1e-6)
