"""Scenes a new user gets wrong are refused, never run silently wrong (issue 19).

An entry's oscillator keys combine with ``[oscillator]`` as if written into it; ``--check``
runs the argument checks of every entry's driver; a ``[[multi_impact]]`` p must be what its
simulation shows; a binary scene file and an absurd ``--dpi`` get clear messages.
"""

from __future__ import annotations

import math
import re
from collections.abc import Callable
from pathlib import Path

import numpy as np
import pytest
import xarray as xr
from matplotlib.figure import Figure

from impactcont import ImpactOscillator, Stops, continuation, robust_stability
from impactcont.analysis.curves import curve
from impactcont.cli import EXIT_OK, EXIT_USAGE, main
from impactcont.errors import ParameterError
from impactcont.scene import SceneError, load_scene, run_scene
from impactcont.scene.figures import plot_file, save_figure
from impactcont.scene.switches import MultiImpactSpec, simulation_seed
from tests._scene_data import ORBITS_SCENE, OSCILLATOR, write

ROOT = Path(__file__).resolve().parents[2]


def scene_error(tmp_path: Path, text: str) -> SceneError:
    with pytest.raises(SceneError) as info:
        load_scene(write(tmp_path, text))
    return info.value


def damped(line: str) -> str:
    """The test oscillator with ``line`` as its damping instead of ``eta = 0.1``."""
    return OSCILLATOR.replace("eta = 0.1", line)


# ---------------------------------------------------------------------------------------------
# An entry's keys are refused or combined exactly as in [oscillator]: none is dropped
# ---------------------------------------------------------------------------------------------
C = "C = [[0.2, 0.0], [0.0, 0.0]]"


@pytest.mark.parametrize(("damping", "entry", "fragment"), [
    (C, "eta = 0.3", "damping matrix C"),
    (C, "alpha = 0.3", "damping matrix C"),
    ("alpha = 0.1", "eta = 0.3", "either eta or alpha/beta"),
    ("eta = 0.1", "beta = 0.3", "either eta or alpha/beta"),
])
def test_an_entry_cannot_set_damping_that_oscillator_refuses(tmp_path: Path, damping: str,
                                                              entry: str, fragment: str) -> None:
    key = entry.split(" =")[0]
    # the same keys in [oscillator] alone are refused ...
    both = scene_error(tmp_path, damped(f"{damping}\n{entry}"))
    assert fragment in str(both)
    # ... and so is the entry that would combine them (it was stored without the C)
    err = scene_error(tmp_path, damped(damping) + f"[[orbits]]\n{entry}\n")
    assert err.key == f"orbits[0].{key}" and fragment in str(err)
    assert "[oscillator] has" in str(err) and err.line == 10


def test_an_entry_combines_keys_the_oscillator_takes_together(tmp_path: Path) -> None:
    text = damped("alpha = 0.1\nF_imag = [0.0, 0.5]") + "[[orbits]]\nbeta = 0.3\nF = [2.0, 0.0]\n"
    osc = load_scene(write(tmp_path, text)).entries("orbits")[0].oscillator
    assert (osc.alpha, osc.beta) == (0.1, 0.3)
    assert osc.F.tolist() == [2.0 + 0.0j, 0.0 + 0.5j]


def test_a_varied_parameter_set_by_a_robust_entry_is_refused(tmp_path: Path) -> None:
    err = scene_error(tmp_path, OSCILLATOR + "[[robust]]\nb = 0.3\nvary = { b = [0.2, 1.0] }\n")
    assert err.key == "robust[0].b" and "would not be used" in str(err)
    assert "nominal = { b = 0.3 }" in err.allowed


# ---------------------------------------------------------------------------------------------
# --check runs the checks of every entry's driver: no entry passes it and then fails its input
# ---------------------------------------------------------------------------------------------
_CLOSED_FORM = {
    "orbits": "[[orbits]]\n",
    "branches": "[[branches]]\nbounds = [1.1, 1.3]\n",
    "robust": "[[robust]]\nvary = { b = [0.5, 0.7] }\nsamples = 3\n",
    "curves": '[[curves]]\nkind = "PD"\nbounds = { omega = [1.0, 3.0], b = [0.0, 1.0] }\n',
    "maps": "[[maps]]\nomega_range = [1, 2]\nb_range = [0, 1]\nomega_points = 3\n"
            "b_points = 3\n",
    "simulations": "[[simulations]]\nperiods = 2\n",  # start = "orbit": the N-1 motion
}
_SIM = '[[simulations]]\nname = "sim"\nstart = "state"\nstate = [0, 0, 0, 0]\ndelta = 0.0\n' \
       'periods = 2\n'
