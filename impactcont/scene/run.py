"""Run a scene: compute its sections, write NetCDF, PNG and ``summary.md``.

:func:`run_scene` computes the entries of every section the scene uses, in
registry order (orbits, branches, robust, simulations, then any registered
section), writes each section to ``<section>.nc`` (one group per entry, the
resolved scene in the ``scene`` attribute), draws the ``[[plots]]`` from
those datasets and writes a short Markdown summary of what was found, the
special points first.

A failing entry does not stop the others (unless ``fail_fast``): it is
logged, listed in the summary and in :attr:`RunResult.failures`, and the
files of everything that succeeded are still written. Progress is shown with
a tqdm bar when asked for (and tqdm is installed), else logged on the
``impactcont.progress`` logger.
"""

from __future__ import annotations

import contextlib
import dataclasses
import datetime
import logging
import sys
import time
from collections.abc import Iterator, Sequence
from pathlib import Path
from typing import Any

import xarray as xr

from impactcont.dataset.io import atomic_output, check_output_directory
from impactcont.progress import interruptible
from impactcont.scene.files import output_lock, write_output
from impactcont.scene.plugins import plot_kinds, scene_sections
from impactcont.scene.schema import Scene, load_scene
from impactcont.scene.sections import RunContext
from impactcont.threads import limit_blas_threads
from impactcont.vocabulary import Label

__all__ = ["RunResult", "TaskFailure", "run_scene"]

log = logging.getLogger(__name__)
progress_log = logging.getLogger("impactcont.progress")

SUMMARY_FILE = "summary.md"


@dataclasses.dataclass(frozen=True)
class TaskFailure:
    """An entry or a plot that could not be computed.

    Attributes
    ----------
    section : str
        ``"branches"``, ..., or ``"plots"``.
    name : str
        The entry's name.
    error : str
        ``"ExceptionType: message"``.
    """

    section: str
    name: str
    error: str


@dataclasses.dataclass
class RunResult:
    """What a run computed and wrote.

    Attributes
    ----------
    scene : Scene
    output_dir : pathlib.Path
    files : list of pathlib.Path
        Every file written (NetCDF, PNG, summary), in order.
    datasets : dict of str to dict of str to xarray.Dataset
        ``section -> entry name -> dataset`` of the entries that succeeded.
    special_points : list of dict
        The special points found on the branches (see :mod:`impactcont.scene.tasks`).
    other_points : dict of str to list of dict
        Points found by other sections (e.g. codim-2 points of curves), by section.
    failures : list of TaskFailure
    elapsed : float
        Wall time in seconds.
    """

    scene: Scene
    output_dir: Path
    files: list[Path] = dataclasses.field(default_factory=list)
    datasets: dict[str, dict[str, xr.Dataset]] = dataclasses.field(default_factory=dict)
    special_points: list[dict[str, Any]] = dataclasses.field(default_factory=list)
    other_points: dict[str, list[dict[str, Any]]] = dataclasses.field(default_factory=dict)
    failures: list[TaskFailure] = dataclasses.field(default_factory=list)
    elapsed: float = 0.0

    @property
    def ok(self) -> bool:
        """True when every entry and plot succeeded."""
        return not self.failures


class _Progress:
    """A tqdm bar over the tasks of a run, or progress lines on a logger."""

    def __init__(self, total: int, enabled: bool) -> None:
        self.total = total
        self.count = 0
        self.bar: Any = None
        self._redirect: Any = contextlib.nullcontext()
        if not enabled:
            self.log = False
            return
        try:
            from tqdm import tqdm
            from tqdm.contrib.logging import logging_redirect_tqdm
        except ImportError:
            self.log = True
            progress_log.info("tqdm is not installed: progress is logged instead")
            return
        self.log = False
        self.bar = tqdm(total=total, unit="task", file=sys.stderr, dynamic_ncols=True,
                        leave=True)
        # Log records go through tqdm.write so they do not break the bar.
        self._redirect = logging_redirect_tqdm(loggers=[logging.getLogger("impactcont"),
                                                        logging.root])

    def __enter__(self) -> _Progress:
        self._redirect.__enter__()
        return self

    def __exit__(self, *exc: Any) -> None:
        self._redirect.__exit__(*exc)
        if self.bar is not None:
            self.bar.close()

    @contextlib.contextmanager
    def task(self, label: str) -> Iterator[None]:
        self.count += 1
        if self.bar is not None:
            self.bar.set_description(label)
        elif self.log:
            progress_log.info("[%d/%d] %s", self.count, self.total, label)
        try:
            yield
        finally:
            if self.bar is not None:
                self.bar.update(1)


