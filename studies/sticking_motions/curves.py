"""The end of the riding damper's rides in two parameters: the SE curve against its closed form.

Issue 30: the special points that bound periodic motions with sticking phases, and their
curves in two parameters. The impact damper of case (c) (:mod:`closed_form`: a primary of
mass 1 on a spring 1 with a damper ``c = 2 eta``, forced ``cos(theta)``, a plastic ball of
mass ``m`` in ``|x2 - x1| <= b``) rides each wall until the end of its rides (SE: the stick
shrinks to nothing, the landing is itself a release), at ``omega = 2.393422959745478`` for
``eta = 0.3``. This script follows that SE point in ``(omega, p2)`` with the package
(:func:`impactcont.curve` from the branch's SE point, ``p2`` one of ``eta``, ``b``, ``m2``)
and puts the closed form's end next to every curve point: :func:`riding_end_at` solves,
in mpmath at 30 digits, the three equations of :func:`closed_form.riding_end` (the
symmetric flight from a release on the upper wall lands on the mirror image half a period
later, where the lower wall presses the ball 0) in ``(theta, x1', omega)`` at that point's
``p2``. Nothing of the package enters the closed form but the seed of its Newton (the
package's release phase and speed, which Newton moves to 30 digits).

Run: ``python studies/sticking_motions/curves.py [eta|b|m2]`` (about half a minute: the
branch to the end of the rides, the curve, one closed form a point). With ``--cost`` it
times a point of the SE curve against one of an SN curve of the same machine's plain
motion (``"UL"`` at R = 0.6, whose branch has no PD; the SN test is the PD test's kind: a
signed smallest singular value from the shot with a forward-difference row).
"""

from __future__ import annotations

import argparse
import importlib.util
import json
import logging
import math
import os
import sys
import time
from pathlib import Path
from typing import Any

import mpmath
import numpy as np

import impactcont as ic
from impactcont.model.stops import Stops

HERE = Path(__file__).resolve().parent

#: The closed form's name of each second parameter (``m2`` is the ball's mass ``m``).
CLOSED_FORM_NAMES = {"eta": "eta", "b": "b", "m2": "m"}
#: The box of each second parameter (around the study's machine: eta 0.3, b 0.3, m 0.2).
BOXES = {"eta": (0.2, 0.4), "b": (0.25, 0.35), "m2": (0.15, 0.25)}


def closed_form() -> Any:
    """The study's closed forms (:mod:`closed_form`, mpmath, no package code)."""
    name = "sticking_closed_form_curves"
    module = sys.modules.get(name)
    if module is None:
        spec = importlib.util.spec_from_file_location(name, HERE / "closed_form.py")
        module = importlib.util.module_from_spec(spec)
        sys.modules[name] = module  # dataclasses look the module up by name
        spec.loader.exec_module(module)
    return module


def damper(omega: float, **more: Any) -> ic.ImpactOscillator:
    """Case (c): primary 1 on spring 1 (eta 0.3), plastic ball 0.2 in |x2 - x1| <= 0.3."""
    values = {"eta": 0.3, "b": 0.3, "R": 0.0, **more}
    mass = values.pop("m", 0.2)
    return ic.ImpactOscillator(M=np.diag([1.0, mass]), K=np.diag([1.0, 0.0]), F=[1.0, 0.0],
                               omega=omega, stops=Stops(mass=2, relative_to=1, mirror=True),
                               **values)


def riding_start(osc: ic.ImpactOscillator) -> np.ndarray:
    """The ball on the upper wall, the pair on the held system's forced response."""
    m, c, omega = osc.M[1, 1], osc.C[0, 0], osc.omega
    amplitude = 1.0 / (1.0 - (1.0 + m) * omega**2 + 1j * c * omega)
    x1, v1 = amplitude.real, (1j * omega * amplitude).real
    return np.array([x1, x1 + osc.b, v1, v1])


def ride_branch(omega: float = 2.3, bounds: tuple[float, float] = (2.2, 2.45)) -> Any:
    """The riding motion (pattern ``"ul"``) settled on by the simulator at `omega`, followed
    in omega past the end of its rides (SE located on it)."""
    osc = damper(omega)
    motion = ic.multi_impact_orbit(osc, 1, 2, ic.simulate(osc, riding_start(osc), 0.0, 20.0))
    return ic.continuation(motion, parameter="omega", bounds=bounds, ds_max=0.05,
                           both_directions=False)


def se_curve(branch: Any, p2: str = "eta", box: tuple[float, float] | None = None,
             **options: Any) -> Any:
    """The SE curve of the riding motion in ``(omega, p2)`` from the branch's SE point."""
    box = BOXES[p2] if box is None else box
    return ic.curve(None, None, "SE", start=branch, parameters=("omega", p2),
                    bounds={"omega": (1.0, 4.0), p2: box}, **options)


