"""The one codim-1 curve problem (:mod:`impactcont.problems.codim1`): a motion's branch
problem plus one test function, with the closed form (N-1) or shooting as its evaluator.

Shooting (:class:`~impactcont.problems.codim1.ShootingCurve`): at the special points the
closed-form N-1 branch located, the curve's residual (the branch system and the test
function) vanishes, the test function changes sign across the point, the exact blocks of
the Jacobian and the parameter column agree with central differences, and bad curves are
refused by name. :func:`~impactcont.problems.codim1.curve_problem` builds either evaluator,
and both evaluators' curve points are the same curve. Its one-call ``linearize`` gives
what ``residual``, ``jacobian`` and ``dparam`` give, kept until the next accepted point."""

from __future__ import annotations

import math

import numpy as np
import pytest

import impactcont as ic
from impactcont.errors import ParameterError
from impactcont.problems.closed_form_curve import CurveProblem
from impactcont.problems.codim1 import (
    MultiImpactCurveProblem,
    ShootingCurve,
    curve_problem,
    signed_smallest_singular_value,
)
from impactcont.problems.symmetric_branch import SymmetricBranchProblem

K = [[1.0, -1.0], [-1.0, 2.0]]


def _paper(b: float, omega: float = 1.0) -> ic.ImpactOscillator:
    return ic.ImpactOscillator(M=np.eye(2), K=K, F=[1.0, 0.0], R=0.6, b=b, omega=omega,
                               eta=0.1)


@pytest.fixture(scope="module")
def specials() -> dict[str, tuple[float, float, float]]:
    """``label -> (b, omega, delta)`` located on closed-form N-1 branches."""
    out = {}
    for b, bounds, detect in ((0.5, (1.1, 1.3), ("SN", "NS", "PD", "ZV")),
                              (0.6, (0.5, 3.0), ("GR",))):
        branch = ic.continuation(_paper(b), N=1, bounds=bounds, detect=detect)
        for label, omega, delta in zip(branch["special_label"].values,
                                       branch["special_omega"].values,
                                       branch["special_delta"].values, strict=True):
            out.setdefault(str(label), (b, float(omega), float(delta)))
    return out


def _x(b: float, omega: float, delta: float) -> np.ndarray:
    """``[u, omega]`` of the N-1 motion at (b, omega) with the phase nearest ``delta``."""
    orbits = ic.periodic_orbits(_paper(b, omega), 1)
    orbit = min(orbits, key=lambda o: abs(np.angle(np.exp(1j * (o.delta - delta)))))
    return np.concatenate([[orbit.delta], orbit.state[1:], [omega]])


def _problem(kind: str, b: float) -> MultiImpactCurveProblem:
    return MultiImpactCurveProblem(_paper(b), 1, 1, "U", kind, ("omega", "b"), symmetric=False)


@pytest.mark.filterwarnings("ignore::impactcont.LowImpactVelocityWarning")  # at ZV: h2 = 0
@pytest.mark.parametrize("kind", ["PD", "NS", "ZV", "GR"])
def test_the_residual_vanishes_at_the_special_point_and_the_test_changes_sign(
        specials, kind) -> None:
    b, omega, delta = specials[kind]
    problem = _problem(kind, b)
    x = _x(b, omega, delta)
    assert problem.size == x.size == 5
    residual = problem.residual(x, b)
    assert np.max(np.abs(residual[:-1])) < 1e-11  # the motion
    before, after = (problem.test(_x(b, omega + dw, delta), b) for dw in (-1e-4, 1e-4))
    assert before * after < 0
    assert abs(residual[-1]) < 1e-3 * min(abs(before), abs(after))


