"""Temporary map files, removed when the map is closed.

A map larger than the memory it may take goes to a temporary file
(:func:`temporary_map_file`) returned opened lazily by :func:`open_temporary_map`:
the file is removed when that dataset is closed (``ds.close()``, or the end of a
``with`` block), and at the latest when the interpreter exits. Temporary maps are
named like the temporary files of :func:`impactcont.dataset.io.save`
(``.impactcont-map.nc.<host>-<pid>.<random>.tmp`` in :func:`tempfile.gettempdir`).

When the process ends without running ``atexit`` (issue 28):

- **SIGTERM** (``kill``, a batch scheduler's time limit): while this process has a
  temporary map (written or open), made from the main thread, and SIGTERM has its
  default action, a handler is installed that removes this process's temporary maps
  (and the one being written) and then ends the process by SIGTERM as before; the
  default action is put back when the last temporary map is gone. (A SIGTERM that
  arrives while the main thread is inside one long compiled call acts when that call
  returns.) A SIGTERM handler of the program's own is left alone: if it raises
  ``SystemExit``, ``atexit`` removes the maps.
- **SIGKILL** (or a crash): nothing runs in the process. Its temporary maps are
  removed by the next map of any process on this host: :func:`remove_stale_maps` runs
  at the first :func:`impactcont.stability_map` of every process and before every
  temporary map (the file names carry the host and the pid; only files of processes
  that no longer run are removed).
"""

from __future__ import annotations

import atexit
import contextlib
import logging
import os
import signal
import tempfile
import threading
from pathlib import Path
from typing import Any

import xarray as xr

from impactcont.dataset.io import open_lazy, remove_stale_temporaries, temporary_path

__all__ = ["open_temporary_map", "remove_stale_maps", "remove_temporary_map",
           "temporary_map_file"]

log = logging.getLogger(__name__)

_lock = threading.Lock()
_temporary: set[Path] = set()  # temporary maps of this process not yet removed
_owner = os.getpid()
_NAME = "impactcont-map.nc"
_swept = False  # remove_stale_maps has run once in this process
_sigterm_installed = False  # _on_sigterm is SIGTERM's handler


def remove_stale_maps(*, once: bool = False) -> list[Path]:
    """Remove the temporary maps (and temporary files) of processes that no longer run.

    Parameters
    ----------
    once : bool
        Only at the first call with ``once=True`` in this process (the first map).

    Returns
    -------
    list of pathlib.Path
        The files removed from :func:`tempfile.gettempdir` (see
        :func:`impactcont.dataset.io.remove_stale_temporaries`).
    """
    global _swept
    if once and _swept:
        return []
    _swept = True
    return remove_stale_temporaries(Path(tempfile.gettempdir()))


def temporary_map_file() -> Path:
    """A fresh path for a temporary map, after removing those left by killed processes.

    The path is this process's until :func:`remove_temporary_map` or the end of the map
    it holds: removed at exit, and on SIGTERM (see the module's docstring).
    """
    remove_stale_maps()
    path = temporary_path(Path(tempfile.gettempdir()) / _NAME)
    with _lock:
        _temporary.add(path)
    _watch_sigterm()
    return path


def _own_files(path: Path) -> list[Path]:
    """`path` and the temporary files of this process's writes of it beside it (a
    temporary map being written is ``.<path's name>.<host>-<pid>.<random>.tmp``)."""
    prefix = f".{path.name}."
    found = [path]
    with contextlib.suppress(OSError), os.scandir(path.parent) as entries:
        found += [Path(e.path) for e in entries if e.name.startswith(prefix)
                  and e.name.endswith(".tmp") and f"-{os.getpid()}." in e.name]
    return found


def _on_sigterm(signum: int, frame: Any) -> None:
    """SIGTERM: remove this process's temporary maps, then end by SIGTERM as by default."""
    global _sigterm_installed
    if os.getpid() == _owner:  # not in a forked child (a pool worker): the maps are not its
        for path in list(_temporary):
            for own in _own_files(path):
                with contextlib.suppress(OSError):
                    own.unlink()
    signal.signal(signal.SIGTERM, signal.SIG_DFL)
    _sigterm_installed = False
    os.kill(os.getpid(), signal.SIGTERM)


def _watch_sigterm() -> None:
    """Install :func:`_on_sigterm` if SIGTERM has its default action (main thread only)."""
    global _sigterm_installed
    if _sigterm_installed or threading.current_thread() is not threading.main_thread():
        return
    with contextlib.suppress(ValueError, OSError):
        if signal.getsignal(signal.SIGTERM) == signal.SIG_DFL:
            signal.signal(signal.SIGTERM, _on_sigterm)
            _sigterm_installed = True


def _unwatch_sigterm() -> None:
    """Give SIGTERM its default action back once no temporary map is left."""
    global _sigterm_installed
    if (not _sigterm_installed or _temporary
            or threading.current_thread() is not threading.main_thread()):
        return
    with contextlib.suppress(ValueError, OSError):
        if signal.getsignal(signal.SIGTERM) is _on_sigterm:
            signal.signal(signal.SIGTERM, signal.SIG_DFL)
        _sigterm_installed = False


def remove_temporary_map(path: Path) -> None:
    """Remove the temporary map `path` (a map that failed, or one closed) and forget it."""
    _remove(path)


def _remove(path: Path) -> None:
    with _lock:
        _temporary.discard(path)
    try:
        path.unlink(missing_ok=True)
    except OSError as exc:  # e.g. the directory is gone or read-only now
        log.warning("cannot remove the temporary map %s: %s", path, exc)
    else:
        log.debug("removed the temporary map %s", path)
    _unwatch_sigterm()


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
