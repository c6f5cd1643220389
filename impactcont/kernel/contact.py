"""The interior-contact check of eq. (16): the highest maximum of x1 between two impacts.

After an impact at phase ``delta`` with velocity ``sigma`` the displacement of the
impacting mass is ``x1(t) = x1p(t + delta / omega) + kappa sigma K(t)``: a harmonic
forced part and a free part ``K(t)`` that depends on the frequency only. The free
part is tabulated once per frequency on a grid of at least 16 cells per fastest
period seen by the mass (:func:`time_grid`, :func:`free_on_grid`, the semigroup
recurrence of eq. 9); every root and gap then reuses it. :func:`x1_maximum` brackets
the maxima cell by cell, bounds each by the tangents of a concave piece and polishes
in decreasing order of the bound (safeguarded Newton from a quintic Hermite start),
so the motion crosses the stop between impacts iff the maximum exceeds b (eq. 16).

A constant force that pushes a free mode the stop coordinate sees adds a polynomial in
time to the free part (:func:`drift_x1`: ``g t^2 / 2`` undamped, the drift
``g t^2 phi(2at) / 2`` damped, a linear drift ``d t`` on the first-order flow):
:func:`drift_on_grid` adds it to the tabulated free part and :func:`stop_maximum` to every
evaluation of the polish, so the grid's values, slopes and curvatures, the tangent bounds
and the Newton steps all see the whole coordinate.
"""

from __future__ import annotations

import math

import numpy as np

from impactcont.kernel.flights import mode_transfer
from impactcont.kernel.jit import entry as _jit
from impactcont.kernel.jit import inner as _inner

__all__ = ["WORK_ROWS", "drift_on_grid", "drift_x1", "flight_tables", "free_on_grid",
           "free_x1", "other_maximum", "stop_maximum", "time_grid", "x1_derivatives",
           "x1_maximum"]


_EPS = 2.220446049250313e-16
_CELLS_PER_PERIOD = 16
_MAX_SAMPLES = 2_000_000
_XTOL = 1e-15
_RTOL = 4.0 * _EPS
_MAX_ITER = 200
_END_TOL = 1e-12  # critical points this close (relative to T) to an impact are the impact


# -- the interior-contact check of eq. (16) --------------------------------------------------
@_jit
def time_grid(w, a, u0, omega, T):
    """Times on [0, T], each cell at most 1/16 of the fastest period seen by mass 1.

    With a geometric refinement near 0 for fast over-damped decays (as
    :func:`impactcont.orbit.extrema.sample_times`). Returns ``(times, capped)``.
    """
    rate = omega
    decay = 0.0
    for i in range(w.size):
        if u0[i] == 0.0:
            continue
        d = (w[i] - a[i]) * (w[i] + a[i])
        if d > 0.0:
            rate = max(rate, math.sqrt(d))
        fast = a[i] + (math.sqrt(-d) if d < 0.0 else 0.0)
        decay = max(decay, fast)
    h = 2.0 * math.pi / (_CELLS_PER_PERIOD * rate)
    count = max(math.ceil(T / h), 8)
    capped = count > _MAX_SAMPLES
    if capped:
        count = _MAX_SAMPLES
    cell = T / count
    extra = 0
    if decay > 0.0:
        tau = 1.0 / (_CELLS_PER_PERIOD * decay)
        if tau < cell:
            extra = math.ceil(math.log2(cell / tau))
    times = np.empty(count + 1 + extra)
    times[0] = 0.0
    for j in range(extra):
        times[1 + j] = cell * 2.0 ** (-(extra - j))
    for j in range(1, count + 1):
        times[extra + j] = T * j / count
    times[extra + count] = T
    return times, capped


@_jit
def free_x1(t, w, a, u0, dy, dv):
    """x1 and its first four time derivatives of the free deviation (per unit kappa sigma)."""
    x0 = 0.0
    x1 = 0.0
    x2 = 0.0
    x3 = 0.0
    x4 = 0.0
    for i in range(w.size):
        if u0[i] == 0.0:
            continue
        w11, w12, w21, w22 = mode_transfer(w[i], a[i], t)
        y = w11 * dy[i] + w12 * dv[i]
        v = w21 * dy[i] + w22 * dv[i]
        acc = -w[i] * w[i] * y - 2.0 * a[i] * v
        jerk = -w[i] * w[i] * v - 2.0 * a[i] * acc
        x0 += u0[i] * y
        x1 += u0[i] * v
        x2 += u0[i] * acc
        x3 += u0[i] * jerk
        x4 += u0[i] * (-w[i] * w[i] * acc - 2.0 * a[i] * jerk)
    return x0, x1, x2, x3, x4


