"""The compiled first-order path (:mod:`impactcont.kernel.general`) against its
numpy reference (:func:`impactcont.orbit.general.reference_form`,
:func:`~impactcont.orbit.general.reference_orbit_values`,
:meth:`~impactcont.model.first_order.FirstOrderBasis.forced_amplitude_reference`).

Both evaluate the same closed form (eq. 12-16 in the first-order modal form) in a
different order of summation, so they agree to rounding: each array to a few hundred eps
of its own size (the condition estimate of eq. 12 bounds what the motion itself
carries), the multipliers to that times the spread of G, for several damping matrices,
omega from 1e-3 to 1e6 and N = 1..4.
"""

from __future__ import annotations

import gc
import math
import weakref

import numpy as np
import pytest

import impactcont as ic
from impactcont.kernel import general as general_kernel
from impactcont.model import first_order
from impactcont.orbit import dense, general
from impactcont.orbit.flow import Flow
from impactcont.orbit.periodic import orbit_at_phase

K2 = [[1.0, -1.0], [-1.0, 2.0]]
K3 = [[2.0, -1.0, 0.0], [-1.0, 2.0, -1.0], [0.0, -1.0, 1.0]]
SYSTEMS = {
    # the paper's machine with only the damper between the masses
    "joint damper": dict(M=np.eye(2), K=K2, C=[[0.2, -0.2], [-0.2, 0.2]], F=[1.0, 0.0]),
    # a damper to ground on mass 2 only, unequal masses
    "grounded damper": dict(M=np.diag([1.0, 2.5]), K=K2, C=[[0.0, 0.0], [0.0, 0.3]],
                            F=[1.0, 0.4]),
    # an over-damped mode (two real eigenvalues: a real scalar pair)
    "over-damped": dict(M=np.eye(2), K=K2, C=[[3.0, -0.5], [-0.5, 0.1]], F=[1.0, 0.0]),
    # three masses, a damper on the last spring only
    "chain of three": dict(M=np.diag([1.0, 0.5, 2.0]), K=K3,
                           C=[[0.0, 0.0, 0.0], [0.0, 0.05, -0.05], [0.0, -0.05, 0.05]],
                           F=[1.0, 0.0, 0.5]),
    # proportional damping with per-mass phases (complex F): the same path
    "complex F": dict(M=np.diag([1.0, 1.5]), K=K2, eta=0.05, F=[1.0, 0.5j]),
}
OMEGAS = (1e-3, 0.37, 1.0, 2.9, 40.0, 1e6)
RTOL = 1e-12  # relative to the size of each array: rounding of O(n^2) sums
_EPS = float(np.finfo(float).eps)


def _osc(name: str, omega: float, b: float = 0.0) -> ic.ImpactOscillator:
    return ic.ImpactOscillator(**SYSTEMS[name], R=0.6, b=b, omega=omega)


def _close(actual, expected, rtol: float = RTOL, what: str = "", floor: float = 0.0) -> None:
    """Equal within ``rtol`` times the size of ``expected`` or the size ``floor`` of the
    terms it sums, if larger (inf and NaN where ``expected`` has them)."""
    actual, expected = np.asarray(actual), np.asarray(expected)
    finite = np.isfinite(expected)
    np.testing.assert_array_equal(np.isfinite(actual), finite, err_msg=what)
    np.testing.assert_array_equal(actual[~finite], expected[~finite], err_msg=what)
    if finite.any():
        scale = max(float(np.abs(expected[finite]).max()), floor)
        np.testing.assert_allclose(actual[finite], expected[finite], rtol=0,
                                   atol=rtol * scale + 1e-300, err_msg=what)


def osc_basis(form: general.PeriodicForm) -> first_order.FirstOrderBasis:
    return form.flow.basis


def _forms(osc: ic.ImpactOscillator, N: int):
    flow = Flow(osc)
    T = 2.0 * math.pi * N / osc.omega
    return general._form_at(flow, T), general.reference_form(flow, T)


