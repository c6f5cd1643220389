"""Bifurcation diagrams and multiplier plots of branch datasets
(:mod:`impactcont.plots.branches`): stability segments, markers on the curves, labels that
avoid each other, non-physical motions in grey, one panel per system (fast, synthetic)."""

from __future__ import annotations

import json
import re

import matplotlib
import matplotlib.pyplot as plt
import numpy as np
import pytest
import xarray as xr

from impactcont.dataset import SPECIAL_LABELS, branch_dataset
from impactcont.plots import (
    SEGMENT_STYLES,
    SPECIAL_MARKERS,
    bifurcation_diagram,
    multipliers_plot,
    stability_segments,
)
from impactcont.plots.branches import NONPHYSICAL_GREY, NONPHYSICAL_MARKER

matplotlib.use("Agg")


from tests._made_up_branch import (  # the fixtures osc and branch: tests/conftest.py
    NPOINTS,
    _columns,
    _special,
)


# -- plots --------------------------------------------------------------------------------------
def test_stability_segments(branch):
    segs = stability_segments(branch)
    assert [k for k, _ in segs] == ["stable", "unstable", "non-physical", "stable"]
    assert [(s.start, s.stop) for _, s in segs] == [(0, 21), (20, 36), (35, 46), (45, 50)]


def test_a_selection_of_no_points_draws_nothing(branch):
    """A branch sliced to no points raised IndexError (index 0 is out of bounds) from
    stability_segments; it has no segments, and its diagram draws no curve."""
    empty = branch.isel(point=slice(0, 0), special=slice(0, 0))
    assert stability_segments(empty) == []
    ax = bifurcation_diagram([branch, empty], legend=None)
    assert ax.get_xlim()[0] < float(branch["omega"].min())
    plt.close(ax.figure)


_SHAPES = {marker: label for label, marker in SPECIAL_MARKERS.items()}


def _is_marker(line) -> bool:
    return line.get_linestyle() in ("None", "none", " ", "")


def _curves(ax) -> list:
    """The lines drawn with a line style (branches, |mu| = 1, the unit circle)."""
    return [ln for ln in ax.get_lines() if not _is_marker(ln)]


def _markers(ax) -> list[tuple[str, np.ndarray, object]]:
    """``(label, xy, line)`` of every special-point marker drawn on ``ax``, one per point."""
    return [(_SHAPES[ln.get_marker()], xy, ln) for ln in ax.get_lines() if _is_marker(ln)
            for xy in ln.get_xydata()]


def _on_curve(ds: xr.Dataset, y: str) -> list[tuple[str, float, float]]:
    """``(label, parameter, y)`` of each special point on the polyline of ``y`` (omega rises)."""
    omega = ds["special_omega"].values
    return sorted(zip(ds["special_label"].values.tolist(), omega,
                      np.interp(omega, ds["omega"].values, ds[y].values), strict=True))


def _assert_same_points(drawn, expected) -> None:
    """Equal lists of ``(label, x, y)``: labels exactly, coordinates to rounding."""
    drawn, expected = sorted(drawn), sorted(expected)
    assert [d[0] for d in drawn] == [e[0] for e in expected]
    np.testing.assert_allclose([d[1:] for d in drawn], [e[1:] for e in expected],
                               rtol=0, atol=1e-12)


