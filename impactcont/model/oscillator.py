"""The impact oscillator of eq. (1)-(4), validated at construction."""

from __future__ import annotations

import dataclasses
import json
import math
import numbers
from collections.abc import Callable, Sequence
from typing import Any

import numpy as np
import scipy.linalg
import scipy.optimize

from impactcont.errors import ParameterError
from impactcont.model.first_order import FirstOrderBasis
from impactcont.model.modal import ModalBasis, classify_modes
from impactcont.model.stops import TOUCH_RTOL, Stops
from impactcont.vocabulary import PARAMETERS

__all__ = ["ImpactOscillator", "chain_stiffness"]

_SYMMETRY_RTOL = 1e-12
_PSD_RTOL = 1e-13  # relative rounding allowance on the smallest eigenvalue of C
# Cholesky pivots of K (relative to its diagonal) above this prove K positive definite; at
# or below it (a free mode, or a nearly free one) the modes are classified by an eigensolve
_PIVOT_PROOF = 1e-8
def _rule(name: str) -> dict[str, Any]:
    """The keyword arguments of :func:`_real` for parameter `name` (from the vocabulary)."""
    p = PARAMETERS[name]
    return {"allowed": p.allowed, "low": p.low, "low_open": p.low_open, "high": p.high}


#: Parameters whose change leaves M, K, F and the modal basis alone.
_SCALAR_RULES: dict[str, dict[str, Any]] = {name: _rule(name) for name in ("R", "b", "omega")}
#: Parameters on which the modal basis of eq. (5)-(6) (M, K, the damping, F) does not depend.
_MODES_KEPT = frozenset({*_SCALAR_RULES, "stops", "F_static"})
#: Parameters on which the first-order basis (M, K, C only) does not depend.
_FIRST_ORDER_KEPT = frozenset({*_MODES_KEPT, "F"})


class _Shared:
    """A basis computed on first use, shared by the oscillators that
    :meth:`ImpactOscillator.replace` derives from one another while it cannot change.

    An oscillator cannot hold it in its own cache: a continuation derives every point's
    oscillator from the same start, which may never compute the basis itself, so each
    point would eigen-decompose again.
    """

    __slots__ = ("value",)

    def __init__(self, value: Any = None) -> None:
        self.value = value

    def get(self, compute: Callable[[], Any]) -> Any:
        """The value, computed by ``compute()`` on the first call."""
        if self.value is None:
            self.value = compute()
        return self.value


def _real_array(name: str, value: Any, what: str) -> np.ndarray:
    """``value`` as a float array; TypeError naming ``name`` unless it holds real numbers.

    Complex input is refused rather than cast: numpy would drop the imaginary
    part with only a ComplexWarning, a silently wrong system.
    """
    try:
        a = np.asarray(value)
    except (TypeError, ValueError) as exc:  # ragged nesting
        raise TypeError(f"{name} must be {what}; got {value!r}") from exc
    items = a.ravel().tolist() if a.dtype.kind == "O" else []
    if a.dtype.kind == "c" or any(isinstance(x, complex) for x in items):
        raise TypeError(f"{name} must be {what} with real entries; got complex values "
                        f"{value!r} (pass the real part, e.g. np.real({name}), if the "
                        f"imaginary parts are meant to vanish)")
    if a.dtype.kind not in "biufO" or not all(isinstance(x, numbers.Real) for x in items):
        raise TypeError(f"{name} must be {what}; got {value!r}")
    return a.astype(float)


def _matrix(name: str, value: Any, *, semi: bool = False) -> np.ndarray:
    """Return ``value`` as a finite, square, symmetric, positive definite float matrix.

    With ``semi`` (the stiffness K) a matrix whose Cholesky factorisation fails is kept
    for the oscillator's modal check (positive semi-definite: free modes).
    """
    a = _real_array(name, value, "a real square matrix (array_like)")
    if a.ndim == 0:
        a = a.reshape(1, 1)
    if a.ndim != 2 or a.shape[0] != a.shape[1] or a.shape[0] == 0:
        raise ParameterError(f"{name} must be a non-empty square matrix; got shape {a.shape}")
    if not np.all(np.isfinite(a)):
        raise ParameterError(f"{name} must be finite; got {a.tolist()}")
    scale = np.max(np.abs(a))
    if np.max(np.abs(a - a.T)) > _SYMMETRY_RTOL * scale:
        raise ParameterError(
            f"{name} must be symmetric (|{name} - {name}.T| <= {_SYMMETRY_RTOL:g}*max|{name}|); "
            f"got {a.tolist()}"
        )
    a = 0.5 * (a + a.T)
    try:
        np.linalg.cholesky(a)
    except np.linalg.LinAlgError:
        if semi:
            return a
        eig = np.linalg.eigvalsh(a)
        raise ParameterError(
            f"{name} must be positive definite; got eigenvalues {eig.tolist()} of {a.tolist()}"
        ) from None
    return a


