"""The bases an oscillator shares with those ``replace`` makes from it (issue 20).

The first-order basis (M, K, C) and the modal basis (M, K, damping, F) are eigen-
decompositions: a continuation in a parameter they do not depend on computes them once,
and a change of a parameter they do depend on gets its own.
"""

from __future__ import annotations

import functools

import numpy as np
import pytest

import impactcont as ic
from impactcont.model.first_order import FirstOrderBasis
from impactcont.model.modal import ModalBasis

K2 = np.array([[1.0, -1.0], [-1.0, 2.0]])


def _damper_on_mass1() -> ic.ImpactOscillator:
    """n = 2, a non-proportional C: the first-order path."""
    return ic.ImpactOscillator(M=np.diag([1.0, 1.5]), K=K2, C=[[0.3, 0.0], [0.0, 0.02]],
                               F=[1.0, 0.0], R=0.6, b=0.3, omega=1.0)


def _proportional() -> ic.ImpactOscillator:
    return ic.ImpactOscillator(M=np.diag([1.0, 1.5]), K=K2, eta=0.02, F=[1.0, 0.0], R=0.6,
                               b=0.3, omega=1.0)


def _count(monkeypatch: pytest.MonkeyPatch, cls: type) -> list[int]:
    """Count the calls of ``cls.from_matrices`` (one per eigen-decomposition)."""
    calls = [0]
    original = cls.from_matrices.__func__

    def counting(klass, *args, **kwargs):
        calls[0] += 1
        return original(klass, *args, **kwargs)

    monkeypatch.setattr(cls, "from_matrices", classmethod(counting))
    return calls


def _without_reuse(monkeypatch: pytest.MonkeyPatch) -> None:
    """The first-order basis cached per oscillator only (as before issue 20)."""
    def first_order(self):
        return FirstOrderBasis.from_matrices(self.M, self.K, self.C)

    prop = functools.cached_property(first_order)
    prop.__set_name__(ic.ImpactOscillator, "first_order")
    monkeypatch.setattr(ic.ImpactOscillator, "first_order", prop)


@pytest.mark.parametrize("parameter, bounds", [("omega", (1.0, 1.5)), ("b", (0.2, 0.4)),
                                               ("R", (0.5, 0.7)), ("F0", (0.8, 1.2))])
def test_first_order_branch_decomposes_once(monkeypatch, parameter, bounds):
    calls = _count(monkeypatch, FirstOrderBasis)
    branch = ic.continuation(_damper_on_mass1(), 1, parameter, bounds)
    assert branch.sizes["point"] > 10
    assert calls[0] == 1  # was one per evaluated point (1591 for omega)


def test_reuse_leaves_the_branch_unchanged(monkeypatch):
    osc = _damper_on_mass1()
    shared = ic.continuation(osc, 1, "omega", (1.0, 1.5))
    calls = _count(monkeypatch, FirstOrderBasis)
    _without_reuse(monkeypatch)
    own = ic.continuation(_damper_on_mass1(), 1, "omega", (1.0, 1.5))
    assert calls[0] > shared.sizes["point"]  # the switch did disable the reuse
    for name in ("omega", "delta", "impact_velocity"):
        np.testing.assert_array_equal(shared[name].values, own[name].values)


def test_damping_branch_reuses_the_eigensolve_with_its_own_decay_rates(monkeypatch):
    calls = _count(monkeypatch, ModalBasis)
    branch = ic.continuation(_proportional(), 1, "eta", (0.01, 0.05))
    assert branch.sizes["point"] > 10
    assert calls[0] == 1  # K u = lambda M u does not depend on eta
    osc = _proportional()
    moved = osc.replace(omega=1.2).replace(eta=0.04)
    assert moved.modes is not osc.modes
    fresh = ic.ImpactOscillator(M=np.diag([1.0, 1.5]), K=K2, eta=0.04, F=[1.0, 0.0], R=0.6,
                                b=0.3, omega=1.2)
    np.testing.assert_allclose(moved.modes.decay_rates, fresh.modes.decay_rates, rtol=1e-13)
    assert moved.first_order is not osc.first_order  # C = 2 eta K moved
    np.testing.assert_allclose(moved.first_order.C, fresh.C, rtol=1e-15)


@pytest.mark.parametrize("change", [
    {"K": 1.5 * K2}, {"M": np.diag([1.0, 2.0])}, {"C": [[0.2, 0.0], [0.0, 0.05]]},
    {"eta": 0.05}, {"alpha": 0.1, "beta": 0.01}])
def test_a_structural_change_gets_its_own_first_order_basis(change):
    osc = _damper_on_mass1()
    first = osc.first_order
    new = osc.replace(**change)
    assert new.first_order is not first
    fresh = FirstOrderBasis.from_matrices(new.M, new.K, new.C)
    np.testing.assert_allclose(new.first_order.eigenvalues, fresh.eigenvalues, rtol=1e-13)
    np.testing.assert_array_equal(new.first_order.C, new.C)
    assert osc.first_order is first  # the original keeps its own


@pytest.mark.parametrize("change", [{"omega": 1.3}, {"b": 0.1}, {"R": 0.9}, {"F0": 2.0},
                                    {"F": [0.0, 1.0 + 1.0j]},
                                    {"stops": {"b_low": 0.5, "R_low": 0.5}}])
