"""The onset of complete chatter (issue 30, item 4) on a branch of chatter-entered motions.

A lowercase letter on a stop with ``0 < R < 1`` is a landing whose chatter accumulates
(:func:`impactcont.kernel.shooting._chatter_map`) and sticks until the release. Along a
parameter the accumulation point moves; the chatter stops being complete where it reaches
the release: there the pressing force at the accumulation point (the sticking onset test
``SO``, ``landing_pressing``) passes through zero, together with the held phase's
duration. (A chatter cannot accumulate where the acceleration pulls the coordinate off its
stop: its bounces would not come back; so the pressing force can only vanish at the
accumulation point where the held phase has shrunk to nothing.)

The machine: the preloaded one-mass oscillator of
tests/integration/test_chatter_entered_motions.py (``F_static = 1`` into the stop ``b = 0``,
forced ``3 cos``, ``R = 0.5``, ``eta = 0.05``): held, its pressing force is ``3 cos(theta)
+ 1``, so it releases at ``cos(theta_r) = -1/3`` whatever came before, and one period of
the motion is the flight from that release, the landing, the chatter and the stick. Raising
omega shortens the period until the chatter accumulates at the next release: omega* =
0.92769274955333 (the closed form below, the returns of the bounces solved in mpmath down
to bounce speeds 1e-16).

Witnesses, each within what it guarantees:

- the shooting model's zero of SO (located on the branch to 3e-15) lies 2.05e-6 above
  omega*: the chatter map resolves ``K`` impacts (``R^K <= CHATTER_SPEED = 1e-5``) and
  jumps to the accumulation point with the quadratic model ``2u / (a (1 - R))``, which
  near the onset (the acceleration vanishing over the jump) takes a chatter as complete
  whose true bounces would still escape past the release. The offset shrinks with the
  cut: 2.3e-7 at ``1e-6``, 3.3e-8 at ``1e-7``;
- the simulator (:func:`impactcont.simulate`, its own flights, chatter jump and sticking
  model) sticks at the accumulation point below the onset, with a pressing force there
  that falls to zero as omega rises to it, and does not stick past it; bisected alone
  (from the release state) its sign change lies 3.4e-8 above omega*: it resolves the
  bounces down to its rounding floor (a bounce apex of 1000 ulps) and takes the
  accumulation there;
- the closed form (mpmath): the flight of the linear oscillator is exact, the returns to
  the stop are solved to 30 digits; from the release the chatter accumulates before the
  next release at omega* - 1e-9 and escapes past it at omega* + 1e-9.

The curve of the onset in (omega, eta) (``ic.curve(branch, "SO", ...)``; the closed form
takes eta as it is, the release does not move): at eta 0.048, 0.05 and 0.052 the closed
form's onset (0.92487405733708, omega*, 0.93050812715488) lies 2.051e-6, 2.052e-6,
2.054e-6 below the shooting model's (the same chatter cut, whatever the damping; each
motion solved alone brackets it within 0.15 .. 0.25 CHATTER_SPEED), the simulator's sign
change at 0.052 3.4e-8 above it (its rounding floor, as at 0.05). The curve follows SO at
the accumulation point, as the branch does (it was taken at the landing impact before).
"""

from __future__ import annotations

import functools
import json
import math

import mpmath
import numpy as np
import pytest

import impactcont as ic
import impactcont.orbit.sticky as sticky

