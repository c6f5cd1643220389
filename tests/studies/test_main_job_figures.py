"""The main job's bifurcation diagrams (``studies/main_job``) at one and two journal columns.

The branches are those of ``studies/main_job/scene.toml``, computed by the scene's own
section (as ``impactcont run`` does, in a few seconds) and drawn by the scene's own plot
kind at 3.5 and 7 in. At b = 0.5 the N = 2 isola has a fold and a grazing about 10 pt
apart in the zoomed inset at 7 in; their labels were written side by side (``SN GR``,
read as one name). The figures of orbits and robust stability are checked in
``tests/integration/test_figures_layout.py``.
"""

from __future__ import annotations

import dataclasses

import pytest

from impactcont.scene.plugins import plot_kinds, scene_sections
from impactcont.scene.schema import load_scene
from impactcont.scene.sections import RunContext
from tests._layout_checks import check_layout, labels_side_by_side
from tests.studies._figure_study import ROOT, WIDTHS

SCENE = ROOT / "studies" / "main_job" / "scene.toml"


@pytest.fixture(scope="module")
def scene():
    return load_scene(SCENE)


@pytest.fixture(scope="module")
def branches(scene) -> dict:
    """Every ``[[branches]]`` entry of the main job, computed by the scene's section."""
    section = scene_sections()["branches"]
    out: dict = {}
    for entry in scene.sections["branches"]:
        out[entry.name] = section.compute(entry, RunContext({"branches": dict(out)}))
    return out


def _draw(scene, branches, name: str, width: float):
    plot = next(p for p in scene.plots if p.name == name)
    plot = dataclasses.replace(plot, width=width)
    return plot_kinds()[plot.kind].load_draw()({n: branches[n] for n in plot.data}, plot)


@pytest.mark.parametrize("width", WIDTHS)
@pytest.mark.parametrize("name", ["bifurcation_b0", "bifurcation_b0p5"])
def test_main_job_diagram_is_clean(scene, branches, name, width):
    fig = _draw(scene, branches, name, width)
    assert fig.get_size_inches()[0] == pytest.approx(width)
    check_layout(fig)


def test_fold_and_grazing_of_the_isola_are_not_labelled_side_by_side(scene, branches):
    """b = 0.5, 7 in: the N = 2 isola's SN (omega 1.2568) and GR (1.2584), drawn about
    10 pt apart in the inset, get labels that do not read as one (``SN GR``)."""
    fig = _draw(scene, branches, "bifurcation_b0p5", 7.0)
    ds = branches["b0p5_N2"]
    labels = [str(v) for v in ds["special_label"].values]
    omegas = ds["special_omega"].values
    near = sorted(lab for lab, w in zip(labels, omegas, strict=True) if 1.25 < w < 1.265)
    assert near == ["GR", "SN"]  # the two points the test is about are there
    assert labels_side_by_side(fig) == []
