"""NetCDF save and load of impactcont datasets, one or many (DataTree groups).

What is on disk (``docs/outputs.md``) reads with plain xarray, netCDF4 or
``ncdump``, and :func:`load` gives back exactly what :func:`save` was given:

- complex variables (the multipliers) are stored as two float variables
  ``<name>_real`` and ``<name>_imag`` (attributes ``impactcont_complex_part``
  and ``impactcont_complex_variable`` say so) and joined again by :func:`load`;
- a file of several groups has an index in its root group (``group_name``,
  ``group_kind``, ``group_title``, ``group_N`` on the dimension ``group``),
  which :func:`load` drops again;
- booleans are stored by xarray as ``int8`` with a ``dtype: bool`` attribute;
- each dataset is in a CF 1.10 form (``_to_cf``, undone by :func:`load`): text
  coordinates as integer flags, int32 for int64, no units on flags and texts, no
  ``_FillValue`` on coordinates, the parameters of a branch or curve as auxiliary
  coordinates, provenance (``Conventions``, ``history``, ``source``,
  ``references``) in every group, and a root that names its groups and how to
  open them.

:func:`save` and :func:`load` check the same things: always the attributes
impactcont reads back (:mod:`impactcont.dataset.attributes`), and with
``validate`` (the default) the schema of branches, curves and maps. What
``save(..., validate=False)`` wrote, ``load(..., validate=False)`` reads;
``load`` with ``validate`` names what is wrong with it and says so.

Every write goes to a temporary file in the target's directory, moved onto
the target with :func:`os.replace`: a failed or interrupted write leaves the
previous file untouched and no temporary file behind, and a failed one raises an
OSError naming the target and why (ENOSPC, "no space left on the device", when
the disk is full: the NetCDF library says only "HDF error"). Temporary files are
named ``.<target>.<host>-<pid>.<random>.tmp``; one left by a writer that was
killed is removed by the next write to that directory once its process is
gone. Ctrl-C ends a save promptly and never lands inside the NetCDF library
(where it used to deadlock xarray's file manager): a large in-memory dataset
is written by a child process (``fork``) that the interrupted parent kills at
once, and that ends by itself, removing its temporary file, if the parent is
killed (``kill -9`` included); a small one (written in milliseconds), or where
a child cannot be used (dask-backed data, no ``fork``), is written with the
interrupt held until the write is complete.
"""

from __future__ import annotations

import contextlib
import errno
import json
import logging
import os
import pickle
import re
import secrets
import select
import signal
import socket
import sys
import threading
import warnings
from collections.abc import Callable, Iterable, Iterator, Mapping
from pathlib import Path
from typing import Any

import numpy as np
import xarray as xr

# branch, curve or map dataset, by its "impactcont_dataset" attribute (branches have none)
from impactcont.dataset.attributes import (
    SECTION_KINDS,
    check_attributes,
    check_file_attributes,
    dataset_kind,
    dataset_tag,
)
from impactcont.dataset.chunk_cache import chunk_cache
from impactcont.dataset.curves import normalise_dataset, validate_dataset
from impactcont.dataset.schema import (
    _LABEL_DTYPE,
    _STATUS_DTYPE,
    parameter_names,
    provenance_attributes,
    special_variable,
)

__all__ = ["ENGINE", "SECTION_ATTRIBUTE", "atomic_output", "check_output_directory",
           "check_output_file", "load", "open_lazy", "remove_stale_temporaries", "save",
           "save_blocks", "temporary_path"]

logger = logging.getLogger(__name__)

#: The NetCDF engine used for every read and write.
ENGINE = "netcdf4"
#: Root attribute of a scene output naming its section (``"orbits"``, ``"branches"``, ...).
SECTION_ATTRIBUTE = "impactcont_kind"

# Kinds of dataset whose omega and b are scalar coordinates (data variables in older files).
_SCALAR_PARAMETER_KINDS = ("orbits", "robust", "simulation")
# Kinds of dataset validated against a schema by validate_dataset.
_SCHEMA_KINDS = ("branch", "curve", "map", "multi_impact_map")
_PART, _OF = "impactcont_complex_part", "impactcont_complex_variable"
_INDEX = {
    "group_name": ("group name", "Path of the group: xarray.open_dataset(file, group=NAME)."),
    "group_kind": ("group content", "branch, curve, map, orbits, robust or simulation."),
    "group_title": ("group title", "The title attribute of the group."),
    "group_N": ("forcing periods per impact", "N of the group's motions; 0 if it has none."),
}


# ---------------------------------------------------------------------------------------------
# Paths: checks before any work, temporary files
# ---------------------------------------------------------------------------------------------
def _path(path: Any) -> Path:
    if isinstance(path, bytes) or not isinstance(path, (str, os.PathLike)):
        raise TypeError(f"path must be a str or os.PathLike; got {path!r}")
    p = Path(path)
    if str(path) == "" or p.name == "":
        raise ValueError(f"path must name a file; got {path!r}")
    return p


_HOST = re.sub(r"[^A-Za-z0-9]", "", socket.gethostname())[:32] or "host"
_TEMPORARY = re.compile(r"^\.(?P<target>.+)\.(?P<host>[A-Za-z0-9]+)-(?P<pid>[0-9]+)"
                        r"\.[0-9a-f]{8}\.tmp$")


def temporary_path(target: Path) -> Path:
    """A fresh temporary path beside ``target``: ``.<name>.<host>-<pid>.<random>.tmp``.

    The host and process id say who writes it, so that
    :func:`remove_stale_temporaries` can tell a file whose writer was killed.
    """
    return target.parent / f".{target.name}.{_HOST}-{os.getpid()}.{secrets.token_hex(4)}.tmp"


def _running(pid: int) -> bool:
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except OSError:  # e.g. another user's process: it exists
        return True
    return True


def remove_stale_temporaries(directory: str | os.PathLike) -> list[Path]:
    """Remove the temporary files of killed writers from ``directory``.

    Only files named by :func:`temporary_path` on this host whose process no
    longer runs are removed; anything else, and any file that cannot be
    removed, is left alone.

    Parameters
    ----------
    directory : str or os.PathLike

    Returns
    -------
    list of pathlib.Path
        The files removed.
    """
    removed = []
    try:
        entries = list(os.scandir(directory))
    except OSError:
        return removed
    for entry in entries:
        match = _TEMPORARY.match(entry.name)
        if match is None or match["host"] != _HOST:
            continue
        pid = int(match["pid"])
        if pid == os.getpid() or _running(pid):
            continue
        try:
            if entry.is_file(follow_symlinks=False):
                os.unlink(entry.path)
                removed.append(Path(entry.path))
                logger.info("removed %s, left by process %d that no longer runs", entry.path, pid)
        except OSError as exc:
            logger.debug("cannot remove stale temporary file %s: %s", entry.path, exc)
    return removed


def _named(exc: OSError, message: str) -> OSError:
    """``exc``'s type with ``message`` (naming the user's path), keeping its errno."""
    new = type(exc)(message)
    new.errno = exc.errno
    return new


# Errors of a device that has no room left for this user.
_FULL_ERRNOS = frozenset({errno.ENOSPC, getattr(errno, "EDQUOT", errno.ENOSPC)})
# A device with less than this free once a write failed is full: the failed write took the
# rest (what remains is a partly used block, or what another process freed since).
_FULL_BYTES = 2**20
# Attribute of an exception noting _full() as the write failed, before its file was emptied.
_FULL_NOTE = "_impactcont_full"


def _room(directory: Path) -> tuple[int, int | None] | None:
    """``(bytes, inodes)`` this process may still use on the device of ``directory``
    (:func:`os.statvfs`; ``inodes`` None where the file system does not count them), or
    None where that is not known (no ``statvfs``, a file system of no stated size)."""
    try:
        st = os.statvfs(directory)
    except (OSError, AttributeError):  # gone, or no statvfs (Windows)
        return None
    if st.f_blocks == 0:  # /proc, some FUSE file systems: no size at all
        return None
    root = hasattr(os, "geteuid") and os.geteuid() == 0  # root may use the reserved blocks
    free = (st.f_bfree if root else st.f_bavail) * st.f_frsize
    inodes = (st.f_ffree if root else st.f_favail) if st.f_files else None
    return int(free), None if inodes is None else int(inodes)


def _full(directory: Path, below: int = 1) -> str | None:
    """Why the device of ``directory`` counts as full (``"0 bytes free"``, ``"no inode
    free"``) when it has fewer than ``below`` bytes or no inode left; None if it does not
    or cannot be told."""
    room = _room(directory)
    if room is None:
        return None
    free, inodes = room
    if inodes == 0:
        return "no inode (file entry) free"
    if free < below:
        return f"{free} bytes free"
    return None


