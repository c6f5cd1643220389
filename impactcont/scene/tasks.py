"""What each built-in scene section computes, as datasets, and how they are described.

One handler per section (registered by :mod:`impactcont.scene.sections`): ``compute``
turns one validated entry into an :class:`xarray.Dataset` with the public
API (:func:`~impactcont.periodic_orbits`, :func:`~impactcont.continuation`,
:func:`~impactcont.robust_stability`, :func:`~impactcont.simulate`);
``describe`` writes Markdown tables from datasets (used by ``summary.md``
and ``impactcont info``). Only what an entry asks for is computed: no
trajectory unless ``trajectory = true``, no robust pass unless a
``[[robust]]`` table exists.

Layouts (every variable has ``long_name``, ``units`` and ``description``;
the attribute ``impactcont_dataset`` says which layout a dataset has):

* orbits (``"orbits"``): dims ``orbit``, ``multiplier``, ``component``,
  ``g_row``/``g_col`` (the coordinates of ``z`` of eq. 19), the scalar
  ``amplitude_squared`` and the scalar coordinates ``omega``, ``b``;
* branches: the branch schema of ``docs/dataset.md``;
* robust (``"robust"``): ``G0``, ``P``, ``theta``, ``Gamma`` on
  ``(g_row, g_col)``, the scalars ``epsilon``, ``epsilon0``, ``robust`` and the
  scalar coordinates ``omega``, ``b`` (of the nominal point);
* simulations (``"simulation"``): dims ``impact``, ``component`` and, with a
  trajectory, ``sample``; the scalar coordinates ``omega``, ``b``.
"""

from __future__ import annotations

import json
import logging
import math
import time
import warnings
from collections.abc import Mapping
from typing import Any

import numpy as np
import xarray as xr

from impactcont.analysis.branch import continuation
from impactcont.dataset import special_variable, state_component_names
from impactcont.dataset.schema import robust_attributes
from impactcont.dataset.simulation import simulation_dataset
from impactcont.errors import NoPeriodicMotionError
from impactcont.model.oscillator import ImpactOscillator
from impactcont.orbit.periodic import PeriodicOrbit, amplitude_squared, periodic_orbits
from impactcont.orbit.robust import robust_stability
from impactcont.scene.entries import BranchSpec, OrbitSpec, RobustSpec, SimulationSpec
from impactcont.simulate import simulate

__all__ = ["BRANCHES", "ORBITS", "ROBUST", "SIMULATIONS", "g_labels", "markdown_table",
           "points_table", "special_points_table"]

log = logging.getLogger(__name__)


def g_labels(n: int) -> list[str]:
    """Names of the coordinates of ``z`` (eq. 19): ``dx2..dxn, dv1..dvn, ddelta``."""
    return [f"dx{i}" for i in range(2, n + 1)] + [f"dv{i}" for i in range(1, n + 1)] + \
        ["ddelta"]


def _attrs(long_name: str, description: str, units: str = "1") -> dict[str, str]:
    return {"long_name": long_name, "units": units, "description": description}


def _coords(n: int) -> dict[str, Any]:
    labels = g_labels(n)
    return {"component": state_component_names(n), "g_row": labels, "g_col": labels}


def _var(dims: tuple[str, ...], data: Any, long_name: str, description: str,
         units: str = "1") -> xr.Variable:
    return xr.Variable(dims, data, attrs=_attrs(long_name, description, units))


def _parameters(osc: ImpactOscillator) -> dict[str, xr.Variable]:
    """``omega`` and ``b`` as scalar coordinates (as on the points of a branch): readable
    without parsing the JSON, and carried by every variable."""
    return {"omega": _var((), osc.omega, "forcing frequency",
                          "Nondimensional forcing frequency omega of eq. (1)."),
            "b": _var((), osc.b, "gap", "Position b of the stop met by mass 1 (eq. 3).")}


def _fmt(x: Any, digits: int = 6) -> str:
    if isinstance(x, (bool, np.bool_)):
        return "yes" if x else "no"
    if isinstance(x, (int, np.integer)):
        return str(int(x))
    x = float(x)
    if math.isnan(x):
        return "-"
    if math.isinf(x):
        return "inf" if x > 0 else "-inf"
    return f"{x:.{digits}g}"


