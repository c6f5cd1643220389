"""The velocity-polished path of :mod:`impactcont.orbit.periodic` builds G and the
multipliers on access only (issue 29, item 8).

Far above the lowest natural frequency the kernel's impact velocity loses digits and
the motion is re-evaluated with the impact-condition form (``_repolish``). That path
used to compute the dense eigenvalues of G inside every :func:`periodic_orbits` call,
O(n^3): a chain's call went from milliseconds at n = 1900 to 80 s at n = 2000 (where the
polish starts for the test chain). Here the dense routines are made to raise while the
motions are found, and the values on access are those of the dense path as before.
"""

from __future__ import annotations

import warnings

import numpy as np
import pytest

import impactcont as ic
from impactcont.kernel import stability
from impactcont.orbit import periodic, secular


def _paper(omega: float) -> ic.ImpactOscillator:
    return ic.ImpactOscillator(M=np.eye(2), K=[[1.0, -1.0], [-1.0, 2.0]], F=[1.0, 0.0],
                               R=0.6, b=0.0, omega=omega, eta=0.1)


def _distance(a: np.ndarray, b: np.ndarray) -> float:
    """Largest distance between matched members of two sets of multipliers."""
    from scipy.optimize import linear_sum_assignment

    cost = np.abs(a[:, None] - b[None, :])
    rows, cols = linear_sum_assignment(cost)
    return float(cost[rows, cols].max())


def _counted_repolish(monkeypatch) -> list:
    calls = []
    original = periodic._repolish

    def counted(*args, **kwargs):
        calls.append(args[3])  # the phase
        return original(*args, **kwargs)

    monkeypatch.setattr(periodic, "_repolish", counted)
    return calls


def _refuse_dense(monkeypatch) -> None:
    def refuse(*args, **kwargs):
        raise AssertionError("G or its dense eigenvalues computed while finding the motions")

    monkeypatch.setattr(stability, "multipliers", refuse)
    monkeypatch.setattr(periodic, "modal_jacobian", refuse)


@pytest.mark.parametrize("system", ["paper", "chain"])
def test_polished_motions_leave_G_and_multipliers_to_access(system, monkeypatch, make_chain):
    """A polished root (n = 2 and n = 48, at or above ``SECULAR_MIN``) is found without G
    or a dense eigenvalue solve; on access G is the one with the polished velocity as its
    pole (what the eager path stored), the multipliers its dense eigenvalues (n = 2) or
    the secular ones within the secular path's tolerance of them (n = 48)."""
    osc = _paper(300.0) if system == "paper" else make_chain(48, omega=100.0, b=0.0)
    calls = _counted_repolish(monkeypatch)
    _refuse_dense(monkeypatch)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        orbits = ic.periodic_orbits(osc, 1)
        again = [periodic.orbit_at_phase(osc, 1, o.delta, root=o.root) for o in orbits]
    assert calls, "no root took the polished path: the test does not test it"
    polished = [o for o in orbits if o.delta in calls]
    assert polished
    monkeypatch.undo()
    for orbit in polished + again:
        assert "G" not in orbit.__dict__ and "multipliers" not in orbit.__dict__
        G = periodic.modal_jacobian(osc, orbit.modal, orbit.delta, orbit.impact_velocity)[0]
        np.testing.assert_array_equal(orbit.G, G)
        mu = stability.multipliers(G)
        assert np.all(np.isfinite(orbit.multipliers))
        if osc.n < secular.SECULAR_MIN:  # the dense eigenvalues of G, as before
            np.testing.assert_array_equal(orbit.multipliers, mu)
        else:  # the secular function with the polished velocity as its pole
            assert _distance(orbit.multipliers, mu) <= 1e-11 * max(1.0, abs(mu[0]))
    for orbit, at in zip(orbits, again, strict=True):
        assert at.impact_velocity == orbit.impact_velocity
        np.testing.assert_array_equal(at.state, orbit.state)
