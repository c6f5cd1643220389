"""A general damping matrix C: the first-order complex-mode path against its witnesses.

- proportional C given as a matrix: the first-order path against the modal kernel
  (orbit state, c/s, impact velocity, G, multipliers) to 1e-12;
- non-proportional C: the flow and the periodic motion against ``scipy.linalg.expm`` of
  the first-order system augmented with the forcing oscillator, G assembled from the
  expm pieces (eq. 22-25), and a 50-digit mpmath reference of the fixed point;
- the event-driven simulator (impacts repeat over 50 periods) and finite differences
  of its impact map (G);
- branches: special points against a recomputation of G by the expm reference;
- the refusals: bad C, C with eta/alpha/beta, continuation in the damping parameters,
  a defective (critically damped) decomposition.

Codim-1 curves on the first-order path (issue 14): a damping matrix C or a complex F.

A proportional C given as a matrix must give the modal path's curves; a damper on one
mass (no modal decoupling) and per-mass forcing phases are checked against the special
points of one-parameter branches and against the defining property of each curve.
"""

from __future__ import annotations

import math

import mpmath
import numpy as np
import pytest
import scipy.linalg

import impactcont as ic
from impactcont.analysis.curves import curve, curve_crossings
from impactcont.errors import IllConditionedWarning, ParameterError
from impactcont.orbit import general
from impactcont.orbit.batched import batched_orbits
from impactcont.orbit.dense import impact_map_jacobian
from impactcont.orbit.flow import Flow, GeneralFlow
from impactcont.orbit.periodic import amplitude_squared, orbit_at_phase, periodic_orbits
from impactcont.problems.codim1 import curve_problem
from impactcont.scene import SceneError, load_scene, read_output, run_scene
from tests._scene_data import OSCILLATOR, SMALL_SCENE, write
from tests.orbit.test_periodic import section_point, simulated_impact_map, simulated_map_jacobian

K2 = np.array([[1.0, -1.0], [-1.0, 2.0]])


def _damper_on_mass1() -> ic.ImpactOscillator:
    """n = 2, unequal masses, a dashpot on mass 1 (and a weak one on mass 2)."""
    return ic.ImpactOscillator(M=np.diag([1.0, 1.5]), K=K2, C=[[0.3, 0.0], [0.0, 0.02]],
                               F=[1.0, 0.0], R=0.6, b=0.3, omega=1.0)


def _chain3_overdamped() -> ic.ImpactOscillator:
    """n = 3 chain, a heavy dashpot on mass 3: two real (over-damped) eigenvalues."""
    return ic.ImpactOscillator.chain(masses=[1.0, 1.2, 0.8], springs=[1.0, 1.5, 2.0],
                                     C=np.diag([0.05, 0.0, 6.0]), F=[1.0, 0.0, 0.3], R=0.7,
                                     b=0.1, omega=1.1)


NONPROPORTIONAL = {"damper_on_mass1": _damper_on_mass1, "chain3_overdamped": _chain3_overdamped}


# -- the expm reference -------------------------------------------------------------------------
def _augmented(osc: ic.ImpactOscillator) -> np.ndarray:
    """``d/dt [X; cos theta; sin theta]``: eq. (1) in first order with the forcing's own
    oscillator (theta = omega t + delta), so one ``expm`` gives the whole flow."""
    n = osc.n
    Minv = np.linalg.inv(osc.M)
    F = np.asarray(osc.F, dtype=complex)
    A = np.zeros((2 * n + 2, 2 * n + 2))
    A[:n, n:2 * n] = np.eye(n)
    A[n:2 * n, :n] = -Minv @ osc.K
    A[n:2 * n, n:2 * n] = -Minv @ osc.C
    A[n:2 * n, 2 * n] = Minv @ F.real  # Re(F e^{i theta}) = F_r cos - F_i sin
    A[n:2 * n, 2 * n + 1] = -Minv @ F.imag
    A[2 * n, 2 * n + 1] = -osc.omega
    A[2 * n + 1, 2 * n] = osc.omega
    return A


def _expm_orbit_pieces(osc, N, E=None):
    """``Phi``, the forcing columns, and the fixed point's S by expm (eq. 12-13); `E`, the
    flow of the augmented system over T, when computed otherwise (mpmath)."""
    n = osc.n
    T = 2.0 * math.pi * N / osc.omega
    if E is None:
        E = scipy.linalg.expm(_augmented(osc) * T)
    Phi, P = E[:2 * n, :2 * n], E[:2 * n, 2 * n:]
    d = np.ones(2 * n)
    d[n] = -osc.R
    S = np.linalg.solve(np.eye(2 * n) - d[:, None] * Phi, d[:, None] * P)
    return T, Phi, P, S, d


def _expm_G(osc, N, delta, E=None):
    """G of eq. (25) assembled from the expm pieces (independent of impactcont's)."""
    n = osc.n
    T, Phi, P, S, d = _expm_orbit_pieces(osc, N, E)
    cs = np.array([math.cos(delta), math.sin(delta)])
    X0 = S @ cs
    Xa = np.concatenate([Phi @ X0 + P @ cs, cs * 0.0])
    Xa[2 * n:] = [math.cos(delta + osc.omega * T), math.sin(delta + osc.omega * T)]
    dX = d * (_augmented(osc) @ Xa)[:2 * n]
    DPhi = d[:, None] * Phi
    dE = d * (P @ np.array([-math.sin(delta), math.cos(delta)]))
    h2 = dX[0]
    p = DPhi[0, 1:]
    G = np.empty((2 * n, 2 * n))
    G[:-1, :-1] = DPhi[1:, 1:] - np.outer(dX[1:], p) / h2
    G[:-1, -1] = dE[1:] - dX[1:] * dE[0] / h2
    G[-1, :-1] = -osc.omega * p / h2
    G[-1, -1] = 1.0 - osc.omega * dE[0] / h2
    return G, X0, h2


def _expm_highest_interior_x1(osc, N, delta, steps=20000):
    """Highest interior local maximum of x1 over a period, by the expm semigroup on a fine
    grid (one-step propagator) and a parabola through the three best samples."""
    T, _, _, S, _ = _expm_orbit_pieces(osc, N)
    h = T / steps
    step = scipy.linalg.expm(_augmented(osc) * h)
    X = np.concatenate([S @ [math.cos(delta), math.sin(delta)], [math.cos(delta),
                                                                  math.sin(delta)]])
    x1 = np.empty(steps + 1)
    for k in range(steps + 1):
        x1[k] = X[0]
        X = step @ X
    interior = np.flatnonzero((x1[1:-1] >= x1[:-2]) & (x1[1:-1] >= x1[2:])) + 1
    best = -math.inf
    for k in interior:
        a, b, c = x1[k - 1], x1[k], x1[k + 1]
        den = a - 2 * b + c
        best = max(best, b - 0.125 * (c - a) ** 2 / den if den != 0 else b)
    return best


# -- proportional C through the general path ----------------------------------------------------
PROPORTIONAL = [
    ({"eta": 0.1}, 1.0, 0.6, 1),
    ({"eta": 0.1}, 2.4, 0.0, 2),
    ({"alpha": 0.05, "beta": 0.3}, 1.3, 0.2, 1),
    ({"alpha": 0.0, "beta": 1.4}, 0.9, 0.1, 1),  # the higher mode over-damped (xi = 1.83)
]


