"""Bad input to the library's drivers is refused before anything is computed (issue 19)."""

from __future__ import annotations

import numpy as np
import pytest

import impactcont as ic


def two_stops(**kw) -> ic.ImpactOscillator:
    args = dict(M=np.eye(2), K=[[1.0, -1.0], [-1.0, 2.0]], F=[1.0, 0.0], R=0.6, eta=0.1, b=0.5,
                omega=1.2, stops=ic.Stops(mass=1, b_low=0.5))
    return ic.ImpactOscillator(**{**args, **kw})


@pytest.mark.parametrize("kind", ["SN", "PD", "NS", "GR", "ZV"])
def test_a_curve_refuses_stops_other_than_the_papers(kind):
    """The curve problem did not check the stops: it failed part way through computing."""
    with pytest.raises(ic.ParameterError, match="the codim-1 curves: the closed form"):
        ic.curve(two_stops(), 1, kind, start={"omega": 1.2, "b": 0.5},
                 bounds={"omega": (0.6, 2.0), "b": (0.0, 2.0)})
    with pytest.raises(ic.ParameterError, match="one stop on mass 1 only"):
        ic.curve(two_stops(stops=ic.Stops(mass=2)), 1, kind, start={"omega": 1.2, "b": 0.5},
                 bounds={"omega": (0.6, 2.0), "b": (0.0, 2.0)})
