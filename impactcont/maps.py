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
import functools
import logging
import math
import os
import tempfile
import time
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np
import xarray as xr

from impactcont.dataset.curves import map_dataset
from impactcont.dataset.io import open_lazy, save
from impactcont.errors import ParameterError
from impactcont.model.oscillator import ImpactOscillator
from impactcont.orbit.batched import batched_orbits
from impactcont.orbit.periodic import _check_N
from impactcont.threads import blas_limited

__all__ = ["stability_map"]

log = logging.getLogger(__name__)

_OMEGA_BLOCK = 32
_POINTS_PER_TASK = 1 << 17  # omega x b points per task at most (fewer omega for long b grids)
_BYTES_PER_MOTION = 70  # delta, velocity, gap, time, rho (8 each), multiplier (16), flags
_DTYPES = {"physical": bool, "stable": bool, "critical_multiplier": complex}
_ROOT_FIELDS = ("delta", "impact_velocity", "gap_min", "spectral_radius", "critical_multiplier",
                "physical", "stable")


@blas_limited
def _map_task(osc_json: str, N: int, omega: np.ndarray, b: np.ndarray,
              spectral_radius: bool = True) -> dict[str, np.ndarray]:
    """One task: every motion for one N and a block of omega values (picklable, top level)."""
    osc = _oscillator(osc_json)
    out = batched_orbits(osc, N, omega, b, spectral_radius=spectral_radius)
    return {k: out[k] for k in ("amplitude_squared", "exists", *_ROOT_FIELDS)}


@functools.lru_cache(maxsize=4)
def _oscillator(osc_json: str) -> ImpactOscillator:
    """The oscillator of a task, built (and its modes computed) once per process: a map
    sends the same one with every block."""
    return ImpactOscillator.from_json(osc_json)


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