@pytest.mark.parametrize(("damping", "omega", "b", "N"), PROPORTIONAL)
def test_general_path_on_proportional_C_agrees_with_the_modal_path(damping, omega, b, N):
    prop = ic.ImpactOscillator(M=np.diag([1.0, 1.3]), K=K2, F=[1.0, 0.4], R=0.6, b=b,
                               omega=omega, **damping)
    gen = ic.ImpactOscillator(M=prop.M, K=prop.K, C=prop.C, F=prop.F, R=0.6, b=b, omega=omega)
    assert gen.general_damping and not prop.general
    c, s = general.amplitude(gen, N)[:2]
    assert c * c + s * s == pytest.approx(amplitude_squared(prop, N), rel=1e-12)
    op, og = ic.periodic_orbits(prop, N), ic.periodic_orbits(gen, N)
    assert len(op) == len(og) == 2
    for a, g in zip(op, og, strict=True):
        assert g.delta == pytest.approx(a.delta, abs=1e-12)
        np.testing.assert_allclose(g.state, a.state, rtol=0, atol=1e-12 * np.abs(a.state).max())
        assert g.impact_velocity == pytest.approx(a.impact_velocity, rel=1e-12, abs=1e-13)
        scale = np.abs(a.G).max()
        np.testing.assert_allclose(g.G, a.G, rtol=0, atol=1e-12 * scale)
        np.testing.assert_allclose(np.sort_complex(g.multipliers), np.sort_complex(a.multipliers),
                                   rtol=0, atol=1e-12 * max(1.0, scale))
        assert g.physical == a.physical
        if math.isfinite(a.gap_min):
            assert g.gap_min == pytest.approx(a.gap_min, abs=1e-12)


@pytest.mark.parametrize("which", ["omega", "R"])
def test_amplitude_derivatives_are_exact(which):
    osc = _damper_on_mass1()
    _, _, dc, ds = general.amplitude(osc, 1, which)
    h = 1e-6 * (osc.omega if which == "omega" else 1.0)
    plus = general.amplitude(osc.replace(**{which: getattr(osc, which) + h}), 1)
    minus = general.amplitude(osc.replace(**{which: getattr(osc, which) - h}), 1)
    assert dc == pytest.approx((plus[0] - minus[0]) / (2 * h), rel=1e-7)
    assert ds == pytest.approx((plus[1] - minus[1]) / (2 * h), rel=1e-7)


# -- non-proportional C against expm and mpmath -------------------------------------------------
@pytest.mark.parametrize("name", NONPROPORTIONAL)
def test_flow_against_expm(name):
    osc = NONPROPORTIONAL[name]()
    flow = ic.Flow(osc)
    assert isinstance(flow, GeneralFlow)
    rng = np.random.default_rng(3)
    X0 = rng.standard_normal(2 * osc.n)
    # scipy's expm is the reference: accurate to ~1e-14 of its scale, not to an ulp
    for t in (0.3, 2.0, 7.5):
        E = scipy.linalg.expm(_augmented(osc) * t)
        for delta in (0.0, 1.1):
            ref = E @ np.concatenate([X0, [math.cos(delta), math.sin(delta)]])
            np.testing.assert_allclose(flow.state(t, X0, delta)[0], ref[:2 * osc.n], rtol=0,
                                       atol=1e-12 * np.abs(ref).max())
            dref = (_augmented(osc) @ ref)[:2 * osc.n]
            np.testing.assert_allclose(flow.state_derivative(t, X0, delta)[0], dref, rtol=0,
                                       atol=1e-12 * np.abs(dref).max())
            x, v, acc = flow.mass1(X0, delta)(np.array([t]))
            np.testing.assert_allclose([x[0], v[0], acc[0]], [ref[0], ref[osc.n], dref[osc.n]],
                                       rtol=0, atol=1e-12 * np.abs(dref).max())
        np.testing.assert_allclose(flow.transition_matrix(t), E[:2 * osc.n, :2 * osc.n], rtol=0,
                                   atol=1e-13)


@pytest.mark.parametrize("name", NONPROPORTIONAL)
@pytest.mark.parametrize("N", [1, 2])
def test_orbits_and_G_against_expm(name, N):
    osc = NONPROPORTIONAL[name]()
    T, _, _, S, _ = _expm_orbit_pieces(osc, N)
    c, s = general.amplitude(osc, N)[:2]
    assert c == pytest.approx(S[0, 0], rel=1e-12)
    assert s == pytest.approx(S[0, 1], rel=1e-12)
    orbits = ic.periodic_orbits(osc, N)
    assert len(orbits) == 2
    for orbit in orbits:
        assert orbit.period == pytest.approx(T, rel=1e-15)
        G, X0, h2 = _expm_G(osc, N, orbit.delta)
        assert X0[0] == pytest.approx(osc.b, abs=1e-12)
        np.testing.assert_allclose(orbit.state, X0, rtol=0, atol=1e-12 * np.abs(X0).max())
        assert orbit.impact_velocity == pytest.approx(h2, rel=1e-12)
        np.testing.assert_allclose(orbit.G, G, rtol=0, atol=1e-9 * np.abs(G).max())
        np.testing.assert_allclose(np.sort_complex(orbit.multipliers),
                                   np.sort_complex(np.linalg.eigvals(G)), atol=1e-9)
        # Liouville: det G = R^2 exp(-T tr(M^-1 C))
        trace = np.trace(np.linalg.solve(osc.M, osc.C))
        assert np.linalg.det(orbit.G) == pytest.approx(osc.R**2 * math.exp(-T * trace),
                                                       rel=1e-10)


def _mp_fixed_point(osc, N, dps=50):
    """``S`` of eq. (13) at `dps` digits: mpmath ``expm`` of the augmented first-order system."""
    with mpmath.workdps(dps):
        n = osc.n
        A = mpmath.matrix(_augmented(osc).tolist())
        A[2 * n, 2 * n + 1] = -mpmath.mpf(osc.omega)
        A[2 * n + 1, 2 * n] = mpmath.mpf(osc.omega)
        T = 2 * mpmath.pi * N / mpmath.mpf(osc.omega)
        E = mpmath.expm(A * T)
        B = mpmath.eye(2 * n)
        rhs = [mpmath.matrix(2 * n, 1), mpmath.matrix(2 * n, 1)]
        for r in range(2 * n):
            dr = -mpmath.mpf(osc.R) if r == n else mpmath.mpf(1)
            for k in range(2 * n):
                B[r, k] -= dr * E[r, k]
            rhs[0][r], rhs[1][r] = dr * E[r, 2 * n], dr * E[r, 2 * n + 1]
        S = [mpmath.lu_solve(B, col) for col in rhs]
        E_float = np.array([[float(E[r, k]) for k in range(2 * n + 2)] for r in range(2 * n + 2)])
        return (np.array([[float(S[k][r]) for k in range(2)] for r in range(2 * n)]), E_float)


def test_orbit_against_50_digit_mpmath_reference():
    """The entries of M^-1 K, M^-1 C and M^-1 F are exact binary fractions here, so the
    mpmath system is the floating-point one exactly."""
    osc = ic.ImpactOscillator(M=np.diag([1.0, 2.0]), K=K2, C=[[0.25, 0.0], [0.0, 0.0]],
                              F=[1.0, 0.0], R=0.625, b=0.25, omega=0.75)
    S, E = _mp_fixed_point(osc, 1)
    c, s = general.amplitude(osc, 1)[:2]
    assert math.hypot(S[0, 0], S[0, 1]) > 0.5  # mass 1 responds (no anti-resonance)
    assert c == pytest.approx(S[0, 0], rel=1e-13, abs=0)
    assert s == pytest.approx(S[0, 1], rel=1e-13, abs=0)
    orbits = ic.periodic_orbits(osc, 1)
    assert len(orbits) == 2
    for orbit in orbits:
        X0 = S @ np.array([math.cos(orbit.delta), math.sin(orbit.delta)])
        np.testing.assert_allclose(orbit.state, X0, rtol=0, atol=1e-12 * np.abs(X0).max())
        G = _expm_G(osc, 1, orbit.delta, E)[0]  # from the 50-digit flow, rounded once
        np.testing.assert_allclose(orbit.G, G, rtol=0, atol=1e-9 * np.abs(G).max())


# -- the simulator ------------------------------------------------------------------------------
@pytest.mark.parametrize("name", NONPROPORTIONAL)
def test_simulator_repeats_the_motion_over_50_periods(name):
    osc = NONPROPORTIONAL[name]()
    assert_simulation_repeats(osc, next(o for o in ic.periodic_orbits(osc, 1) if o.physical))