def test_bifurcation_diagram_renders(branch, tmp_path):
    ax = bifurcation_diagram(branch)
    lines = _curves(ax)
    assert [ln.get_linestyle() for ln in lines] == ["-", "--", ":", "-"]
    assert lines[2].get_alpha() == SEGMENT_STYLES["non-physical"]["alpha"]
    # every point drawn, the segments joined (one shared point at each of the 3 joins)
    assert sum(len(ln.get_xdata()) for ln in lines) == NPOINTS + 3
    np.testing.assert_array_equal(np.concatenate([ln.get_xdata() for ln in lines]),
                                  np.concatenate([branch["omega"].values[s] for _, s in
                                                  stability_segments(branch)]))
    assert all(ln.get_color() == "C0" for ln in lines)
    # one marker per special point, of its label's shape, in the branch's colour, sitting
    # on the drawn curve at its parameter value
    markers = _markers(ax)
    assert all(len(ln.get_xydata()) == 1 for _, _, ln in markers)
    _assert_same_points([(lab, *xy) for lab, xy, _ in markers],
                        _on_curve(branch, "impact_velocity"))
    assert all(ln.get_markeredgecolor() == "C0" for _, _, ln in markers)
    # one label per special point, anchored at its marker
    _assert_same_points([(t.get_text(), *t.xy) for t in ax.texts],
                        [(lab, *xy) for lab, xy, _ in markers])
    legend = ax.get_legend()
    assert [t.get_text() for t in legend.get_texts()] == [
        "stable", "unstable", "non-physical", "NS Neimark-Sacker", "GR grazing",
        "ZV zero-velocity impact", "N = 1"]
    ax.figure.canvas.draw()
    assert legend.get_window_extent().y1 <= ax.get_window_extent().y0, "legend over the axes"
    assert ax.get_xlabel() == r"forcing frequency $\omega$"
    assert ax.get_ylabel() == r"impact velocity $\dot{x}_1(T^-)$"  # no "(impact_velocity)"
    assert ax.get_title() == r"Period-1 motions with 1 impact, $b = 0$, $R = 0.6$, $\eta = 0.1$"
    out = tmp_path / "diagram.png"
    ax.figure.savefig(out)
    assert out.stat().st_size > 0
    plt.close(ax.figure)


def test_bifurcation_diagram_many_branches_and_y(branch, tmp_path):
    fig, ax = plt.subplots()
    shifted = branch.assign({name: branch[name] + 1 for name in (
        "omega", "special_omega", "special_bracket_lo", "special_bracket_hi")})
    tree = xr.DataTree.from_dict({"a": branch, "b": shifted})
    out = bifurcation_diagram(tree, y="delta", ax=ax, label_special=False)
    assert out is ax
    assert [ln.get_color() for ln in _curves(ax)] == ["C0"] * 4 + ["C1"] * 4
    assert len(ax.texts) == 0
    assert [t.get_text() for t in ax.get_legend().get_texts()][-2:] == ["a (N = 1)",
                                                                        "b (N = 1)"]
    assert ax.get_ylabel() == r"impact phase $\delta$ [rad]"
    # each branch's special points in its colour, at their stored (omega, delta)
    markers = _markers(ax)
    assert len(markers) == 2 * branch.sizes["special"]
    for ds, colour in ((branch, "C0"), (shifted, "C1")):
        expected = zip(ds["special_label"].values.tolist(), ds["special_omega"].values,
                       ds["special_delta"].values, strict=True)
        _assert_same_points([(lab, *xy) for lab, xy, ln in markers
                             if ln.get_markeredgecolor() == colour], list(expected))
    fig.savefig(tmp_path / "many.png")
    plt.close(fig)
    with pytest.raises(ValueError, match=r"y must name .* got 'max_x9'"):
        bifurcation_diagram(branch, y="max_x9")
    with pytest.raises(TypeError, match="datasets must be"):
        bifurcation_diagram(3.0)
    plt.close("all")


