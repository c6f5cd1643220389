"""The N-1 closed form as the exact evaluator of the codim-1 curves (paper eq. 12-15).

The one curve problem (:mod:`impactcont.problems.codim1`) is a motion's branch problem
augmented by the test function of a kind; where the motion is N-1 on the paper's one stop
this module evaluates it exactly and fast, in the closed form's own unknowns. Each curve
is the zero set of an augmented system ``F(u, lam) = 0`` where
``lam`` is the second parameter ``p2`` and ``u = [p1, delta, extras...]``
holds the first parameter, the impact phase ``delta`` and the extra unknowns
of the defining condition. Every system contains eq. (14),

    r(delta, p) = c(p) cos(delta) + s(p) sin(delta) - b = 0,

and adds the condition that makes the motion special:

======  =================================  ==========================  ===================
kind    condition                          extra unknowns              equations
======  =================================  ==========================  ===================
``SN``  fold of eq. (14)-(15):             none                        ``r, dr/d delta``
        ``dr/d delta = 0``
``PD``  a multiplier -1:                   none                        ``r, g``
        ``h2 det(G + I) = 0`` via the
        bordered system (below)
``NS``  multipliers ``exp(+-i theta)``:    ``theta``, ``Re v, Im v``   ``r, G v - e^{i theta}
        ``G v = e^{i theta} v``,           (2n each)                   v (2 x 2n), <v_ref,
        ``<v_ref, v> = 1``                                             v> - 1 (2)``
``GR``  x1 tangent to b at ``t*`` inside   ``t*``                      ``r, x1(t*) - b,
        the flight (eq. 16 with equality)                              x1'(t*)``
``ZV``  impact velocity zero:              none                        ``r, h2``
        ``h2 = x1'(T-) = 0`` (eq. 22)
======  =================================  ==========================  ===================

Choices and why
---------------
``PD``: the scalar ``g`` is the last component of the solution of the bordered
system ``[[E, w], [v^T, 0]] [q; g] = [0; 1]`` with ``v, w`` the right and
left singular vectors of the smallest singular value of ``E`` at the last
accepted point (Govaerts' minimally augmented system). ``E`` is ``G + I`` with
the ``1/h2`` pole of G (eq. 25, a rank-one term ``a b^T / h2``) set apart:
``E = [[G_reg + I, a], [b^T, -h2]]``, finite through a zero-velocity impact, with
``det E = -h2 det(G + I)`` (Schur complement). By Cramer's rule
``g = -det(E) / det(bordered)``: it vanishes exactly where ``h2 det(G + I)``
does, so the curve does not depend on the borders, but unlike a determinant
its derivative at a simple PD does not carry the product of the other
factors ``prod (mu_i + 1)``. With ``G + I`` itself the system blew up at ZV, and
PD+ZV and the 1:2 resonance next to it depended on the step. The borders are
renewed after every accepted point (:meth:`CurveProblem.accept`), which leaves
the curve unchanged.

``NS``: the standard augmented system of an NS point of a map (Kuznetsov,
*Elements of Applied Bifurcation Theory*, sec. 10.2): the critical
eigenvector ``v`` and the angle ``theta`` are unknowns. Unlike the bialternate
product ``prod_{i<j} (mu_i mu_j - 1)`` it cannot converge to a neutral saddle
(two real multipliers with product 1), it yields ``theta``, whose approach to
0 or pi marks the 1:1 and 1:2 strong resonances where the curve ends, and it
is regular at a simple NS point (``0 < theta < pi``). The phase and scale of
``v`` are fixed by ``<v_ref, v> = v_ref^H v = 1`` with ``v_ref`` the
eigenvector of the last accepted point divided by its squared norm, so the
accepted point stays an exact solution when ``v_ref`` is renewed.

Far above the lowest natural frequency (``|c, s| >> b``) eq. (14) is divided by its
scale (:func:`~impactcont.problems.periodic_branch.residual_scale`: its rounding would
exceed the Newton tolerance), and where the kernel's impact velocity
``x1p'(delta) / Delta`` cancels the pieces of a parameter pair take the impact
condition's ``(x1p(delta) - b) / (kappa g)`` for every phase, with G's pole at it
(:attr:`_Pieces.impact_form`, ``docs/kernel.md``).

Derivatives are exact: complex steps of the residual in the two parameters, the
phase and the grazing time (the kernel evaluates eq. 12-15, G and ``x1(t)`` in
complex arithmetic; in omega and R the stepped pieces of eq. 12-15 are the real ones plus
``i h`` times their exact slope, :func:`~impactcont.kernel.closed_form.setup_slope`, so
the flights are compiled in real arithmetic only), closed form in the NS system's
``theta`` and ``v``. No
finite differences: the Jacobian is as accurate as the residual at every step
size, including next to a domain boundary of a parameter (``R = 1``,
``eta = 0``), since a complex step never leaves the real point. Newton reuses a
Jacobian within a relative distance of 1e-4 (chord steps); the accuracy of every
point is set by the residual, which is evaluated in closed form.

With a damping matrix C or a complex F (:attr:`ImpactOscillator.general`) the same
systems run on the first-order path: the pieces are
:class:`~impactcont.problems.general_pieces.GeneralPieces` (dense closed form on the
complex modes), exact in the phase, the extra unknowns, ``b`` and ``F0``; the ``omega``
and ``R`` columns are central differences except the rows through ``c, s`` (why: the
docstring of :mod:`impactcont.problems.general_pieces`). ``eta, alpha, beta`` do not
exist with a matrix C and are refused.
"""

from __future__ import annotations

import cmath
import collections
import dataclasses
import functools
import math
import warnings
from collections.abc import Callable

import numpy as np

from impactcont.core.stepper import NewtonConvergenceError
from impactcont.errors import LowImpactVelocityWarning, ParameterError
from impactcont.model.modal import decay_rate_derivative
from impactcont.model.oscillator import ImpactOscillator
from impactcont.model.parameters import FD_RELATIVE_STEP, model_parameter
from impactcont.model.stops import require_paper_stops
from impactcont.orbit.dense import pole_free_pd_matrix
from impactcont.orbit.periodic import (
    PeriodicOrbit,
    _check_N,
    modal_arrays,
    orbit_at_phase,
    physical_transition,
)
from impactcont.problems.events import pole_free
from impactcont.problems.general_pieces import (
    STEPPED_PARAMETERS,
    GeneralPieces,
    bordered_condition,
    impact_condition_form,
)
from impactcont.problems.periodic_branch import residual_scale, root_phase, scaled_derivative
from impactcont.vocabulary import (
    CONTINUABLE_PARAMETERS,
    ELEMENT_FAMILIES,
    PARAMETERS,
    Label,
    check_parameter,
    stop_parameter_name,
)

__all__ = [
    "CURVE_PARAMETERS",
    "CurveProblem",
    "FoldCurve",
    "GrazingCurve",
    "NeimarkSackerCurve",
    "PeriodDoublingCurve",
    "ZeroVelocityCurve",
    "check_parameters",
    "closed_form_curve",
]

"""Kinds of codimension-one curves: saddle-node, period-doubling, Neimark-Sacker,
grazing and zero-velocity impact."""

_STEP = 1e-30  # complex step, relative to max(1, |x_j|): derivatives exact to rounding
_CHORD = 1e-4  # relative distance within which a Jacobian is reused (chord Newton)
_CACHE_SIZE = 48
_FD_STEP = 1e-6  # relative difference step of the first-order path's parameter columns
_OTHER_STOPS = ("b_low", "R_low", "gap")  # parameters of stops the closed form has not



