"""Multipliers from the secular function against the dense eigenvalues of G (eq. 25).

The dense path forms G from the physical transition matrix and calls LAPACK; the
secular path never forms G (2 x 2 determinant of modal sums, Aberth iteration).
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
import textwrap
import warnings

import numpy as np
import pytest

import impactcont as ic
from impactcont.kernel import closed_form, stability
from impactcont.orbit import secular
from impactcont.orbit.periodic import modal_arrays
from tests.kernel.test_closed_form import DAMPING, _random_oscillator


def _secular(orbit: ic.PeriodicOrbit) -> tuple[np.ndarray, bool]:
    osc = orbit.oscillator
    arrays = modal_arrays(osc)
    w, a, f, u0, ui0 = arrays.w, arrays.a, arrays.f, arrays.u0, arrays.ui0
    return secular.secular_multipliers(orbit.modal, w, a, f, u0, ui0, osc.omega, osc.R,
                                       orbit.delta, orbit.impact_velocity)


def _distance(mu: np.ndarray, reference: np.ndarray) -> float:
    """Largest distance from a multiplier of either set to the nearest of the other."""
    d = np.abs(mu[:, None] - reference[None, :])
    return float(max(d.min(axis=0).max(), d.min(axis=1).max()))


def _chain(n: int, omega: float = 1.1, **damping: float) -> ic.ImpactOscillator:
    F = np.zeros(n)
    F[0] = 1.0
    return ic.ImpactOscillator.chain(masses=np.ones(n), springs=np.ones(n), F=F, R=0.7, b=0.1,
                                     omega=omega, **(damping or {"eta": 0.05}))


@pytest.mark.parametrize("damping", list(DAMPING))
def test_secular_multipliers_match_dense_eigenvalues(damping):
    rng = np.random.default_rng(77 + len(damping))
    checked = accepted = 0
    for n in (1, 2, 3, 5, 8, 12):
        for _ in range(5):
            osc = _random_oscillator(rng, n, DAMPING[damping])
            with warnings.catch_warnings():
                warnings.simplefilter("ignore", ic.IllConditionedWarning)
                orbits = ic.periodic_orbits(osc, 1)
            for orbit in orbits:
                mu, ok = _secular(orbit)
                dense = stability.multipliers(orbit.G)
                checked += 1
                if not ok:  # refused by the guard: the dense path takes over
                    continue
                accepted += 1
                assert mu.shape == dense.shape
                # clusters of tiny multipliers (over-damped modes) reach 0.5e-12 under 1-ulp
                # changes of the inputs: compare at 1e-11
                assert _distance(mu, dense) <= 1e-11 * max(1.0, abs(dense[0]))
                assert abs(abs(mu[0]) - abs(dense[0])) <= 1e-11 * max(1.0, abs(dense[0]))
                # exact conjugate pairs, as from LAPACK
                assert _distance(mu, np.conj(mu)) == 0.0
    assert checked >= 6
    assert accepted >= 0.75 * checked  # refused: clusters of tiny roots (over-damped)


@pytest.mark.parametrize("n", [40, 80])
@pytest.mark.parametrize("damping", [{"eta": 0.05}, {"alpha": 0.05, "beta": 0.02}, {}])
def test_large_chain_uses_the_secular_path_and_matches_dense(n, damping):
    osc = _chain(n, **damping)
    orbits = ic.periodic_orbits(osc, 1)
    assert orbits
    for orbit in orbits:
        mu, ok = _secular(orbit)
        assert ok
        np.testing.assert_array_equal(orbit.multipliers, mu)  # what the orbit reports
        dense = stability.multipliers(orbit.G)
        assert _distance(mu, dense) <= 1e-11 * max(1.0, abs(dense[0]))
        assert orbit.stable == (abs(dense[0]) < 1.0)


def test_power_sum_guard_catches_a_missing_or_moved_root():
    orbit = ic.periodic_orbits(_chain(20), 1)[0]
    osc = orbit.oscillator
    arrays = modal_arrays(osc)
    w, a, f, u0, ui0 = arrays.w, arrays.a, arrays.f, arrays.u0, arrays.ui0
    pieces = closed_form.jacobian_pieces(orbit.modal, w, a, f, ui0, osc.omega, osc.R, orbit.delta,
                                    orbit.impact_velocity)
    *_, h2, xn = secular.secular_coefficients(orbit.modal, u0, ui0, osc.omega, osc.R,
                                              *pieces)
    traces = secular.power_sums(orbit.modal, u0, ui0, osc.omega, osc.R, *pieces, h2, xn)
    mu = orbit.multipliers
    assert secular.power_sums_agree(mu, *traces)
    np.testing.assert_allclose(traces[:2], [np.trace(orbit.G), np.trace(orbit.G @ orbit.G)],
                               rtol=1e-12, atol=1e-13)
    dropped = mu.copy()
    dropped[3] = 0.0
    assert not secular.power_sums_agree(dropped, *traces)
    moved = mu.copy()
    moved[0] *= 1.0 + 1e-6
    assert not secular.power_sums_agree(moved, *traces)


def test_orbit_falls_back_to_dense_eigenvalues_when_the_guard_refuses(monkeypatch):
    orbit = ic.periodic_orbits(_chain(20), 1)[0]
    dense = stability.multipliers(orbit.G)
    monkeypatch.setattr(secular, "secular_multipliers",
                        lambda *args: (np.zeros(40, dtype=complex), False))
    np.testing.assert_array_equal(orbit.multipliers, dense)


def test_heavily_damped_chain_matches_high_precision_eigenvalues():
    """Over-damped modes: their fast multipliers (below eps) are exact zeros of the
    secular polynomial; left in they made a ring of 1e-8 spurious multipliers."""
    mpmath = pytest.importorskip("mpmath")
    orbit = ic.periodic_orbits(_chain(16, eta=3.0), 1)[0]
    mu, ok = _secular(orbit)
    assert ok
    mpmath.mp.dps = 40
    exact = np.array([complex(e) for e in mpmath.eig(mpmath.matrix(orbit.G.tolist()),
                                                     left=False, right=False)])
    assert _distance(mu, exact) <= 1e-13 * abs(exact).max()


# -- the numpy secular path: no second compile wave, the threshold, the sweeps ------------
# The four verbs once on the paper's 2-DOF system (studies/performance/first_use.py), then
# the first orbit with its stability at n = 16, 50 and 200; the numba events of each stage.
# "numba:compiler_lock" is entered by every compile and every load from the disk cache,
# "numba:compile" by compiles only (so a warm cache cannot hide a second wave).
_FIRST_WAVE_THEN_LARGE = textwrap.dedent("""
    import json
    import numpy as np
    from numba.core import event
    import impactcont as ic

    class Count(event.Listener):
        def __init__(self):
            self.names, self.locks = [], 0
        def on_start(self, ev):
            if ev.kind == "numba:compile":
                self.names.append(ev.data["dispatcher"].py_func.__qualname__)
            else:
                self.locks += 1
        def on_end(self, ev):
            pass

    count = Count()
    event.register("numba:compile", count)
    event.register("numba:compiler_lock", count)
    osc = ic.ImpactOscillator(M=np.eye(2), K=[[1.0, -1.0], [-1.0, 2.0]], F=[1.0, 0.0],
                              eta=0.05, R=0.8, b=0.5, omega=1.2)
    ic.periodic_orbits(osc, 1)
    branch = ic.continuation(osc, N=1, parameter="omega", bounds=(0.5, 3.0))
    ic.curve(None, kind=str(branch.special_label.values[0]), start=branch, special=0,
             max_points=20, bounds={"omega": (0.5, 3.0), "b": (0.0, 1.5)})
    ic.stability_map(osc, N=1, omega=np.linspace(1.0, 1.6, 20), b=np.linspace(0.1, 0.8, 20))
    out = {}
    for n in (16, 50, 200):
        K = 2.0 * np.eye(n) - np.eye(n, k=1) - np.eye(n, k=-1)
        K[-1, -1] = 1.0
        F = np.zeros(n)
        F[0] = 1.0
        big = ic.ImpactOscillator(M=np.eye(n), K=K, F=F, eta=0.05, R=0.8, b=0.5, omega=1.2)
        names, locks = len(count.names), count.locks
        orbits = ic.periodic_orbits(big, 1)
        stable = [o.stable for o in orbits]
        out[n] = {"orbits": len(orbits), "finite": bool(all(np.isfinite(o.multipliers).all()
                                                            for o in orbits)),
                  "compiled": count.names[names:], "cache_or_compile": count.locks - locks}
    print(json.dumps(out))
