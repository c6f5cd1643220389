"""Compiled stability maps of N-p motions: Newton from solved neighbours over a grid.

The numba side of :func:`impactcont.analysis.maps.multi_impact_map`. One call sweeps a
whole grid of two parameters: every grid point is solved by Newton on the shooting
system of :mod:`impactcont.orbit.multi_impact` (or on the half system of a symmetric
motion, :mod:`impactcont.orbit.symmetry`), started from a solved neighbour (a secant
predictor through two solved points in line when there are two), and the solution is
evaluated (G or the half-map, multipliers, impact velocities, the contact check of
eq. 16 against every stop: U, L and each further stop on its own coordinate). A grid
point that is solved puts its unsolved neighbours in a first-in first-out queue; a point
whose Newton fails stays unsolved and seeds nothing (it is tried again, at most once per
neighbour, when another neighbour is solved).

The flows are stacked by value of the parameters that change them
(:class:`~impactcont.kernel.arrays.FlowTables`: each grid point's row of the tables of
:meth:`impactcont.orbit.flow.Flow.shooting_arrays` and ``forcing_arrays``), the stop
geometry by value of the parameters that move the stops
(:class:`~impactcont.kernel.arrays.GeometryTables`). Flights, Newton steps, G and the
contact search are those of :mod:`impactcont.kernel.shooting`, on the named structures
of :mod:`impactcont.kernel.arrays`.

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
:func:`sweep_stops` (compiled once; a single point is a 1 x 1 grid).
Importing :mod:`impactcont` does not import this module.
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np

from impactcont.kernel.arrays import (
    ContactStops,
    FlowTables,
    Forcing,
    GeometryTables,
    ImpactSequence,
    ShootingFlow,
    ShotFlights,
    SweepGrid,
    SweepMotion,
    SweepOutputs,
    SweepSettings,
    SweepStats,
)
from impactcont.kernel.jit import entry as _jit
from impactcont.kernel.jit import inner as _inner
from impactcont.kernel.linalg import _solve_in_place
from impactcont.kernel.newton_rules import FLOOR, TAKE, _converged, _trial_outcome
from impactcont.kernel.shooting import (
    ShootingWork,
    _clearances,
    _flights,
    _jacobian_product_into,
    _jacobian_wanted,
    _max_abs,
    _shooting_system_into,
    _shooting_work,
    _state_clearance,
    _stop_clearance,
    unknowns_scale,
)
from impactcont.kernel.stability import _multipliers_into

__all__ = ["sweep_stops"]


#: The four neighbours of a grid point.
_STEPS = ((1, 0), (-1, 0), (0, 1), (0, -1))


class NewtonWork(NamedTuple):
    """The arrays of a grid point's Newton (:func:`_newton`), allocated once per sweep."""

    current: ShotFlights
    """The shooting system at Newton's iterate (the solution's, on return)."""
    trial: ShotFlights
    """The shooting system at a trial point (copied into `current` when taken)."""
    shooting: ShootingWork
    """The shooting system's scratch."""
    iterates: np.ndarray
    """Two trial points, shape (2, 2np): one holds the iterate, the other the trial."""
    step: np.ndarray
    """Newton's step, shape (2np,)."""
    elimination: np.ndarray
    """The Jacobian eliminated by the step's solve, shape (2np, 2np)."""


class EvaluationWork(NamedTuple):
    """The arrays of a solution's evaluation (:func:`_evaluate`), allocated once per sweep."""

    G: np.ndarray
    """The motion's G (eq. 25), shape (2n, 2n)."""
    hessenberg: np.ndarray
    """G balanced and reduced to Hessenberg form, shape (2n, 2n)."""
    reflector: np.ndarray
    """The Householder vector of that reduction, shape (2n,)."""
    moduli: np.ndarray
    """The multipliers' moduli, shape (2n,)."""
    multipliers: np.ndarray
    """G's multipliers, shape (2n,), complex."""
    h2: np.ndarray
    """The stop coordinate's arrival velocity of each flight, shape (p,)."""
    image: np.ndarray
    """A mirrored state, shape (2n,)."""


