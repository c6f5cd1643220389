"""The NetCDF files a scene run writes, and reading them back.

Every section of a scene is written to ``<section>.nc``: a DataTree with one
group per entry (named after the entry) and, in the root group, an index of
the groups (see :func:`impactcont.dataset.save`). The root attributes:

``title``, ``impactcont_kind`` (the section, e.g. ``"branches"``),
``impactcont_version``, ``Conventions``, ``history``, ``scene`` (the
resolved scene as JSON: defaults filled in, ``--set`` overrides applied) and
``scene_file``.

Every file reads back with :func:`impactcont.load` (a DataTree of the
entries), with :func:`read_output` (the entries by name, and the section),
or with plain ``xarray.open_datatree(path)`` (``docs/outputs.md``).
"""

from __future__ import annotations

import contextlib
import datetime
import logging
import os
from collections.abc import Iterator, Mapping
from pathlib import Path
from typing import Any

import xarray as xr

from impactcont.dataset import load, save
from impactcont.dataset.io import SECTION_ATTRIBUTE
from impactcont.dataset.maps import MULTI_MAP_KIND
from impactcont.dataset.schema import CONVENTIONS, validate_branch_dataset

try:  # POSIX; elsewhere a run takes no lock (logged)
    import fcntl
except ImportError:  # pragma: no cover - Windows
    fcntl = None  # type: ignore[assignment]

__all__ = ["KIND_ATTRIBUTE", "LOCK_FILE", "OutputInUseError", "SceneOutput", "output_lock",
           "read_output", "write_output"]

log = logging.getLogger(__name__)

#: Root attribute naming the section a file holds.
KIND_ATTRIBUTE = SECTION_ATTRIBUTE

#: The lock file a scene run holds in its output folder (removed when the run ends).
LOCK_FILE = ".impactcont-run.lock"


class OutputInUseError(BlockingIOError):
    """Another scene run holds the output folder (:func:`output_lock`)."""


def _holder(fd: int) -> str:
    """The pid the holder of the lock file wrote into it, as text."""
    try:
        text = os.pread(fd, 64, 0).decode("ascii", "replace").strip()
    except OSError:
        text = ""
    return f"pid {text}" if text.isdigit() else "pid unknown"


@contextlib.contextmanager
def output_lock(directory: str | os.PathLike) -> Iterator[Path]:
    """Hold an exclusive lock on a scene run's output folder while the run writes into it.

    Two runs into one folder would mix their files (a ``branches.nc`` of one beside the
    ``summary.md`` of the other). The lock is ``fcntl.flock`` on :data:`LOCK_FILE` inside
    the folder, taken without waiting; the file holds the run's pid and is removed when
    the run ends (the operating system releases the lock of a killed run, and the next
    run takes the file over).

    Parameters
    ----------
    directory : str or os.PathLike
        The output folder (it must exist).

    Yields
    ------
    pathlib.Path
        The lock file.

    Raises
    ------
    OutputInUseError
        Another process holds the folder; the message names the folder and that run's pid.
    """
    path = Path(directory) / LOCK_FILE
    if fcntl is None:  # pragma: no cover - Windows
        log.debug("no fcntl: the output folder %s is not locked", directory)
        yield path
        return
    while True:
        fd = os.open(path, os.O_RDWR | os.O_CREAT, 0o644)
        try:
            fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except BlockingIOError:
            holder = _holder(fd)
            os.close(fd)
            raise OutputInUseError(
                f"output folder {str(directory)!r} is in use by another scene run ({holder}, "
                f"lock file {str(path)!r}): two runs into one folder would mix their files; "
                "wait for that run to end, or give another output folder") from None
        except BaseException:
            os.close(fd)
            raise
        # the previous holder may have removed the file between our open and our lock:
        # then we hold a lock on a file nobody else sees; take the one at the path again
        try:
            same = os.path.samestat(os.fstat(fd), os.stat(path))
        except FileNotFoundError:
            same = False
        if same:
            break
        os.close(fd)
    try:
        os.ftruncate(fd, 0)
        os.pwrite(fd, f"{os.getpid()}\n".encode("ascii"), 0)
        yield path
    finally:
        with contextlib.suppress(OSError):
            path.unlink()  # before the unlock: a waiting run then sees the file gone
        os.close(fd)  # releases the lock


