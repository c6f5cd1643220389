"""Human-readable descriptions of the files a scene run writes (``impactcont info``)."""

from __future__ import annotations

import json
import os

from impactcont.scene.files import read_output
from impactcont.scene.plugins import scene_sections

__all__ = ["describe_file"]


def describe_file(path: str | os.PathLike) -> str:
    """Describe what a NetCDF file of impactcont holds, in plain text with Markdown tables.

    Parameters
    ----------
    path : str or os.PathLike
        A file written by ``impactcont run`` or :func:`impactcont.save`.

    Returns
    -------
    str
        What the file is (section, entries, provenance, the scene it came
        from), one table describing the entries and, for branches, the
        special points.

    Raises
    ------
    FileNotFoundError, ValueError
        The file does not exist or is not an impactcont NetCDF file.
    """
    from impactcont.scene.tasks import points_table, special_points_table

    out = read_output(path)
    sections = scene_sections()
    section = sections.get(out.kind)
    title = section.title if section else out.kind
    lines = [f"{out.path}: {title.lower()} ({out.kind}), {len(out.datasets)} "
             f"entr{'y' if len(out.datasets) == 1 else 'ies'}"]
    if out.attrs.get("title"):
        lines.append(f"title: {out.attrs['title']}")
    version = out.attrs.get("impactcont_version") or next(
        (ds.attrs.get("impactcont_version") for ds in out.datasets.values()), None)
    history = out.attrs.get("history") or next(
        (ds.attrs.get("history") for ds in out.datasets.values()), None)
    if version or history:
        lines.append(f"written by: impactcont {version or '?'}"
                     + (f"; {history}" if history else ""))
    scene_text = out.attrs.get("scene")
    if scene_text:
        scene = json.loads(scene_text)
        source = out.attrs.get("scene_file") or "?"
        used = [k for k in sections if scene.get(k)]
        lines.append(f"scene: {scene.get('title', '?')!r} from {source} (sections: "
                     f"{', '.join(used)}; plots: {len(scene.get('plots', []))}); the resolved "
                     f"scene is in the 'scene' attribute")
    lines.append("")
    lines.append("groups:")
    for name, ds in out.datasets.items():
        dims = ", ".join(f"{d}={n}" for d, n in ds.sizes.items())
        lines.append(f"  {name}: {dims}; variables: {', '.join(map(str, ds.data_vars))}")
    if section is not None:
        lines += ["", *section.describe_datasets(out.datasets)]
        points = section.find_points(out.datasets)
        if points:
            table = (special_points_table if out.kind in ("branches", "switches", "multi_impact")
                     else points_table)
            lines += ["", "special points:", *table(points)]
    return "\n".join(lines) + "\n"
