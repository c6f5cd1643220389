"""The ``[[curves]]`` and ``[[maps]]`` scene sections (two-parameter continuation, issue 4)."""

from __future__ import annotations

from pathlib import Path

import pytest

from impactcont.cli import EXIT_OK, main
from impactcont.scene import SceneError, load_scene, read_output, run_scene, scene_sections
from tests._scene_data import OSCILLATOR, write

pytestmark = pytest.mark.skipif("curves" not in scene_sections(),
                                reason="impactcont.analysis.curves / .maps not present")

BRANCH = '[[branches]]\nname = "br"\nb = 0.5\nbounds = [0.9, 1.5]\n'
BOX = "bounds = { omega = [0.9, 1.6], b = [0.45, 0.7] }\n"


def error(tmp_path: Path, text: str) -> SceneError:
    with pytest.raises(SceneError) as info:
        load_scene(write(tmp_path, OSCILLATOR + text))
    return info.value


def test_curve_validation(tmp_path: Path) -> None:
    err = error(tmp_path, '[[curves]]\nkind = "XX"\n' + BOX)
    assert err.key == "curves[0].kind" and '"SN"' in err.allowed
    err = error(tmp_path, '[[curves]]\nkind = "SN"\nbounds = { omega = [0.9, 1.6] }\n')
    assert err.key == "curves[0].bounds" and "['omega', 'b']" in err.allowed
    err = error(tmp_path, '[[curves]]\nkind = "SN"\nstart = "nope"\n' + BOX)
    assert err.key == "curves[0].start" and "not a [[branches]] entry" in str(err)
    err = error(tmp_path, BRANCH.replace('bounds = [0.9, 1.5]', 'parameter = "R"\n'
                                         'bounds = [0.1, 0.9]')
                + '[[curves]]\nkind = "SN"\nstart = "br"\n' + BOX)
    assert err.key == "curves[0].start" and "continued in 'R'" in str(err)
    err = error(tmp_path, BRANCH + '[[curves]]\nkind = "SN"\nstart = "br"\nR = 0.5\n' + BOX)
    assert err.key == "curves[0].R" and "branch's oscillator" in str(err)
    err = error(tmp_path, '[[curves]]\nkind = "SN"\nstart = { omega = 1.2 }\n' + BOX)
    assert err.key == "curves[0].start" and "lacks ['b']" in str(err)
    err = error(tmp_path, '[[curves]]\nkind = "SN"\nparameters = ["omega", "omega"]\n' + BOX)
    assert err.key == "curves[0].parameters"


def test_map_validation(tmp_path: Path) -> None:
    err = error(tmp_path, "[[maps]]\nomega_range = [0, 2]\nb_range = [0, 1]\n")
    assert err.key == "maps[0].omega_range" and "> 0" in err.allowed
    err = error(tmp_path, "[[maps]]\nomega_range = [0.5, 2]\nb_range = [0, 1]\nomega = 1.0\n")
    assert err.key == "maps[0].omega" and "omega_range" in err.allowed
    err = error(tmp_path, "[[maps]]\nN = [1, 1]\nomega_range = [0.5, 2]\nb_range = [0, 1]\n")
    assert err.key == "maps[0].N"


def test_curve_from_a_branch_and_a_map(tmp_path: Path) -> None:
    text = (BRANCH + '[[curves]]\nname = "sn"\nkind = "SN"\nstart = "br"\n' + BOX
            + "ds_max = 0.1\n"
            + '[[maps]]\nname = "m"\nN = 1\nomega_range = [0.9, 1.6]\nomega_points = 8\n'
              "b_range = [0.45, 0.7]\nb_points = 6\n"
            + '[[plots]]\nname = "c"\nkind = "curves"\n[[plots]]\nname = "mp"\nkind = "map"\n')
    result = run_scene(write(tmp_path, OSCILLATOR + text), output=tmp_path / "o")
    assert result.ok, result.failures
    curve = read_output(tmp_path / "o" / "curves.nc").datasets["sn"]
    assert curve.attrs["kind"] == "SN" and curve.sizes["point"] > 2
    assert read_output(tmp_path / "o" / "maps.nc").datasets["m"].sizes["omega"] == 8
    assert (tmp_path / "o" / "c.png").is_file() and (tmp_path / "o" / "mp.png").is_file()
    assert "## Two-parameter curves" in (tmp_path / "o" / "summary.md").read_text()
    for name in ("curves", "maps"):
        assert main(["info", str(tmp_path / "o" / f"{name}.nc")]) == EXIT_OK
        assert main(["plot", str(tmp_path / "o" / f"{name}.nc"), "--dpi", "40"]) == EXIT_OK
        assert (tmp_path / "o" / f"{name}.png").is_file()


MAP = '[[maps]]\nname = "m"\nN = 1\nomega_range = [0.9, 1.6]\nomega_points = 8\n' \
      "b_range = [0.45, 0.7]\nb_points = 6\n"


def test_map_executor_validation(tmp_path: Path) -> None:
    err = error(tmp_path, MAP + 'executor = "threads"\n')
    assert err.key == "maps[0].executor" and '"dask"' in err.allowed
    err = error(tmp_path, MAP + 'executor = "dask"\n')
    assert err.key == "maps[0].scheduler" and "needs the address" in str(err)
    assert "tcp://10.0.0.5:8786" in err.allowed
    err = error(tmp_path, MAP + 'executor = "dask"\nscheduler = "10.0.0.5:8786"\n')
    assert err.key == "maps[0].scheduler" and "protocol://host:port" in err.allowed
    err = error(tmp_path, MAP + 'scheduler = "tcp://10.0.0.5:8786"\n')
    assert err.key == "maps[0].scheduler" and 'executor is "serial"' in str(err)
    err = error(tmp_path, MAP + 'executor = "dask"\nscheduler = "tcp://h:8786"\n'
                'max_workers = 2\n')
    assert err.key == "maps[0].max_workers" and "workers decide" in str(err)
    for address in ("tcp://10.0.0.5:8786", "tls://scheduler.example.org:8786",
                    "tcp://[::1]:8786", "tcp://localhost"):
        text = OSCILLATOR + MAP + f'executor = "dask"\nscheduler = "{address}"\n'
        load_scene(write(tmp_path, text))


def test_a_scene_map_on_a_dask_scheduler(tmp_path: Path) -> None:
    distributed = pytest.importorskip("dask.distributed")
    with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=False,
                                  protocol="tcp://", dashboard_address=None) as cluster:
        address = cluster.scheduler_address
        text = OSCILLATOR + MAP + f'executor = "dask"\nscheduler = "{address}"\n'
        result = run_scene(write(tmp_path, text), output=tmp_path / "o")
        assert result.ok, result.failures
        ds = read_output(tmp_path / "o" / "maps.nc").datasets["m"]
        assert '"executor": "dask.distributed"' in ds.attrs["options"]
        assert ds.sizes["omega"] == 8 and bool(ds["exists"].any())