_CASES = [
    *[(f"{key}, {stops}", OSCILLATOR + f"{stops}\n" + text,
       f"{key}[0]" + (".start" if key == "simulations" else ""), "one stop on mass 1 only")
      for stops in ("b_low = 0.5", "stop_mass = 2") for key, text in _CLOSED_FORM.items()],
    ("branches, elastic without damping", damped("eta = 0.0")
     + '[[branches]]\nparameter = "R"\nbounds = [0.5, 1.0]\n', "branches[0]", "elastic"),
    ("branches in F0", OSCILLATOR + '[[branches]]\nparameter = "F0"\nbounds = [0, 1.5]\n',
     "branches[0].bounds", "> 0"),
    ("curves in eta with C", damped(C) + '[[curves]]\nkind = "PD"\nparameters = ["eta", '
     '"omega"]\nbounds = { eta = [0, 1], omega = [1, 3] }\n', "curves[0].parameters",
     "damping matrix"),
    ("curves from the oscillator's b outside the box", OSCILLATOR + '[[curves]]\nkind = "PD"\n'
     'bounds = { omega = [1, 3], b = [0, 0.5] }\n', "curves[0].bounds", "b = 0.6"),
    ("switches out of the parameter's range", OSCILLATOR + '[[branches]]\nname = "N1"\n'
     'bounds = [1.6, 1.9]\n[[switches]]\nstart = "N1"\nbounds = [-1.0, 1.9]\n',
     "switches[0].bounds", "> 0"),
    ("multi_impact in eta with C", damped(C) + _SIM + '[[multi_impact]]\nstart = "sim"\nN = 1\n'
     'p = 1\nparameter = "eta"\nbounds = [0.0, 0.5]\n', "multi_impact[0].parameter",
     "damping matrix"),
    ("multi_impact in b closing the clearance", OSCILLATOR + "b_low = 0.5\n" + _SIM
     + '[[multi_impact]]\nstart = "sim"\nN = 1\np = 2\nparameter = "b"\nbounds = [-1.0, 1.0]\n',
     "multi_impact[0].bounds", "the clearance b + b_low between them closes"),
]


@pytest.mark.parametrize(("text", "key", "fragment"), [c[1:] for c in _CASES],
                         ids=[c[0] for c in _CASES])
def test_check_refuses_what_the_run_would_refuse(tmp_path: Path, text: str, key: str,
                                                 fragment: str,
                                                 capsys: pytest.CaptureFixture[str]) -> None:
    err = scene_error(tmp_path, text)
    assert err.key == key and fragment in str(err)
    path = tmp_path / "scene.toml"
    assert main(["run", str(path), "--check"]) == EXIT_USAGE
    assert f"{key}: " in capsys.readouterr().err
    assert main(["-q", "run", str(path), "--output", str(tmp_path / "o")]) == EXIT_USAGE
    assert not (tmp_path / "o").exists()  # refused before anything was computed


def _scene_oscillator(eta: float) -> ImpactOscillator:
    """The oscillator of ``OSCILLATOR`` with damping ``eta``."""
    return ImpactOscillator(M=np.eye(2), K=[[1.0, -1.0], [-1.0, 2.0]], F=[1.0, 0.0], R=0.6,
                            eta=eta, b=0.6, omega=1.0)


_SAME_CHECK = [
    ("continuation", damped("eta = 0.0") + '[[branches]]\nparameter = "R"\nbounds = [0.5, 1.0]\n',
     lambda: continuation(_scene_oscillator(0.0), 1, "R", (0.5, 1.0))),
    ("robust_stability", OSCILLATOR + '[[robust]]\nvary = { "F[0]" = [0.0, 1.0] }\n',
     lambda: robust_stability(_scene_oscillator(0.1), 1, {"F[0]": (0.0, 1.0)})),
    ("curve", damped(C) + '[[curves]]\nkind = "PD"\nparameters = ["eta", "omega"]\n'
     'bounds = { eta = [0, 1], omega = [1, 3] }\n',
     lambda: curve(_scene_oscillator(0.1).replace(eta=None, C=[[0.2, 0.0], [0.0, 0.0]]), 1,
                   "PD", parameters=("eta", "omega"), bounds={"eta": (0, 1), "omega": (1, 3)})),
]


