"""A study's own module (``studies/<study>/<file>``) imported for the tests that use it."""

from __future__ import annotations

import contextlib
import importlib.util
import sys
from collections.abc import Iterator
from pathlib import Path
from types import ModuleType

STUDIES = Path(__file__).resolve().parents[1] / "studies"


@contextlib.contextmanager
def study_file(study: str, file: str) -> Iterator[ModuleType]:
    """``studies/<study>/<file>`` as a module of its own while the block runs (registered
    in ``sys.modules`` under a name of its own: dataclasses look their module up by name)."""
    spec = importlib.util.spec_from_file_location(f"{study}_{Path(file).stem}_for_tests",
                                                  STUDIES / study / file)
    module = importlib.util.module_from_spec(spec)
    sys.modules[spec.name] = module
    try:
        spec.loader.exec_module(module)
        yield module
    finally:
        sys.modules.pop(spec.name, None)
