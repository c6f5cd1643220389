"""The exact modal transfer and state flow (eq. 5-10) against independent references.

A constant force F_static (issue 21): the exact flow against solve_ivp, and the identity
'a constant force on a system held by springs = the stops shifted by K^-1 F_static'.

Free masses (K positive semi-definite, issue 21): what holds each free mode, the exact
flow of zero-frequency modes against solve_ivp, and the refusals.
"""

from __future__ import annotations

import math

import mpmath
import numpy as np
import pytest
import scipy.linalg
from scipy.integrate import solve_ivp

import impactcont as ic
from impactcont import Flow, ImpactOscillator
from impactcont.errors import ParameterError
from impactcont.model.modal import free_transfer
from impactcont.model.stops import Stops

mpmath.mp.dps = 50


def _mp_transfer(w: float, a: float, t: float) -> np.ndarray:
    """50-digit exp([[0, 1], [-w^2, -2a]] t) by the eigenvalue (Sylvester) formula."""
    w, a, t = mpmath.mpf(w), mpmath.mpf(a), mpmath.mpf(t)
    A = mpmath.matrix([[0, 1], [-w * w, -2 * a]])
    disc = mpmath.sqrt(mpmath.mpc(a * a - w * w))
    if abs(disc) < mpmath.mpf(10) ** -40:  # critical: exp(-a t) (I + (A + a I) t)
        out = mpmath.exp(-a * t) * (mpmath.eye(2) + (A + a * mpmath.eye(2)) * t)
    else:
        r1, r2 = -a + disc, -a - disc
        out = (mpmath.exp(r1 * t) * (A - r2 * mpmath.eye(2))
               - mpmath.exp(r2 * t) * (A - r1 * mpmath.eye(2))) / (r1 - r2)
    return np.array([[float(mpmath.re(out[i, j])) for j in range(2)] for i in range(2)])


def _ours(w: float, a: float, t: float) -> np.ndarray:
    W11, W12, W21, W22 = free_transfer(np.array([w]), np.array([a]), np.array([t]))
    return np.array([[W11[0, 0], W12[0, 0]], [W21[0, 0], W22[0, 0]]])


REGIMES = {
    "undamped": 0.0,
    "underdamped": 0.2,
    "near-critical-below": 1.0 - 1e-9,
    "critical": 1.0,
    "near-critical-above": 1.0 + 1e-9,
    "overdamped": 3.0,
    "heavily-overdamped": 1e4,
}


TIMES = [0.0, 1e-7, 0.05, 0.9, 3.0, 25.0]


@pytest.mark.parametrize("xi", REGIMES.values(), ids=REGIMES.keys())
def test_free_transfer_against_expm(xi):
    w = 1.7
    a = xi * w
    for t in TIMES:
        ref = scipy.linalg.expm(np.array([[0.0, 1.0], [-w * w, -2.0 * a]]) * t)
        ours = _ours(w, a, t)
        scale = np.abs(ref).max()
        # expm itself is only accurate to about cond * eps for the stiff cases, and to 4e-14
        # here (scipy's algorithm, not ours: ours is within 2.5e-15 of 50 digits, line 68)
        tol = 1e-12 if xi < 10 else 1e-9
        assert np.abs(ours - ref).max() <= tol * max(scale, 1.0), (xi, t, ours, ref)


@pytest.mark.parametrize("xi", REGIMES.values(), ids=REGIMES.keys())
def test_free_transfer_against_50_digits(xi):
    w = 1.7
    for t in TIMES[1:]:
        ref = _mp_transfer(w, xi * w, t)
        ours = _ours(w, xi * w, t)
        # entrywise relative error: no cancellation near xi = 1 or for heavy damping
        err = np.abs(ours - ref) / np.maximum(np.abs(ref), 1e-300)
        assert err.max() < 5e-13, (xi, t, ours, ref)


