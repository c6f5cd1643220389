"""Compiled stability maps of N-p motions: Newton from solved neighbours over a grid.

The numba side of :func:`impactcont.analysis.multi_maps.multi_impact_map`. One call sweeps a
whole grid of two parameters: every grid point is solved by Newton on the shooting
system of :mod:`impactcont.orbit.multi_impact` (or on the half system of a symmetric
motion, :mod:`impactcont.orbit.symmetry`), started from a solved neighbour (a secant
predictor through two solved points in line when there are two), and the solution is
evaluated (G or the half-map, multipliers, impact velocities, the contact check of
eq. 16 against every stop: U, L and each further stop on its own coordinate). A grid
point that is solved puts its unsolved neighbours in a first-in first-out queue; a point
whose Newton fails stays unsolved and seeds nothing (it is tried again, at most once per
neighbour, when another neighbour is solved).

The flows are stacked by value of the parameters that change them (``flow_index``
gives each grid point its row of the tables of
:meth:`impactcont.orbit.flow.Flow.shooting_arrays`), the stop geometry by value of
the parameters that move the stops (``geometry_index``). Flights, Newton steps, G
and the contact search are those of :mod:`impactcont.kernel.shooting`.

The half system of a symmetric motion (``p = 2h``; ``X_{k+h} = -X_k``,
``tau_{k+h} = tau_k``) is the shooting system of its first ``h`` flights over half
the period, ``N pi / omega``, closed by the reflection: its last block is
``D_h X_{h-1}^- + X_0`` instead of ``D_0 X_{h-1}^- - X_0`` (``D_h = D_0`` in a
symmetric system), as :class:`impactcont.problems.symmetric_branch.SymmetricBranchProblem`.
Its G is ``H^2`` with the half-map ``H = S G_{h-1} .. G_0``, and the second half's
velocities, flight times, gaps and states are the mirror images of the first's.

Every stop acts on a stop coordinate ``s = n . x`` (a mass, or a clearance between two
masses) with a full impact matrix on the velocities
(:class:`impactcont.orbit.stop_geometry.StopGeometry`); the impacts of one motion may hit
stops of different coordinates (``Stops(extra=...)``), each section solved for the
position of its stop's own mass (``pivots``, one per impact). One compiled entry point,
:func:`sweep_stops` (compiled once; a single point is a 1 x 1 grid), with the constant
force's arrays (:meth:`impactcont.orbit.flow.Flow.static_arrays`) stacked like the flows'.
Importing :mod:`impactcont` does not import this module.
"""

from __future__ import annotations

import math

import numpy as np

from impactcont.kernel.jit import entry as _jit
from impactcont.kernel.jit import inner as _inner
from impactcont.kernel.shooting import (
    _clearances,
    _jacobian_wanted,
    _max_abs,
    _solve,
    _stop_clearance,
    end_clearances,
    jacobian_product_into,
    shooting_system,
    unknowns_scale,
)
from impactcont.kernel.stability import multipliers

__all__ = ["sweep_stops"]


#: The four neighbours of a grid point.
_STEPS = ((1, 0), (-1, 0), (0, 1), (0, -1))