class SweepWork(NamedTuple):
    """The arrays a sweep reuses at every grid point (allocated once per sweep): each
    point's Newton, shooting systems and evaluation write into them instead of allocating
    their own (the results are the same numbers). Each compiled call is given only the part
    it uses: numba counts a reference to every array of the structures a call is given, as
    the call starts and again as it returns (an atomic operation each)."""

    start: np.ndarray
    """The point's predicted unknowns, shape (2np,)."""
    newton: NewtonWork
    """Newton's arrays."""
    evaluation: EvaluationWork
    """The evaluation's arrays."""


@_inner
def _shot_buffers(p, m):
    """A :class:`~impactcont.kernel.arrays.ShotFlights` of `p` impacts of states of size
    `m`, its Jacobian (pm, pm)."""
    return ShotFlights(np.empty(p), np.empty(p), np.empty((p, m)), np.empty((p, m)),
                       np.empty((p, m)), np.empty((p, m, m)), np.empty((p, m)),
                       np.empty(p * m), np.empty((p * m, p * m)))


@_inner
def _sweep_work(q, p, m):
    """A :class:`SweepWork` for the `q` impacts solved of `p` with states of size `m`."""
    size = q * m
    newton = NewtonWork(_shot_buffers(q, m), _shot_buffers(q, m), _shooting_work(m),
                        np.empty((2, size)), np.empty(size), np.empty((size, size)))
    evaluation = EvaluationWork(np.empty((m, m)), np.empty((m, m)), np.empty(m), np.empty(m),
                                np.empty(m, dtype=np.complex128), np.empty(p), np.empty(m))
    return SweepWork(np.empty(size), newton, evaluation)


@_inner
def _period(omega, N, symmetric):
    """The time the system solved spans: the period ``2 pi N / omega``, or its half for the
    half system of a symmetric motion."""
    if symmetric:
        return math.pi * N / omega
    return 2.0 * math.pi * N / omega


@_inner
def _reflect(normals, pivot, starts, residual, jacobian, want_jacobian):
    """Close the half system of a symmetric motion in place: the last block ``D_0 X_{h-1}^-
    - X_0`` of the shooting system of its first h flights becomes ``D_h X_{h-1}^- + X_0``
    (the residual and, when wanted, the Jacobian; `pivot` the position eliminated on every
    section, `normals` the sections' normals)."""
    j = pivot
    h = starts.shape[0]
    m = starts.shape[1]
    n = m // 2
    last = (h - 1) * m
    for r in range(m):  # - X_0 -> + X_0 = - X_h
        residual[last + r] += 2.0 * starts[0, r]
    if want_jacobian:
        for r in range(m):  # dX_0/dz_0: unit columns, and x_j from the section
            if r != j:
                jacobian[last + r, h + (r if r < j else r - 1)] += 2.0
            else:
                for c in range(n):
                    if c != j:
                        jacobian[last + r, h + (c if c < j else c - 1)] -= (
                            2.0 * normals[0, c] / normals[0, j])


@_inner
def _take_trial(trial, current, with_jacobian):
    """Copy the shooting system at a trial point (`trial`) into `current`, its Jacobian when
    it was computed."""
    current.phases[:] = trial.phases
    current.flight_times[:] = trial.flight_times
    current.starts[:, :] = trial.starts
    current.arrivals[:, :] = trial.arrivals
    current.arrival_rates[:, :] = trial.arrival_rates
    current.transitions[:, :, :] = trial.transitions
    current.phase_columns[:, :] = trial.phase_columns
    current.residual[:] = trial.residual
    if with_jacobian:
        current.jacobian[:, :] = trial.jacobian