def assert_simulation_repeats(osc, orbit):
    """The simulator started on a stable N = 1 motion hits the stop once per period for 50
    periods, at the motion's impact velocity (times to 1e-9 T, velocities to 1e-9)."""
    assert orbit.stable
    res = ic.simulate(osc, orbit.state, orbit.delta, 50.5)
    assert res.success and res.impact_times.size == 50
    np.testing.assert_allclose(res.impact_times, orbit.period * np.arange(1, 51), rtol=0,
                               atol=1e-9 * orbit.period)
    np.testing.assert_allclose(res.impact_velocities, orbit.impact_velocity, rtol=1e-9)


@pytest.mark.parametrize("name", NONPROPORTIONAL)
def test_G_against_finite_differences_of_the_simulated_map(name):
    osc = NONPROPORTIONAL[name]()
    orbit = next(o for o in ic.periodic_orbits(osc, 1) if o.physical)
    z0 = section_point(orbit)
    np.testing.assert_allclose(simulated_impact_map(osc, 1, z0), z0, atol=1e-11)
    fd = simulated_map_jacobian(osc, 1, z0)
    assert np.abs(fd - orbit.G).max() < 1e-7 * max(1.0, np.abs(orbit.G).max())


def test_gap_min_against_a_fine_sampling():
    osc = _chain3_overdamped()
    for orbit in ic.periodic_orbits(osc, 2):
        t = np.linspace(0.0, orbit.period, 200001)[1:-1]
        x1 = ic.Flow(osc).state(t, orbit.state, orbit.delta)[:, 0]
        assert osc.b - x1.max() == pytest.approx(orbit.gap_min, abs=1e-8)


# -- branches -----------------------------------------------------------------------------------
@pytest.mark.parametrize(("parameter", "bounds"), [("omega", (0.8, 3.0)), ("b", (0.0, 1.2)),
                                                   ("R", (0.3, 0.9)), ("F0", (0.5, 2.0))])
def test_branch_special_points_against_expm(parameter, bounds):
    osc = _damper_on_mass1()
    branch = ic.continuation(osc, 1, parameter, bounds)
    assert branch.sizes["point"] > 10
    labels = list(branch["special_label"].values)
    checked = set()
    for k, label in enumerate(labels):
        if label not in ("PD", "NS", "SN", "ZV", "GR"):
            continue
        lam = float(branch[f"special_{parameter}"][k])
        delta = float(branch["special_delta"][k])
        at = osc.replace(**{parameter: lam})
        with np.errstate(divide="ignore", invalid="ignore"):  # G ~ 1/h2 is infinite at ZV
            G, _, h2 = _expm_G(at, 1, delta)
        if label in ("PD", "NS"):
            mu = np.linalg.eigvals(G)
        if label == "ZV":  # zero impact velocity
            assert abs(h2) < 1e-9
        elif label == "GR":  # grazing: the highest interior maximum of x1 touches the stop
            assert abs(_expm_highest_interior_x1(at, 1, delta) - at.b) < 1e-9
        elif label == "PD":
            assert np.min(np.abs(mu + 1.0)) < 1e-8
        elif label == "NS":
            assert np.min(np.abs(np.abs(mu[np.abs(mu.imag) > 1e-6]) - 1.0)) < 1e-8
        else:  # fold of eq. (15): c^2 + s^2 = b^2, i.e. the residual and its delta-derivative
            S = _expm_orbit_pieces(at, 1)[3]
            assert math.hypot(S[0, 0], S[0, 1]) == pytest.approx(abs(at.b), rel=1e-9)
        checked.add(label)
    expected = {"omega": {"GR", "NS", "ZV", "SN", "PD"}, "b": {"SN", "ZV", "PD"},
                "R": set(), "F0": {"PD", "ZV", "SN"}}[parameter]
    assert checked == expected, labels


def test_damping_parameters_are_refused_for_continuation():
    osc = _damper_on_mass1()
    for name in ("eta", "alpha", "beta"):
        with pytest.raises(ParameterError, match="meaningless with a general damping matrix"):
            ic.continuation(osc, 1, name, (0.0, 0.5))


def test_stability_map_matches_point_orbits():
    osc = _damper_on_mass1()
    omega = np.array([0.9, 1.0, 1.7])
    b = np.array([0.0, 0.3])
    out = batched_orbits(osc, 1, omega, b)
    for i, w in enumerate(omega):
        for j, bb in enumerate(b):
            orbits = ic.periodic_orbits(osc.replace(omega=float(w), b=float(bb)), 1)
            assert out["exists"][i, j] == bool(orbits)
            for k, orbit in enumerate(orbits):
                assert out["delta"][i, j, k] == pytest.approx(orbit.delta, abs=1e-12)
                assert out["stable"][i, j, k] == orbit.stable
                assert out["spectral_radius"][i, j, k] == pytest.approx(orbit.spectral_radius,
                                                                        rel=1e-12)


# -- construction, serialisation and refusals ---------------------------------------------------
def test_json_round_trip_keeps_C():
    osc = _damper_on_mass1()
    back = ic.ImpactOscillator.from_json(osc.to_json())
    assert back.general_damping
    np.testing.assert_array_equal(back.C, osc.C)
    assert ic.periodic_orbits(back, 1)[1].delta == ic.periodic_orbits(osc, 1)[1].delta
    prop = ic.ImpactOscillator(M=np.eye(2), K=K2, F=[1.0, 0.0], R=0.6, b=0.6, omega=1.0, eta=0.1)
    assert "C" not in prop.to_dict()
    assert not prop.replace(eta=0.2).general_damping


@pytest.mark.parametrize(("C", "match"), [
    ([[0.1, 0.2], [0.0, 0.1]], "C must be symmetric"),
    ([[0.1, 0.0], [0.0, -0.1]], "C must be positive semi-definite"),
    ([[0.1]], r"C must be a square matrix of shape \(2, 2\)"),
    ([[0.1, np.nan], [np.nan, 0.1]], "C must be finite"),
])
def test_bad_C_is_refused(C, match):
    with pytest.raises(ParameterError, match=match):
        ic.ImpactOscillator(M=np.eye(2), K=K2, C=C, F=[1.0, 0.0], R=0.6, b=0.3, omega=1.0)


def test_C_with_eta_or_rayleigh_is_refused():
    for extra in ({"eta": 0.1}, {"alpha": 0.1}, {"beta": 0.0}):
        with pytest.raises(ParameterError, match="give either a damping matrix C or eta"):
            ic.ImpactOscillator(M=np.eye(2), K=K2, C=0.1 * K2, F=[1.0, 0.0], R=0.6, b=0.3,
                                omega=1.0, **extra)
    osc = _damper_on_mass1()
    # replace() switches the damping model: eta replaces the matrix (both at once: refused)
    assert not osc.replace(eta=0.1).general_damping
    assert not osc.replace(C=None, eta=0.1).general_damping
    with pytest.raises(ParameterError, match="give either a damping matrix C or eta"):
        osc.replace(eta=0.1, C=0.1 * K2)
    with pytest.raises(ParameterError, match="no Rayleigh coefficients"):
        _ = osc.rayleigh
    with pytest.raises(ParameterError, match="proportional modal basis"):
        _ = osc.modes


def test_critical_damping_is_refused_and_near_critical_is_accurate():
    """One mass, C = 2 sqrt(K M) (xi = 1: a defective eigenvalue) is refused with the
    numbers; xi = 1 + 1e-6 is diagonalised and agrees with the modal path."""
    base = {"M": [[1.0]], "K": [[4.0]], "F": [1.0], "R": 0.5, "b": 0.1, "omega": 1.3}
    with pytest.raises(ParameterError, match=r"defective or nearly so \(condition number"):
        ic.ImpactOscillator(C=[[4.0]], **base).first_order  # noqa: B018
    xi = 1.0 + 1e-6
    gen = ic.ImpactOscillator(C=[[4.0 * xi]], **base)
    prop = ic.ImpactOscillator(alpha=4.0 * xi, **base)
    assert gen.first_order.condition < 1e4
    for a, g in zip(ic.periodic_orbits(prop, 1), ic.periodic_orbits(gen, 1), strict=True):
        np.testing.assert_allclose(g.state, a.state, atol=1e-11)
        np.testing.assert_allclose(g.G, a.G, atol=1e-10 * np.abs(a.G).max())
    warn_xi = 1.0 + 1e-11
    with pytest.warns(IllConditionedWarning, match="condition number"):
        ic.ImpactOscillator(C=[[4.0 * warn_xi]], **base).first_order  # noqa: B018