def markdown_table(header: list[str], rows: list[list[Any]]) -> list[str]:
    """Markdown table lines; numbers formatted to 6 significant digits."""
    out = ["| " + " | ".join(header) + " |", "|" + "|".join("---" for _ in header) + "|"]
    out += ["| " + " | ".join(c if isinstance(c, str) else _fmt(c) for c in row) + " |"
            for row in rows]
    return out


def _changes_text(osc_json: str) -> str:
    osc = json.loads(osc_json)
    return f"omega={_fmt(osc['omega'])}, b={_fmt(osc['b'])}"


# ---------------------------------------------------------------------------------------------
# [[orbits]]
# ---------------------------------------------------------------------------------------------
class Orbits:
    """``[[orbits]]``: every root of eq. (15) at one parameter point."""

    def compute(self, entry: OrbitSpec, context: Any = None) -> xr.Dataset:
        osc = entry.oscillator
        orbits = periodic_orbits(osc, entry.N)
        kept = orbits
        if entry.which == "physical":
            kept = [o for o in orbits if o.physical]
        elif entry.which == "stable":
            kept = [o for o in orbits if o.physical and o.stable]
        ds = orbits_dataset(kept, osc, entry.N)
        ds.attrs.update(name=entry.name, which=entry.which)
        log.info("orbits %s: %d root(s) of eq. (15) with N=%d at %s", entry.name,
                 len(kept), entry.N, _changes_text(osc.to_json()))
        if not kept:
            ds.attrs["note"] = _no_motion_note(orbits, float(ds["amplitude_squared"]), osc,
                                               entry.which)
            log.warning("orbits %s: %s", entry.name, ds.attrs["note"])
        return ds

    def describe(self, datasets: Mapping[str, xr.Dataset]) -> list[str]:
        rows = []
        for name, ds in datasets.items():
            where = _changes_text(ds.attrs["oscillator"])
            amplitude = float(ds["amplitude_squared"]) if "amplitude_squared" in ds else \
                float(ds.attrs.get("amplitude_squared", math.nan))
            if ds.sizes["orbit"] == 0:
                note = ds.attrs.get("note") or f"no motion kept (which = {ds.attrs.get('which')})"
                rows.append([name, ds.attrs["N"], where, amplitude, "-", "-", "-", "-", "-",
                             "-", "-", str(note).replace("|", "/")])
                continue
            for k in range(ds.sizes["orbit"]):
                physical = bool(ds["physical"][k])
                rows.append([name, ds.attrs["N"], where, amplitude, f"{int(ds['root'][k]):+d}",
                             float(ds["delta"][k]), float(ds["impact_velocity"][k]),
                             float(ds["gap_min"][k]), float(ds["spectral_radius"][k]),
                             bool(ds["stable"][k]) if physical else NOT_PHYSICAL, physical,
                             str(ds["reason"].values[k]) or "-"])
        return markdown_table(["entry", "N", "at", "c^2+s^2", "root", "delta", "impact velocity",
                       "gap_min",
                       "rho(G)", "stable", "physical", "note"], rows)

    def special_points(self, datasets: Mapping[str, xr.Dataset]) -> list[dict[str, Any]]:
        return []


#: The stability shown for a motion that is not physical: rho(G) < 1 of a root of eq. (15)
#: that is no motion of the oscillator says nothing about the oscillator.
NOT_PHYSICAL = "- (not physical)"


def _no_motion_note(roots: list[PeriodicOrbit], amplitude: float, osc: ImpactOscillator,
                    which: str) -> str:
    """Why an ``[[orbits]]`` entry keeps no motion, with the numbers."""
    if not roots:
        reach = math.sqrt(amplitude)
        return (f"no motion: c^2 + s^2 = {amplitude:.6g} < b^2 = {osc.b ** 2:.6g} (eq. 15), "
                f"the stop at b = {osc.b:g} is out of reach of the forced motion; N-1 "
                f"motions exist here only for b between {-reach:.6g} and {reach:.6g}")
    wanted = "physical" if which == "physical" else "physical and stable"
    found = "; ".join(f"root {o.root:+d}: " + ("physical" if o.physical else "not physical")
                      + (", stable" if o.stable else f", unstable (rho(G) = "
                         f"{o.spectral_radius:.4g})") for o in roots)
    return f"no motion kept (which = {which}): none of the {len(roots)} roots is {wanted} " \
           f"({found})"