@_jit
def _system(general, w, a, gam, bet, f, u, ui, lam, V, Vi, Z, st, omega, N, symmetric, pivots,
            normals, positions, matrices, x, want_jacobian):
    """The shooting system (full, or the half of a symmetric motion) at ``x``.

    `normals`, `positions` and `matrices` hold the impacts of the system solved (the
    first h of a symmetric motion), `pivots` the position eliminated on each impact's
    section (the stop's own mass; one for all in a symmetric motion). Returns the tuple
    of :func:`shooting_system`.
    """
    q = positions.size
    if not symmetric:
        return shooting_system(general, w, a, gam, bet, f, u, ui, lam, V, Vi, Z, st, omega,
                               2.0 * math.pi * N / omega, pivots[:q], normals, positions,
                               matrices, x, want_jacobian)
    j = pivots[0]
    out = shooting_system(general, w, a, gam, bet, f, u, ui, lam, V, Vi, Z, st, omega,
                          math.pi * N / omega, pivots[:q], normals, positions, matrices, x,
                          want_jacobian)
    h = q
    m = matrices.shape[1]
    n = m // 2
    starts = out[2]
    residual = out[7]
    last = (h - 1) * m
    for r in range(m):  # - X_0 -> + X_0 = - X_h
        residual[last + r] += 2.0 * starts[0, r]
    if want_jacobian:
        J = out[8]
        for r in range(m):  # dX_0/dz_0: unit columns, and x_j from the section
            if r != j:
                J[last + r, h + (r if r < j else r - 1)] += 2.0
            else:
                for c in range(n):
                    if c != j:
                        J[last + r, h + (c if c < j else c - 1)] -= (
                            2.0 * normals[0, c] / normals[0, j])
    return out


@_jit
def _newton(general, w, a, gam, bet, f, u, ui, lam, V, Vi, Z, st, omega, N, symmetric,
            pivots, normals, positions, matrices, x0, tol, max_iter):
    """Newton with backtracking from ``x0``: the iteration and stopping rules of
    :func:`impactcont.kernel.shooting.newton_solve` on :func:`_system`.

    Returns ``(x, converged, iterations, shooting)``.
    """
    x = x0.copy()
    sh = _system(general, w, a, gam, bet, f, u, ui, lam, V, Vi, Z, st, omega, N, symmetric,
                 pivots, normals, positions, matrices, x, _jacobian_wanted(x))
    norm = _max_abs(sh[7])
    step_norm = np.inf
    it = 0
    for it in range(max_iter + 1):
        scale = unknowns_scale(x)
        small = norm <= tol * scale
        if small and (step_norm <= tol * scale or it == max_iter):
            return x, True, it, sh
        if it == max_iter:
            break
        J = sh[8]
        if not np.all(np.isfinite(J)):
            break
        step, ok = _solve(J, -sh[7])
        if not ok:
            break
        lam_step = 1.0
        while True:
            trial = x + lam_step * step
            tsh = _system(general, w, a, gam, bet, f, u, ui, lam, V, Vi, Z, st, omega, N,
                          symmetric, pivots, normals, positions, matrices, trial,
                          _jacobian_wanted(trial))
            tnorm = _max_abs(tsh[7])
            finite = np.isfinite(tnorm)
            if small and not (finite and tnorm < norm):
                return x, True, it, sh
            if finite and (tnorm < norm or tnorm <= tol * scale or lam_step < 1e-3):
                break
            lam_step *= 0.5
        step_norm = lam_step * _max_abs(step)
        x = trial
        sh = tsh
        norm = tnorm
    return x, False, it, sh