def _checked(ds: Any, section: str, name: str) -> xr.Dataset:
    """The driver's result, if it is a dataset (a plugin's driver may return anything)."""
    if not isinstance(ds, xr.Dataset):
        raise TypeError(f"the driver of [[{section}]] returned {type(ds).__name__} for entry "
                        f"{name!r}; allowed: an xarray.Dataset")
    return ds


def _error_text(exc: BaseException) -> str:
    return f"{type(exc).__name__}: {exc}"


def run_scene(scene: Scene | str | Path, *, settings: Sequence[str] = (),
              output: str | Path | None = None, progress: bool = False,
              fail_fast: bool = False) -> RunResult:
    """Compute a scene and write its outputs.

    Parameters
    ----------
    scene : Scene, str or pathlib.Path
        A validated scene, or the path of a TOML scene file.
    settings : sequence of str
        ``key.path=value`` overrides, for a scene given as a path.
    output : str or pathlib.Path, optional
        Output directory, for a scene given as a path (default: the scene's).
    progress : bool
        Show a progress bar (tqdm) on stderr; without tqdm, log progress.
    fail_fast : bool
        Re-raise the first failure instead of going on with the other entries.

    Returns
    -------
    RunResult

    Raises
    ------
    impactcont.scene.SceneError
        The scene file is malformed.
    NotADirectoryError, PermissionError, OSError
        The output directory cannot be created or written (checked before
        anything is computed).
    impactcont.scene.files.OutputInUseError
        Another scene run writes into the same output directory (the run holds
        :func:`~impactcont.scene.files.output_lock` on it until it ends).
    """
    if not isinstance(scene, Scene):
        scene = load_scene(scene, settings=settings, output=output)
    elif settings or output is not None:
        raise TypeError("settings and output apply to a scene file; pass a path, or use "
                        "load_scene(path, settings=..., output=...)")
    t0 = time.perf_counter()
    out_dir = check_output_directory(scene.output_dir, create=True)  # before any computing
    with output_lock(out_dir):  # one run per folder: two would mix their files
        return _run(scene, out_dir, t0, progress=progress, fail_fast=fail_fast)


def _run(scene: Scene, out_dir: Path, t0: float, *, progress: bool, fail_fast: bool
         ) -> RunResult:
    """The body of :func:`run_scene`, with the output folder held."""
    result = RunResult(scene=scene, output_dir=out_dir)
    sections = scene_sections()
    used = {key: entries for key, entries in scene.sections.items() if entries}
    total = sum(len(e) for e in used.values()) + len(scene.plots)
    scene_json = scene.to_json()
    scene_file = str(scene.source) if scene.source else ""
    log.info("scene %r: %d task(s), output in %s", scene.title, total, out_dir)

    stopped = None  # Ctrl-C taken by an entry's driver, which returned what it computed
    with (limit_blas_threads(), interruptible(f"scene {scene.title!r}") as call,
          _Progress(total, progress) as bar):
        for key, entries in used.items():
            section = sections[key]
            datasets: dict[str, xr.Dataset] = {}
            for entry in entries:
                with bar.task(f"{key} {entry.name}"):
                    try:
                        context = RunContext({**result.datasets, key: dict(datasets)})
                        datasets[entry.name] = _checked(section.compute(entry, context), key,
                                                        entry.name)
                    except Exception as exc:
                        if fail_fast:
                            raise
                        log.error("%s %s failed: %s", key, entry.name, _error_text(exc),
                                  exc_info=log.isEnabledFor(logging.DEBUG))
                        result.failures.append(TaskFailure(key, entry.name, _error_text(exc)))
                if call.interrupted or (entry.name in datasets
                                        and datasets[entry.name].attrs.get("interrupted")):
                    stopped = f"{key} {entry.name}"
                    break
            if datasets:
                path = write_output(out_dir / f"{key}.nc", key, datasets,
                                    title=f"{section.title} of scene {scene.title!r}",
                                    scene_json=scene_json, scene_file=scene_file)
                result.files.append(path)
                result.datasets[key] = datasets
                points = section.find_points(datasets)
                if key in ("branches", "switches", "multi_impact"):
                    result.special_points += points
                elif points:
                    result.other_points[key] = points
            if stopped is not None:  # the files written are kept, the rest is not computed
                raise KeyboardInterrupt(f"scene interrupted by the user in {stopped}; the "
                                        f"files written are kept: {result.files}")

        kinds = plot_kinds()
        for plot in scene.plots:
            with bar.task(f"plot {plot.name}"):
                kind = kinds[plot.kind]
                available = {name: ds for s in kind.sections
                             for name, ds in result.datasets.get(s, {}).items()}
                missing = [n for n in plot.data if n not in available]
                if missing:
                    result.failures.append(TaskFailure(
                        "plots", plot.name, f"not drawn: entries {missing} failed"))
                    log.error("plot %s not drawn: entries %s failed", plot.name, missing)
                    continue
                try:
                    from impactcont.scene.figures import save_figure

                    fig = kind.load_draw()({n: available[n] for n in plot.data}, plot)
                    result.files.append(save_figure(fig, out_dir / plot.filename,
                                                    scene.output.dpi))
                except Exception as exc:
                    if fail_fast:
                        raise
                    log.error("plot %s failed: %s", plot.name, _error_text(exc),
                              exc_info=log.isEnabledFor(logging.DEBUG))
                    result.failures.append(TaskFailure("plots", plot.name, _error_text(exc)))

    result.elapsed = time.perf_counter() - t0
    if scene.output.summary:
        path = out_dir / SUMMARY_FILE
        text = summary_markdown(result)
        with atomic_output(path) as tmp:
            tmp.write_text(text, encoding="utf-8")
        result.files.append(path)
    log.info("scene %r done in %.1f s: %d file(s), %d failure(s)", scene.title,
             result.elapsed, len(result.files), len(result.failures))
    return result