_ANCHOR = 32  # grid steps of the recurrence between direct evaluations


@_jit
def free_on_grid(times, w, a, u0, dy, dv):
    """``free_x1`` at every grid time, shape (5, nt): x1 and its first four derivatives.

    On the uniform part of the grid the modal deviation is advanced by the one-step
    transfer ``W(h)`` (the flow is a semigroup: four products per mode and step
    instead of three transcendental functions) and evaluated directly every
    ``_ANCHOR`` steps, so rounding cannot accumulate beyond a few dozen ulps; the
    grid only brackets roots, which are then polished by direct evaluation.
    """
    nt = times.size
    out = np.zeros((5, nt))
    # the uniform part ends the grid: find where it starts (after the refinement near 0)
    j0 = nt - 1
    while j0 > 1 and abs((times[j0] - times[j0 - 1]) - (times[nt - 1] - times[nt - 2])) <= (
            1e-9 * (times[nt - 1] - times[nt - 2])):
        j0 -= 1
    for k in range(j0):
        x0, x1, x2, x3, x4 = free_x1(times[k], w, a, u0, dy, dv)
        out[0, k] = x0
        out[1, k] = x1
        out[2, k] = x2
        out[3, k] = x3
        out[4, k] = x4
    h = (times[nt - 1] - times[j0]) / max(nt - 1 - j0, 1)
    for i in range(w.size):
        if u0[i] == 0.0:
            continue
        s11, s12, s21, s22 = mode_transfer(w[i], a[i], h)
        wi2 = w[i] * w[i]
        ai2 = 2.0 * a[i]
        y = 0.0
        yv = 0.0
        for k in range(j0, nt):
            if (k - j0) % _ANCHOR == 0:
                w11, w12, w21, w22 = mode_transfer(w[i], a[i], times[k])
                y = w11 * dy[i] + w12 * dv[i]
                yv = w21 * dy[i] + w22 * dv[i]
            else:
                y, yv = s11 * y + s12 * yv, s21 * y + s22 * yv
            ya = -wi2 * y - ai2 * yv
            yj = -wi2 * yv - ai2 * ya
            out[0, k] += u0[i] * y
            out[1, k] += u0[i] * yv
            out[2, k] += u0[i] * ya
            out[3, k] += u0[i] * yj
            out[4, k] += u0[i] * (-wi2 * ya - ai2 * yj)
    return out


_SERIES_BELOW = 0.5  # 2 a t below which phi and psi are summed as series (no cancellation)
_SERIES_TERMS = 20  # enough for rounding level below _SERIES_BELOW


@_inner
def _phi_psi(x):
    """``phi(x) = 2 (x - 1 + e^-x) / x^2`` and ``psi(x) = (1 - e^-x) / x`` (both 1 at 0),
    by their series below ``_SERIES_BELOW`` (``2 sum (-x)^k / (k+2)!``, ``sum (-x)^k /
    (k+1)!``; as :func:`impactcont.model.modal.static_response`), else in closed form."""
    if x < _SERIES_BELOW:
        phi = 0.0
        psi = 0.0
        fact = 1.0
        for k in range(2, _SERIES_TERMS + 2):
            fact *= k
        # Horner from the highest term down, fact = (k + 1)! at term k
        for k in range(_SERIES_TERMS, -1, -1):
            psi = psi * (-x) + 1.0 / fact
            phi = phi * (-x) + 2.0 / (fact * (k + 2))
            fact /= k + 1
        return phi, psi
    em1 = math.expm1(-x)
    return 2.0 * (x + em1) / (x * x), -em1 / x