def test_the_fold_test_changes_sign_across_the_fold(specials) -> None:
    """SN: the branch folds in omega, so the motions on either side are the two roots at one
    omega on the side where they exist; along the branch the phase moves through the fold's."""
    b, omega, delta = specials["SN"]
    problem = _problem("SN", b)
    assert not ic.periodic_orbits(_paper(b, omega + 1e-4), 1)  # beyond the fold: none
    orbits = ic.periodic_orbits(_paper(b, omega - 1e-4), 1)
    near = sorted(orbits, key=lambda o: abs(np.angle(np.exp(1j * (o.delta - delta)))))[:2]
    values = [problem.test(np.concatenate([[o.delta], o.state[1:], [omega - 1e-4]]), b)
              for o in near]
    assert values[0] * values[1] < 0
    # sigma(dF/du) ~ sqrt(distance to the fold): 100 times smaller 1e4 times closer
    closer = _x(b, omega - 1e-8, delta)
    assert abs(problem.test(closer, b)) < 0.03 * min(map(abs, values))


def test_the_exact_blocks_agree_with_central_differences(specials) -> None:
    b, omega, delta = specials["PD"]
    problem = _problem("PD", b)
    x = _x(b, omega - 1e-3, delta)
    J = problem.jacobian(x, b)
    m = x.size - 1
    for i in range(x.size):
        e = np.zeros(x.size)
        e[i] = 1e-6
        fd = (problem.residual(x + e, b) - problem.residual(x - e, b)) / 2e-6
        np.testing.assert_allclose(J[:m, i], fd[:m], rtol=1e-5, atol=1e-7)
        np.testing.assert_allclose(J[m, i], fd[m], rtol=1e-3, atol=1e-6)  # the g row: FD
    fd = (problem.residual(x, b + 1e-6) - problem.residual(x, b - 1e-6)) / 2e-6
    np.testing.assert_allclose(problem.dparam(x, b), fd, rtol=1e-3, atol=1e-6)
    np.testing.assert_allclose(problem.dparam(x, b)[:m], fd[:m], rtol=1e-6, atol=1e-9)


def test_the_signed_smallest_singular_value() -> None:
    assert signed_smallest_singular_value(np.diag([2.0, -3.0])) == pytest.approx(-2.0)
    assert signed_smallest_singular_value(np.eye(3)) == pytest.approx(1.0)
    rotation = np.array([[0.0, -1.0], [1.0, 0.0]])
    assert signed_smallest_singular_value(0.5 * rotation) == pytest.approx(0.5)
    assert math.isnan(signed_smallest_singular_value(np.array([[np.inf, 0], [0, 1.0]])))


@pytest.mark.parametrize(("kind", "parameters", "symmetric", "match"), [
    ("XY", ("omega", "b"), False, r"kind must be one of .*; got 'XY'"),
    ("BP", ("omega", "b"), False, r"kind='BP' is a curve of symmetric motions"),
    ("PD", ("omega", "omega"), False, r"parameters must be two different parameters; got "
                                      r"'omega' twice"),
])
def test_bad_curves_are_refused(kind, parameters, symmetric, match) -> None:
    with pytest.raises(ParameterError, match=match):
        MultiImpactCurveProblem(_paper(0.5), 1, 1, "U", kind, parameters, symmetric=symmetric)


def test_the_kind_of_a_curve_is_its_label():
    """Issue 29, item 2: a kind given as a Label or its string is the Label member; what
    the kind needs (its test, the tests it watches) comes from a Label-keyed table."""
    from impactcont.vocabulary import Label

    osc = _paper(0.0, 1.75)
    for kind in ("SN", "PD", "NS", "GR", "ZV"):
        by_name = MultiImpactCurveProblem(osc, 1, 1, "U", kind, ("omega", "b"),
                                          symmetric=False)
        by_label = MultiImpactCurveProblem(osc, 1, 1, "U", Label(kind), ("omega", "b"),
                                           symmetric=False)
        assert by_name.kind is by_label.kind is Label(kind)
        assert Label(kind) not in by_name.codim2_tests
        assert all(isinstance(test, Label) for test in by_name.codim2_tests)
    with pytest.raises(ParameterError, match="kind must be one of"):
        MultiImpactCurveProblem(osc, 1, 1, "U", "XX", ("omega", "b"), symmetric=False)