@blas_limited
def stability_map(osc: ImpactOscillator, N: int | Sequence[int] = (1, 2, 3, 4),
                  omega: Sequence[float] | np.ndarray = (),
                  b: Sequence[float] | np.ndarray = (), *, executor: Any = None,
                  max_workers: int | None = None, omega_block: int | None = None,
                  spectral_radius: bool = True, out: str | os.PathLike | None = None,
                  memory_limit: float = 2e9) -> xr.Dataset:
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
        Omega values per task; default: up to 32, fewer for long b grids (a fixed
        block: memory per task is bounded and results do not depend on the executor).
    spectral_radius : bool
        Store ``spectral_radius`` and ``critical_multiplier`` (LAPACK eigenvalues of
        every G). Without them the map is about 3x faster: ``stable`` comes from the
        Schur-Cohn test of the characteristic polynomial of G either way.
    out : str or os.PathLike, optional
        Write the map to this NetCDF-4 file (chunked by task, compressed) as the
        blocks finish and return it opened lazily (dask-backed). Without it a map
        larger than `memory_limit` goes to a temporary file the same way (with a
        warning naming it). Needs the extra ``impactcont[dask]``.
    memory_limit : float
        Bytes a map may take in memory (default 2e9; about 70 bytes per motion).

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
    if omega_block is None:
        # a fixed block, whatever the executor and the number of omega values: memory per
        # task bounded (about 70 bytes per motion), results independent of how they ran
        omega_block = max(1, min(_OMEGA_BLOCK, _POINTS_PER_TASK // bb.size))
    elif isinstance(omega_block, bool) or not isinstance(omega_block, int) or omega_block < 1:
        raise ParameterError(f"omega_block must be an integer >= 1 or None; got {omega_block!r}")
    if not (isinstance(memory_limit, (int, float)) and not isinstance(memory_limit, bool)
            and memory_limit > 0):
        raise ParameterError(f"memory_limit must be a number of bytes > 0; got {memory_limit!r}")
    blocks = [slice(i, min(i + omega_block, w.size)) for i in range(0, w.size, omega_block)]
    tasks = [(k, sl) for k in range(len(Ns)) for sl in blocks]
    shape = (len(Ns), w.size, bb.size)
    size = _BYTES_PER_MOTION * 2 * math.prod(shape)
    if out is None and size > memory_limit:
        out = Path(tempfile.mkstemp(prefix="impactcont-map-", suffix=".nc")[1])
        log.warning("the map needs about %.3g GB, more than memory_limit=%.3g GB: it is "
                    "written to %s and returned lazily", size / 1e9, memory_limit / 1e9, out)
    pool, owned, name = _executor(executor, max_workers)
    options = {"executor": name, "tasks": len(tasks), "omega_block": omega_block,
               "spectral_radius": spectral_radius}
    start = time.perf_counter()
    path = None
    try:
        if out is not None:
            path = _map_to_file(osc, Ns, w, bb, tasks, spectral_radius, pool, name, options,
                                out)
            results = []
        elif pool is None:
            text = osc.to_json()
            results = [_map_task(text, Ns[k], w[sl], bb, spectral_radius) for k, sl in tasks]
        else:
            text = osc.to_json()
            futures = [pool.submit(_map_task, text, Ns[k], w[sl], bb, spectral_radius)
                       for k, sl in tasks]
            results = [f.result() for f in futures]
    finally:
        if owned:
            pool.shutdown()
    if path is not None:
        # opened once the workers are gone: a worker forked while the file was being
        # written holds its HDF5 lock until it exits
        return open_lazy(path)
    elapsed = time.perf_counter() - start
    values: dict[str, np.ndarray] = {
        "amplitude_squared": np.empty(shape[:2]),
        "exists": np.empty(shape, dtype=bool),
    }
    for key in _fields(spectral_radius):
        values[key] = np.empty((*shape, 2), dtype=_DTYPES.get(key, float))
    for (k, sl), res in zip(tasks, results, strict=True):
        values["amplitude_squared"][k, sl] = res["amplitude_squared"]
        values["exists"][k, sl] = res["exists"]
        for key in _fields(spectral_radius):
            values[key][k, sl] = res[key]
    values["n_physical"] = values["physical"].sum(axis=-1)
    values["n_stable"] = (values["physical"] & values["stable"]).sum(axis=-1)
    log.info("map of %d x %d x %d points in %.2f s (%d tasks, executor %s)", *shape, elapsed,
             len(tasks), name)
    options["elapsed_seconds"] = round(elapsed, 3)
    return map_dataset(oscillator=osc, N=Ns, omega=w, b=bb, values=values, options=options)


def _fields(spectral_radius: bool) -> tuple[str, ...]:
    return tuple(k for k in _ROOT_FIELDS
                 if spectral_radius or k not in ("spectral_radius", "critical_multiplier"))


def _map_to_file(osc: ImpactOscillator, Ns: list[int], w: np.ndarray, bb: np.ndarray,
                 tasks: list[tuple[int, slice]], spectral_radius: bool, pool: Any,
                 name: str, options: dict[str, Any], out: Any) -> Path:
    """Compute the map block by block into a chunked, compressed NetCDF-4 file.

    Each task is one dask chunk along ``(N, omega)``; writing the file computes the
    chunks and stores each as it finishes, so no more than the blocks in flight are
    held in memory, in the workers or here.
    """
    try:
        import dask
        import dask.array as da
    except ImportError:
        raise ParameterError("a map written to disk (out=..., or larger than memory_limit) "
                             "needs dask: pip install 'impactcont[dask]'") from None
    text = osc.to_json()
    nb = bb.size
    if pool is None:
        compute = _map_task
    else:
        def compute(*args: Any) -> dict[str, np.ndarray]:
            # runs in a thread of this process (dask's threaded scheduler): the task goes
            # to the executor, the NetCDF writes stay here
            return pool.submit(_map_task, *args).result()
    per_n: dict[str, list[list[Any]]] = {}
    for k, sl in tasks:
        part = dask.delayed(compute, pure=True)(text, Ns[k], w[sl], bb, spectral_radius)
        width = sl.stop - sl.start
        pieces = {"amplitude_squared": ((width,), float), "exists": ((width, nb), bool)}
        for key in _fields(spectral_radius):
            pieces[key] = ((width, nb, 2), _DTYPES.get(key, float))
        for key, (shape, dtype) in pieces.items():
            rows = per_n.setdefault(key, [[] for _ in Ns])
            rows[k].append(da.from_delayed(part[key], shape=shape, dtype=dtype))
    values = {key: da.stack([da.concatenate(row, axis=0) for row in rows])
              for key, rows in per_n.items()}
    values["n_physical"] = values["physical"].sum(axis=-1)
    values["n_stable"] = (values["physical"] & values["stable"]).sum(axis=-1)
    ds = map_dataset(oscillator=osc, N=Ns, omega=w, b=bb, values=values, options=options)
    block = tasks[0][1].stop - tasks[0][1].start
    encoding = {key: {"zlib": True, "complevel": 1,
                      "chunksizes": (1, min(block, w.size), *ds[key].shape[2:])}
                for key in ds.data_vars}
    settings = ({"scheduler": "synchronous"} if pool is None else
                {"scheduler": "threads", "num_workers": max(1, getattr(pool, "_max_workers", 2))})
    start = time.perf_counter()
    with dask.config.set(**settings):
        path = save(ds, out, validate=False, encoding=encoding)
    log.info("map of %d x %d x %d points written to %s in %.2f s (%d tasks, executor %s)",
             len(Ns), w.size, nb, path, time.perf_counter() - start, len(tasks), name)
    return path
