"""The one special-point record: every detector's points and the user's events."""

from __future__ import annotations

import types

import numpy as np
import pytest

from impactcont.detection import SpecialPoint
from impactcont.detection.points import SpecialPoint as Record
from impactcont.detection.special_points import UserEvent
from impactcont.vocabulary import Label

ORBIT = types.SimpleNamespace(delta=0.25)


def test_the_former_record_types_are_the_one_record():
    assert SpecialPoint is UserEvent is Record


def test_an_n1_point_given_its_phase_and_an_n_p_point_given_its_unknowns():
    n1 = SpecialPoint(label=Label.PD, value=1.5, delta=0.5, point=3, bracket=(1.4, 1.6),
                      precision=1e-13, status="located", orbit=ORBIT)
    assert n1.u.tolist() == [0.5] and n1.delta == 0.5 and n1.x.tolist() == [0.5, 1.5]
    assert n1.kind is Label.PD and n1.kind.marker == "s" and n1.codimension == 1
    n_p = SpecialPoint(label="SN", value=1.5, u=np.array([0.1, 2.0]), point=0,
                       precision=1e-12, status="bracketed", orbit=ORBIT)
    assert n_p.delta == 0.25 and n_p.kind is Label.SN and n_p.bracket is None
    # a user event: its name and parameter under the former UserEvent's names
    event = UserEvent(label="v07", value=1.7, u=np.array([0.3]), point=1, precision=1e-13,
                      status="located", orbit=ORBIT)
    assert event.name == "v07" and event.kind == "v07" and event.lam == 1.7
    # a codim-2 point of a curve: two parameters, x = [u, value] as the curve gives it
    x = np.array([0.3, 1.8, 0.1])
    codim2 = SpecialPoint.on_curve("PD+NS", x, ORBIT, 2, 1e-10, "located")
    assert codim2.codimension == 2 and codim2.value == 0.1 and codim2.u.tolist() == [0.3, 1.8]
    assert np.array_equal(codim2.x, x) and codim2.kind == "PD+NS" and codim2.bracket is None
    bare = SpecialPoint.on_curve("R1", x, types.SimpleNamespace(), 0, 1e-10, "bracketed")
    assert bare.delta is None  # a motion without a phase


def test_bad_records_are_refused():
    with pytest.raises(ValueError, match="status must be one of"):
        SpecialPoint(label="PD", value=1.0, delta=0.0, point=0, precision=0.0,
                     status="found", orbit=ORBIT)
    with pytest.raises(ValueError, match="needs its unknowns u or its phase delta"):
        SpecialPoint(label="PD", value=1.0, point=0, precision=0.0, status="located",
                     orbit=ORBIT)
    with pytest.raises(TypeError):  # keywords only: the N-1 and N-p orders differed
        SpecialPoint("PD", 1.0, 0, 0.0, "located", ORBIT)