@pytest.mark.parametrize(("text", "run"), [c[1:] for c in _SAME_CHECK],
                         ids=[c[0] for c in _SAME_CHECK])
def test_check_and_driver_refuse_with_the_same_message(tmp_path: Path, text: str,
                                                       run: Callable[[], object]) -> None:
    # --check runs the driver's own argument check: the very same message
    err = scene_error(tmp_path, text)
    with pytest.raises(ParameterError) as driver:
        run()
    assert err.problem == str(driver.value)


def test_check_refuses_the_main_job_with_the_stop_on_mass_2(
        capsys: pytest.CaptureFixture[str]) -> None:
    scene = str(ROOT / "studies/main_job/scene.toml")
    assert main(["run", scene, "--check", "--set", "oscillator.stop_mass=2"]) == EXIT_USAGE
    assert "orbits[0]: the N-1 closed form" in capsys.readouterr().err
    assert main(["-q", "run", scene, "--check"]) == EXIT_OK


# ---------------------------------------------------------------------------------------------
# [[multi_impact]]: p must be what the simulation shows
# ---------------------------------------------------------------------------------------------
BACKLASH = """
[oscillator]
masses = [1.0, 1.0]
springs = [1.0, 1.0]
F = [1.0, 0.0]
R = 0.6
eta = 0.1
b = 0.5
b_low = 0.5
omega = 1.6

[[simulations]]
name = "settled"
start = "state"
state = [0.0, 0.0, 0.0, 0.0]
delta = 0.0
periods = 60

[[multi_impact]]
name = "ulu"
start = "settled"
N = 1
p = 3
bounds = [1.5, 1.7]
"""


def test_a_p_the_simulation_does_not_show_is_refused(tmp_path: Path) -> None:
    """The simulation settles on the symmetric 1-2 motion (one impact on each stop per
    period): p = 3 was solved as a "ULU" motion, none of its points physical."""
    result = run_scene(write(tmp_path, BACKLASH), output=tmp_path / "o")
    (failure,) = result.failures
    assert failure.name == "ulu" and failure.error.startswith("ParameterError")
    assert "shows 2 impact(s) in its last N = 1 forcing period(s) (stops 'UL')" in failure.error
    assert "allowed: p = 2 with N = 1" in failure.error
    assert not (tmp_path / "o" / "multi_impact.nc").exists()


def oscillator(omega: float) -> ImpactOscillator:
    return ImpactOscillator(M=np.eye(2), K=[[1.0, -1.0], [-1.0, 2.0]], F=[1.0, 0.0], R=0.6,
                            b=0.5, omega=omega, eta=0.1, stops=Stops(b_low=0.5))


def simulation(times: list[float], stops: str, osc: ImpactOscillator) -> xr.Dataset:
    """A simulation dataset with impacts at ``times`` (in forcing periods) on ``stops``."""
    t = np.array(times) * 2.0 * math.pi / osc.omega
    return xr.Dataset({"impact_times": ("impact", t),
                       "impact_phases": ("impact", np.zeros(t.size)),
                       "impact_states": (("impact", "component"), np.zeros((t.size, 4)))},
                      attrs={"impact_stops": stops, "oscillator": osc.to_json()})


def entry(N: int, p: int) -> MultiImpactSpec:
    return MultiImpactSpec(name="np", start="sim", N=N, p=p, bounds=(0.5, 2.0))


def test_the_seed_takes_the_impacts_of_n_periods() -> None:
    # a 1-2 motion: impacts 0.38 and 0.62 periods apart, upper then lower stop
    times = [k + d for k in range(10) for d in (0.0, 0.38)]
    osc = oscillator(1.3)
    sim = simulation(times, "UL" * 10, osc)
    seed = simulation_seed(sim, entry(1, 2), osc)  # the last p + 1 impacts, no sticking
    assert seed.impact_stops[:-1] == "LU"  # the stops of the impacts that start the flights
    assert np.allclose(np.diff(seed.impact_times) * 1.3 / (2 * math.pi), [0.62, 0.38])
    assert seed.sticking == ()
    assert simulation_seed(sim, entry(2, 4), osc).impact_stops[:-1] == "LULU"  # twice
    for N, p, shown in ((1, 1, "2 impact(s)"), (1, 3, "2 impact(s)"), (2, 3, "4 impact(s)")):
        with pytest.raises(ParameterError, match=rf"shows {re.escape(shown)} in its last "
                                                 rf"N = {N} forcing period\(s\) \(stops "
                                                 rf"'(UL)+'\), not p = {p}"):
            simulation_seed(sim, entry(N, p), osc)