def _vector(name: str, value: Any, n: int) -> np.ndarray:
    v = np.atleast_1d(_real_array(name, value, f"a real vector of length {n}"))
    return _check_vector(name, v, n)


def _forcing(value: Any, n: int) -> np.ndarray:
    """F as a float vector, or a complex one when it has a nonzero imaginary part.

    Complex ``F`` gives each mass its own forcing phase: the forcing is
    ``Re(F e^{i(omega t + delta)})`` (so a real F keeps its meaning ``F cos(omega t +
    delta)`` exactly). A complex F whose imaginary parts all vanish is stored as real.
    """
    try:
        a = np.asarray(value)
    except (TypeError, ValueError) as exc:  # ragged nesting
        raise TypeError(f"F must be a real or complex vector of length {n}; got {value!r}"
                        ) from exc
    if a.dtype.kind != "c":
        return _vector("F", value, n)
    v = _check_vector("F", np.atleast_1d(a.astype(complex)), n)
    return v.real.copy() if not np.any(v.imag) else v


def _check_vector(name: str, v: np.ndarray, n: int) -> np.ndarray:
    if v.shape != (n,):
        raise ParameterError(f"{name} must have shape ({n},) to match M and K; got shape {v.shape}")
    if not np.all(np.isfinite(v)):
        raise ParameterError(f"{name} must be finite; got {v.tolist()}")
    return v


def _real(name: str, value: Any, *, allowed: str, low: float | None = None,
          low_open: bool = False, high: float | None = None) -> float:
    if isinstance(value, bool) or not isinstance(value, (int, float, np.integer, np.floating)):
        raise TypeError(f"{name} must be a real number ({allowed}); got {value!r}")
    x = float(value)
    bad = not math.isfinite(x)
    if low is not None:
        bad = bad or (x <= low if low_open else x < low)
    if high is not None:
        bad = bad or x > high
    if bad:
        raise ParameterError(f"{name} must be {allowed}; got {value!r}")
    return x


def _damping(value: Any, n: int) -> np.ndarray:
    """A general damping matrix: finite, square (n, n), symmetric, positive semi-definite."""
    a = _real_array("C", value, "a real square matrix (array_like)")
    if a.ndim == 0:
        a = a.reshape(1, 1)
    if a.shape != (n, n):
        raise ParameterError(f"C must be a square matrix of shape ({n}, {n}) to match M and K; "
                             f"got shape {a.shape}")
    if not np.all(np.isfinite(a)):
        raise ParameterError(f"C must be finite; got {a.tolist()}")
    scale = np.max(np.abs(a))
    if np.max(np.abs(a - a.T)) > _SYMMETRY_RTOL * scale:
        raise ParameterError(f"C must be symmetric (|C - C.T| <= {_SYMMETRY_RTOL:g}*max|C|); "
                             f"got {a.tolist()}")
    a = 0.5 * (a + a.T)
    eig = np.linalg.eigvalsh(a)
    if eig.size and eig[0] < -_PSD_RTOL * max(scale, 0.0) * n:
        raise ParameterError(f"C must be positive semi-definite (a damping matrix dissipates "
                             f"energy); got eigenvalues {eig.tolist()} of {a.tolist()}")
    return a


def chain_stiffness(springs: Sequence[float]) -> np.ndarray:
    """Stiffness matrix of the chain of eq. (2).

    Mass 1 hangs on mass 2 by spring ``k1``, mass j on mass j+1 by ``k_j`` and
    the last mass on the ground by ``k_n``. A spring constant 0 leaves that link out:
    ``k_n = 0`` leaves the chain free of the ground (its rigid-body mode, e.g.
    ``springs=[k1, 0]``: two masses on one spring, free to move together), ``k_j = 0``
    (``j < n``) frees masses ``1..j`` from the rest. The oscillator then requires a stop
    that holds each free mode (:class:`ImpactOscillator`).

    Parameters
    ----------
    springs : sequence of float, length n
        Spring constants ``k_1 ... k_n``, all >= 0.

    Returns
    -------
    ndarray, shape (n, n)
        ``K[0,0] = k1``, ``K[j,j] = k_j + k_{j+1}``, ``K[j,j+1] = -k_{j+1}``.
    """
    k = np.atleast_1d(np.array(springs, dtype=float))
    if k.ndim != 1 or k.size == 0:
        raise ParameterError(f"springs must be a non-empty 1-D sequence; got {springs!r}")
    if not np.all(np.isfinite(k)) or np.any(k < 0):
        raise ParameterError(f"springs must be finite and >= 0 (0: no spring, a free mass "
                             f"held by a stop); got {k.tolist()}")
    n = k.size
    K = np.zeros((n, n))
    K[0, 0] = k[0]
    for j in range(1, n):
        K[j, j] = k[j - 1] + k[j]
        K[j - 1, j] = K[j, j - 1] = -k[j - 1]
    return K