@dataclasses.dataclass(eq=False)
class _Pieces:
    """The kernel's modal pieces (eq. 12-15) at one parameter pair, real or complex-stepped.

    Everything a curve's residual needs is O(n) or one G: ``c, s`` of eq. (14), the
    impact velocity and ``x1`` along the flight for a phase, G (eq. 25). The
    kernel arguments ``omega, R, b, a, f`` are held here, not read from
    :attr:`osc`, so that the same methods evaluate a complex step
    (:meth:`stepped`): one parameter moved by ``i h`` gives its derivative as the
    imaginary part divided by ``h``, exact to rounding (no cancellation, no step
    error), because every residual is analytic in the parameters and the phase.
    Not a frozen dataclass (nothing changes them once built): one is built per Newton
    iterate and complex step, and a frozen one's construction costs 1.2 us more.
    """

    osc: ImpactOscillator
    """The oscillator at the (real) parameter pair."""
    N: int
    modal: np.ndarray
    scalars: np.ndarray
    omega: float | complex
    R: float | complex
    b: float | complex
    w: np.ndarray
    a: np.ndarray
    f: np.ndarray
    scale: float | complex = 1.0
    """:func:`~impactcont.problems.periodic_branch.residual_scale` of eq. (14) (complex
    along a complex step, where it is not 1)."""
    impact_form: bool = False
    """The impact velocity from the impact condition ``x1(0) = b`` instead of the kernel's
    ``x1p'(delta) / Delta``, for every phase of this pair
    (:func:`~impactcont.problems.general_pieces.impact_condition_form`); G's pole is then
    that velocity, not the kernel's recomputation of ``x1'(T^-)``."""

    @classmethod
    def at(cls, osc: ImpactOscillator, N: int) -> _Pieces:
        """The real pieces of `osc` (:func:`kernel.omega_setup`)."""
        from impactcont.kernel import closed_form as kernel

        arrays = modal_arrays(osc)
        w, a, f = arrays.w, arrays.a, arrays.f
        modal, scalars = kernel.omega_setup(w, a, f, arrays.u0, arrays.ui0, arrays.eig_err,
                                            osc.R, osc.omega, N)
        _, Gam, B, g, Delta, c, s = scalars[:7].tolist()
        return cls(osc, N, modal, scalars, osc.omega, osc.R, osc.b, w, a, f,
                   residual_scale(c, s),
                   impact_condition_form(Gam, B, g, Delta, osc.omega, osc.R, osc.b))

    def stepped(self, name: str | None, h: float) -> _Pieces:
        """These pieces in complex arithmetic with parameter `name` moved to ``p + i h``.

        ``name=None`` moves nothing (the phase or an extra unknown is stepped by the
        caller). Damping parameters move the decay rates along ``d a / d p``; ``F0``
        scales the modal forces (eq. 13 is linear in F). ``b`` leaves ``c, s`` alone.
        """
        from impactcont.kernel import closed_form as kernel

        w, a, f = (np.asarray(x, dtype=complex) for x in (self.w, self.a, self.f))
        omega, R, b = complex(self.omega), complex(self.R), complex(self.b)
        if name is None or name == "b":
            b += 1j * h if name == "b" else 0.0
            modal, scalars = self.modal.astype(complex), self.scalars.astype(complex)
        elif name in ("omega", "R"):
            # the step's first order from the exact slope of omega_setup (real arithmetic:
            # no complex variant of the flights is compiled), equal to the step's to rounding
            omega += 1j * h if name == "omega" else 0.0
            R += 1j * h if name == "R" else 0.0
            arrays = modal_arrays(self.osc)
            d_modal, d_scalars = kernel.setup_slope(
                arrays.w, arrays.a, arrays.f, arrays.u0, arrays.ui0, float(self.R),
                float(self.omega), self.N, 0 if name == "omega" else 1)
            modal = self.modal + 1j * h * d_modal
            scalars = self.scalars + 1j * h * d_scalars
        else:
            if name == "F0":
                f = f * complex(1.0, h / self.osc.F0)
            else:
                a = a + 1j * h * decay_rate_derivative(name, self.w)
            arrays = modal_arrays(self.osc)
            modal, scalars = kernel.omega_setup(w, a, f, arrays.u0, arrays.ui0, arrays.eig_err,
                                                R, omega, self.N)
        scale = self.scale if self.scale == 1.0 else residual_scale(scalars[5], scalars[6])
        return _Pieces(self.osc, self.N, modal, scalars, omega, R, b, w, a, f, scale,
                       self.impact_form)

    @property
    def S0(self) -> tuple[float, float]:
        """``c, s`` of eq. (14) (the first row of S, eq. 13)."""
        return self.scalars[5], self.scalars[6]

    @property
    def T(self) -> float:
        return float(self.scalars[0].real)

    def impact_velocity(self, delta: float) -> float:
        """``h2 = x1'(T^-)`` of the motion with impact phase ``delta``, from the form of
        :attr:`impact_form`."""
        from impactcont.kernel import roots

        if self.impact_form:  # the impact condition x1(0) = b
            Gam, B, g = self.scalars[1], self.scalars[2], self.scalars[3]
            return (Gam * np.cos(delta) + B * np.sin(delta) - self.b) / ((1.0 + self.R) * g)
        if self.scalars.dtype.kind == "c":  # a complex step: roots.phase_sigma's formula here,
            # not a complex compiled variant of it
            Gam, B, g, Delta = self.scalars[1:5].tolist()
            cd, sd = cmath.cos(delta), cmath.sin(delta)
            if self.scalars[9] != 0.0:  # elastic, undamped
                return (Gam * cd + B * sd - self.b) / ((1.0 + self.R) * g)
            return self.omega * (B * cd - Gam * sd) / Delta
        return roots.phase_sigma(self.scalars, self.omega, self.R, self.b, delta)

    @functools.cached_property
    def transition(self) -> np.ndarray:
        """``U W(T) U^-1`` (eq. 9): it depends on the parameters, not on ``delta``."""
        return physical_transition(self.osc, self.modal)

    def _kernel_args(self, delta: float) -> tuple:
        """The arguments of the kernel's G functions after the transition (``delta``
        complex with complex-stepped pieces, as when the phase itself is stepped: one
        compiled complex variant of each kernel function)."""
        arrays = modal_arrays(self.osc)
        u, ui0 = arrays.u, arrays.ui0
        if self.modal.dtype.kind == "c":
            delta = complex(delta)
        return (self.modal, self.w, self.a, self.f, u, ui0, self.omega, self.R, delta,
                self.impact_velocity(delta))

    def jacobian(self, delta: float) -> tuple[np.ndarray, float]:
        """G of eq. (25) and ``h2`` for the impact phase ``delta``."""
        from impactcont.kernel import closed_form as kernel

        if self.impact_form:  # the pole at the motion's own velocity (split)
            G_reg, a, b, h2 = self.split(delta)
            return G_reg + np.outer(a, b) / h2, h2
        return kernel.assemble_jacobian(self.transition, *self._kernel_args(delta))

    def split(self, delta: float) -> tuple[np.ndarray, np.ndarray, np.ndarray, float]:
        """G of eq. (25) as ``(G_reg, a, b, h2)``, ``G = G_reg + a b^T / h2``, every piece
        finite where ``h2`` vanishes (:func:`kernel.jacobian_split`; with
        :attr:`impact_form`, ``h2`` is the motion's velocity, not the kernel's
        recomputation of ``x1'(T^-)``, which cancels there)."""
        from impactcont.kernel import closed_form as kernel

        args = self._kernel_args(delta)
        G_reg, a, b, h2 = kernel.jacobian_split(self.transition, *args)
        return G_reg, a, b, (args[-1] if self.impact_form else h2)

    def pd_condition(self, delta: float, left: np.ndarray, right: np.ndarray) -> float:
        """The pole-free period-doubling condition ``g`` (:func:`kernel.pd_condition`; with
        :attr:`impact_form` the same bordered solve on :meth:`pole_free_pd_matrix`)."""
        from impactcont.kernel import closed_form as kernel

        if self.impact_form:
            return bordered_condition(self.pole_free_pd_matrix(delta), left, right)
        if self.modal.dtype.kind == "c":  # a complex step
            return kernel.pd_condition(self.transition, *self._kernel_args(delta), left, right)
        # real: the compiled variant the exact Jacobian uses, with no direction
        arrays = modal_arrays(self.osc)
        d_tr, d_modal, d_point = _no_directions(self.modal.shape[1])
        point = np.array([self.omega, self.R, delta, self.impact_velocity(delta)])
        g, _ = kernel.pd_condition_slope(self.transition, d_tr, self.modal, d_modal, arrays.w,
                                         arrays.a, arrays.u, arrays.ui0, point, d_point, left,
                                         right)
        return g

    def pole_free_pd_matrix(self, delta: float) -> np.ndarray:
        """``E = [[G_reg + I, a], [b^T, -h2]]`` with ``G = G_reg + a b^T / h2``, (m+1, m+1).

        Finite through a zero-velocity impact; ``det E = -h2 det(G + I)`` (Schur
        complement), so ``E`` is singular exactly at a period-doubling (``h2 != 0``).
        """
        return pole_free_pd_matrix(*self.split(delta))

    def other_maximum(self, delta: float, exclude: float) -> float:
        """The highest interior maximum of ``x1`` other than the one at time ``exclude``
        (:func:`impactcont.kernel.contact.other_maximum`); ``-inf`` when there is none."""
        from impactcont.kernel import contact

        arrays = modal_arrays(self.osc)
        best, _ = contact.other_maximum(arrays.w, arrays.a, arrays.u0, self.modal, self.scalars,
                                        self.omega, self.R, delta, self.impact_velocity(delta),
                                        exclude)
        return float(best)

    def mass1(self, delta: float, t: float) -> tuple[float, float]:
        """``x1(t), x1'(t)`` along the flight after the impact at phase ``delta``."""
        from impactcont.kernel import contact

        u0 = modal_arrays(self.osc).u0
        ks = (1.0 + self.R) * self.impact_velocity(delta)
        x, v, _, _ = contact.x1_derivatives(t, self.scalars[1], self.scalars[2], self.omega,
                                            delta, ks, self.w, self.a, u0,
                                            self.modal[6].copy(), self.modal[7].copy())
        return x, v