#: The release phase of the held preloaded oscillator: ``3 cos(theta_r) + 1 = 0``, falling.
THETA_R = math.acos(-1.0 / 3.0)
#: The onset of complete chatter, the closed form (:func:`_closed_form_chatter`, bisected to
#: 1e-14 with bounces resolved down to speed 1e-20 at 40 digits; this file checks its
#: bracket of +-1e-9).
OMEGA_ONSET = 0.92769274955333
#: The zero of SO of the shooting model (the chatter cut R^K <= 1e-5), as located.
OMEGA_SO = 0.92769480200187
#: The simulator's sign change from the release state (bisected alone to 1e-15; it is not
#: monotone within +-3e-10 of it: at its rounding floor the decision is rounding).
OMEGA_SIMULATED = 0.92769278369253
#: The closed form's onset at other damping (:func:`_closed_form_onset` at 30 digits,
#: bounces resolved down to speed 1e-16, bisected to 1.2e-12 from the bracket (SO curve's
#: omega - 1e-5, SO curve's omega); this file checks a bracket of +-1e-9 at each and
#: bisects again to 1e-9 at 0.052).
OMEGA_ONSET_AT = {0.048: 0.92487405733708, 0.05: OMEGA_ONSET, 0.052: 0.93050812715488}


def preloaded(omega: float, eta: float = 0.05) -> ic.ImpactOscillator:
    """One mass pushed into its stop b = 0 by F_static = 1, forced 3 cos, R = 0.5."""
    return ic.ImpactOscillator(M=[[1.0]], K=[[1.0]], F=[3.0], F_static=[1.0], R=0.5, b=0.0,
                               omega=omega, eta=eta)


@functools.cache
def seed():
    """The chatter-entered motion at omega 0.92, read from a run from rest."""
    osc = preloaded(0.92)
    return ic.multi_impact_orbit(osc, 1, 1, ic.simulate(osc, [0.0, 0.0], 0.0, 4.0))


def motion(omega: float, eta: float = 0.05):
    return ic.multi_impact_orbit(preloaded(omega, eta), 1, 1, seed())


def onset_test(orbit) -> float:
    """SO made sign-definite past the onset: the pressing force at the accumulation point,
    ``-|p|`` where the held phase after the chatter has no duration (``pressing_min`` NaN:
    the chatter map's accumulation point lies past the release, and further on the map
    jumps to a later period where ``p`` is positive again)."""
    low = float(orbit.pressing_min[0])
    p = float(orbit.landing_pressing[0])
    return -abs(p) if math.isnan(low) else p


def simulated_stick(omega: float, state, phase: float, periods: float = 1.02,
                    eta: float = 0.05):
    """The first sticking phase of a run that ends by a release, and the run."""
    res = ic.simulate(preloaded(omega, eta), state, phase, periods)
    released = [ph for ph in res.sticking if ph.ended_by == "release"]
    return (released[0] if released else None), res


@functools.cache
def branch():
    return ic.continuation(seed(), parameter="omega", bounds=(0.92, 0.935),
                           events={"onset": onset_test})


def test_the_branch_locates_the_onset_of_complete_chatter():
    """The branch's own special points include SO at the shooting model's zero, once: the
    release grazing test vanishes there too (the held phase shrinks to nothing), and RG
    at SO is reported as the SO (``detection.locator.TWIN_OF``)."""
    ds = branch()
    labels = list(ds.special_label.values)
    assert labels.count("SO") == 1 and "RG" not in labels, labels
    i = labels.index("SO")
    assert ds.special_status.values[i] == "located"
    assert float(ds.special_precision.values[i]) < 1e-12
    assert float(ds.special_omega.values[i]) == pytest.approx(OMEGA_SO, abs=1e-9)


def test_the_branch_locates_the_zero_of_the_pressing_force_at_the_accumulation_point():
    """With SO made sign-definite past the onset (a user event), the branch locates its
    zero to 1e-12 at OMEGA_SO; there the accumulation point reaches the release (the held
    phase shrinks to nothing), and the motions on both sides are what SO says."""
    ds = branch()
    assert list(ds.event_name.values) == ["onset"]
    assert ds.event_status.values[0] == "located" and ds.event_precision.values[0] < 1e-12
    located = float(ds.event_omega.values[0])
    assert located == pytest.approx(OMEGA_SO, abs=1e-9)
    before, after = motion(located - 1e-7), motion(located + 1e-7)
    assert before.physical and 0 < before.landing_pressing[0] < 1e-3
    held = before.stick_times[0] - before.chatters[0].duration
    assert 0 < held < 1e-3
    release = before.phases[0] + before.oscillator.omega * before.stick_times[0]
    assert math.cos(release) == pytest.approx(-1.0 / 3.0, abs=1e-12)
    assert not after.physical and after.landing_pressing[0] < 0
    assert "after its chatter" in after.reason