@pytest.mark.filterwarnings("ignore::impactcont.errors.IllConditionedWarning")
@pytest.mark.parametrize("name", SYSTEMS)
@pytest.mark.parametrize("N", [1, 2, 3, 4])
def test_periodic_form_matches_the_numpy_reference(name, N):
    for omega in OMEGAS:
        compiled, reference = _forms(_osc(name, omega), N)
        what = f"{name}, omega={omega}, N={N}"
        # the size of the terms each piece sums: the identity in Phi(T), the forced state
        # in E and S, order one in y (after its exact A^-1 e / T), A (y + e) in the rate
        forced = float(np.abs(reference.P0).max())
        terms = {"DPhi": 1.0, "E": forced, "S": forced, "y": 1.0,
                 "rate": float(np.abs(osc_basis(compiled).A).max()) * max(
                     1.0, float(np.abs(reference.y).max()))}
        for field in ("DPhi", "P0", "rate0", "E", "S", "y", "y_modal", "rate"):
            _close(getattr(compiled, field), getattr(reference, field), what=f"{field}: {what}",
                   floor=terms.get(field, 0.0))
        for field in ("g", "Delta"):
            _close(getattr(compiled, field), getattr(reference, field), what=f"{field}: {what}",
                   floor=1.0)
        _close(compiled.__dict__["_period_rate"], reference.__dict__["_period_rate"],
               what=f"period rate: {what}", floor=1.0)
        # the condition estimate decides the same warnings
        assert compiled.cond == pytest.approx(reference.cond, rel=1e-9), what
        assert (compiled.cond > dense.COND_WARN) == (reference.cond > dense.COND_WARN), what


def _gap(osc: ic.ImpactOscillator, N: int) -> float:
    """A gap with two roots of eq. (15): half the amplitude of ``c cos + s sin``."""
    compiled, _ = _forms(osc, N)
    return 0.5 * math.hypot(compiled.c, compiled.s)


@pytest.mark.filterwarnings("ignore::impactcont.errors.IllConditionedWarning")
@pytest.mark.filterwarnings("ignore::impactcont.errors.UnresolvedMotionWarning")
@pytest.mark.parametrize("name", SYSTEMS)
@pytest.mark.parametrize("N", [1, 2, 3, 4])
def test_motions_match_the_numpy_reference(name, N):
    for omega in OMEGAS:
        base = _osc(name, omega)
        osc = base.replace(b=_gap(base, N))
        compiled, reference = _forms(osc, N)
        found = general.roots(compiled.c, compiled.s, osc.b)
        assert len(found) == 2
        for delta, _ in found:
            got = general.orbit_values(compiled, delta)
            ref = general.reference_orbit_values(reference, delta)
            what = f"{name}, omega={omega}, N={N}, delta={delta}"
            # the velocity's own rounding estimate (either form) bounds the difference
            assert got.h2 == pytest.approx(ref.h2, rel=max(RTOL, 64 * ref.h2_error),
                                           abs=1e-300), what
            assert got.h2_error == pytest.approx(ref.h2_error, rel=1e-6, abs=1e-300), what
            _close(got.state, ref.state, what=f"state: {what}")
            assert got.velocity_scale == pytest.approx(ref.velocity_scale, rel=RTOL), what
            # G sums D Phi(T) (terms of order one) and X'(T^-) h0 / h2, omega h0 / h2
            g_terms = 1.0 + osc.omega * (1.0 + ref.velocity_scale) / abs(ref.h2)
            _close(got.G, ref.G, what=f"G: {what}", floor=g_terms)
            # eigenvalues: G's rounding, amplified at most by the spread of the eigenvector
            # basis (G is small and its eigenvalues well separated here)
            np.testing.assert_allclose(got.multipliers, ref.multipliers, rtol=0,
                                       atol=1e-9 * max(g_terms, np.abs(ref.G).max()),
                                       err_msg=what)
            x_scale = max(1.0, abs(osc.b), float(np.abs(ref.state[:osc.n]).max()))
            if math.isinf(ref.gap_min):
                assert got.gap_min == ref.gap_min, what
            else:
                assert got.gap_min == pytest.approx(ref.gap_min, abs=1e-10 * x_scale), what
                assert got.gap_min_time == pytest.approx(ref.gap_min_time,
                                                         abs=1e-6 * compiled.T), what


