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
    assert err.key == "curves[0].start"
    assert "not a [[branches]], [[multi_impact]] or [[switches]] entry" in str(err)
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


# -- maps over any two parameters, of any motion (issue 29, item 5) --------------------------
PLANE = ('[[maps]]\nname = "k2b"\nN = 1\nparameters = ["k2", "b"]\n'
         "ranges = { k2 = [1.5, 2.5], b = [0.4, 0.7] }\npoints = [5, 4]\n")


@pytest.mark.parametrize(("text", "key", "words"), [
    (PLANE.replace("ranges = { k2 = [1.5, 2.5], b = [0.4, 0.7] }", "ranges = { k2 = [1.5, 2.5] }"),
     "maps[0].ranges", "exactly the two parameters ['k2', 'b']"),
    (PLANE.replace("ranges = { k2 = [1.5, 2.5], b = [0.4, 0.7] }\npoints = [5, 4]\n",
                   "omega_range = [0.9, 1.6]\nb_range = [0.4, 0.7]\n"),
     "maps[0].omega_range", "ranges = {k2 = [lo, hi], b = [lo, hi]}"),
    (PLANE + "omega_range = [0.9, 1.6]\n", "maps[0].omega_range", "without omega_range"),
    (PLANE.replace("[1.5, 2.5]", "[-1.5, 2.5]"), "maps[0].ranges.k2", "> 0"),
    (PLANE.replace('"k2"', '"M[1,2]"').replace("k2 = [1.5, 2.5]", '"M[1,2]" = [0.5, 1.5]'),
     "maps[0].ranges", "M[1,2]"),
    (PLANE.replace("points = [5, 4]", "points = [5]"), "maps[0].points", "[n1, n2]"),
    (PLANE + "p = 2\n", "maps[0].p", "start = a [[simulations]] entry"),
    (PLANE + "memory_limit = 0\n", "maps[0].memory_limit", "> 0"),
    (PLANE + "k2 = 2.0\n", "maps[0].k2", None),
    (MAP + "points = [5, 4]\n", "maps[0].points", "ranges and points"),
    (PLANE.replace("N = 1", 'N = [1, 2]\nstart = "nope"\np = 1'), "maps[0].N", "one integer N"),
    (PLANE.replace("N = 1", 'N = 1\nstart = "nope"\np = 1'), "maps[0].start",
     "a [[simulations]] entry"),
])
def test_map_plane_and_motion_validation(tmp_path: Path, text: str, key: str, words) -> None:
    """Each key of a map over any two parameters, or of a motion's family, is refused by
    name with what is allowed."""
    err = error(tmp_path, text)
    assert err.key == key, (err.key, str(err))
    if words is not None:
        assert words in (err.allowed or "") or words in str(err), (str(err), err.allowed)


def test_a_scene_maps_an_element_and_the_gap(tmp_path: Path) -> None:
    """A [[maps]] entry over (k2, b): the closed form's map of stability_map over that pair."""
    import numpy as np
    import xarray as xr

    import impactcont as ic

    text = OSCILLATOR + PLANE + '[[plots]]\nname = "mp"\nkind = "map"\n'
    result = run_scene(write(tmp_path, text), output=tmp_path / "o")
    assert result.ok, result.failures
    ds = read_output(tmp_path / "o" / "maps.nc").datasets["k2b"]
    osc = load_scene(write(tmp_path, text)).sections["maps"][0].oscillator
    direct = ic.stability_map(osc, 1, parameters=("k2", "b"),
                              grid={"k2": np.linspace(1.5, 2.5, 5), "b": np.linspace(0.4, 0.7, 4)})
    assert ds.attrs["parameters"] == "k2,b" and dict(ds.sizes) == dict(direct.sizes)
    for key in ("exists", "n_stable", "stable", "physical"):
        xr.testing.assert_equal(ds[key], direct[key])
    assert (tmp_path / "o" / "mp.png").is_file()
    assert "k2 in [1.5, 2.5] x 5" in (tmp_path / "o" / "summary.md").read_text()


FAMILY = """
[[simulations]]
name = "settled"
omega = 1.8
periods = 200
perturbation = 1e-3

[[maps]]
name = "family"
start = "settled"
N = 2
p = 2
parameters = ["omega", "b"]
ranges = { omega = [1.76, 1.8], b = [-0.02, 0.02] }
points = [3, 3]
executor = "process"
max_workers = 2

[[plots]]
name = "fam"
kind = "map"
"""