@_jit
def _evaluate(general, w, a, gam, bet, f, u, ui, lam, V, Vi, Z, pw, pa, pk, pj, st, omega, N,
              symmetric, admits, pivots, normal, two_sided, b, b_low, extra_normals,
              extra_signs, extra_positions, full_normals, full_matrices, signs, sh, checks,
              point, out_rho, out_mu, out_gap, out_velocity, out_tau,
              out_state, out_asym):
    """Stability, velocities, flight times, states and the contact check of a solution.

    The contact check (eq. 16) searches every flight against both stops U, L of the stop
    coordinate ``normal`` and against each further stop (``extra_normals`` (q, n),
    ``extra_signs``, ``extra_positions`` (q,)), as
    :func:`impactcont.kernel.shooting.motion_checks` does, and checks every stop at both
    ends of every flight but the stop hit there (:func:`_end_gap`); the gap is the
    smallest of all.

    Writes the grid point `point` (flat index) of the output arrays; returns
    ``(physical, capped)``.
    """
    phases, taus, starts, transitions, pcols, rates = sh[0], sh[1], sh[2], sh[5], sh[6], sh[4]
    p = signs.size
    m = full_matrices.shape[1]
    flights = taus.size  # h of a symmetric motion, else p
    h2 = np.empty(flights)
    G = np.empty((m, m))
    jacobian_product_into(pivots, full_normals, full_matrices, omega, transitions, pcols, rates,
                          flights, G, h2)
    if symmetric:  # the half-map H = S G_{h-1} .. G_0: G = H^2
        for r in range(m - 1):
            for c in range(m):
                G[r, c] = -G[r, c]
    mu = multipliers(G)
    if symmetric:
        mu = mu * mu
    out_rho[point] = abs(mu[0])
    out_mu[point] = mu[0]
    physical = True
    for k in range(p):
        q = k % flights
        sign = 1.0 if (k < flights or not symmetric) else -1.0
        out_tau[point, k] = taus[q]
        for c in range(m):
            out_state[point, k, c] = sign * starts[q, c]
        if not taus[q] > 0.0:
            physical = False
    # the speed towards its stop before impact k: flight k-1 arrives there
    for k in range(p):
        prev = (k - 1) % p
        if symmetric:
            # flight prev >= h is the mirror of flight prev - h: -x_j' towards the other stop
            v = h2[prev % flights] * (1.0 if prev < flights else -1.0) * signs[k]
        else:
            v = h2[prev] * signs[k]
        out_velocity[point, k] = v
        if not v > 0.0:
            physical = False
    gap = np.inf
    capped = False
    if checks:
        for k in range(flights):
            if not taus[k] > 0.0:
                continue
            gu, _, gl, _, cap = _clearances(general, w, a, gam, bet, u, ui, pw, pa, pk, pj,
                                            lam, V, Vi, Z, st, omega, normal, two_sided, b,
                                            b_low, starts[k], phases[k], taus[k])
            if not (gu == gu and gl == gl):  # not searchable: a constant force on a free mode
                gap = np.nan
                break
            # a mirrored flight's clearance to one stop is the other's of its image
            gap = min(gap, gu, gl)
            capped = capped or cap
            for i in range(extra_signs.size):  # every further stop, each on its coordinate
                gx, _, cap = _stop_clearance(general, w, a, gam, bet, u, ui, pw, pa, pk, pj,
                                             lam, V, Vi, Z, st, omega, extra_normals[i],
                                             extra_signs[i], extra_positions[i], starts[k],
                                             phases[k], taus[k])
                if gx != gx:  # NaN: not searchable
                    gap = np.nan
                    break
                gap = min(gap, gx)
                capped = capped or cap
            if gap != gap:
                break
        if not gap > 0.0:  # NaN included
            physical = False
        ends, crossed = _end_gap(normal, two_sided, b, b_low, full_normals, signs,
                                 extra_normals, extra_signs, extra_positions, sh[2], sh[3],
                                 flights, symmetric)
        if gap == gap:  # a NaN gap (not searchable) stays NaN
            gap = min(gap, ends)
        if crossed:
            physical = False
    else:
        gap = np.nan
        physical = False
    out_gap[point] = gap
    if admits and not symmetric:  # symmetry_defect of the motion
        half = p // 2
        big = 1.0
        dx = 0.0
        dt = 0.0
        for k in range(p):
            for c in range(m):
                big = max(big, abs(out_state[point, k, c]))
        for k in range(half):
            dt = max(dt, abs(taus[k + half] - taus[k]))
            for c in range(m):
                dx = max(dx, abs(out_state[point, k + half, c] + out_state[point, k, c]))
        out_asym[point] = max(dx, omega * dt) / big
    elif admits:
        out_asym[point] = 0.0
    return physical, capped