@pytest.mark.parametrize("distance", [1e-2, 1e-3, 1e-4])
def test_the_simulator_sticks_at_the_accumulation_point_below_the_onset(distance):
    """From the solved motion's landing state the simulator's chatter accumulates and
    sticks, its pressing force at the accumulation point the shooting's within what the
    chatter cut leaves (measured 3.6e-8, 4.1e-7 and 1.0e-5 at 1e-2, 1e-3 and 1e-4 below
    the onset: the accumulation time of the jump at R^K <= 1e-5 against the simulator's
    bounces resolved to rounding, 1.3e-8 .. 3.8e-6, times the force's rate ``3 sin(theta)
    omega``; the quadratic jump worsens as the acceleration at its end vanishes), and
    falling towards zero."""
    orbit = motion(OMEGA_SO - distance)
    assert orbit.physical, orbit.reason
    stick, res = simulated_stick(OMEGA_SO - distance, orbit.states[0], float(orbit.phases[0]))
    assert stick is not None and len(res.chatter) == 1
    assert stick.start == pytest.approx(res.chatter[0].time, abs=1e-12)
    assert stick.start == pytest.approx(orbit.chatters[0].duration, abs=1e-5)  # 4e-6 at 1e-4
    force = float(stick.forces[0, 0])
    tolerance = {1e-2: 1e-7, 1e-3: 1e-6, 1e-4: 3e-5}[distance]
    assert force == pytest.approx(float(orbit.landing_pressing[0]), abs=tolerance)
    assert force < {1e-2: 0.6, 1e-3: 0.15, 1e-4: 0.04}[distance]


@pytest.mark.parametrize("past", [1e-7, 1e-5])
def test_past_the_onset_the_simulated_chatter_does_not_stick(past):
    """From the last physical motion's landing state (1e-7 below the onset) at omega past
    it, the simulator's impacts do not accumulate: no chatter point, no sticking phase
    in the period; the bounces run on past the release and the next impact is the landing
    a period later."""
    orbit = motion(OMEGA_SO - 1e-7)
    assert orbit.physical
    stick, res = simulated_stick(OMEGA_SO + past, orbit.states[0], float(orbit.phases[0]))
    assert stick is None and not res.chatter and not res.sticking
    period = 2 * math.pi / (OMEGA_SO + past)
    assert res.impact_times[-1] > 0.99 * period


def test_the_simulator_alone_brackets_the_onset():
    """From the release state (the whole motion follows from it) the simulator sticks at
    OMEGA_SIMULATED - 2e-9, with a pressing force at the accumulation point that falls to
    zero as omega rises to it, and not at OMEGA_SIMULATED + 2e-9; its sign change lies
    between the closed form's onset and the shooting model's SO (3.4e-8 and 2.0e-6
    above the onset: the rounding floor of its bounces, the chatter cut)."""
    forces = []
    for below in (1e-4, 1e-6, 1e-8, 2e-9):
        stick, res = simulated_stick(OMEGA_SIMULATED - below, [0.0, 0.0], THETA_R)
        assert stick is not None and len(res.chatter) == 1, below
        forces.append(float(stick.forces[0, 0]))
    assert all(f > 0 for f in forces) and forces == sorted(forces, reverse=True)
    assert forces[0] < 0.04 and forces[-1] < 3e-5  # measured 0.0343 .. 1.44e-5
    stick, res = simulated_stick(OMEGA_SIMULATED + 2e-9, [0.0, 0.0], THETA_R)
    # no stick; the unresolvable last bounce's accumulation point (if taken) past the release
    period = 2 * math.pi / (OMEGA_SIMULATED + 2e-9)
    assert stick is None and all(c.time > period for c in res.chatter)
    assert 0 < OMEGA_SIMULATED - OMEGA_ONSET < 1e-7
    assert 0 < OMEGA_SO - OMEGA_SIMULATED < 3e-6