def test_multipliers_plot_renders(branch, tmp_path):
    ax_abs, ax_c = multipliers_plot(branch)
    # the spectral radius at every point and |mu| = 1; every modulus as a dot
    rho, unit = _curves(ax_abs)
    np.testing.assert_array_equal(rho.get_xydata(), np.column_stack(
        [branch["omega"].values, branch["spectral_radius"].values]))
    np.testing.assert_allclose(unit.get_ydata(), [1.0, 1.0], rtol=0, atol=0)
    assert len(ax_abs.collections) == 1
    assert ax_abs.collections[0].get_offsets().shape == (NPOINTS * 4, 2)
    # one marker per special point on the drawn spectral radius, labelled there
    markers = _markers(ax_abs)
    _assert_same_points([(lab, *xy) for lab, xy, _ in markers],
                        _on_curve(branch, "spectral_radius"))
    _assert_same_points([(t.get_text(), *t.xy) for t in ax_abs.texts],
                        [(lab, *xy) for lab, xy, _ in markers])
    # complex plane: the unit circle, every multiplier, and one marker line per special
    # label holding the multipliers of its special points (all inside the frame here)
    (circle,) = _curves(ax_c)
    np.testing.assert_allclose(np.hypot(*circle.get_xydata().T), 1.0, rtol=0, atol=1e-12)
    assert len(ax_c.collections) == 1
    drawn = np.asarray(ax_c.collections[0].get_offsets()) @ [1.0, 1.0j]
    mult = branch["multipliers"].values.ravel()
    framed = mult[np.abs(mult) <= ax_c.get_xlim()[1]]  # the frame's inscribed circle
    assert framed.size >= NPOINTS * 3 and drawn.size <= mult.size
    assert np.all(np.min(np.abs(framed[:, None] - drawn[None, :]), axis=1) <= 1e-12)
    labels = branch["special_label"].values
    assert set(labels.tolist()) <= set(SPECIAL_LABELS)
    lines = [ln for ln in ax_c.get_lines() if _is_marker(ln)]
    assert sorted(_SHAPES[ln.get_marker()] for ln in lines) == sorted(set(labels.tolist()))
    for ln in lines:
        drawn = ln.get_xydata() @ [1.0, 1.0j]
        expected = branch["special_multipliers"].values[labels == _SHAPES[ln.get_marker()]]
        np.testing.assert_allclose(np.sort_complex(drawn), np.sort_complex(expected.ravel()),
                                   rtol=0, atol=1e-12)
    # one legend names every mark
    assert [t.get_text() for t in ax_abs.get_legend().get_texts()] == [
        "spectral radius", r"$|\mu| = 1$", "NS Neimark-Sacker", "GR grazing",
        "ZV zero-velocity impact"]
    ax_abs.figure.savefig(tmp_path / "multipliers.png")
    plt.close(ax_abs.figure)
    with pytest.raises(TypeError, match="pair of matplotlib Axes"):
        multipliers_plot(branch, ax=ax_abs)


# -- figures a user can publish (issue 13) ----------------------------------------------------
def _crowded(osc) -> xr.Dataset:
    """Six special points on six neighbouring points: their labels would pile up."""
    cols = _columns()
    specials = [_special(label, p, cols) for label, p in
                zip(("SN", "PD", "NS", "GR", "ZV", "SN"), range(20, 26), strict=True)]
    return branch_dataset(parameter="omega", N=1, oscillator=osc, options={}, columns=cols,
                          special_points=specials)


def _extents(fig, artists) -> list:
    """Window extents after drawing; of an annotation, its text only (not its leader line)."""
    from matplotlib.text import Annotation, Text

    fig.canvas.draw()
    renderer = fig.canvas.get_renderer()
    return [Text.get_window_extent(a, renderer) if isinstance(a, Annotation)
            else a.get_window_extent(renderer) for a in artists]


#: Points closer than this on the page (a marker's size, in points) share one label.
ONE_PLACE = 8.0