@_inner
def _end_gap(normal, two_sided, b, b_low, full_normals, signs, extra_normals, extra_signs,
             extra_positions, starts, arrivals, flights, symmetric):
    """Every stop's clearance at both ends of every flight, as
    :func:`impactcont.kernel.shooting.end_clearances` (the second half of a symmetric
    motion the mirror image of the first): ``(smallest clearance, crossed)``, ``crossed``
    when an end is past a stop by more than the rounding of its clearance."""
    p = signs.size
    m = starts.shape[1]
    full_starts = np.empty((p, m))
    full_arrivals = np.empty((p, m))
    for k in range(p):
        q = k % flights
        sign = 1.0 if (k < flights or not symmetric) else -1.0
        for c in range(m):
            full_starts[k, c] = sign * starts[q, c]
            full_arrivals[k, c] = sign * arrivals[q, c]
    gap, _, tol = end_clearances(normal, two_sided, b, b_low, full_normals, signs,
                                 extra_normals, extra_signs, extra_positions, full_starts,
                                 full_arrivals)
    smallest = np.inf
    crossed = False
    for k in range(p):
        for end in range(2):
            smallest = min(smallest, gap[k, end])
            crossed = crossed or gap[k, end] < -tol[k, end]
    return smallest, crossed


@_inner
def _push(queue, tail, size, point, parent):
    queue[tail % size, 0] = point
    queue[tail % size, 1] = parent
    return tail + 1