def test_the_shooting_onset_moves_onto_the_exact_one_with_the_chatter_cut(monkeypatch):
    """The SO offset is the chatter cut's: with R^K <= 1e-7 (K = 24) the motion sticks
    1e-8 below the simulator's sign change and is not physical past it (measured 3.3e-8
    above the closed form's onset, as the simulator), where at 1e-5 it was still
    physical."""
    assert motion(OMEGA_SIMULATED + 2e-8).physical
    monkeypatch.setattr(sticky, "CHATTER_SPEED", 1e-7)
    assert sticky.chatter_impacts(0.5) == 24
    below = motion(OMEGA_SIMULATED - 1.1e-8)  # omegas no other test builds a flow at
    above = motion(OMEGA_SIMULATED + 2.1e-8)
    assert below.physical and onset_test(below) > 0
    assert not above.physical and onset_test(above) < 0


def _closed_form_chatter(omega: float, stop_speed: float = 1e-16, eta: float = 0.05) -> bool:
    """Whether the chatter after the release accumulates before the next release.

    From ``x = x' = 0`` at the phase ``theta_r`` the mass flies
    (``x'' + 2 eta x' + x = 3 cos(omega t + theta_r) + 1``, the homogeneous part
    ``e^(-eta t) (c1 cos wd t + c2 sin wd t)`` and the forced ``1 + Re(A e^(i theta))``,
    ``A = 3 / (1 - omega^2 + 2 eta i omega)``; eta 0.05 unless given), lands on ``x = 0``
    and bounces (``x'`` times ``-R``); each return is a root of the exact flight, bracketed
    by steps from the parabola ``2u/a`` and solved in mpmath at 30 digits. The chatter
    escapes when a bounce's acceleration is not into the stop or it returns after the next
    release ``t = 2 pi / omega``; it is complete when the bounce speed falls below
    `stop_speed` with its accumulation point (the parabola's, exact to ``O(u^2)``) before
    that release."""
    with mpmath.workdps(30):
        return _chatter_at(mpmath.mpf(omega), mpmath.mpf(stop_speed), 2 * mpmath.mpf(eta))


def _chatter_at(w, stop_speed, c) -> bool:
    mp = mpmath
    R = mp.mpf(1) / 2
    zeta = c / 2
    wd = mp.sqrt(1 - zeta**2)
    th = mp.acos(mp.mpf(-1) / 3)
    period = 2 * mp.pi / w
    A = 3 / (1 - w**2 + 1j * c * w)

    def forced(t):
        e = A * mp.expj(w * t + th)
        return 1 + e.real, (1j * w * e).real

    def flight(t0, v0):
        p0, q0 = forced(t0)
        c1 = -p0
        c2 = (v0 - q0 + zeta * c1) / wd

        def x(t):
            s = t - t0
            return forced(t)[0] + mp.exp(-zeta * s) * (c1 * mp.cos(wd * s)
                                                        + c2 * mp.sin(wd * s))

        def v(t):
            s = t - t0
            e, co, si = mp.exp(-zeta * s), mp.cos(wd * s), mp.sin(wd * s)
            return forced(t)[1] + e * (-zeta * (c1 * co + c2 * si) + wd * (c2 * co - c1 * si))
        return x, v

    def next_return(t0, v0, h, grow):
        x, v = flight(t0, v0)
        t = t0 + h
        while x(t) < 0:
            h *= grow
            t += h
            if t > period * (1 + mp.mpf(1) / 50):
                return None
        root = mp.findroot(x, (t - h, t), solver="anderson")
        return root, v(root)

    t, v = next_return(mp.mpf(0), mp.mpf(0), period / 200, 1)
    while True:
        u = R * v
        a = -c * (-u) + 3 * mp.cos(w * t + th) + 1  # x'' at the stop, leaving it
        if not a > 0 or t > period:
            return False
        if u < stop_speed:
            return t + 2 * u / (a * (1 - R)) < period
        found = next_return(t, -u, 2 * u / a / 16, mp.mpf(5) / 4)
        if found is None:
            return False
        t, v = found


