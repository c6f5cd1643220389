"""The point record (:class:`impactcont.core.point.ContinuationPoint`).

The points the core streams (:func:`impactcont.core.iter_points`) along the circle
``u^2 + lam^2 = 1``, whose exact tangent at ``(u, lam)`` is parallel to ``(-lam, u)``: the
record's state, tangent (unit in the scaled norm ``du^2 / m + theta dlam^2``), ``dlam``,
direction, index, steps and monitors against it; and the record's own properties on a
hand-made point.
"""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from impactcont.core import ContinuationOptions, ContinuationPoint, iter_points


class Circle:
    def residual(self, u, lam):
        return np.array([u[0] ** 2 + lam ** 2 - 1.0])

    def jacobian(self, u, lam):
        return np.array([[2.0 * u[0]]])

    def dparam(self, u, lam):
        return np.array([2.0 * lam])

    def monitors(self, u, lam):
        return {"u": u[0]}


def test_a_hand_made_point():
    point = ContinuationPoint(u=np.array([0.6, -2.0]), lam=0.8, tangent=np.array([0.0, 0.6, -0.8]),
                              ds=0.1, newton_iterations=3, index=4, direction=-1)
    np.testing.assert_array_equal(point.state, [0.6, -2.0, 0.8])
    assert point.state.shape == (3,)
    assert point.dlam == -0.8 and type(point.dlam) is float
    assert point.monitors == {}
    with pytest.raises(dataclasses.FrozenInstanceError):
        point.lam = 1.0
    # eq=False: records compare by identity (arrays inside)
    twin = dataclasses.replace(point)
    assert twin != point and twin == twin


def _scaled_norm(v, theta):
    return float(np.sqrt(np.sum(v[:-1] ** 2) / (v.size - 1) + theta * v[-1] ** 2))


@pytest.mark.parametrize("theta", [1.0, 0.5])
@pytest.mark.parametrize("direction", [1, -1])
def test_the_points_of_a_run_describe_the_circle(direction, theta):
    options = ContinuationOptions(bounds=(-0.9, 0.9), ds=0.05, ds_max=0.1, direction=direction,
                                  theta=theta)
    run = iter_points(Circle(), [1.0], 0.0, options)
    points = list(run)
    assert len(points) > 5
    assert [p.index for p in points] == list(range(len(points)))
    assert points[0].ds == 0.0
    previous = None
    for p in points:
        assert p.direction == direction
        assert p.state[-1] == p.lam
        assert abs(p.u[0] ** 2 + p.lam ** 2 - 1.0) < 1e-10
        assert p.monitors == {"u": pytest.approx(p.u[0], abs=0.0)}
        # the tangent is the circle's, unit in the scaled norm, oriented along the run
        # (the sign of dlam at the start)
        exact = np.array([-p.lam, p.u[0]])
        assert abs(p.tangent[0] * exact[1] - p.tangent[1] * exact[0]) < 1e-8
        assert _scaled_norm(p.tangent, theta) == pytest.approx(1.0, abs=1e-12)
        assert p.dlam * direction > 0.0
        assert p.newton_iterations >= 0
        if previous is not None:
            assert p.ds > 0.0
            step = p.state - previous.state
            assert float(np.dot(step, previous.tangent)) > 0.0  # moving along the tangent
            # the step's scaled arclength: the chord of an arc of the circle
            assert _scaled_norm(step, theta) == pytest.approx(p.ds, rel=0.01)
        previous = p
    assert abs(points[-1].lam) == pytest.approx(0.9, abs=1e-12)  # landed on the bound