@_inner
def _newton(flights, forcing, impacts, period, symmetric, pivot, x0, settings, work):
    """Newton with backtracking from ``x0`` (not modified: the iterates are written into
    ``work.iterates``, the systems into ``work.current`` and ``work.trial``, a
    :class:`NewtonWork`): the iteration and stopping rules of
    :func:`impactcont.kernel.shooting.newton_solve`
    (:mod:`impactcont.kernel.newton_rules`) on the shooting system (full, or the
    half of a symmetric motion closed by :func:`_reflect`; `flights` a
    :class:`~impactcont.kernel.arrays.FlightFlow`, `period` the time solved,
    :func:`_period`; `impacts` the impacts solved, the first h of a symmetric motion),
    ``settings.tol``, ``settings.max_iter``. A trial point once the residual is below the
    tolerance is evaluated without the Jacobian (it only confirms the rounding floor, or
    ends the iteration); its Jacobian is computed only when another step needs it.

    Returns ``(x, converged, iterations)``: `x` one of ``work.iterates`` or `x0`, its
    system in ``work.current`` (valid until the next call). A trial taken is copied into
    ``work.current``: the structures are never bound to new names (numba counts a
    reference to each of their arrays at every such binding).
    """
    tol = settings.tol
    max_iter = settings.max_iter
    current, spare = work.current, work.trial
    free, other = work.iterates[0], work.iterates[1]  # the trial's array, and the iterate's
    step = work.step
    shooting = work.shooting
    normals = impacts.normals
    residual = current.residual
    x = x0
    want = _jacobian_wanted(x)
    _shooting_system_into(flights, forcing, impacts, period, x, want, current, shooting)
    if symmetric:
        _reflect(normals, pivot, current.starts, residual, current.jacobian, want)
    has_jacobian = True
    norm = _max_abs(residual)
    step_norm = np.inf
    it = 0
    for it in range(max_iter + 1):
        bound = tol * unknowns_scale(x)
        small, converged = _converged(norm, step_norm, bound, it, max_iter)
        if converged:
            return x, True, it
        if it == max_iter:
            break
        if not has_jacobian:  # a trial taken without it: the step needs it now
            _shooting_system_into(flights, forcing, impacts, period, x, want, current,
                                  shooting)
            if symmetric:
                _reflect(normals, pivot, current.starts, residual, current.jacobian, want)
            has_jacobian = True
        J = current.jacobian
        if not _finite(J):
            break
        M = work.elimination
        M[:, :] = J
        for r in range(step.size):
            step[r] = -residual[r]
        if not _solve_in_place(M, step):
            break
        lam_step = 1.0
        while True:
            trial = free
            for r in range(trial.size):
                trial[r] = x[r] + lam_step * step[r]
            _shooting_system_into(flights, forcing, impacts, period, trial, not small, spare,
                                  shooting)
            if symmetric:
                _reflect(normals, pivot, spare.starts, spare.residual, spare.jacobian,
                         not small)
            tnorm = _max_abs(spare.residual)
            outcome = _trial_outcome(tnorm, norm, small, bound, lam_step)
            if outcome == FLOOR:  # x is at its rounding floor
                return x, True, it
            if outcome == TAKE:
                break
            lam_step *= 0.5
        step_norm = lam_step * _max_abs(step)
        x = trial
        _take_trial(spare, current, not small)
        has_jacobian = not small
        norm = tnorm
        free, other = other, free  # the next trial must not overwrite x
    return x, False, it


@_inner
def _finite(A):
    """Every entry of the matrix ``A`` is finite (``np.all(np.isfinite(A))``)."""
    for r in range(A.shape[0]):
        for c in range(A.shape[1]):
            if not np.isfinite(A[r, c]):
                return False
    return True