def _full_text(directory: Path, reason: str, code: int | None) -> str:
    what = ("disk quota exceeded" if code == getattr(errno, "EDQUOT", None)
            else "no space left on the device")
    return f"{what} of directory {str(directory)!r} ({reason})"


def _no_room(message: str) -> OSError:
    """An OSError of errno ENOSPC whose text is ``message`` alone."""
    exc = OSError(message)
    exc.errno = errno.ENOSPC
    return exc


def _check_room(directory: Path, message: str) -> None:
    """OSError (ENOSPC) with ``message`` if the device of ``directory`` is full (no byte or
    no inode free): refused before any work rather than after a failed write."""
    reason = _full(directory)
    if reason is not None:
        raise _no_room(message.format(reason=_full_text(directory, reason, None)))


def _probe(directory: Path, message: str, full: str) -> None:
    """Create and remove a file in ``directory``, and check that its device has room; an
    OSError with ``message`` if the file cannot be made, with ``full`` (ENOSPC) if the
    device is full."""
    probe = temporary_path(directory / "impactcont-write-test")
    try:
        os.close(os.open(probe, os.O_CREAT | os.O_EXCL | os.O_WRONLY, 0o600))
        os.unlink(probe)
    except OSError as exc:
        if exc.errno in _FULL_ERRNOS:
            raise _named(exc, full.format(reason=_full_text(directory, exc.strerror or str(exc),
                                                            exc.errno))) from None
        raise _named(exc, message.format(reason=exc.strerror or exc)) from None
    _check_room(directory, full)


def _descriptors_of(path: Path) -> list[int]:
    """The file descriptors of this process open on the file ``path`` (none where the
    system does not list them: ``/proc/self/fd`` on Linux, ``/dev/fd`` elsewhere)."""
    try:
        st = os.stat(path)
    except OSError:
        return []
    for listing in ("/proc/self/fd", "/dev/fd"):
        try:
            names = os.listdir(listing)
        except OSError:
            continue
        found = []
        for name in names:
            try:
                fd = int(name)
                info = os.fstat(fd)
            except (ValueError, OSError):
                continue
            if (info.st_dev, info.st_ino) == (st.st_dev, st.st_ino):
                found.append(fd)
        return found
    return []


def _release(tmp: Path) -> None:
    """Free the disk space of the temporary file of a failed write still open here.

    When closing a file fails (HDF5 cannot flush its last data to a full disk), the NetCDF
    library keeps it open: removed, it would hold its disk space until the interpreter
    exits. It is emptied (truncated to 0 bytes) first, which frees that space at once.
    The library's descriptor stays open on the empty removed file (closed at exit): taken
    from under it, the file's inode number could be given to a new file, which HDF5 would
    then take for the one it holds open and refuse to create.
    """
    if not _descriptors_of(tmp):
        return
    try:
        os.truncate(tmp, 0)
    except OSError as exc:
        logger.debug("cannot empty %s, which the NetCDF library keeps open: %s", tmp, exc)
    else:
        logger.debug("emptied %s, which the NetCDF library keeps open after a failed write",
                     tmp)


def _write_error(exc: BaseException, shown: str, tmp: Path) -> OSError | None:
    """The error to raise for ``exc``, raised while ``tmp`` was written for the target
    ``shown``; None to raise ``exc`` as it is (not a failure to write: Ctrl-C, a bad value).

    A write fails with an :class:`OSError` or a :class:`RuntimeError` of the NetCDF library
    (``NetCDF: HDF error``, whatever the cause). Either is an OSError naming the target, not
    the temporary file: errno ENOSPC, "no space left on the device", when the device is
    full once it failed (checked before ``tmp`` is removed: a full disk can make the
    library say "Permission denied"); otherwise the OSError's own type and errno, or EIO
    with what the library said. Called before ``tmp`` is removed.
    """
    library = isinstance(exc, RuntimeError) and str(exc).startswith("NetCDF:")
    if not (isinstance(exc, OSError) or library):
        return None
    directory = tmp.parent
    code = exc.errno if isinstance(exc, OSError) else None
    said = (exc.strerror if isinstance(exc, OSError) and exc.strerror else str(exc))
    said = said.replace(str(tmp), shown)
    # the room when the write failed, noted where the file had to be emptied to close
    reason = getattr(exc, _FULL_NOTE) if hasattr(exc, _FULL_NOTE) else _full(directory,
                                                                             _FULL_BYTES)
    if reason is not None or code in _FULL_ERRNOS:
        room = reason if reason is not None else said
        return _no_room(f"cannot write {shown!r}: {_full_text(directory, room, code)}; the "
                        f"write failed with: {said}. Free some space or choose another path "
                        f"(nothing was written: a previous file there is untouched)")
    if library:
        new = OSError(f"cannot write {shown!r} in directory {str(directory)!r}: the NetCDF "
                      f"library failed ({said}); nothing was written (a previous file there "
                      f"is untouched)")
        new.errno = errno.EIO
        return new
    return _named(exc, f"cannot write {shown!r} in directory {str(directory)!r}: {said}")


def check_output_file(path: str | os.PathLike) -> Path:
    """Check, before any work, that a file can be written at ``path``.

    Parameters
    ----------
    path : str or os.PathLike

    Returns
    -------
    pathlib.Path

    Raises
    ------
    ValueError
        ``path`` is a directory.
    FileNotFoundError, NotADirectoryError, PermissionError
        Its directory does not exist, is not a directory or is not writable;
        the message names ``path`` and says what to do.
    OSError
        errno ENOSPC: the device of its directory is full (no byte or no file
        entry free).
    """
    target = _path(path)
    shown = str(path)
    if target.is_dir():
        raise ValueError(f"path must be a file, not a directory; got {shown!r}")
    parent = target.parent
    if not parent.exists():
        raise FileNotFoundError(f"cannot write {shown!r}: directory {str(parent)!r} does not "
                                f"exist; create it first or choose another path")
    if not parent.is_dir():
        raise NotADirectoryError(f"cannot write {shown!r}: {str(parent)!r} is not a directory")
    _probe(parent, f"cannot write {shown!r}: directory {str(parent)!r} is not writable "
                   f"({{reason}}); choose another path or change its permissions",
           f"cannot write {shown!r}: {{reason}}; free some space or choose another path")
    return target


def check_output_directory(directory: str | os.PathLike, *, create: bool = False) -> Path:
    """Check, before any work, that files can be written in ``directory``.

    Parameters
    ----------
    directory : str or os.PathLike
        An existing directory, or one to be created.
    create : bool, optional
        Create it (and its parents) if missing. Without ``create`` nothing is
        left on disk: a missing directory is checked through the nearest
        existing parent.

    Returns
    -------
    pathlib.Path

    Raises
    ------
    NotADirectoryError
        ``directory`` (or a parent) exists and is a file.
    PermissionError, OSError
        It cannot be created or written, or its device is full (errno ENOSPC);
        the message names ``directory`` and says what to do.
    """
    d = Path(directory)
    shown = str(directory)
    if d.exists() and not d.is_dir():
        raise NotADirectoryError(f"output directory {shown!r} is an existing file, not a "
                                 f"directory; choose a directory (it is created if missing)")
    if d.is_dir():
        _probe(d, f"output directory {shown!r} is not writable ({{reason}}); choose another "
                  f"or change its permissions",
               f"output directory {shown!r}: {{reason}}; free some space or choose another")
        return d
    parent = next(p for p in d.absolute().parents if p.exists())
    if not parent.is_dir():
        raise NotADirectoryError(f"output directory {shown!r} cannot be created: "
                                 f"{str(parent)!r} is a file, not a directory")
    message = (f"output directory {shown!r} cannot be created in {str(parent)!r} "
               f"({{reason}}); choose another or change the permissions of {str(parent)!r}")
    if not create:
        _probe(parent, message, f"output directory {shown!r} cannot be created: {{reason}}; "
                                f"free some space or choose another")
        return d
    try:
        d.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise _named(exc, message.format(reason=exc.strerror or exc)) from None
    return check_output_directory(d)


