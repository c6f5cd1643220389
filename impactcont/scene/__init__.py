"""Scenes: a study described in a TOML file, computed and written by one call.

>>> from impactcont.scene import load_scene, run_scene  # doctest: +SKIP
>>> result = run_scene("studies/main_job/scene.toml", output="output/main_job")  # doctest: +SKIP

The format is in ``docs/scenes.md``; :mod:`impactcont.scene.schema` validates
it, :mod:`impactcont.scene.run` computes it, :mod:`impactcont.scene.files`
reads the NetCDF files back. Sections and plot kinds come from the one
problem registry, :mod:`impactcont.scene.plugins` (the built-in ones are
in :mod:`impactcont.scene.sections`; other packages add theirs through the
entry-point group ``impactcont.problems``, ``docs/plugins.md``).
"""

from __future__ import annotations

from impactcont.scene.files import SceneOutput, read_output, write_output
from impactcont.scene.run import RunResult, TaskFailure, run_scene
from impactcont.scene.schema import Scene, SceneError, apply_settings, load_scene, parse_scene
from impactcont.scene.sections import (
    PlotKind,
    RunContext,
    SceneSection,
    plot_kinds,
    register_section,
    scene_sections,
)

__all__ = [
    "PlotKind",
    "RunContext",
    "RunResult",
    "Scene",
    "SceneError",
    "SceneOutput",
    "SceneSection",
    "TaskFailure",
    "apply_settings",
    "load_scene",
    "parse_scene",
    "plot_kinds",
    "read_output",
    "register_section",
    "run_scene",
    "scene_sections",
    "write_output",
]
