"""Diagrams of every impact (:mod:`impactcont.plots.impacts`): an N-1 branch draws one curve
and an N-p branch p curves, each through the branch's own values of the per-impact quantity;
special points marked on every impact; the legend names each branch with its N-p, the axes
name the parameter and the quantity; bad arguments refused by name."""

from __future__ import annotations

import matplotlib
import numpy as np
import pytest
import xarray as xr
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure

import impactcont as ic
from impactcont.model.stops import Stops
from impactcont.plots import SPECIAL_MARKERS
from impactcont.plots.branches import NONPHYSICAL_GREY, NONPHYSICAL_MARKER
from impactcont.plots.impacts import IMPACT_QUANTITIES, impact_diagram, impact_label

matplotlib.use("Agg")

PAPER = ic.ImpactOscillator(M=np.eye(2), K=[[1.0, -1.0], [-1.0, 2.0]], F=[1.0, 0.0], R=0.6,
                            b=0.0, omega=1.75, eta=0.1)


@pytest.fixture(scope="module")
def n1() -> xr.Dataset:
    return ic.continuation(PAPER, N=1, bounds=(1.6, 1.9), detect=("PD",))


@pytest.fixture(scope="module")
def two(n1) -> xr.Dataset:
    return ic.period_doubling_switch(n1, 0, ds_max=0.05, detect=())


def _axes():
    fig = Figure(figsize=(6.0, 5.0), layout="constrained")
    FigureCanvasAgg(fig)
    return fig.add_subplot()


def _curve_points(ax, color: str) -> set[tuple[float, float]]:
    """The (x, y) vertices of the curves (no markers) drawn in ``color``."""
    out = set()
    for line in ax.get_lines():
        if line.get_color() == color and line.get_marker() in ("None", "", None, "none"):
            out |= {(float(x), float(y)) for x, y in line.get_xydata()}
    return out


@pytest.mark.parametrize("y", list(IMPACT_QUANTITIES))
def test_each_impact_of_each_branch_is_a_curve_through_its_values(n1, two, y) -> None:
    ax = impact_diagram({"n1": n1, "two": two}, y=y, ax=_axes(), physical_range=False)
    one = IMPACT_QUANTITIES[y]
    expected_n1 = {(float(x), float(v)) for x, v in zip(n1["omega"].values, n1[one].values,
                                                        strict=True)}
    expected_two = {(float(x), float(v)) for x, row in zip(two["omega"].values, two[y].values,
                                                           strict=True) for v in row}
    assert _curve_points(ax, "C0") == expected_n1
    assert _curve_points(ax, "C1") == expected_two
    if y != "gap_min_k":  # (no interior maximum: +inf, the same vertex)
        assert len(expected_two) == 2 * two.sizes["point"]


def test_the_legend_and_axes_name_the_branches_the_parameter_and_the_quantity(n1, two) -> None:
    ax = impact_diagram({"n1": n1, "two": two}, ax=_axes())
    texts = [t.get_text() for t in ax.get_legend().get_texts()]
    assert "n1 (1-1)" in texts and "two (2-2)" in texts
    assert "stable" in texts and any(t.startswith("PD") for t in texts)
    assert ax.get_xlabel() == r"forcing frequency $\omega$"
    assert ax.get_ylabel() == impact_label(n1, "impact_velocity_k") == \
        r"impact velocity $\dot{x}_1(T_k^-)$"
    # the system held fixed: b, R, eta of the oscillator (omega is on the axis)
    assert ax.get_title() == (r"Period-$N$ motions with $p$ impacts, $b = 0$, $R = 0.6$, "
                              r"$\eta = 0.1$")


def _marks(ax, label: str) -> np.ndarray:
    lines = [line for line in ax.get_lines() if line.get_marker() == SPECIAL_MARKERS[label]]
    return np.unique(np.concatenate([line.get_xydata() for line in lines]), axis=0)


def test_the_period_doublings_are_marked_where_they_were_found(n1) -> None:
    """Both roots of eq. (15) double their period at the same omega: the physical one
    (impact velocity > 0) and the non-physical one, drawn only when the range is not fitted
    to the physical motions."""
    pd = n1["special_label"].values == "PD"
    expected = np.column_stack([n1["special_omega"].values[pd],
                                n1["special_impact_velocity"].values[pd]])
    every = impact_diagram(n1, ax=_axes(), specials=("PD",), physical_range=False)
    # the non-physical root's: a small grey circle, like every point of a non-physical motion
    grey = np.concatenate([line.get_xydata() for line in every.get_lines()
                           if line.get_marker() == NONPHYSICAL_MARKER
                           and line.get_markeredgecolor() == NONPHYSICAL_GREY])
    np.testing.assert_array_equal(np.unique(np.vstack([_marks(every, "PD"), grey]), axis=0),
                                  np.unique(expected, axis=0))
    np.testing.assert_array_equal(_marks(every, "PD"), expected[expected[:, 1] > 0])
    physical = impact_diagram(n1, ax=_axes(), specials=("PD",))
    np.testing.assert_array_equal(_marks(physical, "PD"), expected[expected[:, 1] > 0])
    none = impact_diagram(n1, ax=_axes(), specials=())
    assert not [line for line in none.get_lines() if line.get_marker() not in ("None", "")]


def test_a_two_sided_branch_plots_the_speed_towards_the_stop(n1) -> None:
    osc = PAPER.replace(b=0.5, stops=Stops(mirror=True))
    ds = n1.assign_attrs(oscillator=osc.to_json(), pattern="U")
    assert impact_label(ds, "impact_velocity_k") == \
        r"impact speed towards the stop hit $|\dot{x}_1(T_k^-)|$"
    assert impact_label(ds, "delta_k") == r"impact phase $\theta_k$ [rad]"
    assert impact_label(ds, "gap_min_k") == "minimum gap of flight $k$ (mass 1)"


@pytest.mark.parametrize(("kwargs", "match"), [
    ({"y": "flight_time"}, r"y must be one of \['delta_k', 'gap_min_k', 'impact_velocity_k'\]; "
                           r"got 'flight_time'"),
    ({"specials": ("PD", "XY")}, r"specials must be a subset of .*; got unknown \['XY'\]"),
    ({"legend": "above"}, r"legend must be one of .*; got 'above'"),
])
def test_a_bad_argument_is_named(n1, kwargs, match) -> None:
    with pytest.raises(ValueError, match=match):
        impact_diagram(n1, ax=_axes(), **kwargs)


def test_branches_in_different_parameters_are_refused(n1) -> None:
    in_b = ic.continuation(PAPER, N=1, parameter="b", bounds=(-0.1, 0.1), detect=())
    with pytest.raises(ValueError, match="parameter"):
        impact_diagram([n1, in_b], ax=_axes())


def test_the_legend_names_only_the_branches_drawn(n1, two) -> None:
    """Without non-physical parts, a branch with no physical motion draws nothing: no
    legend entry (the cascades study listed five branches nobody could see)."""
    hidden = two.copy(deep=True)
    hidden["physical"][:] = False
    ax = impact_diagram({"n1": n1, "two": two, "hidden": hidden}, ax=_axes(),
                        nonphysical=False)
    texts = [t.get_text() for t in ax.get_legend().get_texts()]
    assert "n1 (1-1)" in texts and "two (2-2)" in texts
    assert not [t for t in texts if t.startswith("hidden")]