@contextlib.contextmanager
def atomic_output(path: str | os.PathLike) -> Iterator[Path]:
    """Write a file atomically: yield a temporary path, then move it onto ``path``.

    The directory is checked first (:func:`check_output_file`) and cleared of
    stale temporary files. If the body raises (Ctrl-C included), ``path`` is
    left as it was and the temporary file is removed (emptied first where the
    NetCDF library still holds it open: :func:`_release`); an OSError (or an
    error of the NetCDF library) is raised again as an OSError naming ``path``,
    not the temporary file, and saying when the disk is full (errno ENOSPC).
    :func:`save`, :func:`save_blocks` and the scene outputs all write through it.

    Yields
    ------
    pathlib.Path
        Where to write.
    """
    target = check_output_file(path)
    remove_stale_temporaries(target.parent)
    tmp = temporary_path(target)
    try:
        yield tmp
        os.replace(tmp, target)
    except BaseException as exc:
        error = _write_error(exc, str(path), tmp)  # before tmp goes: is the disk full?
        _release(tmp)
        if error is None:
            raise
        raise error from exc
    finally:
        tmp.unlink(missing_ok=True)


# ---------------------------------------------------------------------------------------------
# What is written: groups, the root index, complex variables as real and imaginary parts
# ---------------------------------------------------------------------------------------------
def _check_group_name(name: Any) -> str:
    if not isinstance(name, str) or not name or "/" in name or name in (".", ".."):
        raise ValueError(f"branch names must be non-empty str without '/'; got {name!r}")
    return name


def _check(ds: xr.Dataset, section: Any, validate: bool) -> None:
    """Check the attributes impactcont reads and, with ``validate``, the schema of ``ds``.

    The attributes (:mod:`impactcont.dataset.attributes`) are checked whatever
    ``validate``; the schema of branches (N-1 and N-p), curves and maps only with
    it. Other results (orbits, robust, simulations, sections a plugin registers)
    have no schema of variables here: their layout is their section's
    (``docs/outputs.md``). A dataset of no known kind in a file of
    :func:`save` (no section) is checked as a branch.

    Raises
    ------
    _SchemaError
        The schema check failed (only with ``validate``).
    ValueError
        An attribute is missing or wrong.
    """
    kind = dataset_kind(ds, section)
    if kind is not None:
        check_attributes(ds, kind, in_section=isinstance(section, str)
                         and section in SECTION_KINDS)
    if not validate:
        return
    if kind in _SCHEMA_KINDS or (kind is None and dataset_tag(ds) is None and section is None):
        try:
            validate_dataset(ds)
        except ValueError as exc:
            raise _SchemaError(str(exc)) from exc


class _SchemaError(ValueError):
    """A dataset that does not follow its schema: ``validate=False`` reads or writes it."""


def _tree(obj: Any, validate: bool) -> xr.Dataset | xr.DataTree:
    """The object to write: a Dataset, or a DataTree of groups."""
    if isinstance(obj, xr.Dataset):
        _check(obj, None, validate)
        return obj
    if isinstance(obj, xr.DataTree):
        tree = obj
    elif isinstance(obj, Mapping):
        if not obj:
            raise ValueError("obj must hold at least one branch; got an empty mapping")
        groups: dict[str, xr.Dataset] = {}
        for name, ds in obj.items():
            name = _check_group_name(name)
            if not isinstance(ds, xr.Dataset):
                raise TypeError(f"obj[{name!r}] must be an xarray.Dataset; "
                                f"got {type(ds).__name__}")
            groups[f"/{name}"] = ds
        # the root's title, provenance and description are written with its index
        tree = xr.DataTree.from_dict({"/": xr.Dataset(), **groups})
    else:
        raise TypeError(f"obj must be an xarray.Dataset, a mapping of name to Dataset, an "
                        f"xarray.DataTree or a SimulationResult; got {type(obj).__name__}")
    check_file_attributes(tree.attrs)
    section = tree.attrs.get(SECTION_ATTRIBUTE)
    for node in tree.subtree:
        if node.has_data:
            try:
                _check(node.to_dataset(inherit=False), section, validate)
            except ValueError as exc:
                raise ValueError(f"group {node.path!r}: {exc}") from exc
    return tree


def _kind(ds: xr.Dataset) -> str:
    tag = dataset_tag(ds)
    if tag is not None:
        return str(tag)
    return "branch" if "parameter" in ds.attrs and "point" in ds.dims else ""


def _index(tree: xr.DataTree) -> xr.Dataset:
    """The root index of a file of groups: one entry per group holding data."""
    nodes = [node for node in tree.subtree if node.has_data and node is not tree]
    attrs = [node.to_dataset(inherit=False).attrs for node in nodes]
    N = [a.get("N", 0) for a in attrs]
    columns = {
        "group_name": np.array([node.path.lstrip("/") for node in nodes], dtype=str),
        "group_kind": np.array([_kind(node.to_dataset(inherit=False)) for node in nodes],
                               dtype=str),
        "group_title": np.array([str(a.get("title", "")) for a in attrs], dtype=str),
        "group_N": np.array([int(n) if isinstance(n, (int, np.integer)) else 0 for n in N],
                            dtype=np.int64),
    }
    return xr.Dataset({key: ("group", columns[key], {"long_name": ln, "description": text,
                                                    **({"units": "1"} if key == "group_N"
                                                       else {})})
                       for key, (ln, text) in _INDEX.items()},
                      attrs=_root_attributes(tree.attrs, columns["group_name"].tolist(),
                                             columns["group_kind"].tolist()))


def _split_complex(ds: xr.Dataset) -> xr.Dataset:
    """Complex variables as ``<name>_real`` and ``<name>_imag`` float variables."""
    names = [k for k, v in ds.data_vars.items() if v.dtype.kind == "c"]
    if not names:
        return ds
    out = ds.drop_vars(names)
    for name in names:
        var = ds[name].variable
        for part, values in (("real", var.real), ("imag", var.imag)):
            key = f"{name}_{part}"
            if key in ds.variables:
                raise ValueError(f"cannot store complex variable {name!r} as {key!r}: the "
                                 f"dataset already has a variable {key!r}")
            attrs = dict(var.attrs)
            if "long_name" in attrs:
                words = "real part" if part == "real" else "imaginary part"
                attrs["long_name"] = f"{words} of {attrs['long_name']}"
            attrs.update({_PART: part, _OF: name})
            out[key] = xr.Variable(var.dims, values.data, attrs)
    return out


def _is_part(var: Any, part: str) -> bool:
    value = var.attrs.get(_PART)
    return isinstance(value, str) and value == part


def _join_complex(ds: xr.Dataset) -> xr.Dataset:
    """Inverse of :func:`_split_complex`."""
    for key in [k for k, v in ds.data_vars.items() if _is_part(v, "real")]:
        name = str(ds[key].attrs.get(_OF))
        real, imag = ds[key].variable, ds.get(f"{name}_imag")
        if imag is None or not _is_part(imag, "imag") or name in ds.variables:
            continue
        if (real.dims != imag.dims or real.shape != imag.shape
                or real.dtype.kind not in "iuf" or imag.dtype.kind not in "iuf"):
            raise ValueError(f"variables {key!r} and {name + '_imag'!r} (the real and imaginary "
                             f"parts of {name!r}) must be real numbers of the same dimensions; "
                             f"got {real.dims} {real.dtype} and {imag.dims} {imag.dtype}")
        attrs = {k: v for k, v in real.attrs.items() if k not in (_PART, _OF)}
        if "long_name" in attrs:
            attrs["long_name"] = str(attrs["long_name"]).removeprefix("real part of ")
        data = real.data + 1j * imag.variable.data
        ds = ds.drop_vars([key, f"{name}_imag"]).assign({name: (real.dims, data, attrs)})
    return ds


# The CF form on disk (CF 1.10, readable by netCDF classic readers), undone by load: a text
# dimension coordinate becomes an integer index with flag_values / flag_meanings, int64 values
# int32, booleans and texts carry no units, coordinates no _FillValue, the parameters of a
# branch or curve are auxiliary coordinates of its points, and every dataset says where it
# comes from (Conventions, history, source, references).
_MEMORY_DTYPE = "impactcont_dtype"  # the dtype in memory of a variable stored otherwise
_MEMORY_UNITS = "impactcont_units"  # the units in memory of a boolean or text variable
_FILE_ATTRIBUTES = "impactcont_file_attributes"  # dataset attributes only the file has
_FLAG_MEANING = re.compile(r"^[0-9A-Za-z_\-.+@]+$")  # one word of flag_meanings (CF 3.5)
_TEXT_KINDS = "USO"
_MEMORY_NAME = "impactcont_name"  # the name in memory of a variable stored under a CF name
_LABEL_OF = "impactcont_label_of"  # on <dim>_label: the text coordinate it spells out
_FILE_COORDINATE = "impactcont_file_coordinate"  # a data variable made a coordinate on disk
#: Data variables of text labels stored as CF auxiliary coordinates (labels, CF 6.1) of
#: their dimension, so that a plain reader selects by them (``special_label == "PD"``).
LABEL_VARIABLES = ("special_label", "codim2_label")
_CF_NAME = re.compile(r"^[A-Za-z][A-Za-z0-9_]*$")  # CF 2.3: letters, digits, underscores
_KIND_WORDS = {"branch": "branches of periodic impacting motions",
               "curve": "codimension-1 curves", "map": "stability maps",
               "multi_impact_map": "stability maps of one N-p motion family",
               "orbits": "periodic impacting motions", "robust": "robust stability results",
               "simulation": "simulations"}