@pytest.mark.parametrize("width", [3.5, 5.0, 7.0])
def test_special_point_labels_avoid_each_other(osc, width):
    """Crowded special points: no two labels overlap, and each label names its point(s).

    A label (on the axes or in a zoomed inset) is anchored at a special point and names
    only special points within one marker of that anchor; every special point is named
    by such a label.
    """
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    fig = Figure(figsize=(width, 3.5), layout="constrained")
    FigureCanvasAgg(fig)
    ax = fig.add_subplot()
    ds = _crowded(osc)
    bifurcation_diagram(ds, ax=ax)
    panels = [ax, *[inset for inset in ax.child_axes if inset.get_visible()]]
    labels = [(panel, t) for panel in panels for t in panel.texts if t.get_text()]
    boxes = _extents(fig, [t for _, t in labels])
    for i, a in enumerate(boxes):
        for b in boxes[i + 1:]:
            assert not a.overlaps(b), "two special-point labels overlap"
    specials = _on_curve(ds, "impact_velocity")
    assert len(specials) == 6
    named = set()
    for panel, t in labels:
        def points(xy, panel=panel):
            return panel.transData.transform(xy) * 72.0 / fig.dpi

        (x0, x1), (y0, y1) = sorted(panel.get_xlim()), sorted(panel.get_ylim())
        shown = [k for k, (_, x, y) in enumerate(specials) if x0 <= x <= x1 and y0 <= y <= y1]
        away = {k: float(np.hypot(*(points((specials[k][1], specials[k][2]))
                                    - points(t.xy)))) for k in shown}
        assert min(away.values()) < 0.5, f"{t.get_text()!r} is not at a special point"
        near = [k for k in shown if away[k] <= ONE_PLACE]
        names = t.get_text().split(", ")
        assert len(set(names)) == len(names), t.get_text()
        assert set(names) <= {specials[k][0] for k in near}, (
            f"{t.get_text()!r} names a point not within a marker of it")
        named.update(k for k in near if specials[k][0] in names)
    assert named == set(range(len(specials))), "a special point has no label"
    legend, frame = _extents(fig, [ax.get_legend(), ax])
    assert legend.y1 <= frame.y0, "the legend must not cover the curves"