def orbits_dataset(orbits: list[PeriodicOrbit], osc: ImpactOscillator, N: int) -> xr.Dataset:
    """Dataset of periodic orbits (dimension ``orbit``), as written to ``orbits.nc``."""
    n = osc.n
    k = len(orbits)

    def col(attr: str, dtype: Any = float) -> np.ndarray:
        return np.array([getattr(o, attr) for o in orbits], dtype=dtype).reshape(k)

    data = {
        "root": _var(("orbit",), col("root", np.int64), "root of eq. (15)",
                     "Sign in front of the square root of eq. (15)."),
        "delta": _var(("orbit",), col("delta"), "impact phase",
                      "Forcing phase at the impact, in (-pi, pi] (eq. 15).", "rad"),
        "period": _var(("orbit",), col("period"), "period", "T = 2 pi N / omega."),
        "impact_velocity": _var(("orbit",), col("impact_velocity"), "impact velocity",
                                "x1'(T-), velocity of mass 1 just before the impact (h2)."),
        "gap_min": _var(("orbit",), col("gap_min"), "smallest interior gap",
                        "Smallest b - x1 at interior maxima of x1 (eq. 16); +inf if none."),
        "spectral_radius": _var(("orbit",), col("spectral_radius"), "spectral radius",
                                "rho(G), largest multiplier modulus."),
        "stable": _var(("orbit",), col("stable", bool), "stable",
                       "rho(G) < 1 (Theorem 3.1)."),
        "physical": _var(("orbit",), col("physical", bool), "physical",
                         "impact_velocity > 0 and gap_min > 0 (eq. 16)."),
        "reason": _var(("orbit",), np.array([o.reason for o in orbits], dtype=object)
                       if k else np.array([], dtype=str), "why not physical",
                       "Empty when the motion is physical."),
        "multipliers": _var(("orbit", "multiplier"),
                            np.array([o.multipliers for o in orbits], dtype=complex)
                            .reshape(k, 2 * n), "Floquet multipliers",
                            "Eigenvalues of G (eq. 25), largest modulus first."),
        "state": _var(("orbit", "component"),
                      np.array([o.state for o in orbits], dtype=float).reshape(k, 2 * n),
                      "state after impact", "X(0) right after the impact (eq. 13)."),
        "G": _var(("orbit", "g_row", "g_col"),
                  np.array([o.G for o in orbits], dtype=float).reshape(k, 2 * n, 2 * n),
                  "impact-map Jacobian", "G of eq. (25) in z = [dx2..dxn, dv1..dvn, ddelta]."),
        "amplitude_squared": _var((), amplitude_squared(osc, N), "c^2 + s^2",
                                  "c^2 + s^2 of eq. (14): N-1 motions exist iff it is >= b^2."),
    }
    return xr.Dataset(data, coords={**_coords(n), **_parameters(osc)},
                      attrs={"title": f"Periodic N-1 motions, N = {N}", "N": N,
                             "impactcont_dataset": "orbits", "oscillator": osc.to_json()})


ORBITS = Orbits()