def _cf_variable(name: Any, var: xr.Variable, coordinate: bool) -> xr.Variable:
    """``var`` in its CF form on disk (the same object if nothing changes)."""
    attrs, encoding = dict(var.attrs), dict(var.encoding)
    data = var.data
    if coordinate:
        encoding["_FillValue"] = None  # CF 2.5.1: no missing values in a coordinate
    # a text dimension coordinate becomes a numeric index (CF 1.3: coordinate variables are
    # numbers); a text auxiliary coordinate (labels, CF 6.1) stays text
    labels = (var.values.tolist() if coordinate and var.dims == (name,)
              and var.dtype.kind in _TEXT_KINDS else None)
    if labels is not None and (not labels or len(set(labels)) != len(labels)
                               or not all(isinstance(x, str) and _FLAG_MEANING.match(x)
                                          for x in labels)):
        logger.info("coordinate %r stays text in the file: its labels %s are not distinct "
                    "words (CF flag_meanings)", name, labels[:8])
        labels = None
    if labels is not None:  # CF coordinates are numbers: the index, the labels its flags
        data = np.arange(len(labels), dtype=np.int32)
        attrs.update({"flag_values": data, "flag_meanings": " ".join(labels),
                      _MEMORY_DTYPE: "str"})
        encoding.pop("dtype", None)
        if "long_name" not in attrs and "standard_name" not in attrs:  # CF 3.3
            attrs.update({"long_name": f"index of {name}", _FILE_ATTRIBUTES: "long_name"})
    elif (var.dtype.kind in "iu" and var.dtype.itemsize == 8 and isinstance(data, np.ndarray)
          and (data.size == 0 or (data.min() >= np.iinfo(np.int32).min
                                  and data.max() <= np.iinfo(np.int32).max))):
        data = data.astype(np.int32)  # netCDF classic has no 64-bit integers
        attrs[_MEMORY_DTYPE] = str(var.dtype)
        encoding.pop("dtype", None)
    if (var.dtype.kind in "b" + _TEXT_KINDS or labels is not None) and "units" in attrs:
        attrs[_MEMORY_UNITS] = attrs.pop("units")  # a flag or a text has no units
    attrs = {k: _cf_attribute(v) for k, v in attrs.items()}
    if data is var.data and attrs == var.attrs and encoding == var.encoding:
        return var
    return xr.Variable(var.dims, data, attrs, encoding)


def cf_name(name: str) -> str:
    """The name a variable named `name` has in a file: `name` itself when CF allows it
    (CF 2.3: a letter, then letters, digits and underscores), else each run of other
    characters made one underscore (``M[1,2]`` -> ``M_1_2``, ``special_F[2]`` ->
    ``special_F_2``; ``v_`` in front of a name that does not start with a letter)."""
    if _CF_NAME.match(name):
        return name
    safe = re.sub(r"[^A-Za-z0-9_]+", "_", name).rstrip("_")
    return safe if safe[:1].isalpha() else f"v_{safe}"


def _disk_names(ds: xr.Dataset) -> dict[str, str]:
    """``{name in memory: name on disk}`` of the variables of `ds` CF does not allow
    (:func:`cf_name`: an element parameter's column ``M[1,2]``, ``special_F[2]``).

    Raises
    ------
    ValueError
        Two names would be stored under one (``F[2]`` and ``F_2``).
    """
    names = [str(k) for k in ds.variables]
    renames = {name: cf_name(name) for name in names if cf_name(name) != name}
    taken: dict[str, str] = {cf_name(name): name for name in names if name not in renames}
    for name, safe in renames.items():
        if safe in taken:
            raise ValueError(f"cannot store variable {name!r} under the CF name {safe!r} "
                             f"(CF 2.3: letters, digits and underscores): variable "
                             f"{taken[safe]!r} has that name in the file too")
        taken[safe] = name
    return renames


def _cf_attribute(value: Any) -> Any:
    """An attribute without 64-bit integers where its values fit in 32 bits."""
    if isinstance(value, (bool, np.bool_)):
        return value
    if isinstance(value, (int, np.integer)) and np.iinfo(np.int32).min <= value \
            <= np.iinfo(np.int32).max:
        return np.int32(value)
    return value


def _to_cf(ds: xr.Dataset) -> xr.Dataset:
    """The CF form of one dataset (a file's root dataset or a group) on disk."""
    out = ds.set_coords(parameter_names(ds))  # the points of a branch or curve are labelled
    labels = [k for k in LABEL_VARIABLES if k in out.data_vars and out[k].ndim == 1
              and out[k].dtype.kind in _TEXT_KINDS]
    if labels:  # auxiliary coordinates on disk, data variables again in memory
        out = out.assign({k: out[k].variable.copy(deep=False) for k in labels})
        for k in labels:
            out[k].attrs[_FILE_COORDINATE] = "label"
        out = out.set_coords(labels)
    changed = {name: _cf_variable(name, var, name in out.coords)
               for name, var in out.variables.items()}
    out = out.assign_coords({k: v for k, v in changed.items()
                             if k in out.coords and v is not out.variables[k]})
    out = out.assign({k: v for k, v in changed.items()
                      if k not in out.coords and v is not out.variables[k]})
    out = out.assign_coords(_label_coordinates(ds, out))
    provenance = provenance_attributes("written")
    added = [key for key in provenance if key not in ds.attrs]
    attrs = {k: _cf_attribute(v) for k, v in ds.attrs.items()}
    if added:
        attrs.update({key: provenance[key] for key in added})
        attrs[_FILE_ATTRIBUTES] = " ".join(added)
    out.attrs = attrs
    renames = _disk_names(out)
    if renames:  # CF 2.3 names on disk; the name in memory in an attribute
        marked = {name: out.variables[name].copy(deep=False) for name in renames}
        for name, var in marked.items():
            var.attrs = {**var.attrs, _MEMORY_NAME: name}
        out = out.assign_coords({k: v for k, v in marked.items() if k in out.coords})
        out = out.assign({k: v for k, v in marked.items() if k not in out.coords})
        out = out.rename(renames)
    return out


def _label_coordinates(ds: xr.Dataset, out: xr.Dataset) -> dict[str, xr.Variable]:
    """The text labels of each text dimension coordinate stored as integer flags: one
    string auxiliary coordinate ``<dim>_label`` per such dimension (CF 6.1, labels), so
    that a plain reader sees ``x1, v1`` beside the index ``0 .. k-1`` (``component_label``).

    Raises
    ------
    ValueError
        The dataset already has a variable of that name.
    """
    added = {}
    for name, var in out.coords.items():
        if name not in out.dims or _MEMORY_DTYPE not in var.attrs \
                or var.attrs[_MEMORY_DTYPE] != "str":
            continue
        key = f"{name}_label"
        if key in ds.variables:
            raise ValueError(f"cannot store the labels of coordinate {name!r} as {key!r}: the "
                             f"dataset already has a variable {key!r}")
        what = ds[name].attrs.get("long_name", str(name))
        added[key] = xr.Variable(
            (name,), np.asarray(ds[name].values).astype(str),
            {"long_name": f"{what} (label)",
             "description": f"The label of each entry of {name} (the index {name} is "
                            f"0 .. {ds.sizes[name] - 1}, its flag_meanings the same labels).",
             _LABEL_OF: str(name)})
    return added


def _memory_names(ds: xr.Dataset) -> xr.Dataset:
    """`ds` with each variable stored under a CF name (:func:`_disk_names`) given back
    its name in memory (attribute ``impactcont_name``).

    Raises
    ------
    ValueError
        The attribute is not text, or names a variable the dataset has.
    """
    renames = {}
    for name, var in ds.variables.items():
        if _MEMORY_NAME not in var.attrs:
            continue
        memory = var.attrs[_MEMORY_NAME]
        if not isinstance(memory, str) or not memory or memory in ds.variables \
                or memory in renames.values():
            raise ValueError(f"variable {name!r}: attribute {_MEMORY_NAME} must be the name "
                             f"in memory of the variable, a name no other variable has; got "
                             f"{memory!r}")
        renames[str(name)] = memory
    if not renames:
        return ds
    ds = ds.rename(renames)
    for name in renames.values():
        var = ds.variables[name].copy(deep=False)
        var.attrs = {k: v for k, v in var.attrs.items() if k != _MEMORY_NAME}
        ds = ds.assign_coords({name: var}) if name in ds.coords else ds.assign({name: var})
    return ds


