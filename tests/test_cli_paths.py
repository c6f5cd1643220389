"""Output paths are checked before anything is computed, and errors name the user's path
(issue 13): ``impactcont run --output``, ``run --check``, ``plot -o`` and ``impactcont.save``."""

from __future__ import annotations

import errno
import os
from pathlib import Path

import numpy as np
import pytest
import xarray as xr
from _scene_data import ORBITS_SCENE, write

import impactcont as ic
from impactcont.cli import EXIT_OK, EXIT_USAGE, main
from impactcont.dataset import io as dataset_io
from impactcont.scene import tasks

ORBITS = xr.Dataset({"x": ("t", np.arange(3.0))}, attrs={"impactcont_dataset": "orbits"})


@pytest.fixture
def no_computing(monkeypatch: pytest.MonkeyPatch) -> None:
    """Computing anything fails the test: the paths must be refused first."""
    def compute(self, entry, context=None):
        raise AssertionError("computed before the output path was checked")

    monkeypatch.setattr(tasks.Orbits, "compute", compute)


@pytest.fixture
def read_only(tmp_path: Path):
    """A directory nobody may write in (chmod 555), or a skip where that does not hold."""
    directory = tmp_path / "read_only"
    directory.mkdir()
    directory.chmod(0o555)
    try:
        (directory / "probe").touch()
    except PermissionError:
        yield directory
    else:
        (directory / "probe").unlink()
        pytest.skip("chmod 555 does not stop this user from writing (running as root): "
                    "the real read-only case cannot be set up here")
    finally:
        directory.chmod(0o755)


def test_existing_file_as_output_is_refused_before_computing(
        tmp_path: Path, capsys: pytest.CaptureFixture[str], no_computing: None) -> None:
    scene = write(tmp_path, ORBITS_SCENE)
    existing = tmp_path / "results.csv"
    existing.write_text("keep me")
    for extra in ([], ["--check"]):
        assert main(["run", str(scene), "--output", str(existing), *extra]) == EXIT_USAGE
        err = capsys.readouterr().err
        assert f"output directory {str(existing)!r} is an existing file, not a directory" in err
        assert "FileExistsError" not in err
    assert existing.read_text() == "keep me"
    below = existing / "out"
    assert main(["run", str(scene), "--output", str(below)]) == EXIT_USAGE
    assert f"{str(existing)!r} is a file, not a directory" in capsys.readouterr().err


def test_read_only_output_is_refused_before_computing(
        read_only: Path, capsys: pytest.CaptureFixture[str], no_computing: None) -> None:
    scene = write(read_only.parent, ORBITS_SCENE)
    for output, extra in ((read_only, []), (read_only, ["--check"]),
                          (read_only / "new" / "dir", []), (read_only / "new", ["--check"])):
        assert main(["run", str(scene), "--output", str(output), *extra]) == EXIT_USAGE
        err = capsys.readouterr().err
        assert f"output directory {str(output)!r}" in err and ".tmp" not in err
    assert list(read_only.iterdir()) == []


def test_unwritable_directory_is_named_whoever_runs_the_tests(
        tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str],
        no_computing: None) -> None:
    """The same refusal where the operating system says EACCES (root included)."""
    locked = tmp_path / "locked"
    locked.mkdir()
    real_open = os.open

    def refusing_open(path, flags, *args):
        if Path(path).parent == locked and flags & os.O_CREAT:
            raise PermissionError(errno.EACCES, "Permission denied", str(path))
        return real_open(path, flags, *args)

    monkeypatch.setattr(dataset_io.os, "open", refusing_open)
    scene = write(tmp_path, ORBITS_SCENE)
    for extra in ([], ["--check"]):
        assert main(["run", str(scene), "--output", str(locked), *extra]) == EXIT_USAGE
        err = capsys.readouterr().err
        assert (f"error: output directory {str(locked)!r} is not writable (Permission denied); "
                f"choose another or change its permissions") in err
    with pytest.raises(PermissionError, match=rf"cannot write {str(locked / 'x.nc')!r}: "
                                              rf"directory .* is not writable") as info:
        ic.save(ORBITS, locked / "x.nc")
    assert ".tmp" not in str(info.value) and info.value.errno == errno.EACCES
    assert list(locked.iterdir()) == []


def test_check_says_where_the_run_would_write(tmp_path: Path,
                                              capsys: pytest.CaptureFixture[str]) -> None:
    scene = write(tmp_path, ORBITS_SCENE)
    out = tmp_path / "not" / "yet"
    assert main(["run", str(scene), "--output", str(out), "--check"]) == EXIT_OK
    assert f"output directory {out}" in capsys.readouterr().out
    assert not (tmp_path / "not").exists()  # --check creates nothing
    assert main(["run", str(scene), "--output", str(out), "-q"]) == EXIT_OK
    assert (out / "orbits.nc").is_file()


def test_plot_into_a_missing_directory_names_it(tmp_path: Path,
                                                capsys: pytest.CaptureFixture[str]) -> None:
    scene = write(tmp_path, ORBITS_SCENE)
    assert main(["run", str(scene), "--output", str(tmp_path / "o"), "-q"]) == EXIT_OK
    png = tmp_path / "missing" / "x.png"
    assert main(["plot", str(tmp_path / "o" / "orbits.nc"), "-o", str(png)]) == EXIT_USAGE
    err = capsys.readouterr().err
    assert (f"error: cannot write {str(png)!r}: directory {str(png.parent)!r} does not exist; "
            f"create it first or choose another path") in err
    assert ".tmp" not in err
    assert sorted(p.name for p in (tmp_path / "o").iterdir()) == ["orbits.nc", "summary.md"]


def test_save_names_the_path_the_user_gave(tmp_path: Path) -> None:
    with pytest.raises(FileNotFoundError, match=r"cannot write '.*nope/x\.nc': directory "
                                                r"'.*nope' does not exist"):
        ic.save(ORBITS, tmp_path / "nope" / "x.nc")
    afile = tmp_path / "afile"
    afile.write_text("")
    with pytest.raises(NotADirectoryError, match=r"'.*afile' is not a directory"):
        ic.save(ORBITS, afile / "x.nc")
    with pytest.raises(ValueError, match="path must be a file, not a directory"):
        ic.save(ORBITS, tmp_path)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["afile"]