def test_a_simulation_that_has_not_settled_is_named() -> None:
    osc = oscillator(1.0)
    sparse = simulation([0.0, 3.0, 6.0, 9.0], "UUUU", osc)  # one impact every 3 periods
    with pytest.raises(ParameterError, match=r"shows 1 impact\(s\) in its last N = 2 .* "
                                             r"has not settled"):
        simulation_seed(sparse, entry(2, 1), osc)
    short = simulation([0.0, 0.3, 0.6], "UUU", osc)
    with pytest.raises(ParameterError, match=r"span 0.6 forcing periods, fewer than N = 1"):
        simulation_seed(short, entry(1, 1), osc)
    flipped = simulation([0.0, 0.5, 1.0, 1.5, 2.0], "UULUU", osc)  # 1 period back: L
    with pytest.raises(ParameterError, match="hit the lower stop and the last the other"):
        simulation_seed(flipped, entry(1, 2), osc)


# ---------------------------------------------------------------------------------------------
# Clear messages: a binary scene file, an absurd --dpi
# ---------------------------------------------------------------------------------------------
@pytest.mark.parametrize(("content", "fragment"), [
    (b"\x89PNG\r\n\x1a\n\x00\x00\x00\rIHDR", "not a UTF-8 TOML scene: byte 0x89 at offset 0"),
    (b'title = "x"\x00\n', "not a TOML scene: it holds a NUL byte at offset 11"),
])
def test_a_binary_file_is_not_a_scene(tmp_path: Path, content: bytes, fragment: str,
                                      capsys: pytest.CaptureFixture[str]) -> None:
    path = tmp_path / "picture.toml"
    path.write_bytes(content)
    with pytest.raises(SceneError) as info:
        load_scene(path)
    assert str(info.value).startswith(f"{path}: {fragment}")
    assert main(["run", str(path), "--check"]) == EXIT_USAGE
    err = capsys.readouterr().err
    assert f"error: {path}: {fragment}" in err and "codec" not in err
    assert main(["run", str(tmp_path), "--check"]) == EXIT_USAGE
    assert f"{tmp_path}: is a directory, not a scene file" in capsys.readouterr().err


def test_a_scene_with_a_byte_order_mark_reads(tmp_path: Path) -> None:
    path = tmp_path / "scene.toml"
    path.write_bytes(b"\xef\xbb\xbf" + ORBITS_SCENE.encode("utf-8"))
    assert load_scene(path).title == "orbits only"


@pytest.mark.parametrize("dpi", ["100000", "0", "-5", "9"])
def test_plot_refuses_a_dpi_out_of_range(tmp_path: Path, dpi: str,
                                         capsys: pytest.CaptureFixture[str]) -> None:
    out = tmp_path / "o"
    assert main(["-q", "run", str(write(tmp_path, ORBITS_SCENE)), "-o", str(out)]) == EXIT_OK
    png = tmp_path / "x.png"
    assert main(["plot", str(out / "orbits.nc"), "-o", str(png), "--dpi", dpi]) == EXIT_USAGE
    assert f"dpi must be an integer in [10, 1200] (dots per inch of the image); got {dpi}" \
        in capsys.readouterr().err
    assert not png.exists()
    with pytest.raises(ParameterError, match="dpi must be an integer in"):
        plot_file(out / "orbits.nc", png, dpi=int(dpi))
    err = scene_error(tmp_path, ORBITS_SCENE + f"[output]\ndpi = {dpi}\n")
    assert err.key == "output.dpi" and err.allowed == "an integer in [10, 1200]"


def test_a_figure_too_large_to_draw_is_refused(tmp_path: Path) -> None:
    fig = Figure(figsize=(40.0, 30.0))
    with pytest.raises(ParameterError, match=r"48000 x 36000 pixels, more than 1e\+08; "
                                             r"allowed: dpi <= 288 for it"):
        save_figure(fig, tmp_path / "big.png", 1200)
    assert not (tmp_path / "big.png").exists()