def upper_release(ds: Any, point: int) -> tuple[float, float]:
    """``(theta, x1')`` at the release from the upper wall of curve point `point` (the stick
    time is 0 on the SE curve: the landing on the upper wall is the release)."""
    pattern = str(ds.attrs["pattern"])
    k = pattern.lower().index("u")
    theta = float(ds["delta_k"].values[point, k])
    theta += float(ds["omega"].values[point]) * float(ds["stick_time_k"].values[point, k])
    return theta, float(ds["release_state_k"].values[point, k, 2])


def riding_end_at(p2: str, value: float, guess: tuple[float, float, float]) -> mpmath.mpf:
    """The closed form's end of the rides in omega at ``p2 = value`` (30 digits), from
    ``guess = (theta, x1', omega)`` (:func:`closed_form.riding_end`)."""
    cf = closed_form()
    return cf.riding_end(guess, **{CLOSED_FORM_NAMES[p2]: mpmath.mpf(repr(float(value)))})[0]


def compare(ds: Any, p2: str) -> list[tuple[float, float, float]]:
    """``(p2, omega on the curve, omega of the closed form)`` at every curve point."""
    out = []
    for k in range(ds.sizes["point"]):
        omega, value = float(ds["omega"].values[k]), float(ds[p2].values[k])
        end = riding_end_at(p2, value, (*upper_release(ds, k), omega))
        out.append((value, omega, float(end)))
    return out


def plain_branch() -> Any:
    """The same machine's plain motion (``"UL"``, R = 0.6: no sticking phases) settled on
    by the simulator at omega 2.5 (as ``branch_cost.py``), followed in omega to its fold (SN
    at 4.3995; its branch in omega (0.8, 5) has GR, BP, SN and ZV, no PD)."""
    osc = damper(2.5, R=0.6)
    motion = ic.multi_impact_orbit(osc, 1, 2, ic.simulate(osc, np.array([0.0, 0.3, 0.0, 0.0]),
                                                           0.0, 150.0), pattern="UL")
    return ic.continuation(motion, parameter="omega", bounds=(2.4, 4.5), ds_max=0.05,
                           detect=["SN"])


def cost(rounds: int = 3) -> None:
    """Prints the cost of a curve point: the SE curve of the riding motion against the SN
    curve of the same machine's plain motion (each in (omega, eta), eta in (0.2, 0.4),
    ``ds_max = 0.02``; the whole :func:`impactcont.curve` call over its points), without
    and with the location of codim-2 points, the best of `rounds` after a warm-up run."""
    curves = {"SE (sticky 'ul', R 0)": (ride_branch(), "SE"),
              "SN (plain 'UL', R 0.6)": (plain_branch(), "SN")}

    def run(branch: Any, kind: str, codim2: bool) -> tuple[float, int]:
        begin = time.perf_counter()
        ds = ic.curve(None, None, kind, start=branch, parameters=("omega", "eta"),
                      bounds={"omega": (1.0, 5.0), "eta": BOXES["eta"]}, ds_max=0.02,
                      detect_codim2_points=codim2)
        return (time.perf_counter() - begin) / ds.sizes["point"], ds.sizes["point"]

    for branch, kind in curves.values():
        run(branch, kind, False)  # warm
    for codim2 in (False, True):
        best: dict[str, tuple[float, int]] = {}
        for _ in range(rounds):
            for name, (branch, kind) in curves.items():
                best[name] = min(best.get(name, (math.inf, 0)), run(branch, kind, codim2))
        plain = best["SN (plain 'UL', R 0.6)"][0]
        print(("with" if codim2 else "without") + " codim-2 points: " + ", ".join(
            f"{name} {seconds * 1e3:.1f} ms/point ({points} points, ratio "
            f"{seconds / plain:.2f})" for name, (seconds, points) in best.items()))
    print(f"load {os.getloadavg()[0]:.1f}")


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("p2", nargs="?", default="eta", choices=sorted(BOXES))
    parser.add_argument("--cost", action="store_true", help="time a curve point instead")
    args = parser.parse_args(argv)
    logging.basicConfig(level=logging.WARNING)
    if args.cost:
        cost()
        return 0
    t0 = time.perf_counter()
    branch = ride_branch()
    t1 = time.perf_counter()
    ds = se_curve(branch, args.p2, ds_max=0.02)
    t2 = time.perf_counter()
    rows = compare(ds, args.p2)
    message = json.loads(ds.attrs["options"]).get("message", "")
    print(f"SE curve in (omega, {args.p2}): {len(rows)} points in {t2 - t1:.2f} s "
          f"({(t2 - t1) / len(rows) * 1e3:.0f} ms a point; branch {t1 - t0:.1f} s); {message}")
    print(f"| {args.p2} | omega (curve) | omega (closed form) | difference |")
    print("|---|---|---|---|")
    for value, omega, end in rows:
        print(f"| {value:.6f} | {omega:.15f} | {end:.15f} | {omega - end:.1e} |")
    worst = max(abs(omega - end) for _, omega, end in rows)
    print(f"largest difference {worst:.2e}")
    return 0 if math.isfinite(worst) else 1


if __name__ == "__main__":
    raise SystemExit(main())