@_jit
def drift_x1(t, pg, pa, p1):
    """The polynomial part of the stop coordinate and its first four time derivatives.

    ``p(t) = p1 t + sum_i pg_i t^2 phi(2 a_i t) / 2`` (``a_i = pa[i]``): the response
    from rest of the free modes a constant force pushes
    (:func:`impactcont.model.modal.static_response`, weighted by the stop's modal
    weights), ``pg_i t^2 / 2`` undamped, and the linear drift ``p1 t`` of the
    first-order flow. Each free mode obeys ``y'' + 2 a y' = g``, so its second, third and
    fourth derivatives are ``g e^{-2at}`` times ``1, -2a, 4a^2`` (``g, 0, 0`` undamped).
    """
    x0 = p1 * t
    x1 = p1
    x2 = 0.0
    x3 = 0.0
    x4 = 0.0
    for i in range(pg.size):
        g = pg[i]
        if g == 0.0:
            continue
        ai = pa[i]
        if ai == 0.0:
            x0 += 0.5 * g * t * t
            x1 += g * t
            x2 += g
            continue
        x = 2.0 * ai * t
        phi, psi = _phi_psi(x)
        e = g * math.exp(-x)
        x0 += 0.5 * g * t * t * phi
        x1 += g * t * psi
        x2 += e
        x3 -= 2.0 * ai * e
        x4 += 4.0 * ai * ai * e
    return x0, x1, x2, x3, x4


@_jit
def drift_on_grid(times, pg, pa, p1, free):
    """Add :func:`drift_x1` at every grid time to ``free`` (the table of
    :func:`free_on_grid`, shape (5, nt)) in place; returns ``free``."""
    if pg.size == 0 and p1 == 0.0:
        return free
    for k in range(times.size):
        q0, q1, q2, q3, q4 = drift_x1(times[k], pg, pa, p1)
        free[0, k] += q0
        free[1, k] += q1
        free[2, k] += q2
        free[3, k] += q3
        free[4, k] += q4
    return free


@_jit
def x1_derivatives(t, Gam, B, omega, delta, ks, w, a, u0, dy, dv):
    """``x1`` and its first three derivatives at time t after the impact at ``delta``.

    ``Gam, B``: the forced motion of mass 1 (``scalars[1:3]`` of :func:`omega_setup`);
    ``ks = kappa sigma``; ``dy, dv``: ``modal[6], modal[7]``.
    """
    d = _x1_derivs(t, Gam, B, omega, delta, ks, w, a, u0, dy, dv, None)
    return d[0], d[1], d[2], d[3]


@_jit
def _x1_derivs(t, Gam, B, omega, delta, ks, w, a, u0, dy, dv, drift=None):
    """x1 and its first four derivatives; ``drift``: None, or ``(pg, pa, p1)`` of
    :func:`drift_x1`, added to the free part (per unit ``ks``). A None is a type: numba
    compiles the branch away, so the searches without a drift run the code they ran
    before it existed."""
    th = omega * t + delta
    c, s = np.cos(th), np.sin(th)
    p = Gam * c + B * s
    dp = omega * (B * c - Gam * s)
    f0, f1, f2, f3, f4 = free_x1(t, w, a, u0, dy, dv)
    if drift is not None:
        q0, q1, q2, q3, q4 = drift_x1(t, drift[0], drift[1], drift[2])
        f0 += q0
        f1 += q1
        f2 += q2
        f3 += q3
        f4 += q4
    om2 = omega * omega
    return (p + ks * f0, dp + ks * f1, -om2 * p + ks * f2, -om2 * dp + ks * f3,
            om2 * om2 * p + ks * f4)


# the derivative a polish finds a root of, as run-time integers: a literal argument would
# make numba compile _polish once per value
_ORDER_VEL = np.int64(1)
_ORDER_ACC = np.int64(2)