@functools.cache
def _no_directions(n: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Empty direction arrays of :func:`~impactcont.kernel.closed_form.pd_condition_slope`
    for ``n`` modes (``g`` alone), shared: nothing writes them."""
    return np.empty((0, 2 * n, 2 * n)), np.empty((0, 8, n)), np.empty((0, 4))


def _velocity_slope(pc: _Pieces, delta: float, d_scalars: np.ndarray, d_point: np.ndarray,
                    d_b: float) -> float:
    """The derivative of the kernel's impact velocity (:func:`impactcont.kernel.roots.
    phase_sigma`) at the real pieces `pc` and phase `delta` along ``d_scalars`` (of
    :func:`~impactcont.kernel.closed_form.setup_slope`), ``d_point = d [omega, R, delta,
    .]`` and ``d_b``: ``x1p'(delta) / Delta``, or ``(x1p(delta) - b) / (kappa g)`` for
    elastic impacts without damping."""
    Gam, B, g, Delta = (float(v) for v in pc.scalars[1:5])
    d_omega, d_R, d_delta = d_point[0], d_point[1], d_point[2]
    cd, sd = math.cos(delta), math.sin(delta)
    if pc.scalars[9] != 0.0:  # elastic, undamped: the impact condition
        num, den = Gam * cd + B * sd - pc.b, (1.0 + pc.R) * g
        d_num = d_scalars[1] * cd + d_scalars[2] * sd + (B * cd - Gam * sd) * d_delta - d_b
        d_den = d_R * g + (1.0 + pc.R) * d_scalars[3]
        return (d_num - num * d_den / den) / den
    num = B * cd - Gam * sd
    d_num = d_scalars[2] * cd - d_scalars[1] * sd - (B * sd + Gam * cd) * d_delta
    return (d_omega * num + pc.omega * d_num - pc.omega * num * d_scalars[4] / Delta) / Delta


#: The named parameters of the N-1 curves: the paper's stop and the model's named scalars
#: (the lower stop's and the clearance's would leave the paper's one stop). The elements of
#: the model (``k2``, ``M[1,2]``, ``F[2]``, ...; :data:`~impactcont.vocabulary.ELEMENT_FAMILIES`)
#: are curve parameters too, by their :class:`~impactcont.model.parameters.ModelParameter`.
CURVE_PARAMETERS: tuple[str, ...] = tuple(
    name for name in CONTINUABLE_PARAMETERS if name not in _OTHER_STOPS)

#: Parameters that are exact by a complex step of the closed form's pieces (:meth:`_Pieces.
#: stepped`); the others (the elements) take the central difference of their model
#: parameter (:meth:`~impactcont.model.parameters.ModelParameter.difference`).
_STEPPED = ("omega", "R", "b", "F0", "eta", "alpha", "beta")


def check_parameters(osc: ImpactOscillator, parameters: object) -> tuple[str, str]:
    """Validate a pair of distinct parameter names of the N-1 curves for `osc`.

    The names are :data:`CURVE_PARAMETERS` of the oscillator's damping model, or elements
    of the model (``k2``, ``M[1,2]``, ``K[1,2]``, ``F[2]``, ...).

    Raises
    ------
    ParameterError
        Naming the argument ``parameters``, the value received and what is allowed: a
        parameter of another stop than the paper's (``b_low``, ``R_low``, ``gap``, an
        extra stop's ``gap[S]``, ``R[S]``), an unknown name, one the oscillator does not
        have (``eta`` with a damping matrix, ``k3`` with two masses), the same name twice.
    """
    allowed = (f"a pair of names from {CURVE_PARAMETERS} or elements of the model "
               f"{tuple(ELEMENT_FAMILIES)} (1-based, e.g. 'k2', 'M[1,2]', 'F[2]')")
    if isinstance(parameters, str) or not isinstance(parameters, (tuple, list)) \
            or len(parameters) != 2:
        raise ParameterError(f"parameters must be {allowed}; got {parameters!r}")
    p1, p2 = parameters
    for name in (p1, p2):
        if not isinstance(name, str) or name not in PARAMETERS:
            raise ParameterError(f"parameters must be {allowed}; got {parameters!r}: "
                                 f"{name!r} is no parameter")
        check_parameter(osc, name, "parameters")  # of the oscillator's damping model
        if name in _OTHER_STOPS or stop_parameter_name(name) is not None:
            raise ParameterError(
                f"parameters must be {allowed}; got {parameters!r}: {name!r} is a parameter "
                "of a stop other than the paper's one stop on mass 1, which the closed form "
                "of the N-1 curves does not have (curves of such systems: "
                "impactcont.multi_impact_curve)")
        model_parameter(osc, name, "parameters")  # an element the oscillator has
    if p1 == p2:
        raise ParameterError(f"parameters must be two different names; got {parameters!r}")
    return str(p1), str(p2)


class CurveProblem:
    """Base of the codim-1 curve problems: ``F(u, lam) = 0`` with ``u = [p1, delta, extras]``.

    Parameters
    ----------
    osc : ImpactOscillator
        The oscillator; its values of the two parameters are replaced.
    N : int
        One impact every N forcing periods.
    parameters : (str, str)
        ``(p1, p2)``: ``p1`` is an unknown, ``p2`` the continuation parameter
        ``lam``. Any two of ``omega, b, R, eta, alpha, beta, F0`` (of the
        oscillator's damping model: not ``eta, alpha, beta`` with a damping matrix C) and
        the elements of the model (``k2``, ``M[1,2]``, ``F[2]``, ...: set by their
        :class:`~impactcont.model.parameters.ModelParameter`, their Jacobian column a
        central difference).

    Notes
    -----
    Subclasses define :attr:`kind`, :attr:`extra_names`, :meth:`_conditions`
    (the equations after eq. 14) and :meth:`extras_from_orbit`; they may renew
    auxiliary data in :meth:`accept`.
    """

    kind: Label
    p1_index: int = 0
    """Where ``p1`` is in a curve point ``x = [p1, delta, extras, p2]``."""
    extra_names: tuple[str, ...] = ()
    codim2_tests: tuple[Label, ...] = ()
    """The other kinds whose test functions are watched along the curve (the table of
    :mod:`impactcont.detection.codim2`)."""
    multipliers_defined: bool = True
    """False on a ZV curve: G has its pole at ``h2 = 0`` (eq. 25)."""
    fold_condition: bool = False
    """The second equation is the fold condition ``dr/d delta = 0`` (an SN curve)."""

    def __init__(self, osc: ImpactOscillator, N: int, parameters: tuple[str, str] = ("omega", "b")
                 ) -> None:
        if not isinstance(osc, ImpactOscillator):
            raise TypeError(f"osc must be an ImpactOscillator; got {osc!r}")
        require_paper_stops(osc, "the codim-1 curves")  # stops: mass 1, one stop only
        self._general = osc.general  # a damping matrix C or complex F: the first-order path
        # computed once here, shared by every replace() along the curve
        _ = osc.first_order if self._general else osc.modes
        self.osc = osc
        self.N = _check_N(N)
        self.parameters = check_parameters(osc, parameters)
        #: The two parameters as model parameters (how each is set on the oscillator).
        self.params = tuple(model_parameter(osc, name) for name in self.parameters)
        self._cache: collections.OrderedDict[tuple[float, float], _Pieces | GeneralPieces] = \
            collections.OrderedDict()
        self._jac_cache: tuple[np.ndarray, np.ndarray, bool] | None = None
        self.last_step = math.nan

    # -- layout ---------------------------------------------------------------------------------
    @property
    def size(self) -> int:
        """Number of unknowns ``m`` (and of equations)."""
        return 2 + len(self.extra_names)

    def values(self, u: np.ndarray, lam: float) -> dict[str, float]:
        """The two parameter values of a point, by name."""
        return {self.parameters[0]: float(u[0]), self.parameters[1]: float(lam)}

    # -- closed-form pieces ---------------------------------------------------------------------
    def oscillator_at(self, p1: float, p2: float) -> ImpactOscillator:
        """The oscillator with the two parameters set to ``p1, p2``."""
        return self._pieces(p1, p2).osc

    def _pieces(self, p1: float, p2: float) -> _Pieces | GeneralPieces:
        key = (float(p1), float(p2))
        hit = self._cache.get(key)
        if hit is not None:
            self._cache.move_to_end(key)
            return hit
        first, second = self.params
        osc = second.at(first.at(self.osc, key[0]), key[1])
        pieces = GeneralPieces.at(osc, self.N) if self._general else _Pieces.at(osc, self.N)
        self._cache[key] = pieces
        if len(self._cache) > _CACHE_SIZE:
            self._cache.popitem(last=False)
        return pieces

    def orbit(self, u: np.ndarray, lam: float) -> PeriodicOrbit:
        """The periodic motion at a point (state, G, multipliers, eq. 16 checks).

        A curve meets ``h2 = 0`` on purpose (a ZV curve lies on it, other curves
        cross it at a codim-2 point), where ``G`` has its pole (eq. 25): the
        warning about an inexact ``G`` is not raised here; the curve flags it. Where the
        pieces take the impact velocity from the impact condition (:attr:`_Pieces.
        impact_form`: the kernel's form cancels) the motion is that of the root of
        eq. (14) nearest the point's phase
        (:func:`~impactcont.problems.periodic_branch.root_phase`): a point solves its
        system to the Newton tolerance only, and the orbit takes that form at a root.
        """
        pc = self._pieces(u[0], lam)
        delta = float(u[1])
        if pc.impact_form:
            c, s = pc.S0
            delta = root_phase(float(c), float(s), float(pc.b), delta)
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", LowImpactVelocityWarning)
            return orbit_at_phase(pc.osc, self.N, delta)

    def fold_function(self, u: np.ndarray, lam: float) -> float:
        """``dr/d delta = -c sin(delta) + s cos(delta)``; ``= -root * sqrt(c^2+s^2-b^2)``."""
        pc = self._pieces(u[0], lam)
        c, s = pc.S0
        return float(-c * math.sin(u[1]) + s * math.cos(u[1]))

    def other_gap(self, orbit: PeriodicOrbit, tangency_time: float) -> float:
        """``b`` minus the highest interior maximum of x1 other than the tangency at
        ``t*`` (the exact search of the pieces, with the tangency excluded; inf when there
        is none)."""
        pc = self._pieces(*self.plane_of(orbit))
        return float(pc.b - pc.other_maximum(orbit.delta, float(tangency_time)))

    def plane_of(self, orbit: PeriodicOrbit) -> tuple[float, float]:
        """``(p1, p2)`` of a motion of the curve."""
        return tuple(param.value(orbit.oscillator) for param in self.params)

    # -- what differs between the kinds (the curve driver asks the problem) --------------------
    def start_phase(self, osc: ImpactOscillator) -> float | None:
        """The impact phase of a start on the curve known in closed form, else None (the
        motions of eq. 15 are then searched)."""
        return None

    def root(self, x: np.ndarray) -> int:
        """The root of eq. (15) at a curve point: ``-sign(dr/d delta)``."""
        return int(-np.sign(self.fold_function(x[:-1], x[-1])))

    def other_multipliers(self, mu: np.ndarray, x: np.ndarray) -> np.ndarray:
        """The multipliers but the critical one(s) of the curve (all on a GR curve)."""
        return mu

    def angles(self, x: np.ndarray) -> dict[str, float]:
        """The columns ``tangency_time`` (GR) and ``angle`` (NS) at a point, NaN otherwise."""
        return {"tangency_time": math.nan, "angle": math.nan}

    def stored_extras(self, ds: object, k: int) -> np.ndarray | None:
        """The extra unknowns a curve dataset stores at point `k` (None: from the motion)."""
        return None

    def terminal_event(self, xa: np.ndarray, xb: np.ndarray
                       ) -> tuple[str, Callable[[np.ndarray], float]] | None:
        """A curve end between two accepted points: (label, condition) or None."""
        return None

    # -- what the location of codim-2 points needs (detection.codim2.Codim2Problem) ------------
    def grazing_test(self, x: np.ndarray, orbit: PeriodicOrbit) -> float:
        """The GR test at a curve point: ``gap_min`` (eq. 16)."""
        return orbit.gap_min

    def codim2_test(self, test: Label, x: np.ndarray, orbit: PeriodicOrbit) -> float:
        """The test function of `test` at the curve point ``x = [u, lam]``: the impact
        velocity (ZV), :meth:`grazing_test` (GR), :meth:`fold_function` (SN), the pole-free
        PD and NS products (:func:`~impactcont.problems.events.pole_free`)."""
        return _CODIM2_TESTS[test](self, x, orbit)

    def plane(self, x: np.ndarray) -> tuple[float, float]:
        """``(p1, p2)`` of a curve point ``x = [u, lam]``."""
        return float(x[0]), float(x[-1])

    def on_hyperplane(self, guess: np.ndarray, normal: np.ndarray) -> np.ndarray:
        """The curve point on the hyperplane through `guess` normal to `normal`
        (:meth:`solve`)."""
        return self.solve(guess, lambda y: float(normal @ (y - guess)), normal)

    def end_resonance(self, x: np.ndarray) -> Label | None:
        """The strong resonance that ends the curve at `x` (an NS curve's), else None."""
        return None

    def oscillator_of(self, x: np.ndarray) -> ImpactOscillator:
        """The oscillator at a curve point."""
        return self.oscillator_at(x[0], x[-1])

    def phase(self, point: object) -> float:
        """The impact phase of a codim-2 point (its ``x[1]``)."""
        return float(point.x[1])

    def parameter_value(self, osc: ImpactOscillator, name: str) -> float:
        """The value of parameter `name` on `osc` (by its model parameter: an element too)."""
        return model_parameter(osc, name).value(osc)

    # -- the Problem protocol -------------------------------------------------------------------
    def residual(self, u: np.ndarray, lam: float) -> np.ndarray:
        """``[r (eq. 14), condition...]``, shape (m,)."""
        u = np.asarray(u, dtype=float)
        return self._residual(self._pieces(u[0], lam), float(u[1]), u[2:])

    def _residual(self, pc: _Pieces, delta: float | complex, extras: np.ndarray) -> np.ndarray:
        """The residual from the pieces: real, or complex along a complex step. Eq. (14)
        is divided by its :func:`~impactcont.problems.periodic_branch.residual_scale`
        (analytic in a complex step too: :attr:`_Pieces.scale`)."""
        c, s = pc.S0
        r = (c * np.cos(delta) + s * np.sin(delta) - pc.b) / pc.scale
        return np.concatenate([[r], self._conditions(pc, delta, extras)])

    def jacobian(self, u: np.ndarray, lam: float) -> np.ndarray:
        """``dF/du`` (exact, :meth:`full_jacobian`), shape (m, m)."""
        return self._full_jacobian(u, lam)[:, :-1]

    def dparam(self, u: np.ndarray, lam: float) -> np.ndarray:
        """``dF/dlam`` (exact, :meth:`full_jacobian`), shape (m,)."""
        return self._full_jacobian(u, lam)[:, -1]

    def full_jacobian(self, x: np.ndarray) -> np.ndarray:
        """``dF/dx`` with ``x = [u, lam]``, shape (m, m + 1)."""
        x = np.asarray(x, dtype=float)
        return self._full_jacobian(x[:-1], float(x[-1]))

    def _full_jacobian(self, u: np.ndarray, lam: float) -> np.ndarray:
        """``dF/dx`` by complex steps: column j is ``Im F(x + i h e_j) / h``.

        Exact to rounding: every residual is analytic in the two parameters, the
        phase and the extra unknowns (the kernel's functions run in complex
        arithmetic), so there is no step-size error and no cancellation. A parameter
        column costs one complex ``omega_setup`` and transition; the phase and extra
        columns reuse the real pieces. Subclasses may give the extra columns in
        closed form (:meth:`_extra_columns`).
        """
        x = np.append(np.asarray(u, dtype=float), float(lam))
        pc = self._pieces(x[0], x[-1])
        if self._jac_cache is not None and self._jac_cache[2] == pc.impact_form and np.max(
                np.abs(self._jac_cache[0] - x)) <= _CHORD * max(1.0, float(np.max(np.abs(x)))):
            # a chord step: the iterates of one corrector stay this close; Newton then
            # converges linearly instead of quadratically, the accuracy is the residual's
            # (not across a change of the velocity's form: the two agree on eq. 14 only)
            return self._jac_cache[1]
        J = None if self._general or pc.impact_form else self._exact_jacobian(pc, x)
        if J is not None:
            self._jac_cache = (x, J, pc.impact_form)
            return J
        m = x.size - 1
        delta, extras = float(x[1]), x[2:-1]
        J = np.empty((m, m + 1))
        p1, p2 = self.parameters
        for j, name in ((0, p1), (m, p2)):
            if name not in _STEPPED:  # an element of the model
                J[:, j] = self._element_column(x, j)
                continue
            if self._general and name not in STEPPED_PARAMETERS:
                J[:, j] = self._parameter_column(pc, x, j, name)
                continue
            h = _STEP * max(1.0, abs(x[j]))
            J[:, j] = self._residual(pc.stepped(name, h), delta, extras).imag / h
        still = pc.stepped(None, 0.0)
        h = _STEP * max(1.0, abs(delta))
        J[:, 1] = self._residual(still, complex(delta, h), extras).imag / h
        closed = self._extra_columns(pc, delta, extras)
        if closed is not None:
            J[:, 2:m] = closed
        else:
            for k in range(extras.size):
                h = _STEP * max(1.0, abs(extras[k]))
                stepped = extras.astype(complex)
                stepped[k] += 1j * h
                J[:, 2 + k] = self._residual(still, delta, stepped).imag / h
        self._jac_cache = (x, J, pc.impact_form)
        return J

    def _element_column(self, x: np.ndarray, j: int) -> np.ndarray:
        """``dF/d p`` of an element parameter (column `j` of ``x = [u, lam]``): a central
        difference, the one finite difference of the N-1 curves in an element.

        The step is that of :meth:`~impactcont.model.parameters.ModelParameter.difference`,
        ``eps^(1/3) max(|p|, scale)``, one-sided where the oscillator refuses a side
        (:meth:`~impactcont.model.parameters.ModelParameter.admits`), but also for a forcing
        entry ``F[j]``: the residual is not affine in it (eq. 14 is divided by its scale,
        the PD and NS conditions are not linear in the state), so the model parameter's
        exact step for affine data (half the scale) would be off by its curvature. The
        points solve the residual exactly; the difference steers Newton and the tangent.
        """
        param = self.params[0 if j == 0 else 1]
        osc = self._pieces(x[0], x[-1]).osc
        value = float(x[j])
        h = FD_RELATIVE_STEP * max(abs(value), param.scale(osc))
        ends = []
        for side in (value - h, value + h):
            y = x.copy()
            y[j] = side if param.admits(osc, side) else value
            ends.append(y)
        down, up = ends
        return (self.residual(up[:-1], up[-1]) - self.residual(down[:-1], down[-1])) \
            / (up[j] - down[j])

    def _parameter_column(self, pc: GeneralPieces, x: np.ndarray, j: int, name: str
                          ) -> np.ndarray:
        """``dF/d name`` on the first-order path, where no exact complex step exists
        (:mod:`impactcont.problems.general_pieces`): central differences of the residual
        with the step ``1e-6 max(1, |p|)``, one-sided at the boundary of the parameter's
        domain; the rows that depend on ``omega`` or ``R`` only through ``c, s`` (eq. 14,
        and the fold condition) from the exact ``dc, ds``."""
        h = _FD_STEP * max(1.0, abs(x[j]))
        lo_dom, hi_dom = PARAMETERS[name].domain
        up, down = x.copy(), x.copy()
        if x[j] + h <= hi_dom:
            up[j] = x[j] + h
        if x[j] - h >= lo_dom:
            down[j] = x[j] - h
        column = (self.residual(up[:-1], up[-1]) - self.residual(down[:-1], down[-1])) \
            / (up[j] - down[j])
        if name in ("omega", "R"):
            dc, ds = pc.cs_derivative(name)
            cd, sd = math.cos(x[1]), math.sin(x[1])
            c, s = pc.S0
            column[0] = scaled_derivative(c * cd + s * sd - pc.b, dc * cd + ds * sd, c, s, dc,
                                          ds)
            if self.fold_condition:
                column[1] = scaled_derivative(-c * sd + s * cd, -dc * sd + ds * cd, c, s, dc,
                                              ds)
        return column

    def _extra_columns(self, pc: _Pieces, delta: float, extras: np.ndarray
                       ) -> np.ndarray | None:
        """``dF/d extras`` in closed form, shape (m, m - 2), or None (complex steps)."""
        return None

    def _exact_jacobian(self, pc: _Pieces, x: np.ndarray) -> np.ndarray | None:
        """``dF/dx`` in real arithmetic, shape (m, m + 1), or None (complex steps); asked
        on the closed form's pieces with the kernel's impact velocity only."""
        return None

    # -- for subclasses -------------------------------------------------------------------------
    def _conditions(self, pc: _Pieces, delta: float, extras: np.ndarray) -> np.ndarray:
        raise NotImplementedError

    def extras_from_orbit(self, orbit: PeriodicOrbit) -> np.ndarray:
        """Initial values of the extra unknowns at a motion near the curve."""
        return np.empty(0)

    def initial_unknowns(self, p1: float, p2: float, delta: float,
                         extras: np.ndarray | None = None) -> np.ndarray:
        """``u0 = [p1, delta, extras]`` from a guess of the point; prepares auxiliary data.

        The extra unknowns are taken from the motion at the guess unless given.
        """
        if extras is None:
            pc = self._pieces(p1, p2)
            orbit = orbit_at_phase(pc.osc, self.N, float(delta), check=False)  # a guess
            extras = self.extras_from_orbit(orbit)
        u0 = np.concatenate([[p1, delta], np.asarray(extras, dtype=float)])
        self.accept(u0, p2)
        return u0

    def solve(self, x0: np.ndarray, extra: Callable[[np.ndarray], float],
              gradient: np.ndarray | None = None, *, tol: float = 1e-12,
              max_iter: int = 30, residual_tol: float = 0.0) -> np.ndarray:
        """Newton on ``[F(x); extra(x)] = 0`` in all of ``x = [u, lam]`` (m + 1 unknowns).

        Parameters
        ----------
        x0 : ndarray, shape (m + 1,)
            Guess.
        extra : callable
            Scalar condition closing the system (a fixed parameter, a hyperplane,
            a test function).
        gradient : ndarray, optional
            ``d extra / dx`` if constant (linear conditions); else central differences.
        tol : float
            Converged when the Newton step is at most ``tol * max(1, |x|)``; the
            last step is kept in :attr:`last_step` (a bound on the error).
        max_iter : int
            Newton iterations allowed.
        residual_tol : float
            At a singular solution (a Jordan block at a strong resonance) Newton
            stagnates at a residual of rounding size before its steps reach `tol`:
            accept the iterate once the residual is at most this and the step stops
            shrinking; :attr:`last_step` then states the (larger) error.

        Returns
        -------
        ndarray, shape (m + 1,)

        Raises
        ------
        NewtonConvergenceError
            If the iteration does not converge or produces non-finite values.
        """
        x = np.array(x0, dtype=float)
        best: tuple[float, np.ndarray, float] | None = None
        for _ in range(max_iter):
            H = np.append(self.residual(x[:-1], x[-1]), extra(x))
            size = float(np.max(np.abs(H)))
            if size <= residual_tol and (best is None or size < best[0]):
                best = (size, x.copy(), self.last_step)
            if gradient is None:
                grad = np.empty(x.size)
                for j in range(x.size):
                    h = 1e-7 * max(1.0, abs(x[j]))
                    up, down = x.copy(), x.copy()
                    up[j] += h
                    down[j] -= h
                    grad[j] = (extra(up) - extra(down)) / (2.0 * h)
            else:
                grad = gradient
            A = np.vstack([self.full_jacobian(x), grad])
            if not (np.all(np.isfinite(A)) and np.all(np.isfinite(H))):
                raise NewtonConvergenceError("non-finite augmented system")
            try:
                step = np.linalg.solve(A, -H)
            except np.linalg.LinAlgError as exc:
                raise NewtonConvergenceError(f"singular augmented system: {exc}") from exc
            x = x + step
            self.last_step = float(np.max(np.abs(step)))
            if self.last_step <= tol * max(1.0, float(np.max(np.abs(x)))):
                return x
        if best is not None:
            self.last_step = best[2]
            return best[1]
        raise NewtonConvergenceError(f"augmented Newton did not converge in {max_iter} "
                                     f"iterations (residual {np.max(np.abs(H)):.3g})")

    def accept(self, u: np.ndarray, lam: float) -> None:
        """Renew auxiliary data (borders, reference vectors) at an accepted point."""
        self._jac_cache = None


class FoldCurve(CurveProblem):
    """Saddle-node (fold) curve: ``r = dr/d delta = 0`` (eq. 14-15 with a double root).

    Its closed form is ``b^2 = c^2 + s^2``; at it ``G`` has a multiplier +1.
    """

    kind = Label.SN
    codim2_tests = (Label.ZV, Label.GR, Label.PD, Label.NS)
    fold_condition = True

    def start_phase(self, osc: ImpactOscillator) -> float:
        """The double root of eq. (15): ``(cos, sin)`` along ``sign(b) (c, s)``."""
        c, s = self._pieces(*(param.value(osc) for param in self.params)).S0
        sign = 1.0 if osc.b >= 0 else -1.0
        return math.atan2(sign * s, sign * c)

    def root(self, x: np.ndarray) -> int:
        """0: the double root."""
        return 0

    def other_multipliers(self, mu: np.ndarray, x: np.ndarray) -> np.ndarray:
        """Without the multiplier nearest +1."""
        return np.delete(mu, np.argmin(np.abs(mu - 1.0)))

    def _conditions(self, pc: _Pieces, delta: float, extras: np.ndarray) -> np.ndarray:
        c, s = pc.S0  # over the scale of eq. (14), as r
        return np.array([(-c * np.sin(delta) + s * np.cos(delta)) / pc.scale])


class PeriodDoublingCurve(CurveProblem):
    """Period-doubling curve: a multiplier of ``G`` (eq. 25) at -1, minimally augmented.

    The condition is ``g = 0`` with ``[[E, w], [v^T, 0]] [q; g] = [0; 1]`` where
    ``E = [[G_reg + I, a], [b^T, -h2]]`` is ``G + I`` with its ``1/h2`` pole set
    apart (``G = G_reg + a b^T / h2``, ``det E = -h2 det(G + I)``): the system stays
    regular through a zero-velocity impact, where ``G + I`` itself blows up.
    ``v`` and ``w`` (right and left singular vectors of ``E`` for its smallest
    singular value) are renewed at every accepted point.
    """

    kind = Label.PD
    codim2_tests = (Label.ZV, Label.GR, Label.SN, Label.NS)

    def other_multipliers(self, mu: np.ndarray, x: np.ndarray) -> np.ndarray:
        """Without the multiplier nearest -1."""
        return np.delete(mu, np.argmin(np.abs(mu + 1.0)))

    def __init__(self, osc: ImpactOscillator, N: int, parameters: tuple[str, str] = ("omega", "b")
                 ) -> None:
        super().__init__(osc, N, parameters)
        m = 2 * osc.n + 1
        self._right = np.eye(m)[0]
        self._left = np.eye(m)[0]

    def _conditions(self, pc: _Pieces, delta: float, extras: np.ndarray) -> np.ndarray:
        return np.array([pc.pd_condition(delta, self._left, self._right)])

    def _exact_jacobian(self, pc: _Pieces, x: np.ndarray) -> np.ndarray | None:
        """``dF/d[p1, delta, p2]`` in real arithmetic when both parameters are among omega,
        R and b: eq. (14) from the exact slope of ``c, s``
        (:func:`~impactcont.kernel.closed_form.setup_slope`), ``g`` from
        :func:`~impactcont.kernel.closed_form.pd_condition_slope`. Equal to the complex
        steps within rounding, without compiling complex variants of G and its solve."""
        if any(name not in ("omega", "R", "b") for name in self.parameters):
            return None
        from impactcont.kernel import closed_form as kernel

        arrays = modal_arrays(pc.osc)
        delta = float(x[1])
        n = pc.modal.shape[1]
        d_modal, d_scalars = np.zeros((3, 8, n)), np.zeros((3, 10))
        d_point, d_b = np.zeros((3, 4)), np.zeros(3)  # d [omega, R, delta, sigma], d b
        for j, name in enumerate((self.parameters[0], "delta", self.parameters[1])):
            if name in ("omega", "R"):
                which = 0 if name == "omega" else 1
                d_modal[j], d_scalars[j] = kernel.setup_slope(
                    arrays.w, arrays.a, arrays.f, arrays.u0, arrays.ui0, pc.R, pc.omega, pc.N,
                    which)
                d_point[j, which] = 1.0
            elif name == "b":
                d_b[j] = 1.0
            else:
                d_point[j, 2] = 1.0
            d_point[j, 3] = _velocity_slope(pc, delta, d_scalars[j], d_point[j], d_b[j])
        d_tr = np.stack([physical_transition(pc.osc, d_modal[j]) for j in range(3)])
        c, s = (float(v) for v in pc.S0)
        cd, sd = math.cos(delta), math.sin(delta)
        J = np.empty((2, 3))
        for j in range(3):
            dc, ds = d_scalars[j, 5], d_scalars[j, 6]
            df = dc * cd + ds * sd - d_b[j] + (-c * sd + s * cd) * d_point[j, 2]
            J[0, j] = scaled_derivative(c * cd + s * sd - pc.b, df, c, s, dc, ds)
        point = np.array([pc.omega, pc.R, delta, pc.impact_velocity(delta)])
        _, J[1] = kernel.pd_condition_slope(pc.transition, d_tr, pc.modal, d_modal, arrays.w,
                                            arrays.a, arrays.u, arrays.ui0, point, d_point,
                                            self._left, self._right)
        return J

    def accept(self, u: np.ndarray, lam: float) -> None:
        """Borders from the SVD of the pole-free ``E`` at the accepted point."""
        super().accept(u, lam)
        p1, delta = float(u[0]), float(u[1])
        E = self._pieces(p1, lam).pole_free_pd_matrix(delta)
        U, _, Vt = np.linalg.svd(E)
        self._left, self._right = U[:, -1].copy(), Vt[-1].copy()


class NeimarkSackerCurve(CurveProblem):
    """Neimark-Sacker curve: ``G v = e^{i theta} v`` with ``<v_ref, v> = 1``.

    Unknowns ``u = [p1, delta, theta, Re v (2n), Im v (2n)]``.
    """

    kind = Label.NS
    codim2_tests = (Label.ZV, Label.GR, Label.SN, Label.PD)

    def other_multipliers(self, mu: np.ndarray, x: np.ndarray) -> np.ndarray:
        """Without the pair nearest ``exp(+-i theta)``."""
        theta = x[2]
        return np.delete(mu, [np.argmin(np.abs(mu - np.exp(1j * theta))),
                              np.argmin(np.abs(mu - np.exp(-1j * theta)))])

    def angles(self, x: np.ndarray) -> dict[str, float]:
        """``angle``: theta."""
        return {"tangency_time": math.nan, "angle": float(x[2])}

    def terminal_event(self, xa: np.ndarray, xb: np.ndarray
                       ) -> tuple[str, Callable[[np.ndarray], float]] | None:
        """``R1``/``R2`` where ``sin(theta)`` changes sign (theta through 0 or pi)."""
        sa, sb = math.sin(xa[2]), math.sin(xb[2])
        if (sa < 0) != (sb < 0) or sb == 0.0:
            label = "R1" if math.cos(xb[2]) > 0 else "R2"
            return label, lambda y: math.sin(float(y[2]))
        return None

    def __init__(self, osc: ImpactOscillator, N: int, parameters: tuple[str, str] = ("omega", "b")
                 ) -> None:
        super().__init__(osc, N, parameters)
        m = 2 * osc.n
        self.extra_names = ("theta", *(f"re_v{i + 1}" for i in range(m)),
                            *(f"im_v{i + 1}" for i in range(m)))
        self._ref = np.eye(m, dtype=complex)[0]

    def _unpack(self, pc: _Pieces, delta: float, extras: np.ndarray
                ) -> tuple[np.generic, np.ndarray, np.ndarray, np.ndarray]:
        """``theta``, ``Re v``, ``Im v`` (from `extras`) and the map's Jacobian ``G``."""
        m = 2 * self.osc.n
        vr, vi = extras[1:1 + m], extras[1 + m:1 + 2 * m]
        G, _ = pc.jacobian(delta)
        return extras[0], vr, vi, G

    def _conditions(self, pc: _Pieces, delta: float, extras: np.ndarray) -> np.ndarray:
        # in real arithmetic on (Re v, Im v), so that a complex step differentiates it
        theta, vr, vi, G = self._unpack(pc, delta, extras)
        ct, st = np.cos(theta), np.sin(theta)
        rr, ri = self._ref.real, self._ref.imag
        return np.concatenate([G @ vr - (ct * vr - st * vi), G @ vi - (st * vr + ct * vi),
                               [rr @ vr + ri @ vi - 1.0, rr @ vi - ri @ vr]])

    def _extra_columns(self, pc: _Pieces, delta: float, extras: np.ndarray) -> np.ndarray:
        """``d/d(theta, Re v, Im v)`` of ``[r, G v - e^{i theta} v, <v_ref, v> - 1]``."""
        m = 2 * self.osc.n
        theta, vr, vi, G = self._unpack(pc, delta, extras)
        ct, st = math.cos(theta), math.sin(theta)
        eye = np.eye(m)
        J = np.zeros((1 + 2 * m + 2, 1 + 2 * m))
        J[1:1 + m, 0] = st * vr + ct * vi
        J[1 + m:1 + 2 * m, 0] = -(ct * vr - st * vi)
        J[1:1 + m, 1:1 + m] = G - ct * eye
        J[1:1 + m, 1 + m:] = st * eye
        J[1 + m:1 + 2 * m, 1:1 + m] = -st * eye
        J[1 + m:1 + 2 * m, 1 + m:] = G - ct * eye
        J[1 + 2 * m, 1:1 + m] = self._ref.real
        J[1 + 2 * m, 1 + m:] = self._ref.imag
        J[2 + 2 * m, 1:1 + m] = -self._ref.imag
        J[2 + 2 * m, 1 + m:] = self._ref.real
        return J

    def extras_from_orbit(self, orbit: PeriodicOrbit) -> np.ndarray:
        """``theta`` and ``v`` of the complex multiplier closest to the unit circle."""
        mu, vecs = np.linalg.eig(orbit.G)
        upper = np.flatnonzero(mu.imag > 1e-12)
        if upper.size == 0:
            raise ParameterError(f"start of an NS curve needs a complex pair of multipliers; got "
                                 f"multipliers {np.round(mu, 6).tolist()}")
        k = upper[np.argmin(np.abs(np.abs(mu[upper]) - 1.0))]
        v = vecs[:, k] / np.linalg.norm(vecs[:, k])
        return np.concatenate([[float(np.angle(mu[k]))], v.real, v.imag])

    def end_resonance(self, x: np.ndarray) -> Label | None:
        """``R1`` at ``theta = 0``, ``R2`` at ``theta = pi``: where the curve ends
        (:meth:`resonance_end` puts its last point there exactly)."""
        return _ENDS.get(float(x[2]))

    def eigenvector(self, u: np.ndarray) -> np.ndarray:
        """The complex critical eigenvector ``v`` of a point."""
        m = 2 * self.osc.n
        return u[3:3 + m] + 1j * u[3 + m:3 + 2 * m]

    def accept(self, u: np.ndarray, lam: float) -> None:
        """``v_ref = v / |v|^2`` at the accepted point, so that ``<v_ref, v> = 1`` there."""
        super().accept(u, lam)
        v = self.eigenvector(u)
        self._ref = v / np.vdot(v, v).real

    def resonance_end(self, x: np.ndarray, label: str, tol: float = 1e-13,
                      max_iter: int = 20) -> tuple[np.ndarray, float] | None:
        """The strong resonance that ends the curve, located on a regular system.

        At ``R1``/``R2`` (``theta -> 0, pi``) the NS system is singular (a Jordan
        block), so its own Newton stops 1e-5 away. There the characteristic polynomial
        of G has a double root at ``+1``/``-1``: with ``P(mu) = det [[mu I - G_reg, a],
        [b^T, h2]] = h2 det(mu I - G)`` (pole-free), Newton on ``[r, P(+-1), P'(+-1)]``
        in ``(p1, delta, p2)`` (``P'`` by a complex step, central differences for the
        Jacobian) is regular. Returns the full NS state there (``theta = 0`` or ``pi``,
        ``v`` the real eigenvector, scaled to ``<v_ref, v> = 1``) and the last Newton
        step, or None when Newton does not converge.
        """
        sign = 1.0 if label == "R1" else -1.0
        m = 2 * self.osc.n

        def pencil(pc: _Pieces, delta: float, mu: complex) -> np.ndarray:
            G_reg, a, b, h2 = pc.split(delta)
            E = np.zeros((m + 1, m + 1), dtype=complex)
            E[:m, :m] = mu * np.eye(m) - G_reg
            E[:m, m] = a
            E[m, :m] = b
            E[m, m] = h2
            return E

        def system(y: np.ndarray) -> np.ndarray:
            pc = self._pieces(y[0], y[2])
            c, s = pc.S0
            residual = c * math.cos(y[1]) + s * math.sin(y[1]) - pc.osc.b
            value = np.linalg.det(pencil(pc, float(y[1]), sign)).real
            slope = np.linalg.det(pencil(pc, float(y[1]), sign + 1e-30j)).imag / 1e-30
            return np.array([residual, value, slope])

        y = np.array([x[0], x[1], x[-1]], dtype=float)
        step = math.inf
        for _ in range(max_iter):
            f = system(y)
            h = 1e-7 * np.maximum(1.0, np.abs(y))
            J = np.empty((3, 3))
            for j in range(3):
                e = np.zeros(3)
                e[j] = h[j]
                J[:, j] = (system(y + e) - system(y - e)) / (2.0 * h[j])
            try:
                dy = np.linalg.solve(J, -f)
            except np.linalg.LinAlgError:
                return None
            y = y + dy
            step = float(np.max(np.abs(dy)))
            if not np.all(np.isfinite(y)):
                return None
            if step <= tol * max(1.0, float(np.max(np.abs(y)))):
                break
        else:
            return None
        pc = self._pieces(y[0], y[2])
        _, _, vh = np.linalg.svd(pencil(pc, float(y[1]), sign).real)
        v = vh[-1, :m].astype(complex)
        v = v / np.vdot(self._ref, v)
        theta = 0.0 if sign > 0 else math.pi
        full = np.concatenate([[y[0], y[1], theta], v.real, v.imag, [y[2]]])
        return full, max(step, 1e-15)


class GrazingCurve(CurveProblem):
    """Grazing curve: ``x1(t*) = b`` and ``x1'(t*) = 0`` at a time ``0 < t* < T``.

    Unknowns ``u = [p1, delta, t*]``; the tangency time is an unknown.
    """

    kind = Label.GR
    extra_names = ("tangency_time",)
    codim2_tests = (Label.ZV, Label.GR, Label.SN, Label.PD, Label.NS)

    def grazing_test(self, x: np.ndarray, orbit: PeriodicOrbit) -> float:
        """The GR test on a grazing curve: the gap at the highest interior maximum other
        than the tangency (a double grazing where it vanishes)."""
        return self.other_gap(orbit, float(x[2]))

    def angles(self, x: np.ndarray) -> dict[str, float]:
        """``tangency_time``: t*."""
        return {"tangency_time": float(x[2]), "angle": math.nan}

    def stored_extras(self, ds: object, k: int) -> np.ndarray:
        """The tangency time stored at point `k`."""
        return np.array([float(ds["tangency_time"].values[k])])

    def terminal_event(self, xa: np.ndarray, xb: np.ndarray
                       ) -> tuple[str, Callable[[np.ndarray], float]] | None:
        """``GR+ZV`` where the tangency time reaches the impact (``t* -> 0`` or ``T``)."""
        if xb[2] <= 0.0:
            return "GR+ZV", lambda y: float(y[2])
        if xb[2] >= self.period(xb[:-1], xb[-1]):
            return "GR+ZV", lambda y: float(y[2] - self.period(y[:-1], y[-1]))
        return None

    def _conditions(self, pc: _Pieces, delta: float, extras: np.ndarray) -> np.ndarray:
        x1, v1 = pc.mass1(delta, extras[0])
        return np.array([x1 - pc.b, v1])

    def extras_from_orbit(self, orbit: PeriodicOrbit) -> np.ndarray:
        """The time of the highest interior maximum of x1."""
        if not math.isfinite(orbit.gap_min_time):
            raise ParameterError("start of a GR curve needs an interior maximum of x1; the motion "
                                 f"at delta={orbit.delta!r} has none")
        return np.array([orbit.gap_min_time])

    def period(self, u: np.ndarray, lam: float) -> float:
        """``T = 2 pi N / omega`` at a point."""
        return self._pieces(u[0], lam).T


class ZeroVelocityCurve(CurveProblem):
    """Zero-velocity-impact curve: ``h2 = x1'(T-) = 0`` (eq. 22).

    At ``h2 = 0`` the impact does nothing: the motion is the linear forced
    response whose amplitude of ``x1`` is ``|b|``, the same for every N.
    """

    kind = Label.ZV
    codim2_tests = (Label.SN,)
    multipliers_defined = False

    def _conditions(self, pc: _Pieces, delta: float, extras: np.ndarray) -> np.ndarray:
        return np.array([pc.impact_velocity(delta)])


_ENDS = {0.0: "R1", math.pi: "R2"}
"""The strong resonances where an NS curve ends, by its angle theta."""

#: The test function of each kind at a point of a curve of another kind.
_CODIM2_TESTS: dict[Label, Callable[[CurveProblem, np.ndarray, PeriodicOrbit], float]] = {
    Label.ZV: lambda problem, x, orbit: orbit.impact_velocity,
    Label.GR: lambda problem, x, orbit: problem.grazing_test(x, orbit),
    Label.SN: lambda problem, x, orbit: problem.fold_function(x[:-1], x[-1]),
    Label.PD: lambda problem, x, orbit: pole_free(Label.PD, orbit.multipliers,
                                                  np.array([orbit.impact_velocity])),
    Label.NS: lambda problem, x, orbit: pole_free(Label.NS, orbit.multipliers,
                                                  np.array([orbit.impact_velocity])),
}

#: The closed form's problem of each kind of N-1 curve.
_KINDS: dict[Label, type[CurveProblem]] = {
    Label.SN: FoldCurve, Label.PD: PeriodDoublingCurve, Label.NS: NeimarkSackerCurve,
    Label.GR: GrazingCurve, Label.ZV: ZeroVelocityCurve,
}


def closed_form_curve(kind: Label, osc: ImpactOscillator, N: int,
                      parameters: tuple[str, str] = ("omega", "b")) -> CurveProblem:
    """The closed form's problem of a codim-1 curve of N-1 motions.

    Parameters
    ----------
    kind : Label
        One of :data:`~impactcont.vocabulary.CURVE_KINDS` but BP (a curve of symmetric
        motions, which are not N-1).
    osc : ImpactOscillator
        The oscillator (the paper's one stop on mass 1).
    N : int
        One impact every N forcing periods.
    parameters : (str, str)
        ``(p1, p2)`` (:func:`check_parameters`).

    Raises
    ------
    ParameterError
        `kind` has no closed form (BP), or a bad parameter (named).
    """
    if kind not in _KINDS:
        raise ParameterError(f"kind must be one of {tuple(map(str, _KINDS))} for a curve of "
                             f"N-1 motions in closed form; got {str(kind)!r}")
    return _KINDS[kind](osc, N, parameters)
