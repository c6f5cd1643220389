"""The study's impact damper whose ball rides on a wall (issue 30, item 6) against the closed
form of a held phase: the ball moves with the primary (one mass 1 + m), the wall's force on it
is m x1'' and it is released where x1'' changes sign (run.held_pressing, in mpmath)."""

from __future__ import annotations

import math

from tests.studies._figure_study import study_module


def test_the_ball_is_released_where_the_walls_acceleration_changes_sign():
    study = study_module("chatter_sticking", figures=False)
    osc, res = study.riding(0.3, 1.6, chatter_tolerance=1e-3)
    found = study.ride_rows(osc, res)
    assert len(found["releases"]) == 3  # U from the start, L after a chatter, U again
    assert max(found["releases"]) < 1e-12  # release times against the closed form
    assert found["force_error"] < 1e-12  # the contact force along each phase, relative
    # each release lies near the quasi-static one (x1 ~ cos theta: x1'' = 0 at +-pi/2)
    for phase in found["phases"]:
        assert abs(abs(phase) - math.pi / 2) < 0.3