# ---------------------------------------------------------------------------------------------
# issue 28: what a new user found
# ---------------------------------------------------------------------------------------------
_BRANCH_AND_MULTI = OSCILLATOR.replace("b = 0.6", "b = 0.0").replace("omega = 1.0", "omega = 1.8") \
    + """
[[simulations]]
name = "s"
periods = 50

[[multi_impact]]
name = "mi"
start = "s"
N = 1
p = 1
bounds = [1.6, 1.9]

[[branches]]
name = "br"
bounds = [1.6, 1.9]
"""


def test_a_plot_lists_each_entry_under_its_own_table(tmp_path: Path) -> None:
    err = scene_error(tmp_path, _BRANCH_AND_MULTI + '[[plots]]\nkind = "bifurcation_diagram"\n'
                      'data = ["nope"]\n')
    assert err.key == "plots[0].data[0]"
    assert "'nope' is not an entry of [[branches]], [[switches]] or [[multi_impact]]" in str(err)
    assert err.allowed == "[[branches]]: br; [[multi_impact]]: mi"


def test_check_refuses_a_pitchfork_switch_from_an_n1_branch(tmp_path: Path) -> None:
    err = scene_error(tmp_path, _BRANCH_AND_MULTI + '[[switches]]\nname = "w"\nstart = "br"\n'
                      'at = "BP"\n')
    assert err.key == "switches[0].at" and "an N-1 motion is never symmetric" in str(err)


def test_a_side_at_a_period_doubling_switch_is_refused(tmp_path: Path) -> None:
    err = scene_error(tmp_path, _BRANCH_AND_MULTI + '[[switches]]\nname = "w"\nstart = "br"\n'
                      'side = -1\n')
    assert err.key == "switches[0].side" and '-1 is only used with at = "BP"' in str(err)


def test_a_bad_element_parameter_is_reported_at_parameter(tmp_path: Path) -> None:
    text = _BRANCH_AND_MULTI.replace('p = 1\n', 'p = 1\nparameter = "m9"\n')
    err = scene_error(tmp_path, text)
    assert err.key == "multi_impact[0].parameter" and "'m9'" in str(err) and "m1..m2" in str(err)


def test_bounds_of_a_stiffness_entry_are_checked_against_the_rest_of_k(tmp_path: Path) -> None:
    # K = [[t, -1], [-1, 2]] is positive semi-definite for t >= 1/2 only
    text = _BRANCH_AND_MULTI.replace('p = 1\nbounds = [1.6, 1.9]',
                                     'p = 1\nparameter = "K[1,1]"\nbounds = [-1.0, 3.0]')
    err = scene_error(tmp_path, text)
    assert err.key == "multi_impact[0].bounds", err
    assert "at K[1,1] = -1.0 the oscillator is refused" in str(err)
    assert "K[1,1] in [0.5, inf)" in str(err)
    text = _BRANCH_AND_MULTI.replace('name = "br"\nbounds = [1.6, 1.9]',
                                     'name = "br"\nparameter = "K[1,1]"\nbounds = [-1.0, 3.0]')
    err = scene_error(tmp_path, text)
    assert err.key == "branches[0].bounds" and "K[1,1] in [0.5, inf)" in str(err)


def test_a_start_state_is_checked_on_the_clearance_between_masses(tmp_path: Path) -> None:
    pair = OSCILLATOR + "stop_mass = 2\nstop_relative_to = 1\nmirror_stop = true\n"
    sim = '[[simulations]]\nstart = "state"\ndelta = 0.0\nperiods = 2\n'
    # outside the clearance (x2 - x1 = 0.7 > b = 0.6): refused by --check, not by the run
    err = scene_error(tmp_path, pair + sim + "state = [1.0, 1.7, 0.0, 0.0]\n")
    assert err.key == "simulations[0].state" and "x2 - x1 = 0.7 is beyond stop 'U'" in str(err)
    # inside it (x2 = 1.6 > b, but x2 - x1 = 0.1): accepted, and the run takes it
    scene = load_scene(write(tmp_path, pair + sim + "state = [1.5, 1.6, 0.0, 0.0]\n"))
    assert run_scene(scene).ok
