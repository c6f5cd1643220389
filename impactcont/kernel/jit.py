"""The two ways the kernel compiles a function (numba, cached on disk per host CPU).

``entry``: a function Python calls. ``inner``: a private helper only compiled code
calls; it gets no CPython wrapper (calling it from Python would crash, so only names
with a leading underscore take it). Neither gets a C-callback wrapper, which the
kernel never uses. The wrappers are about a tenth of what a new install compiles
before the four main verbs have each run once (21.1 -> 19.5 s of CPU,
``studies/performance/first_use.py``).

``error_model="numpy"``: ``x / 0`` gives ``inf`` as in numpy, no exception.

Notes
-----
numba inlines the compiled helpers a function calls into its own machine code, but its
on-disk cache is checked against the source of the function's own file only: after an
edit of ``shooting.py``, the map sweep of ``sweep.py`` (which calls the flights of
``shooting.py``) was loaded from the cache with the old flights, and returned wrong
gaps. The kernel's functions are therefore cached against the sources of every module
of their directory (:func:`source_stamp`): an edit of any kernel module compiles the
kernel again. The kernel imports nothing compiled from outside its directory. An index
that an earlier source wrote with types since removed is read as obsolete (numba raises
while unpickling it).
"""

from __future__ import annotations

import hashlib
import logging
import os
import pickle
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numba as nb
from numba.core import config, typeinfer
from numba.core.caching import (
    CompileResultCacheImpl,
    FunctionCache,
    IndexDataCacheFile,
    InTreeCacheLocator,
    UserProvidedCacheLocator,
    UserWideCacheLocator,
)

__all__ = ["entry", "inner", "source_stamp", "typed_entry"]

_OPTIONS = dict(nogil=True, error_model="numpy", no_cfunc_wrapper=True)

log = logging.getLogger(__name__)

_stamps: dict[tuple, bytes] = {}


def source_stamp(directory: str | os.PathLike) -> bytes:
    """SHA-256 of the sources of every ``*.py`` module in `directory` (by name order).

    Parameters
    ----------
    directory : path
        A package directory (the kernel's).

    Returns
    -------
    bytes
        The digest; computed once per set of (name, mtime, size) of the files.
    """
    files = sorted(Path(directory).glob("*.py"))
    key = tuple((f.name, st.st_mtime_ns, st.st_size) for f in files for st in [f.stat()])
    if key not in _stamps:
        digest = hashlib.sha256()
        for f in files:
            digest.update(f.name.encode())
            digest.update(hashlib.sha256(f.read_bytes()).digest())
        _stamps[key] = digest.digest()
    return _stamps[key]


class _DirectoryStamp:
    """A numba cache locator whose freshness is that of the whole source directory."""

    _py_file: str

    def get_source_stamp(self) -> bytes:
        return source_stamp(os.path.dirname(os.path.abspath(self._py_file)))


class _UserProvided(_DirectoryStamp, UserProvidedCacheLocator):
    pass


class _InTree(_DirectoryStamp, InTreeCacheLocator):
    pass


class _UserWide(_DirectoryStamp, UserWideCacheLocator):
    pass


class _DirectoryCacheImpl(CompileResultCacheImpl):
    _locator_classes = (_UserProvided, _InTree, _UserWide)


class _IndexFile(IndexDataCacheFile):
    """numba's index of a function's cached variants; one written by an earlier source whose
    types are gone (``AttributeError`` while unpickling) is obsolete, not an error."""

    def _load_index(self) -> dict:
        try:
            return super()._load_index()
        except (AttributeError, ImportError, EOFError, pickle.UnpicklingError) as exc:
            log.debug("obsolete numba cache index %s (%s): compiling again",
                      self._index_path, exc)
            return {}


class _DirectoryCache(FunctionCache):
    """numba's function cache, invalidated by an edit of any module of the directory."""

    _impl_class = _DirectoryCacheImpl

    def __init__(self, py_func: Callable) -> None:
        super().__init__(py_func)
        self._cache_file = _IndexFile(cache_path=self._cache_path,
                                      filename_base=self._impl.filename_base,
                                      source_stamp=self._impl.locator.get_source_stamp())


def _compiled(options: dict[str, Any], signature: Any = None) -> Callable:
    """A decorator: ``nb.njit(**options)`` cached by :class:`_DirectoryCache`."""

    def decorate(func: Callable) -> Any:
        disp = nb.njit(**options)(func)
        if config.DISABLE_JIT:
            return disp
        disp._cache = _DirectoryCache(disp.py_func)
        if signature is not None:
            with typeinfer.register_dispatcher(disp):
                disp.compile(signature)
            disp.disable_compile()
        return disp

    return decorate


entry = _compiled(_OPTIONS)
inner = _compiled(dict(no_cpython_wrapper=True, **_OPTIONS))


def typed_entry(signature: Any) -> Callable:
    """``entry`` compiled eagerly for one explicit `signature`."""
    return _compiled(_OPTIONS, signature)