def _free_modes(M: np.ndarray, K: np.ndarray, stops: Stops) -> np.ndarray:
    """The free modes of K relative to M, (n, n_f), each checked to be held by a stop.

    K positive definite (its Cholesky factorisation succeeds with every pivot above
    ``_PIVOT_PROOF`` of its diagonal entry) has none, without an eigensolve. Otherwise
    the modes of ``K u = lambda M u`` are classified against their componentwise rounding
    scale (:func:`~impactcont.model.modal.classify_modes`); the free ones span a subspace
    that the stops must hold: every free motion ``U c`` (``c != 0``) moves some stop
    coordinate ``s = normal . x`` (:meth:`~impactcont.model.stops.Stops.coordinates`: the
    upper and lower stops', a clearance's, each extra stop's). With ``T = N U`` (a row per
    stop coordinate, each column scaled by ``|N| |U|``) that is ``T`` of full column rank,
    its smallest singular value above ``TOUCH_RTOL``; one free mode is held by any stop
    coordinate that touches it (``normal . u != 0``), and ``q`` stop coordinates hold at
    most ``q`` free modes.

    Raises
    ------
    ParameterError
        K not positive semi-definite, or a free motion no stop holds (named by its shape).
    """
    n = M.shape[0]
    try:
        L = np.linalg.cholesky(K)
    except np.linalg.LinAlgError:
        pass
    else:
        # a free mode can pass Cholesky in rounding (a pivot of rounding size): only pivots
        # well above rounding prove K positive definite without an eigensolve
        pivots = np.diag(L) ** 2 / np.diag(K)
        if np.min(pivots) > _PIVOT_PROOF:
            return np.zeros((n, 0))
    lam, u = scipy.linalg.eigh(K, M)
    _, free = classify_modes(lam, u, K)
    U = u[:, free]
    U = U * np.where(U[np.argmax(np.abs(U), axis=0), np.arange(U.shape[1])] < 0, -1.0, 1.0)
    nf = U.shape[1]
    if not nf:
        return U
    coordinates = stops.coordinates(n)
    N = np.array([normal for _, normal in coordinates])  # (q, n)
    scale = np.max(np.abs(N) @ np.abs(U), axis=0)  # (n_f,): each free mode's size on the stops
    T = (N @ U) / np.where(scale > 0.0, scale, 1.0)
    _, sv, vt = np.linalg.svd(T)  # full_matrices: vt (n_f, n_f)
    held = sv.size == nf and sv[-1] > TOUCH_RTOL
    if not held:
        shape = U @ vt[-1]  # a free motion the stop coordinates do not see: T c = 0
        shape = shape / np.max(np.abs(shape))
        seen = "; ".join(f"s = {text} (normal {normal.tolist()})"
                         for text, normal in coordinates)
        raise ParameterError(
            f"K has {nf} free (rigid-body, zero-frequency) mode(s) and the free mode "
            f"u = {np.round(shape, 12).tolist()} is held by nothing: no spring, and no stop "
            f"touches it (normal . u = 0 for every stop coordinate: {seen}). Allowed: every "
            f"free motion touched by a stop (the upper/lower stops, a clearance or an extra "
            f"stop; q stop coordinates hold at most q free modes); add a spring (K positive "
            f"definite) or a stop on a coordinate that moves with that mode")
    return U


