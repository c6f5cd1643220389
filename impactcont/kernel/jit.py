"""The two ways the kernel compiles a function (numba, cached on disk per host CPU).

``entry``: a function Python calls. ``inner``: a private helper only compiled code
calls; it gets no CPython wrapper (calling it from Python would crash, so only names
with a leading underscore take it). Neither gets a C-callback wrapper, which the
kernel never uses. The wrappers are about a tenth of what a new install compiles
before the four main verbs have each run once (21.1 -> 19.5 s of CPU,
``studies/performance/first_use.py``).

``error_model="numpy"``: ``x / 0`` gives ``inf`` as in numpy, no exception.
"""

from __future__ import annotations

import numba as nb

__all__ = ["entry", "inner", "typed_entry"]

_OPTIONS = dict(cache=True, nogil=True, error_model="numpy", no_cfunc_wrapper=True)

entry = nb.njit(**_OPTIONS)
inner = nb.njit(no_cpython_wrapper=True, **_OPTIONS)


def typed_entry(signature):
    """``entry`` compiled eagerly for one explicit `signature`."""
    return nb.njit(signature, **_OPTIONS)