def test_naive_offsets_would_overlap(osc):
    """The case above is a real collision: fixed offsets (the former layout) overlap."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    fig = Figure(figsize=(5, 3.5), layout="constrained")
    FigureCanvasAgg(fig)
    ax = fig.add_subplot()
    ds = _crowded(osc)
    bifurcation_diagram(ds, ax=ax, label_special=False)
    naive = [ax.annotate(str(lab), (x, 0), xytext=(4, 4), textcoords="offset points",
                         fontsize="small")
             for lab, x in zip(ds["special_label"].values, ds["special_omega"].values,
                               strict=True)]
    boxes = _extents(fig, naive)
    assert any(a.overlaps(b) for i, a in enumerate(boxes) for b in boxes[i + 1:])


def test_special_points_of_non_physical_motions_are_grey_and_unlabelled(osc):
    cols = _columns()
    ds = branch_dataset(parameter="omega", N=1, oscillator=osc, options={}, columns=cols,
                        special_points=[_special("PD", 40, cols), _special("NS", 20, cols)])
    ax = bifurcation_diagram(ds)
    assert [t.get_text() for t in ax.texts] == ["NS"]
    lines = [ln for ln in ax.get_lines() if _is_marker(ln)]
    ns = [ln for ln in lines if ln.get_marker() == SPECIAL_MARKERS["NS"]]
    grey = [ln for ln in lines if ln.get_markeredgecolor() == NONPHYSICAL_GREY]
    assert len(ns) == 1 and ns[0].get_markeredgecolor() == "C0"  # physical: branch colour
    # the PD inside the dotted run: a small grey circle, like every non-physical point
    assert len(grey) == 1 and grey[0].get_marker() == NONPHYSICAL_MARKER
    assert grey[0].get_markersize() < ns[0].get_markersize()
    legend = {t.get_text(): h for t, h in zip(ax.get_legend().get_texts(),
                                              ax.get_legend().legend_handles, strict=True)}
    entry = legend["point on non-physical motion"]
    assert entry.get_markeredgecolor() == NONPHYSICAL_GREY
    assert entry.get_marker() == NONPHYSICAL_MARKER
    assert "PD period doubling" not in legend  # no PD square is drawn
    plt.close(ax.figure)


def test_vertical_range_fits_the_physical_motions(branch):
    far = (branch["point"] > 36) & (branch["point"] < 43)  # inside the non-physical run
    wild = branch.assign(impact_velocity=branch["impact_velocity"].where(~far, 50.0))
    ax = bifurcation_diagram(wild)
    lo, hi = ax.get_ylim()
    physical = wild["impact_velocity"].values[wild["physical"].values]
    assert lo < physical.min() and physical.max() < hi < 5.0
    ax_all = bifurcation_diagram(wild, physical_range=False)
    assert ax_all.get_ylim()[1] > 50.0
    plt.close("all")


def _branch_at_gap(osc, b: float, N: int):
    """A synthetic branch of the test columns with every point at gap b."""
    cols = _columns()
    cols["b"] = np.full(NPOINTS, b)
    return branch_dataset(parameter="omega", N=N, oscillator=osc.replace(b=b), options={},
                          columns=cols, special_points=[])


def test_scene_diagram_has_one_panel_per_system(branch, osc):
    from impactcont.scene.figures import draw_bifurcation

    other = _branch_at_gap(osc, 0.5, N=2)
    fig = draw_bifurcation({"b0": branch, "b0p5": other})
    axes = fig.get_axes()
    assert [ax.get_title() for ax in axes] == ["$b = 0$", "$b = 0.5$"]
    assert fig._suptitle.get_text() == ("Bifurcation diagram: impact velocity against "
                                        "forcing frequency")
    # each panel draws its own branch only, named (by its N) in its legend
    for ax, ds in zip(axes, (branch, other), strict=True):
        np.testing.assert_array_equal(
            np.concatenate([ln.get_xdata() for ln in _curves(ax)]),
            np.concatenate([ds["omega"].values[s] for _, s in stability_segments(ds)]))
    assert [ax.get_legend().get_texts()[-1].get_text() for ax in axes] == ["N = 1", "N = 2"]
    assert [ax.get_xlabel() for ax in axes] == ["", r"forcing frequency $\omega$"]
    single = draw_bifurcation({"b0": branch, "again": branch.assign(omega=branch["omega"] + 1)})
    (ax,) = single.get_axes()
    assert ax.get_title() == r"Period-1 motions with 1 impact, $b = 0$, $R = 0.6$, $\eta = 0.1$"
    assert [t.get_text() for t in ax.get_legend().get_texts()][-2:] == ["b0 (N = 1)",
                                                                        "again (N = 1)"]


def test_one_axis_of_several_systems_names_the_system_of_each_branch(branch, osc):
    other = _branch_at_gap(osc, 0.5, N=1)
    ax = bifurcation_diagram({"a": branch, "c": other})
    assert [t.get_text() for t in ax.get_legend().get_texts()][-2:] == [
        "a (N = 1, b = 0)", "c (N = 1, b = 0.5)"]
    plt.close(ax.figure)


def test_multipliers_plot_keeps_components_apart_and_frames_poles(branch):
    component = np.where(np.arange(NPOINTS) < 30, 0, 1)
    mult = branch["multipliers"].values.copy()
    mult[10, 0] = -1e14  # the pole of G at a zero-velocity impact
    ds = branch.assign(connected_component=("point", component),
                       multipliers=(branch["multipliers"].dims, mult,
                                    branch["multipliers"].attrs))
    ax_abs, ax_c = multipliers_plot(ds)
    rho = _curves(ax_abs)[0].get_ydata()
    assert np.isnan(rho[30]) and rho.size == NPOINTS + 1  # no chord between the components
    np.testing.assert_array_equal(np.delete(rho, 30), ds["spectral_radius"].values)
    # the pole is framed out, the bulk framed in, and the title says what is not shown
    lo, hi = ax_c.get_xlim()
    assert ax_c.get_ylim() == (lo, hi) and -hi == lo and 1.0 < hi < 10.0
    note = re.fullmatch(r"\$\|\\mu\| > ([0-9.]+)\$ not shown", ax_c.get_title(loc="left"))
    assert note is not None, ax_c.get_title(loc="left")
    assert float(note.group(1)) == pytest.approx(hi, rel=5e-3)
    bulk = np.delete(mult.ravel(), 10 * mult.shape[1])  # every multiplier but the pole
    assert np.all(np.abs(bulk.real) <= hi) and np.all(np.abs(bulk.imag) <= hi)
    for ln in ax_c.get_lines():  # the special markers too stay inside the frame
        assert np.all(np.abs(ln.get_xydata()) <= hi)
    plt.close(ax_abs.figure)


def test_multipliers_plot_note_says_what_is_not_drawn(branch):
    """``|mu| > r not shown``: every dot drawn has ``|mu| <= r``, every one left out ``> r``."""
    ax_abs, ax_c = multipliers_plot(branch)
    mult = branch["multipliers"].values.ravel()
    drawn = np.asarray(ax_c.collections[0].get_offsets()) @ [1.0, 1.0j]
    note = re.fullmatch(r"\$\|\\mu\| > ([0-9.]+)\$ not shown", ax_c.get_title(loc="left"))
    if note is None:
        assert drawn.size == mult.size, "multipliers left out without a word"
    else:
        r = float(note.group(1))
        assert np.all(np.abs(drawn) <= r * (1 + 5e-3))
        assert drawn.size == np.count_nonzero(np.abs(mult) <= r * (1 + 5e-3))
    plt.close(ax_abs.figure)


def test_fit_text_never_breaks_inside_mathtext():
    """A title broken to fit its figure keeps ``$(\\omega, b)$`` and ``$\\eta = 0.1$`` whole
    (a break inside ``$...$`` leaves an unclosed mathtext, drawn as raw text or refused)."""
    from matplotlib.figure import Figure

    from impactcont.plots.branches import fit_text

    fig = Figure(figsize=(3.5, 3.0))
    title = fig.suptitle(r"Backlash, $R = 0.6$, $\eta = 0.1$: motions with one impact on "
                         r"each stop in $(\omega, b)$", fontsize="medium")
    fig.draw_without_rendering()
    fit_text(title)
    lines = title.get_text().split("\n")
    assert len(lines) > 1
    assert all(line.count("$") % 2 == 0 for line in lines), lines
    assert r"$(\omega, b)$" in title.get_text()


def test_special_points_at_one_place_become_one_combined_marker():
    """Two ZV points of different N at one place (the paper's b = 0.5, omega = 1.213462,
    v = 0): drawn alike, the later hid the earlier; nested, both are in view."""
    from matplotlib.figure import Figure

    from impactcont.plots.branches import nest_coincident_markers
    from tests._layout_checks import markers_hiding_markers

    fig = Figure(figsize=(3.5, 2.5))
    ax = fig.add_subplot()
    for colour in ("tab:blue", "tab:green"):
        ax.plot([1.213462, 1.5], [0.0, 0.5 if colour == "tab:blue" else 0.3],
                linestyle="none", marker="v", markersize=6.0, markerfacecolor="white",
                markeredgecolor=colour)
    ax.set_xlim(1.0, 2.0)
    ax.set_ylim(-0.1, 1.0)
    assert len(markers_hiding_markers(fig)) == 1
    nest_coincident_markers(ax)
    assert markers_hiding_markers(fig) == []
    sizes = sorted(line.get_markersize() for line in ax.get_lines()
                   for x, _ in line.get_xydata() if x == pytest.approx(1.213462))
    assert sizes == pytest.approx([4.2, 6.0])
    nest_coincident_markers(ax)  # once nested, they stay as they are
    assert len([x for line in ax.get_lines() for x, _ in line.get_xydata()]) == 4
    with pytest.raises(ValueError, match="shrink must be in"):
        nest_coincident_markers(ax, shrink=1.5)


def test_motion_text_names_the_stops_a_motion_sticks_on():
    """A lowercase letter of a pattern is an impact followed by a sticking phase: the title
    reads the impacts in capitals and says where the motion sticks."""
    from impactcont.plots.branches import motion_text

    def dataset(pattern: str) -> xr.Dataset:
        stops = {"mass": 2, "relative_to": 1, "b_low": -0.3}
        return xr.Dataset(attrs={"N": 1, "impacts": len(pattern), "pattern": pattern,
                                 "oscillator": json.dumps({"stops": stops})})

    assert motion_text([dataset("UL")]) == ("Period-1 motions with 2 impacts, impacts UL "
                                            "(L: lower stop)")
    assert motion_text([dataset("lu")]) == ("Period-1 motions with 2 impacts, impacts LU "
                                            "(L: lower stop), sticking on L and U")
