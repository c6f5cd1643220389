"""Every committed figure of the studies and the docs fits a journal's double column.

A journal's double column is 7.2 in (Elsevier 190 mm, Springer 174 mm, AIP 7 in); a PNG
wider than that at the dpi it stores is scaled down in print and its 8-9 pt text becomes
unreadable (issue 31). The width is read from the PNG's pixel size and its ``pHYs`` dpi.
"""

from __future__ import annotations

from pathlib import Path

import pytest
from PIL import Image

ROOT = Path(__file__).resolve().parents[2]
FIGURES = sorted([*ROOT.glob("studies/*/figures/*.png"), *ROOT.glob("docs/figures/*.png")])
DOUBLE_COLUMN = 7.2  # inches


def _size_inches(path: Path) -> tuple[float, float]:
    with Image.open(path) as im:
        dpi = im.info.get("dpi")
        if not dpi or not dpi[0]:
            raise AssertionError(f"{path.relative_to(ROOT)} stores no dpi (pHYs chunk)")
        return im.size[0] / float(dpi[0]), im.size[1] / float(dpi[1])


def test_there_are_committed_figures():
    assert len(FIGURES) >= 20


#: Drawn by the new figure code but not redrawn yet from a full run (strict: a redrawn
#: figure that fits must leave this set).
NOT_REDRAWN: set[str] = set()


def _marked(path: Path):
    name = str(path.relative_to(ROOT))
    if name in NOT_REDRAWN:
        return pytest.param(path, id=name, marks=pytest.mark.xfail(
            strict=True, reason="not redrawn yet: needs a full run of a timing study on a "
                                "quiet machine"))
    return pytest.param(path, id=name)


@pytest.mark.parametrize("path", [_marked(p) for p in FIGURES])
def test_committed_figure_fits_a_double_column(path):
    width, height = _size_inches(path)
    assert width <= DOUBLE_COLUMN + 1e-6, (
        f"{path.relative_to(ROOT)} is {width:.2f} x {height:.2f} in, wider than a "
        f"double column ({DOUBLE_COLUMN} in)")
    assert height <= 9.5 + 1e-6, (
        f"{path.relative_to(ROOT)} is {height:.2f} in high, more than a journal page's "
        f"text height (9.5 in)")
