"""Figures of scene outputs (:mod:`impactcont.scene.figures`): saving a figure leaves no
temporary file."""

from __future__ import annotations

import matplotlib

matplotlib.use("Agg")


def test_figures_leave_no_temporary_file(tmp_path):
    from matplotlib.figure import Figure

    from impactcont.scene.figures import save_figure

    fig = Figure()
    fig.add_subplot().plot([0, 1])
    assert save_figure(fig, tmp_path / "f.png", 40).read_bytes()[:4] == b"\x89PNG"
    assert save_figure(fig, tmp_path / "f.pdf", 40).read_bytes()[:4] == b"%PDF"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["f.pdf", "f.png"]