def test_free_transfer_no_overflow_for_huge_damping_times():
    W = free_transfer(np.array([1.0, 1.0]), np.array([1e6, 0.5]), np.array([1e4]))
    for blk in W:
        assert np.all(np.isfinite(blk))
    # slow over-damped decay rate is w^2 / (a + k) ~ 5e-7: W11 ~ exp(-5e-3)
    assert W[0][0, 0] == pytest.approx(np.exp(-1e4 / (2e6)), rel=1e-6)


def _augmented_flow(osc: ImpactOscillator, t: float, X0: np.ndarray, delta: float) -> np.ndarray:
    """Reference: expm of the first-order system with the forcing as two extra states."""
    n, om = osc.n, osc.omega
    Minv = np.linalg.inv(osc.M)
    A = np.zeros((2 * n + 2, 2 * n + 2))
    A[:n, n:2 * n] = np.eye(n)
    A[n:2 * n, :n] = -Minv @ osc.K
    A[n:2 * n, n:2 * n] = -Minv @ osc.C
    A[n:2 * n, 2 * n] = Minv @ osc.F
    A[2 * n, 2 * n + 1] = -om
    A[2 * n + 1, 2 * n] = om
    Y0 = np.concatenate([X0, [np.cos(delta), np.sin(delta)]])
    return (scipy.linalg.expm(A * t) @ Y0)[: 2 * n]


@pytest.mark.parametrize("n", [1, 2, 3, 8])
@pytest.mark.parametrize("damping", [{"eta": 0.0}, {"eta": 0.1}, {"eta": 1.5},
                                     {"alpha": 0.2, "beta": 0.01}])
def test_state_flow_against_expm(n, damping, make_chain):
    osc = make_chain(n, omega=1.3, **damping)
    flow = Flow(osc)
    rng = np.random.default_rng(7)
    X0 = rng.normal(size=2 * n)
    delta = 0.4
    ts = np.array([0.0, 0.3, 2.0, 7.5])
    states = flow.state(ts, X0, delta)
    for t, X in zip(ts, states, strict=True):
        ref = _augmented_flow(osc, t, X0, delta)
        np.testing.assert_allclose(X, ref, rtol=0, atol=1e-11 * max(1.0, np.abs(ref).max()))
    # the matrix form of eq. (9) gives the same state
    t = 2.0
    X9 = flow.transition_matrix(t) @ X0 + flow.forcing_matrix(t) @ [np.cos(delta), np.sin(delta)]
    np.testing.assert_allclose(X9, states[2], atol=1e-12)


def test_state_derivative_is_the_vector_field(paper):
    flow = Flow(paper)
    X0 = np.array([0.2, -0.1, 0.5, 0.3])
    delta = 1.1
    ts = np.linspace(0.1, 6.0, 7)
    dX = flow.state_derivative(ts, X0, delta)
    X = flow.state(ts, X0, delta)
    Minv = np.linalg.inv(paper.M)
    for t, x, dx in zip(ts, X, dX, strict=True):
        force = paper.F * np.cos(paper.omega * t + delta)
        acc = Minv @ (force - paper.C @ x[2:] - paper.K @ x[:2])
        np.testing.assert_allclose(dx, np.concatenate([x[2:], acc]), atol=1e-13)
    h = 1e-5
    fd = (flow.state(ts + h, X0, delta) - flow.state(ts - h, X0, delta)) / (2 * h)
    np.testing.assert_allclose(dX, fd, atol=1e-9)


def test_mass1_motion_matches_full_state(paper):
    flow = Flow(paper)
    X0 = np.array([0.6, 0.1, -0.5, 0.3])
    ts = np.linspace(0.0, 9.0, 13)
    x1, v1, a1 = flow.mass1(X0, 0.7)(ts)
    X = flow.state(ts, X0, 0.7)
    dX = flow.state_derivative(ts, X0, 0.7)
    np.testing.assert_allclose(x1, X[:, 0], atol=1e-14)
    np.testing.assert_allclose(v1, X[:, 2], atol=1e-14)
    np.testing.assert_allclose(a1, dX[:, 2], atol=1e-13)