def _version() -> str:
    from impactcont import __version__

    return __version__


def write_output(path: str | os.PathLike, kind: str, datasets: Mapping[str, xr.Dataset], *,
                 title: str, scene_json: str = "", scene_file: str = "") -> Path:
    """Write the datasets of one section to a NetCDF file, one group per entry, atomically.

    Parameters
    ----------
    path : str or os.PathLike
        Target file (its directory must exist).
    kind : str
        The section (stored in the ``impactcont_kind`` attribute).
    datasets : mapping of str to xarray.Dataset
        ``entry name -> dataset``.
    title : str
        Title of the file.
    scene_json, scene_file : str
        The resolved scene as JSON and the scene file it came from.

    Returns
    -------
    pathlib.Path
    """
    stamp = datetime.datetime.now(datetime.timezone.utc).isoformat(timespec="seconds")
    root = xr.Dataset(attrs={
        "title": title, KIND_ATTRIBUTE: kind, "impactcont_version": _version(),
        "Conventions": CONVENTIONS, "history": f"{stamp} written by impactcont run",
        "scene": scene_json, "scene_file": scene_file})
    tree = xr.DataTree.from_dict({"/": root, **{f"/{k}": v for k, v in datasets.items()}})
    # branches, curves and maps are checked against their schema; the other
    # sections have their own layouts (see impactcont.scene.tasks)
    return save(tree, path)


class SceneOutput:
    """A file read by :func:`read_output`.

    Attributes
    ----------
    path : pathlib.Path
    kind : str
        The section: ``"branches"``, ``"orbits"``, ... (``"branches"`` for a
        file of :func:`impactcont.save`).
    attrs : dict
        Root attributes.
    datasets : dict of str to xarray.Dataset
        ``entry name -> dataset``, in file order.
    """

    def __init__(self, path: Path, kind: str, attrs: dict[str, Any],
                 datasets: dict[str, xr.Dataset]) -> None:
        self.path = path
        self.kind = kind
        self.attrs = attrs
        self.datasets = datasets

    def __repr__(self) -> str:
        return f"SceneOutput({str(self.path)!r}, kind={self.kind!r}, " \
               f"entries={list(self.datasets)})"


_KIND_NAMES = {None: "branch"}  # the tag of a dataset without one (a branch)


def read_output(path: str | os.PathLike) -> SceneOutput:
    """Read a file written by a scene run (or by :func:`impactcont.save`).

    Raises
    ------
    FileNotFoundError
        ``path`` does not exist.
    ValueError
        ``path`` is not a NetCDF file of impactcont.
    """
    p = Path(path)
    data = load(p)  # a file whose variables were edited is refused by name, not a KeyError
    if isinstance(data, xr.Dataset):
        attrs = dict(data.attrs)
        datasets = {p.stem: data}
    else:
        attrs = dict(data.attrs)
        datasets = {node.name or p.stem: node.to_dataset(inherit=False)
                    for node in data.subtree if node.has_data}
    kind = attrs.get(KIND_ATTRIBUTE)
    if kind is None:
        # a file of impactcont.save: two-parameter datasets and simulations say what they are
        tags = {ds.attrs.get("impactcont_dataset") for ds in datasets.values()}
        kind = ("maps" if tags and tags <= {"map", MULTI_MAP_KIND}  # (a scene's maps hold both)
                else {frozenset({"curve"}): "curves",
                      frozenset({"simulation"}): "simulations"}.get(frozenset(tags)))
        if kind is None and len(tags) > 1:
            raise ValueError(f"{str(path)!r} holds datasets of several kinds "
                             f"({', '.join(sorted(_KIND_NAMES.get(t, t) for t in tags))}): "
                             f"impactcont info and plot read files of one kind (a scene's "
                             f"section); save each kind to a file of its own")
    if kind is None:
        try:
            for ds in datasets.values():
                validate_branch_dataset(ds)
        except ValueError as exc:
            raise ValueError(f"{str(path)!r} is not a file written by impactcont "
                             f"(no {KIND_ATTRIBUTE!r} attribute, and {exc})") from None
        kind = "branches"
    if not datasets and kind == "branches":
        raise ValueError(f"{str(path)!r} holds no data")
    return SceneOutput(p, str(kind), attrs, datasets)