def test_curve_problem_builds_the_closed_form_or_shooting():
    """One entry: ``p`` None is the closed form of an N-1 motion, ``p`` given shooting;
    the earlier name of the shooting problem is the same class."""
    osc = _paper(0.0, 1.75)
    assert isinstance(curve_problem("PD", osc, 1, ("omega", "b")), CurveProblem)
    shooting = curve_problem("PD", osc, 1, ("omega", "b"), p=1, pattern="U")
    assert isinstance(shooting, ShootingCurve) and MultiImpactCurveProblem is ShootingCurve
    with pytest.raises(ParameterError, match=r"kind must be one of \('SN', 'PD', 'NS', "
                                             r"'GR', 'ZV'\) for a curve of N-1|kind must be one"):
        curve_problem("BP", osc, 1)
    with pytest.raises(ParameterError, match=r"give p too; got pattern='U'"):
        curve_problem("PD", osc, 1, pattern="U")


@pytest.mark.filterwarnings("ignore::impactcont.LowImpactVelocityWarning")  # at ZV: h2 = 0
@pytest.mark.parametrize("kind", ["PD", "NS", "ZV"])
def test_both_evaluators_solve_the_same_curve(specials, kind):
    """One curve problem, two evaluators: from a start 1e-4 off the special point in omega, the
    closed form and shooting, each by its own Newton on the hyperplane ``b = b0`` (the same
    call, :meth:`on_hyperplane`), land on the same point of the curve (the closed form is
    the oracle; both solve to the Newton tolerance 1e-11)."""
    b, omega, delta = specials[kind]
    osc = _paper(b, omega)
    closed = curve_problem(kind, osc, 1, ("omega", "b"))
    shooting = curve_problem(kind, osc, 1, ("omega", "b"), p=1, pattern="U")
    off = _x(b, omega, delta)
    off[-1] += 1e-4  # the motion at omega, the unknown omega moved
    starts = (np.append(closed.initial_unknowns(omega + 1e-4, b, delta), b), np.append(off, b))
    found = []
    for problem, x0 in zip((closed, shooting), starts, strict=True):
        normal = np.zeros(x0.size)
        normal[-1] = 1.0
        x = problem.on_hyperplane(x0, normal)
        assert problem.plane(x)[1] == pytest.approx(b, abs=1e-14)
        found.append(problem.plane(x)[0])
    assert abs(found[0] - omega) < 1e-6  # the same special point
    assert abs(found[0] - found[1]) < 1e-8


# -- the kinds that bound motions with sticking phases (SE, RG, SO) --------------------------
def _riding_damper(omega: float) -> ic.ImpactOscillator:
    """The impact damper of studies/sticking_motions whose plastic ball rides each wall."""
    from impactcont.model.stops import Stops

    return ic.ImpactOscillator(M=np.diag([1.0, 0.2]), K=np.diag([1.0, 0.0]), F=[1.0, 0.0],
                               R=0.0, b=0.3, omega=omega, eta=0.3,
                               stops=Stops(mass=2, relative_to=1, mirror=True))


@pytest.fixture(scope="module")
def ride() -> ic.MultiImpactOrbit:
    """The riding motion (pattern 'ul') at omega = 2.3, settled on by the simulator from the
    held forced response."""
    osc = _riding_damper(2.3)
    x1 = 1.0 / (1.0 - 1.2 * 2.3**2 + 0.6j * 2.3)
    v1 = (2.3j * x1).real
    start = np.array([x1.real, x1.real + 0.3, v1, v1])
    return ic.multi_impact_orbit(osc, 1, 2, ic.simulate(osc, start, 0.0, 20.0))