@pytest.mark.parametrize("damping", [{"eta": 0.1}, {"alpha": 0.05, "beta": 0.02},
                                     {"C": [[0.0, 0.0], [0.0, 0.2]]}])
@pytest.mark.parametrize("complex_forcing", [False, True])
def test_omega_partial_matches_differences(damping, complex_forcing):
    """``dX(t)/d omega`` of the modal and of the first-order flow against central differences
    of the exact flow (state, start state and start phase fixed)."""
    F = [1.0, 0.3j] if complex_forcing else [1.0, 0.3]
    osc = ImpactOscillator(M=np.eye(2), K=[[1.0, -1.0], [-1.0, 2.0]], F=F, R=0.6, b=0.5,
                           omega=1.3, **damping)
    X0 = np.array([0.5, -0.2, -0.3, 0.4])
    t, theta, h = 2.7, 0.4, 1e-5
    exact = Flow(osc).omega_partial(t, X0, theta)
    up = Flow(osc.replace(omega=1.3 + h)).state(np.array([t]), X0, theta)[0]
    down = Flow(osc.replace(omega=1.3 - h)).state(np.array([t]), X0, theta)[0]
    assert np.max(np.abs(exact - (up - down) / (2 * h))) < 1e-8 * max(1.0, np.max(np.abs(exact)))


@pytest.mark.parametrize("damping", [{"eta": 0.1}, {"C": [[0.1, 0.0], [0.0, 0.3]]}])
@pytest.mark.parametrize("index, sign", [(0, 1.0), (1, 1.0), (1, -1.0), (0, -1.0)])
def test_motion_of_any_mass_matches_the_state(damping, index, sign):
    """``flow.motion(X0, delta, index, sign)`` is ``sign`` times mass ``index + 1``'s
    displacement, velocity and acceleration of the full state, modal and first-order."""
    osc = ImpactOscillator(M=np.eye(2), K=[[1.0, -1.0], [-1.0, 2.0]], F=[1.0, 0.4], R=0.6,
                           b=0.5, omega=1.3, **damping)
    flow = Flow(osc)
    X0 = np.array([0.5, -0.2, -0.3, 0.4])
    t = np.linspace(0.0, 4.0, 9)
    x, v, a, _ = flow.motion(X0, 0.7, index, sign).derivatives(t)
    X = flow.state(t, X0, 0.7)
    dX = flow.state_derivative(t, X0, 0.7)
    n = osc.n
    assert np.allclose(x, sign * X[:, index], rtol=0, atol=1e-13)
    assert np.allclose(v, sign * X[:, n + index], rtol=0, atol=1e-13)
    assert np.allclose(a, sign * dX[:, n + index], rtol=0, atol=1e-12)


def test_time_scales_follow_the_stop_coordinate():
    """A clearance x2 - x1 sees the modes of both masses: with mass 1 on its own stiff
    spring (w = 50) and masses 2, 3 a slow chain, the pair's scale is the fast mode's
    (mass 2's row alone sees the slow ones); the modal flow (Rayleigh damping) and the
    first-order flow (the same C as a matrix) agree; e_j is mass j's row."""
    K = np.array([[2500.0, 0.0, 0.0], [0.0, 2.0, -1.0], [0.0, -1.0, 2.0]])
    base = {"M": np.eye(3), "K": K, "F": [0.0, 1.0, 0.0], "R": 0.7, "b": 1.0, "omega": 1.0,
            "stops": Stops(mass=2, relative_to=1)}
    modal = Flow(ImpactOscillator(alpha=0.002, beta=0.001, **base))
    general = Flow(ImpactOscillator(C=0.002 * np.eye(3) + 0.001 * K, **base))
    assert type(general).__name__ == "GeneralFlow"
    pair = [-1.0, 1.0, 0.0]
    fast = (math.sqrt(2500.0 - 1.251**2), 1.251)  # w_d and a of mass 1's mode
    for flow in (modal, general):
        np.testing.assert_allclose(flow.time_scales(normal=pair), fast, rtol=1e-9)
        assert flow.time_scales(normal=pair) == tuple(
            max(a, b) for a, b in zip(flow.time_scales(0), flow.time_scales(1), strict=True))
        for j in range(3):
            e = np.eye(3)[j]
            assert flow.time_scales(normal=e) == flow.time_scales(j) == flow.time_scales(row=j)
        assert flow.time_scales() == flow.time_scales(0)
        with pytest.raises(TypeError, match="not both"):
            flow.time_scales(1, normal=pair)
        with pytest.raises(ParameterError, match="normal must be"):
            flow.time_scales(normal=[1.0, -1.0])
        with pytest.raises(ParameterError, match="normal must be"):
            flow.time_scales(normal=[0.0, 0.0, 0.0])
        with pytest.raises(ParameterError, match=r"row must be in 0 \.\. 2"):
            flow.time_scales(3)
        with pytest.raises(TypeError, match="row must be an integer"):
            flow.time_scales(True)


