"""The two ways the kernel compiles (:mod:`impactcont.kernel.jit`).

The options are read from the dispatchers (``targetoptions``, the cache object); an
``inner`` function is never called from Python here (it has no CPython wrapper: the call
would crash the interpreter), only through an ``entry`` that calls it. The on-disk cache is
checked against the sources of the whole kernel directory: numba inlines one module's
compiled helpers into another's machine code.
"""

from __future__ import annotations

import importlib
import math
import os
import pickle
import pkgutil
import subprocess
import sys
from pathlib import Path

import numba as nb
import numpy as np
import pytest
from numba.core.caching import FunctionCache
from numba.core.registry import CPUDispatcher

import impactcont.kernel
import impactcont.orbit
from impactcont.kernel import jit, shooting


@jit.inner
def _twice(x):
    return 2.0 * x


@jit.entry
def _calls_inner(x):
    return _twice(x) + 1.0


@jit.entry
def _divide(x, y):
    return x / y


def test_entry_is_cached_nogil_with_numpy_errors_and_no_cfunc_wrapper():
    opts = _divide.targetoptions
    assert opts["nogil"] is True
    assert opts["error_model"] == "numpy"
    assert opts["no_cfunc_wrapper"] is True
    assert not opts.get("no_cpython_wrapper", False)
    assert isinstance(_divide._cache, FunctionCache)  # cache=True: on disk, not NullCache


def test_inner_has_no_cpython_wrapper_and_the_entry_options():
    opts = _twice.targetoptions
    assert opts["no_cpython_wrapper"] is True
    assert opts["nogil"] is True and opts["error_model"] == "numpy"
    assert isinstance(_twice._cache, FunctionCache)


def test_an_entry_calls_an_inner_function():
    assert _calls_inner(1.5) == 4.0


def test_error_model_numpy_divides_by_zero_to_inf():
    """``error_model="numpy"``: no ZeroDivisionError as under Python's model."""
    assert _divide(1.0, 0.0) == math.inf
    assert math.isnan(_divide(0.0, 0.0))


def _negate(x):
    return -x


def test_typed_entry_compiles_eagerly_for_its_signature():
    typed = jit.typed_entry("float64(float64)")(_negate)
    assert typed.signatures == [(nb.float64,)]  # compiled at decoration, before any call
    assert typed.targetoptions["nogil"] is True
    assert typed.targetoptions["error_model"] == "numpy"
    assert isinstance(typed._cache, FunctionCache)
    assert typed(3.0) == -3.0


def _dispatchers():
    """Every compiled function of the kernel and orbit packages, with its module."""
    for package in (impactcont.kernel, impactcont.orbit):
        for info in pkgutil.iter_modules(package.__path__):
            module = importlib.import_module(f"{package.__name__}.{info.name}")
            for name, value in vars(module).items():
                if isinstance(value, CPUDispatcher) and value.__module__ == module.__name__:
                    yield module.__name__, name, value


def test_only_private_names_lack_the_cpython_wrapper():
    """A function without a CPython wrapper must not be callable from Python by name: its
    name starts with an underscore. Every compiled function of the kernel is cached."""
    found = list(_dispatchers())
    assert len(found) > 20  # the kernel's functions were seen
    for module, name, disp in found:
        if disp.targetoptions.get("no_cpython_wrapper"):
            assert name.startswith("_"), f"{module}.{name} has no CPython wrapper"
        assert isinstance(disp._cache, FunctionCache), f"{module}.{name} is not cached"
        assert disp.targetoptions["nogil"] is True, f"{module}.{name} holds the GIL"


@pytest.mark.parametrize("value", [np.float64(2.0), 2])
def test_entry_accepts_what_numba_types(value):
    assert _calls_inner(value) == 5.0

_CALLER = """\
from kern.helper import _value
from impactcont.kernel.jit import entry

@entry
def value(x):
    return _value(x)
"""

_HELPER = """\
from impactcont.kernel.jit import inner

@inner
def _value(x):
    return x + {0}
"""


def _run(root: Path) -> float:
    env = {**os.environ, "PYTHONPATH": os.pathsep.join([str(root), *sys.path])}
    env.pop("NUMBA_CACHE_DIR", None)
    code = "from kern.caller import value; print(value(1.0))"
    out = subprocess.run([sys.executable, "-c", code], env=env, capture_output=True,
                         text=True, check=True, timeout=300)
    return float(out.stdout.split()[-1])


def _cached_package(root: Path) -> Path:
    """The package ``kern`` (a caller and its helper) under `root`, run once: compiled and
    cached on disk with the helper adding 1."""
    package = root / "kern"
    package.mkdir()
    (package / "__init__.py").write_text("")
    (package / "caller.py").write_text(_CALLER)
    (package / "helper.py").write_text(_HELPER.format("1.0"))
    assert _run(root) == 2.0
    return package


def test_an_edit_of_a_helper_module_compiles_its_callers_again(tmp_path):
    package = _cached_package(tmp_path)
    assert list((package / "__pycache__").glob("caller.value-*.nbi"))  # cached on disk
    (package / "helper.py").write_text(_HELPER.format("10.0"))
    assert _run(tmp_path) == 11.0  # numba's own stamp (caller.py unchanged) loads 2.0


def test_an_index_with_types_an_earlier_source_had_is_obsolete(tmp_path):
    """An index pickled with a class since removed from the kernel raised AttributeError."""
    package = _cached_package(tmp_path)
    for index in (package / "__pycache__").glob("*.nbi"):
        with open(index, "rb") as f:
            version = pickle.load(f)
        with open(index, "wb") as f:
            pickle.dump(version, f)
            f.write(b"ckern.helper\nRemovedRecord\n.")  # a class the source no longer has
    assert _run(tmp_path) == 2.0


def test_the_stamp_covers_every_module_of_the_directory(tmp_path):
    (tmp_path / "a.py").write_text("x = 1\n")
    (tmp_path / "b.py").write_text("y = 1\n")
    first = jit.source_stamp(tmp_path)
    assert jit.source_stamp(tmp_path) == first
    (tmp_path / "b.py").write_text("y = 2\n")
    assert jit.source_stamp(tmp_path) != first
    (tmp_path / "c.py").write_text("")
    assert len({first, jit.source_stamp(tmp_path)}) == 2


def test_kernel_functions_are_cached_against_the_kernel_directory():
    kernel = Path(shooting.__file__).parent
    for name in ("newton_solve", "palc_correct"):
        locator = getattr(shooting, name)._cache._impl.locator
        assert locator.get_source_stamp() == jit.source_stamp(kernel), name


