"""The ``impactcont`` command: run, info, plot, list-problems; exit codes; logging levels.

The command line answers ``--help`` and usage errors without the heavy imports; plain text.

The import tests run in a subprocess (a fresh ``sys.modules``).

Output paths are checked before anything is computed, and errors name the user's path
(issue 13): ``impactcont run --output``, ``run --check``, ``plot -o`` and ``impactcont.save``.
"""

from __future__ import annotations

import errno
import json
import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
import xarray as xr

import impactcont
import impactcont as ic
from impactcont.cli import EXIT_FAILURE, EXIT_OK, EXIT_USAGE, main, plain_text
from impactcont.dataset import io as dataset_io
from impactcont.scene import read_output, tasks
from impactcont.scene.plugins import register_problem, unregister_problem
from tests import _fake_plugins
from tests._scene_data import ORBITS_SCENE, OSCILLATOR, SMALL_SCENE, write

ROOT = Path(__file__).resolve().parents[1]


@pytest.fixture(scope="module")
def ran(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """``impactcont run`` of a small scene with one entry of every section; its output dir."""
    directory = tmp_path_factory.mktemp("cli")
    out = directory / "out"
    code = main(["run", str(write(directory, SMALL_SCENE)), "--output", str(out), "-q"])
    assert code == EXIT_OK
    return out


fake_entry_points = pytest.fixture(_fake_plugins.fake_entry_points)


def test_run_writes_netcdf_png_and_summary(ran: Path) -> None:
    names = sorted(p.name for p in ran.iterdir())
    assert names == ["bif.png", "branches.nc", "mult.png", "orb.png", "orbits.nc", "rob.png",
                     "robust.nc", "simp.png", "simulations.nc", "summary.md"]


def test_run_reports_what_it_wrote(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    code = main(["run", str(write(tmp_path, ORBITS_SCENE)), "-o", str(tmp_path / "o")])
    out = capsys.readouterr().out
    assert code == EXIT_OK
    assert "orbits.nc" in out and "summary.md" in out and str(tmp_path / "o") in out


@pytest.mark.parametrize("name", ["branches", "orbits", "robust", "simulations"])
def test_info_describes_each_file(ran: Path, name: str, capsys: pytest.CaptureFixture[str]
                                  ) -> None:
    assert main(["info", str(ran / f"{name}.nc")]) == EXIT_OK
    out = capsys.readouterr().out
    assert f"({name})" in out
    assert "scene: 'small'" in out
    assert "groups:" in out
    assert "| entry |" in out or "| branch |" in out


def test_info_lists_special_points(ran: Path, capsys: pytest.CaptureFixture[str]) -> None:
    main(["info", str(ran / "branches.nc")])
    out = capsys.readouterr().out
    assert "special points:" in out
    for label in ("NS", "ZV", "SN"):
        assert f"| br | 1 | {label} |" in out


@pytest.mark.parametrize(("name", "kind"), [("branches", None), ("branches", "multipliers"),
                                            ("orbits", None), ("robust", None),
                                            ("simulations", None)])
def test_plot_draws_each_file(ran: Path, tmp_path: Path, name: str, kind: str | None) -> None:
    png = tmp_path / f"{name}.png"
    argv = ["plot", str(ran / f"{name}.nc"), "-o", str(png), "--dpi", "40"]
    assert main(argv + (["--kind", kind] if kind else [])) == EXIT_OK
    assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


def test_plot_default_output_beside_the_file(ran: Path, tmp_path: Path) -> None:
    copy = tmp_path / "branches.nc"
    copy.write_bytes((ran / "branches.nc").read_bytes())
    assert main(["plot", str(copy), "--y", "spectral_radius", "--dpi", "40"]) == EXIT_OK
    assert (tmp_path / "branches.png").is_file()


def test_plot_and_info_reject_bad_files(ran: Path, tmp_path: Path,
                                        capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["info", str(tmp_path / "missing.nc")]) == EXIT_USAGE
    not_netcdf = tmp_path / "x.nc"
    not_netcdf.write_text("hello")
    assert main(["info", str(not_netcdf)]) == EXIT_USAGE
    assert main(["plot", str(ran / "orbits.nc"), "--kind", "multipliers"]) == EXIT_USAGE
    err = capsys.readouterr().err
    assert "error:" in err and "does not draw 'orbits' files" in err


def test_malformed_scene_exits_2_naming_key_and_allowed(tmp_path: Path,
                                                        capsys: pytest.CaptureFixture[str]
                                                        ) -> None:
    path = write(tmp_path, OSCILLATOR + "[[branches]]\nbounds = [1, 2]\nds_maxx = 0.1\n")
    assert main(["run", str(path)]) == EXIT_USAGE
    err = capsys.readouterr().err
    assert f"{path}:11: branches[0].ds_maxx: unknown key; did you mean 'ds_max'?" in err
    assert "allowed: name, F, R, b, omega" in err
    assert not (tmp_path / "output").exists()  # nothing computed


def test_set_overrides_the_scene(tmp_path: Path) -> None:
    path = write(tmp_path, ORBITS_SCENE)
    out = tmp_path / "o"
    assert main(["run", str(path), "-o", str(out), "-q", "--set", "orbits[paper].b=0.2",
                 "--set", "output.summary=false"]) == EXIT_OK
    scene = json.loads(read_output(out / "orbits.nc").attrs["scene"])
    assert scene["orbits"][0]["b"] == 0.2 and scene["output"]["summary"] is False
    assert not (out / "summary.md").exists()
    assert main(["run", str(path), "--set", "oscillator.R=3", "--check"]) == EXIT_USAGE


def test_check_validates_without_computing(tmp_path: Path,
                                           capsys: pytest.CaptureFixture[str]) -> None:
    path = write(tmp_path, SMALL_SCENE)
    assert main(["run", str(path), "--check"]) == EXIT_OK
    assert "valid scene 'small'" in capsys.readouterr().out
    assert not (tmp_path / "output").exists()


def test_compute_failure_exits_1(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    text = ORBITS_SCENE + '[[simulations]]\nname = "nowhere"\nb = 100.0\nperiods = 2\n'
    path = write(tmp_path, text)
    assert main(["run", str(path), "-o", str(tmp_path / "o")]) == EXIT_FAILURE
    err = capsys.readouterr().err
    assert "simulations nowhere" in err and "NoPeriodicMotionError" in err
    assert (tmp_path / "o" / "orbits.nc").is_file()
    assert main(["run", str(path), "-o", str(tmp_path / "o2"), "--fail-fast"]) == EXIT_FAILURE


def test_logging_levels(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    path = write(tmp_path, ORBITS_SCENE)
    assert main(["run", str(path), "-o", str(tmp_path / "a"), "-q"]) == EXIT_OK
    captured = capsys.readouterr()
    assert captured.out == "" and captured.err == ""
    assert main(["-v", "run", str(path), "-o", str(tmp_path / "b")]) == EXIT_OK
    assert "info: orbits paper: 2 root(s)" in capsys.readouterr().err
    assert main(["run", str(path), "-o", str(tmp_path / "c"), "-vv"]) == EXIT_OK
    assert "info: impactcont.scene.run: scene 'orbits only'" in capsys.readouterr().err


def test_progress_is_logged_without_tqdm(tmp_path: Path, monkeypatch: pytest.MonkeyPatch,
                                         capsys: pytest.CaptureFixture[str]) -> None:
    monkeypatch.setitem(sys.modules, "tqdm", None)  # import tqdm now fails
    path = write(tmp_path, ORBITS_SCENE)
    assert main(["run", str(path), "-o", str(tmp_path / "o"), "--progress"]) == EXIT_OK
    err = capsys.readouterr().err
    assert "info: [1/2] orbits paper" in err and "info: [2/2] orbits fig3" in err


def test_progress_bar_with_tqdm(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    pytest.importorskip("tqdm")
    path = write(tmp_path, ORBITS_SCENE)
    assert main(["run", str(path), "-o", str(tmp_path / "o"), "--progress"]) == EXIT_OK
    assert "2/2" in capsys.readouterr().err
    # not a terminal and no --progress: no bar
    assert main(["run", str(path), "-o", str(tmp_path / "o")]) == EXIT_OK
    assert "2/2" not in capsys.readouterr().err


def test_usage_errors_exit_2(capsys: pytest.CaptureFixture[str]) -> None:
    assert main([]) == EXIT_USAGE
    assert main(["frobnicate"]) == EXIT_USAGE
    assert main(["run"]) == EXIT_USAGE
    assert main(["run", "/nonexistent/scene.toml"]) == EXIT_USAGE
    assert "no such scene file" in capsys.readouterr().err
    assert main(["--version"]) == EXIT_OK
    assert "impactcont" in capsys.readouterr().out


def test_list_problems_with_plugins(capsys: pytest.CaptureFixture[str],
                                    fake_entry_points) -> None:
    fake_entry_points(("good", "tests_fake_plugin:GoodProblem"),
                      ("broken", "tests_no_such_module_xyz:Problem"),
                      ("tally", "tests_fake_plugin:TALLY"))
    assert main(["list-problems"]) == EXIT_OK
    captured = capsys.readouterr()
    lines = captured.out.splitlines()
    assert any(line.split()[:3] == ["branches", "built-in", "[[branches]]"] for line in lines)
    assert any(line.split()[:3] == ["tally", "plugin", "[[tally]]"] for line in lines)
    assert any(line.startswith("good ") and "(no scene section)" in line for line in lines)
    assert "good" in captured.out and "A problem from a plugin." in captured.out
    assert "broken" not in captured.out
    assert "warning:" in captured.err and "'broken'" in captured.err
    assert "ModuleNotFoundError" in captured.err


def test_python_m_impactcont(tmp_path: Path) -> None:
    path = write(tmp_path, ORBITS_SCENE)
    run = subprocess.run([sys.executable, "-m", "impactcont", "run", str(path), "-o",
                          str(tmp_path / "o")], capture_output=True, text=True, timeout=300,
                         check=False)
    assert run.returncode == EXIT_OK, run.stderr
    assert "orbits.nc" in run.stdout
    info = subprocess.run([sys.executable, "-m", "impactcont", "info",
                           str(tmp_path / "o" / "orbits.nc")], capture_output=True, text=True,
                          timeout=300, check=False)
    assert info.returncode == EXIT_OK and "(orbits), 2 entries" in info.stdout
    bad = subprocess.run([sys.executable, "-m", "impactcont", "run", str(tmp_path / "x.toml")],
                         capture_output=True, text=True, timeout=300, check=False)
    assert bad.returncode == EXIT_USAGE and "no such scene file" in bad.stderr


def test_info_and_plot_on_a_file_of_impactcont_save(ran: Path, tmp_path: Path,
                                                    capsys: pytest.CaptureFixture[str]) -> None:
    import impactcont as ic

    branch = read_output(ran / "branches.nc").datasets["br"]
    path = ic.save(branch, tmp_path / "one_branch.nc")
    assert main(["info", str(path)]) == EXIT_OK
    assert "(branches), 1 entry" in capsys.readouterr().out
    assert main(["plot", str(path), "--dpi", "40"]) == EXIT_OK
    assert (tmp_path / "one_branch.png").is_file()


def test_readme_test_command_is_what_ci_runs() -> None:
    """The README's test command and .ci/run must not drift apart (issue 13)."""
    readme = (ROOT / "README.md").read_text(encoding="utf-8")
    ci = (ROOT / ".ci" / "run").read_text(encoding="utf-8")
    commands = [line.strip() for line in ci.splitlines()
                if line.startswith("python3 -m venv")]
    assert len(commands) == 1, "no single command line in .ci/run"
    (command,) = commands
    assert f"\n    {command}\n" in readme, "README.md does not show the command .ci/run runs"
    assert "pytest" in command and "ruff check" in command and "mkdocs build --strict" in command
    assert "export" not in ci, ".ci/run sets variables the README command does not have"


HEAVY = ("numba", "scipy", "xarray", "matplotlib")


SOURCE = Path(impactcont.__file__).resolve().parents[1]


#: Runs ``main(argv)`` and prints the heavy top-level modules then in ``sys.modules``.
#: With ``bare``, the package ``impactcont`` is an empty module (its ``__init__`` not run):
#: what the command line imports itself.
_PROBE = """
import json, sys, types
argv, bare = json.loads(sys.argv[1])
if bare:
    package = types.ModuleType("impactcont")
    package.__path__ = [{package!r}]
    package.__version__ = "0"
    sys.modules["impactcont"] = package
from impactcont.cli import main
code = main(argv)
heavy = sorted({{name.partition(".")[0] for name in sys.modules}} & set({heavy!r}))
print(json.dumps([code, heavy]))
"""


def _probe(argv: list[str], *, bare: bool) -> tuple[int, list[str]]:
    script = _PROBE.format(package=str(SOURCE / "impactcont"), heavy=HEAVY)
    run = subprocess.run([sys.executable, "-c", script, json.dumps([argv, bare])],
                         cwd=SOURCE, capture_output=True, text=True, timeout=120, check=False)
    assert run.returncode == 0, run.stderr
    code, heavy = json.loads(run.stdout.splitlines()[-1])
    return code, heavy


@pytest.mark.parametrize("argv, code", [
    (["--help"], 0), (["run", "--help"], 0), (["--version"], 0), ([], 2), (["frobnicate"], 2),
    (["run"], 2), (["plot", "a.nc", "--dpi", "many"], 2),
])
def test_the_command_line_itself_imports_nothing_heavy(argv: list[str], code: int) -> None:
    assert _probe(argv, bare=True) == (code, [])


def test_impactcont_help_imports_nothing_heavy() -> None:
    assert _probe(["--help"], bare=False) == (0, [])


class _Documented:
    """Follows :func:`~impactcont.curve` in ``[[x]]``, see :class:`the flow <impactcont.Flow>`.

    More text that list-problems does not show.
    """


def test_list_problems_prints_plain_text(capsys: pytest.CaptureFixture[str]) -> None:
    register_problem("documented", _Documented)
    try:
        assert main(["list-problems"]) == EXIT_OK
    finally:
        unregister_problem("documented")
    out = capsys.readouterr().out
    assert "Follows curve in [[x]], see the flow." in out
    assert "[[branches]]: a one-parameter branch" in out
    assert "`" not in out and ":func:" not in out and ":class:" not in out


@pytest.mark.parametrize("rst, text", [
    (":func:`impactcont.curve`", "impactcont.curve"),
    (":py:meth:`~impactcont.scene.SceneSection.check`", "check"),
    (":class:`Flow <impactcont.orbit.flow.Flow>`", "Flow"),
    (":math:`\\rho(G) < 1`", "\\rho(G) < 1"),
    ("``[[orbits]]``: every root", "[[orbits]]: every root"),
    ("`default role` and `a link <https://example.org>`_", "default role and a link"),
    ("**strong** and *emphasis*, but 2*x*y and a*", "strong and emphasis, but 2*x*y and a*"),
])
def test_plain_text(rst: str, text: str) -> None:
    assert plain_text(rst) == text


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


def _statvfs(free_blocks: int) -> os.statvfs_result:
    return os.statvfs_result((4096, 4096, 262144, free_blocks, free_blocks, 65536, 60000,
                              60000, 0, 255))


def test_a_disk_filling_up_during_a_run_is_one_clear_line(
        tmp_path: Path, monkeypatch: pytest.MonkeyPatch,
        capsys: pytest.CaptureFixture[str]) -> None:
    """The NetCDF library's "HDF error" on a full disk is said as such, naming the file."""
    free = [1000]
    monkeypatch.setattr(dataset_io.os, "statvfs", lambda path: _statvfs(free[0]))

    def filling(self, target, *args, **kwargs):
        Path(target).write_bytes(b"\x89HDF half a file")
        free[0] = 0
        raise RuntimeError("NetCDF: HDF error")

    monkeypatch.setattr(xr.DataTree, "to_netcdf", filling)
    out = tmp_path / "o"
    assert main(["run", str(write(tmp_path, ORBITS_SCENE)), "--output", str(out)]) \
        == EXIT_FAILURE
    err = capsys.readouterr().err
    assert (f"error: cannot write {str(out / 'orbits.nc')!r}: no space left on the device of "
            f"directory {str(out)!r} (0 bytes free)") in err, err
    assert "RuntimeError" not in err and "OSError" not in err and ".tmp" not in err, err
    assert list(out.iterdir()) == []


def test_a_full_disk_is_refused_before_computing(
        tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str],
        no_computing: None) -> None:
    monkeypatch.setattr(dataset_io.os, "statvfs", lambda path: _statvfs(0))
    scene = write(tmp_path, ORBITS_SCENE)
    out = tmp_path / "o"
    out.mkdir()
    for extra in ([], ["--check"]):
        assert main(["run", str(scene), "--output", str(out), *extra]) == EXIT_USAGE
        err = capsys.readouterr().err
        assert (f"error: output directory {str(out)!r}: no space left on the device of "
                f"directory {str(out)!r} (0 bytes free); free some space") in err, err
    assert list(out.iterdir()) == []