@pytest.mark.parametrize(("offset", "complete"), [(-1e-9, True), (1e-9, False)])
def test_the_closed_form_brackets_the_onset(offset, complete):
    """The closed form's chatter from the release is complete just below OMEGA_ONSET and
    escapes just above it; the shooting model's SO lies within its chatter cut of it
    (2.05e-6, about 0.2 CHATTER_SPEED) and the simulator within its rounding floor."""
    assert _closed_form_chatter(OMEGA_ONSET + offset) is complete
    assert 0 < OMEGA_SO - OMEGA_ONSET < 0.3 * sticky.CHATTER_SPEED


def _closed_form_onset(eta: float, lo: float, hi: float, tol: float) -> float:
    """The closed form's onset of complete chatter at `eta`, bisected in omega to `tol` from
    ``(lo, hi)`` (the chatter complete at `lo`, escaping at `hi`): how
    :data:`OMEGA_ONSET_AT` was computed."""
    assert _closed_form_chatter(lo, eta=eta) and not _closed_form_chatter(hi, eta=eta)
    while hi - lo > tol:
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if _closed_form_chatter(mid, eta=eta) else (lo, mid)
    return 0.5 * (lo + hi)


def test_the_closed_form_onset_at_other_damping():
    """OMEGA_ONSET_AT by the closed form again: its chatter is complete 1e-9 below the
    onset at eta 0.048 and escapes 1e-9 above it; at 0.052 the bisection from +-2e-9 lands
    within 1e-9 of it. The onset rises with the damping (1.41 per unit eta: the bounces die
    sooner, so a shorter period still holds the accumulation point)."""
    onset = OMEGA_ONSET_AT[0.048]
    assert _closed_form_chatter(onset - 1e-9, eta=0.048)
    assert not _closed_form_chatter(onset + 1e-9, eta=0.048)
    onset = OMEGA_ONSET_AT[0.052]
    assert _closed_form_onset(0.052, onset - 2e-9, onset + 2e-9, 1e-9) == pytest.approx(
        onset, abs=1e-9)
    slope = (OMEGA_ONSET_AT[0.052] - OMEGA_ONSET_AT[0.048]) / 0.004
    assert 1.3 < slope < 1.5


@pytest.mark.parametrize("eta", [0.048, 0.052])
def test_the_shooting_onset_lies_the_chatter_cut_above_the_closed_form(eta):
    """At other damping the shooting model's SO lies as far above the closed form's onset
    as at eta 0.05 (2.05e-6, 0.2 CHATTER_SPEED: the cut R^K <= 1e-5 does not depend on the
    damping; the offset shrinks about tenfold for each tenfold smaller cut, see
    test_the_shooting_onset_moves_onto_the_exact_one_with_the_chatter_cut): the motion
    solved alone sticks 0.15 CHATTER_SPEED above the onset and is not physical 0.25 above
    (measured 2.0509e-6 and 2.0541e-6 at 0.048 and 0.052)."""
    cut, onset = sticky.CHATTER_SPEED, OMEGA_ONSET_AT[eta]
    below, above = motion(onset + 0.15 * cut, eta), motion(onset + 0.25 * cut, eta)
    assert below.physical and onset_test(below) > 0, below.reason
    assert not above.physical and onset_test(above) < 0


def test_the_simulator_brackets_the_onset_at_other_damping():
    """At eta 0.052 the simulator alone (from the release state) sticks 1e-8 above the
    closed form's onset, with a small pressing force at the accumulation point, and not
    1e-7 above it: its sign change lies within its rounding floor of the onset, as at eta
    0.05 (bisected alone: 3.396e-8 above, against 3.41e-8 at 0.05)."""
    onset = OMEGA_ONSET_AT[0.052]
    stick, res = simulated_stick(onset + 1e-8, [0.0, 0.0], THETA_R, eta=0.052)
    assert stick is not None and len(res.chatter) == 1
    assert 0 < float(stick.forces[0, 0]) < 5e-4  # measured 1.42e-4
    stick, res = simulated_stick(onset + 1e-7, [0.0, 0.0], THETA_R, eta=0.052)
    period = 2 * math.pi / (onset + 1e-7)
    assert stick is None and all(c.time > period for c in res.chatter)


