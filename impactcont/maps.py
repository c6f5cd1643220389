"""Maps of the (omega, b) plane: existence, physicality and stability of N-1 motions on a grid.

``stability_map(osc, N=[1, 2, 3, 4], omega=..., b=...)`` evaluates every root of
eq. (15) at every grid point with the batched closed form of
:mod:`impactcont.orbit.batched` (stacked numpy over ``omega x b x root``; ``S``
of eq. 13 once per ``omega``) and returns an :class:`xarray.Dataset` with dims
``(N, omega, b, root)`` (schema: :mod:`impactcont.dataset.curves`).

The work is split into tasks of ``(N, block of omega values)`` run through a
standard :class:`concurrent.futures.Executor`:

- ``executor=None`` or ``"serial"``: in this process;
- ``"process"``: a :class:`~concurrent.futures.ProcessPoolExecutor` created and
  shut down here (``max_workers`` processes);
- any :class:`~concurrent.futures.Executor` instance (owned by the caller), e.g.
  ``dask.distributed.Client(...).get_executor()``; a ``dask.distributed.Client``
  itself is accepted too (optional extra ``impactcont[dask]``).

Tasks receive the oscillator as JSON and return plain arrays, so any executor
that pickles works.
"""

from __future__ import annotations

import concurrent.futures as cf
import logging
import math
import time
from collections.abc import Sequence
from typing import Any

import numpy as np
import xarray as xr

from impactcont.dataset.curves import map_dataset
from impactcont.errors import ParameterError
from impactcont.model.oscillator import ImpactOscillator
from impactcont.orbit.batched import batched_orbits
from impactcont.orbit.periodic import _check_N

__all__ = ["stability_map"]

log = logging.getLogger(__name__)

_ROOT_FIELDS = ("delta", "impact_velocity", "gap_min", "spectral_radius", "critical_multiplier",
                "physical", "stable")


def _map_task(osc_json: str, N: int, omega: np.ndarray, b: np.ndarray,
              spectral_radius: bool = True) -> dict[str, np.ndarray]:
    """One task: every motion for one N and a block of omega values (picklable, top level)."""
    osc = ImpactOscillator.from_json(osc_json)
    out = batched_orbits(osc, N, omega, b, spectral_radius=spectral_radius)
    return {k: out[k] for k in ("amplitude_squared", "exists", *_ROOT_FIELDS)}


def _grid(name: str, values: Any) -> np.ndarray:
    try:
        a = np.asarray(values, dtype=float)
    except (TypeError, ValueError):
        raise ParameterError(f"{name} must be a 1-D array of finite numbers; got {values!r}"
                             ) from None
    if a.ndim != 1 or a.size == 0 or not np.all(np.isfinite(a)):
        raise ParameterError(f"{name} must be a non-empty 1-D array of finite numbers; got "
                             f"{values!r}")
    if a.size > 1 and not np.all(np.diff(a) > 0):
        raise ParameterError(f"{name} must be strictly increasing; got {values!r}")
    return a


def _executor(executor: Any, max_workers: int | None) -> tuple[cf.Executor | None, bool, str]:
    """The executor to use, whether it is owned here, and its name for the record."""
    if executor is None or executor == "serial":
        return None, False, "serial"
    if executor == "process":
        return cf.ProcessPoolExecutor(max_workers=max_workers), True, "process"
    if isinstance(executor, cf.Executor):
        return executor, False, type(executor).__name__
    get_executor = getattr(executor, "get_executor", None)  # a dask.distributed.Client
    if callable(get_executor) and type(executor).__name__ == "Client":
        return get_executor(), False, "dask.distributed"
    raise ParameterError(f"executor must be None, 'serial', 'process', a concurrent.futures."
                         f"Executor or a dask.distributed.Client; got {executor!r}")