@_jit
def _polish(order, lo, hi, g_lo, g_hi, dg_lo, dg_hi, ddg_lo, ddg_hi, Gam, B, omega, delta, ks,
            w, a, u0, dy, dv, drift=None):
    """Root of the ``order``-th derivative of x1 in [lo, hi] by safeguarded Newton.

    Returns the root and x1 with its first three derivatives there. The start is the
    root of the quintic Hermite interpolant of the ``order``-th derivative from its
    values ``g``, slopes ``dg`` and curvatures ``ddg`` at the ends (cubic when a
    curvature is not finite, the secant point when a slope is not), so one Newton
    step (two from a cubic start) reaches rounding level; a step that would leave the
    shrinking bracket bisects instead. A Newton step below the tolerance, or whose predicted
    error (the next derivative over twice the slope, times the step squared) is, is
    the last: the values at the root then follow from the Taylor series at the last
    evaluation (exact to rounding, no further evaluation).
    """
    left, right = lo, hi
    ga = g_lo
    x = _hermite_root(lo, hi, g_lo, g_hi, dg_lo, dg_hi, ddg_lo, ddg_hi)
    for _ in range(_MAX_ITER):
        d = _x1_derivs(x, Gam, B, omega, delta, ks, w, a, u0, dy, dv, drift)
        g = d[order]
        dg = d[order + 1]
        if (g < 0.0) == (ga < 0.0):
            left = x
            ga = g
        else:
            right = x
        if g == 0.0:
            return x, d[0], d[1], d[2], d[3]
        step = g / dg if dg != 0.0 else np.inf
        tol = _XTOL + _RTOL * abs(x)
        xn = x - step
        if np.isfinite(xn) and (abs(step) <= tol or (
                left <= xn <= right and abs(d[order + 2] / (2.0 * dg)) * step * step <= tol)):
            return _taylor(xn, -step, d)  # the Newton step is the last
        if right - left <= tol:
            if np.isfinite(xn):
                d = _x1_derivs(xn, Gam, B, omega, delta, ks, w, a, u0, dy, dv, drift)
            return (xn if np.isfinite(xn) else x), d[0], d[1], d[2], d[3]
        if not (np.isfinite(xn) and left <= xn <= right):
            xn = 0.5 * (left + right)
        x = xn
    d = _x1_derivs(x, Gam, B, omega, delta, ks, w, a, u0, dy, dv, drift)
    return x, d[0], d[1], d[2], d[3]


@_inner
def _taylor(t, h, d):
    """``t`` and x1 with its first three derivatives at ``t`` from ``d`` (x1 to its fourth)
    at ``t - h``: for the tiny last Newton step ``h`` the remainder is O(h^4) or less."""
    return (t, d[0] + h * (d[1] + h * (0.5 * d[2] + h * (d[3] / 6.0 + h * d[4] / 24.0))),
            d[1] + h * (d[2] + h * (0.5 * d[3] + h * d[4] / 6.0)),
            d[2] + h * (d[3] + 0.5 * h * d[4]), d[3] + h * d[4])


@_inner
def _hermite_root(lo, hi, g_lo, g_hi, dg_lo, dg_hi, ddg_lo, ddg_hi):
    """Root in (lo, hi) of the Hermite interpolant of g (g of opposite signs at the ends).

    The cubic one from the values and slopes at the ends, by three Newton steps from the
    secant point, then, when the second derivatives ``ddg`` are finite, the quintic one
    by two Newton steps from there; the secant point (or the midpoint) when a slope is
    not finite; a step that leaves the interval, or a zero slope, ends the steps on
    that interpolant."""
    h = hi - lo
    x = g_lo / (g_lo - g_hi) if g_lo != g_hi else 0.5
    if not 0.0 < x < 1.0:
        return 0.5 * (lo + hi)
    if not (np.isfinite(dg_lo) and np.isfinite(dg_hi)):
        return lo + h * x
    m0 = h * dg_lo
    m1 = h * dg_hi
    c0 = h * h * ddg_lo
    c1 = h * h * ddg_hi
    # one Newton loop for both interpolants (written once, compiled once)
    for stage in range(2 if np.isfinite(ddg_lo) and np.isfinite(ddg_hi) else 1):
        quintic = stage == 1
        for _ in range(2 if quintic else 3):
            x2 = x * x
            x3 = x2 * x
            if quintic:
                # quintic Hermite basis on [0, 1]: values, slopes and curvatures at 0 and 1
                x4 = x3 * x
                x5 = x4 * x
                p = ((1.0 - 10.0 * x3 + 15.0 * x4 - 6.0 * x5) * g_lo
                     + (x - 6.0 * x3 + 8.0 * x4 - 3.0 * x5) * m0
                     + 0.5 * (x2 - 3.0 * x3 + 3.0 * x4 - x5) * c0
                     + 0.5 * (x3 - 2.0 * x4 + x5) * c1
                     + (-4.0 * x3 + 7.0 * x4 - 3.0 * x5) * m1
                     + (10.0 * x3 - 15.0 * x4 + 6.0 * x5) * g_hi)
                dp = ((-30.0 * x2 + 60.0 * x3 - 30.0 * x4) * g_lo
                      + (1.0 - 18.0 * x2 + 32.0 * x3 - 15.0 * x4) * m0
                      + 0.5 * (2.0 * x - 9.0 * x2 + 12.0 * x3 - 5.0 * x4) * c0
                      + 0.5 * (3.0 * x2 - 8.0 * x3 + 5.0 * x4) * c1
                      + (-12.0 * x2 + 28.0 * x3 - 15.0 * x4) * m1
                      + (30.0 * x2 - 60.0 * x3 + 30.0 * x4) * g_hi)
            else:
                # cubic Hermite basis on [0, 1]: values and slopes at 0 and 1
                p = ((2 * x3 - 3 * x2 + 1) * g_lo + (x3 - 2 * x2 + x) * m0
                     + (-2 * x3 + 3 * x2) * g_hi + (x3 - x2) * m1)
                dp = ((6 * x2 - 6 * x) * g_lo + (3 * x2 - 4 * x + 1) * m0
                      + (-6 * x2 + 6 * x) * g_hi + (3 * x2 - 2 * x) * m1)
            if dp == 0.0:
                break
            xn = x - p / dp
            if not 0.0 < xn < 1.0:
                break
            x = xn
    return lo + h * x


