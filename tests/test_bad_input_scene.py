"""Scenes a new user gets wrong are refused, never run silently wrong (issue 19).

An entry's oscillator keys combine with ``[oscillator]`` as if written into it; ``--check``
runs the argument checks of every entry's driver.
"""

from __future__ import annotations

from pathlib import Path

import pytest
from _scene_data import OSCILLATOR, write

from impactcont.cli import EXIT_OK, EXIT_USAGE, main
from impactcont.scene import SceneError, load_scene

ROOT = Path(__file__).resolve().parents[1]


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


def test_check_refuses_the_main_job_with_the_stop_on_mass_2(
        capsys: pytest.CaptureFixture[str]) -> None:
    scene = str(ROOT / "studies/main_job/scene.toml")
    assert main(["run", scene, "--check", "--set", "oscillator.stop_mass=2"]) == EXIT_USAGE
    assert "orbits[0]: the N-1 closed form" in capsys.readouterr().err
    assert main(["-q", "run", scene, "--check"]) == EXIT_OK