""")


def test_first_large_orbits_after_the_four_verbs_compile_nothing():
    env = dict(os.environ, OPENBLAS_NUM_THREADS="1")
    run = subprocess.run([sys.executable, "-c", _FIRST_WAVE_THEN_LARGE], capture_output=True,
                         text=True, env=env, timeout=900, check=False)
    assert run.returncode == 0, run.stderr[-3000:]
    out = json.loads(run.stdout.strip().splitlines()[-1])
    for n in ("16", "50", "200"):
        assert out[n]["orbits"] >= 1 and out[n]["finite"], out[n]
        assert out[n]["compiled"] == [], f"n = {n}: compiled {out[n]['compiled']}"
        # not even a load from numba's disk cache: nothing numba-compiled is new here
        assert out[n]["cache_or_compile"] == 0, f"n = {n}: {out[n]}"


def test_secular_module_holds_no_compiled_function():
    """The path a large orbit takes is plain numpy (numba compiles at the first call)."""
    import numba.core.dispatcher

    compiled = [name for name, value in vars(secular).items()
                if isinstance(value, numba.core.dispatcher.Dispatcher)]
    assert compiled == []


def _kinds(orbit: ic.PeriodicOrbit) -> np.ndarray:
    """How many modal multipliers each mode keeps (2, or 1 / 0 below ``DEAD``)."""
    osc = orbit.oscillator
    arrays = modal_arrays(osc)
    pieces = secular.jacobian_pieces(orbit.modal, arrays.w, arrays.a, arrays.f, arrays.ui0,
                                     osc.omega, osc.R, orbit.delta, orbit.impact_velocity)
    return secular.secular_coefficients(orbit.modal, arrays.u0, arrays.ui0, osc.omega, osc.R,
                                        *pieces)[1]


def _check_against_lapack(orbit: ic.PeriodicOrbit, tol: float, refusal: bool = False) -> None:
    mu, ok = _secular(orbit)
    dense = stability.multipliers(orbit.G)
    scale = max(1.0, abs(dense[0]))
    if refusal and not ok:  # the guard's refusal: the orbit reports G's dense eigenvalues
        assert _distance(orbit.multipliers, dense) <= tol * scale
        return
    assert ok
    assert mu.shape == dense.shape
    assert _distance(mu, dense) <= tol * scale
    assert abs(abs(mu[0]) - abs(dense[0])) <= tol * scale
    assert _distance(mu, np.conj(mu)) == 0.0  # exact conjugate pairs
    # what the orbit reports: these, or G's dense eigenvalues where the orbit formed G
    assert _distance(orbit.multipliers, dense) <= tol * scale


@pytest.mark.parametrize("factor", [1, 2])
@pytest.mark.parametrize("damping", [{"eta": 0.05}, {"alpha": 0.05, "beta": 0.02},
                                     {"eta": 3.0}, {"alpha": 6.0, "beta": 0.0}])
@pytest.mark.parametrize("omega", [1.1, 2.5])
def test_multipliers_match_lapack_at_the_threshold_and_twice_it(factor, damping, omega):
    n = factor * secular.SECULAR_MIN
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", ic.IllConditionedWarning)
        orbits = ic.periodic_orbits(_chain(n, omega, **damping), 1)
    assert orbits
    for orbit in orbits:
        over_damped = damping.get("eta") == 3.0
        if over_damped:  # multipliers below DEAD set apart; a cluster of tiny ones may be
            assert (_kinds(orbit) < 2).any()  # refused by the guard (docs/kernel.md)
        _check_against_lapack(orbit, 1e-12, refusal=over_damped)


def test_over_damped_200_chain_cluster_is_resolved():
    """200 masses, eta = 3: 130 modes keep one multiplier, and 70 modes' multipliers
    crowd near 0.383. The compiled Gauss-Seidel iteration took a root there as stagnant
    while the largest one (-143.6) still moved, and returned multipliers 2.6e-8 off
    (1.8e-10 of the largest), accepted by its guard; now 1e-13."""
    orbit = next(o for o in ic.periodic_orbits(_chain(200, 1.1, eta=3.0), 1) if o.root == -1)
    assert (_kinds(orbit) == 1).sum() > 100
    _check_against_lapack(orbit, 1e-12)


def test_over_damped_chain_with_a_root_on_a_modal_multiplier():
    """40 masses of random size, eta = 2 (20 modes keep one multiplier): a root lands
    exactly on a kept modal multiplier, a pole of the secular function. The compiled
    version raised ZeroDivisionError there (``orbit.multipliers`` and ``orbit.stable``
    with it); the root is now taken as found."""
    rng = np.random.default_rng(6)
    n = 40
    osc = ic.ImpactOscillator.chain(masses=0.5 + rng.random(n), springs=0.5 + rng.random(n),
                                    F=np.eye(n)[0], R=0.7, b=0.0, omega=1.4, eta=2.0)
    orbit = next(o for o in ic.periodic_orbits(osc, 1) if o.root == 1)
    assert (_kinds(orbit) == 1).sum() == 20
    _check_against_lapack(orbit, 1e-12)
    assert orbit.stable == (abs(stability.multipliers(orbit.G)[0]) < 1.0)


def test_noise_limited_roots_are_refused():
    """A 12-DOF system over-damped by ``alpha = 6``: at omega = 0.9 every multiplier is
    between 1e-11 and 5e-8, at the noise floor of the secular function. Its roots stop
    moving 1e-10 from LAPACK's (which mpmath confirms to 2e-23) and passed the power sums;
    the path refuses them now (``_NOISE_OK``: the orbit takes the dense eigenvalues) and
    agrees with LAPACK to 1e-12 wherever it accepts."""
    rng = np.random.default_rng(42)
    n = 12
    A = rng.standard_normal((n, n))
    found = 0
    for omega in (0.5, 0.9, 1.7):
        osc = ic.ImpactOscillator(M=np.diag(0.5 + rng.random(n)), K=A @ A.T + n * np.eye(n),
                                  F=rng.standard_normal(n), R=0.6, b=0.0, omega=omega,
                                  alpha=6.0, beta=0.0)
        for orbit in ic.periodic_orbits(osc, 1):
            dense = stability.multipliers(orbit.G)
            if abs(dense[0]) > 1e-6:
                continue
            found += 1
            mu, ok = _secular(orbit)
            assert not ok or _distance(mu, dense) <= 1e-12
    assert found


@pytest.mark.parametrize("damping", [{"eta": 0.05}, {"eta": 3.0}])
def test_roots_swept_in_blocks_give_the_same_multipliers(monkeypatch, damping):
    """Large systems sweep their roots in blocks (scratch bounded by ``_BLOCK``: an
    n = 2000 chain needed 0.5 GB in one block); blocks of 32 roots here."""
    orbit = ic.periodic_orbits(_chain(2 * secular.SECULAR_MIN, **damping), 1)[0]
    whole, ok_whole = _secular(orbit)
    monkeypatch.setattr(secular, "_BLOCK", 1)  # 32 roots per block, the least
    blocks, ok_blocks = _secular(orbit)
    assert ok_whole and ok_blocks
    assert 2 * orbit.oscillator.n > 32  # more than one block
    assert _distance(blocks, whole) <= 1e-13 * max(1.0, abs(whole[0]))
    _check_against_lapack(orbit, 1e-12)


@pytest.mark.parametrize("damping", [{"eta": 0.05}, {"eta": 3.0}, {}])
def test_numpy_pieces_match_the_kernel(damping):
    """The numpy ingredients of G (the secular path computes them itself so that it
    compiles nothing) against the compiled kernel's."""
    orbit = ic.periodic_orbits(_chain(24, **damping), 1)[0]
    osc = orbit.oscillator
    arrays = modal_arrays(osc)
    args = (orbit.modal, arrays.w, arrays.a, arrays.f, arrays.ui0, osc.omega, osc.R,
            orbit.delta, orbit.impact_velocity)
    for mine, kernel in zip(secular.jacobian_pieces(*args), closed_form.jacobian_pieces(*args),
                            strict=True):
        np.testing.assert_allclose(mine, kernel, rtol=0, atol=1e-13 * np.abs(kernel).max())