def test_parameters_outside_the_matrices_share_the_first_order_basis(change):
    osc = _damper_on_mass1()
    new = osc.replace(**change)
    assert new.first_order is osc.first_order  # computed once, by whichever asks first
    assert osc.replace(**change).replace(omega=2.0).first_order is osc.first_order


def test_modes_follow_the_forcing_and_stay_for_the_rest():
    osc = _proportional()
    for change in ({"omega": 1.3}, {"b": 0.1}, {"R": 0.9},
                   {"stops": {"b_low": 0.5, "R_low": 0.5}}):
        assert osc.replace(**change).modes is osc.modes
    for change in ({"F": [0.0, 1.0]}, {"F0": 2.0}):
        new = osc.replace(**change)
        np.testing.assert_allclose(new.modes.modal_forces, ModalBasis.from_matrices(
            new.M, new.K, *new.rayleigh, new.F).modal_forces, rtol=1e-13, atol=1e-15)


# -- free modes that C leaves undamped (issue 30, item 5) ----------------------------------------
def _mp_expm(A: np.ndarray, t: float) -> np.ndarray:
    """exp(A t) to 40 digits (mpmath's Pade/scaling, independent of the basis)."""
    import mpmath

    with mpmath.workdps(40):
        out = mpmath.expm(mpmath.matrix(A.tolist()) * t)
        return np.array(out.tolist(), dtype=float)


# undamped free (masses 2, 3), damped free (mass 4), held non-proportional (mass 1 on a spring)
_M4 = np.diag([1.0, 0.3, 0.5, 0.7])
_K4 = np.diag([2.0, 0.0, 0.0, 0.0])
_C4 = np.diag([0.1, 0.0, 0.0, 0.05])
_CHAIN = (np.diag([1.0, 0.5, 0.2]), np.array([[2.0, -1.0, 0.0], [-1.0, 1.0, 0.0], [0.0, 0.0, 0.0]]),
          np.diag([0.1, 0.0, 0.0]))  # a two-mass primary, a dashpot on mass 1, a free ball


@pytest.mark.parametrize("matrices", [(_M4, _K4, _C4), _CHAIN], ids=["two-undamped-one-damped",
                                                                     "ball-on-a-chain"])
def test_undamped_free_modes_are_jordan_chains_and_the_flow_is_exact(matrices):
    """A free mode C leaves undamped (C u = 0) was refused ('unless C damps every free
    mode'); now its Jordan chain [u; 0], [0; u] carries it: A V = V (diag(lambda) + J),
    V^-1 V = I, N = [[0, U U^T M], [0, 0]] with N^2 = 0, and Phi(t) = exp(A t) to rounding
    against 40 digits (the polynomial part grows linearly: t up to 200)."""
    M, K, C = matrices
    basis = FirstOrderBasis.from_matrices(M, K, C)
    n = M.shape[0]
    gen = np.flatnonzero(basis.generalized)
    undamped = [i for i in range(n) if K[i, i] == 0.0 and C[i, i] == 0.0]
    assert gen.size == len(undamped)
    lam, V, Vi = basis.eigenvalues, basis.V, basis.V_inv
    J = np.diag(lam)
    J[gen - 1, gen] = 1.0  # the eigenvector [u; 0] is the column before [0; u]
    np.testing.assert_allclose(basis.A @ V, V @ J, rtol=0, atol=1e-14 * np.abs(basis.A).max())
    np.testing.assert_allclose(Vi @ V, np.eye(2 * n), rtol=0, atol=1e-14)
    U = np.eye(n)[:, undamped] / np.sqrt(np.diag(M)[undamped])
    N = np.zeros((2 * n, 2 * n))
    N[:n, n:] = U @ U.T @ M
    np.testing.assert_allclose(basis.nilpotent, N, rtol=0, atol=1e-15)
    assert not np.any(basis.nilpotent @ basis.nilpotent)
    for t in (0.0, 0.37, 4.1, 200.0):
        ref = _mp_expm(basis.A, t)
        np.testing.assert_allclose(basis.transition(t), ref, rtol=0,
                                   atol=1e-14 * max(1.0, np.abs(ref).max()))
    # the contact search's pairs: each chain one pair y0 + v0 t (w = a = 0)
    w, a, k, j = basis.scalar_pairs
    assert sorted(j[: gen.size].tolist()) == gen.tolist()
    assert np.all(w[: gen.size] == 0.0) and np.all(a[: gen.size] == 0.0)
    assert sorted(np.concatenate([k, j]).tolist()) == list(range(2 * n))


def test_undamped_free_mode_builds_and_bad_damping_is_still_refused():
    """The impact damper's usual layout (a dashpot on the primary, none on the ball) builds
    on the first-order path; a C that is not positive semi-definite is still refused at
    construction, naming C and what is allowed."""
    base = dict(M=np.diag([1.0, 0.2]), K=np.diag([1.0, 0.0]), F=[1.0, 0.0], R=0.6, b=0.3,
                omega=0.9, stops=ic.Stops(mass=2, relative_to=1, mirror=True))
    osc = ic.ImpactOscillator(**base, C=[[0.04, 0.0], [0.0, 0.0]])
    assert osc.general and osc.first_order.polynomial
    with pytest.raises(ic.ParameterError, match=r"C must be positive semi-definite"):
        ic.ImpactOscillator(**base, C=[[-0.04, 0.0], [0.0, -0.01]])