def test_flow_of_shares_one_flow_per_oscillator_and_lets_both_go():
    # a weak-key table of flows kept every oscillator alive (its flow holds it)
    import gc
    import weakref

    from impactcont.orbit.flow import flow_of

    osc = ImpactOscillator(M=np.eye(2), K=[[1.0, -1.0], [-1.0, 2.0]], F=[1.0, 0.0],
                           R=0.6, b=0.6, omega=1.0, eta=0.1)
    flow = flow_of(osc)
    assert flow_of(osc) is flow
    other = osc.replace(omega=1.3)
    assert flow_of(other) is not flow and flow_of(other).omega == 1.3
    gone = weakref.ref(osc), weakref.ref(flow)
    del osc, flow
    gc.collect()
    assert gone[0]() is None and gone[1]() is None


M = np.diag([1.0, 0.5])


K = np.array([[1.0, -1.0], [-1.0, 2.0]])


FS = np.array([-0.3, 0.2])


def _ivp(osc, X0, delta, t_end):
    """Independent witness: M x'' + C x' + K x = Re(F e^{i(omega t + delta)}) + F_static."""
    n = osc.n
    Minv = np.linalg.inv(osc.M)
    F = np.asarray(osc.F, dtype=complex)

    def rhs(t, X):
        force = (F * np.exp(1j * (osc.omega * t + delta))).real + osc.F_static
        acc = Minv @ (force - osc.C @ X[n:] - osc.K @ X[:n])
        return np.concatenate([X[n:], acc])

    sol = solve_ivp(rhs, (0.0, t_end), X0, method="DOP853", rtol=1e-10, atol=1e-12,
                    dense_output=True)
    return sol.sol


@pytest.mark.parametrize("damping", [{"eta": 0.05}, {"C": [[0.3, -0.1], [-0.1, 0.1]]},
                                     {"eta": 0.05, "F": [1.0, 0.4j]}])
def test_flow_with_a_constant_force_matches_solve_ivp(damping):
    params = {"F": [1.0, 0.0], **damping}
    osc = ic.ImpactOscillator(M=M, K=K, R=0.5, b=1.0, omega=1.3, F_static=FS, **params)
    flow = Flow(osc)
    X0 = np.array([0.1, -0.2, 0.3, 0.05])
    t = np.linspace(0.0, 12.0, 7)
    ref = _ivp(osc, X0, 0.4, 12.0)(t).T
    np.testing.assert_allclose(flow.state(t, X0, 0.4), ref, rtol=0, atol=1e-8)
    # matrices(static=True) and state_derivative agree with the same flow
    Phi, E, S = flow.matrices(12.0, static=True)
    np.testing.assert_allclose(Phi @ X0 + E @ [np.cos(0.4), np.sin(0.4)] + S, ref[-1],
                               rtol=0, atol=1e-8)
    h = 1e-6
    fd = (flow.state(5.0 + h, X0, 0.4) - flow.state(5.0 - h, X0, 0.4)) / (2 * h)
    np.testing.assert_allclose(flow.state_derivative(5.0, X0, 0.4), fd, rtol=0, atol=1e-7)