def _from_cf(ds: xr.Dataset) -> xr.Dataset:
    """Inverse of :func:`_to_cf`: the dataset as it was given to :func:`save`.

    Files written before the CF form read unchanged (they have none of its marks).

    Raises
    ------
    ValueError
        A mark of the CF form contradicts the variable it is on.
    """
    ds = _memory_names(ds)
    ds = _without_label_coordinates(ds)
    # the points of a branch or curve are labelled by its parameters, in memory as on disk
    # (files written before that hold them as data variables)
    ds = ds.set_coords([k for k in parameter_names(ds) if k in ds.data_vars])
    # so are the orbits, robust and simulation results (older files: scalar data variables)
    if dataset_tag(ds) in _SCALAR_PARAMETER_KINDS:
        ds = ds.set_coords([k for k in ("omega", "b") if k in ds.data_vars
                            and ds[k].ndim == 0])
    for name, var in list(ds.variables.items()):
        if not {_MEMORY_DTYPE, _MEMORY_UNITS, _FILE_ATTRIBUTES} & set(var.attrs):
            continue
        attrs = _without_file_attributes(var.attrs)
        dtype, units = attrs.pop(_MEMORY_DTYPE, None), attrs.pop(_MEMORY_UNITS, None)
        data = var.data
        if dtype == "str":
            labels = str(attrs.pop("flag_meanings", "")).split()
            attrs.pop("flag_values", None)
            if len(labels) != var.size or var.ndim != 1:
                raise ValueError(f"variable {name!r} (attribute {_MEMORY_DTYPE} = 'str') must "
                                 f"be a 1-D index with one word of flag_meanings per entry; "
                                 f"got shape {var.shape} and {len(labels)} word(s)")
            data = np.array(labels)[np.asarray(var.values, dtype=np.int64)]
        elif dtype is not None:
            if dtype not in ("int64", "uint64") or var.dtype.kind not in "iu":
                raise ValueError(f"variable {name!r}: attribute {_MEMORY_DTYPE} must be "
                                 f"'str', 'int64' or 'uint64' on an integer variable; got "
                                 f"{dtype!r} on dtype {var.dtype}")
            data = data.astype(dtype)
        if units is not None:
            attrs["units"] = units
        new = xr.Variable(var.dims, data, attrs)
        if name in ds.coords:
            ds = ds.assign_coords({name: new})
        else:
            ds[name] = new
    ds.attrs = _without_file_attributes(ds.attrs)
    return ds


def _without_label_coordinates(ds: xr.Dataset) -> xr.Dataset:
    """``ds`` without what the file alone has: the ``<dim>_label`` text coordinates
    (:func:`_label_coordinates`; the index's ``flag_meanings`` give the labels back) and,
    as data variables again, the labels stored as auxiliary coordinates
    (:data:`LABEL_VARIABLES`).

    Raises
    ------
    ValueError
        A ``<dim>_label`` contradicts the ``flag_meanings`` of its index.
    """
    drop = []
    for name, var in ds.variables.items():
        of = var.attrs.get(_LABEL_OF)
        if of is None:
            continue
        index = ds.variables.get(of)
        words = str(index.attrs.get("flag_meanings", "")).split() if index is not None else []
        if var.dims != (of,) or (len(words) == var.size  # else the index's own check says
                                 and np.asarray(var.values).astype(str).tolist() != words):
            raise ValueError(f"variable {name!r} (attribute {_LABEL_OF} = {of!r}) must be the "
                             f"labels of {of!r}, its flag_meanings {words}; got "
                             f"{np.asarray(var.values).tolist()} on dims {var.dims}")
        drop.append(name)
    ds = ds.drop_vars(drop)
    back = [k for k, v in ds.coords.items() if v.attrs.get(_FILE_COORDINATE) == "label"]
    if back:
        ds = ds.reset_coords(back)
        for k in back:
            ds[k].attrs = {a: v for a, v in ds[k].attrs.items() if a != _FILE_COORDINATE}
    gone = {*map(str, drop), *back}
    for var in ds.variables.values():  # as read, each names them in its encoding
        named = var.encoding.get("coordinates")
        if isinstance(named, str) and gone & set(named.split()):
            kept = [k for k in named.split() if k not in gone]
            if kept:
                var.encoding["coordinates"] = " ".join(kept)
            else:
                del var.encoding["coordinates"]
    return ds


def _without_file_attributes(attrs: Mapping[str, Any]) -> dict[str, Any]:
    """``attrs`` without those the file alone has (named by ``impactcont_file_attributes``)."""
    added = attrs.get(_FILE_ATTRIBUTES)
    if not isinstance(added, str):
        return dict(attrs)
    return {k: v for k, v in attrs.items() if k != _FILE_ATTRIBUTES and k not in added.split()}


def _root_attributes(attrs: Mapping[str, Any], names: list[str], kinds: list[str]
                     ) -> dict[str, Any]:
    """The attributes of the root group of a file of groups: what it holds, how to open it."""
    out = {"title": _contents_title(kinds), **provenance_attributes("written"), **attrs}
    out["impactcont_groups"] = json.dumps(names)
    counts = {kind: kinds.count(kind) for kind in dict.fromkeys(kinds)}
    listed = ", ".join(f"{kind or 'other'} ({count})" for kind, count in counts.items())
    out["comment"] = (
        f"Groups of impactcont results: {listed} (attribute impactcont_groups, variables "
        "group_name, group_kind, group_title, group_N). This root group holds only that index: "
        "open a group with xarray.open_dataset(path, group=NAME), every group with "
        "xarray.open_datatree(path), or read the file with impactcont.load(path) (complex "
        "multipliers and text coordinates restored).")
    return {k: _cf_attribute(v) for k, v in out.items()}


def _contents_title(kinds: list[str]) -> str:
    """The title of a file of groups of these kinds (``"Branches of ..."`` for branches)."""
    words = [_KIND_WORDS.get(kind, "impactcont results") for kind in dict.fromkeys(kinds)]
    text = ", ".join(words[:-1]) + (" and " if len(words) > 1 else "") + words[-1]
    return text[:1].upper() + text[1:]


def _for_disk(data: xr.Dataset | xr.DataTree) -> xr.Dataset | xr.DataTree:
    """What is written: complex variables split, each dataset in its CF form, the index."""
    if isinstance(data, xr.Dataset):
        return _to_cf(_split_complex(data))
    nodes = {node.path: _to_cf(_split_complex(node.to_dataset(inherit=False)))
             if node.has_data else node.to_dataset(inherit=False) for node in data.subtree}
    if not data.has_data and data.children:
        nodes["/"] = _to_cf(_index(data))
    return xr.DataTree.from_dict(nodes)


def _disk_encoding(encoding: Mapping[str, Any], ds: xr.Dataset) -> dict[str, Any]:
    """``encoding`` with the entry of a complex variable given to both of its parts, each
    under its name on disk (:func:`_disk_names`).

    Raises
    ------
    ValueError
        A key that is not a variable of `ds`, or an entry that is not a mapping (xarray
        raised a bare KeyError from inside its writer).
    """
    out = {}
    for key, value in encoding.items():
        if key not in ds.variables:
            raise ValueError(f"encoding has an entry for {key!r}, which is not a variable of "
                             f"the dataset; its variables: {sorted(map(str, ds.variables))}")
        if not isinstance(value, Mapping):
            raise ValueError(f"encoding[{key!r}] must be a mapping of NetCDF encoding "
                             f"settings (e.g. {{'zlib': True}}); got {value!r}")
        if key in ds.data_vars and ds[key].dtype.kind == "c":
            out[f"{key}_real"] = out[f"{key}_imag"] = dict(value)
        else:
            out[key] = value
    return {cf_name(key): value for key, value in out.items()}


# ---------------------------------------------------------------------------------------------
# Writing that Ctrl-C can stop
# ---------------------------------------------------------------------------------------------
_CAN_FORK = hasattr(os, "fork") and sys.platform != "darwin"
# Below this size a write lasts milliseconds: holding Ctrl-C that long is prompt, and
# cheaper than a child process (20-40 ms to fork a process of 160 MB).
_FORK_BYTES = 16 * 2**20