def _check_static_force(M: np.ndarray, U: np.ndarray, F_static: np.ndarray, stops: Stops,
                        b: float, R: float) -> None:
    """Refuse a constant force that drives a free motion away from every stop.

    On the free modes ``U`` (M-normalised: ``q'' = U^T F_static`` plus damping) the stops
    can take the constant force only if it lies in the cone of their reactions: ``U^T
    F_static = sum_k lam_k sign_k U^T n_k`` with ``lam_k >= 0`` (stop k on ``s = n_k . x``,
    met moving ``sign_k``). Otherwise the residual ``r`` of the non-negative least-squares
    fit gives a free motion ``U r`` along which the force does work (``r . U^T F_static =
    |r|^2 > 0``) and which approaches no stop (``sign_k n_k . U r <= 0`` for every k): the
    masses drift away for ever, without impacts (Farkas' lemma).

    Raises
    ------
    ParameterError
        Naming the force, the escaping free motion, the stops and what is allowed.
    """
    if not U.shape[1] or not np.any(F_static):
        return
    f = U.T @ F_static
    views = [stops.stop(name, M, b, R) for name in stops.names]
    A = np.column_stack([v.sign * (U.T @ v.normal) for v in views])
    size = np.abs(U).T @ np.column_stack([np.abs(v.normal) for v in views])
    A[np.abs(A) <= TOUCH_RTOL * size] = 0.0  # a stop that touches a mode only in rounding
    lam, _ = scipy.optimize.nnls(A, f)
    r = f - A @ lam
    if np.linalg.norm(r) <= TOUCH_RTOL * float(np.max(np.abs(U).T @ np.abs(F_static))):
        return
    shape = U @ r
    shape = shape / np.max(np.abs(shape))
    met = "; ".join(f"stop {v.name!r} on {_coordinate_text(v.normal)} = {v.position!r}, met "
                    f"moving {'up' if v.sign > 0 else 'down'}" for v in views)
    raise ParameterError(
        f"F_static = {F_static.tolist()} pushes the free (rigid-body) mode "
        f"u = {np.round(shape, 12).tolist()} away from every stop: the force does work along "
        f"u (u . F_static = {float(shape @ F_static):.6g} > 0) and no stop is met moving "
        f"along u ({met}), so the free masses would drift away for ever without an impact. "
        f"Allowed: a constant force on a free mode that the stops take, pushing it into a "
        f"stop that holds it (a ball under gravity on a floor: a lower stop), or a mode held "
        f"on both sides (an upper and a lower stop, a clearance); change F_static, add a stop "
        f"on the other side (stops b_low, mirror or an extra stop) or a spring")


def _coordinate_text(normal: np.ndarray) -> str:
    """``x2`` or ``x2 - x1`` for a stop normal."""
    plus = [f"x{i + 1}" for i in np.flatnonzero(normal > 0)]
    minus = [f"x{i + 1}" for i in np.flatnonzero(normal < 0)]
    return " - ".join([" + ".join(plus), *minus]) if plus else "-" + " - ".join(minus)


