"""The dense closed form (:mod:`impactcont.orbit.dense`) against independent witnesses.

- ``periodic_matrix``, ``impact_map_jacobian``, ``impact_velocity``, ``polished_velocity``:
  the 50-digit reference :mod:`tests.reference_mp` (written from the equations, no code
  shared) and the compiled modal kernel (:func:`impactcont.periodic_orbits`);
- ``pole_free_pd_matrix``: the Schur-complement identity ``det E = -h2 det(G + I)`` with
  ``G = G_reg + a b^T / h2`` formed densely;
- ``velocity_bound``: the error estimate it bounds, over every phase;
- the warnings of an ill-conditioned eq. (12).
"""

from __future__ import annotations

import math
import warnings

import numpy as np
import pytest

import impactcont as ic
from impactcont.errors import IllConditionedWarning
from impactcont.kernel import closed_form
from impactcont.orbit import periodic
from impactcont.orbit.dense import (
    COND_WARN,
    VELOCITY_POLISH,
    impact_map_jacobian,
    impact_velocity,
    periodic_matrix,
    pole_free_pd_matrix,
    polished_velocity,
    second_form,
    velocity_bound,
    velocity_errors,
    warn_ill_conditioned,
)
from tests import reference_mp as ref

K2 = [[1.0, -1.0], [-1.0, 2.0]]
K3 = [[2.0, -1.0, 0.0], [-1.0, 2.0, -1.0], [0.0, -1.0, 1.5]]
M3 = np.diag([1.0, 1.5, 0.8])

# (oscillator keywords, reference keywords): Rayleigh damping C = alpha M + beta K
SYSTEMS = {
    "paper": (dict(M=np.eye(2), K=K2, F=[1.0, 0.0], R=0.6, b=0.3, eta=0.1),
              dict(M=np.eye(2), K=K2, F=[1.0, 0.0], R=0.6, b=0.3, beta=0.2)),
    "rayleigh n=3": (dict(M=M3, K=K3, F=[1.0, 0.0, 0.4], R=0.8, b=0.1, alpha=0.05, beta=0.02),
                     dict(M=M3, K=K3, F=[1.0, 0.0, 0.4], R=0.8, b=0.1, alpha=0.05, beta=0.02)),
}


def _wrap(x):
    return math.atan2(math.sin(x), math.cos(x))


def _cases():
    for name, (kw, rkw) in SYSTEMS.items():
        for omega, N in ((0.9, 1), (1.7, 1), (2.0, 2)):
            yield pytest.param(kw, rkw, omega, N, id=f"{name}-omega{omega}-N{N}")


@pytest.mark.parametrize(("kw", "rkw", "omega", "N"), list(_cases()))
def test_dense_path_is_the_high_precision_reference(kw, rkw, omega, N):
    osc = ic.ImpactOscillator(omega=omega, **kw)
    expected = ref.to_float(ref.closed_form(ref.MPSystem(**rkw), omega, N, gap=False))
    flow = ic.Flow(osc)
    S, DPhi, T = periodic_matrix(flow, N)
    assert abs(T - 2 * math.pi * N / omega) <= 1e-15 * T
    np.testing.assert_allclose(S[0], [expected["c"], expected["s"]], rtol=1e-10, atol=1e-12)
    n = osc.n
    d = np.ones(2 * n)
    d[n] = -osc.R
    transition = ref.to_float(ref.MPSystem(**rkw).transition(T))
    np.testing.assert_allclose(DPhi, d[:, None] * transition, rtol=1e-10,
                               atol=1e-12 * np.abs(transition).max())
    assert expected["orbits"], "the test needs motions at this point"
    for orbit in expected["orbits"]:
        delta = orbit["delta"]
        state = S @ np.array([math.cos(delta), math.sin(delta)])
        np.testing.assert_allclose(state, orbit["state"], rtol=1e-10, atol=1e-11)
        G, h2 = impact_map_jacobian(flow, state, delta, T, DPhi)
        assert h2 == pytest.approx(orbit["impact_velocity"], rel=1e-9, abs=1e-12)
        np.testing.assert_allclose(G, orbit["G"], rtol=1e-8,
                                   atol=1e-9 * np.abs(orbit["G"]).max())
        # DPhi is optional: the same G without it
        G2, h2b = impact_map_jacobian(flow, state, delta, T)
        np.testing.assert_allclose(G2, G, rtol=1e-12, atol=1e-13 * np.abs(G).max())
        assert h2b == pytest.approx(h2, rel=1e-12)


@pytest.mark.parametrize(("kw", "rkw", "omega", "N"), list(_cases())[:3])
def test_dense_jacobian_is_the_kernels(kw, rkw, omega, N):
    """The kernel's G (modal form, :class:`PeriodicOrbit`) and the dense G of the state."""
    osc = ic.ImpactOscillator(omega=omega, **kw)
    flow = ic.Flow(osc)
    _, DPhi, T = periodic_matrix(flow, N)
    orbits = ic.periodic_orbits(osc, N)
    assert orbits
    for orbit in orbits:
        G, h2 = impact_map_jacobian(flow, orbit.state, orbit.delta, T, DPhi)
        assert h2 == pytest.approx(orbit.impact_velocity, rel=1e-9, abs=1e-12)
        np.testing.assert_allclose(G, orbit.G, rtol=1e-8, atol=1e-9 * np.abs(G).max())