@_inner
def _evaluate(flow, forcing, motion, full, stops, sh, checks, point, outputs, work):
    """Stability, velocities, flight times, states and the contact check of a solution.

    `motion` is the :class:`~impactcont.kernel.arrays.SweepMotion`, `full` the
    :class:`~impactcont.kernel.arrays.ImpactSequence` of all p impacts (G of every
    flight), `sh` the shot flights at the solution (the first h of a symmetric motion).
    The contact check (eq. 16) searches every flight against both stops U, L of the stop
    coordinate ``stops.normal`` and against each further stop of `stops`, as
    :func:`impactcont.kernel.shooting.motion_checks` does, and checks every stop at both
    ends of every flight but the stop hit there (:func:`_end_gap`); the gap is the
    smallest of all.

    Writes the grid point `point` (flat index) of `outputs` (`work`: the sweep's
    :class:`EvaluationWork`); returns ``(physical, capped)``.
    """
    symmetric, admits, signs = motion.symmetric, motion.admits, motion.signs
    omega = forcing.omega
    phases, taus, starts = sh.phases, sh.flight_times, sh.starts
    out_rho, out_mu, out_gap = outputs.rho, outputs.mu, outputs.gap
    out_velocity, out_tau = outputs.velocity, outputs.tau
    out_state, out_asym = outputs.state, outputs.asym
    p = signs.size
    m = full.matrices.shape[1]
    flights = taus.size  # h of a symmetric motion, else p
    h2 = work.h2
    G = work.G
    _jacobian_product_into(full, omega, sh, flights, G, h2)
    if symmetric:  # the half-map H = S G_{h-1} .. G_0: G = H^2
        for r in range(m - 1):
            for c in range(m):
                G[r, c] = -G[r, c]
    mu = work.multipliers
    _multipliers_into(G, mu, work.hessenberg, work.reflector, work.moduli)
    critical = mu[0] * mu[0] if symmetric else mu[0]  # G = H^2
    out_rho[point] = abs(critical)
    out_mu[point] = critical
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
            gu, _, gl, _, cap = _clearances(flow, forcing, stops, starts[k], phases[k], taus[k])
            if not (gu == gu and gl == gl):  # not searchable: a constant force on a free mode
                gap = np.nan
                break
            # a mirrored flight's clearance to one stop is the other's of its image
            gap = min(gap, gu, gl)
            capped = capped or cap
            for i in range(stops.extra_signs.size):  # each further stop, on its coordinate
                gx, _, cap = _stop_clearance(flow, forcing, stops, i, starts[k], phases[k],
                                             taus[k])
                if gx != gx:  # NaN: not searchable
                    gap = np.nan
                    break
                gap = min(gap, gx)
                capped = capped or cap
            if gap != gap:
                break
        if not gap > 0.0:  # NaN included
            physical = False
        mirrored = symmetric and _mirrored(stops, full, flights)
        ends, crossed = _end_gap(stops, full, sh.starts, sh.arrivals, flights, symmetric,
                                 mirrored, work.image)
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
def _end_gap(stops, full, starts, arrivals, flights, symmetric, mirrored, image):
    """Every stop's clearance at both ends of every flight, as
    :func:`impactcont.kernel.shooting.end_clearances` (the second half of a symmetric
    motion the mirror image of the first): ``(smallest clearance, crossed)``, ``crossed``
    when an end is past a stop by more than the rounding of its clearance.

    With `mirrored` stops (U and L at the same distance, no further stop) a mirrored
    flight's clearance to one stop is exactly the other's of its image (``-x``: the same
    sums negated), so the second half of a symmetric motion adds nothing and is skipped;
    `mirrored` is False otherwise, and the mirrored flights are checked on their states
    (``image``: scratch of a state's size).
    """
    p = full.signs.size
    m = starts.shape[1]
    last = flights if (symmetric and mirrored) else p
    smallest = np.inf
    crossed = False
    for k in range(last):
        q = k % flights
        nxt = (k + 1) % p
        sign = 1.0 if (k < flights or not symmetric) else -1.0
        for end in range(2):
            source = starts[q] if end == 0 else arrivals[q]
            own = k if end == 0 else nxt
            if sign < 0.0:
                for c in range(m):
                    image[c] = -source[c]
                x = image
            else:
                x = source
            g, _, tol = _state_clearance(x, full.normals[own], full.signs[own], stops.normal,
                                         stops.two_sided, stops.b, stops.b_low,
                                         stops.extra_normals, stops.extra_signs,
                                         stops.extra_positions)
            smallest = min(smallest, g)
            crossed = crossed or g < -tol
    return smallest, crossed


