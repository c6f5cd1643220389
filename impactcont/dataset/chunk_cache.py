"""The chunk cache of the NetCDF-C library while large chunked files are written or read.

NetCDF-C gives every variable of a file it opens its own chunk cache, by default
64 MiB: a map of a dozen variables written or read chunk by chunk holds up to
0.8 GB of chunks the cache keeps although each is written, or read, once.
:func:`chunk_cache` sets the size the library gives the variables of the files
opened while it is active; the setting is process-wide, so it is taken by the
first of concurrent users and the previous one is put back when the last leaves.
"""

from __future__ import annotations

import contextlib
import threading
from collections.abc import Iterator

__all__ = ["MAP_CHUNK_CACHE", "chunk_cache"]

#: Bytes of chunk cache per variable for files written or read chunk by chunk (0: none;
#: a chunk written whole goes through compression straight to the file).
MAP_CHUNK_CACHE = 0

_lock = threading.Lock()
_users = 0
_previous: tuple[int, int, float] | None = None


@contextlib.contextmanager
def chunk_cache(nbytes: int = MAP_CHUNK_CACHE) -> Iterator[None]:
    """Give the variables of the NetCDF files opened in the body ``nbytes`` of chunk cache each.

    Parameters
    ----------
    nbytes : int
        Cache per variable, in bytes (``>= 0``).

    Raises
    ------
    ValueError
        ``nbytes`` is not an integer ``>= 0``.
    """
    if isinstance(nbytes, bool) or not isinstance(nbytes, int) or nbytes < 0:
        raise ValueError(f"nbytes must be an integer >= 0; got {nbytes!r}")
    import netCDF4

    global _users, _previous
    with _lock:
        if _users == 0:
            _previous = netCDF4.get_chunk_cache()
            netCDF4.set_chunk_cache(size=nbytes)
        _users += 1
    try:
        yield
    finally:
        with _lock:
            _users -= 1
            if _users == 0 and _previous is not None:
                size, nelems, preemption = _previous
                netCDF4.set_chunk_cache(size=size, nelems=nelems, preemption=preemption)
                _previous = None