@pytest.mark.parametrize("dtype", [float, complex])
def test_pole_free_pd_matrix_is_singular_exactly_at_a_period_doubling(dtype):
    rng = np.random.default_rng(3)
    m = 5
    G_reg = rng.standard_normal((m, m)).astype(dtype)
    a = rng.standard_normal(m).astype(dtype)
    b = rng.standard_normal(m).astype(dtype)
    h2 = dtype(0.37) if dtype is float else 0.37 + 1e-3j
    if dtype is complex:
        G_reg = G_reg + 1e-3j * rng.standard_normal((m, m))
    E = pole_free_pd_matrix(G_reg, a, b, h2)
    assert E.shape == (m + 1, m + 1)
    assert E.dtype == np.result_type(G_reg, a, b, h2)
    G = G_reg + np.outer(a, b) / h2
    assert np.linalg.det(E) == pytest.approx(-h2 * np.linalg.det(G + np.eye(m)), rel=1e-11)
    # finite through h2 = 0, where G has its pole
    assert np.all(np.isfinite(pole_free_pd_matrix(G_reg, a, b, 0.0 * h2)))


def _scalars(osc: ic.ImpactOscillator, N: int):
    arrays = periodic.modal_arrays(osc)
    _, sc = closed_form.omega_setup(arrays.w, arrays.a, arrays.f, arrays.u0, arrays.ui0,
                                    arrays.eig_err, osc.R, osc.omega, N)
    return [float(x) for x in sc[1:5]]  # Gam, B, g, Delta


@pytest.mark.parametrize(("omega", "polished"), [(1.7, False), (300.0, True), (3000.0, True)])
def test_impact_velocity_keeps_its_digits_at_any_frequency(omega, polished):
    """At the roots of eq. (15) the two exact forms of the velocity; far above the natural
    frequencies the first cancels (2e-11 relative at omega = 300, 3e-9 at 3000) and the
    second is taken. Both against the 50-digit reference."""
    kw, rkw = SYSTEMS["paper"]
    kw, rkw = {**kw, "b": 0.0}, {**rkw, "b": 0.0}
    osc = ic.ImpactOscillator(omega=omega, **kw)
    expected = ref.to_float(ref.closed_form(ref.MPSystem(**rkw), omega, 1, multipliers=False,
                                            gap=False))
    Gam, B, g, Delta = _scalars(osc, 1)
    deltas = np.array([o["delta"] for o in expected["orbits"]])
    sigma, rel = impact_velocity(Gam, B, g, Delta, omega, osc.R, 0.0, deltas)
    assert sigma.shape == rel.shape == (2,)
    for k, orbit in enumerate(expected["orbits"]):
        assert sigma[k] == pytest.approx(orbit["impact_velocity"], rel=1e-11, abs=0.0)
        assert rel[k] < 1e-11
        first = omega * (B * math.cos(deltas[k]) - Gam * math.sin(deltas[k])) / Delta
        better, _ = polished_velocity(Gam, B, g, Delta, omega, osc.R, 0.0, deltas[k], first)
        if polished and abs(first / orbit["impact_velocity"] - 1) > 1e-11:
            assert better is not None
            assert better == pytest.approx(orbit["impact_velocity"], rel=1e-12, abs=0.0)
        if not polished:
            assert better is None  # the first form kept, it has its digits


def test_velocity_bound_bounds_the_first_forms_error_at_every_phase():
    kw, _ = SYSTEMS["paper"]
    for omega in (0.5, 1.7, 40.0, 3000.0):
        osc = ic.ImpactOscillator(omega=omega, **kw)
        Gam, B, g, Delta = _scalars(osc, 1)
        deltas = np.linspace(-math.pi, math.pi, 721)
        err_a, err_b = velocity_errors(Gam, B, g, Delta, omega, osc.R, osc.b, deltas,
                                       np.cos(deltas), np.sin(deltas))
        assert np.all(err_a <= velocity_bound(Gam, B, Delta, omega))
        assert np.all(err_b > 0.0)


def test_second_form_needs_a_loss_a_gain_and_agreement():
    """The second form only when the first lost digits, the second lost fewer and the two
    agree within their estimates (a hand-made table of the three conditions)."""
    lost = VELOCITY_POLISH * 10.0
    assert second_form(1.0, 1.0 + lost, lost, lost / 10)
    assert not second_form(1.0, 1.0, VELOCITY_POLISH / 10, VELOCITY_POLISH / 100)  # no loss
    assert not second_form(1.0, 1.0, lost, 2 * lost)  # the second is worse
    assert not second_form(1.0, 1.1, lost, lost / 10)  # they disagree: off a root
    got = second_form(np.ones(3), np.array([1.0, 1.0, 1.1]), np.full(3, lost),
                      np.array([lost / 10, 2 * lost, lost / 10]))
    np.testing.assert_array_equal(got, [True, False, False])


def test_warn_ill_conditioned_above_the_threshold_only():
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        warn_ill_conditioned(1.25, COND_WARN, stacklevel=1)
    with pytest.warns(IllConditionedWarning, match=r"omega=1\.25.*condition estimate 1e\+12"):
        warn_ill_conditioned(1.25, 1e12, stacklevel=1)
    with pytest.warns(IllConditionedWarning):
        warn_ill_conditioned(1.25, math.inf, stacklevel=1)


def test_a_family_of_motions_warns_that_eq12_is_ill_conditioned():
    """No damping and R = 1: the periodic motions form a family, ``I - D Phi(T)`` is
    singular up to rounding and the solve says so."""
    kw, _ = SYSTEMS["paper"]
    osc = ic.ImpactOscillator(omega=1.3, **{**kw, "eta": 0.0, "R": 1.0})
    with pytest.warns(IllConditionedWarning, match="ill-conditioned"):
        periodic_matrix(ic.Flow(osc), 1)