def test_a_constant_force_equals_shifting_the_stops():
    """K positive definite: x = x_s + K^-1 F_static, so the system with F_static and stops
    at b, -b_low is the system without it and stops at b - c, -b_low - c, c = (K^-1 F_s)_j;
    two simulations, one identity."""
    stops = Stops(mass=1, b_low=0.4, R_low=0.7)
    shift = np.linalg.solve(K, FS)
    c = shift[0]
    with_force = ic.ImpactOscillator(M=M, K=K, F=[1.0, 0.0], R=0.6, b=0.5, omega=1.1,
                                     eta=0.05, stops=stops, F_static=FS)
    shifted = ic.ImpactOscillator(M=M, K=K, F=[1.0, 0.0], R=0.6, b=0.5 - c, omega=1.1,
                                  eta=0.05, stops=Stops(mass=1, b_low=0.4 + c, R_low=0.7))
    X0 = np.array([0.0, 0.0, 0.0, 0.0])
    a = ic.simulate(with_force, X0, 0.0, 30.0)
    b = ic.simulate(shifted, X0 - np.concatenate([shift, [0, 0]]), 0.0, 30.0)
    assert a.impact_times.size > 10 and a.impact_stops == b.impact_stops
    np.testing.assert_allclose(a.impact_times, b.impact_times, rtol=1e-9, atol=1e-9)
    np.testing.assert_allclose(a.impact_states[:, :2] - shift, b.impact_states[:, :2],
                               rtol=0, atol=1e-8)
    np.testing.assert_allclose(a.impact_states[:, 2:], b.impact_states[:, 2:], rtol=0,
                               atol=1e-8)


def test_static_force_is_validated_and_serialised():
    base = {"M": M, "K": K, "F": [1.0, 0.0], "R": 0.5, "b": 1.0, "omega": 1.3, "eta": 0.05}
    with pytest.raises(ParameterError, match=r"F_static must have shape \(2,\)"):
        ic.ImpactOscillator(**base, F_static=[1.0, 2.0, 3.0])
    with pytest.raises(ParameterError, match="F_static must be finite"):
        ic.ImpactOscillator(**base, F_static=[np.nan, 0.0])
    with pytest.raises(TypeError, match="F_static must be"):
        ic.ImpactOscillator(**base, F_static=[1j, 0.0])
    osc = ic.ImpactOscillator(**base, F_static=FS)
    assert "F_static=[-0.3, 0.2]" in repr(osc)
    again = ic.ImpactOscillator.from_json(osc.to_json())
    np.testing.assert_array_equal(again.F_static, FS)
    assert "F_static" not in ic.ImpactOscillator(**base).to_dict()
    np.testing.assert_array_equal(osc.replace(omega=2.0).F_static, FS)
    np.testing.assert_array_equal(osc.replace(F_static=[0.0, 1.0]).F_static, [0.0, 1.0])


def test_closed_form_paths_refuse_a_constant_force():
    osc = ic.ImpactOscillator(M=M, K=K, F=[1.0, 0.0], R=0.5, b=1.0, omega=1.3, eta=0.05,
                              F_static=FS)
    assert not osc.paper_form
    with pytest.raises(ParameterError, match=r"constant force.*multi_impact_orbit"):
        ic.periodic_orbits(osc, 1)


# a primary mass on a spring to the ground and a free ball (an impact damper)
M2 = np.diag([1.0, 0.2])


K2 = np.diag([1.0, 0.0])


PAIR = Stops(mass=2, relative_to=1, mirror=True)


def test_chain_with_a_zero_spring_has_a_free_mode_with_zero_frequency():
    osc = ic.ImpactOscillator.chain(masses=[1.0, 0.5], springs=[2.0, 0.0], F=[1.0, 0.0],
                                    R=0.5, b=0.1, omega=1.3, eta=0.05)
    assert osc.free_modes.shape == (2, 1)
    np.testing.assert_allclose(osc.free_modes[:, 0] / osc.free_modes[0, 0], [1.0, 1.0],
                               rtol=1e-12)
    modes = osc.modes
    assert modes.free.tolist() == [True, False]
    assert modes.natural_frequencies[0] == 0.0  # clamped, not rounding of either sign
    np.testing.assert_allclose(modes.natural_frequencies[1] ** 2, 2.0 / 1.0 + 2.0 / 0.5,
                               rtol=1e-12)