@dataclasses.dataclass(frozen=True, eq=False)
class ImpactOscillator:
    """A chain of masses, springs and dampers whose mass 1 strikes a rigid stop.

    Between impacts ``M x'' + C x' + K x = Re(F e^{i(omega t + delta)}) + F_static``
    (eq. 1 plus a constant force; for a real F this is the paper's ``F cos(omega t + delta)``);
    mass 1 hits the stop when ``x1 = b`` moving towards it (eq. 3) and its
    velocity is multiplied by ``-R`` (eq. 4).

    Parameters
    ----------
    M, K : array_like, shape (n, n)
        Symmetric mass and stiffness matrices; M positive definite, K positive
        semi-definite. A free (rigid-body, zero-frequency) mode of K must be held by the
        stops: every free motion moves some stop coordinate (U/L's, a clearance's or an
        extra stop's, ``normal . u != 0``); a free motion no stop touches is refused.
    F : array_like, shape (n,)
        Forcing amplitude vector. Complex entries give the masses their own phases:
        ``F_j = |F_j| e^{i phi_j}`` forces mass j with ``|F_j| cos(omega t + delta + phi_j)``.
        ``F = 0`` (no harmonic forcing) is a machine too: :func:`~impactcont.simulate` follows
        it from a state (a ball bouncing on a still table under ``F_static``); periodic
        motions, which have the forcing's period, need ``F != 0``
        (:func:`~impactcont.model.stops.require_forcing`).
    R : float
        Coefficient of restitution, ``0 <= R <= 1``.
    b : float
        Gap: position of the stop for mass 1 (any real number).
    omega : float
        Forcing frequency, ``> 0``.
    eta : float, optional
        Paper's damping, ``C = 2 eta K`` (modal damping ``xi_i = eta omega_i``).
    alpha, beta : float, optional
        Rayleigh damping ``C = alpha M + beta K``. Give either ``eta`` or
        ``alpha``/``beta``; with none the system is undamped.
    C : array_like, shape (n, n), optional
        Any symmetric positive semi-definite damping matrix (instead of ``eta`` or
        ``alpha``/``beta``). The flow then comes from the first-order complex modes
        (:mod:`impactcont.model.first_order`), as it does for a complex F.
    stops : Stops or mapping, optional
        Which mass meets the stops and an optional lower stop with its own
        restitution (:class:`~impactcont.model.stops.Stops`; ``b`` and ``R`` stay
        those of the upper stop). None: the paper's single stop on mass 1.
    F_static : array_like, shape (n,), optional
        A constant force (gravity, a preload, a mean torque); default zeros. On a free
        mode it is allowed when the stops take it (the mean impulse): it pushes the mode
        into a stop that holds it, or the mode is held on both sides; a force driving a
        free motion away from every stop is refused (:func:`_check_static_force`).

    Notes
    -----
    The oscillator is immutable; use :meth:`replace` to change parameters.
    Its modal and first-order bases are computed once, on first use, and shared with the
    oscillators :meth:`replace` makes from it while the changed parameters cannot move them
    (omega, b, R, stops; F or F0 for the first-order basis). After construction ``C`` holds the
    damping matrix for every damping model; :attr:`general_damping` says whether it was
    given as a matrix.
    """

    M: np.ndarray
    K: np.ndarray
    F: np.ndarray
    R: float
    b: float
    omega: float
    eta: float | None = None
    alpha: float | None = None
    beta: float | None = None
    C: Any = None
    stops: Stops | None = None
    F_static: Any = None

    def __post_init__(self) -> None:
        M = _matrix("M", self.M)
        K = _matrix("K", self.K, semi=True)
        if M.shape != K.shape:
            raise ParameterError(f"M and K must have the same shape; got {M.shape} and {K.shape}")
        n = M.shape[0]
        F = _forcing(self.F, n)
        R = _real("R", self.R, **_SCALAR_RULES["R"])
        b = _real("b", self.b, **_SCALAR_RULES["b"])
        omega = _real("omega", self.omega, **_SCALAR_RULES["omega"])
        if self.eta is not None and (self.alpha is not None or self.beta is not None):
            raise ParameterError(
                f"give either eta (C = 2 eta K) or alpha/beta (C = alpha M + beta K), not both; "
                f"got eta={self.eta!r}, alpha={self.alpha!r}, beta={self.beta!r}"
            )
        if self.C is not None and not (self.eta is None and self.alpha is None
                                       and self.beta is None):
            raise ParameterError(
                f"give either a damping matrix C or eta (C = 2 eta K) or alpha/beta (C = alpha M "
                f"+ beta K), not both; got C={np.asarray(self.C).tolist()!r} with eta="
                f"{self.eta!r}, alpha={self.alpha!r}, beta={self.beta!r}")
        eta = alpha = beta = None
        if self.eta is not None:
            eta = _real("eta", self.eta, **_rule("eta"))
        if self.alpha is not None or self.beta is not None:
            alpha = _real("alpha", 0.0 if self.alpha is None else self.alpha, **_rule("alpha"))
            beta = _real("beta", 0.0 if self.beta is None else self.beta, **_rule("beta"))
        # -- stops (two-sided clearance, stop on any mass): begin ---------------------------
        stops = self.stops if self.stops is not None else Stops()
        if not isinstance(stops, Stops):
            stops = Stops.from_dict(stops)
        object.__setattr__(self, "stops", stops.check(n, b, R))
        # -- stops: end -------------------------------------------------------------------------
        F_static = (np.zeros(n) if self.F_static is None
                    else _vector("F_static", self.F_static, n))
        object.__setattr__(self, "_free_modes", _free_modes(M, K, self.stops))
        _check_static_force(M, self.free_modes, F_static, self.stops, b, R)
        general = self.C is not None
        if general:
            C = _damping(self.C, n)
        else:
            ra, rb = (0.0, 2.0 * eta) if eta is not None else (alpha or 0.0, beta or 0.0)
            C = ra * M + rb * K
        object.__setattr__(self, "_general_damping", general)
        object.__setattr__(self, "_first_order", _Shared())
        object.__setattr__(self, "_modes", _Shared())
        for name, value in [("M", M), ("K", K), ("F", F), ("C", C), ("F_static", F_static)]:
            value.setflags(write=False)
            object.__setattr__(self, name, value)
        for name, value in [("R", R), ("b", b), ("omega", omega), ("eta", eta),
                            ("alpha", alpha), ("beta", beta)]:
            object.__setattr__(self, name, value)

    # -- what the model holds -----------------------------------------------------------------
    @property
    def free_modes(self) -> np.ndarray:
        """The free (rigid-body, zero-frequency) modes of K, M-normalised by column, (n, n_f);
        ``n_f = 0`` for K positive definite. Each is held by the stops."""
        return self.__dict__["_free_modes"]

    @property
    def has_static_force(self) -> bool:
        """A nonzero constant force ``F_static``."""
        known = self.__dict__.get("_has_static_force")
        if known is None:
            known = bool(np.any(self.F_static))
            object.__setattr__(self, "_has_static_force", known)
        return known

    def paper_form_violations(self) -> list[str]:
        """What sets the system apart from the paper's form (one stop above mass 1 fixed to
        the frame, K positive definite, no constant force), as phrases; empty in that form.

        The closed-form N-1 paths (:func:`~impactcont.model.stops.require_paper_stops`)
        refuse a system with any of these (every call: worked out once per oscillator).
        """
        known = self.__dict__.get("_paper_form_violations")
        if known is None:
            known = tuple(self._violations())
            object.__setattr__(self, "_paper_form_violations", known)
        return list(known)

    def _violations(self) -> list[str]:
        out = []
        if not self.stops.paper:
            out.append(f"stops={self.stops!r} (not one stop on mass 1)")
        if self.free_modes.shape[1]:
            out.append(f"{self.free_modes.shape[1]} free mode(s) (K must be positive definite "
                       f"relative to M for this path; the free mode shapes "
                       f"{np.round(self.free_modes.T, 12).tolist()})")
        if self.has_static_force:
            out.append(f"a constant force F_static={self.F_static.tolist()}")
        return out

    @property
    def paper_form(self) -> bool:
        """The paper's form: the closed-form N-1 paths apply (:meth:`paper_form_violations`)."""
        return not self.paper_form_violations()

    # -- construction -------------------------------------------------------------------------
    @classmethod
    def chain(cls, *, masses: Sequence[float], springs: Sequence[float], **params: Any
              ) -> ImpactOscillator:
        """Build the chain of eq. (2) from masses and springs.

        Parameters
        ----------
        masses : sequence of float, length n
            ``m_1 ... m_n``, all > 0.
        springs : sequence of float, length n
            ``k_1 ... k_n``; see :func:`chain_stiffness`.
        **params
            ``F, R, b, omega`` and the damping (``eta``, ``alpha``/``beta`` or a matrix ``C``).
        """
        m = np.atleast_1d(np.array(masses, dtype=float))
        if m.ndim != 1 or m.size == 0 or not np.all(np.isfinite(m)) or np.any(m <= 0):
            raise ParameterError(f"masses must be a non-empty sequence of finite values > 0; "
                                 f"got {masses!r}")
        K = chain_stiffness(springs)
        if K.shape[0] != m.size:
            raise ParameterError(f"springs must have the same length as masses ({m.size}); "
                                 f"got {len(np.atleast_1d(springs))}")
        return cls(M=np.diag(m), K=K, **params)

    def replace(self, **changes: Any) -> ImpactOscillator:
        """Return a copy with some parameters changed (validated again).

        ``F0`` (the forcing amplitude, :attr:`F0`) scales ``F`` and keeps its shape.

        Examples
        --------
        >>> osc2 = osc.replace(omega=1.5, b=0.2)  # doctest: +SKIP
        >>> stronger = osc.replace(F0=2.0 * osc.F0)  # doctest: +SKIP
        """
        scale = None
        if "F0" in changes:
            if "F" in changes:
                raise ParameterError("give F or F0, not both: F0 scales the oscillator's F")
            value = _real("F0", changes.pop("F0"), **_rule("F0"))
            if not self.F0:
                raise ParameterError(f"F0={value!r} scales the oscillator's F, which is 0 (no "
                                     "harmonic forcing) and has no shape to scale: give F")
            scale = value / self.F0
            changes["F"] = self.F / self.F0 * value  # exactly F0 = value for the largest |F_i|
        if changes.keys() <= _SCALAR_RULES.keys():
            # omega, b and R leave M, K, F (already validated) and the modal basis unchanged:
            # validate only what changes and share the rest (the continuation's hot path;
            # copy.copy's reduce protocol made the same shallow copy at twice the cost)
            new = object.__new__(type(self))
            new.__dict__.update(self.__dict__)
            new.__dict__.pop("_flow", None)  # orbit.flow.flow_of's: the flow of self
            for name, value in changes.items():
                object.__setattr__(new, name, _real(name, value, **_SCALAR_RULES[name]))
            if "b" in changes or "R" in changes:
                # the lower stop must stay below the upper one; mirrored stops follow b, R
                object.__setattr__(new, "stops", new.stops.check(new.n, new.b, new.R))
                new.__dict__.pop("_paper_form_violations", None)  # its text names the stops
            return new
        unknown = set(changes) - {f.name for f in dataclasses.fields(self)}
        if unknown:
            allowed = ", ".join(f.name for f in dataclasses.fields(self))
            raise ParameterError(f"unknown parameter(s) {sorted(unknown)}; allowed: {allowed}")
        if "eta" in changes and changes["eta"] is not None:
            changes.setdefault("alpha", None)
            changes.setdefault("beta", None)
        if ("alpha" in changes or "beta" in changes) and changes.get("eta") is None:
            changes["eta"] = None
        # the damping model: a matrix C given here replaces eta / alpha / beta, and eta /
        # alpha / beta given here replace a matrix C; otherwise the damping matrix follows
        # eta / alpha / beta unless it was given as a matrix
        proportional = any(changes.get(k) is not None for k in ("eta", "alpha", "beta"))
        if changes.get("C") is not None:
            for name in ("eta", "alpha", "beta"):
                changes.setdefault(name, None)
            implied: dict[str, Any] = {}
        elif "C" in changes:
            implied = {}
        else:
            implied = {"C": None} if proportional or not self.general_damping else {}
        new = dataclasses.replace(self, **changes, **implied)
        if set(changes) <= _FIRST_ORDER_KEPT:  # M, K, C kept (F may come from F0)
            object.__setattr__(new, "_first_order", self._first_order)
        modes = self._modes.value
        if set(changes) <= _MODES_KEPT:
            object.__setattr__(new, "_modes", self._modes)
        elif scale is not None and modes is not None and set(changes) <= _FIRST_ORDER_KEPT:
            # only the forcing's amplitude changed: the same modes, modal forces scaled
            new._modes.value = dataclasses.replace(modes, modal_forces=modes.modal_forces * scale)
        elif modes is not None and set(changes) <= {*_MODES_KEPT, "eta", "alpha", "beta"}:
            # only the damping changed: the modes of K u = lambda M u are the same, the decay
            # rates a_i = (alpha + beta omega_i^2) / 2 follow (no new eigensolve per point of a
            # branch in eta, alpha or beta)
            alpha, beta = new.rayleigh
            w = modes.natural_frequencies
            new._modes.value = dataclasses.replace(modes, decay_rates=0.5 * (alpha + beta * w * w))
        return new

    # -- derived quantities -------------------------------------------------------------------
    @property
    def F0(self) -> float:
        """Forcing amplitude: the largest ``|F_i|`` (continuable: ``replace(F0=...)`` scales F)."""
        return float(np.max(np.abs(self.F)))

    @property
    def n(self) -> int:
        """Number of degrees of freedom."""
        return self.M.shape[0]

    @property
    def rayleigh(self) -> tuple[float, float]:
        """Damping as Rayleigh coefficients ``(alpha, beta)``, ``C = alpha M + beta K``.

        Raises
        ------
        ParameterError
            If the damping was given as a general matrix C (it has no such coefficients).
        """
        if self.general_damping:
            raise ParameterError(f"the damping is a general matrix C={self.C.tolist()}, not "
                                 "C = alpha M + beta K: it has no Rayleigh coefficients")
        if self.eta is not None:
            return 0.0, 2.0 * self.eta
        return (self.alpha or 0.0, self.beta or 0.0)

    @property
    def general_damping(self) -> bool:
        """Whether the damping was given as a matrix ``C`` (not ``eta`` or ``alpha/beta``)."""
        return bool(self.__dict__.get("_general_damping", False))

    @property
    def general(self) -> bool:
        """Whether the flow needs the first-order complex modes (:attr:`first_order`).

        True for a general damping matrix C and for a complex F (per-mass phases); the
        proportional modal basis (:attr:`modes`) and the compiled kernel serve the rest.
        """
        return self.general_damping or self.F.dtype.kind == "c"

    @property
    def first_order(self) -> FirstOrderBasis:
        """First-order complex modes of eq. (1) with the damping matrix C, computed once
        (and kept by :meth:`replace` unless M, K or the damping change)."""
        return self._first_order.get(lambda: FirstOrderBasis.from_matrices(self.M, self.K,
                                                                           self.C))

    @property
    def D(self) -> np.ndarray:
        """Impact matrix of eq. (4) at the upper stop: ``diag(1, ..., -R, ..., 1)``, (2n, 2n).

        ``-R`` multiplies the velocity of the impacting mass (mass 1 in the paper;
        ``stops.mass`` in general). For a clearance between two masses the velocity block
        is the two-body law :meth:`Stops.impact_matrix`.
        """
        n = self.n
        out = np.eye(2 * n)
        out[n:, n:] = self.stops.impact_matrix(self.M, self.R)
        return out

    @property
    def modes(self) -> ModalBasis:
        """Mass-normalised modal basis of eq. (5)-(6), computed once (and kept by
        :meth:`replace` unless M, K, the damping or F change).

        Raises
        ------
        ParameterError
            For a general damping matrix C or a complex F (see :attr:`general`): the
            undamped modes do not decouple such a system; :attr:`first_order` does.
        """
        if self.general:
            what = ("a general damping matrix C" if self.general_damping
                    else f"a complex F={self.F.tolist()} (per-mass phases)")
            raise ParameterError(f"the oscillator has {what}: the proportional modal basis of "
                                 "eq. (5)-(6) does not apply; its flow uses first_order "
                                 "(periodic motions, branches in omega, b, R, F0, curves, maps, "
                                 "robust stability and the simulator do)")
        alpha, beta = self.rayleigh
        return self._modes.get(lambda: ModalBasis.from_matrices(self.M, self.K, alpha, beta,
                                                                self.F))

    # -- serialisation ------------------------------------------------------------------------
    def to_dict(self) -> dict[str, Any]:
        """Plain-Python description (JSON-able) of the oscillator."""
        out: dict[str, Any] = {"M": self.M.tolist(), "K": self.K.tolist(),
                               "F": self.F.real.tolist(), "R": self.R, "b": self.b,
                               "omega": self.omega}
        if self.F.dtype.kind == "c":
            out["F_imag"] = self.F.imag.tolist()  # JSON has no complex numbers
        if self.general_damping:
            out["C"] = self.C.tolist()
        if self.eta is not None:
            out["eta"] = self.eta
        if self.alpha is not None:
            out["alpha"] = self.alpha
            out["beta"] = self.beta
        if not self.stops.paper:
            out["stops"] = self.stops.to_dict()
        if self.has_static_force:
            out["F_static"] = self.F_static.tolist()
        return out

    def to_json(self) -> str:
        """JSON text of :meth:`to_dict`."""
        return json.dumps(self.to_dict())

    @classmethod
    def from_dict(cls, data: dict[str, Any]) -> ImpactOscillator:
        """Inverse of :meth:`to_dict` (``F_imag``, when present, is the imaginary part of F)."""
        data = dict(data)
        if "F_imag" in data:
            imag = data.pop("F_imag")
            try:
                real = np.atleast_1d(np.asarray(data["F"], dtype=float))
                imag_part = np.atleast_1d(np.asarray(imag, dtype=float))
            except (TypeError, ValueError, KeyError) as exc:
                raise ParameterError(f"F_imag must be a real vector matching F; got {imag!r}"
                                     ) from exc
            if imag_part.shape != real.shape:  # no broadcasting: each mass has its own phase
                raise ParameterError(f"F_imag must have the shape of F, {real.shape}; got "
                                     f"shape {imag_part.shape} ({imag!r})")
            data["F"] = real + 1j * imag_part
        return cls(**data)

    @classmethod
    def from_json(cls, text: str) -> ImpactOscillator:
        """Inverse of :meth:`to_json`."""
        return cls.from_dict(json.loads(text))

    def __repr__(self) -> str:
        damping = (f"C={self.C.tolist()}" if self.general_damping
                   else f"eta={self.eta!r}" if self.eta is not None
                   else f"alpha={self.alpha!r}, beta={self.beta!r}"
                   if self.alpha is not None or self.beta is not None else "undamped")
        stops = "" if self.stops.paper else f", stops={self.stops!r}"
        static = f", F_static={self.F_static.tolist()}" if self.has_static_force else ""
        return (f"ImpactOscillator(n={self.n}, R={self.R!r}, b={self.b!r}, "
                f"omega={self.omega!r}, {damping}, F={self.F.tolist()}{stops}{static})")