def test_the_sticking_tests_follow_one_stick(ride) -> None:
    """SE: the followed stick time (an unknown: its row is e_k, equal to forward differences
    of the test to 1e-7, and 0 in p2); SO: the followed landing's pressing force, the
    motion's own to 1e-12; RG refused at a motion whose pressing forces have no interior
    minimum (each ride's smallest pressing force is its landing's at omega = 2.3)."""
    osc = ride.oscillator
    x = np.append(ride.unknowns, osc.omega)
    lam = osc.eta
    se = ShootingCurve(osc, 1, 2, ride.pattern, "SE", ("omega", "eta"), symmetric=False)
    assert se.test(x, lam) == pytest.approx(float(np.min(ride.stick_times)), rel=1e-12)
    row, dlam = se._test_gradient(x, lam)
    h = 1e-7
    for i in (0, 1, 2, 3, 5, x.size - 1):
        e = np.zeros(x.size)
        e[i] = h
        assert row[i] == pytest.approx((se.test(x + e, lam) - se.test(x, lam)) / h, abs=1e-7)
    assert dlam == 0.0 and se.codim2_tests == ("ZV", "GR", "SN", "PD", "NS")
    so = ShootingCurve(osc, 1, 2, ride.pattern, "SO", ("omega", "eta"), symmetric=False)
    assert so.test(x, lam) == pytest.approx(float(np.min(ride.landing_pressing)), abs=1e-12)
    rg = ShootingCurve(osc, 1, 2, ride.pattern, "RG", ("omega", "eta"), symmetric=False)
    with pytest.raises(ParameterError, match="no sticking phase of the motion at the start "
                                             "has an interior minimum"):
        rg.test(x, lam)
    # a PD curve of the motion watches the sticking kinds too
    pd = ShootingCurve(osc, 1, 2, ride.pattern, "PD", ("omega", "eta"), symmetric=False)
    assert set(pd.codim2_tests) >= {"SE", "RG", "SO"}


def test_the_rounding_noise_of_a_plain_test_leaves_the_newton_tolerance(ride) -> None:
    """``test_noise`` takes the line out: at the plastic ride (no chatter) the SE and SO
    tests' noise is rounding (below 1e-11, so the default tolerance 1e-10 stays); a test
    with a slope of 1e6 along the steps keeps only the rounding of its inputs (1e6 x a few
    ulps of x: about 5e-10), not its rise over the 8 steps (1e6 x 8 x 1e-14 x the direction:
    3.9e-8)."""
    osc = ride.oscillator
    x = np.append(ride.unknowns, osc.omega)
    for kind in ("SE", "SO"):
        curve = ShootingCurve(osc, 1, 2, ride.pattern, kind, ("omega", "eta"),
                              symmetric=False)
        assert curve.test_noise(x, osc.eta) < 1e-11
    steep = ShootingCurve(osc, 1, 2, ride.pattern, "SE", ("omega", "eta"), symmetric=False)
    plain = steep._test
    steep._test = lambda y, lam: plain(y, lam) + 1e6 * float(np.sum(y - x))
    assert steep.test_noise(x, osc.eta) < 1e-8


def test_other_multipliers_leave_out_the_curves_critical_ones() -> None:
    """SN drops the multiplier nearest +1, PD the one nearest -1, NS the complex pair
    nearest the unit circle (here 0.008 inside it, real ones 0.001 off); GR and ZV keep
    them all (their motions are bounded by a contact, not by
    a multiplier)."""
    mu = np.array([0.999, -1.001, 0.6 + 0.79j, 0.6 - 0.79j, 0.2])
    expect = {"SN": [-1.001, 0.6 + 0.79j, 0.6 - 0.79j, 0.2],
              "PD": [0.999, 0.6 + 0.79j, 0.6 - 0.79j, 0.2],
              "NS": [0.999, -1.001, 0.2], "GR": mu.tolist(), "ZV": mu.tolist()}
    for kind, rest in expect.items():
        curve = ShootingCurve(_paper(0.5), 1, 1, "U", kind, ("omega", "b"), symmetric=False)
        assert curve.other_multipliers(mu).tolist() == rest, kind