@_jit
def x1_maximum(times, free, cw, sw, Gam, B, omega, delta, ks, w, a, u0, dy, dv, work, exclude):
    """Highest interior local maximum of ``x1`` on ``(0, T)``: ``(value, time)``.

    ``x1 = Gam cos(omega t + delta) + B sin(omega t + delta) + ks * free(t)``, the free
    part the modal sum ``sum u0_i y_i(t)`` of :func:`free_x1` (tabulated in ``free``);
    :func:`stop_maximum` with no polynomial part (the search of eq. 16, see there).
    """
    return _maximum(times, free, cw, sw, Gam, B, omega, delta, ks, w, a, u0, dy, dv, work,
                    exclude, None)


@_jit
def stop_maximum(times, free, cw, sw, Gam, B, omega, delta, ks, w, a, u0, dy, dv, pg, pa, p1,
                 work, exclude):
    """Highest interior local maximum of a stop coordinate on ``(0, T)``: ``(value, time)``.

    As :func:`x1_maximum` with the polynomial part of :func:`drift_x1` (``pg, pa, p1``, a
    free mode pushed by a constant force) in the free part: ``s = Gam cos + B sin + ks
    (modal free part + p(t))``; ``free`` must hold it (:func:`drift_on_grid` after
    :func:`free_on_grid`).
    """
    return _maximum(times, free, cw, sw, Gam, B, omega, delta, ks, w, a, u0, dy, dv, work,
                    exclude, (pg, pa, p1))