@pytest.mark.filterwarnings("ignore::impactcont.errors.NearResonanceWarning")
@pytest.mark.parametrize("name", SYSTEMS)
def test_forced_response_and_its_derivative_match_the_numpy_reference(name):
    for omega in (*OMEGAS, 1e-300 ** 0.5):
        osc = _osc(name, omega)
        basis = osc.first_order
        Z = basis.forced_amplitude(osc.F, omega)
        _close(Z, basis.forced_amplitude_reference(osc.F, omega), what=f"Z: {name} {omega}")
        _close(basis.forced_amplitude_derivative(Z, omega),
               basis.forced_amplitude_derivative_reference(Z, omega), what=f"dZ: {name}")


def test_resonance_is_refused_and_its_neighbourhood_warned_as_before():
    """The symmetric mode of two equal masses is undamped by the damper between them
    (``omega_1 = 1`` exactly): the compiled condition number refuses it as the numpy one
    does, and both warn next to it."""
    osc = ic.ImpactOscillator(M=np.eye(2), K=[[2.0, -1.0], [-1.0, 2.0]],
                              C=[[0.2, -0.2], [-0.2, 0.2]], F=[1.0, 0.0], R=0.6, b=0.1,
                              omega=1.5)
    basis = osc.first_order
    for forced in (basis.forced_amplitude, basis.forced_amplitude_reference):
        with pytest.raises(ic.ResonanceError, match=r"omega=1\.0 is a natural frequency"):
            forced(osc.F, 1.0)
        with pytest.warns(ic.NearResonanceWarning, match="so close to the natural"):
            forced(osc.F, 1.0 + 1e-10)


def test_periodic_orbits_evaluates_both_roots_in_one_compiled_call(monkeypatch):
    """The two motions of eq. (15) share the search tables of eq. (16): one call of the
    compiled ``orbit_values`` per ``periodic_orbits``, the second root a lookup that hands
    out its own arrays."""
    osc = _osc("joint damper", 1.0, b=0.6)
    calls = []
    original = general_kernel.orbit_values

    def counted(*args):
        calls.append(args[-2].size)
        return original(*args)

    monkeypatch.setattr(general_kernel, "orbit_values", counted)
    orbits = ic.periodic_orbits(osc, 1)
    assert len(orbits) == 2 and calls == [2]
    form = general.periodic_form(osc, 1)
    first = general.orbit_values(form, orbits[0].delta)
    again = general.orbit_values(form, orbits[0].delta)  # handed out once: computed anew
    assert calls == [2, 2, 1]
    assert first.state is not again.state
    np.testing.assert_array_equal(first.state, again.state)
    # a phase that is no root (orbit_at_phase with check=False) is evaluated alone
    assert general.orbit_values(general.periodic_form(osc, 1), 0.3).state.shape == (4,)
    assert calls[-1] == 1


def test_orbit_at_phase_and_maps_match_periodic_orbits():
    osc = _osc("grounded damper", 1.3, b=0.2)
    for orbit in ic.periodic_orbits(osc, 1):
        at = orbit_at_phase(osc, 1, orbit.delta)
        assert at.impact_velocity == orbit.impact_velocity
        np.testing.assert_array_equal(at.state, orbit.state)
        np.testing.assert_array_equal(at.multipliers, orbit.multipliers)
    form = general.periodic_form(osc, 1)
    deltas = np.array([o.delta for o in ic.periodic_orbits(osc, 1)])
    h2, mu, gap, _ = general.orbit_values_many(form, deltas, osc.b)
    for k, orbit in enumerate(ic.periodic_orbits(osc, 1)):
        assert h2[k] == orbit.impact_velocity and gap[k] == orbit.gap_min
        np.testing.assert_array_equal(mu[k], orbit.multipliers)


def test_each_entry_point_is_compiled_once():
    """Explicit argument types: the continuation, a map and the orbits call the same
    compiled functions (read-only or strided arrays would be refused, not recompiled)."""
    osc = _osc("joint damper", 1.0, b=0.6)
    ic.periodic_orbits(osc, 2)
    ic.stability_map(osc, 1, omega=np.linspace(0.8, 1.2, 3), b=np.array([0.3, 0.6]))
    ic.continuation(osc, 1, "omega", (0.9, 1.1))
    for entry in (general_kernel.forced_response, general_kernel.forced_response_derivative,
                  general_kernel.periodic_setup, general_kernel.orbit_values):
        assert len(entry.signatures) == 1, entry