def test_the_so_curve_in_omega_and_eta_is_the_closed_form_onset():
    """The SO curve from the branch's SO in (omega, eta), eta in (0.048, 0.052): it reaches
    both edges with no codim-2 point, and none can be there (the stick lasts 2.7 and the
    landing speed is 4.4, far from SE and ZV; one stop, no GR; the multipliers of a motion
    with a stick are 0, no SN, PD or NS). It passes through the branch's SO at eta 0.05,
    and at eta 0.048, 0.05 and 0.052 lies above the closed form's onset by the chatter
    cut's offset (0.15 .. 0.25 CHATTER_SPEED; measured 2.0509e-6, 2.0524e-6, 2.0541e-6).
    The SO test at an accumulation point is known to about 1e-8 only (8e-9 peak to peak
    over steps of 1e-14 in the unknowns: the accumulation time sums bounce returns each
    known to eps |x| / u, u down to R^17 times the landing speed, times the force's rate
    2.6): the curve measures that noise at its start and raises its default Newton
    tolerance of 1e-10 to 4 times it (at 1e-10 Newton stalls; 4e-8 is 3e-11 in omega).
    The options are the curve's defaults."""
    ds = ic.curve(None, None, "SO", start=branch(), parameters=("omega", "eta"),
                  bounds={"omega": (0.85, 1.0), "eta": (0.048, 0.052)})
    options = json.loads(ds.attrs["options"])
    message = options["message"]
    assert message.count("parameter bound reached") == 2, message
    assert 1e-9 < options["test_noise"] < 1e-7
    assert options["newton_tol"] == pytest.approx(4.0 * options["test_noise"], rel=1e-12)
    assert ds.sizes["codim2"] == 0
    assert ds["stick_time_k"].values.min() > 2.5
    assert np.abs(ds["impact_velocity"].values).min() > 4.0
    assert np.abs(ds["multipliers"].values).max() < 1e-12
    for eta, onset in OMEGA_ONSET_AT.items():
        (crossing,) = ic.curve_crossings(ds, "eta", eta)
        offset = crossing["omega"] - onset
        assert 0.15 * sticky.CHATTER_SPEED < offset < 0.25 * sticky.CHATTER_SPEED, (eta, offset)
        if eta == 0.05:
            assert crossing["omega"] == pytest.approx(OMEGA_SO, abs=1e-9)
    k = int(np.argmax(ds["eta"].values))
    omega, eta = float(ds["omega"].values[k]), float(ds["eta"].values[k])
    assert onset_test(motion(omega, eta)) == pytest.approx(0.0, abs=1e-7)  # 1350 per omega
    assert motion(omega - 1e-7, eta).physical and not motion(omega + 1e-7, eta).physical


def test_an_so_curve_asked_for_a_tolerance_below_its_noise_says_so(caplog):
    """newton_tol=1e-13 given: far below 4 times the SO test's noise at the accumulation
    point (about 1e-8), the start does not converge (at 1e-10 the residual stays near
    3e-9); the warning and the error say why."""
    with caplog.at_level("WARNING", logger="impactcont.analysis.curves"), \
            pytest.raises(ic.NoPeriodicMotionError, match="below 4 times the SO test's "
                          "rounding noise"):
        ic.curve(None, None, "SO", start=branch(), parameters=("omega", "eta"),
                 bounds={"omega": (0.85, 1.0), "eta": (0.048, 0.052)}, newton_tol=1e-13)
    assert "newton_tol=1e-13 is below 4 times the rounding noise" in caplog.text
