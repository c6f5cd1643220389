"""summary.md and ``impactcont info`` (issue 31): the stop reason names the parameter, a
special point that is not physical says why (and which point it mirrors at b = 0), rho(G) of
a ZV point is unbounded, a root that is not physical shows no stability."""

from __future__ import annotations

import numpy as np

import impactcont as ic
from impactcont.core import ContinuationOptions
from impactcont.core.driver import follow
from impactcont.scene.tasks import NOT_PHYSICAL, ZV_RADIUS, orbits_dataset, special_points_table

PAPER = dict(M=[[1.0, 0.0], [0.0, 1.0]], K=[[1.0, -1.0], [-1.0, 2.0]], F=[1.0, 0.0], R=0.6,
             eta=0.1)


class _Line:
    """``u - lam = 0`` continued in a parameter named ``omega``."""

    parameter = "omega"

    def residual(self, u, lam):
        return np.array([u[0] - lam])

    def jacobian(self, u, lam):
        return np.array([[1.0]])

    def dparam(self, u, lam):
        return np.array([-1.0])


def test_the_stop_reason_names_the_parameter() -> None:
    options = ContinuationOptions(bounds=(0.0, 1.0), ds=0.1, ds_max=0.3)
    result = follow(_Line(), [0.5], 0.5, options)
    assert result.message == "parameter bound reached: omega = 1"


def _point(**changes):
    base = {"branch": "b0", "N": 1, "parameter": "omega", "label": "PD", "value": 1.700383,
            "omega": 1.700383, "b": 0.0, "delta": 1.59683, "status": "located",
            "precision": 1e-14, "rho": 1.0, "physical": True, "why": ""}
    return {**base, **changes}


def test_special_points_say_why_not_physical_and_zv_is_a_pole() -> None:
    from impactcont.scene.tasks import _mirrors_noted

    points = _mirrors_noted([
        _point(), _point(delta=1.59683 + np.pi, physical=False,
                         why="impact velocity -0.905 <= 0: mass 1 does not arrive towards "
                             "the stop"),
        _point(label="ZV", b=0.5, rho=1.36e13, value=1.21, omega=1.21)])
    lines = special_points_table(points)
    assert lines[0].endswith("| why not physical |")
    assert "mirror image (x -> -x, delta + pi) of the PD at delta = 1.59683" in lines[3]
    assert "impact velocity -0.905 <= 0" in lines[3]
    assert ZV_RADIUS in lines[4] and "1.36e+13" not in lines[4]


def test_a_root_that_is_not_physical_shows_no_stability() -> None:
    from impactcont.scene.tasks import ORBITS

    osc = ic.ImpactOscillator(**PAPER, b=0.6, omega=1.0)
    orbits = ic.periodic_orbits(osc, 1)
    ds = orbits_dataset(orbits, osc, 1)
    ds.attrs["name"] = "paper"
    rows = ORBITS.describe({"paper": ds})[2:]
    for row, orbit in zip(rows, orbits, strict=True):
        cells = [c.strip() for c in row.split("|")]
        assert (NOT_PHYSICAL in cells) == (not orbit.physical)
    assert any(not o.physical and o.stable for o in orbits)  # the case of the issue
