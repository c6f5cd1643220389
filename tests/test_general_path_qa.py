"""A user's first hour with the first-order path (damping matrix C, complex F): the
problems found by trying the public API, each with its witness.

- refusals that named the wrong cause (C = 0 given as a matrix with R = 1; a critically
  damped proportional C that is on the first-order path only because F is complex);
- continuation in ``eta``/``alpha``/``beta`` with a complex F (an internal error);
- robust stability varying ``"F[i]"`` of a complex F (the entry's phase was dropped);
"""

from __future__ import annotations

import numpy as np
import pytest

import impactcont as ic
from impactcont.errors import ParameterError

K2 = np.array([[1.0, -1.0], [-1.0, 2.0]])


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