@_inner
def _maximum(times, free, cw, sw, Gam, B, omega, delta, ks, w, a, u0, dy, dv, work, exclude,
             drift):
    """The search of :func:`x1_maximum` and :func:`stop_maximum` (``drift``: None, or the
    polynomial part ``(pg, pa, p1)``).

    ``free``: :func:`free_on_grid` at ``times``; ``cw, sw``: cos and sin of
    ``omega times``; ``work``: scratch of shape ``(WORK_ROWS, 2 nt)`` (reused across calls).
    Each grid cell holds at most one root of ``x1''`` (the grid is built so), hence
    at most two roots of ``x1'``:

    - ``x1''`` keeps its sign: ``x1'`` is monotone, a maximum iff ``x1'`` goes from
      ``>= 0`` to ``< 0``;
    - ``x1''`` changes sign: ``x1'`` is unimodal; with ``x1'`` of opposite signs at
      the ends there is one root and the cell brackets it; with equal signs the
      root of ``x1''`` is polished first and splits the cell in two monotone pieces.

    A candidate piece ``[p, q]`` with ``x1'`` decreasing through 0 is concave, so x1
    lies below the meeting point of its tangents at ``p`` and ``q``; candidates are
    polished (safeguarded Newton from a quintic Hermite start, :func:`_polish`) in
    decreasing order of that bound, and the search stops once the bound is below the
    best maximum found: the result is the same as polishing every one.
    A maximum within ``1e-7 T`` of the time ``exclude`` is skipped (NaN: none is),
    e.g. the tangency of a grazing motion. ``(-inf, nan)`` when there is none.

    A polynomial part ``p`` (a free mode a constant force pushes, :func:`drift_x1`) is in
    the table and in every evaluation of the polish, so the classification of the
    cells, the tangent bounds and the Newton steps all see ``x1 + p``: a bound without
    ``p`` would misplace where a maximum can hide. It adds no faster time scale:
    ``p''`` is a constant (undamped) or ``g e^{-2at}``, the decay of a free mode the
    coordinate sees, which :func:`time_grid` already refines for (its ``a + sqrt(a^2 -
    w^2) = 2a``); ``p'''`` is 0 or of one sign.
    """
    cd, sd = math.cos(delta), math.sin(delta)
    nt = times.size
    T = times[nt - 1]
    om2 = omega * omega
    x = work[0]
    v = work[1]
    acc = work[2]
    c_lo = work[3]
    c_hi = work[4]
    c_v = work[5]
    c_ub = work[6]
    c_vh = work[7]
    c_a = work[8]
    c_ah = work[9]
    # first x1, x1', x1'' on the whole grid (a branch-free loop the compiler vectorises:
    # faster than one pass that classifies each cell as it goes)
    for k in range(nt):
        c = cw[k] * cd - sw[k] * sd
        s = sw[k] * cd + cw[k] * sd
        p = Gam * c + B * s
        x[k] = p + ks * free[0, k]
        v[k] = omega * (B * c - Gam * s) + ks * free[1, k]
        acc[k] = -om2 * p + ks * free[2, k]
    m = np.int64(0)  # not a literal 0: _candidate is then compiled once (int64)
    for k in range(1, nt):
        lo, hi = times[k - 1], times[k]
        v0, v1 = v[k - 1], v[k]
        a0, a1 = acc[k - 1], acc[k]
        if (a0 < 0.0) == (a1 < 0.0) or (v0 < 0.0) != (v1 < 0.0):
            if v0 >= 0.0 and v1 < 0.0:  # one root of x1', a maximum
                m = _candidate(work, m, lo, hi, v0, v1, a0, a1,
                               _jerk(omega, ks, v0, free[1, k - 1], free[3, k - 1]),
                               _jerk(omega, ks, v1, free[1, k], free[3, k]),
                               _concave_bound(lo, hi, x[k - 1], x[k], v0, v1))
            continue
        # x1'' changes sign, x1' has one sign at both ends: zero or two roots; none when
        # x1' falls then rises from below 0, or rises then falls to >= 0
        if (a0 < 0.0) == (v0 < 0.0):
            continue
        j0 = _jerk(omega, ks, v0, free[1, k - 1], free[3, k - 1])
        j1 = _jerk(omega, ks, v1, free[1, k], free[3, k])
        tm, xm, vm, am, jm = _polish(_ORDER_ACC, lo, hi, a0, a1, j0, j1,
                                     _snap(omega, ks, x[k - 1], free[0, k - 1], free[4, k - 1]),
                                     _snap(omega, ks, x[k], free[0, k], free[4, k]),
                                     Gam, B, omega, delta, ks, w, a, u0, dy, dv, drift)
        if v0 >= 0.0 and vm < 0.0:  # falls through 0 before the inflection
            m = _candidate(work, m, lo, tm, v0, vm, a0, am, j0, jm,
                           _concave_bound(lo, tm, x[k - 1], xm, v0, vm))
        elif vm >= 0.0 and v1 < 0.0:  # rises above 0, then falls through it
            m = _candidate(work, m, tm, hi, vm, v1, am, a1, jm, j1,
                           _concave_bound(tm, hi, xm, x[k], vm, v1))
    best = -np.inf
    best_t = np.nan
    for _ in range(m):
        j = 0
        for i in range(1, m):
            if c_ub[i] > c_ub[j]:
                j = i
        if not c_ub[j] > best:
            break
        c_ub[j] = -np.inf  # done
        best, best_t = _take(best, best_t, c_lo[j], c_hi[j], c_v[j], c_vh[j], c_a[j], c_ah[j],
                             work[10, j], work[11, j], T, Gam, B, omega, delta, ks, w, a, u0,
                             dy, dv, exclude, drift)
    return best, best_t