def test_physical_on_a_curve_leaves_out_the_curves_own_bound() -> None:
    """On a GR curve the motion's own clearance is zero to rounding: the impact velocity
    (ZV, the other bound it watches) decides. A ZV curve watches no other bound: the
    motion's word. A PD curve bounds no physical motions: the motion's word too."""
    from types import SimpleNamespace

    x = np.zeros(3)
    curves = {kind: ShootingCurve(_paper(0.5), 1, 1, "U", kind, ("omega", "b"),
                                  symmetric=False) for kind in ("GR", "ZV", "PD")}

    def orbit(physical: bool, velocity: float) -> SimpleNamespace:
        return SimpleNamespace(physical=physical, impact_velocity=velocity, gap_min=-1e-16)

    assert curves["GR"].physical_on_curve(x, orbit(False, 0.3))
    assert not curves["GR"].physical_on_curve(x, orbit(False, -0.1))
    assert not curves["ZV"].physical_on_curve(x, orbit(False, 1e-17))
    assert curves["ZV"].physical_on_curve(x, orbit(True, 1e-17))
    assert not curves["PD"].physical_on_curve(x, orbit(False, 0.3))


def test_sticking_kinds_need_sticking_phases(ride) -> None:
    """SE, RG, SO on a motion without sticking phases, and a motion with sticking phases
    followed by its half, are refused by name."""
    with pytest.raises(ParameterError, match=r"kind='SE' \(end of a sticking phase\) bounds "
                                             "motions with sticking phases"):
        ShootingCurve(_paper(0.5), 1, 1, "U", "SE", ("omega", "b"), symmetric=False)
    with pytest.raises(ParameterError, match="symmetric=True: a motion with sticking phases"):
        ShootingCurve(ride.oscillator, 1, 2, ride.pattern, "SE", ("omega", "eta"),
                      symmetric=True)


def test_a_sticky_curve_ends_where_its_motion_stops_being_physical(ride) -> None:
    """Between two accepted points whose flights' clearance (GR) or another bounding test
    changes sign the curve of a motion with sticking phases ends, saying which; a test that
    keeps its sign, or a NaN, does not end it; a curve of a plain motion never ends so."""
    from types import SimpleNamespace

    osc = ride.oscillator
    se = ShootingCurve(osc, 1, 2, ride.pattern, "SE", ("omega", "eta"), symmetric=False)
    x = np.append(np.append(ride.unknowns, osc.omega), osc.eta)
    inside = SimpleNamespace(impact_velocity=0.4, gap_min=0.6)
    assert se.physical_end(x, inside, x, SimpleNamespace(impact_velocity=0.3, gap_min=0.2)) \
        is None
    assert se.physical_end(x, inside, x, SimpleNamespace(impact_velocity=0.3,
                                                         gap_min=math.nan)) is None
    why = se.physical_end(x, inside, x, SimpleNamespace(impact_velocity=0.3, gap_min=-1e-9))
    assert why is not None and "the grazing test (GR) changes sign: 0.6 -> -1e-09" in why
    why = se.physical_end(x, inside, x, SimpleNamespace(impact_velocity=-0.1, gap_min=0.6))
    assert why is not None and "(ZV) changes sign" in why
    plain = ShootingCurve(_paper(0.5), 1, 1, "U", "PD", ("omega", "b"), symmetric=False)
    assert plain.physical_end(x, inside, x, SimpleNamespace(impact_velocity=0.3,
                                                            gap_min=-1.0)) is None