#: The kinds the summary's sentence on special points names in any case; the others
#: (BP, SE, RG, SO) are named, in their words, where a branch has one.
_NAMED = (Label.SN, Label.PD, Label.NS, Label.GR, Label.ZV)


def summary_markdown(result: RunResult) -> str:
    """The ``summary.md`` of a run: special points first, then one table per section."""
    from impactcont import __version__
    from impactcont.scene.tasks import points_table, special_points_table

    scene = result.scene
    sections = scene_sections()
    stamp = datetime.datetime.now(datetime.timezone.utc).strftime("%Y-%m-%d %H:%M UTC")
    source = f"`{scene.source}`" if scene.source else "a scene"
    lines = [f"# {scene.title}", ""]
    if scene.description:
        lines += [scene.description.strip(), ""]
    lines += [f"Computed from {source} by impactcont {__version__} on {stamp} in "
              f"{result.elapsed:.1f} s.", ""]
    if any(scene.entries(k) for k in ("branches", "switches", "multi_impact")):
        lines += ["## Special points", ""]
        if result.special_points:
            more = "".join(f", {kind} {kind.words}" for kind in Label
                           if kind not in _NAMED and any(str(p["label"]) == kind
                                                         for p in result.special_points))
            lines += ["SN saddle-node, PD period-doubling, NS Neimark-Sacker, GR grazing, "
                      f"ZV zero-velocity impact{more}; `located` points are refined to "
                      "`precision` "
                      "in the continued parameter; `physical` tells whether the nearest "
                      "accepted point of the branch is a physical motion (eq. 16), and the "
                      "last column why not. rho(G) of a ZV point is unbounded: G (eq. 25) "
                      "divides by the impact velocity, which is 0 there.", ""]
            lines += special_points_table(result.special_points)
        else:
            lines.append("No special point was found on the branches.")
        lines.append("")
    for key, points in result.other_points.items():
        lines += [f"## Special points of the {sections[key].title.lower()}", ""]
        lines += points_table(points)
        lines.append("")
    for key, datasets in result.datasets.items():
        lines += [f"## {sections[key].title}", ""]
        lines += sections[key].describe_datasets(datasets)
        lines.append("")
    if result.failures:
        lines += ["## Failures", ""]
        lines += [f"- {f.section} `{f.name}`: {f.error}" for f in result.failures]
        lines.append("")
    lines += ["## Files", ""]
    for path in result.files:
        lines.append(f"- `{path.name}`")
    lines.append(f"- `{SUMMARY_FILE}` (this file)")
    lines += ["", "Inspect a file with `impactcont info FILE.nc`; draw one with "
              "`impactcont plot FILE.nc`.", ""]
    return "\n".join(lines)