# ---------------------------------------------------------------------------------------------
# [[branches]]
# ---------------------------------------------------------------------------------------------
class Branches:
    """``[[branches]]``: :func:`impactcont.continuation` of one branch."""

    def compute(self, entry: BranchSpec, context: Any = None) -> xr.Dataset:
        t0 = time.perf_counter()
        try:
            ds = continuation(entry.oscillator, **entry.continuation_kwargs())
        except NoPeriodicMotionError as exc:
            why = _out_of_reach(entry)
            if why is None:
                raise
            raise NoPeriodicMotionError(f"{exc}: {why}") from exc
        ds.attrs["name"] = entry.name
        log.info("branch %s: N=%d in %s, %d points, %d special point(s) (%.1f s)", entry.name,
                 entry.N, entry.parameter, ds.sizes["point"], ds.sizes["special"],
                 time.perf_counter() - t0)
        return ds

    def describe(self, datasets: Mapping[str, xr.Dataset]) -> list[str]:
        rows = []
        for name, ds in datasets.items():
            p = ds.attrs["parameter"]
            x = np.asarray(ds[p].values, dtype=float)
            stable = np.asarray(ds["stable"].values, bool) & np.asarray(ds["physical"].values,
                                                                        bool)
            options = json.loads(ds.attrs.get("options", "{}"))
            rows.append([name, int(ds.attrs["N"]), p,
                         f"[{_fmt(x.min())}, {_fmt(x.max())}]" if x.size else "-",
                         int(x.size), int(np.count_nonzero(np.asarray(ds["physical"].values,
                                                                      bool))),
                         int(np.count_nonzero(stable)), int(ds.sizes["special"]),
                         str(options.get("message", "-")).replace("|", "/")])
        return markdown_table(["branch", "N", "parameter", "range", "points", "physical", "stable",
                       "special points", "stop"], rows)

    def special_points(self, datasets: Mapping[str, xr.Dataset]) -> list[dict[str, Any]]:
        out = []
        for name, ds in datasets.items():
            p = ds.attrs["parameter"]
            physical = np.asarray(ds["physical"].values, dtype=bool)
            for k in range(ds.sizes["special"]):
                mult = np.asarray(ds[special_variable("multipliers")].values[k])
                nearest = int(ds[special_variable("point")].values[k])
                inside = 0 <= nearest < physical.size
                out.append({
                    "branch": name, "N": int(ds.attrs["N"]), "parameter": p,
                    "label": str(ds[special_variable("label")].values[k]),
                    "value": float(ds[special_variable(p)].values[k]),
                    "omega": float(ds[special_variable("omega")].values[k]),
                    "b": float(ds[special_variable("b")].values[k]),
                    "delta": float(ds[special_variable("delta")].values[k]),
                    "status": str(ds[special_variable("status")].values[k]),
                    "precision": float(ds[special_variable("precision")].values[k]),
                    "rho": float(np.max(np.abs(mult))) if mult.size else math.nan,
                    "physical": bool(physical[nearest]) if inside else False,
                    "why": _not_physical_reason(ds, nearest) if inside else "",
                })
        return _mirrors_noted(out)


BRANCHES = Branches()


def _out_of_reach(entry: BranchSpec, samples: int = 400) -> str | None:
    """The numbers behind "no motion anywhere in bounds": c^2 + s^2 against b^2.

    None if the scan finds a motion (then the failure has another cause).
    """
    values = np.linspace(*entry.bounds, samples)
    margin = np.empty(samples)
    amplitude = np.empty(samples)
    gap = np.empty(samples)
    with warnings.catch_warnings():  # only for the message: accuracy warnings do not matter
        warnings.simplefilter("ignore")
        for i, value in enumerate(values):
            osc = entry.oscillator.replace(**{entry.parameter: float(value)})
            amplitude[i], gap[i] = amplitude_squared(osc, entry.N), osc.b
            margin[i] = amplitude[i] - gap[i] ** 2
    best = int(np.nanargmax(margin)) if np.any(np.isfinite(margin)) else 0
    if margin[best] >= 0:
        return None
    reach = math.sqrt(max(amplitude[best], 0.0))
    return (f"closest at {entry.parameter} = {values[best]:.6g}, where c^2 + s^2 = "
            f"{amplitude[best]:.6g} against b^2 = {gap[best] ** 2:.6g} (eq. 15): the stop is "
            f"out of reach of the forced motion; N-1 motions there need b between "
            f"{-reach:.6g} and {reach:.6g}")


def _not_physical_reason(ds: xr.Dataset, k: int) -> str:
    """Why point ``k`` of a branch is not a physical motion (eq. 16), from its numbers; empty
    when it is one."""
    if bool(ds["physical"].values[k]):
        return ""
    velocity, gap = float(ds["impact_velocity"].values[k]), float(ds["gap_min"].values[k])
    why = []
    if not velocity > 0:
        why.append(f"impact velocity {velocity:.3g} <= 0: mass 1 does not arrive towards the "
                   f"stop")
    if not gap > 0:
        why.append(f"x1 passes the stop inside the period (gap_min = {gap:.3g})")
    return "; ".join(why) or "not physical"