@pytest.mark.parametrize("damping", [{"eta": 0.05}, {"alpha": 0.3, "beta": 0.02},
                                     {"C": [[0.1, 0.0], [0.0, 0.05]]},
                                     {"C": [[0.1, 0.0], [0.0, 0.0]]}])
@pytest.mark.parametrize("static", [None, [0.1, -0.05]])
def test_free_mode_flow_matches_solve_ivp(damping, static):
    """Undamped free mode (eta: g t^2/2), damped by alpha (drift g t/(2a)), by a damping
    matrix (the first-order basis with an exact zero eigenvalue) and left undamped by a
    damping matrix (the first-order basis's Jordan chain, its polynomial part)."""
    osc = ic.ImpactOscillator(M=M2, K=K2, F=[1.0, 0.3], R=0.5, b=0.3, omega=1.3,
                              stops=PAIR, F_static=static, **damping)
    flow = Flow(osc)
    X0 = np.array([0.1, -0.2, 0.3, 0.05])
    t = np.linspace(0.0, 15.0, 6)
    ref = _ivp(osc, X0, 0.7, 15.0)(t).T
    np.testing.assert_allclose(flow.state(t, X0, 0.7), ref, rtol=0, atol=1e-8)
    motion = flow.motion(X0, 0.7, 1, -1.0, osc.stops.normal(2))  # -(x2 - x1)
    s, sv, sa = motion(t)
    np.testing.assert_allclose(s, -(ref[:, 1] - ref[:, 0]), rtol=0, atol=1e-8)
    np.testing.assert_allclose(sv, -(ref[:, 3] - ref[:, 2]), rtol=0, atol=1e-8)
    acc = flow.state_derivative(t, X0, 0.7)[:, 2:]
    np.testing.assert_allclose(sa, -(acc[:, 1] - acc[:, 0]), rtol=0, atol=1e-12)


def test_a_free_mode_nothing_holds_is_refused():
    with pytest.raises(ParameterError, match=r"free mode u = \[0.0, 1.0\] is held by nothing"):
        ic.ImpactOscillator(M=M2, K=K2, F=[1.0, 0.0], R=0.5, b=0.1, omega=1.3, eta=0.05)
    # two free masses, one stop coordinate: the common motion of both is free
    with pytest.raises(ParameterError, match="2 free"):
        ic.ImpactOscillator(M=np.eye(2), K=np.zeros((2, 2)), F=[1.0, 0.0], R=0.5, b=0.1,
                            omega=1.3, stops=PAIR)
    with pytest.raises(ParameterError, match="K must be positive semi-definite"):
        ic.ImpactOscillator(M=M2, K=[[1.0, 0.0], [0.0, -1e-3]], F=[1.0, 0.0], R=0.5, b=0.1,
                            omega=1.3, stops=PAIR)