@_inner
def _mirrored(stops, full, flights):
    """The stops are the mirror images of each other for the half motion: U and L on one
    coordinate at the same distance (``b == b_low``), no further stop, and impact ``k + h``
    hits the mirror of impact k's stop (the same normal, the other side)."""
    if not (stops.two_sided and stops.b == stops.b_low and stops.extra_signs.size == 0):
        return False
    normals, signs = full.normals, full.signs
    for k in range(flights):
        if signs[k + flights] != -signs[k]:
            return False
        for c in range(normals.shape[1]):
            if normals[k + flights, c] != normals[k, c]:
                return False
    return True


@_inner
def _push(queue, tail, size, point, parent):
    queue[tail % size, 0] = point
    queue[tail % size, 1] = parent
    return tail + 1


@_jit
def sweep_stops(flows, geometries, motion, grid, settings, outputs):
    """Solve every grid point reachable from the seed through solved neighbours.

    Parameters
    ----------
    flows : tuple
        :class:`~impactcont.kernel.arrays.FlowTables` (a plain tuple): the flows'
        arrays (:meth:`impactcont.orbit.flow.Flow.shooting_arrays`, ``forcing_arrays``),
        each stacked on a first axis of flows, and the flow of each grid point.
    geometries : tuple
        :class:`~impactcont.kernel.arrays.GeometryTables`: the stop geometries
        (:class:`impactcont.orbit.stop_geometry.StopGeometry`) likewise.
    motion : tuple
        :class:`~impactcont.kernel.arrays.SweepMotion`: ``N``, the half system of a
        symmetric motion, the pivots and sides of the impacts, a lower stop.
    grid : tuple
        :class:`~impactcont.kernel.arrays.SweepGrid`: the two axes (the secant predictor)
        and the seed grid point, solved from its unknowns (any distance).
    settings : tuple
        :class:`~impactcont.kernel.arrays.SweepSettings`: Newton's tolerance and
        iterations per grid point, the largest change from the predictor, the contact
        search, the attempts per grid point.
    outputs : tuple
        :class:`~impactcont.kernel.arrays.SweepOutputs`, flat over the grid (``n0 * n1``
        first axis), filled in place.

    Returns
    -------
    SweepStats
        Points solved, Newton attempts, Newton iterations in all, and whether a
        contact-search grid was capped.
    """
    return _sweep(FlowTables(*flows), GeometryTables(*geometries), SweepMotion(*motion),
                  SweepGrid(*grid), SweepSettings(*settings), SweepOutputs(*outputs))


@_inner
def _flow_at(tables, i):
    """Flow `i` of the stacked `tables`: its :class:`~impactcont.kernel.arrays.ShootingFlow`
    and :class:`~impactcont.kernel.arrays.Forcing`."""
    flow = ShootingFlow(tables.general, tables.w[i], tables.a[i], tables.f[i], tables.u[i],
                        tables.ui[i], tables.lam[i], tables.V[i], tables.Vi[i], tables.pw[i],
                        tables.pa[i], tables.pk[i], tables.pj[i], tables.g[i], tables.free[i],
                        tables.xs[i], tables.xd[i])
    return flow, Forcing(tables.omega[i], tables.gamma[i], tables.beta[i], tables.Z[i])