def test_an_rg_test_says_where_its_minimum_is_lost(ride) -> None:
    """The RG test follows one interior minimum: where there is none in the stick (at
    omega = 2.3 each ride's pressing force only falls) it is NaN and says why (the reason
    an RG curve that cannot go on gives), until the next accepted point."""
    osc = ride.oscillator
    x = np.append(ride.unknowns, osc.omega)
    rg = ShootingCurve(osc, 1, 2, ride.pattern, "RG", ("omega", "eta"), symmetric=False)
    rg.followed_stick, rg._minimum_time = 0, 1e3  # as if followed from elsewhere
    assert math.isnan(rg.test(x, osc.eta))
    assert "lies outside sticking phase 0" in rg.lost_minimum
    rg._minimum_time = 0.5 * float(ride.stick_times[0])
    assert math.isnan(rg.test(x + 1e-12, osc.eta))
    assert "reaches its landing or its release" in rg.lost_minimum
    rg.accept(x, osc.eta)
    assert rg.lost_minimum == ""


@pytest.mark.parametrize(("parameters", "stops"), [
    (("omega", "b"), ic.Stops(mirror=True)),   # b moves both stops: its column exact too
    (("omega", "R"), ic.Stops(mirror=True)),   # R by a forward difference
])
def test_the_pitchfork_row_agrees_with_central_differences(parameters, stops, monkeypatch):
    """The BP row ``d sigma(H + I)`` from the shot (exact in the half unknowns, omega and a
    parameter moving the stops) against central differences of the test (step 1e-6:
    within 1e-6 relative; R's forward-differenced column within 1e-5)."""
    osc = ic.ImpactOscillator(M=np.eye(2), K=[[1.0, -1.0], [-1.0, 2.0]], F=[1.0, 0.0],
                              R=0.6, b=0.5, omega=1.6, eta=0.1, stops=stops)
    motion = ic.multi_impact_orbit(osc, 1, 2, ic.simulate(osc, np.zeros(4), 0.0, 150.0))
    problem = curve_problem("BP", osc, 1, parameters, p=2, pattern=motion.pattern,
                            symmetric=True)
    lam = problem.params[1].value(osc)
    half = problem.branch_problem(lam)
    x = np.append(half.half_unknowns(motion.unknowns), 1.6)
    calls = []
    exact = SymmetricBranchProblem.half_map_derivative
    monkeypatch.setattr(SymmetricBranchProblem, "half_map_derivative",
                        lambda *args: calls.append(1) or exact(*args))
    row, column = problem.jacobian(x, lam)[-1], problem.dparam(x, lam)[-1]
    assert calls == [1]  # the row from the shot, once for both
    fd = np.empty(x.size + 1)
    for i in range(x.size + 1):
        y = np.append(x, lam)
        h = 1e-6 * max(1.0, abs(y[i]))
        up, down = y.copy(), y.copy()
        up[i] += h
        down[i] -= h
        fd[i] = (problem.test(up[:-1], up[-1]) - problem.test(down[:-1], down[-1])) / (2 * h)
    scale = np.abs(fd).max()
    exact = slice(0, x.size - 1)
    np.testing.assert_allclose(row[exact], fd[exact], rtol=1e-6, atol=1e-6 * scale)
    np.testing.assert_allclose(row[-1], fd[-2], rtol=1e-6, atol=1e-6 * scale)  # omega
    np.testing.assert_allclose(column, fd[-1], rtol=1e-6 if parameters[1] == "b" else 1e-5,
                               atol=1e-6 * scale)


def _mirrored_bp() -> tuple[ShootingCurve, np.ndarray, float]:
    """A BP curve problem in (omega, b) of the symmetric 1-2 motion with mirrored stops, and
    a point near it (the motion at b = 0.5, omega = 1.6)."""
    osc = ic.ImpactOscillator(M=np.eye(2), K=K, F=[1.0, 0.0], R=0.6, b=0.5, omega=1.6,
                              eta=0.1, stops=ic.Stops(mirror=True))
    motion = ic.multi_impact_orbit(osc, 1, 2, ic.simulate(osc, np.zeros(4), 0.0, 150.0))
    problem = curve_problem("BP", osc, 1, ("omega", "b"), p=2, pattern=motion.pattern,
                            symmetric=True)
    x = np.append(problem.branch_problem(0.5).half_unknowns(motion.unknowns), 1.6)
    return problem, x, 0.5