@_inner
def _jerk(omega, ks, v, free_v, free_jerk):
    """The third derivative of x1 at a grid point from ``x1'`` there: the forced part's
    is ``-omega^2`` times its velocity ``x1' - ks free'``."""
    return ks * free_jerk - omega * omega * (v - ks * free_v)


@_inner
def _snap(omega, ks, x, free_x, free_snap):
    """The fourth derivative of x1 at a grid point from ``x1`` there: the forced part's
    is ``omega^4`` times its displacement ``x1 - ks free``."""
    return ks * free_snap + omega ** 4 * (x - ks * free_x)


@_inner
def _concave_bound(p, q, xp, xq, vp, vq):
    """An upper bound of x1 on ``[p, q]`` where it is concave (``x1'' < 0``) with
    ``x1'(p) >= 0 > x1'(q)``: the meeting point of the tangents at both ends."""
    t = (xq - xp + vp * p - vq * q) / (vp - vq)
    return xp + vp * (min(max(t, p), q) - p)


@_inner
def _candidate(work, m, lo, hi, v_lo, v_hi, a_lo, a_hi, j_lo, j_hi, bound):
    """Record the piece ``[lo, hi]`` where x1' falls through 0 (a maximum) as candidate ``m``
    in the rows 3-11 of ``work`` with the upper bound of x1 on it (``j``: its third
    derivative at the ends, NaN where unknown); returns ``m + 1``."""
    work[3, m] = lo
    work[4, m] = hi
    work[5, m] = v_lo
    work[6, m] = bound
    work[7, m] = v_hi
    work[8, m] = a_lo
    work[9, m] = a_hi
    work[10, m] = j_lo
    work[11, m] = j_hi
    return m + 1


@_inner
def _take(best, best_t, lo, hi, v_lo, v_hi, a_lo, a_hi, j_lo, j_hi, T, Gam, B, omega, delta, ks,
          w, a, u0, dy, dv, exclude, drift):
    r, xr, _, acc, _ = _polish(_ORDER_VEL, lo, hi, v_lo, v_hi, a_lo, a_hi, j_lo, j_hi, Gam, B,
                            omega, delta, ks, w, a, u0, dy, dv, drift)
    if r <= _END_TOL * T or r >= (1.0 - _END_TOL) * T:
        # the impact itself, not an interior contact (with R = 0, x1' = 0 at t = 0 and
        # its rounding would otherwise place a "maximum" a few ulps after the impact)
        return best, best_t
    if abs(r - exclude) <= _EXCLUDE_TOL * T:
        return best, best_t
    if acc < 0.0 and xr > best:
        return xr, r
    return best, best_t


WORK_ROWS = 12  # rows of the scratch of x1_maximum (its grid values and candidates)
_EXCLUDE_TOL = 1e-7  # relative to T: a maximum this close to ``exclude`` is the same one


@_jit
def flight_tables(w, a, u0, modal, omega, T):
    """Per-frequency tables of the interior-contact check, shared by every gap and root.

    Returns ``(times, capped, free, cw, sw, dy, dv, work)``: the grid of
    :func:`time_grid`, the free response of :func:`free_on_grid` on it, cos and sin of
    ``omega t``, the free modal deviation per unit ``kappa sigma`` and the scratch of
    :func:`x1_maximum`.
    """
    times, capped = time_grid(w, a, u0, omega, T)
    dy = modal[6].copy()
    dv = modal[7].copy()
    free = free_on_grid(times, w, a, u0, dy, dv)
    return (times, capped, free, np.cos(omega * times), np.sin(omega * times), dy, dv,
            np.empty((WORK_ROWS, 2 * times.size)))


@_jit
def other_maximum(w, a, u0, modal, scalars, omega, R, delta, sigma, exclude):
    """Highest interior maximum of ``x1`` other than the one at time ``exclude``:
    ``(value, time)``, ``(-inf, nan)`` when there is none (:func:`x1_maximum`)."""
    times, _, free, cw, sw, dy, dv, work = flight_tables(w, a, u0, modal, omega, scalars[0])
    return x1_maximum(times, free, cw, sw, scalars[1], scalars[2], omega, delta,
                      (1.0 + R) * sigma, w, a, u0, dy, dv, work, exclude)
