"""Temporary map files, removed when the map is closed.

A map larger than the memory it may take goes to a temporary file
(:func:`temporary_map_file`) returned opened lazily by :func:`open_temporary_map`:
the file is removed when that dataset is closed (``ds.close()``, or the end of a
``with`` block), and at the latest when the interpreter exits. Temporary maps are
named like the temporary files of :func:`impactcont.dataset.io.save`
(``.impactcont-map.nc.<host>-<pid>.<random>.tmp`` in :func:`tempfile.gettempdir`):
those of a process that was killed are removed when the next one is made.
"""

from __future__ import annotations

import atexit
import logging
import os
import tempfile
import threading
from pathlib import Path

import xarray as xr

from impactcont.dataset.io import open_lazy, remove_stale_temporaries, temporary_path

__all__ = ["open_temporary_map", "temporary_map_file"]

log = logging.getLogger(__name__)

_lock = threading.Lock()
_temporary: set[Path] = set()  # temporary maps of this process not yet removed
_owner = os.getpid()


def temporary_map_file() -> Path:
    """A fresh path for a temporary map, after removing those left by killed processes."""
    directory = Path(tempfile.gettempdir())
    remove_stale_temporaries(directory)
    return temporary_path(directory / "impactcont-map.nc")


def _remove(path: Path) -> None:
    with _lock:
        _temporary.discard(path)
    try:
        path.unlink(missing_ok=True)
    except OSError as exc:  # e.g. the directory is gone or read-only now
        log.warning("cannot remove the temporary map %s: %s", path, exc)
    else:
        log.debug("removed the temporary map %s", path)


@atexit.register
def _remove_all() -> None:
    """At exit, the temporary maps still open (in the process that made them only)."""
    if os.getpid() != _owner:
        return
    for path in list(_temporary):
        _remove(path)


def open_temporary_map(path: Path) -> xr.Dataset:
    """Open the temporary map ``path`` lazily; the file is removed when the dataset is closed.

    Parameters
    ----------
    path : pathlib.Path
        A map written to a path of :func:`temporary_map_file`.

    Returns
    -------
    xarray.Dataset
        Dask-backed; ``close()`` (or leaving a ``with`` block) closes and removes the
        file, and so does the end of the interpreter.
    """
    with _lock:
        _temporary.add(path)
    try:
        return open_lazy(path, on_close=lambda: _remove(path))
    except BaseException:
        _remove(path)
        raise