@_jit
def sweep_stops(general, w, a, gam, bet, f, u, ui, lam, V, Vi, Z, pw, pa, pk, pj, sg, sfree,
                sxs, sxd, omegas,
                flow_index, positions, normals, matrices, full_normals, full_matrices,
                contact_normals, b_upper, b_lower, extra_normals, extra_signs, extra_positions,
                geometry_index, coord0, coord1, signs, N, symmetric, admits, pivots, two_sided,
                seed0, seed1, x_seed, tol, max_iter, max_change, checks, max_attempts, unknowns,
                found, iterations, delta, stable, physical, rho, mu, gap, velocity, tau, state,
                asym):
    """Solve every grid point reachable from the seed through solved neighbours.

    Parameters
    ----------
    general, w .. Z, pw .. pj
        The flows' arrays (:meth:`impactcont.orbit.flow.Flow.shooting_arrays`), each
        stacked on a first axis of flows.
    sg, sfree, sxs, sxd
        The flows' constant-force arrays (:meth:`impactcont.orbit.flow.Flow.static_arrays`),
        stacked likewise (second axis of size 0: no constant force).
    omegas : ndarray, shape (nf,)
        Forcing frequency of each flow.
    flow_index, geometry_index : ndarray of int64, shape (n0, n1)
        The flow and the stop geometry of each grid point.
    positions, normals, matrices : ndarray, shape (ng, q), (ng, q, n), (ng, q, 2n, 2n)
        Stop position, normal of the stop coordinate and impact matrix of the q impacts
        solved (h of a symmetric motion, else p), per geometry
        (:class:`impactcont.orbit.stop_geometry.StopGeometry`).
    full_normals, full_matrices : ndarray, shape (ng, p, n), (ng, p, 2n, 2n)
        The same for all p impacts (G of every flight).
    contact_normals, b_upper, b_lower : ndarray, shape (ng, n), (ng,), (ng,)
        The stop coordinate, ``b`` and ``b_low`` of each geometry (the contact check).
    extra_normals, extra_signs, extra_positions : ndarray, shape (ng, q, n), (ng, q), (ng, q)
        The further stops (``Stops(extra=...)``) of each geometry, each checked on every
        flight (q = 0: none).
    coord0, coord1 : ndarray
        The grid's two axes (the secant predictor).
    signs : ndarray, shape (p,)
        ``+1``/``-1``: impact k is met moving up/down its stop coordinate.
    N : int
    symmetric, admits, two_sided, checks : bool
        Solve the half system; store the asymmetry; a lower stop; search contacts.
    pivots : ndarray of int64, shape (p,)
        0-based index of the position eliminated on each impact's section (the own mass
        of the stop it hits; one for all in a symmetric motion).
    seed0, seed1 : int
        The seed grid point, solved from ``x_seed`` (any distance).
    x_seed : ndarray
    tol, max_iter
        Newton's tolerance and iterations per grid point.
    max_change : float
        A solution farther than this (max-norm) from its predictor is refused.
    max_attempts : int
        Newton attempts per grid point at most (one per solved neighbour).
    unknowns, found .. asym
        Outputs, flat over the grid (``n0 * n1`` first axis), filled in place.

    Returns
    -------
    tuple
        ``(solved, attempts, newton_iterations, capped)``: points solved, Newton
        attempts, Newton iterations in all, and whether a contact-search grid was capped.
    """
    n0 = coord0.size
    n1 = coord1.size
    npts = n0 * n1
    size = 4 * npts + 1
    queue = np.empty((size, 2), dtype=np.int64)
    tried = np.zeros(npts, dtype=np.int8)
    head = 0
    tail = _push(queue, 0, size, seed0 * n1 + seed1, -1)
    solved = 0
    attempts = 0
    total_iterations = 0
    capped = False
    while head < tail:
        point = queue[head % size, 0]
        parent = queue[head % size, 1]
        head += 1
        if found[point] or tried[point] >= max_attempts:
            continue
        tried[point] += 1
        i0 = point // n1
        i1 = point % n1
        if parent < 0:
            x0 = x_seed.copy()
        else:
            x0 = unknowns[parent].copy()
            p0 = parent // n1
            p1 = parent % n1
            g0 = 2 * p0 - i0
            g1 = 2 * p1 - i1
            if 0 <= g0 < n0 and 0 <= g1 < n1 and found[g0 * n1 + g1]:
                if g0 != p0:
                    ratio = (coord0[i0] - coord0[p0]) / (coord0[p0] - coord0[g0])
                else:
                    ratio = (coord1[i1] - coord1[p1]) / (coord1[p1] - coord1[g1])
                x0 += ratio * (unknowns[parent] - unknowns[g0 * n1 + g1])
        fi = flow_index[i0, i1]
        gi = geometry_index[i0, i1]
        omega = omegas[fi]
        attempts += 1
        st = (sg[fi], sfree[fi], sxs[fi], sxd[fi])
        x, ok, it, sh = _newton(general, w[fi], a[fi], gam[fi], bet[fi], f[fi], u[fi],
                                ui[fi], lam[fi], V[fi], Vi[fi], Z[fi], st, omega, N, symmetric,
                                pivots, normals[gi], positions[gi], matrices[gi], x0, tol, max_iter)
        total_iterations += it
        if ok and parent >= 0:
            change = 0.0
            for k in range(x.size):
                change = max(change, abs(x[k] - x0[k]))
            ok = change <= max_change
        if not ok:
            continue
        found[point] = True
        solved += 1
        unknowns[point, :] = x
        iterations[point] = it
        delta[point] = math.atan2(math.sin(x[0]), math.cos(x[0]))
        phys, cap = _evaluate(general, w[fi], a[fi], gam[fi], bet[fi], f[fi], u[fi], ui[fi],
                              lam[fi], V[fi], Vi[fi], Z[fi], pw[fi], pa[fi], pk[fi], pj[fi],
                              st, omega, N, symmetric, admits, pivots, contact_normals[gi],
                              two_sided, b_upper[gi], b_lower[gi], extra_normals[gi],
                              extra_signs[gi], extra_positions[gi], full_normals[gi],
                              full_matrices[gi],
                              signs, sh, checks, point, rho, mu, gap, velocity, tau, state,
                              asym)
        physical[point] = phys
        stable[point] = rho[point] < 1.0
        capped = capped or cap
        for s in _STEPS:
            k0 = i0 + s[0]
            k1 = i1 + s[1]
            if 0 <= k0 < n0 and 0 <= k1 < n1:
                q = k0 * n1 + k1
                if not found[q] and tried[q] < max_attempts:
                    tail = _push(queue, tail, size, q, point)
    return solved, attempts, total_iterations, capped