def stability_map(osc: ImpactOscillator, N: int | Sequence[int] = (1, 2, 3, 4),
                  omega: Sequence[float] | np.ndarray = (),
                  b: Sequence[float] | np.ndarray = (), *, executor: Any = None,
                  max_workers: int | None = None, omega_block: int | None = None,
                  spectral_radius: bool = True) -> xr.Dataset:
    """Existence, physicality and stability of every N-1 motion on an (N, omega, b) grid.

    Parameters
    ----------
    osc : ImpactOscillator
        The oscillator; its own ``omega`` and ``b`` are ignored.
    N : int or sequence of int
        Forcing periods per impact.
    omega, b : 1-D array_like
        Strictly increasing grids of the forcing frequency (``> 0``) and the gap.
    executor : None, "serial", "process", Executor or dask.distributed.Client
        Where the tasks run (see the module docstring).
    max_workers : int, optional
        Processes of the ``"process"`` pool.
    omega_block : int, optional
        Omega values per task; default: about 4 tasks per worker and N.
    spectral_radius : bool
        Store ``spectral_radius`` and ``critical_multiplier`` (LAPACK eigenvalues of
        every G). Without them the map is about 3x faster: ``stable`` comes from the
        Schur-Cohn test of the characteristic polynomial of G either way.

    Returns
    -------
    xarray.Dataset
        Dims ``N``, ``omega``, ``b``, ``root`` (``+1, -1``, eq. 15): ``exists``,
        ``n_physical``, ``n_stable`` on ``(N, omega, b)``; ``delta``,
        ``impact_velocity``, ``gap_min``, ``spectral_radius``,
        ``critical_multiplier``, ``physical``, ``stable`` per root;
        ``amplitude_squared`` on ``(N, omega)``.

    Raises
    ------
    ParameterError
        A bad grid, N or executor (named in the message).
    """
    if not isinstance(osc, ImpactOscillator):
        raise ParameterError(f"osc must be an ImpactOscillator; got {osc!r}")
    Ns = [N] if isinstance(N, (int, np.integer)) and not isinstance(N, bool) else list(N)
    if not Ns:
        raise ParameterError(f"N must be an integer >= 1 or a non-empty sequence of them; "
                             f"got {N!r}")
    Ns = [_check_N(k) for k in Ns]
    if len(set(Ns)) != len(Ns):
        raise ParameterError(f"N must not repeat values; got {N!r}")
    w = _grid("omega", omega)
    if np.any(w <= 0):
        raise ParameterError(f"omega must be > 0; got {omega!r}")
    bb = _grid("b", b)
    if not isinstance(spectral_radius, bool):
        raise ParameterError(f"spectral_radius must be True or False; got {spectral_radius!r}")
    if max_workers is not None and (isinstance(max_workers, bool)
                                    or not isinstance(max_workers, int) or max_workers < 1):
        raise ParameterError(f"max_workers must be an integer >= 1 or None; got {max_workers!r}")
    pool, owned, name = _executor(executor, max_workers)
    if omega_block is None:
        workers = 1 if pool is None else (max_workers or 2)
        omega_block = max(1, math.ceil(w.size / (4 * workers)))
    elif isinstance(omega_block, bool) or not isinstance(omega_block, int) or omega_block < 1:
        raise ParameterError(f"omega_block must be an integer >= 1 or None; got {omega_block!r}")
    blocks = [slice(i, min(i + omega_block, w.size)) for i in range(0, w.size, omega_block)]
    tasks = [(k, sl) for k in range(len(Ns)) for sl in blocks]
    text = osc.to_json()
    start = time.perf_counter()
    try:
        if pool is None:
            results = [_map_task(text, Ns[k], w[sl], bb, spectral_radius) for k, sl in tasks]
        else:
            futures = [pool.submit(_map_task, text, Ns[k], w[sl], bb, spectral_radius)
                       for k, sl in tasks]
            results = [f.result() for f in futures]
    finally:
        if owned:
            pool.shutdown()
    elapsed = time.perf_counter() - start
    shape = (len(Ns), w.size, bb.size)
    values: dict[str, np.ndarray] = {
        "amplitude_squared": np.empty(shape[:2]),
        "exists": np.empty(shape, dtype=bool),
    }
    for key in _ROOT_FIELDS:
        dtype = bool if key in ("physical", "stable") else (
            complex if key == "critical_multiplier" else float)
        values[key] = np.empty((*shape, 2), dtype=dtype)
    for (k, sl), res in zip(tasks, results, strict=True):
        values["amplitude_squared"][k, sl] = res["amplitude_squared"]
        values["exists"][k, sl] = res["exists"]
        for key in _ROOT_FIELDS:
            values[key][k, sl] = res[key]
    values["n_physical"] = values["physical"].sum(axis=-1)
    values["n_stable"] = (values["physical"] & values["stable"]).sum(axis=-1)
    log.info("map of %d x %d x %d points in %.2f s (%d tasks, executor %s)", *shape, elapsed,
             len(tasks), name)
    if not spectral_radius:
        del values["spectral_radius"], values["critical_multiplier"]
    options = {"executor": name, "tasks": len(tasks), "omega_block": omega_block,
               "spectral_radius": spectral_radius, "elapsed_seconds": round(elapsed, 3)}
    return map_dataset(oscillator=osc, N=Ns, omega=w, b=bb, values=values, options=options)
