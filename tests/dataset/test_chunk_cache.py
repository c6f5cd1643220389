"""The NetCDF chunk cache while maps are written or read (:mod:`impactcont.dataset.chunk_cache`):
set for the files opened in the body, put back when the last user leaves, refused when not a
byte count."""

from __future__ import annotations

import threading

import netCDF4
import pytest

from impactcont.dataset.chunk_cache import MAP_CHUNK_CACHE, chunk_cache


def test_the_cache_is_set_in_the_body_and_put_back_after() -> None:
    before = netCDF4.get_chunk_cache()
    with chunk_cache(12345):
        assert netCDF4.get_chunk_cache()[0] == 12345
    assert netCDF4.get_chunk_cache() == before
    with chunk_cache():
        assert netCDF4.get_chunk_cache()[0] == MAP_CHUNK_CACHE == 0
    assert netCDF4.get_chunk_cache() == before


def test_the_cache_is_put_back_when_the_body_raises() -> None:
    before = netCDF4.get_chunk_cache()
    with pytest.raises(RuntimeError, match="inside"), chunk_cache(4096):
        raise RuntimeError("inside")
    assert netCDF4.get_chunk_cache() == before


def test_the_first_of_concurrent_users_sets_it_and_the_last_puts_it_back() -> None:
    before = netCDF4.get_chunk_cache()
    inside, leave = threading.Event(), threading.Event()
    seen = []

    def other() -> None:
        with chunk_cache(999):
            inside.set()
            leave.wait(10)

    thread = threading.Thread(target=other)
    thread.start()
    assert inside.wait(10)
    with chunk_cache(5):  # a second user: the first one's setting holds
        seen.append(netCDF4.get_chunk_cache()[0])
    seen.append(netCDF4.get_chunk_cache()[0])  # the first user is still inside
    leave.set()
    thread.join(10)
    assert seen == [999, 999]
    assert netCDF4.get_chunk_cache() == before


@pytest.mark.parametrize("nbytes", [-1, 1.5, True, "64", None])
def test_a_size_that_is_no_byte_count_is_refused(nbytes) -> None:
    before = netCDF4.get_chunk_cache()
    with pytest.raises(ValueError, match=rf"nbytes must be an integer >= 0; got {nbytes!r}"), \
            chunk_cache(nbytes):
        pass
    assert netCDF4.get_chunk_cache() == before
