"""The modal arrays the kernel's entry points take, as one typed structure.

The modal form of eq. (5)-(7): mass-normalised modes ``u`` (``u^T M u = I``), their
inverse ``u^-1 = u^T M``, the natural frequencies ``omega_i``, the decay rates ``a_i``
of proportional damping (eq. 6), the modal forces ``u^T F`` and the rounding scale of
``omega_i^2``; with them the row of ``u`` and the column of ``u^-1`` of the impacting
mass, which is all of the modes the impact law of eq. (4) sees (``q = [0; u_j.]``,
``p = [0; (u^-1)_.j]`` of the rank-one impact map). :class:`ModalArrays` is a
:class:`typing.NamedTuple`, so numba passes it to compiled code as one argument (its
fields typed once: C-contiguous float64 arrays) and Python unpacks it by name. A compiled
call takes its fields as a plain tuple (:meth:`ModalArrays.as_tuple`): numba types an exact
tuple in its C dispatcher, a named one through its Python ``typeof`` (about 1 us more per
call, a tenth of the kernel call of an N-1 orbit of two masses; ``docs/kernel.md``).

:func:`modal_arrays` is the one place it is built and checked; this module imports
neither numba nor anything of impactcont's.

:class:`FirstOrderArrays` names the fields of the first-order basis of any damping
matrix C (:attr:`impactcont.model.first_order.FirstOrderBasis.kernel_arrays`), the
inputs of :mod:`impactcont.kernel.general`.

The N-p shooting path (:mod:`impactcont.kernel.shooting`) and the map sweep
(:mod:`impactcont.kernel.sweep`) take the same kind of structures, a few per call: the flow
between impacts (:class:`ShootingFlow`), the forcing at omega (:class:`Forcing`, its omega
derivatives :class:`ForcingDerivatives`), the motion's impacts (:class:`ImpactSequence`),
the stops of the contact check (:class:`ContactStops`) and the shot flights
(:class:`ShotFlights`); a map stacks flows and stop geometries (:class:`FlowTables`,
:func:`stack_flows`, :class:`GeometryTables`) and names its motion, grid, settings and
outputs (:class:`SweepMotion`, :class:`SweepGrid`, :class:`SweepSettings`,
:class:`SweepOutputs`). Results are named records (:class:`NewtonResult`,
:class:`MotionChecks`, :class:`PalcResult`, :class:`BranchLinearization`,
:class:`ForcedAmplitudes`, :class:`SweepStats`). Each is a module-level
:class:`typing.NamedTuple`, so the compiled functions that take or return one are cached
on disk (numba pickles its class by name).
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

__all__ = ["BranchLinearization", "CheckedFlights", "ContactStops", "CorrectorSettings",
           "CorrectorStep", "Embedding", "FirstOrderArrays", "FirstOrderFlight", "FlightArrays",
           "FlightFlow", "FlowTables", "ForcedAmplitudes", "Forcing", "ForcingDerivatives",
           "GeometryTables", "HeldForcing", "HeldSegments", "ImpactSequence", "ModalArrays",
           "ModalFlight", "MotionChecks", "NewtonResult", "PalcResult", "ShootingFlow",
           "ShotFlights", "StickyFlights", "StopSeries", "SweepGrid", "SweepMotion", "SweepOutputs",
           "SweepSettings", "SweepStats", "modal_arrays", "stack_flows"]


class ModalArrays(NamedTuple):
    """The modal arrays of one oscillator, as the compiled kernel takes them.

    Every field is a C-contiguous float64 array (:func:`modal_arrays` checks it). The
    order is that of the positional tuple it replaces, so ``w, a, f, u, ui, eig_err,
    u0, ui0 = arrays`` still reads it.
    """

    w: np.ndarray
    """Natural frequencies ``omega_i``, shape (n,)."""
    a: np.ndarray
    """Decay rates ``a_i = xi_i omega_i`` (eq. 6), shape (n,)."""
    f: np.ndarray
    """Modal forces ``u^T F`` (eq. 7), shape (n,)."""
    u: np.ndarray
    """Mass-normalised modes, columns ``u_.i``, shape (n, n)."""
    ui: np.ndarray
    """``u^-1 = u^T M``, shape (n, n)."""
    eig_err: np.ndarray
    """Rounding-error scale of ``omega_i^2``, shape (n,)."""
    u0: np.ndarray
    """Row of ``u`` of the impacting mass (``u_j.``), shape (n,)."""
    ui0: np.ndarray
    """Column of ``u^-1`` of the impacting mass (``(u^-1)_.j``), shape (n,)."""

    def as_tuple(self) -> tuple[np.ndarray, ...]:
        """The fields as a plain tuple, in this order: the argument of the compiled entry
        points (:func:`impactcont.kernel.closed_form.point_orbits`, ``phase_orbit``,
        ``block_map``), which unpack it as ``w, a, f, u, ui, eig_err, u0, ui0``."""
        return tuple(self)


def _real_array(name: str, value: object, shape: tuple[int, ...]) -> np.ndarray:
    """`value` as a C-contiguous float64 array of `shape`, or a clear refusal."""
    if not isinstance(value, np.ndarray):
        raise TypeError(f"modal_arrays: {name} must be a numpy array of real numbers; got "
                        f"{type(value).__name__} {value!r}")
    if value.dtype.kind not in "fiu":
        raise TypeError(f"modal_arrays: {name} must hold real numbers (float or integer "
                        f"dtype); got dtype {value.dtype}")
    if value.shape != shape:
        raise ValueError(f"modal_arrays: {name} must have shape {shape} (n = {shape[0]} "
                         f"modes, from w); got shape {value.shape}")
    return np.ascontiguousarray(value, dtype=np.float64)


def modal_arrays(w: np.ndarray, a: np.ndarray, f: np.ndarray, u: np.ndarray, ui: np.ndarray,
                 eig_err: np.ndarray | None = None, *, mass: int = 0) -> ModalArrays:
    """Check the modal arrays and build :class:`ModalArrays`.

    Parameters
    ----------
    w, a, f : ndarray, shape (n,)
        Natural frequencies, decay rates (eq. 6), modal forces (eq. 7).
    u, ui : ndarray, shape (n, n)
        Mass-normalised modes and their inverse ``u^T M`` (eq. 5).
    eig_err : ndarray, shape (n,), optional
        Rounding-error scale of ``omega_i^2`` (zero when not given).
    mass : int
        The impacting mass, 0-based (the row of ``u``, the column of ``u^-1`` the impact
        law of eq. 4 sees): the model's, ``stops.mass - 1``.

    Returns
    -------
    ModalArrays
        C-contiguous float64 copies where needed (the inputs themselves when they
        already are).

    Raises
    ------
    TypeError
        If an array is not a numpy array of real numbers (complex, bool, object), or
        `mass` is not an integer.
    ValueError
        If a shape does not match ``n = w.size`` or `mass` is not in ``0..n-1``.
    """
    if not isinstance(w, np.ndarray) or w.ndim != 1:
        raise (TypeError if not isinstance(w, np.ndarray) else ValueError)(
            f"modal_arrays: w must be a one-dimensional numpy array (the natural "
            f"frequencies); got {type(w).__name__} of shape {np.shape(w)}")
    n = w.shape[0]
    vec, mat = (n,), (n, n)
    w = _real_array("w", w, vec)
    a = _real_array("a", a, vec)
    f = _real_array("f", f, vec)
    u = _real_array("u", u, mat)
    ui = _real_array("ui", ui, mat)
    eig_err = (np.zeros(n) if eig_err is None else _real_array("eig_err", eig_err, vec))
    if isinstance(mass, (bool, np.bool_)) or not isinstance(mass, (int, np.integer)):
        raise TypeError(f"modal_arrays: mass must be an integer (the impacting mass, 0-based); "
                        f"got {mass!r}")
    if not 0 <= mass < n:
        raise ValueError(f"modal_arrays: mass must be in 0..{n - 1} (0-based, n = {n} "
                         f"masses); got {mass!r}")
    return ModalArrays(w, a, f, u, ui, eig_err, np.ascontiguousarray(u[mass]),
                       np.ascontiguousarray(ui[:, mass]))


class FirstOrderArrays(NamedTuple):
    """The first-order basis of any damping matrix C as the compiled first-order path
    takes it (:mod:`impactcont.kernel.general`), by name.

    The order is that of
    :attr:`impactcont.model.first_order.FirstOrderBasis.kernel_arrays`;
    ``FirstOrderArrays._make(basis.kernel_arrays)`` reads it (and returns it unchanged
    when it already is one). The last six fields are the arguments of the contact search
    in their order (:meth:`contact_arguments`).
    """

    lam: np.ndarray
    """Eigenvalues ``lambda_k`` of the first-order system, complex, shape (2n,)."""
    V: np.ndarray
    """Eigenvectors (columns), complex, shape (2n, 2n)."""
    V_inv: np.ndarray
    """``V^-1``, complex, shape (2n, 2n)."""
    A: np.ndarray
    """The first-order system matrix, shape (2n, 2n)."""
    impact_column: np.ndarray
    """The column the impact law of eq. (4) adds to the state, shape (2n,)."""
    w_p: np.ndarray
    """Frequencies of the scalar pairs (:attr:`FirstOrderBasis.scalar_pairs`)."""
    a_p: np.ndarray
    """Decay rates of the scalar pairs."""
    k_p: np.ndarray
    """First eigenvalue index of each pair (int64)."""
    j_p: np.ndarray
    """Second eigenvalue index of each pair (int64)."""
    M: np.ndarray
    """Mass matrix, shape (n, n)."""
    K: np.ndarray
    """Stiffness matrix, shape (n, n)."""
    C: np.ndarray
    """Damping matrix, shape (n, n)."""
    search_lam: np.ndarray
    """``lambda`` again, for the contact search."""
    search_v0: np.ndarray
    """The first row of ``V`` (mass 1's displacement), for the contact search."""
    search_w_p: np.ndarray
    """``w_p`` again, for the contact search."""
    search_a_p: np.ndarray
    """``a_p`` again, for the contact search."""
    search_k_p: np.ndarray
    """``k_p`` again, for the contact search."""
    search_j_p: np.ndarray
    """``j_p`` again, for the contact search."""

    def contact_arguments(self) -> tuple[np.ndarray, ...]:
        """``(lambda, V[0], w_p, a_p, k_p, j_p)``: the arguments of the contact search."""
        return (self.search_lam, self.search_v0, self.search_w_p, self.search_a_p,
                self.search_k_p, self.search_j_p)


# -- the N-p shooting path (kernel/shooting.py, kernel/sweep.py) ------------------------------
# Every structure below is what one compiled argument of the shooting path holds, by name.
# Python builds them (orbit/flow.py, orbit/multi_impact.py, the map's tables) and hands a
# compiled entry point their plain tuple (``tuple(structure)``: numba types an exact tuple in
# its C dispatcher, a named one through its Python ``typeof``, several microseconds for
# twenty arrays); the entry point names it again (``ShootingFlow(*flow)``) and everything
# compiled below it reads fields by name. Results come back as named records the same way.


class ShootingFlow(NamedTuple):
    """The flow of eq. (9) between impacts as the shooting kernel takes it, omega aside.

    Both flows of :mod:`impactcont.orbit.flow` fill one structure (fixed field types, so
    that every entry point compiles once): the modal flow (proportional damping) its
    modal arrays, the first-order flow (any C) its complex modes; the other's fields are
    empty. Built once per flow by :meth:`impactcont.orbit.flow.Flow.shooting_arrays`.
    """

    general: bool
    """True for the first-order flow (any C, complex F), False for the modal flow."""
    w: np.ndarray
    """Natural frequencies ``omega_i`` (modal), shape (n,)."""
    a: np.ndarray
    """Decay rates ``a_i`` (eq. 6; modal), shape (n,)."""
    f: np.ndarray
    """Modal forces ``u^T F`` (eq. 7; modal), shape (n,)."""
    u: np.ndarray
    """Mass-normalised modes (modal), shape (n, n)."""
    ui: np.ndarray
    """``u^-1 = u^T M`` (modal), shape (n, n)."""
    lam: np.ndarray
    """Eigenvalues of the first-order system (first order), complex, shape (2n,)."""
    V: np.ndarray
    """Its eigenvectors (first order), complex, shape (2n, 2n)."""
    Vi: np.ndarray
    """``V^-1`` (first order), complex, shape (2n, 2n)."""
    pw: np.ndarray
    """Frequencies of the scalar pairs the contact search sums (the modes, modal)."""
    pa: np.ndarray
    """Decay rates of the scalar pairs."""
    pk: np.ndarray
    """First eigenvalue index of each pair (int64)."""
    pj: np.ndarray
    """Second eigenvalue index of each pair (int64)."""
    g: np.ndarray
    """Modal constant force ``u^T F_static`` (modal; empty for the first-order flow)."""
    free: np.ndarray
    """The free modes, ``w_i = 0`` (bool; modal)."""
    xs: np.ndarray
    """Constant part ``X_s`` of the static response (first order), shape (2n,)."""
    xd: np.ndarray
    """Drift ``d`` of the damped free modes per unit time (first order), shape (2n,)."""


    def flight_arrays(self) -> FlightArrays:
        """The fields one flight reads (:class:`FlightArrays`): the flow without the contact
        search's scalar pairs, what :func:`~impactcont.kernel.shooting.shooting_system` and
        :func:`~impactcont.kernel.shooting.newton_solve` take."""
        return FlightArrays(self.general,
                            *(getattr(self, name) for name in FlightArrays._fields[1:]))


class ModalFlight(NamedTuple):
    """What a flight of the modal flow reads (:class:`ShootingFlow`'s fields of the same
    names): the modal form of eq. (5)-(7) and the constant force."""

    w: np.ndarray
    a: np.ndarray
    f: np.ndarray
    u: np.ndarray
    ui: np.ndarray
    g: np.ndarray
    free: np.ndarray


class FirstOrderFlight(NamedTuple):
    """What a flight of the first-order flow reads (:class:`ShootingFlow`'s fields of the
    same names): its complex modes and the constant force's offset and drift."""

    lam: np.ndarray
    V: np.ndarray
    Vi: np.ndarray
    xs: np.ndarray
    xd: np.ndarray


# its fields are ModalFlight's and FirstOrderFlight's after `general`, declared there only
FlightArrays = NamedTuple("FlightArrays", [("general", bool)] + [
    (name, np.ndarray) for name in ModalFlight._fields + FirstOrderFlight._fields])
FlightArrays.__doc__ = """The fields of :class:`ShootingFlow` one flight reads (the scalar
pairs of the contact search left out), flat: ``general``, then those of
:class:`ModalFlight` and :class:`FirstOrderFlight`; the argument of the shooting entry points
(:meth:`ShootingFlow.flight_arrays`), named on entry as :class:`FlightFlow`."""


class FlightFlow(NamedTuple):
    """The flow as the compiled flights take it: ``general`` selects the part read, so that
    each flight function is compiled for its own small structure."""

    general: bool
    modal: ModalFlight
    first_order: FirstOrderFlight


class Forcing(NamedTuple):
    """The harmonic forcing at one omega: the steady response of eq. (7)."""

    omega: float
    """Forcing frequency."""
    gamma: np.ndarray
    """Steady modal amplitudes ``gamma_i`` (modal; empty for the first-order flow)."""
    beta: np.ndarray
    """Steady modal amplitudes ``beta_i`` (modal)."""
    Z: np.ndarray
    """Complex steady state amplitude, ``X_p = Re(Z e^{i omega t})`` (first order), (2n,)."""


class ForcingDerivatives(NamedTuple):
    """``d/d omega`` of :class:`Forcing`'s amplitudes (the other flow's fields empty)."""

    dgamma: np.ndarray
    """``d gamma_i / d omega`` (modal)."""
    dbeta: np.ndarray
    """``d beta_i / d omega`` (modal)."""
    dZ: np.ndarray  # noqa: N815 - the paper's Z, differentiated
    """``dZ / d omega`` (first order)."""


class ImpactSequence(NamedTuple):
    """The p impacts of a motion, each on its own stop
    (:class:`impactcont.orbit.stop_geometry.StopGeometry`)."""

    pivots: np.ndarray
    """0-based index ``j_k`` of the position eliminated on impact k's section (int64)."""
    normals: np.ndarray
    """Normal ``n_k`` of the stop coordinate of each impact, shape (p, n)."""
    signs: np.ndarray
    """``+1``/``-1``: impact k meets its stop moving up/down its coordinate, shape (p,)."""
    positions: np.ndarray
    """Stop position ``c_k`` of each impact, shape (p,)."""
    matrices: np.ndarray
    """Impact matrix ``D_k`` (eq. 4) of each impact, shape (p, 2n, 2n)."""


class HeldSegments(NamedTuple):
    """The sticking phases of a motion (:mod:`impactcont.orbit.held_flow`), one row per
    impact k (zeros where no stick follows it); ``r = 2n - 2`` the held system's states.

    The held state is ``X = X_c + L Y`` with ``Y`` the first-order flow of the held system
    of n - 1 masses (``lam, V, Vi, xs, xd`` and its forcing ``Z`` as
    :class:`FirstOrderFlight` and :class:`Forcing` name them) from ``Y(0) = L^+ (X_k -
    X_c)``; the pressing force is ``p = grad . X + Re(force e^{i theta}) + level``.
    """

    sticks: np.ndarray
    """A sticking phase follows impact k (bool, (p,))."""
    lifts: np.ndarray
    """``L = diag(P, P)``, (p, 2n, r)."""
    inverses: np.ndarray
    """``L^+``, the M-weighted left inverse, (p, r, 2n)."""
    offsets: np.ndarray
    """``X_c = [x_c; 0]``, (p, 2n)."""
    lam: np.ndarray
    """The held system's first-order eigenvalues, (p, r) complex."""
    V: np.ndarray
    """Its eigenvectors, (p, r, r) complex."""
    Vi: np.ndarray
    """``V^-1``, (p, r, r) complex."""
    xs: np.ndarray
    """The constant force's offset ``X_s`` of the held system, (p, r)."""
    xd: np.ndarray
    """Its drift ``d`` per unit time, (p, r)."""
    Z: np.ndarray
    """The held system's complex steady amplitude at omega, (p, r) complex."""
    grads: np.ndarray
    """``dp/dX``, (p, 2n)."""
    forces: np.ndarray
    """The forcing's part of the pressing force, ``p = .. + Re(force e^{i theta})``, (p,)
    complex."""
    levels: np.ndarray
    """The constant force's part of the pressing force, (p,)."""
    shifts: np.ndarray
    """Where the contact search of the flight from the release starts after it (at most half
    the flight), (p,): there ``s = c``, ``s' = 0`` and ``s'' = 0``."""
    restitutions: np.ndarray
    """The restitution ``R`` of the stop held after impact k, (p,): ``R > 0`` enters the
    sticking phase through complete chatter (:func:`impactcont.kernel.shooting._chatter_map`),
    ``R = 0`` by the plastic impact k itself."""
    chatter_impacts: np.ndarray
    """How many impacts of the chatter after impact k are resolved before the jump to their
    accumulation point (int, (p,); 0 where ``R = 0``)."""


class HeldForcing(NamedTuple):
    """The held systems of a motion's sticking phases as their forced amplitudes need them at
    any omega (:func:`~impactcont.kernel.shooting.sticky_palc_correct`): ``(K_r - omega^2
    M_r + i omega C_r) y_hat = F_r`` (:func:`impactcont.kernel.general.forced_response`),
    one row per impact k (zeros where no stick follows it); ``n - 1`` masses held."""

    M: np.ndarray
    """``P^T M P``, (p, n-1, n-1)."""
    K: np.ndarray
    """``P^T K P``, (p, n-1, n-1)."""
    C: np.ndarray
    """``P^T C P``, (p, n-1, n-1)."""
    F: np.ndarray
    """``P^T F``, (p, n-1) complex."""


class StickyFlights(NamedTuple):
    """:func:`impactcont.kernel.shooting.sticky_system`'s result, named: the fields of
    :class:`impactcont.orbit.sticky.StickyShooting`."""

    phases: np.ndarray
    stick_times: np.ndarray
    flight_times: np.ndarray
    starts: np.ndarray
    releases: np.ndarray
    release_phases: np.ndarray
    held_transitions: np.ndarray
    held_phase_columns: np.ndarray
    held_rates: np.ndarray
    arrivals: np.ndarray
    arrival_rates: np.ndarray
    transitions: np.ndarray
    phase_columns: np.ndarray
    residual: np.ndarray
    jacobian: np.ndarray
    search_shifts: np.ndarray
    search_starts: np.ndarray
    search_phases: np.ndarray
    accumulations: np.ndarray
    accumulation_phases: np.ndarray
    chatter_times: np.ndarray
    chatter_status: np.ndarray


class ContactStops(NamedTuple):
    """Every stop a flight is checked against (eq. 16): U and L on the stop coordinate
    ``s = normal . x`` and the further stops, each on its own coordinate."""

    normal: np.ndarray
    """Normal of the stop coordinate of U and L, shape (n,)."""
    two_sided: bool
    """A lower stop L is present."""
    b: float
    """Position of U: ``s = b``."""
    b_low: float
    """``-`` position of L: ``s = -b_low``."""
    extra_normals: np.ndarray
    """Normals of the further stops, shape (q, n)."""
    extra_signs: np.ndarray
    """Their sides (``+1``/``-1``), shape (q,)."""
    extra_positions: np.ndarray
    """Their positions ``c`` (``s = c``), shape (q,)."""


class ShotFlights(NamedTuple):
    """The shooting system at one set of unknowns
    (:func:`impactcont.kernel.shooting.shooting_system`): the fields of
    :class:`impactcont.orbit.multi_impact.Shooting`."""

    phases: np.ndarray
    """``theta_k``, shape (p,)."""
    flight_times: np.ndarray
    """``tau_k``, shape (p,)."""
    starts: np.ndarray
    """``X_k`` after impact k, shape (p, 2n)."""
    arrivals: np.ndarray
    """``X_k^-`` at the end of flight k, shape (p, 2n)."""
    arrival_rates: np.ndarray
    """``X'(tau_k^-)``, shape (p, 2n)."""
    transitions: np.ndarray
    """``Phi(tau_k)``, shape (p, 2n, 2n)."""
    phase_columns: np.ndarray
    """``dX_k^-/d theta_k``, shape (p, 2n)."""
    residual: np.ndarray
    """``[r_0, .., r_{p-1}]``, shape (2np,)."""
    jacobian: np.ndarray
    """``dr/du``, shape (2np, 2np), or (0, 0) when not asked for."""

    def checked(self) -> CheckedFlights:
        """The fields :func:`~impactcont.kernel.shooting.motion_checks` reads."""
        return CheckedFlights(self.phases, self.flight_times, self.starts, self.transitions,
                              self.phase_columns, self.arrival_rates)


class CheckedFlights(NamedTuple):
    """The fields of :class:`ShotFlights` :func:`~impactcont.kernel.shooting.motion_checks`
    reads (:meth:`ShotFlights.checked`)."""

    phases: np.ndarray
    flight_times: np.ndarray
    starts: np.ndarray
    transitions: np.ndarray
    phase_columns: np.ndarray
    arrival_rates: np.ndarray


class NewtonResult(NamedTuple):
    """What :func:`~impactcont.kernel.shooting.newton_solve` returns."""

    x: np.ndarray
    """The last iterate."""
    status: int
    """``CONVERGED`` (0) or ``FAILED`` (1)."""
    iterations: int
    residual_norm: float
    """Max-norm of the residual at ``x``."""
    step_norm: float
    """Max-norm of the last update."""
    shot: ShotFlights
    """The shooting system at ``x``, with its Jacobian."""

    @classmethod
    def from_kernel(cls, raw: tuple) -> NewtonResult:
        """The record of :func:`~impactcont.kernel.shooting.newton_solve`'s plain tuple (a
        compiled function returns plain tuples: numba boxes a named one through a Python
        call of its class, about 0.7 us per record)."""
        x, status, iterations, residual_norm, step_norm, shot = raw
        return cls(x, status, iterations, residual_norm, step_norm, ShotFlights._make(shot))


class MotionChecks(NamedTuple):
    """What :func:`~impactcont.kernel.shooting.motion_checks` returns."""

    jacobians: np.ndarray
    """``G_k`` of eq. (25), shape (p, 2n, 2n)."""
    h2: np.ndarray
    """Arrival velocity of the stop coordinate at the end of each flight, shape (p,)."""
    G: np.ndarray
    """``G_{p-1} .. G_0``, shape (2n, 2n)."""
    multipliers: np.ndarray
    """Eigenvalues of G, largest modulus first (complex)."""
    gap_upper: np.ndarray
    time_upper: np.ndarray
    gap_lower: np.ndarray
    time_lower: np.ndarray
    gap_extra: np.ndarray
    """Shape (p, q): each further stop."""
    time_extra: np.ndarray
    capped: bool
    """A search grid was capped."""


class ForcedAmplitudes(NamedTuple):
    """What :func:`~impactcont.kernel.shooting.forced_amplitudes` returns."""

    gamma: np.ndarray
    beta: np.ndarray
    dgamma: np.ndarray
    dbeta: np.ndarray
    worst: float
    """Largest relative error bound of the amplitudes from the eigenvalue errors."""
    resonant: bool
    """An undamped forced mode at ``omega_i = omega``."""


class Embedding(NamedTuple):
    """The unknowns a corrector solves for: ``u = E v + c / omega``, the first `rows`
    equations (the identity, zero and all rows for an N-p motion; the half-motion's
    embedding for a symmetric one, :class:`impactcont.orbit.symmetry.HalfUnknowns`)."""

    E: np.ndarray
    c: np.ndarray
    rows: int


class CorrectorStep(NamedTuple):
    """One pseudo-arclength step: the predicted point ``[v, omega]``, the tangent and the
    weights of the arclength condition."""

    predicted: np.ndarray
    tangent: np.ndarray
    weights: np.ndarray


class CorrectorSettings(NamedTuple):
    """How :func:`~impactcont.kernel.shooting.palc_correct` iterates."""

    tol: float
    max_iter: int
    singular: float
    """Frobenius condition bound above which a bordered matrix is flagged."""
    hyperplane: bool
    """Newton on the hyperplane only (no residual test, no tangent)."""


class PalcResult(NamedTuple):
    """What :func:`~impactcont.kernel.shooting.palc_correct` returns."""

    state: np.ndarray
    iterations: int
    status: int
    omega: float
    residual_norm: float
    tangent: np.ndarray
    worst: float
    worst_omega: float
    flagged: np.ndarray
    last_update: float


class StopSeries(NamedTuple):
    """A stop coordinate ``s = n . x`` along one flight, as the contact search of eq. (16)
    sums it (:func:`impactcont.kernel.contact.stop_maximum`): a forced part, free modes
    (or the first-order flow's scalar pairs), a constant level and a polynomial part."""

    w: np.ndarray
    """Frequencies of the free terms."""
    a: np.ndarray
    """Their decay rates."""
    weights: np.ndarray
    """Their weights in ``s`` (``n^T U``; ones for the scalar pairs)."""
    gamma: float
    """Forced part ``gamma cos(omega t + theta) + beta sin(omega t + theta)`` of ``s``."""
    beta: float
    dy: np.ndarray
    """Free deviation of each term: displacement."""
    dv: np.ndarray
    """... and velocity."""
    level: float
    """The constant the constant force adds to ``s``."""
    pg: np.ndarray
    """Weighted static force of each free mode it pushes (modal flow)."""
    pd: np.ndarray
    """Decay rate of each such mode."""
    p1: float
    """Drift of ``s`` per unit time (first-order flow)."""


class BranchLinearization(NamedTuple):
    """What :func:`~impactcont.kernel.shooting.branch_linearization` returns."""

    shot: ShotFlights
    """The shooting system with its Jacobian."""
    extended: np.ndarray
    """``[dr/dx | dr/d omega]``, shape (2np, 2np + 1)."""


# -- the map sweep (kernel/sweep.py) ----------------------------------------------------------
# its fields are those of ShootingFlow and Forcing, declared there only
FlowTables = NamedTuple("FlowTables", [("general", bool)] + [
    (name, np.ndarray) for name in ShootingFlow._fields[1:] + Forcing._fields + ("index",)])
FlowTables.__doc__ = """The flows of a map's grid, stacked: each field of :class:`ShootingFlow`
(but ``general``, one for all) and of :class:`Forcing` with a first axis of flows, and
``index``, the flow (row) of each grid point (int64, shape (n0, n1); :func:`stack_flows`)."""


def stack_flows(flows: list[tuple[ShootingFlow, Forcing]], index: np.ndarray) -> FlowTables:
    """:class:`FlowTables` of `flows` (each a flow and its forcing) and the grid's `index`.

    Raises
    ------
    ValueError
        When a field's shape differs between two flows (the first-order modes change their
        structure across the grid), naming the field.
    """
    if not flows:
        raise ValueError("stack_flows: flows must hold at least one (flow, forcing) pair")
    columns = {}
    for name in ShootingFlow._fields[1:] + Forcing._fields:
        values = [getattr(flow if name in ShootingFlow._fields else forcing, name)
                  for flow, forcing in flows]
        if len({np.shape(v) for v in values}) != 1:
            raise ValueError(f"stack_flows: field {name!r} has shapes "
                             f"{sorted({np.shape(v) for v in values})} across the flows; "
                             "every flow of a map must have the same")
        columns[name] = np.ascontiguousarray(np.stack(values))
    return FlowTables(general=bool(flows[0][0].general), **columns,
                      index=np.ascontiguousarray(index, dtype=np.int64))


class GeometryTables(NamedTuple):
    """The stop geometries of a map's grid, stacked on a first axis of geometries
    (read-only arrays: the types the shooting's Python callers pass)."""

    positions: np.ndarray
    """``c_k`` of the q impacts solved (h of a symmetric motion, else p), (ng, q)."""
    normals: np.ndarray
    """Their normals, (ng, q, n)."""
    matrices: np.ndarray
    """Their impact matrices, (ng, q, 2n, 2n)."""
    full_normals: np.ndarray
    """The normals of all p impacts, (ng, p, n)."""
    full_positions: np.ndarray
    """The stop positions of all p impacts, (ng, p)."""
    full_matrices: np.ndarray
    """The impact matrices of all p impacts, (ng, p, 2n, 2n)."""
    contact_normals: np.ndarray
    """The stop coordinate of U and L, (ng, n)."""
    b_upper: np.ndarray
    """``b``, (ng,)."""
    b_lower: np.ndarray
    """``b_low``, (ng,)."""
    extra_normals: np.ndarray
    """The further stops' normals, (ng, q', n)."""
    extra_signs: np.ndarray
    extra_positions: np.ndarray
    index: np.ndarray
    """The geometry (row) of each grid point, int64, shape (n0, n1)."""


class SweepMotion(NamedTuple):
    """The motion a map solves at every grid point."""

    N: int
    symmetric: bool
    """Solve the half system of a symmetric motion."""
    admits: bool
    """The motion admits the symmetry: store its asymmetry."""
    pivots: np.ndarray
    """0-based index of the position eliminated on each impact's section, int64, (p,)."""
    signs: np.ndarray
    """``+1``/``-1``: impact k is met moving up/down its stop coordinate, (p,)."""
    two_sided: bool
    """A lower stop is present."""


class SweepGrid(NamedTuple):
    """The grid's two axes and the seed grid point with its unknowns."""

    coord0: np.ndarray
    coord1: np.ndarray
    seed0: int
    seed1: int
    x_seed: np.ndarray


class SweepSettings(NamedTuple):
    """Newton's settings per grid point and the checks."""

    tol: float
    max_iter: int
    max_change: float
    """A solution farther than this (max-norm) from its predictor is refused."""
    checks: bool
    """Search contacts (eq. 16)."""
    max_attempts: int
    """Newton attempts per grid point at most (one per solved neighbour)."""


class SweepOutputs(NamedTuple):
    """The map's outputs, flat over the grid (first axis ``n0 * n1``), filled in place."""

    unknowns: np.ndarray
    found: np.ndarray
    iterations: np.ndarray
    delta: np.ndarray
    stable: np.ndarray
    physical: np.ndarray
    rho: np.ndarray
    mu: np.ndarray
    gap: np.ndarray
    velocity: np.ndarray
    tau: np.ndarray
    state: np.ndarray
    asym: np.ndarray


class SweepStats(NamedTuple):
    """What :func:`~impactcont.kernel.sweep.sweep_stops` returns."""

    solved: int
    attempts: int
    newton_iterations: int
    capped: bool
    """A contact-search grid was capped."""