@pytest.mark.parametrize("static", [None, [0.0, -0.05]])
def test_undamped_free_mode_first_order_flow_equals_the_modal_flow(static):
    """A damping matrix that leaves the free mode undamped (was refused: 'unless C damps
    every free mode'): the first-order flow with its polynomial part (the Jordan chain of
    the free mode, a constant force's g t^2 / 2 on it) is the modal flow of the same
    proportional C (beta K, given as eta on the modal path) to rounding: state, its time
    derivative, the matrices of eq. (9) with the constant force and a stop coordinate."""
    base = dict(M=M2, K=K2, F=[1.0, 0.3], R=0.5, b=0.3, omega=1.3, stops=PAIR,
                F_static=static)
    modal = ic.ImpactOscillator(**base, alpha=0.0, beta=0.04)
    general = ic.ImpactOscillator(**base, C=modal.C)
    fm, fg = Flow(modal), Flow(general)
    assert type(fg).__name__ == "GeneralFlow" and fm.free.tolist() == [True, False]
    X0 = np.array([0.1, -0.2, 0.3, 0.05])
    t = np.array([0.0, 0.4, 3.0, 40.0])  # long enough for the drift to dominate
    ref = fm.state(t, X0, 0.7)
    tol = 1e-13 * np.abs(ref).max()
    np.testing.assert_allclose(fg.state(t, X0, 0.7), ref, rtol=0, atol=tol)
    np.testing.assert_allclose(fg.state_derivative(t, X0, 0.7), fm.state_derivative(t, X0, 0.7),
                               rtol=0, atol=tol)
    for a, b in zip(fg.matrices(40.0, static=True), fm.matrices(40.0, static=True), strict=True):
        np.testing.assert_allclose(a, b, rtol=0, atol=1e-13 * max(1.0, np.abs(b).max()))
    s = fg.motion(X0, 0.7, 1, -1.0, general.stops.normal(2)).derivatives(t)
    r = fm.motion(X0, 0.7, 1, -1.0, modal.stops.normal(2)).derivatives(t)
    for a, b in zip(s, r, strict=True):
        np.testing.assert_allclose(a, b, rtol=0, atol=tol)
    # the time derivative and the omega partial are derivatives (central differences)
    h = 1e-5
    fd = (fg.state(t + h, X0, 0.7) - fg.state(t - h, X0, 0.7)) / (2 * h)
    np.testing.assert_allclose(fg.state_derivative(t, X0, 0.7), fd, rtol=0,
                               atol=1e-8 * np.abs(ref).max())
    shifted = [Flow(general.replace(omega=general.omega + d)) for d in (h, -h)]
    fd = (shifted[0].state(3.0, X0, 0.7)[0] - shifted[1].state(3.0, X0, 0.7)[0]) / (2 * h)
    np.testing.assert_allclose(fg.omega_partial(3.0, X0, 0.7), fd, rtol=0, atol=1e-7)


def test_closed_form_paths_refuse_free_masses():
    osc = ic.ImpactOscillator.chain(masses=[1.0, 0.5], springs=[2.0, 0.0], F=[1.0, 0.0],
                                    R=0.5, b=0.1, omega=1.3, eta=0.05)
    with pytest.raises(ParameterError, match=r"free mode.*multi_impact_orbit"):
        ic.periodic_orbits(osc, 1)


def test_a_free_ball_between_walls_simulates_against_solve_ivp():
    """An impact damper's ball alone would be refused; here a primary on a spring carries a
    ball in a clearance: each simulated flight against solve_ivp of the equations."""
    osc = ic.ImpactOscillator(M=M2, K=K2, F=[1.0, 0.0], R=0.6, b=0.3, omega=0.9, eta=0.02,
                              stops=PAIR, F_static=[0.0, -0.05])
    res = ic.simulate(osc, np.zeros(4), 0.0, 6.0)
    assert res.impact_times.size >= 4  # (the ball comes to rest on the lower stop later)
    flow = Flow(osc)
    start, phase, t0 = np.zeros(4), 0.0, 0.0
    for k in range(4):
        tau = res.impact_times[k] - t0
        X_minus = _ivp(osc, start, phase, tau)(tau)
        s = X_minus[1] - X_minus[0]
        level = osc.b if res.impact_stops[k] == "U" else -osc.stops.b_low
        assert abs(s - level) < 1e-8
        np.testing.assert_allclose(X_minus[:2], res.impact_states[k, :2], rtol=0, atol=1e-8)
        np.testing.assert_allclose(flow.state(tau, start, phase)[0], X_minus, rtol=0,
                                   atol=1e-8)
        start, phase, t0 = res.impact_states[k], res.impact_phases[k], res.impact_times[k]


def _roundtrips(obj):
    """`obj` pickled and unpickled, and deep-copied (the process pools' and dask's way)."""
    import copy
    import pickle

    return pickle.loads(pickle.dumps(obj)), copy.deepcopy(obj)