def test_repeated_eigenvalues_are_diagonalised():
    """Two identical uncoupled oscillators: every eigenvalue is double, the basis is fine."""
    osc = ic.ImpactOscillator(M=np.eye(2), K=np.eye(2), C=[[0.1, 0.0], [0.0, 0.1]],
                              F=[1.0, 0.5], R=0.6, b=0.2, omega=1.4)
    assert osc.first_order.condition < 10
    T = 2 * math.pi / osc.omega
    np.testing.assert_allclose(ic.Flow(osc).transition_matrix(T),
                               scipy.linalg.expm(_augmented(osc) * T)[:4, :4], atol=1e-14)


# -- scenes and datasets ------------------------------------------------------------------------
GENERAL_SCENE = SMALL_SCENE.replace("eta = 0.1",
                                    "C = [[0.3, 0.0], [0.0, 0.02]]\nF_imag = [0.0, 0.4]")


def test_scene_with_C_and_phases_runs_and_its_files_keep_the_oscillator(tmp_path):
    run = run_scene(write(tmp_path, GENERAL_SCENE), output=tmp_path / "out")
    assert run.ok, run.failures
    osc = run.scene.osc
    assert osc.general_damping and osc.F.dtype.kind == "c"
    np.testing.assert_array_equal(osc.C, [[0.3, 0.0], [0.0, 0.02]])
    np.testing.assert_array_equal(osc.F, [1.0, 0.4j])
    orbits = read_output(tmp_path / "out" / "orbits.nc").datasets["o1"]
    expected = ic.periodic_orbits(osc, 1)
    np.testing.assert_allclose(orbits["delta"].values, [o.delta for o in expected], atol=1e-14)
    branch = ic.load(tmp_path / "out" / "branches.nc")["br"].to_dataset()
    back = ic.ImpactOscillator.from_json(branch.attrs["oscillator"])
    np.testing.assert_array_equal(back.C, osc.C)
    np.testing.assert_array_equal(back.F, osc.F.copy())
    assert back.b == 0.5  # the entry's gap
    at = back.replace(omega=float(branch["omega"][3]))
    c, s = general.amplitude(at, 1)[:2]
    d = float(branch["delta"][3])
    assert c * math.cos(d) + s * math.sin(d) == pytest.approx(0.5, abs=1e-10)


def test_scene_refuses_C_with_eta(tmp_path):
    text = SMALL_SCENE.replace("eta = 0.1", "eta = 0.1\nC = [[0.3, 0.0], [0.0, 0.0]]")
    with pytest.raises(SceneError, match="give either a damping matrix C or eta"):
        load_scene(write(tmp_path, text))


def test_branch_netcdf_round_trip_keeps_C(tmp_path):
    osc = _damper_on_mass1()
    branch = ic.continuation(osc, 1, "b", (0.0, 1.0))
    ic.save(branch, tmp_path / "b.nc")
    back = ic.load(tmp_path / "b.nc")
    again = ic.ImpactOscillator.from_json(back.attrs["oscillator"])
    assert again.general_damping
    np.testing.assert_array_equal(again.C, osc.C)
    np.testing.assert_allclose(back["delta"].values, branch["delta"].values, rtol=0, atol=0)


def test_robust_stability_on_a_proportional_C_matches_the_modal_path():
    prop = ic.ImpactOscillator(M=np.eye(2), K=K2, F=[1.0, 0.0], R=0.6, b=0.6, omega=1.0,
                               eta=0.1)
    gen = ic.ImpactOscillator(M=prop.M, K=prop.K, C=prop.C, F=prop.F, R=0.6, b=0.6, omega=1.0)
    a = ic.robust_stability(prop, 1, vary={"b": (0.2, 1.0)}, nominal={"b": 0.6})
    g = ic.robust_stability(gen, 1, vary={"b": (0.2, 1.0)}, nominal={"b": 0.6})
    assert g.epsilon == pytest.approx(a.epsilon, rel=1e-9)
    assert g.epsilon0 == pytest.approx(a.epsilon0, rel=1e-9)
    assert g.robust == a.robust


def test_two_parameter_curves_accept_a_general_C():
    """Curves run on the first-order path (tests/orbit/test_general.py checks them)."""
    osc = _damper_on_mass1()
    branch = ic.continuation(osc, 1, "omega", (0.8, 3.0))
    k = list(branch["special_label"].values).index("PD")
    c = ic.curve(osc, 1, "PD", start=branch, special=k,
                 bounds={"omega": (0.8, 3.0), "b": (0.0, 1.0)})
    assert c.sizes["point"] > 2 and float(c["residual"].max()) < 1e-10
    crossings = [x["omega"] for x in ic.curve_crossings(c, "b", osc.b)]
    assert min(abs(w - float(branch["special_omega"][k])) for w in crossings) < 1e-8


# ==========================================================================================
# A user's first hour with the first-order path (damping matrix C, complex F): the
# problems found by trying the public API, each with its witness.
#
# - refusals that named the wrong cause (C = 0 given as a matrix with R = 1; a critically
#   damped proportional C that is on the first-order path only because F is complex);
# - continuation in ``eta``/``alpha``/``beta`` with a complex F (an internal error);
# - robust stability varying ``"F[i]"`` of a complex F (the entry's phase was dropped);
# ==========================================================================================
def _phased(**params) -> ic.ImpactOscillator:
    """n = 2, the paper's damping, mass 2 forced a quarter period later (complex F)."""
    base = {"M": np.diag([1.0, 1.5]), "K": K2, "eta": 0.05, "F": [1.0, 0.5j], "R": 0.6,
            "b": 0.3, "omega": 1.0}
    base.update(params)
    return ic.ImpactOscillator(**base)


# -- the elastic undamped case on the first-order path -------------------------------------
def test_zero_C_matrix_with_elastic_impacts_names_the_matrix_not_a_complex_F():
    osc = ic.ImpactOscillator(M=np.eye(2), K=K2, C=np.zeros((2, 2)), F=[1.0, 0.0], R=1.0,
                              b=0.3, omega=1.0)
    with pytest.raises(ParameterError) as info:
        ic.periodic_orbits(osc, 1)
    text = str(info.value)
    assert "complex F" not in text  # F is real here
    assert "C=[[0.0, 0.0], [0.0, 0.0]]" in text and "eta=0" in text
    # the advice works: the same machine with eta = 0 is solved on the modal path
    assert len(ic.periodic_orbits(osc.replace(C=None, eta=0.0), 1)) == 2


def test_elastic_undamped_complex_F_names_the_forcing():
    with pytest.raises(ParameterError) as info:
        ic.periodic_orbits(_phased(eta=0.0, R=1.0), 1)
    text = str(info.value)
    assert "F=[" in text and "complex" in text and "eta=0" not in text


# -- a critically damped mode --------------------------------------------------------------
def test_critical_proportional_damping_with_complex_F_does_not_advise_eta():
    """eta = 1 on n = 1 is critical. The refusal used to advise 'use proportional damping
    (eta or alpha/beta)', which the user had done: the first-order path is taken because
    of the complex F."""
    osc = ic.ImpactOscillator(M=[[1.0]], K=[[1.0]], eta=1.0, F=[1.0j], R=0.5, b=0.01,
                              omega=1.2)
    with pytest.raises(ParameterError, match="defective or nearly so") as info:
        ic.periodic_orbits(osc, 1)
    text = str(info.value)
    assert "proportional" in text and "real F" in text
    # the modal path does solve it with a real F (the advice is usable)
    assert len(ic.periodic_orbits(osc.replace(F=[1.0]), 1)) == 2


