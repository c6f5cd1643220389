"""Import a study's ``run.py`` for its figure functions (shared by the study figure tests).

``IMPACTCONT_STUDY_ROOT`` (a directory holding ``<study>/run.py``) imports the studies from
elsewhere: to run a figure test against another version of a study's figure code (e.g.
the one before a fix, to see the test fail on it).
"""

from __future__ import annotations

import importlib.util
import os
import sys
from pathlib import Path
from types import ModuleType

ROOT = Path(__file__).resolve().parents[2]
#: The widths a journal prints a figure at: one column, two columns (inches).
WIDTHS = (3.5, 7.0)


def study_module(name: str, *, figures: bool = True) -> ModuleType:
    """Import ``studies/<name>/run.py`` as a module of its own (its helpers not shared).

    ``figures=True``: the one whose figures are tested (``IMPACTCONT_STUDY_ROOT`` if set);
    ``False``: this tree's, which computes the data.
    """
    root = Path(os.environ.get("IMPACTCONT_STUDY_ROOT", ROOT / "studies")) if figures \
        else ROOT / "studies"
    here = root / name
    tag = "figures" if figures else "data"
    spec = importlib.util.spec_from_file_location(f"{name}_run_for_{tag}", here / "run.py")
    module = importlib.util.module_from_spec(spec)
    saved = {k: sys.modules.pop(k) for k in ("closed_form",) if k in sys.modules}
    sys.modules[spec.name] = module  # dataclasses and worker processes look it up by name
    try:
        spec.loader.exec_module(module)
    finally:
        sys.modules.pop("closed_form", None)
        sys.modules.update(saved)
    return module
