"""NetCDF save and load of branch datasets, one branch or many (DataTree groups).

Files are written with the ``netcdf4`` engine and ``auto_complex=True`` so that
complex multipliers are stored as a compound type and read back as complex.
Booleans are stored by xarray as ``int8`` with a ``dtype: bool`` attribute and
decoded back to ``bool``. Every write goes to a temporary file in the target's
directory, replaced atomically onto the target with :func:`os.replace`; a
failed write leaves the previous file untouched and no temporary file behind.
"""

from __future__ import annotations

import logging
import os
import uuid
from collections.abc import Mapping
from pathlib import Path
from typing import Any

import xarray as xr

# branch, curve or map dataset, by its "impactcont_dataset" attribute (branches have none)
from impactcont.dataset.curves import normalise_dataset, validate_dataset
from impactcont.dataset.schema import (
    _LABEL_DTYPE,
    _STATUS_DTYPE,
    CONVENTIONS,
    special_variable,
)

__all__ = ["ENGINE", "load", "open_lazy", "save"]

logger = logging.getLogger(__name__)

#: The NetCDF engine used for every read and write.
ENGINE = "netcdf4"


def _path(path: Any) -> Path:
    if isinstance(path, bytes) or not isinstance(path, (str, os.PathLike)):
        raise TypeError(f"path must be a str or os.PathLike; got {path!r}")
    p = Path(path)
    if str(path) == "" or p.name == "":
        raise ValueError(f"path must name a file; got {path!r}")
    return p


def _check_group_name(name: Any) -> str:
    if not isinstance(name, str) or not name or "/" in name or name in (".", ".."):
        raise ValueError(f"branch names must be non-empty str without '/'; got {name!r}")
    return name


def _tree(obj: Any, validate: bool) -> xr.Dataset | xr.DataTree:
    """The object to write: a branch Dataset or a DataTree of branch groups."""
    if isinstance(obj, xr.Dataset):
        if validate:
            validate_dataset(obj)
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
        from impactcont import __version__

        root = xr.Dataset(attrs={"title": "Branches of periodic impacting motions",
                                 "impactcont_version": __version__,
                                 "Conventions": CONVENTIONS})
        tree = xr.DataTree.from_dict({"/": root, **groups})
    else:
        raise TypeError(f"obj must be an xarray.Dataset, a mapping of name to Dataset or an "
                        f"xarray.DataTree; got {type(obj).__name__}")
    if validate:
        for node in tree.subtree:
            if node.has_data:
                try:
                    validate_dataset(node.to_dataset(inherit=False))
                except ValueError as exc:
                    raise ValueError(f"group {node.path!r}: {exc}") from exc
    return tree


def save(obj: xr.Dataset | xr.DataTree | Mapping[str, xr.Dataset], path: str | os.PathLike,
         *, validate: bool = True, encoding: Mapping[str, Any] | None = None) -> Path:
    """Write one branch or several to a NetCDF-4 file, atomically.

    Parameters
    ----------
    obj : xarray.Dataset, mapping of str to Dataset, or xarray.DataTree
        One branch dataset (written to the root group), or several (one group
        per mapping key; a DataTree is written as it is).
    path : str or os.PathLike
        Target file; its directory must exist. An existing file is replaced
        only once the new one is completely written.
    validate : bool, optional
        Check every dataset against the branch schema first (default).
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
        A dataset does not follow the schema, a group name is invalid or
        ``path`` is a directory.
    FileNotFoundError
        The directory of ``path`` does not exist.
    """
    target = _path(path)
    data = _tree(obj, validate)
    if target.is_dir():
        raise ValueError(f"path must be a file, not a directory; got {str(path)!r}")
    directory = target.parent
    if not directory.is_dir():
        raise FileNotFoundError(f"directory of path {str(path)!r} does not exist: {directory}")
    # The temporary file lives next to the target so that os.replace is an
    # atomic rename on the same file system; the random name avoids clashes.
    tmp = directory / f".{target.name}.{uuid.uuid4().hex}.tmp"
    try:
        kwargs = {"encoding": dict(encoding)} if encoding else {}
        data.to_netcdf(tmp, mode="w", engine=ENGINE, auto_complex=True, **kwargs)
        os.replace(tmp, target)
    except BaseException:
        tmp.unlink(missing_ok=True)
        raise
    logger.info("saved %s to %s", type(data).__name__, target)
    return target


def _normalise(ds: xr.Dataset) -> xr.Dataset:
    """Give strings back their schema dtype (an empty array is read back as <U1)."""
    for key, dtype in (("label", _LABEL_DTYPE), ("status", _STATUS_DTYPE)):
        name = special_variable(key)
        if name in ds.variables and ds[name].dtype != dtype:
            ds[name] = ds[name].astype(dtype)
    return normalise_dataset(ds)


def open_lazy(path: str | os.PathLike) -> xr.Dataset:
    """Open a single-dataset file lazily (dask-backed; the file stays open).

    For results larger than memory, such as big :func:`impactcont.stability_map`
    maps: values are read chunk by chunk when computed. Needs dask
    (``pip install 'impactcont[dask]'``).
    """
    target = _path(path)
    if not target.is_file():
        raise FileNotFoundError(f"path {str(path)!r} does not exist or is not a file")
    return _normalise(xr.open_dataset(target, engine=ENGINE, auto_complex=True, chunks={}))


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


def load(path: str | os.PathLike, *, validate: bool = True) -> xr.Dataset | xr.DataTree:
    """Read a file written by :func:`save`, fully into memory (the file is closed).

    Parameters
    ----------
    path : str or os.PathLike
        A NetCDF-4 file.
    validate : bool, optional
        Check every branch against the schema (default).

    Returns
    -------
    xarray.Dataset or xarray.DataTree
        A Dataset if the file holds one branch in its root group, a DataTree
        if it holds groups.

    Raises
    ------
    FileNotFoundError
        ``path`` does not exist.
    ValueError
        ``path`` is not a readable NetCDF file or holds no branch dataset.
    """
    target = _path(path)
    if not target.is_file():
        raise FileNotFoundError(f"path {str(path)!r} does not exist or is not a file")
    try:
        tree = _read_tree(target)
    except (OSError, ValueError, RuntimeError) as exc:
        raise ValueError(f"cannot read {str(path)!r} as NetCDF-4: {exc}") from exc
    if not tree.children:
        if not tree.has_data:
            raise ValueError(f"file {str(path)!r} holds no branch dataset (empty root group)")
        ds = _normalise(tree.to_dataset())
        if validate:
            try:
                validate_dataset(ds)
            except ValueError as exc:
                raise ValueError(f"file {str(path)!r}: {exc}") from exc
        return ds
    for node in tree.subtree:
        if node.has_data:
            node.dataset = _normalise(node.to_dataset(inherit=False))
            if validate:
                try:
                    validate_dataset(node.to_dataset(inherit=False))
                except ValueError as exc:
                    raise ValueError(f"file {str(path)!r}, group {node.path!r}: {exc}") from exc
    return tree