def test_the_kernel_constants_are_the_reference_ones():
    assert general_kernel.VELOCITY_POLISH == dense.VELOCITY_POLISH
    assert general_kernel.VELOCITY_AGREE == dense._VELOCITY_AGREE
    np.testing.assert_array_equal(general_kernel.BERNOULLI, first_order._BERNOULLI)
    assert general_kernel.SERIES_RADIUS == first_order._SERIES_RADIUS


def test_forms_and_their_flows_are_released_when_nobody_holds_them():
    """The per-flow cache of forms held each form by a weak key that its own value (the
    form holds its flow) kept alive: every form of a process stayed in memory (1.3 MB of
    ``D Phi`` each at n = 200, thousands per branch)."""
    osc = _osc("joint damper", 1.0, b=0.6)
    orbits = ic.periodic_orbits(osc, 1)
    form = general.periodic_form(osc, 1)
    T = form.T
    # while held, the pieces kept as (flow, S, DPhi, T) find their form
    assert general._form_at(form.flow, T) is form
    dead = weakref.ref(form), weakref.ref(form.flow)
    assert len(orbits) == 2
    # the form goes with its last holder; the flow is the oscillator's (flow_of: one per
    # oscillator, shared by its motions) and goes with it
    del form
    gc.collect()
    assert dead[0]() is None
    del orbits, osc
    gc.collect()
    assert dead[1]() is None


@pytest.mark.filterwarnings("ignore::impactcont.errors.IllConditionedWarning")
@pytest.mark.parametrize("name", SYSTEMS)
def test_amplitude_is_the_forms_c_s_and_its_derivatives(name):
    """The continuation's eq. (14) (O(n), :func:`general.amplitude`) is the same sums as
    the full form's first row of S: equal, so a branch point's phase is a root of the
    form that evaluates its motion."""
    for omega in OMEGAS:
        for N in (1, 3):
            osc = _osc(name, omega)
            form = general.periodic_form(osc, N)
            assert general.amplitude(osc, N)[:2] == (form.c, form.s)
            for which in ("omega", "R"):
                _, _, dc, ds = general.amplitude(osc, N, which)
                assert (dc, ds) == general.amplitude_derivative(form.flow, form.S, form.DPhi,
                                                                form.T, which)


@pytest.mark.filterwarnings("ignore::impactcont.errors.IllConditionedWarning")
def test_a_large_system_takes_its_transition_from_blas_and_agrees():
    """From ``general_kernel.BLAS_MIN`` (2n) the form's ``D Phi(T)`` is numpy's product
    (the compiled loops cost three times BLAS at n = 200); the rest stays compiled."""
    n = general_kernel.BLAS_MIN // 2 + 3
    K = 2.0 * np.eye(n) - np.eye(n, k=1) - np.eye(n, k=-1)
    K[-1, -1] = 1.0
    C = 0.01 * K
    C[5:7, 5:7] += [[0.1, -0.1], [-0.1, 0.1]]
    F = np.zeros(n)
    F[0] = 1.0
    base = ic.ImpactOscillator(M=np.eye(n), K=K, C=C, F=F, R=0.6, b=0.0, omega=0.7)
    osc = base.replace(b=_gap(base, 1))
    compiled, reference = _forms(osc, 1)
    _close(compiled.DPhi, reference.DPhi, floor=1.0, what="DPhi")
    _close(compiled.S, reference.S, floor=float(np.abs(reference.P0).max()), what="S")
    for delta, _ in general.roots(compiled.c, compiled.s, osc.b):
        got = general.orbit_values(compiled, delta)
        ref = general.reference_orbit_values(reference, delta)
        assert got.h2 == pytest.approx(ref.h2, rel=1e-10)
        _close(got.state, ref.state, rtol=1e-10)
        assert got.gap_min == pytest.approx(ref.gap_min, abs=1e-9)