def _fork_worthy(data: xr.Dataset | xr.DataTree) -> bool:
    """Large and fully in memory (a child cannot share dask tasks or open files)."""
    nodes = [data] if isinstance(data, xr.Dataset) else [n.dataset for n in data.subtree]
    variables = [var for ds in nodes for var in ds.variables.values()]
    return (all(var._in_memory for var in variables)
            and sum(var.nbytes for var in variables) >= _FORK_BYTES)


def _between_dask_tasks(received: list[int]) -> contextlib.AbstractContextManager[Any]:
    """Stop a dask computation at the next task once Ctrl-C was received.

    Dask calls this between tasks, where no NetCDF lock is held: a dask-backed
    write (a map computed as it is written) stops after the chunks in flight.
    """
    try:
        from dask.callbacks import Callback
    except ImportError:
        return contextlib.nullcontext()

    def pretask(key: Any, dsk: Any, state: Any) -> None:
        if received:
            raise KeyboardInterrupt

    return Callback(pretask=pretask)


@contextlib.contextmanager
def _sigint_held(what: Path) -> Iterator[None]:
    """Hold Ctrl-C (SIGINT) while the body runs, then deliver it to the previous handler.

    A dask computation in the body stops at its next task. In the main thread
    only: signals reach no other thread.
    """
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    received: list[int] = []

    def hold(signum: int, frame: Any) -> None:
        if not received:
            logger.warning("interrupted: finishing the write of %s first", what)
        received.append(signum)

    previous = signal.signal(signal.SIGINT, hold)
    try:
        with _between_dask_tasks(received):
            yield
    finally:
        # None: a handler installed outside Python, which cannot be put back
        signal.signal(signal.SIGINT, signal.SIG_DFL if previous is None else previous)
        # delivered here and now, not at some later bytecode (after os.replace, say)
        if received and previous is signal.default_int_handler:
            raise KeyboardInterrupt
        if received and callable(previous):
            previous(signal.SIGINT, None)
        elif received and previous == signal.SIG_DFL:
            signal.raise_signal(signal.SIGINT)


def _xarray_locks() -> list[Any]:
    try:
        from xarray.backends.locks import HDF5_LOCK, NETCDFC_LOCK
    except ImportError:  # pragma: no cover - other xarray layouts
        return []
    return [HDF5_LOCK, NETCDFC_LOCK]


def _end_with_parent(parent: int, parent_alive: int, tmp: Path) -> None:
    """In the forked child: end at once, removing ``tmp``, when the parent ``parent`` ends.

    ``parent_alive`` is the read end of a pipe whose write end only the parent
    holds: the kernel closes it when the parent ends, however it ends (``kill -9``
    included), and the pipe reads as ended. A thread waits for that (the NetCDF
    library releases the GIL while it writes), removes the temporary file and
    ends the process. The parent's pid is polled as well, in case another
    process forked meanwhile holds the write end too. (Linux's
    ``prctl(PR_SET_PDEATHSIG, SIGKILL)`` would end the child as promptly, but
    nothing would remove the file; this works on every system with ``fork``.)
    """
    def watch() -> None:
        while os.getppid() == parent and not select.select([parent_alive], [], [], 0.5)[0]:
            pass
        with contextlib.suppress(OSError):
            os.unlink(tmp)
        os._exit(1)

    threading.Thread(target=watch, name="impactcont-save-watch", daemon=True).start()


def _child_write(data: xr.Dataset | xr.DataTree, tmp: Path, kwargs: dict[str, Any],
                 pipe: int, parent: int, parent_alive: int) -> None:
    """In the forked child: write, report a failure on ``pipe``, never return.

    The child ends with its parent (:func:`_end_with_parent`).
    """
    code = 1
    try:
        signal.signal(signal.SIGINT, signal.SIG_IGN)  # the parent decides, and kills us
        _end_with_parent(parent, parent_alive, tmp)
        data.to_netcdf(tmp, mode="w", engine=ENGINE, auto_complex=True, **kwargs)
        code = 0
    except BaseException as exc:
        try:
            payload = pickle.dumps(exc)
        except Exception:
            payload = pickle.dumps(OSError(f"{type(exc).__name__}: {exc}"))
        with contextlib.suppress(OSError):
            os.write(pipe, payload)
    finally:
        os._exit(code)


def _write_in_child(data: xr.Dataset | xr.DataTree, tmp: Path, kwargs: dict[str, Any],
                    target: Path) -> bool:
    """Write ``data`` to ``tmp`` in a forked child; Ctrl-C here kills the child at once.

    The child shares the data (copy-on-write) and leaves with ``os._exit``: the
    NetCDF library of this process is never interrupted halfway. If this process
    is killed, the child ends too and removes ``tmp``. Returns False, having
    written nothing, if no child can be started.
    """
    read_end, write_end = os.pipe()  # the child's error, if any
    alive_read, alive_write = os.pipe()  # ends when this process does
    parent = os.getpid()
    pid = 0
    try:
        locks = _xarray_locks()
        with _sigint_held(target), warnings.catch_warnings():
            # Python 3.12 warns that a lock held by another thread at the fork stays held
            # in the child. The child only writes and leaves: the locks that write takes,
            # xarray's, are taken here around the fork, so none is held by another thread.
            warnings.filterwarnings("ignore", message=".*fork.*", category=DeprecationWarning)
            for lock in locks:
                lock.acquire()
            try:
                pid = os.fork()
            except OSError as exc:  # no memory or processes left: write here instead
                logger.debug("cannot fork to write %s (%s): writing in this process", tmp, exc)
                return False
            finally:
                for lock in locks:
                    lock.release()
            if pid == 0:
                os.close(read_end)
                os.close(alive_write)
                _child_write(data, tmp, kwargs, write_end, parent, alive_read)
        os.close(write_end)
        os.close(alive_read)
        write_end = alive_read = -1
        chunks = []
        while chunk := os.read(read_end, 1 << 16):
            chunks.append(chunk)
        _, status = os.waitpid(pid, 0)
        pid = 0
    except BaseException:
        if pid:
            with contextlib.suppress(OSError):
                os.kill(pid, signal.SIGKILL)
                os.waitpid(pid, 0)
        raise
    finally:
        for fd in (read_end, write_end, alive_read, alive_write):
            if fd >= 0:
                os.close(fd)
    if chunks:
        raise pickle.loads(b"".join(chunks))
    code = os.waitstatus_to_exitcode(status)
    if code:
        raise OSError(errno.EIO, f"the process writing {tmp} ended with "
                                 f"{f'signal {-code}' if code < 0 else f'exit code {code}'}")
    return True


def _write(data: xr.Dataset | xr.DataTree, tmp: Path, kwargs: dict[str, Any],
           target: Path) -> None:
    if (_CAN_FORK and threading.current_thread() is threading.main_thread()
            and _fork_worthy(data) and _write_in_child(data, tmp, kwargs, target)):
        return
    with _sigint_held(target):
        data.to_netcdf(tmp, mode="w", engine=ENGINE, auto_complex=True, **kwargs)


