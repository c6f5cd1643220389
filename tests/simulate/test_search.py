"""The simulator's own root search (:mod:`impactcont.simulate.search`).

``newton_in_brackets`` finds one root in each bracket, all brackets at once, to a few ulps,
whatever the brackets' sizes, and keeps to its bracket where the Newton step would leave it.
"""

from __future__ import annotations

import math

import numpy as np

from impactcont.simulate.search import newton_in_brackets


def _cosine(level: float):
    def fun(t: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        return np.cos(t) - level, -np.sin(t)
    return fun


def test_each_bracket_gives_its_own_root_to_a_few_ulps():
    level = 0.3
    root = math.acos(level)  # roots of cos t = 0.3: +-root + 2 pi k
    lo = np.array([0.0, 2 * math.pi - 2.0, 2 * math.pi + 0.5, root - 1e-9])
    hi = np.array([1.5, 2 * math.pi - 0.5, 2 * math.pi + 2.0, root + 1e-9])
    exact = np.array([root, 2 * math.pi - root, 2 * math.pi + root, root])
    fun = _cosine(level)
    found = newton_in_brackets(fun, lo, hi, fun(lo)[0])
    assert np.all(np.abs(found - exact) <= 8 * np.spacing(exact)), found - exact


def test_a_root_at_a_flat_place_stays_in_its_bracket():
    """cos t - 1 + 1e-12 has two close roots around 0 where the slope nearly vanishes: a
    Newton step from the middle would leave the bracket; the result stays inside it."""
    fun = _cosine(1.0 - 1e-12)
    lo, hi = np.array([1e-9]), np.array([3.0])
    found = newton_in_brackets(fun, lo, hi, fun(lo)[0])
    assert lo[0] <= found[0] <= hi[0]
    assert abs(math.cos(found[0]) - (1.0 - 1e-12)) <= 4e-16


def test_a_root_known_only_to_rounding_does_not_cycle():
    """Near its root g is rounding: its sign flips between two neighbouring iterates whose
    Newton steps (above the tolerance) land exactly on each other, the ends of the bracket.
    Such a step is replaced by the midpoint, so the bracket shrinks and the search ends long
    before its cap of 200 evaluations (it used to cycle to the cap; a crossing of the impact
    damper of docs/machines.md at omega = 0.8 did so)."""
    slope, root, noise = 0.153, 0.3812931801597779, 3.9e-16
    calls = []

    def fun(t: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        calls.append(t.size)
        g = slope * (t - root)
        g = np.where(np.abs(g) < 2 * noise, np.where(t < root, -noise, noise), g)
        return g, np.full_like(t, slope)

    found = newton_in_brackets(fun, np.array([0.18]), np.array([0.39]), np.array([-1.0]))
    # bisection alone would take log2(0.21 / 1e-15) < 48 evaluations
    assert len(calls) <= 60, len(calls)
    assert abs(found[0] - root) <= 2 * noise / slope + 8 * np.spacing(root)


def _bounce(height: float):
    """``g = t^2 / 2 - height`` counted: a small bounce of a chatter (a parabola whose vertex,
    at t = 0, lies just below the stop), with its slope and curvature."""
    calls = []

    def fun(t: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        calls.append(t.size)
        return 0.5 * t * t - height, t, np.ones_like(t)
    return fun, calls


def test_a_crossing_near_the_vertex_of_a_bounce_takes_a_few_steps():
    """From the vertex of a bounce 1e-9 below the stop to the end of a window 0.4 later, the
    crossing at sqrt(2e-9) is found to a few ulps in at most 4 evaluations with the
    curvature and the value at the bracket's far end (Newton's steps from the far side
    only halve the distance: 17 evaluations)."""
    height = 1e-9
    root = math.sqrt(2 * height)
    fun, calls = _bounce(height)
    lo, hi = np.array([0.0]), np.array([0.4])
    found = newton_in_brackets(fun, lo, hi, fun(lo)[0], fun(hi)[0])
    calls.clear()
    found = newton_in_brackets(fun, lo, hi, fun(lo)[0], fun(hi)[0])
    assert abs(found[0] - root) <= 8 * np.spacing(root)
    assert len(calls) - 2 <= 4, len(calls)  # the two end values above are not the search's


def test_a_root_within_rounding_of_g_ends_the_search():
    """Where ``|g|`` is within its rounding (`noise`) the iterate is the root: the search
    ends there, within ``noise / g'`` of the root, instead of bisecting rounding."""
    slope, root, noise = 1e-4, 2.5614291772e-05, 4.4e-16
    calls = []

    def fun(t: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        calls.append(t.size)
        g = slope * (t - root)
        flip = np.where(np.floor(t / 1e-13) % 2 == 0, 1.0, -1.0)  # rounding's sign
        return np.where(np.abs(g) < noise, flip * noise / 2, g), np.full_like(t, slope)

    lo, hi = np.array([1e-5]), np.array([0.4])
    found = newton_in_brackets(fun, lo, hi, fun(lo)[0], fun(hi)[0], noise)
    assert abs(found[0] - root) <= noise / slope
    assert len(calls) - 2 <= 4, len(calls)


def test_a_root_within_rounding_is_taken_short_of_the_level_only():
    """Newton's iterates approach the root of a convex g from above: each is past the level,
    those within `noise` of it too. The rounding stop takes only an iterate short of the
    level (a crossing's root is never past its stop); here the steps go on to a few ulps
    (it used to stop at the first iterate within `noise`, 4e-8 past the root)."""
    slope, root, noise = 1e-3, 0.25, 1e-10

    def fun(t: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        return slope * (t - root) + (t - root) ** 2, slope + 2 * (t - root)

    found = newton_in_brackets(fun, np.array([root - 1e-3]), np.array([root + 0.4]),
                               np.array([-1.0]), noise=noise)
    assert found[0] - root <= 8 * np.spacing(root), found[0] - root