def _mirrors_noted(points: list[dict[str, Any]]) -> list[dict[str, Any]]:
    """``points`` with each point of a branch at b = 0 that mirrors an earlier one noted.

    At b = 0 the motion mirrored through the stop (``x -> -x``, ``delta -> delta + pi``)
    solves eq. (15) too, so a branch through both roots meets each bifurcation twice, at
    the same parameter value; the mirrored copy arrives from the far side of the stop.
    """
    for j, q in enumerate(points):
        if q["b"] != 0.0:
            continue
        for p in points[:j]:
            if (p["branch"], p["label"]) != (q["branch"], q["label"]) or p["b"] != 0.0:
                continue
            precision = np.nan_to_num([p["precision"], q["precision"]], nan=0.0)
            close = abs(p["value"] - q["value"]) <= max(1e-8, 100 * float(precision.max()))
            if close and abs(math.remainder(q["delta"] - p["delta"] - math.pi,
                                            2 * math.pi)) < 1e-6:
                mirror = (f"the mirror image (x -> -x, delta + pi) of the {p['label']} at "
                          f"delta = {_fmt(p['delta'])}: at b = 0 both roots of eq. (15) are "
                          f"one branch")
                q["why"] = f"{q['why']}; {mirror}" if q["why"] else mirror
                break
    return points


#: What rho(G) of a zero-velocity impact is shown as: G (eq. 25) divides by the impact
#: velocity, so the number computed next to v = 0 only says how close it came.
ZV_RADIUS = "unbounded (pole of G at v = 0)"


def special_points_table(points: list[dict[str, Any]]) -> list[str]:
    """Markdown table of special points (rows from :meth:`Branches.special_points`).

    ``rho(G)`` of a ZV point (a zero-velocity impact, where G of eq. 25 has a pole) is
    :data:`ZV_RADIUS`; the last column says why a point that is not physical is not (its
    numbers, and the point it mirrors on a branch at b = 0).
    """
    rows = [[p["branch"], p["N"], p["label"], f"{p['parameter']} = {_fmt(p['value'], 8)}",
             p["omega"], p["b"], p["delta"], ZV_RADIUS if p["label"] == "ZV" else p["rho"],
             p["physical"], p["status"], p["precision"],
             str(p.get("why") or "-").replace("|", "/")] for p in points]
    return markdown_table(["branch", "N", "label", "at", "omega", "b", "delta", "rho(G)",
                           "physical", "status", "precision", "why not physical"], rows)


# ---------------------------------------------------------------------------------------------
# [[robust]]
# ---------------------------------------------------------------------------------------------
class Robust:
    """``[[robust]]``: :func:`impactcont.robust_stability` over a box."""

    def compute(self, entry: RobustSpec, context: Any = None) -> xr.Dataset:
        rs = robust_stability(entry.oscillator, entry.N, vary=entry.vary, nominal=entry.nominal,
                              root=entry.root, samples=entry.samples)
        n = entry.oscillator.n
        shape = (2 * n, 2 * n)
        P = rs.P if rs.P is not None else np.full(shape, np.nan)
        g = ("g_row", "g_col")
        data = {
            "G0": _var(g, rs.G0, "G at the nominal point", "G0 = G(q0) (eq. 25, 26)."),
            "P": _var(g, P, "Lyapunov matrix", "G0^T P G0 - P = -I (eq. 27); NaN if G0 is "
                      "not Schur stable."),
            "theta": _var(g, rs.theta, "largest perturbation",
                          "theta_ij = max over the box of |G_ij - G0_ij| (eq. 28)."),
            "grid_theta": _var(g, rs.grid_theta, "largest perturbation on the grid",
                               "The maxima over the sampled grid alone."),
            "Gamma": _var(g, rs.Gamma, "perturbation pattern",
                          "Gamma = theta / epsilon (eq. 28)."),
            "epsilon": _var((), rs.epsilon, "perturbation size", "max theta_ij (eq. 28)."),
            "epsilon0": _var((), rs.epsilon0, "robust bound",
                             "epsilon^0 of eq. (29); NaN if G0 is not Schur stable."),
            "robust": _var((), bool(rs.robust), "robustly stable",
                           "G0 Schur stable and epsilon < epsilon0 (Theorem 3.2)."),
            "spectral_radius": _var((), rs.orbit.spectral_radius, "spectral radius of G0",
                                    "rho(G0)."),
            "delta": _var((), rs.orbit.delta, "impact phase at q0",
                          "Forcing phase at the impact at q0, in (-pi, pi] (eq. 15).", "rad"),
            "state": _var(("component",), rs.orbit.state, "state after impact at q0",
                          "X(0) of eq. (13) at the nominal point."),
            "multipliers": _var(("multiplier",), rs.orbit.multipliers, "multipliers of G0",
                                "Eigenvalues of G0, largest modulus first."),
        }
        coords = {**_coords(n), **_parameters(rs.orbit.oscillator)}
        ds = xr.Dataset(data, coords=coords, attrs={
            "title": f"Robust stability of the N={entry.N} motion", "name": entry.name,
            "impactcont_dataset": "robust",
            "N": entry.N, "root": rs.root, "samples": rs.samples,
            "evaluations": rs.evaluations,
            **robust_attributes(rs.vary, rs.nominal, rs.argmax),
            "message": rs.message, "oscillator": rs.orbit.oscillator.to_json()})
        log.info("robust %s: %s", entry.name, rs.message)
        return ds

    def describe(self, datasets: Mapping[str, xr.Dataset]) -> list[str]:
        rows = []
        for name, ds in datasets.items():
            vary = json.loads(ds.attrs["vary"])
            nominal = json.loads(ds.attrs["nominal"])
            box = ", ".join(f"{k} in [{_fmt(lo)}, {_fmt(hi)}]" for k, (lo, hi) in vary.items())
            q0 = ", ".join(f"{k} = {_fmt(v)}" for k, v in nominal.items())
            rows.append([name, int(ds.attrs["N"]), box, q0, float(ds["spectral_radius"]),
                         float(ds["epsilon"]), float(ds["epsilon0"]), bool(ds["robust"])])
        return markdown_table(["entry", "N", "box", "nominal", "rho(G0)", "epsilon", "epsilon0",
                       "robustly stable"], rows)

    def special_points(self, datasets: Mapping[str, xr.Dataset]) -> list[dict[str, Any]]:
        return []