def test_a_scene_maps_the_family_of_a_simulated_motion(tmp_path: Path) -> None:
    """A [[maps]] entry with start = a simulation, N and p: the map of the N-p family through
    the motion it settled on (the motion [[multi_impact]] starts its branch from), run on a
    process pool, the same as stability_map of that motion in this process."""
    import numpy as np
    import xarray as xr

    import impactcont as ic
    from impactcont.scene.switches import simulation_seed
    from impactcont.scene.twoparam import _MotionOf

    # the system of tests/scene/test_switches.py, whose simulation settles on a 2-2 motion
    system = OSCILLATOR.replace("b = 0.6", "b = 0.0").replace("omega = 1.0", "omega = 1.75")
    result = run_scene(write(tmp_path, system + FAMILY), output=tmp_path / "o")
    assert result.ok, result.failures
    ds = read_output(tmp_path / "o" / "maps.nc").datasets["family"]
    assert ds.attrs["impactcont_dataset"] == "multi_impact_map" and ds.attrs["start"] == "settled"
    assert (int(ds.attrs["N"]), int(ds.attrs["impacts"])) == (2, 2) and bool(ds["found"].all())
    assert '"executor": "process"' in ds.attrs["options"]
    sim = read_output(tmp_path / "o" / "simulations.nc").datasets["settled"]
    osc = ic.ImpactOscillator.from_json(sim.attrs["oscillator"])
    motion = ic.multi_impact_orbit(osc, 2, 2, simulation_seed(sim, _MotionOf("family", "settled",
                                                                           2, 2), osc))
    direct = ic.stability_map(motion, parameters=("omega", "b"),
                              grid={"omega": np.linspace(1.76, 1.8, 3),
                                    "b": np.linspace(-0.02, 0.02, 3)})
    for key in ("found", "stable", "physical", "newton_iterations"):
        xr.testing.assert_equal(ds[key], direct[key])
    np.testing.assert_allclose(ds["state_k"].values, direct["state_k"].values, rtol=0,
                               atol=1e-9)
    assert (tmp_path / "o" / "fam.png").is_file()
    assert "2-2 family" in (tmp_path / "o" / "summary.md").read_text()


NP_CURVE = """
[[branches]]
name = "N1"
b = 0.0
omega = 1.75
bounds = [1.6, 1.9]
detect = ["PD"]

[[switches]]
name = "two"
start = "N1"
detect = ["PD"]
ds_max = 0.02

[[curves]]
name = "pd4"
kind = "PD"
start = "two"
parameters = ["omega", "b"]
bounds = { omega = [1.5, 2.2], b = [-0.05, 0.05] }

[[plots]]
kind = "curves"
data = ["pd4"]
file = "pd4.png"
"""


def test_a_curve_of_the_n_p_motion_of_a_switch(tmp_path: Path) -> None:
    """[[curves]] from a [[switches]] entry (the 2-2 motion born at the PD of the N = 1
    branch): its PD curve in (omega, b), followed by shooting, is the one ``ic.curve``
    follows from the same branch (switches run before curves), drawn with the other curves
    and written with ``stable_side``."""
    import numpy as np

    import impactcont as ic

    result = run_scene(write(tmp_path, OSCILLATOR + NP_CURVE), output=tmp_path / "o")
    assert result.ok, result.failures
    two = read_output(tmp_path / "o" / "switches.nc").datasets["two"]
    scene = read_output(tmp_path / "o" / "curves.nc").datasets["pd4"]
    direct = ic.curve(None, None, "PD", start=two, parameters=("omega", "b"),
                      bounds={"omega": (1.5, 2.2), "b": (-0.05, 0.05)})
    assert scene.attrs["curve_kind"] == "PD" and int(scene.attrs["impacts"]) == 2
    np.testing.assert_allclose(scene["omega"].values, direct["omega"].values, atol=1e-10)
    np.testing.assert_allclose(scene["b"].values, direct["b"].values, atol=1e-10)
    assert (scene["stable_side"].values == direct["stable_side"].values).all()
    assert (tmp_path / "o" / "pd4.png").stat().st_size > 0
    assert "pd4" in (tmp_path / "o" / "summary.md").read_text()


@pytest.mark.parametrize(("change", "key", "words"), [
    ('start = "N1"\nkind = "SO"', "curves[0].kind", "N-p motions only"),
    ('start = "two"\nN = 2', "curves[0].N", "no N"),
    ('start = "two"\nparameters = ["b", "omega"]', "curves[0].parameters", "p1 is the "),
    ('start = "two"\nparameters = ["omega", "q7"]', "curves[0].parameters", "q7"),
])
def test_a_curve_from_an_n_p_branch_is_checked_before_it_runs(tmp_path: Path, change, key,
                                                             words) -> None:
    head, curve = NP_CURVE.split("[[plots]]")[0].split("[[curves]]")
    lines = [ln for ln in curve.splitlines()
             if not any(ln.startswith(c.split(" =")[0] + " =") for c in change.splitlines())]
    text = head + "[[curves]]" + "\n".join(lines).replace('name = "pd4"',
                                                          'name = "pd4"\n' + change)
    err = error(tmp_path, text)
    assert err.key == key and words in str(err) + (err.allowed or ""), (err.key, str(err))
