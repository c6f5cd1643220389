"""Scenes a new user gets wrong are refused, never run silently wrong (issue 19).

An entry's oscillator keys combine with ``[oscillator]`` as if written into it.
"""

from __future__ import annotations

from pathlib import Path

import pytest
from _scene_data import OSCILLATOR, write

from impactcont.scene import SceneError, load_scene


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