def save(obj: xr.Dataset | xr.DataTree | Mapping[str, xr.Dataset], path: str | os.PathLike,
         *, validate: bool = True, encoding: Mapping[str, Any] | None = None) -> Path:
    """Write one dataset or several to a NetCDF-4 file, atomically.

    Parameters
    ----------
    obj : xarray.Dataset, mapping of str to Dataset, xarray.DataTree or SimulationResult
        One dataset (written to the root group), or several (one group per
        mapping key, with an index in the root group; a DataTree is written
        as it is, with that index if its root holds no data); a result of
        :func:`impactcont.simulate` is written as its dataset
        (:func:`impactcont.dataset.simulation.simulation_dataset`: impacts, sticking
        phases with their contact forces, accumulation points, the trajectory).
    path : str or os.PathLike
        Target file; its directory must exist. An existing file is replaced
        only once the new one is completely written.
    validate : bool, optional
        Check branch (N-1 and N-p), curve and map datasets against their schema
        first (default). Whatever ``validate``, the attributes impactcont reads
        back (:mod:`impactcont.dataset.attributes`) are checked: a file written
        with ``validate=False`` reads with ``load(..., validate=False)``.
    encoding : mapping, optional
        Per-variable NetCDF encoding (chunk sizes, compression) of a single Dataset.
        A dask-backed Dataset is computed and written chunk by chunk.

    Returns
    -------
    pathlib.Path
        ``path``.

    Raises
    ------
    TypeError
        ``obj`` or ``path`` has an unsupported type.
    ValueError
        A dataset does not follow the schema (with ``validate``), an attribute
        impactcont reads is wrong, a group name is invalid or ``path`` is a
        directory.
    FileNotFoundError, NotADirectoryError, PermissionError
        The directory of ``path`` does not exist or is not writable.
    OSError
        The write failed; the message names ``path`` (never the temporary file) and
        why: errno ENOSPC, "no space left on the device", when the disk is full
        (before writing, or once the write failed), EIO with what the NetCDF library
        said for another error of the library. ``path`` is untouched and no
        temporary file is left.
    KeyboardInterrupt
        Ctrl-C: the target is untouched and the temporary file removed.
    """
    target = _path(path)
    if not isinstance(obj, (xr.Dataset, xr.DataTree, Mapping)):
        from impactcont.dataset.simulation import simulation_dataset
        from impactcont.simulate.simulator import SimulationResult

        if isinstance(obj, SimulationResult):
            obj = simulation_dataset(obj)
    try:
        data = _tree(obj, validate)
    except _SchemaError as exc:
        raise _SchemaError(f"{exc}. impactcont.save(obj, path, validate=False) writes it "
                           f"without this check (impactcont.load(path, validate=False) reads "
                           f"it back)") from exc
    with atomic_output(path) as tmp:
        kwargs = {}
        if encoding:
            kwargs["encoding"] = _disk_encoding(encoding, data) if isinstance(
                data, xr.Dataset) else dict(encoding)
        _write(_for_disk(data), tmp, kwargs, target)
    logger.info("saved %s to %s", type(data).__name__, target)
    return target


def _write_blocks(ds: xr.Dataset, tmp: Path,
                  blocks: Iterable[tuple[Mapping[str, Any], Mapping[str, Any]]],
                  encoding: dict[str, Any], target: Path) -> None:
    """:func:`save_blocks` into ``tmp``: the layout, then the blocks; Ctrl-C between blocks."""
    import netCDF4

    with _sigint_held(target):
        # the layout, attributes and coordinates; the data variables, dask arrays, are only
        # handed to a writer that is dropped (never computed)
        store = xr.backends.NetCDF4DataStore.open(tmp, mode="w", format="NETCDF4")
        try:
            _for_disk(ds).dump_to_store(store, encoding=encoding)
        finally:
            store.close()
        with chunk_cache():
            nc = netCDF4.Dataset(tmp, "a")
    try:
        nc.set_auto_maskandscale(False)
        for name in ds.data_vars:
            for key in map(cf_name, [f"{name}_real", f"{name}_imag"]
                           if ds[name].dtype.kind == "c" else [name]):
                bad = {"scale_factor", "add_offset", "calendar"} & set(nc[key].ncattrs())
                if bad or nc[key].dtype.kind not in "iuf":
                    raise ValueError(f"variable {key!r} is stored as {nc[key].dtype} with "
                                     f"attributes {sorted(bad)}: not a plain cast of its "
                                     f"values, which save_blocks writes")
        for region, values in blocks:
            with _sigint_held(target):
                for name, block in values.items():
                    where = tuple(region[d] for d in ds[name].dims if d in region)
                    block = np.asarray(block)
                    if block.dtype.kind == "c":
                        nc[cf_name(f"{name}_real")][where] = block.real
                        nc[cf_name(f"{name}_imag")][where] = block.imag
                    else:
                        nc[cf_name(name)][where] = block.astype(nc[cf_name(name)].dtype,
                                                                copy=False)
    except BaseException as exc:
        with _sigint_held(target):
            _close_written(nc, tmp, exc)
        raise
    with _sigint_held(target):
        _close_written(nc, tmp, None)


def _close_written(nc: Any, tmp: Path, failed: BaseException | None) -> None:
    """Close the netCDF4 file ``nc`` written to ``tmp``; ``failed``: the error that stopped
    the write, which stays the one raised (the close's own error is raised only without it).

    Where closing fails (HDF5 cannot flush its last data to a full disk, and the library
    then keeps the file open), the file is emptied (:func:`_release`: the write has
    failed anyway) and closed again with the room that freed. Whether the disk was full
    is noted on the errors first (attribute ``_FULL_NOTE``, read by :func:`_write_error`):
    emptied, the file no longer fills it.
    """
    try:
        nc.close()
    except RuntimeError as exc:
        full = _full(tmp.parent, _FULL_BYTES)
        for error in (exc, failed):
            if error is not None:
                setattr(error, _FULL_NOTE, full)
        _release(tmp)
        with contextlib.suppress(RuntimeError):
            nc.close()
        if failed is None:
            raise


def save_blocks(ds: xr.Dataset, path: str | os.PathLike,
                blocks: Iterable[tuple[Mapping[str, Any], Mapping[str, Any]]], *,
                encoding: Mapping[str, Any] | None = None,
                finish: Callable[[], xr.Dataset | None] | None = None) -> Path:
    """Write a dataset larger than memory block by block, atomically (as :func:`save`).

    The file is laid out as :func:`save` would write `ds` (same attributes, CF form,
    complex variables as two parts, `encoding`), then each block is written as it
    comes; nothing but the block in hand is held in memory, and the NetCDF library
    caches no chunk (:mod:`impactcont.dataset.chunk_cache`). Ctrl-C is held while a
    block is written and acts between blocks: the target is untouched and the
    temporary file removed. Needs dask.

    Parameters
    ----------
    ds : xarray.Dataset
        The dataset, its data variables dask arrays of the right shape, dtype and
        attributes, never computed (their values are those of `blocks`).
    path : str or os.PathLike
        Target file; its directory must exist.
    blocks : iterable of (region, values)
        ``region`` maps every dimension of the values to an int or a slice;
        ``values`` maps data variables to their arrays over that region (dims in
        the variable's order, those indexed by an int dropped). Every value of
        every data variable should be in one block (those in none read as the
        fill value).
    encoding : mapping, optional
        Per-variable NetCDF encoding (chunk sizes, compression), as in :func:`save`.
    finish : callable, optional
        Called after the last block: None, or a small dataset in memory whose data
        variables (on dims of `ds`, no coordinates) and attributes are added to the file
        before it is moved onto `path` (an interrupted map's ``computed`` and
        ``interrupted``: the file is whole either way).

    Returns
    -------
    pathlib.Path
        ``path``, as :func:`save`.

    Raises
    ------
    TypeError, ValueError
        As :func:`save`; a data variable that is not a dask array, or whose encoding
        on disk is not a plain cast of its values (scale factors, ...).
    FileNotFoundError, NotADirectoryError, PermissionError
        As :func:`save`: the directory of ``path`` does not exist or is not writable.
    OSError
        As :func:`save`: the write failed (ENOSPC on a full disk), naming ``path``.
    KeyboardInterrupt
        Ctrl-C, acting between blocks: the target is untouched and the temporary
        file removed.
    """
    target = _path(path)
    if not isinstance(ds, xr.Dataset):
        raise TypeError(f"ds must be an xarray.Dataset; got {type(ds).__name__}")
    eager = [k for k, v in ds.data_vars.items() if not hasattr(v.data, "dask")]
    if eager:
        raise ValueError(f"the data variables of ds must be dask arrays (placeholders, never "
                         f"computed); got other arrays in {eager}")
    data = _tree(ds, False)
    with atomic_output(path) as tmp:
        _write_blocks(data, tmp, blocks, _disk_encoding(encoding or {}, data), target)
        extra = finish() if finish is not None else None
        if extra is not None:
            with _sigint_held(target):
                xr.Dataset({k: _cf_variable(k, v.variable, False) for k, v in
                            extra.data_vars.items()},
                           attrs={k: _cf_attribute(v) for k, v in extra.attrs.items()}
                           ).to_netcdf(tmp, mode="a", format="NETCDF4")
    logger.info("saved Dataset to %s block by block", target)
    return target


# ---------------------------------------------------------------------------------------------
# Reading
# ---------------------------------------------------------------------------------------------
def _normalise(ds: xr.Dataset) -> xr.Dataset:
    """The dataset given to save: its CF form undone (:func:`_from_cf`), complex variables
    joined, strings with their schema dtype (empty ones read as <U1)."""
    ds = _join_complex(_from_cf(ds))
    for key, dtype in (("label", _LABEL_DTYPE), ("status", _STATUS_DTYPE)):
        name = special_variable(key)
        if name in ds.variables and ds[name].dtype != dtype:
            ds[name] = ds[name].astype(dtype)
    return normalise_dataset(ds)