def test_critical_general_C_still_advises_proportional_damping():
    osc = ic.ImpactOscillator(M=[[1.0]], K=[[1.0]], C=[[2.0]], F=[1.0], R=0.5, b=0.01,
                              omega=1.2)
    with pytest.raises(ParameterError, match="critically damped"):
        ic.periodic_orbits(osc, 1)


# -- continuation in the damping with a complex F ------------------------------------------
@pytest.mark.parametrize("name, damping", [("eta", {"eta": 0.05}),
                                           ("alpha", {"eta": None, "alpha": 0.05, "beta": 0.0}),
                                           ("beta", {"eta": None, "alpha": 0.0, "beta": 0.1})])
def test_continuation_in_the_damping_with_complex_F_follows_the_motion(name, damping):
    # Once refused (eq. 12-14 have no exact derivative in the damping on the first-order
    # path); the parameter object's finite-difference fallback now gives dF/dlam. Witness:
    # every point is a root of eq. (15) of a freshly built oscillator at its damping.
    osc = _phased(**damping)
    branch = ic.continuation(osc, 1, name, (0.01, 0.2))
    values, phases = branch[name].values, branch.delta.values
    assert values.size > 5
    for k in range(0, values.size, max(1, values.size // 6)):
        roots = ic.periodic_orbits(osc.replace(**{name: float(values[k])}), 1)
        assert min(abs(np.angle(np.exp(1j * (o.delta - phases[k])))) for o in roots) < 1e-8


# -- robust stability varying an entry of a complex F --------------------------------------
def test_robust_stability_refuses_a_phased_F_entry():
    osc = _phased()
    with pytest.raises(ParameterError) as info:
        ic.robust_stability(osc, 1, {"F[2]": (0.4, 0.6)})  # mass 2's forcing (1-based)
    text = str(info.value)
    assert "'F[2]'" in text and "0.5j" in text and "F0" in text
    # the advice works: F0 scales the whole F and keeps the phases
    assert np.isfinite(ic.robust_stability(osc, 1, {"F0": (0.9, 1.1)}, samples=5).epsilon)


def test_robust_stability_varies_a_real_entry_of_a_complex_F():
    """An entry with no phase keeps its meaning: F[1] = value (mass 1, 1-based), F[2] keeps
    its phase, so the nominal motion (box centre F[1] = 1) is the oscillator's own."""
    osc = _phased()
    box = ic.robust_stability(osc, 1, {"F[1]": (0.95, 1.05)}, samples=5)
    orbit = next(o for o in ic.periodic_orbits(osc, 1) if o.root == box.root)
    np.testing.assert_allclose(box.G0, orbit.G, rtol=1e-12, atol=1e-12)
    assert np.isfinite(box.epsilon)


# -- a singular stiffness ------------------------------------------------------------------
K_FREE = np.array([[2.0, -1.0, -1.0], [-1.0, 1.0, 0.0], [-1.0, 0.0, 1.0]])


"""Masses 2 and 3 hang on mass 1 only and nothing holds mass 1: ``K [1, 1, 1] = 0`` (a
rigid-body mode). Its Cholesky factorisation succeeds in rounding, so ``ImpactOscillator``
accepts it; the modal path refuses it, the first-order path returned an ill-conditioned
warning and numbers of no meaning (condition number 1.7e17 of eq. 12)."""


@pytest.mark.parametrize("damping", [{"C": np.diag([0.2, 0.0, 0.0])},
                                     {"eta": 0.05, "F": [1.0, 0.3j, 0.0]}])
def test_singular_stiffness_is_refused_on_the_first_order_path(damping):
    params = {"F": [1.0, 0.0, 0.0], "R": 0.5, "b": 0.1, "omega": 1.3, **damping}
    osc = ic.ImpactOscillator(M=np.eye(3), K=K_FREE, **params)
    with pytest.raises(ParameterError, match=r"K must be positive definite relative to M"):
        ic.periodic_orbits(osc, 1)
    with pytest.raises(ParameterError, match=r"K must be positive definite relative to M"):
        ic.periodic_orbits(ic.ImpactOscillator(M=np.eye(3), K=K_FREE, eta=0.05,
                                               F=[1.0, 0.0, 0.0], R=0.5, b=0.1, omega=1.3),
                           1)  # the modal path's own refusal


# -- stability maps: the batched first-order block against point-by-point orbits ---------
def _map_cases() -> dict[str, ic.ImpactOscillator]:
    return {
        "damper_on_mass1": ic.ImpactOscillator(M=np.diag([1.0, 1.5]), K=K2,
                                               C=[[0.3, 0.0], [0.0, 0.02]], F=[1.0, 0.0],
                                               R=0.6, b=0.3, omega=1.0),
        "overdamped_chain3": ic.ImpactOscillator.chain(
            masses=[1.0, 1.2, 0.8], springs=[1.0, 1.5, 2.0], C=np.diag([0.05, 0.0, 6.0]),
            F=[1.0, 0.0, 0.3], R=0.7, b=0.1, omega=1.1),
        "phased": _phased(),
        "n1": ic.ImpactOscillator(M=[[1.0]], K=[[1.0]], C=[[0.1]], F=[1.0], R=0.5, b=0.1,
                                  omega=1.2),
    }


@pytest.mark.parametrize("name", sorted(_map_cases()))
def test_general_stability_map_matches_point_orbits_in_every_field(name):
    """The block is batched over the gaps (G by broadcasting, the x1 search grid shared);
    each field must still be the motion's own."""
    osc = _map_cases()[name]
    from impactcont.orbit.batched import batched_orbits

    omega = np.array([0.7, 1.05, 1.9])
    b = np.array([-0.4, 0.0, 0.2, 0.45])
    for N in (1, 2):
        out = batched_orbits(osc, N, omega, b)
        checked = 0
        for i, w in enumerate(omega):
            for j, bb in enumerate(b):
                orbits = ic.periodic_orbits(osc.replace(omega=float(w), b=float(bb)), N)
                assert out["exists"][i, j] == bool(orbits)
                for k, orbit in enumerate(orbits):
                    checked += 1
                    assert out["delta"][i, j, k] == orbit.delta
                    assert out["impact_velocity"][i, j, k] == pytest.approx(
                        orbit.impact_velocity, rel=1e-11, abs=1e-13)
                    assert out["gap_min"][i, j, k] == pytest.approx(orbit.gap_min, rel=1e-9,
                                                                    abs=1e-11)
                    if np.isfinite(orbit.gap_min):
                        assert out["gap_min_time"][i, j, k] == pytest.approx(
                            orbit.gap_min_time, rel=1e-7)
                    assert out["spectral_radius"][i, j, k] == pytest.approx(
                        orbit.spectral_radius, rel=1e-10)
                    assert out["critical_multiplier"][i, j, k] == pytest.approx(
                        orbit.multipliers[0], rel=1e-9, abs=1e-12)
                    assert out["stable"][i, j, k] == orbit.stable
                    assert out["physical"][i, j, k] == orbit.physical
        assert checked >= 8


# -- scenes: an entry's F on an oscillator with forcing phases ------------------------------
_PHASED_SCENE = """
[oscillator]
K = [[1.0, -1.0], [-1.0, 2.0]]
F = [1.0, 0.0]
F_imag = [0.0, 0.5]
eta = 0.05
R = 0.6
b = 0.3
omega = 1.0
[[orbits]]
name = "same"
[[orbits]]
name = "louder"
F = [2.0, 0.0]
[[orbits]]
name = "rephased"
F_imag = [0.0, -0.5]
[[orbits]]
name = "unphased"
F_imag = [0.0, 0.0]
"""


def test_scene_entry_F_keeps_the_oscillators_phases(tmp_path):
    """An entry with ``F = [2, 0]`` used to drop the oscillator's ``F_imag`` silently (the
    entry's motion had no phase on mass 2); now F is the real part, as in [oscillator],
    and an entry may give its own ``F_imag``."""
    from impactcont.scene import load_scene

    path = tmp_path / "scene.toml"
    path.write_text(_PHASED_SCENE, encoding="utf-8")
    scene = load_scene(path)
    entries = {e.name: e.oscillator for e in scene.entries("orbits")}
    np.testing.assert_array_equal(entries["same"].F, [1.0, 0.5j])
    np.testing.assert_array_equal(entries["louder"].F, [2.0, 0.5j])
    np.testing.assert_array_equal(entries["rephased"].F, [1.0, -0.5j])
    assert entries["unphased"].F.dtype == float and not entries["unphased"].general
    np.testing.assert_array_equal(entries["unphased"].F, [1.0, 0.0])
    bad = _PHASED_SCENE.replace('F_imag = [0.0, -0.5]', 'F_imag = [0.0, -0.5, 1.0]')
    path.write_text(bad, encoding="utf-8")
    from impactcont.scene import SceneError

    with pytest.raises(SceneError, match="F_imag must have the length of F"):
        load_scene(path)


# -- a map column at an undamped resonance --------------------------------------------------
def test_general_map_leaves_a_resonant_column_empty_instead_of_failing():
    """A dashpot between two equal masses leaves their in-phase mode (omega_1 = 1)
    undamped. A map whose grid holds omega = 1 used to stop with ResonanceError, losing
    every other column; now that column is empty (no forced response, so no motion),
    with a warning naming omega, and the other columns are the motions'."""
    K = np.array([[2.0, -1.0], [-1.0, 2.0]])
    d = np.array([1.0, -1.0])
    osc = ic.ImpactOscillator(M=np.eye(2), K=K, C=0.2 * np.outer(d, d), F=[1.0, 0.0], R=0.6,
                              b=0.1, omega=1.2)
    with pytest.raises(ic.ResonanceError):
        ic.periodic_orbits(osc.replace(omega=1.0), 1)
    omega = np.array([0.7, 1.0, 1.3])
    b = np.array([0.0, 0.1])
    with pytest.warns(ic.NearResonanceWarning, match=r"omega=1\.0"):
        m = ic.stability_map(osc, 1, omega, b)
    exists = m["exists"].sel(N=1).values
    assert not exists[1].any() and np.isnan(m["amplitude_squared"].sel(N=1).values[1])
    for i in (0, 2):
        for j, bb in enumerate(b):
            orbits = ic.periodic_orbits(osc.replace(omega=float(omega[i]), b=float(bb)), 1)
            assert exists[i, j] == bool(orbits)
            assert int(m["n_stable"].sel(N=1).values[i, j]) == sum(
                o.stable for o in orbits if o.physical)


def test_replace_switches_between_a_damping_matrix_and_eta_alpha_beta():
    """eta / alpha / beta given to replace() replace a matrix C and a matrix C replaces them
    (both were refused with 'give either ...'); C=None leaves the oscillator undamped."""
    osc = ic.ImpactOscillator(M=np.eye(2), K=[[1.0, -1.0], [-1.0, 2.0]], F=[1.0, 0.0], R=0.6,
                              b=0.5, omega=1.2, C=[[0.0, 0.0], [0.0, 0.2]])
    prop = osc.replace(eta=0.1)
    assert not prop.general_damping and prop.eta == 0.1
    assert np.allclose(prop.C, 0.2 * np.asarray(prop.K))
    back = prop.replace(C=[[0.0, 0.0], [0.0, 0.2]])
    assert back.general_damping and back.eta is None and back.alpha is None
    assert np.array_equal(back.C, osc.C)
    rayleigh = osc.replace(alpha=0.05, beta=0.02)
    assert rayleigh.rayleigh == (0.05, 0.02) and not rayleigh.general_damping
    bare = osc.replace(C=None)
    assert not np.any(bare.C) and "undamped" in repr(bare)
    with pytest.raises(ic.ParameterError, match="not both"):
        osc.replace(eta=0.1, C=[[0.1, 0.0], [0.0, 0.1]])


def test_f_imag_must_have_the_shape_of_f():
    """A shorter F_imag was broadcast over F (every mass the same phase) or blamed on F."""
    data = ic.ImpactOscillator(M=np.eye(2), K=[[1.0, -1.0], [-1.0, 2.0]], F=[1.0, 0.5j],
                               R=0.6, b=0.5, omega=1.2, eta=0.1).to_dict()
    assert ic.ImpactOscillator.from_dict(data).F.tolist() == [1.0, 0.5j]
    with pytest.raises(ic.ParameterError, match="F_imag must have the shape of F"):
        ic.ImpactOscillator.from_dict({**data, "F_imag": [0.5]})


@pytest.mark.parametrize("damping", [{"eta": 0.1}, {"C": [[0.0, 0.0], [0.0, 0.2]]}])
def test_orbit_at_phase_refuses_a_phase_off_eq_14(damping):
    """A phase that does not satisfy eq. (14) gave a 'motion' with x1(0) != b, reported
    physical; now it is refused, and the roots of eq. (15) are accepted."""
    from impactcont.orbit.periodic import orbit_at_phase

    osc = ic.ImpactOscillator(M=np.eye(2), K=[[1.0, -1.0], [-1.0, 2.0]], F=[1.0, 0.0], R=0.6,
                              b=0.3, omega=1.25, **damping)
    roots = ic.periodic_orbits(osc, 1)
    assert roots
    for orbit in roots:
        again = orbit_at_phase(osc, 1, orbit.delta)
        assert abs(again.state[0] - osc.b) < 1e-12
    with pytest.raises(ic.ParameterError, match=r"does not satisfy eq\. \(14\)"):
        orbit_at_phase(osc, 1, roots[0].delta + 0.3)


BOX = {"omega": (0.6, 2.0), "b": (0.0, 0.6)}


KINDS = ("SN", "PD", "NS", "GR", "ZV")


START_B = {"SN": 0.5, "PD": 0.0, "NS": 0.5, "GR": 0.5, "ZV": 0.5}


#: gaps at which the damper-on-mass-2 curves are compared with one-parameter points
CHECK_B = {"SN": (0.45, 0.5), "PD": (0.1, 0.3, 0.5), "NS": (0.3, 0.45),
           "GR": (0.45, 0.5), "ZV": (0.3, 0.45)}


def _paper(**damping):
    return ic.ImpactOscillator(M=np.eye(2), K=K2, F=[1.0, 0.0], R=0.6, b=0.5, omega=1.0,
                               **damping)


def _starts(osc, kinds=KINDS):
    """The first located special point of each kind on the omega-branches at START_B."""
    branches = {b: ic.continuation(osc.replace(b=b), 1, "omega", BOX["omega"],
                                   detect=[k for k in kinds if START_B[k] == b])
                for b in {START_B[k] for k in kinds}}
    out = {}
    for kind in kinds:
        ds = branches[START_B[kind]]
        k = int(np.flatnonzero((ds.special_label.values == kind)
                               & (ds.special_status.values == "located"))[0])
        out[kind] = {"omega": float(ds.special_omega[k]), "b": START_B[kind],
                     "delta": float(ds.special_delta[k])}
    return out


# -- (a) a proportional C given as a matrix: the modal path's curves -----------------------------
@pytest.mark.parametrize("damping", [{"eta": 0.1}, {"alpha": 0.05, "beta": 0.1}],
                         ids=["eta", "rayleigh"])
def test_proportional_C_as_a_matrix_gives_the_modal_curves(damping):
    modal = _paper(**damping)
    matrix = _paper(C=modal.C)
    assert matrix.general and not modal.general
    starts = _starts(modal)
    labels = set()
    for kind in KINDS:
        a = curve(modal, 1, kind, start=starts[kind], bounds=BOX)
        g = curve(matrix, 1, kind, start=starts[kind], bounds=BOX)
        assert g.sizes["point"] == a.sizes["point"] > 5, kind
        for name in ("omega", "b", "delta", "impact_velocity"):
            assert np.max(np.abs(g[name].values - a[name].values)) < 1e-9, (kind, name)
        assert float(g.residual.max()) < 1e-10
        assert g.codim2_label.values.tolist() == a.codim2_label.values.tolist(), kind
        assert g.codim2_status.values.tolist() == a.codim2_status.values.tolist(), kind
        for name in ("codim2_omega", "codim2_b"):
            assert np.max(np.abs(g[name].values - a[name].values), initial=0.0) < 1e-9, kind
        labels |= set(g.codim2_label.values.tolist())
    assert len(labels) >= 4, labels  # codim-2 points of several kinds were compared


@pytest.mark.parametrize(("kind", "parameters", "bounds"), [
    ("PD", ("omega", "R"), {"omega": (1.0, 2.0), "R": (0.4, 0.9)}),
    ("NS", ("F0", "omega"), {"F0": (0.6, 1.4), "omega": (1.2, 1.8)}),
])
def test_proportional_C_as_a_matrix_in_other_parameter_pairs(kind, parameters, bounds):
    """R and F0 as parameters: the difference columns (R) and the F0 step agree too."""
    modal = _paper(eta=0.1)
    if kind == "PD":
        modal = modal.replace(b=0.3)
        start = {"omega": 1.3737, "R": 0.6}
    else:
        found = _starts(modal, ["NS"])["NS"]
        start = {"F0": 1.0, "omega": found["omega"], "delta": found["delta"]}
    matrix = _paper(C=modal.C).replace(b=modal.b)
    a, g = (curve(osc, 1, kind, start=start, parameters=parameters, bounds=bounds)
            for osc in (modal, matrix))
    assert matrix.general and g.sizes["point"] == a.sizes["point"] > 5
    assert max(np.ptp(g[p].values) for p in parameters) > 0.1
    for name in (*parameters, "delta"):
        assert np.max(np.abs(g[name].values - a[name].values)) < 1e-9, name
    assert g.codim2_label.values.tolist() == a.codim2_label.values.tolist()


# -- (b) a damper on mass 2 only: no modal decoupling --------------------------------------------
@pytest.fixture(scope="module")
def damper():
    return _paper(C=[[0.0, 0.0], [0.0, 0.2]])


@pytest.fixture(scope="module")
def damper_curves(damper):
    starts = _starts(damper)
    return {kind: curve(damper, 1, kind, start=starts[kind], bounds=BOX) for kind in KINDS}


def _one_parameter_points(osc, kind, b, omega):
    ds = ic.continuation(osc.replace(b=b), 1, "omega", (omega - 0.015, omega + 0.015),
                         detect=[kind], ds=0.002, ds_max=0.005)
    rows = (ds.special_label.values == kind) & (ds.special_status.values == "located")
    return ds.special_omega.values[rows]


@pytest.mark.parametrize("kind", KINDS)
def test_damper_curve_passes_through_one_parameter_special_points(damper, damper_curves, kind):
    c = damper_curves[kind]
    assert float(c.residual.max()) < 1e-10
    compared = 0
    for b in CHECK_B[kind]:
        crossings = curve_crossings(c, "b", b)
        assert crossings, f"{kind} curve does not cross b={b}"
        for cr in crossings:
            found = _one_parameter_points(damper, kind, b, cr["omega"])
            assert found.size, f"no 1-parameter {kind} near omega={cr['omega']} at b={b}"
            assert np.min(np.abs(found - cr["omega"])) < 1e-8, (kind, b, cr, found)
            compared += 1
    assert compared >= 3


def test_damper_pd_curve_in_omega_and_R(damper):
    osc = damper.replace(b=0.3)
    c = curve(osc, 1, "PD", start={"omega": 0.70646, "R": 0.6}, parameters=("omega", "R"),
              bounds={"omega": (0.6, 1.0), "R": (0.4, 0.9)}, detect_codim2_points=False)
    compared = 0
    for R in (0.45, 0.85):
        for cr in curve_crossings(c, "R", R):
            found = _one_parameter_points(osc.replace(R=R), "PD", 0.3, cr["omega"])
            assert found.size and np.min(np.abs(found - cr["omega"])) < 1e-8, (R, cr, found)
            compared += 1
    assert compared >= 2


def _motion(osc, point):
    """The motion of ``periodic_orbits`` at a curve point (the root with its phase)."""
    at = osc.replace(omega=float(point.omega), b=float(point.b))
    orbits = periodic_orbits(at, 1)
    delta = float(point.delta)
    return min(orbits, key=lambda o: abs(math.remainder(o.delta - delta, 2 * math.pi)))


@pytest.mark.parametrize("kind", KINDS)
def test_damper_curve_points_are_special(damper, damper_curves, kind):
    c = damper_curves[kind]
    checked = 0
    for k in range(0, c.sizes["point"], 3):
        point = c.isel(point=k)
        osc = damper.replace(omega=float(point.omega), b=float(point.b))
        if kind == "SN":
            cs, s = general.amplitude(osc, 1)[:2]
            assert abs(cs**2 + s**2 - float(point.b) ** 2) < 1e-10
        elif kind == "ZV":
            assert abs(orbit_at_phase(osc, 1, float(point.delta)).impact_velocity) < 1e-10
        else:
            o = _motion(damper, point)
            if kind == "PD":
                assert np.min(np.abs(o.multipliers + 1.0)) < 1e-8, (k, o.multipliers)
            elif kind == "NS":
                theta = float(point.angle)
                assert np.min(np.abs(o.multipliers - np.exp(1j * theta))) < 1e-8
            elif not bool(point.physical):
                continue  # another maximum of x1 above b: gap_min is that one's
            else:
                assert abs(o.gap_min) < 1e-9, (k, o.gap_min)
        checked += 1
    assert checked >= 3


def test_damper_codim2_points_lie_on_both_curves(damper_curves):
    for a, b, la, lb in (("PD", "GR", "PD+GR", "GR+PD"), ("SN", "ZV", "SN+ZV", "ZV+SN")):
        ca, cb = damper_curves[a], damper_curves[b]
        pa = ca.isel(codim2=np.flatnonzero(ca.codim2_label.values == la))
        pb = cb.isel(codim2=np.flatnonzero(cb.codim2_label.values == lb))
        assert pa.sizes["codim2"] and pb.sizes["codim2"], (la, lb)
        assert (pa.codim2_status.values == "located").all()
        d = np.hypot(pa.codim2_omega.values[:, None] - pb.codim2_omega.values[None, :],
                     pa.codim2_b.values[:, None] - pb.codim2_b.values[None, :])
        assert d.min() < 1e-7, (la, lb, d.min())


# -- the pieces: G split, x1, Jacobian columns -----------------------------------------------------
def test_general_pieces_match_the_dense_closed_form(damper):
    osc = damper.replace(omega=1.1, b=0.3)
    pc = curve_problem("GR", osc, 1)._pieces(1.1, 0.3)
    flow = Flow(osc)
    for o in periodic_orbits(osc, 1):
        G_reg, a, b, h2 = pc.split(o.delta)
        G, h2_dense = impact_map_jacobian(flow, pc.state(o.delta), o.delta, pc.T, pc.DPhi)
        np.testing.assert_allclose(G_reg + np.outer(a, b) / h2, G, rtol=0, atol=1e-12)
        np.testing.assert_allclose(pc.jacobian(o.delta)[0], o.G, rtol=0, atol=1e-12)
        assert h2 == pytest.approx(h2_dense, abs=1e-14)
        assert pc.impact_velocity(o.delta) == pytest.approx(o.impact_velocity, abs=1e-14)
        E = pc.pole_free_pd_matrix(o.delta)
        assert np.linalg.det(E) == pytest.approx(-h2 * np.linalg.det(G + np.eye(4)), rel=1e-9)
        t = np.array([0.3, 2.0, 4.5])
        exact = flow.mass1(pc.state(o.delta), o.delta).derivatives(t)
        for j, tj in enumerate(t):
            np.testing.assert_allclose(pc.mass1_derivatives(o.delta, tj, 3),
                                       [exact[0][j], exact[1][j], exact[2][j]], atol=1e-13)


@pytest.mark.parametrize("kind", KINDS)
@pytest.mark.parametrize("parameters", [("omega", "b"), ("R", "F0"), ("F0", "omega")])
def test_general_jacobian_against_differences(damper, kind, parameters):
    osc = damper.replace(omega=1.1, b=0.3)
    o = periodic_orbits(osc, 1)[0]
    problem = curve_problem(kind, osc, 1, parameters)
    extras = {"NS": np.r_[0.7, np.linspace(0.1, 0.4, 4), np.linspace(-0.2, 0.2, 4)],
              "GR": np.array([2.0])}.get(kind, np.empty(0))
    x = np.concatenate([[getattr(osc, parameters[0]), o.delta], extras,
                        [getattr(osc, parameters[1])]])
    problem.accept(x[:-1], x[-1])  # PD borders, NS reference vector, as along a curve
    J = problem.full_jacobian(x)
    D = np.empty_like(J)  # fourth-order central differences: error ~1e-11
    for j in range(x.size):
        h = 1e-3 * max(1.0, abs(x[j]))
        F = []
        for step in (-2, -1, 1, 2):
            y = x.copy()
            y[j] += step * h
            F.append(problem.residual(y[:-1], y[-1]))
        D[:, j] = (F[0] - 8 * F[1] + 8 * F[2] - F[3]) / (12 * h)
    scale = max(1.0, np.max(np.abs(J)))
    exact = [j for j in range(x.size) if not (j in (0, x.size - 1) and
                                              parameters[min(j, 1)] in ("omega", "R"))]
    # delta, the extra unknowns, b and F0: exact; omega and R: central differences
    np.testing.assert_allclose(J[:, exact], D[:, exact], rtol=0, atol=1e-9 * scale)
    np.testing.assert_allclose(J, D, rtol=0, atol=1e-6 * scale)
    for j in set(range(x.size)) - set(exact):  # the rows through c, s alone: exact
        rows = 2 if kind == "SN" else 1
        np.testing.assert_allclose(J[:rows, j], D[:rows, j], rtol=0, atol=1e-9 * scale)


# -- (c) complex F: per-mass forcing phases ------------------------------------------------------
@pytest.fixture(scope="module")
def phased():
    return ic.ImpactOscillator(M=np.eye(2), K=K2, F=[1.0, 0.4j], R=0.6, b=0.5, omega=1.0,
                               eta=0.1)


def test_complex_F_pd_curve_passes_through_one_parameter_points(phased):
    assert phased.general and not phased.general_damping
    c = curve(phased, 1, "PD", start=_starts(phased, ["PD"])["PD"], bounds=BOX)
    compared = 0
    for b in (0.1, 0.3, 0.5):
        for cr in curve_crossings(c, "b", b):
            found = _one_parameter_points(phased, "PD", b, cr["omega"])
            assert found.size and np.min(np.abs(found - cr["omega"])) < 1e-8, (b, cr, found)
            compared += 1
    assert compared >= 2


def test_complex_F_zero_velocity_curve_in_omega_and_F0_is_the_linear_response(phased):
    """On ``h2 = 0`` the impact does nothing: ``|x1|`` of the linear response is b (eq. 7)."""
    start = _starts(phased, ["ZV"])["ZV"]
    osc = phased.replace(b=start["b"])
    c = curve(osc, 1, "ZV", start={"F0": 1.0, "omega": start["omega"]},
              parameters=("F0", "omega"), bounds={"F0": (0.5, 1.5), "omega": (1.0, 2.0)})
    assert c.sizes["point"] > 5 and np.ptp(c.F0.values) > 0.2
    assert np.max(np.abs(c.impact_velocity.values)) < 1e-10
    for F0, w in zip(c.F0.values, c.omega.values, strict=True):
        at = osc.replace(F0=float(F0), omega=float(w))
        X = np.linalg.solve(at.K - w**2 * at.M + 1j * w * at.C, at.F)
        assert abs(abs(X[0]) - osc.b) < 1e-10


def test_complex_F_pd_curve_in_omega_and_eta(phased):
    """eta exists with a complex F on C = 2 eta K: its column is a central difference."""
    osc = phased.replace(b=0.0)
    start = _starts(phased, ["PD"])["PD"]
    c = curve(osc, 1, "PD", start={"omega": start["omega"], "eta": 0.1, "delta": start["delta"]},
              parameters=("omega", "eta"), bounds={"omega": (1.0, 2.5), "eta": (0.02, 0.2)},
              detect_codim2_points=False)
    assert np.ptp(c.eta.values) > 0.15
    compared = 0
    for eta in (0.05, 0.15):
        for cr in curve_crossings(c, "eta", eta):
            found = _one_parameter_points(osc.replace(eta=eta), "PD", 0.0, cr["omega"])
            assert found.size and np.min(np.abs(found - cr["omega"])) < 1e-8, (eta, cr, found)
            compared += 1
    assert compared >= 2


# -- (d) bad input --------------------------------------------------------------------------------
@pytest.mark.parametrize("name", ["eta", "alpha", "beta"])
def test_damping_parameters_are_refused_with_a_matrix_C(damper, name):
    with pytest.raises(ParameterError, match=f"'{name}' is meaningless with a general damping "
                                             "matrix"):
        curve(damper, 1, "PD", start={"omega": 0.7, "b": 0.1}, parameters=("omega", name),
              bounds={"omega": (0.6, 2.0), name: (0.0, 1.0)})
    with pytest.raises(ParameterError, match=r"continue in omega, b, R, F0 or an element of C"):
        curve_problem("SN", damper, 1, (name, "b"))


def test_bad_inputs_on_the_first_order_path(damper):
    with pytest.raises(ParameterError, match="must be two different names"):
        curve(damper, 1, "SN", start={"omega": 1.2, "b": 0.5}, parameters=("omega", "omega"),
              bounds=BOX)
    with pytest.raises(ParameterError, match="kind must be one of"):
        curve(damper, 1, "XX", start={"omega": 0.7, "b": 0.1}, bounds=BOX)
    elastic = ic.ImpactOscillator(M=np.eye(2), K=K2, F=[1.0, 0.4j], R=1.0, b=0.5, omega=1.0,
                                  eta=0.0)
    with pytest.raises(ParameterError, match=r"R=1\.0 without damping"):
        curve(elastic, 1, "SN", start={"omega": 1.2, "b": 0.5}, bounds=BOX)


# -- (e) a scene with a damping matrix --------------------------------------------------------
def test_scene_curve_entry_with_a_damping_matrix(tmp_path):
    text = (OSCILLATOR.replace("eta = 0.1", "C = [[0.0, 0.0], [0.0, 0.2]]")
            + '[[branches]]\nname = "br"\nb = 0.5\nbounds = [0.9, 1.5]\n'
            + '[[curves]]\nname = "sn"\nkind = "SN"\nstart = "br"\n'
            + "bounds = { omega = [0.9, 1.6], b = [0.45, 0.7] }\nds_max = 0.1\n")
    result = run_scene(write(tmp_path, text), output=tmp_path / "o")
    assert result.ok, result.failures
    c = read_output(tmp_path / "o" / "curves.nc").datasets["sn"]
    osc = ic.ImpactOscillator.from_json(c.attrs["oscillator"])
    assert osc.general_damping and c.attrs["kind"] == "SN" and c.sizes["point"] > 2
    np.testing.assert_array_equal(osc.C, [[0.0, 0.0], [0.0, 0.2]])
    for w, b in zip(c.omega.values, c.b.values, strict=True):
        cs, s = general.amplitude(osc.replace(omega=float(w)), 1)[:2]
        assert abs(cs**2 + s**2 - b**2) < 1e-10
