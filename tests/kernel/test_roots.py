"""The roots of eq. (12)-(15) (:mod:`impactcont.kernel.roots`): polished roots and the
Taylor values of ``x1`` at the contact search's candidates are exact (against the dense
path)."""

from __future__ import annotations

import numpy as np
import pytest

import impactcont as ic
from impactcont.kernel import closed_form, contact, roots
from impactcont.orbit import periodic


@pytest.mark.parametrize("omega, b, N",
                         [(0.8, 0.3, 2), (0.6, 0.5, 2), (1.25, 0.3, 1), (0.45, 0.2, 3)])
def test_polish_roots_and_taylor_values_are_exact(omega, b, N):
    """Every root the interior-contact search polishes (of x1' for maxima, of x1'' for the
    cells it splits) agrees with bisection to rounding, and the values it returns from
    its last Taylor step agree with a direct evaluation at the root."""
    from scipy.optimize import brentq

    osc = ic.ImpactOscillator(M=np.eye(2), K=[[1.0, -1.0], [-1.0, 2.0]], F=[1.0, 0.0], R=0.6,
                              b=b, omega=omega, eta=0.1)
    arrays = periodic.modal_arrays(osc)
    w, a, f, eig_err, u0, ui0 = arrays.w, arrays.a, arrays.f, arrays.eig_err, arrays.u0, arrays.ui0
    modal, sc = closed_form.omega_setup(w, a, f, u0, ui0, eig_err, osc.R, omega, N)
    count, dl, sg, _, _ = roots.orbit_roots(sc, b, omega, osc.R)
    assert count > 0
    times, _, _, _, _, dy, dv, _ = contact.flight_tables(w, a, u0, modal, omega, sc[0])
    checked = 0
    for k in range(count):
        ks = (1.0 + osc.R) * sg[k]
        args = (sc[1], sc[2], omega, dl[k], ks, w, a, u0, dy, dv)

        def d(t, args=args):
            return contact.x1_derivatives(t, *args)

        for order in (1, 2):
            g = np.array([d(t)[order] for t in times])
            for j in np.flatnonzero(np.sign(g[:-1]) * np.sign(g[1:]) < 0):
                lo, hi = times[j], times[j + 1]
                e_lo, e_hi = d(lo), d(hi)
                snap = [contact._x1_derivs(t, *args)[4] for t in (lo, hi)]
                ddg = (e_lo[3], e_hi[3]) if order == 1 else tuple(snap)
                r, x, v, acc, jerk = contact._polish(
                    np.int64(order), lo, hi, e_lo[order], e_hi[order], e_lo[order + 1],
                    e_hi[order + 1], ddg[0], ddg[1], *args)
                ref = brentq(lambda t, o=order: d(t)[o], lo, hi, xtol=1e-15, rtol=1e-15)
                assert abs(r - ref) <= 1e-13 * max(1.0, ref)
                direct = d(r)
                # the difference is rounding of sums of modal terms (up to 0.77 of 1e-13 here,
                # above it for 7.5 % of omegas within 100 ulp): 1e-12 of the bracket's scale
                scale = np.max(np.abs(np.array([d(t) for t in (lo, hi)])), axis=0)
                assert np.all(np.abs(np.array([x, v, acc, jerk]) - direct) <= 1e-12 * scale)
                checked += 1
    assert checked >= 4