def _groups(path: Path) -> tuple[list[str], dict[str, Any], bool]:
    """The groups of the file ``path`` holding variables (paths without the leading ``/``,
    nested ones ``a/b``), its root attributes, and whether its root holds data other than
    the index of a file of groups."""
    import netCDF4

    with chunk_cache(), netCDF4.Dataset(path, "r") as nc:
        names: list[str] = []
        todo = list(nc.groups.values())
        while todo:
            group = todo.pop(0)
            if group.variables:
                names.append(group.path.lstrip("/"))
            todo[:0] = list(group.groups.values())
        attrs = {key: nc.getncattr(key) for key in nc.ncattrs()}
        root_data = bool(set(nc.variables) - set(_INDEX))
    return names, attrs, root_data


def open_lazy(path: str | os.PathLike, *, group: str | None = None,
              on_close: Callable[[], None] | None = None) -> xr.Dataset:
    """Open one dataset of a file lazily (dask-backed; the file stays open).

    For results larger than memory, such as big :func:`impactcont.stability_map`
    maps: values are read chunk by chunk when computed, without the NetCDF
    library's chunk cache (:mod:`impactcont.dataset.chunk_cache`: each chunk is
    read once). Needs dask (``pip install 'impactcont[dask]'``). The attributes
    are checked as by :func:`load` (with the data they describe: a ``pattern``
    against the stored states, the parameters finite); the schema is not (it would
    not change what is read). ``close()`` on the dataset (or the end of a ``with``
    block) closes the file.

    Parameters
    ----------
    path : str or os.PathLike
    group : str, optional
        The group to open in a file of groups (:func:`save` of a mapping, a scene's
        ``<section>.nc``): its name, as listed by the file's ``group_name`` (a leading
        ``/`` is allowed). Required for such a file, whose root holds only the index of
        its groups; absent for a file of one dataset.
    on_close : callable, optional
        Called without arguments once the dataset's file is closed (e.g. to remove
        a temporary file).

    Raises
    ------
    FileNotFoundError
        ``path`` does not exist.
    ValueError
        ``path`` is a file of groups and ``group`` is not one of them (the message
        lists them), ``group`` is given for a file without groups, or an attribute
        impactcont reads is wrong (see :func:`load`).
    """
    target = _path(path)
    if not target.is_file():
        raise FileNotFoundError(f"path {str(path)!r} does not exist or is not a file")
    shown = f"file {str(path)!r}"
    try:
        names, root_attrs, root_data = _groups(target)
    except (OSError, RuntimeError) as exc:
        raise ValueError(f"cannot read {str(path)!r} as NetCDF-4: {exc}") from exc
    if group is not None:
        if not isinstance(group, str):
            raise TypeError(f"group must be a str (a group of the file) or None; got "
                            f"{type(group).__name__}")
        name = group.strip("/")
        if not names:
            raise ValueError(f"{shown} has no groups (one dataset in its root group): open it "
                             f"with open_lazy(path); got group={group!r}")
        if name not in names:
            raise ValueError(f"{shown} has no group {group!r}; allowed: one of {names}")
        try:
            check_file_attributes(root_attrs)
        except ValueError as exc:
            raise ValueError(f"{shown}, root group: {exc}") from exc
        section = root_attrs.get(SECTION_ATTRIBUTE)
        where = f"{shown}, group {'/' + name!r}"
    elif names and not root_data:
        raise ValueError(f"{shown} holds groups {names} (a file of several datasets), not one "
                         f"dataset: open one lazily with open_lazy(path, group=NAME), or read "
                         f"them all with impactcont.load(path)")
    else:
        name, section, where = None, None, shown
    with chunk_cache():
        raw = xr.open_dataset(target, group=name, engine=ENGINE, auto_complex=True, chunks={})
    try:
        # a copy: the dataset returned closes `raw` (the variables joined by _normalise
        # are new datasets, which would not close the file)
        ds = _loaded(raw.copy(), section, False, where)
    except BaseException:
        raw.close()
        raise

    def close() -> None:
        try:
            raw.close()
        finally:
            if on_close is not None:
                on_close()

    ds.set_close(close)
    return ds


def _read_tree(path: Path) -> xr.DataTree:
    """Open ``path`` as a DataTree, load every variable into memory and close the file."""
    with xr.open_datatree(path, engine=ENGINE, auto_complex=True) as tree:
        # Not DataTree.load(): in xarray 2026.9 it skips variables whose name equals a
        # group path (a variable "b" in a file with a group "b"), which then read from
        # a closed file. Loading each variable in place has no such blind spot.
        for node in tree.subtree:
            for var in node.variables.values():
                var.load()
    return tree


def _loaded(ds: xr.Dataset, section: Any, validate: bool, where: str) -> xr.Dataset:
    """``ds`` as read (:func:`_normalise`), checked (:func:`_check`); errors name ``where``."""
    try:
        ds = _normalise(ds)
        _check(ds, section, validate)
    except _SchemaError as exc:
        raise ValueError(f"{where}: {exc}. impactcont.load(path, validate=False) reads it "
                         f"without this check (impactcont.save(..., validate=False) writes "
                         f"such files)") from exc
    except ValueError as exc:
        raise ValueError(f"{where}: {exc} (impactcont checks the attributes it reads, "
                         f"whatever validate; xarray.open_datatree(path) opens the file "
                         f"unchecked)") from exc
    return ds


def load(path: str | os.PathLike, *, validate: bool = True) -> xr.Dataset | xr.DataTree:
    """Read a file written by impactcont, fully into memory (the file is closed).

    Reads every file the package writes: :func:`save` of a branch, curve or
    map, and each ``<section>.nc`` of a scene run (orbits, branches, robust,
    simulations, curves, maps, switches, multi_impact).

    Two checks, the same as :func:`save`'s, so that what :func:`save` writes
    :func:`load` reads with the same ``validate``:

    - the attributes impactcont reads (the oscillator JSON, ``N``, the
      continued parameter, the impact pattern, ...: the table of
      :mod:`impactcont.dataset.attributes`) are checked always, whatever
      ``validate``: a file whose attributes were edited is refused rather than
      misread (:func:`save` never writes one);
    - with ``validate`` (default), branches (N-1 and N-p), curves and maps are
      checked against their schema (variables, dimensions, dtypes). A dataset
      written with ``save(..., validate=False)`` that does not follow it reads
      with ``validate=False``; ``validate=True`` refuses it and says so.

    Parameters
    ----------
    path : str or os.PathLike
        A NetCDF-4 file.
    validate : bool, optional
        Check branches (N-1 and N-p), curves and maps against their schema
        (default); the attributes are checked whatever ``validate``.

    Returns
    -------
    xarray.Dataset or xarray.DataTree
        A Dataset if the file holds one dataset in its root group, a DataTree
        (one group per entry, the root index dropped) if it holds groups.
        Complex variables are complex again.

    Raises
    ------
    FileNotFoundError
        ``path`` does not exist.
    ValueError
        ``path`` is not a readable NetCDF file, holds no impactcont dataset, an
        attribute impactcont reads is missing or wrong, or (with ``validate``) a
        dataset does not follow its schema; the message names the file, the
        group and the attribute or variable, its value and what is allowed.
    """
    target = _path(path)
    if not target.is_file():
        raise FileNotFoundError(f"path {str(path)!r} does not exist or is not a file")
    try:
        tree = _read_tree(target)
    except (OSError, ValueError, RuntimeError) as exc:
        raise ValueError(f"cannot read {str(path)!r} as NetCDF-4: {exc}") from exc
    except (TypeError, ArithmeticError) as exc:  # xarray's decoding of CF attributes
        raise ValueError(f"cannot read {str(path)!r}: a variable cannot be decoded from its "
                         f"attributes (units, scale_factor, ...): {type(exc).__name__}: "
                         f"{exc}") from exc
    shown = f"file {str(path)!r}"
    if not tree.children:
        if not tree.has_data:
            raise ValueError(f"{shown} holds no dataset (empty root group)")
        return _loaded(tree.to_dataset(), None, validate, shown)
    try:
        check_file_attributes(tree.attrs)
    except ValueError as exc:
        raise ValueError(f"{shown}, root group: {exc}") from exc
    if set(tree.data_vars) == set(_INDEX):
        tree.dataset = xr.Dataset(attrs=tree.attrs)
    section = tree.attrs.get(SECTION_ATTRIBUTE)
    for node in tree.subtree:
        if node.has_data:
            node.dataset = _loaded(node.to_dataset(inherit=False), section, validate,
                                   f"{shown}, group {node.path!r}")
    return tree
