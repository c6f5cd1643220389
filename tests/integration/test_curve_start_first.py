"""``ic.curve(branch, "SE", ...)``: a branch dataset or a motion given where the oscillator
goes is the curve's start (the notes of issue 30 themselves wrote the SO curve so). Before,
it failed with "osc must be an ImpactOscillator; got <the whole dataset printed>", or, for a
kind of motions with sticking phases, with the misleading "kind must be one of ('SN', 'PD',
'NS', 'GR', 'ZV')". An index of a special point out of range names ``special``, the argument
of ``curve`` (it named ``which``, that of ``special_orbit``)."""

from __future__ import annotations

import numpy as np
import pytest
import xarray as xr

import impactcont as ic
from impactcont.errors import ParameterError
from impactcont.model.stops import Stops

BOX_NP = {"omega": (1.0, 4.0), "eta": (0.2, 0.4)}


@pytest.fixture(scope="module")
def ride_branch() -> xr.Dataset:
    """The riding damper of docs/two_parameter.md: the ball riding each wall ("ul"), its
    branch in omega with the end of the rides (SE) at omega 2.3934."""
    osc = ic.ImpactOscillator(M=np.diag([1.0, 0.2]), K=np.diag([1.0, 0.0]), F=[1.0, 0.0],
                              R=0.0, b=0.3, omega=2.3, eta=0.3,
                              stops=Stops(mass=2, relative_to=1, mirror=True))
    x1 = 1.0 / (1.0 - 1.2 * 2.3**2 + 0.6j * 2.3)
    state = np.array([x1.real, x1.real + 0.3, (2.3j * x1).real, (2.3j * x1).real])
    ride = ic.multi_impact_orbit(osc, 1, 2, ic.simulate(osc, state, 0.0, 20.0))
    branch = ic.continuation(ride, parameter="omega", bounds=(2.2, 2.45), ds_max=0.05,
                             both_directions=False)
    assert "SE" in branch["special_label"].values.tolist()
    return branch


def test_a_branch_given_first_is_the_start(ride_branch):
    kwargs = dict(parameters=("omega", "eta"), bounds=BOX_NP, ds_max=0.05)
    by_start = ic.curve(None, None, "SE", start=ride_branch, **kwargs)
    xr.testing.assert_identical(ic.curve(ride_branch, "SE", **kwargs).drop_attrs(),
                                by_start.drop_attrs())
    xr.testing.assert_identical(ic.curve(ride_branch, kind="SE", **kwargs).drop_attrs(),
                                by_start.drop_attrs())


def test_an_n1_branch_given_first_is_the_start(paper):
    branch = ic.continuation(paper.replace(b=0.0), N=1, parameter="omega",
                             bounds=(0.5, 6.0), components="start")
    kwargs = dict(parameters=("omega", "b"), bounds={"omega": (0.6, 2.0), "b": (-0.2, 0.2)})
    xr.testing.assert_identical(
        ic.curve(branch, "PD", **kwargs).drop_attrs(),
        ic.curve(None, None, "PD", start=branch, **kwargs).drop_attrs())


def test_what_cannot_be_meant_is_refused_by_name(ride_branch):
    kwargs = dict(parameters=("omega", "eta"), bounds=BOX_NP)
    with pytest.raises(ParameterError, match="kind is given twice: 'SE'"):
        ic.curve(ride_branch, "SE", "RG", **kwargs)
    with pytest.raises(ParameterError, match="give the branch or motion as start only"):
        ic.curve(ride_branch, None, "SE", start=ride_branch, **kwargs)
    with pytest.raises(ParameterError, match=r"special=1 is out of range: the branch has 1 SE"):
        ic.curve(ride_branch, "SE", special=1, **kwargs)
    with pytest.raises(ParameterError, match=r"special=0 is out of range: the branch has 0 RG"):
        ic.curve(ride_branch, "RG", **kwargs)
