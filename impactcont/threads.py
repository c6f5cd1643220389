"""BLAS threads while impactcont computes: one by default, so that no user needs to know.

The linear algebra of impactcont works on ``2n x 2n`` matrices with small ``n``,
solved many thousand times per branch. BLAS threads bring no speed there, and
on a loaded machine their spinning slows a continuation down by up to 12 times
(29 s against 3 s for one N = 1 branch on two busy cores). The long-running
entry points therefore limit BLAS to one thread while they run and restore the
caller's setting afterwards::

    from impactcont.threads import blas_limited, limit_blas_threads

    @blas_limited                 # a public entry point of the library
    def continuation(...): ...

    with limit_blas_threads():    # a block of code
        ...

The limit is taken once by the outermost entry (nested and concurrent entries
share it; it is lifted when the last one leaves). Finding the BLAS libraries the
process has loaded (threadpoolctl's scan of the shared objects) costs about 1.3 ms, so
it is done once and again only when a Python module has been imported since (a new
extension module is how a new BLAS comes in); setting the limit then costs about
0.02 ms. A BLAS loaded without any import (``ctypes`` alone) is not limited until the
next import.

The environment variable ``IMPACTCONT_BLAS_THREADS`` changes the limit: a
positive integer is the number of threads, ``none`` leaves BLAS as it is.
"""

from __future__ import annotations

import contextlib
import functools
import logging
import os
import sys
import threading
from collections.abc import Callable
from typing import Any, TypeVar

__all__ = ["ENVIRONMENT_VARIABLE", "blas_limited", "blas_thread_limit", "limit_blas_threads"]

logger = logging.getLogger(__name__)

#: Environment variable that sets the limit (a positive integer, or ``none``).
ENVIRONMENT_VARIABLE = "IMPACTCONT_BLAS_THREADS"

_F = TypeVar("_F", bound=Callable[..., Any])

_lock = threading.Lock()
_depth = 0
_limiter: Any = None
_controller: Any = None  # threadpoolctl's ThreadpoolController of the last scan
_modules_seen = -1  # len(sys.modules) at that scan


def blas_thread_limit() -> int | None:
    """The number of BLAS threads impactcont allows, from ``IMPACTCONT_BLAS_THREADS``.

    Returns
    -------
    int or None
        1 when the variable is unset, its value when it is a positive integer,
        None (no limit) when it is ``none``.

    Raises
    ------
    ValueError
        The variable holds anything else; the message names it and its value.
    """
    text = os.environ.get(ENVIRONMENT_VARIABLE, "").strip()
    if not text:
        return 1
    if text.lower() == "none":
        return None
    if text.isdigit() and int(text) >= 1:
        return int(text)
    raise ValueError(f"environment variable {ENVIRONMENT_VARIABLE} must be a positive integer "
                     f"or 'none'; got {text!r}")


def _start() -> Any:
    """Apply the limit; return what restores the previous setting (or None)."""
    limit = blas_thread_limit()
    if limit is None:
        return None
    controller = _blas_controller()
    if controller is None:  # pragma: no cover - threadpoolctl is a dependency
        return None
    return controller.limit(limits=limit, user_api="blas")


def _blas_controller() -> Any:
    """threadpoolctl's view of the loaded thread pools, scanned again only when a module
    has been imported since the last scan (called under ``_lock``)."""
    global _controller, _modules_seen
    try:
        from threadpoolctl import ThreadpoolController
    except ImportError:  # pragma: no cover - threadpoolctl is a dependency
        logger.debug("threadpoolctl is not installed: BLAS threads are left as they are")
        return None
    if _controller is None or len(sys.modules) != _modules_seen:
        _controller = ThreadpoolController()
        _modules_seen = len(sys.modules)
    return _controller


class _BlasLimit(contextlib.ContextDecorator):
    """Limit BLAS threads from the outermost ``__enter__`` to the matching ``__exit__``."""

    def __enter__(self) -> _BlasLimit:
        global _depth, _limiter
        with _lock:
            if _depth == 0:
                _limiter = _start()
            _depth += 1
        return self

    def __exit__(self, *exc: object) -> None:
        global _depth, _limiter
        with _lock:
            _depth -= 1
            if _depth == 0 and _limiter is not None:
                _limiter.restore_original_limits()
                _limiter = None


def limit_blas_threads() -> contextlib.AbstractContextManager[Any]:
    """Context manager (and decorator) that limits BLAS threads while it is active.

    Returns
    -------
    contextlib.ContextDecorator
        ``with limit_blas_threads(): ...`` or ``@limit_blas_threads()``.

    Raises
    ------
    ValueError
        ``IMPACTCONT_BLAS_THREADS`` is neither a positive integer nor ``none``.
    """
    return _BlasLimit()


def blas_limited(func: _F) -> _F:
    """Decorator: run ``func`` with BLAS limited to :func:`blas_thread_limit` threads.

    Parameters
    ----------
    func : callable
        A public entry point that runs for milliseconds or more.

    Returns
    -------
    callable
        ``func`` wrapped; its name, docstring and signature are kept.
    """

    @functools.wraps(func)
    def wrapper(*args: Any, **kwargs: Any) -> Any:
        with _BlasLimit():
            return func(*args, **kwargs)

    return wrapper  # type: ignore[return-value]