ROBUST = Robust()


# ---------------------------------------------------------------------------------------------
# [[simulations]]
# ---------------------------------------------------------------------------------------------
class Simulations:
    """``[[simulations]]``: :func:`impactcont.simulate` from an orbit or a given state."""

    def compute(self, entry: SimulationSpec, context: Any = None) -> xr.Dataset:
        osc = entry.oscillator
        n = osc.n
        if entry.start == "state":
            state, delta = np.array(entry.state, dtype=float), float(entry.delta)
            start = "state"
        else:
            orbits = periodic_orbits(osc, entry.N)
            if entry.root is not None:
                orbits = [o for o in orbits if o.root == entry.root]
            if not orbits:
                raise NoPeriodicMotionError(
                    f"simulation {entry.name}: no N={entry.N} motion"
                    f"{'' if entry.root is None else f' with root {entry.root:+d}'} at "
                    f"{_changes_text(osc.to_json())} to start from")
            orbit = sorted(orbits, key=lambda o: (not o.physical, not o.stable))[0]
            state, delta = orbit.state.copy(), orbit.delta
            start = f"N={entry.N} motion, root {orbit.root:+d}"
        state[n:] += entry.perturbation
        res = simulate(osc, state, delta, entry.periods, trajectory=entry.trajectory,
                       samples_per_period=entry.samples_per_period,
                       max_impacts=entry.max_impacts)
        ds = simulation_dataset(res, name=entry.name, start=start,
                                perturbation=entry.perturbation)
        log.info("simulation %s: %d impacts in %g periods (%s)", entry.name,
                 res.impact_times.size, entry.periods, res.status.name)
        return ds

    def describe(self, datasets: Mapping[str, xr.Dataset]) -> list[str]:
        rows = []
        for name, ds in datasets.items():
            v = np.asarray(ds["impact_velocities"].values)
            rows.append([name, _changes_text(ds.attrs["oscillator"]), str(ds.attrs["start"]),
                         float(ds.attrs["periods"]), int(ds.sizes["impact"]),
                         float(v[-1]) if v.size else math.nan,
                         int(ds.sizes.get("sticking", 0)), int(ds.sizes.get("chatter", 0)),
                         "yes" if "X" in ds else "no", str(ds.attrs["status"]),
                         str(ds.attrs.get("impact_stops", ""))[-8:] or "-"])
        return markdown_table(["entry", "at", "start", "periods", "impacts", "last impact velocity",
                               "sticking phases", "accumulation points", "trajectory",
                               "status", "last stops (U/L)"], rows)

    def special_points(self, datasets: Mapping[str, xr.Dataset]) -> list[dict[str, Any]]:
        return []


SIMULATIONS = Simulations()


def points_table(points: list[dict[str, Any]]) -> list[str]:
    """Markdown table of points given as dicts (columns: the keys of the first one)."""
    if not points:
        return []
    header = list(points[0])
    return markdown_table(header, [[p.get(k, "-") for k in header] for p in points])
