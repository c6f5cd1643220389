"""Files of the machines of issue 21: a branch of a loaded impact pair and of an impact
damper (a free ball in a cavity) survives save and load, the oscillator rebuilt from the
file is the one continued (stops between masses, the constant force, the free mass), a
stored point is a motion of it, and every group passes the CF checker."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

import impactcont as ic
from impactcont.dataset import oscillator_from_dataset
from tests.integration.test_cf_files import _check
from tests.integration.test_machine_branches import damper, loaded, settled


@pytest.fixture(scope="module")
def loaded_branch():
    orbit = settled(loaded(), 1, 1, [0.0, 0.0, 0.0, 0.5], 200.0)
    return ic.multi_impact_continuation(orbit, parameter="omega", bounds=(1.5, 1.7),
                                        max_points=25)


@pytest.fixture(scope="module")
def damper_branch():
    orbit = settled(damper(), 1, 2, [0.0, 0.0, 0.0, 1.0], 150.0)
    return ic.multi_impact_continuation(orbit, parameter="b", bounds=(0.9, 1.1),
                                        max_points=25)


@pytest.mark.parametrize("which", ["loaded", "damper"])
def test_a_machine_branch_survives_its_file(which, loaded_branch, damper_branch,
                                            tmp_path: Path) -> None:
    branch = loaded_branch if which == "loaded" else damper_branch
    built = loaded() if which == "loaded" else damper()
    path = tmp_path / "branch.nc"
    ic.save(branch, path)
    back = ic.load(path)
    k = int(back.sizes["point"]) // 2
    osc = oscillator_from_dataset(back, k)
    assert osc.stops == built.stops and osc.stops.relative_to is not None
    np.testing.assert_array_equal(osc.F_static, built.F_static)
    np.testing.assert_array_equal(osc.K, built.K)
    np.testing.assert_array_equal(osc.M, built.M)
    assert osc.free_modes.shape[1] == (1 if which == "damper" else 0)
    # the stored point is a motion of the rebuilt oscillator: Newton started from the
    # stored impact states returns them (within Newton's guarantee)
    p = int(back.sizes["impact"])
    guess = {"delta": float(back.delta_k.values[k, 0]),
             "flight_times": back.flight_time_k.values[k],
             "states": back.state_k.values[k]}
    again = ic.multi_impact_orbit(osc, 1, p, guess, pattern=str(back.attrs["pattern"]))
    np.testing.assert_allclose(again.states, back.state_k.values[k], atol=1e-9)
    failed, crashed = _check(path)
    assert failed == [] and crashed == {}
