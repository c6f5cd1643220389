"""The simulator's own flight: eq. (1) between impacts as one autonomous linear system.

The witness reads the oscillator's matrices and nothing of the orbit code: no modal basis,
no first-order basis, no closed-form forced response. With the forcing phase
``theta = omega t + delta`` carried as two states ``c = cos theta``, ``s = sin theta`` and
the constant force as a third state equal to 1, eq. (1)

    M x'' + C x' + K x = Re(F e^{i theta}) + F_static = Re(F) c - Im(F) s + F_static

between impacts is the autonomous system ``Y' = A Y`` of order ``N = 2n + 3`` on
``Y = [x; x'; c; s; 1]``:

    x'  = x'
    x'' = M^-1 (Re(F) c - Im(F) s + F_static - K x - C x')
    c'  = -omega s,   s' = omega c,   1' = 0

so the exact flow from ``Y(0)`` is ``Y(t) = expm(A t) Y(0)``: one matrix exponential
(:func:`scipy.linalg.expm`, scaling and squaring with a Pade approximant) gives the state at
any time with no truncation, for any damping matrix C, free masses, a constant force and a
complex F alike, and with no case analysis (undamped, critical, over-damped, a free mode
drifting under a constant force: all the same matrix). Its derivatives are exact too:
``Y^(j)(t) = A^j Y(t)``.

Locating an impact evaluates a stop coordinate at many times (a grid and Newton
iterates). Where ``A = W diag(lambda) W^-1`` with a well-conditioned ``W``
(:attr:`Flight.fast`) a stop coordinate ``y = r . Y`` is
``Re(sum_k c_k e^{lambda_k t})``, ``c_k = (r W)_k (W^-1 Y(0))_k``: O(N) per time
(:class:`StopMotion`), to about ``cond(W)`` ulps at any t (the forcing's eigenvalues
``+-i omega`` and 0 are set exactly).

An undamped free mass makes A defective: a free mode ``u`` of the stiffness and damping
blocks (``B_K u = 0``, ``B_C u = 0`` of ``x'' = B_K x + B_C x' + B_F [c; s; 1]``) has the
double eigenvalue 0 with one eigenvector, and a constant force on it a third (``g t^2 /
2``). Such modes split off exactly (:func:`_split_free`): with the left null rows ``U~``
(``U~ B_K = 0``, ``U~ B_C = 0``, ``U~ U = I``) and ``P`` spanning ``U~ x = 0``, ``x = U q + P
y`` gives ``q'' = U~ B_F [c; s; 1]`` and a reduced system in ``y`` alone, diagonalised as
above. Then ``A = S + N`` (``S = W diag(lambda) W^-1``, ``N`` nilpotent, ``S N = N S = 0``)
and the flow is ``e^{A t} = W diag(e^{lambda t}) W^-1 + t N + N^2 t^2 / 2``: in the modal
coordinates ``zeta = W^-1 Y``, ``zeta_q(t) = zeta_q + t zeta_q' + t^2 H zeta / 2`` and
``zeta_q'(t) = zeta_q' + t H zeta`` (``H zeta`` the constant force on q), the polynomial part
of a stop coordinate O(1) per time beside the O(N) sum (:attr:`Flight.chains`).

Where ``A`` is otherwise defective or nearly so (a damped free mass drifting under a
constant force, a critically damped mode) every
evaluation is a matrix exponential from an anchor a bounded time before it: scaling and
squaring loses about ``log2 |A t|`` bits and the rotation of the forcing states would
drift over a long flight, so a long advance is taken in steps of ``|A| dt <=
_STEP_NORM``, ``c, s`` set to their exact values after each (:meth:`Flight.advance`).
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np
import scipy.linalg

from impactcont.model.oscillator import ImpactOscillator

__all__ = ["Flight", "StopMotion", "flight_of"]

_EPS = float(np.finfo(float).eps)
#: Largest condition number of the eigenvectors W of A for the fast path: the values of a
#: stop coordinate are then exact to about cond(W) ulps of the motion's size.
_COND_LIMIT = 1e4
#: Size of the work arrays of one vectorised evaluation (entries of times x N, or of the
#: stacked N x N matrices of the matrix exponential).
_CHUNK = 1 << 20
#: Longest step ``|A| dt`` of one matrix exponential on the slow path.
_STEP_NORM = 256.0


def _combine(columns: np.ndarray, weights: np.ndarray) -> np.ndarray:
    """``columns @ weights`` (`weights` of shape (N, m)), summed term by term in a fixed
    order: the value at one time does not depend on how many times are evaluated with it
    (a matrix product's rounding follows its shape, and the search compares the value at a
    window's end with the same value at the next window's start)."""
    out = columns[..., 0, None] * weights[0]
    for k in range(1, weights.shape[0]):
        out = out + columns[..., k, None] * weights[k]
    return out


def flight_of(source: Any) -> Flight:
    """The simulator's :class:`Flight` of `source`.

    Parameters
    ----------
    source : Flight, ImpactOscillator or an object carrying one
        A flight (returned as it is), an oscillator, or anything that carries one as
        ``source.osc`` (e.g. :class:`impactcont.Flow`: only its oscillator is read, never
        its evaluation of the flow).

    Returns
    -------
    Flight

    Raises
    ------
    TypeError
        `source` is none of these.
    """
    if isinstance(source, Flight):
        return source
    osc = source if isinstance(source, ImpactOscillator) else getattr(source, "osc", None)
    if not isinstance(osc, ImpactOscillator):
        raise TypeError(f"expected an ImpactOscillator, a simulate.flight.Flight or an object "
                        f"carrying an oscillator as .osc (e.g. impactcont.Flow); got "
                        f"{type(source).__name__}")
    return Flight(osc)


def _system_matrix(osc: ImpactOscillator) -> np.ndarray:
    """``A`` of ``Y' = A Y`` on ``Y = [x; x'; cos theta; sin theta; 1]``, (2n+3, 2n+3)."""
    n, omega = osc.n, float(osc.omega)
    forcing = np.asarray(osc.F)
    inputs = np.column_stack([forcing.real, -forcing.imag if np.iscomplexobj(forcing)
                              else np.zeros(n), np.asarray(osc.F_static, dtype=float)])
    solved = np.linalg.solve(osc.M, np.hstack([osc.K, osc.C, inputs]))
    A = np.zeros((2 * n + 3, 2 * n + 3))
    A[:n, n:2 * n] = np.eye(n)
    A[n:2 * n, :n] = -solved[:, :n]
    A[n:2 * n, n:2 * n] = -solved[:, n:2 * n]
    A[n:2 * n, 2 * n:] = solved[:, 2 * n:]
    A[2 * n, 2 * n + 1] = -omega
    A[2 * n + 1, 2 * n] = omega
    return A


def _eigen(A: np.ndarray, inner: int, omega: float
           ) -> tuple[np.ndarray, np.ndarray, np.ndarray | None, float, np.ndarray | None]:
    """Eigenvalues, eigenvectors ``W``, ``W^-1`` (None off the fast path), the condition
    number of W and the kinds of the modes (:func:`_mode_kinds`; None off the fast path)
    of ``A`` on ``[x; x'; c; s; 1]`` with ``inner`` degrees of freedom."""
    lam, W = scipy.linalg.eig(A)
    condition = math.inf
    W_inv = None
    if np.all(np.isfinite(lam)) and np.all(np.isfinite(W)):
        with np.errstate(all="ignore"):
            condition = float(np.linalg.cond(W))
        if math.isfinite(condition) and condition <= _COND_LIMIT:
            W_inv = np.linalg.inv(W)
    if W_inv is None:
        return lam, W, None, condition, None
    # the forcing's eigenvalues are known exactly (the rotation c' = -omega s,
    # s' = omega c and the constant 1' = 0): the computed ones carry an error of
    # about eps |A|, a phase error growing with t (relative 1e-7 at omega = 1e-8)
    kinds = _mode_kinds(lam, W, inner, condition, omega)
    signs = np.sign(lam[kinds == 1].imag)
    if sorted(signs) != [-1.0, 1.0]:  # the forcing pair not told apart from the modes
        return lam, W, None, condition, None
    lam = lam.copy()
    lam[kinds == 1] = 1j * omega * signs
    lam[kinds == 0] = 0.0
    return lam, W, W_inv, condition, kinds


def _mode_kinds(lam: np.ndarray, W: np.ndarray, inner: int, condition: float,
                omega: float) -> np.ndarray:
    """Each eigenvalue's part in the motion: 1 forced (the pair ``+-i omega``, whose
    eigenvectors carry the forcing states c, s), 0 constant (``lambda = 0``), -1 free.

    A is block upper-triangular (the forcing states evolve on their own), so the
    eigenvectors of the oscillator's own modes vanish on ``c, s`` and those of the
    forcing pair do not: the pair is the two eigenvectors of largest weight there.
    """
    N = W.shape[0]
    kinds = -np.ones(N, dtype=np.int64)
    m = 2 * inner
    share = np.linalg.norm(W[m:m + 2], axis=0) / np.linalg.norm(W, axis=0)
    kinds[np.argsort(share)[-2:]] = 1
    size = max(float(np.abs(lam).max()), omega)
    zero = np.abs(lam) <= 64.0 * _EPS * condition * size
    kinds[zero & (kinds < 0)] = 0
    return kinds


def _null_rows(B: np.ndarray) -> np.ndarray:
    """An orthonormal basis (rows) of the left null space of ``B`` (rows r with ``r B = 0``
    to rounding: singular values below ``64 eps`` of the largest times the size)."""
    if not B.size:
        return np.eye(B.shape[0])
    u, sv, _ = np.linalg.svd(B)
    tol = 64.0 * _EPS * max(B.shape) * max(float(sv[0]) if sv.size else 0.0, _EPS)
    rank = int(np.sum(sv > tol))
    return u[:, rank:].T


def _split_free(A: np.ndarray, inner: int, omega: float) -> dict[str, Any] | None:
    """The fast path of an ``A`` made defective by undamped free modes (module docstring).

    Returns
    -------
    dict or None
        ``eigenvalues, W, W_inv, condition`` of ``S`` and ``chains = (iq, iv, H)``: the
        columns ``e_q``, ``e_q'`` of the free modes in W and the matrix ``H`` (m, N) of
        the constant force on them (``zeta_q'(t) = zeta_q' + t H zeta``); None when there is
        no undamped free mode or the reduced system is itself defective.
    """
    r = inner
    B_K, B_C, B_F = A[r:2 * r, :r], A[r:2 * r, r:2 * r], A[r:2 * r, 2 * r:]
    left = _null_rows(np.hstack([B_K, B_C]))  # U~ (m, r): U~ B_K = 0, U~ B_C = 0
    right = _null_rows(np.vstack([B_K, B_C]).T).T  # U (r, m): B_K U = 0, B_C U = 0
    m = left.shape[0]
    if m == 0 or right.shape[1] != m:
        return None
    gram = left @ right
    if np.linalg.cond(gram) > 1.0 / math.sqrt(_EPS):
        return None
    left = np.linalg.solve(gram, left)  # U~ U = I
    P = _null_rows(left.T).T  # (r, r - m): U~ P = 0
    basis = np.hstack([right, P])
    inverse = np.linalg.inv(basis)
    P_left = inverse[m:]  # P~ (r - m, r): P~ U = 0, P~ P = I
    k = r - m
    A_r = np.zeros((2 * k + 3, 2 * k + 3))
    A_r[:k, k:2 * k] = np.eye(k)
    A_r[k:2 * k, :k] = P_left @ B_K @ P
    A_r[k:2 * k, k:2 * k] = P_left @ B_C @ P
    A_r[k:2 * k, 2 * k:] = P_left @ B_F
    A_r[2 * k:, 2 * k:] = A[2 * r:, 2 * r:]
    lam_r, W_r, W_r_inv, _, kinds = _eigen(A_r, k, omega)
    if W_r_inv is None:
        return None
    drive = left @ B_F  # q'' = drive [c; s; 1]
    h = drive @ W_r[2 * k:]  # (m, 2k + 3): the drive of each reduced mode
    still = kinds == 0
    N_r = 2 * k + 3
    # W_Z on Z = [q; q'; y; y'; c; s; 1]: [[I, Q], [0, W_r]], Q the free modes' part of each
    # reduced eigenvector (q = h / lambda^2, q' = h / lambda; none for lambda = 0: its
    # drive is the chain's H)
    Q = np.zeros((2 * m, N_r), dtype=complex)
    moving = ~still
    Q[:m, moving] = h[:, moving] / lam_r[moving] ** 2
    Q[m:, moving] = h[:, moving] / lam_r[moving]
    N = 2 * r + 3
    W_Z = np.zeros((N, N), dtype=complex)
    W_Z[:2 * m, :2 * m] = np.eye(2 * m)
    W_Z[:2 * m, 2 * m:] = Q
    W_Z[2 * m:, 2 * m:] = W_r
    W_Z_inv = np.zeros((N, N), dtype=complex)
    W_Z_inv[:2 * m, :2 * m] = np.eye(2 * m)
    W_Z_inv[:2 * m, 2 * m:] = -Q @ W_r_inv
    W_Z_inv[2 * m:, 2 * m:] = W_r_inv
    # Y = L Z, Z = L^-1 Y
    L = np.zeros((N, N))
    L[:r, :m] = right
    L[r:2 * r, m:2 * m] = right
    L[:r, 2 * m:2 * m + k] = P
    L[r:2 * r, 2 * m + k:2 * m + 2 * k] = P
    L[2 * r:, 2 * r:] = np.eye(3)
    L_inv = np.zeros((N, N))
    L_inv[:m, :r] = left
    L_inv[m:2 * m, r:2 * r] = left
    L_inv[2 * m:2 * m + k, :r] = P_left
    L_inv[2 * m + k:2 * m + 2 * k, r:2 * r] = P_left
    L_inv[2 * r:, 2 * r:] = np.eye(3)
    W = L @ W_Z
    W_inv = W_Z_inv @ L_inv
    H = np.zeros((m, N), dtype=complex)
    H[:, 2 * m:] = np.where(still, h, 0.0)
    with np.errstate(all="ignore"):
        condition = float(np.linalg.cond(W))
    return {"eigenvalues": np.concatenate([np.zeros(2 * m, dtype=complex), lam_r]), "W": W,
            "W_inv": W_inv, "condition": condition,
            "chains": (np.arange(m), np.arange(m, 2 * m), H)}


class Flight:
    """The exact flow of eq. (1) between impacts, ``Y(t) = expm(A t) Y(0)``.

    Parameters
    ----------
    osc : ImpactOscillator
        Read for ``M, C, K, F, F_static, omega`` and its stops, nothing else.

    Attributes
    ----------
    osc : ImpactOscillator
    n : int
        Degrees of freedom.
    omega : float
        Forcing frequency.
    A : ndarray, shape (2n+3, 2n+3)
        The system matrix (module docstring).
    norm : float
        Its 1-norm (the steps of the slow path).
    eigenvalues : ndarray, complex, shape (2n+3,)
        Eigenvalues of A (the oscillator's, ``+-i omega`` and 0): the time scales.
    fast : bool
        A is diagonalised by eigenvectors of condition number at most ``_COND_LIMIT`` (or
        is so after its undamped free modes are split off, :attr:`chains`): stop
        coordinates are evaluated from the eigenvalues, O(N) per time. Otherwise every
        evaluation is a matrix exponential.
    condition : float
        Condition number of the eigenvectors (``inf`` when A is defective in rounding).
    chains : tuple or None
        The undamped free modes' polynomial part on the fast path (module docstring):
        ``(iq, iv, H)``, the columns ``e_q``, ``e_q'`` of W and the constant force's ``H``;
        None without one.
    """

    def __init__(self, osc: ImpactOscillator) -> None:
        if not isinstance(osc, ImpactOscillator):
            raise TypeError(f"osc must be an ImpactOscillator; got {type(osc).__name__}")
        self._build(osc, _system_matrix(osc), None, None)

    def _build(self, osc: ImpactOscillator, A: np.ndarray, lift: np.ndarray | None,
               restrict: np.ndarray | None) -> None:
        """Set up the flow of ``Y' = A Y`` (`A` of order ``2 r + 3``, the forcing states
        last), read in the oscillator's coordinates through ``lift`` (``[x; x'; c; s; 1] =
        lift @ Y``) and started through ``restrict`` (``Y = restrict @ [x; x'; c; s; 1]``);
        both None for the free flight (``r = n``, the identity)."""
        self.osc = osc
        self.n = osc.n
        self.omega = float(osc.omega)
        self.A = A
        self.inner = (A.shape[0] - 3) // 2  # r: degrees of freedom of the internal state
        self.lift, self.restrict = lift, restrict
        self.norm = float(np.linalg.norm(self.A, 1))
        lam, W, W_inv, condition, kinds = _eigen(A, self.inner, self.omega)
        self.chains: tuple[np.ndarray, np.ndarray, np.ndarray] | None = None
        if W_inv is None and self.inner:
            split = _split_free(A, self.inner, self.omega)
            if split is not None and split["condition"] <= _COND_LIMIT:
                lam, W, W_inv = split["eigenvalues"], split["W"], split["W_inv"]
                condition, self.chains = split["condition"], split["chains"]
        self.eigenvalues = lam
        self.condition = condition
        self.fast = W_inv is not None
        self.W, self.W_inv = W, W_inv
        # the eigenvectors read in the oscillator's coordinates [x; x'; c; s; 1]
        self.W_out = W if lift is None else lift @ W
        self._kinds = kinds if self.chains is None else None  # (no envelope of a drift)
        self._scales: dict[bytes, tuple[float, float]] = {}

    # -- states -------------------------------------------------------------------------------
    def start(self, X: np.ndarray, phase: float) -> np.ndarray:
        """``Y(0) = [X; cos phase; sin phase; 1]`` of a state ``X = [x; x']`` and a phase
        (restricted to the internal state of a constrained flight)."""
        Y = np.concatenate([np.asarray(X, dtype=float).reshape(2 * self.n),
                            [math.cos(phase), math.sin(phase), 1.0]])
        return Y if self.restrict is None else self.restrict @ Y

    def outer(self, Y: np.ndarray) -> np.ndarray:
        """Internal states ``Y`` (rows, shape (nt, N)) as ``[x; x']``, shape (nt, 2n)."""
        m = 2 * self.n
        return Y[..., :m] if self.lift is None else Y @ self.lift[:m].T

    def row(self, coefficients: np.ndarray) -> np.ndarray:
        """The internal row of a linear function ``coefficients . [x; x'; c; s; 1]``."""
        r = np.asarray(coefficients, dtype=float)
        return r if self.lift is None else r @ self.lift

    def propagate(self, t: Any, Y0: np.ndarray) -> np.ndarray:
        """``expm(A t) Y0`` at each time of `t`, shape (nt, N): the exact flow.

        Evaluated in chunks of stacked matrices (at most ``_CHUNK`` entries of work array);
        each matrix exponential is computed on its own, so a value does not depend on the
        times evaluated with it.
        """
        t = np.atleast_1d(np.asarray(t, dtype=float))
        N = self.A.shape[0]
        step = max(1, _CHUNK // (N * N))
        out = np.empty((t.size, N))
        for k in range(0, t.size, step):
            part = t[k:k + step]
            out[k:k + step] = _combine(scipy.linalg.expm(part[:, None, None] * self.A),
                                       Y0[:, None])[..., 0]
        return out

    def advance(self, Y: np.ndarray, dt: float, theta: float) -> np.ndarray:
        """``Y`` a time `dt` later, from forcing phase `theta`: matrix exponentials of steps
        ``|A| h <= _STEP_NORM``, the forcing states set to ``cos, sin`` of the exact phase
        after each."""
        if dt == 0.0:
            return Y.copy()
        steps = max(1, math.ceil(self.norm * abs(dt) / _STEP_NORM))
        h = dt / steps
        E = scipy.linalg.expm(h * self.A)
        m = 2 * self.inner
        for j in range(1, steps + 1):
            Y = _combine(E, Y[:, None])[:, 0]
            Y[m:m + 2] = (math.cos(theta + self.omega * j * h),
                          math.sin(theta + self.omega * j * h))
        return Y

    def modal_sum(self, t: np.ndarray, table: np.ndarray) -> np.ndarray:
        """``Re(sum_k e^{lambda_k t} table[k])`` at each time of `t`, shape (nt, m), on the
        fast path (`table` of shape (N, m))."""
        step = max(1, _CHUNK // (self.A.shape[0] * table.shape[1]))
        out = np.empty((t.size, table.shape[1]))
        for k in range(0, t.size, step):
            rotations = np.exp(np.multiply.outer(t[k:k + step], self.eigenvalues))
            out[k:k + step] = _combine(rotations, table).real
        return out

    def polynomial(self, weights: np.ndarray, modal: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """The polynomial part ``p1 t + p2 t^2 / 2`` of linear functions of the state on the
        fast path with :attr:`chains` (zeros without): `weights` (m, N) the functions' rows
        times W, `modal` (N,) the start's ``W^-1 Y(0)``; ``p1 = w_q zeta_q' + w_q' H zeta``,
        ``p2 = w_q H zeta`` (module docstring). Returns ``p1, p2``, each (m,)."""
        if self.chains is None:
            zeros = np.zeros(weights.shape[0])
            return zeros, zeros
        iq, iv, H = self.chains
        drive = H @ modal  # the constant force on each free mode
        p1 = (weights[:, iq] @ modal[iv] + weights[:, iv] @ drive).real
        p2 = (weights[:, iq] @ drive).real
        return p1, p2

    def samples(self, t: Any, X: np.ndarray, phase: float) -> np.ndarray:
        """The state ``[x; x']`` at sorted times `t` after a start at state X and phase,
        shape (nt, 2n): from the eigenvalues on the fast path, else by matrix exponentials
        from anchors (:meth:`advance`) at most ``_STEP_NORM / |A|`` before each time."""
        m = 2 * self.n
        rows = np.eye(self.A.shape[0])[:m] if self.lift is None else self.lift[:m]
        return self.evaluate(t, X, phase, rows)

    def evaluate(self, t: Any, X: np.ndarray, phase: float, rows: np.ndarray) -> np.ndarray:
        """Linear functions ``rows @ Y`` of the internal state at sorted times `t` after a
        start at state X and phase, shape (nt, len(rows)) (:meth:`samples`)."""
        t = np.atleast_1d(np.asarray(t, dtype=float))
        rows = np.atleast_2d(np.asarray(rows, dtype=float))
        Y = self.start(X, phase)
        if self.fast:
            modal, weights = self.W_inv @ Y, rows @ self.W
            out = self.modal_sum(t, modal[:, None] * weights.T)
            if self.chains is not None:
                p1, p2 = self.polynomial(weights, modal)
                out += np.multiply.outer(t, p1) + np.multiply.outer(0.5 * t * t, p2)
            return out
        out = np.empty((t.size, rows.shape[0]))
        span = _STEP_NORM / max(self.norm, _EPS)
        origin, i = 0.0, 0
        while i < t.size:
            if t[i] - origin > span:
                Y = self.advance(Y, t[i] - origin, phase + self.omega * origin)
                origin = float(t[i])
            j = max(i + 1, int(np.searchsorted(t, origin + span, side="right")))
            out[i:j] = self.propagate(t[i:j] - origin, Y) @ rows.T
            i = j
        return out

    def state(self, t: float, X: np.ndarray, phase: float) -> np.ndarray:
        """The state ``[x; x']`` at time `t` after a start at state X and phase, (2n,)."""
        return self.samples(np.array([float(t)]), X, phase)[0]

    def rate(self, X: np.ndarray, phase: float) -> np.ndarray:
        """``X' = [x'; x'']`` at a state X and phase (eq. 1), shape (2n,)."""
        return self.outer(self.A @ self.start(X, phase))

    # -- time scales --------------------------------------------------------------------------
    def time_scales(self, normal: np.ndarray) -> tuple[float, float]:
        """Fastest oscillation frequency and fastest decay rate seen by ``s = normal . x``.

        On the fast path the modes seen are those of weight ``(r W)_k`` above rounding
        (``r = [normal; 0]``); otherwise every eigenvalue of A counts.

        Returns
        -------
        rate, decay : float
            ``max(omega, max |Im lambda_k|)`` and ``max(0, max -Re lambda_k)`` over the
            modes seen.
        """
        normal = np.asarray(normal, dtype=float)
        full = np.zeros(2 * self.n + 3)
        full[:self.n] = normal
        return self.row_scales(self.row(full))

    def row_scales(self, row: np.ndarray) -> tuple[float, float]:
        """:meth:`time_scales` of any linear function ``row . Y`` of the internal state."""
        row = np.asarray(row, dtype=float)
        key = row.tobytes()
        known = self._scales.get(key)
        if known is None:
            lam = self.eigenvalues
            if self.fast:
                weight = np.abs(row @ self.W)
                lam = lam[weight > 4.0 * _EPS * max(float(weight.max(initial=0.0)), _EPS)]
            known = self._scales[key] = (
                float(max(self.omega, np.abs(lam.imag).max(initial=0.0))),
                float(max(0.0, (-lam.real).max(initial=0.0))))
        return known

    def motion(self, X: np.ndarray, phase: float, normal: np.ndarray | None,
               sign: float = 1.0, *, row: np.ndarray | None = None) -> StopMotion:
        """The evaluator of ``y = sign * normal . x`` (or of ``row . Y``, a linear function
        of the internal state, e.g. a contact force) along the flight from X at `phase`."""
        return StopMotion(self, X, phase, normal, sign, row=row)

    # -- the modes of the envelope ------------------------------------------------------------
    def _mode_kinds(self) -> np.ndarray:
        """:func:`_mode_kinds` of this flight's eigenvalues and eigenvectors."""
        return _mode_kinds(self.eigenvalues, self.W, self.inner, self.condition, self.omega)


class StopMotion:
    """``y = sign * normal . x`` and its first three derivatives along one flight.

    Parameters
    ----------
    flight : Flight
    X : ndarray, shape (2n,)
        The state at the start of the flight.
    phase : float
        The forcing phase there.
    normal : array_like, shape (n,)
        The stop coordinate ``s = normal . x``.
    sign : float
        ``+1`` for a stop met moving up, ``-1`` for one met moving down.
    row : ndarray, optional
        Instead of `normal`: ``y = row . Y`` for a row over the flight's internal state
        (:meth:`Flight.row`; a contact force along a sticking phase).

    Notes
    -----
    Fast path: ``y^(j)(t) = Re(sum_k lambda_k^j c_k e^{lambda_k t})``. Otherwise
    ``y^(j)(t) = (r A^j) expm(A (t - t_a)) Y(t_a)`` with ``r = [sign normal; 0]``, from an
    anchor ``t_a`` that the search moves along the flight (:meth:`anchor`).
    """

    def __init__(self, flight: Flight, X: np.ndarray, phase: float, normal: Any,
                 sign: float = 1.0, *, row: np.ndarray | None = None) -> None:
        n = flight.n
        Y0 = flight.start(X, phase)
        if row is None:
            full = np.zeros(2 * n + 3)
            full[:n] = float(sign) * np.asarray(normal, dtype=float)
            r = flight.row(full)
        else:
            r = np.asarray(row, dtype=float)
        self.row = r
        self.flight = flight
        self.phase = float(phase)
        rows = [r]
        for _ in range(3):
            rows.append(rows[-1] @ flight.A)
        self.rows = np.array(rows)  # r A^j, j = 0..3: the exact derivatives
        self.origin, self.Y_origin = 0.0, Y0  # the anchor of the slow path
        self.p1 = self.p2 = 0.0  # the polynomial part p1 t + p2 t^2 / 2 (Flight.chains)
        if flight.fast:
            self.modal = flight.W_inv @ Y0
            row_w = r @ flight.W
            self.weights = row_w * self.modal
            self.table = self.weights[:, None] * flight.eigenvalues[:, None] ** np.arange(4)
            if flight.chains is not None:
                p1, p2 = flight.polynomial(row_w[None, :], self.modal)
                self.p1, self.p2 = float(p1[0]), float(p2[0])

    def __call__(self, t: Any) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """``y, y', y''`` at times `t` (each shape (nt,))."""
        return self.derivatives(t)[:3]

    def derivatives(self, t: Any) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """``y, y', y'', y'''`` at times `t` (each shape (nt,))."""
        t = np.atleast_1d(np.asarray(t, dtype=float))
        fl = self.flight
        if fl.fast:
            values = fl.modal_sum(t, self.table)
            if fl.chains is not None:
                values[:, 0] += (self.p1 + 0.5 * self.p2 * t) * t
                values[:, 1] += self.p1 + self.p2 * t
                values[:, 2] += self.p2
        else:
            values = _combine(fl.propagate(t - self.origin, self.Y_origin), self.rows.T)
        return values[:, 0], values[:, 1], values[:, 2], values[:, 3]

    def size(self) -> float:
        """The size of the terms ``y`` is summed from at the start (or anchor): an
        evaluation of ``y`` is exact only up to a few ulps of it.

        Returns
        -------
        float
            ``sum_k |c_k|`` over the modal terms on the fast path (with the polynomial
            part's coefficients), and never less than ``|r| . |Y|`` (the row's terms over
            the internal state, the forcing states included): ``y`` is a sum of these
            terms, so its rounding scales with them, not with ``|y|``. At a stop at
            ``s = 0`` with the stop coordinate on it (``b = 0``), ``|y|`` and the stop's
            position are both zero while the state and the forcing are not.
        """
        terms = float(np.abs(self.row) @ np.abs(self.Y_origin))
        if self.flight.fast:
            terms = max(terms, float(np.sum(np.abs(self.weights)))
                        + abs(self.p1) + abs(self.p2))
        return terms

    def anchor(self, t: float) -> None:
        """Evaluate from time `t` on (the slow path; the fast path needs no anchor)."""
        if not self.flight.fast and t != self.origin:
            self.Y_origin = self.flight.advance(self.Y_origin, t - self.origin,
                                                self.phase + self.flight.omega * self.origin)
            self.origin = float(t)

    def state(self, t: float) -> np.ndarray:
        """The state ``[x; x']`` at time `t` (not before the anchor), shape (2n,)."""
        fl = self.flight
        m = 2 * fl.n
        if fl.fast:
            t = float(t)
            out = fl.modal_sum(np.array([t]), self.modal[:, None] * fl.W_out[:m].T)[0]
            if fl.chains is not None:
                p1, p2 = fl.polynomial(fl.W_out[:m], self.modal)
                out += (p1 + 0.5 * p2 * t) * t
            return out
        theta = self.phase + fl.omega * self.origin
        return fl.outer(fl.advance(self.Y_origin, float(t) - self.origin, theta))

    def envelope(self, t0: float, horizon: float) -> tuple[complex, float, float, float] | None:
        """Forced amplitude, a bound on the free part on ``[t0, horizon]`` and two sizes.

        ``y(t) = Re(z e^{i omega t}) + offset + y_free(t)`` with
        ``|y_free(t)| <= sum_k |c_k| e^{Re(lambda_k) t}``, the largest over the stretch:
        at ``t0`` for a decaying mode, at `horizon` for one whose computed real part is
        positive (an undamped mode, in rounding).

        Returns
        -------
        (z, free, start, offset) or None
            ``z`` the complex amplitude of the forced part at ``t = 0``, ``free`` the bound,
            ``start`` the sum of every ``|c_k|`` (the size of the motion), ``offset`` the
            constant part (a constant force). None off the fast path.
        """
        fl = self.flight
        if fl._kinds is None:
            return None
        kinds, lam, c = fl._kinds, fl.eigenvalues, self.weights
        pair = np.flatnonzero(kinds == 1)
        z = complex(np.sum(np.where(lam[pair].imag > 0, c[pair], np.conj(c[pair]))))
        free = kinds < 0
        rates = lam[free].real
        with np.errstate(over="ignore"):
            bound = float(np.sum(np.abs(c[free]) * np.exp(rates * np.where(rates > 0.0, horizon,
                                                                             t0))))
        if not math.isfinite(bound):
            return None
        offset = float(np.sum(c[kinds == 0]).real)
        return z, bound, float(np.sum(np.abs(c))), offset