@pytest.mark.parametrize("kind", ["BP", "PD"])
def test_linearize_gives_the_residual_jacobian_and_dparam(specials, kind):
    """The same numbers as the three methods (the same evaluations, gathered); a second call
    at the point is the kept one until the next accepted point, which takes the test row
    afresh."""
    if kind == "BP":
        problem, x, lam = _mirrored_bp()
    else:
        b, omega, delta = specials["PD"]
        problem, x, lam = _problem("PD", b), _x(b, omega - 1e-3, delta), b
    residual, extended = problem.linearize(x, lam)
    np.testing.assert_array_equal(residual, problem.residual(x, lam))
    np.testing.assert_array_equal(extended[:, :-1], problem.jacobian(x, lam))
    np.testing.assert_array_equal(extended[:, -1], problem.dparam(x, lam))
    extended[:] = 0.0  # a copy: the kept one stays
    again = problem.linearize(x, lam)[1]
    np.testing.assert_array_equal(again[:, -1], problem.dparam(x, lam))
    problem.accept(x, lam)
    near = x * (1.0 + 1e-6)
    row = problem.linearize(near, lam)[1][-1]
    # this close (within _REUSE) the row of `near` is reused, until the next accepted point
    np.testing.assert_array_equal(problem.linearize(x, lam)[1][-1], row)
    problem.accept(near, lam)
    assert not np.array_equal(problem.linearize(x, lam)[1][-1], row)


def test_linearize_takes_no_row_where_the_residual_is_not_finite(monkeypatch):
    problem, x, lam = _mirrored_bp()
    monkeypatch.setattr(ShootingCurve, "_test", lambda self, x, lam: math.nan)
    monkeypatch.setattr(ShootingCurve, "_test_gradient", lambda *args: pytest.fail("a row"))
    residual, extended = problem.linearize(x, lam)
    assert math.isnan(residual[-1]) and np.isnan(extended).all()


def test_the_codim2_tests_are_the_branch_problems_own(ride) -> None:
    """Issue 29, 2: a shooting curve watches each other kind by the branch problem's own
    test of the motion (its ``motion_tests``), the fold by sigma(dF/du): the numbers the
    per-kind table gave (impact velocity, clearance, the pole-free products, the sticking
    tests), so a new kind needs no entry there."""
    from impactcont.problems.events import event_function
    from impactcont.problems.multi_impact_branch import (
        release_grazing_test,
        stick_end_test,
        sticking_onset_test,
    )
    from impactcont.vocabulary import Label

    osc = ride.oscillator
    x = np.append(np.append(ride.unknowns, osc.omega), osc.eta)
    pd = ShootingCurve(osc, 1, 2, ride.pattern, "PD", ("omega", "eta"), symmetric=False)
    orbit = pd.orbit(x[:-1], x[-1])
    former = {Label.ZV: orbit.impact_velocity, Label.GR: orbit.gap_min,
              Label.SN: pd.fold_test(x), Label.NS: event_function(Label.NS, orbit),
              Label.SE: stick_end_test(orbit), Label.RG: release_grazing_test(orbit),
              Label.SO: sticking_onset_test(orbit)}
    assert set(pd.codim2_tests) == set(former)
    for test in pd.codim2_tests:
        assert pd.codim2_test(test, x, orbit) == former[test]
    # the end of a flight has no curve (a singular point of the shooting), refused so
    with pytest.raises(ParameterError, match="has no curve yet: its points are singular"):
        ShootingCurve(osc, 1, 2, ride.pattern, "FT", ("omega", "eta"), symmetric=False)