@_inner
def _geometry_at(tables, i, motion):
    """Geometry `i` of the stacked `tables`: the impacts solved (the first q), all p
    impacts and the stops of the contact check."""
    q = tables.positions.shape[1]
    solved = ImpactSequence(motion.pivots[:q], tables.normals[i], motion.signs[:q],
                            tables.positions[i], tables.matrices[i])
    full = ImpactSequence(motion.pivots, tables.full_normals[i], motion.signs,
                          tables.full_positions[i], tables.full_matrices[i])
    stops = ContactStops(tables.contact_normals[i], motion.two_sided, tables.b_upper[i],
                         tables.b_lower[i], tables.extra_normals[i], tables.extra_signs[i],
                         tables.extra_positions[i])
    return solved, full, stops


@_inner
def _sweep(flows, geometries, motion, grid, settings, outputs):
    """:func:`sweep_stops` on the named structures."""
    coord0, coord1, x_seed = grid.coord0, grid.coord1, grid.x_seed
    max_attempts, max_change = settings.max_attempts, settings.max_change
    unknowns, found = outputs.unknowns, outputs.found
    n0 = coord0.size
    n1 = coord1.size
    npts = n0 * n1
    size = 4 * npts + 1
    queue = np.empty((size, 2), dtype=np.int64)
    tried = np.zeros(npts, dtype=np.int8)
    head = 0
    tail = _push(queue, 0, size, grid.seed0 * n1 + grid.seed1, -1)
    solved = 0
    attempts = 0
    total_iterations = 0
    capped = False
    flow_row = flows.index[grid.seed0, grid.seed1]
    flow, forcing = _flow_at(flows, flow_row)
    flights = _flights(flow)
    geometry_row = geometries.index[grid.seed0, grid.seed1]
    solved_impacts, full, stops = _geometry_at(geometries, geometry_row, motion)
    work = _sweep_work(geometries.positions.shape[1], motion.signs.size,
                       geometries.matrices.shape[2])
    x0 = work.start
    newton, evaluation = work.newton, work.evaluation
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
            x0[:] = x_seed
        else:
            x0[:] = unknowns[parent]
            p0 = parent // n1
            p1 = parent % n1
            g0 = 2 * p0 - i0
            g1 = 2 * p1 - i1
            if 0 <= g0 < n0 and 0 <= g1 < n1 and found[g0 * n1 + g1]:
                if g0 != p0:
                    ratio = (coord0[i0] - coord0[p0]) / (coord0[p0] - coord0[g0])
                else:
                    ratio = (coord1[i1] - coord1[p1]) / (coord1[p1] - coord1[g1])
                grand = g0 * n1 + g1
                for c in range(x0.size):
                    x0[c] += ratio * (unknowns[parent, c] - unknowns[grand, c])
        if flows.index[i0, i1] != flow_row:  # the flow and geometry of the point's row
            flow_row = flows.index[i0, i1]
            flow, forcing = _flow_at(flows, flow_row)
            flights = _flights(flow)
        if geometries.index[i0, i1] != geometry_row:
            geometry_row = geometries.index[i0, i1]
            solved_impacts, full, stops = _geometry_at(geometries, geometry_row, motion)
        attempts += 1
        x, ok, it = _newton(flights, forcing, solved_impacts,
                            _period(forcing.omega, motion.N, motion.symmetric), motion.symmetric,
                            motion.pivots[0], x0, settings, newton)
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
        outputs.iterations[point] = it
        outputs.delta[point] = math.atan2(math.sin(x[0]), math.cos(x[0]))
        phys, cap = _evaluate(flow, forcing, motion, full, stops, newton.current,
                              settings.checks, point, outputs, evaluation)
        outputs.physical[point] = phys
        outputs.stable[point] = outputs.rho[point] < 1.0
        capped = capped or cap
        for s in _STEPS:
            k0 = i0 + s[0]
            k1 = i1 + s[1]
            if 0 <= k0 < n0 and 0 <= k1 < n1:
                q = k0 * n1 + k1
                if not found[q] and tried[q] < max_attempts:
                    tail = _push(queue, tail, size, q, point)
    return SweepStats(solved, attempts, total_iterations, capped)