@pytest.mark.parametrize("general", [False, True])
def test_an_oscillator_and_its_flow_pickle_after_the_shooting_path_used_them(general):
    # issue 28: Flow.__new__ needed osc, so an oscillator whose flow flow_of had cached
    # (every N-p solve) could be neither pickled nor deep-copied
    from impactcont.orbit.flow import GeneralFlow, flow_of

    params = {"C": [[0.3, -0.1], [-0.1, 0.1]]} if general else {"eta": 0.1}
    osc = ImpactOscillator(M=M, K=K, F=[1.0, 0.0], R=0.6, b=0.6, omega=1.3,
                           F_static=FS, **params)
    flow = flow_of(osc)
    flow.shooting_arrays(), flow.static_arrays(), flow.omega_arrays()
    flow.matrices(0.7)
    X0, t = np.array([0.1, -0.2, 0.3, 0.05]), np.array([0.0, 0.4, 2.5])
    for copied in _roundtrips(osc):
        again = flow_of(copied)
        assert type(again) is (GeneralFlow if general else Flow)
        assert again.osc is copied and again is not flow
        np.testing.assert_array_equal(again.state(t, X0, 0.3), flow.state(t, X0, 0.3))
        for mine, theirs in zip(again.shooting_arrays(), flow.shooting_arrays(), strict=True):
            np.testing.assert_array_equal(mine, theirs)
    for copied in _roundtrips(flow):
        np.testing.assert_array_equal(copied.matrices(0.7)[0], flow.matrices(0.7)[0])


def test_n1_and_np_motions_pickle_after_use_and_compute_the_same_numbers(paper):
    # issue 28: every N-p task of a process pool or dask pickles its motion and oscillator
    n1 = ic.periodic_orbits(paper, 1)[0]
    mp = ic.multi_impact_orbit(paper, 1, 1, n1)  # the shooting path: paper's flow is cached
    assert "_flow" in paper.__dict__
    for orbit in (n1, mp):
        for copied in _roundtrips(orbit):
            assert type(copied) is type(orbit)
            resolved = ic.multi_impact_orbit(copied.oscillator, 1, 1, copied)
            np.testing.assert_allclose(resolved.unknowns, mp.unknowns, rtol=0, atol=1e-12)
            np.testing.assert_allclose(resolved.multipliers, mp.multipliers, rtol=0,
                                       atol=1e-12)
            assert resolved.physical == mp.physical and resolved.stable == mp.stable
    n1_copy, mp_copy = _roundtrips(n1)[0], _roundtrips(mp)[0]
    assert n1_copy.delta == n1.delta and n1_copy.physical == n1.physical
    np.testing.assert_array_equal(n1_copy.G, n1.G)
    np.testing.assert_array_equal(mp_copy.states, mp.states)
    np.testing.assert_array_equal(mp_copy.G, mp.G)


def test_an_np_motion_of_two_stops_pickles_and_is_solved_again_the_same():
    # a 1-2 motion of a backlash (mirror stops): what a process pool or dask sends per task
    osc = ImpactOscillator(M=np.eye(2), K=K, F=[1.0, 0.0], R=0.6, b=0.5, omega=1.6,
                           eta=0.1, stops=Stops(mirror=True))
    orbit = ic.multi_impact_orbit(osc, 1, 2, ic.simulate(osc, np.zeros(4), 0.0, 150.0))
    assert orbit.p == 2
    for copied in _roundtrips(orbit):
        np.testing.assert_array_equal(copied.states, orbit.states)
        assert copied.pattern == orbit.pattern
        again = ic.multi_impact_orbit(copied.oscillator, 1, 2, copied)
        np.testing.assert_allclose(again.unknowns, orbit.unknowns, rtol=0, atol=1e-12)
        np.testing.assert_allclose(again.multipliers, orbit.multipliers, rtol=0, atol=1e-12)
        assert (again.stable, again.physical) == (orbit.stable, orbit.physical)
