"""The attributes impactcont reads back from its datasets, and their check.

Readers of a saved dataset (``impactcont info`` and ``plot``, the plots, the
drivers that start from a branch) interpret some of its attributes: the
oscillator as JSON, ``N``, the continued parameter, the impact pattern of an
N-p branch, ... A file whose attributes were edited would be misread (a
pattern ``"XX"`` listed as a motion) or fail deep inside a reader.
:func:`check_attributes` checks every attribute impactcont reads, for each
kind of dataset it writes, and names the attribute, its value and what is
allowed. :func:`impactcont.dataset.save` and :func:`impactcont.dataset.load`
run it on every dataset whatever their ``validate`` (which switches the check
of the variables against the schema): a dataset with wrong attributes is never
written, and a file with wrong attributes is never read as if it were right.

The kind of a dataset is its attribute ``impactcont_dataset`` (a branch has
none); in a file of a built-in scene section it must be the section's
(:data:`SECTION_KINDS`). Datasets of other kinds (a plugin's) are left to
their section. Each attribute of :data:`KIND_ATTRIBUTES` is checked where the
dataset has it; which attributes a dataset must have is part of its schema
(:func:`~impactcont.dataset.validate_branch_dataset`, ...), except in a file of
a built-in scene section, whose description reads :data:`SECTION_ATTRIBUTES`.

========== ==================================================================
kind       attributes checked, and what must hold
========== ==================================================================
any        ``oscillator``: JSON of an :class:`~impactcont.ImpactOscillator`
           with ``2n`` = the sizes of ``component`` and ``multiplier``;
           ``title``, ``impactcont_version``, ``history``: text
branch     ``N``: integer >= 1, ``2 pi N / omega`` the period of the N-p
           motions stored (the sum of ``flight_time_k``); ``parameter``: a
           continuable parameter with its column, which (and ``omega``,
           ``b``) is finite at every point; ``options``: a JSON
           object; ``impacts``: p >= 1, the size of ``impact`` (required
           with that dimension); ``pattern``: p letters ``U``/``L``, ``L``
           only with a lower stop (required with a lower stop), and letter
           k the stop the stored state right after impact k is on
           (``state_k``, ``state`` of an N-1 branch)
curve      ``kind``: SN, PD, NS, GR or ZV; ``N``; ``parameters``: two
           different parameters with their columns; ``options``
map        ``options``
orbits     ``N`` (``2 pi N / omega`` = the variable ``period``); ``which``,
           ``note``: text
robust     ``N``; ``vary``: JSON object of a parameter robust stability can vary
           (:func:`~impactcont.model.parameters.model_parameter`'s names, elements
           1-based, no lower stop's) to ``[low, high]``; ``nominal``: JSON object
           of numbers; ``argmax``: JSON object; ``element_indexing``: ``"1-based"``
           (absent in files written before: their ``F[i]`` counted from 0 and are
           read as ``F[i+1]`` and the attribute added,
           :func:`upgrade_robust_attributes`)
simulation ``start``, ``status``: text; ``periods``: a number > 0;
           ``impact_stops``: one letter ``U``/``L`` per impact (required
           with a lower stop)
========== ==================================================================

The root attributes of a scene file (``impactcont_kind``, ``scene``,
``scene_file``, ``title``, ...) are checked by :func:`check_file_attributes`.
"""

from __future__ import annotations

import json
import logging
import math
import re
from collections.abc import Callable, Mapping
from typing import Any

import numpy as np
import xarray as xr

from impactcont.model.oscillator import ImpactOscillator
from impactcont.model.parameters import GAP, model_parameter
from impactcont.model.stops import LOWER, UPPER
from impactcont.vocabulary import CURVE_KINDS, ELEMENT_FAMILIES, PARAMETERS

__all__ = [
    "KIND_ATTRIBUTES",
    "ROBUST_INDEXING",
    "ROBUST_INDEXING_ATTRIBUTE",
    "SECTION_ATTRIBUTES",
    "SECTION_KINDS",
    "SECTION_OTHER_KINDS",
    "check_attributes",
    "check_file_attributes",
    "check_pattern_attribute",
    "dataset_kind",
    "dataset_tag",
    "impacts_attribute",
    "oscillator_attribute",
    "split_parameters",
    "upgrade_robust_attributes",
]

log = logging.getLogger(__name__)

#: The kind of the datasets in a file of each built-in scene section.
SECTION_KINDS: dict[str, str] = {
    "orbits": "orbits", "branches": "branch", "switches": "branch", "multi_impact": "branch",
    "robust": "robust", "simulations": "simulation", "curves": "curve", "maps": "map"}
#: ``section -> the other kinds its files may hold``: a ``[[maps]]`` entry maps every N-1
#: motion (``"map"``) or one motion family (``"multi_impact_map"``, ``start`` given); a
#: ``[[curves]]`` entry from an N-p branch is followed by shooting and written as an N-p
#: branch in its second parameter (``"branch"``: no ``impactcont_dataset``, a
#: ``curve_kind``).
SECTION_OTHER_KINDS: dict[str, tuple[str, ...]] = {"maps": ("multi_impact_map",),
                                                   "curves": ("branch",)}

# Attributes every kind may carry, shown as text by ``impactcont info``.
_TEXT = ("title", "impactcont_version", "history")

#: ``kind -> attributes checked where present`` (``oscillator`` first: the others may
#: depend on it).
KIND_ATTRIBUTES: dict[str, tuple[str, ...]] = {
    "branch": ("oscillator", "N", "parameter", "options", "impacts", "pattern", *_TEXT),
    "curve": ("oscillator", "kind", "N", "parameters", "options", *_TEXT),
    "map": ("oscillator", "options", *_TEXT),
    "multi_impact_map": ("oscillator", "N", "options", "impacts", "pattern", *_TEXT),
    "orbits": ("oscillator", "N", "which", "note", *_TEXT),
    "robust": ("oscillator", "N", "vary", "nominal", "argmax", "element_indexing", *_TEXT),
    "simulation": ("oscillator", "start", "periods", "status", "impact_stops", *_TEXT),
}

#: ``kind -> attributes a dataset in a file of a built-in scene section must carry``
#: (the section's description and plots read them).
SECTION_ATTRIBUTES: dict[str, tuple[str, ...]] = {
    "branch": ("oscillator", "N", "parameter"),
    "curve": ("oscillator", "kind", "N", "parameters"),
    "map": ("oscillator",),
    "multi_impact_map": ("oscillator", "N"),
    "orbits": ("oscillator", "N"),
    "robust": ("oscillator", "N", "vary", "nominal"),
    "simulation": ("oscillator", "start", "periods", "status"),
}

_OSCILLATOR = "the oscillator as JSON text (ImpactOscillator.to_json())"
# The names PARAMETERS resolves: the named parameters and the elements (k2, M[1,2], F[2]).
_ALLOWED = (f"one of {list(PARAMETERS)} or an element name {list(ELEMENT_FAMILIES)} "
            "(1-based, e.g. 'k2', 'M[1,2]', 'F[2]')")


def _shown(value: Any, limit: int = 100) -> str:
    text = repr(value)
    return text if len(text) <= limit else f"{text[:limit - 3]}..."


def _refused(name: str, value: Any, allowed: str, why: str = "") -> ValueError:
    return ValueError(f"attribute {name!r} must be {allowed}; got {_shown(value)}{why}")


def _integer(name: str, value: Any, allowed: str) -> int:
    if (isinstance(value, (bool, np.bool_)) or not isinstance(value, (int, np.integer))
            or value < 1):
        raise _refused(name, value, allowed)
    return int(value)


def _json(name: str, value: Any, allowed: str) -> Any:
    if not isinstance(value, str):
        raise _refused(name, value, allowed)
    try:
        return json.loads(value)
    except ValueError as exc:  # json.JSONDecodeError
        raise _refused(name, value, allowed, f", which is not JSON ({exc})") from None


def _json_object(name: str, value: Any, allowed: str = "a JSON object (text)") -> dict:
    data = _json(name, value, allowed)
    if not isinstance(data, dict):
        raise _refused(name, value, allowed)
    return data


def _real(x: Any) -> bool:
    return (not isinstance(x, (bool, np.bool_)) and isinstance(x, (int, float, np.integer,
                                                                   np.floating))
            and math.isfinite(x))


def oscillator_attribute(ds: xr.Dataset) -> ImpactOscillator:
    """The oscillator of a dataset, from its ``oscillator`` attribute, checked.

    Parameters
    ----------
    ds : xarray.Dataset

    Returns
    -------
    ImpactOscillator

    Raises
    ------
    ValueError
        The attribute is missing, is not JSON, does not describe an oscillator,
        or its number of masses ``n`` differs from the dataset's dimensions
        ``component`` and ``multiplier`` (``2n``).
    """
    if "oscillator" not in ds.attrs:
        raise ValueError(f"attribute 'oscillator' is missing: it must be {_OSCILLATOR}")
    text = ds.attrs["oscillator"]
    data = _json("oscillator", text, _OSCILLATOR)
    if not isinstance(data, dict):
        raise _refused("oscillator", text, f"{_OSCILLATOR}: a JSON object")
    try:
        osc = ImpactOscillator.from_dict(data)
    except (TypeError, ValueError, KeyError) as exc:
        raise _refused("oscillator", text, _OSCILLATOR,
                       f", which is not a valid oscillator ({exc})") from None
    for dim in ("component", "multiplier"):
        if dim in ds.sizes and ds.sizes[dim] != 2 * osc.n:
            raise ValueError(f"attribute 'oscillator' has n={osc.n} masses, but dimension "
                             f"{dim!r} has size {ds.sizes[dim]}; allowed: an oscillator of "
                             f"{ds.sizes[dim] / 2:g} masses (size 2n)")
    return osc


def impacts_attribute(ds: xr.Dataset) -> int:
    """Impacts per motion ``p`` of a branch: attribute ``impacts``, 1 when absent.

    Raises
    ------
    ValueError
        ``impacts`` is not an integer >= 1, or differs from the size of the
        dimension ``impact`` (a branch without that dimension has ``p = 1``).
    """
    p = _integer("impacts", ds.attrs.get("impacts", 1),
                 "an integer >= 1 (impacts per motion)")
    size = ds.sizes.get("impact", 1)
    if p != size:
        where = (f"the dimension 'impact' has size {size}" if "impact" in ds.sizes
                 else "the dataset has no dimension 'impact' (p = 1)")
        raise ValueError(f"attribute 'impacts' must equal the impacts per motion: {where}; "
                         f"got {_shown(ds.attrs.get('impacts'))}")
    return p


def check_pattern_attribute(pattern: Any, p: int, two_sided: bool | None = None,
                            name: str = "pattern", extra: str = "", *,
                            sticking: bool = False) -> str:
    """The impact pattern of an N-p branch: ``p`` letters, the stop of each impact.

    Parameters
    ----------
    pattern : Any
        The attribute's value.
    p : int
        Impacts per motion.
    two_sided : bool or None
        Whether the dataset's oscillator has a lower stop (None: unknown).
    name : str
        The attribute, for the message.
    extra : str
        The names of the oscillator's extra stops (:class:`~impactcont.model.stops.Stop`).
    sticking : bool
        Accept a stop's letter in lowercase too (that stop's plastic impact followed by a
        sticking phase: a branch of motions with sticking phases,
        :func:`~impactcont.model.stops.sticking_pattern`).

    Returns
    -------
    str

    Raises
    ------
    ValueError
        Not ``p`` letters from ``U`` (upper stop) and ``L`` (lower stop), or ``L``
        without a lower stop.
    """
    letters = (UPPER, LOWER) if two_sided is not False else (UPPER,)
    stops = " and ".join(f"{s!r} ({w} stop)" for s, w in zip(letters, ("upper", "lower"),
                                                               strict=False))
    if extra:
        stops += "".join(f", {s!r}" for s in extra) + " (extra stops)"
    allowed = (f"{p} letter{'s' if p != 1 else ''} (one per impact) from {stops}"
               + ("" if two_sided is not False else ": the oscillator has no lower stop"))
    names = set(letters) | set(extra)
    if sticking:
        names |= {c.lower() for c in names}
        if isinstance(pattern, str) and pattern != pattern.upper():
            allowed += " (lowercase where a sticking phase follows the impact)"
    if not isinstance(pattern, str) or len(pattern) != p or set(pattern) - names:
        raise _refused(name, pattern, allowed)
    return pattern


def extra_stop_names(osc: ImpactOscillator) -> str:
    """The names of `osc`'s extra stops (beyond the upper and the lower one), as a string."""
    return "".join(stop.name for stop in getattr(osc.stops, "extra", ()))


def _impact_stops(value: Any, ds: xr.Dataset, osc: ImpactOscillator | None) -> None:
    check_pattern_attribute(value, ds.sizes.get("impact", 0),
                            None if osc is None else osc.stops.two_sided, "impact_stops",
                            "" if osc is None else extra_stop_names(osc))


def _parameter(value: Any, ds: xr.Dataset, osc: Any) -> None:
    if not isinstance(value, str) or value not in PARAMETERS:
        raise _refused("parameter", value, _ALLOWED)
    if value not in ds.variables:
        raise ValueError(f"attribute 'parameter' = {value!r} names no variable of the "
                         f"dataset; allowed: a parameter with its column, one of "
                         f"{[str(k) for k in ds.variables if k in PARAMETERS]}")
    _finite_parameters(ds, value)


def _finite_parameters(ds: xr.Dataset, parameter: str) -> None:
    """The parameters that label the points of a branch (``omega``, ``b``, ``parameter``)
    are finite at every point: a point without its parameter is no point of the branch
    (``continuation_from`` and ``extend`` would start from it, or carry it on). Other
    columns may hold NaN (a multiplier not computed, ``gap_min`` ``+inf``: docs/dataset.md).
    """
    for name in dict.fromkeys(("omega", "b", parameter)):
        var = ds.variables.get(name)
        if var is None or var.dims != ("point",) or var.dtype.kind != "f":
            continue
        values = np.asarray(var.values)
        bad = np.flatnonzero(~np.isfinite(values))
        if bad.size:
            what = "the continued parameter" if name == parameter else "a parameter"
            raise ValueError(
                f"variable {name!r} ({what}, a coordinate of the points) must be finite at "
                f"every point; got {values[bad[0]]} at point {int(bad[0])} ({bad.size} "
                f"point{'s' if bad.size > 1 else ''} not finite): the branch is corrupt; "
                f"drop those points (ds.isel(point=...)) or compute the branch again")


def _pattern(value: Any, ds: xr.Dataset, osc: ImpactOscillator | None) -> None:
    pattern = check_pattern_attribute(value, impacts_attribute(ds),
                                      None if osc is None else osc.stops.two_sided,
                                      extra="" if osc is None else extra_stop_names(osc),
                                      sticking=True)
    if osc is not None:  # a sticking phase's impact is on its stop's capital
        _pattern_of_states("".join(c if c in osc.stops.names else c.upper()
                                   for c in pattern), ds, osc)


# The state right after an impact is on its stop to rounding (the stop position is set,
# not solved for); another stop is a finite distance away.
_ON_STOP_RTOL = 1e-8


def _stored_states(ds: xr.Dataset) -> tuple[str, np.ndarray] | None:
    """The states right after each impact, ``(variable, array (point, impact, 2n))``: the
    variable ``state_k`` of an N-p branch, ``state`` of an N-1 one; None if not stored so."""
    var = ds.variables.get("state_k")
    if var is not None and var.dims == ("point", "impact", "component"):
        name = "state_k"
    elif "impact" not in ds.dims and ds.variables.get("state") is not None \
            and ds.variables["state"].dims == ("point", "component"):
        name, var = "state", ds.variables["state"]
    else:
        return None
    if var.dtype.kind not in "iuf":
        return None
    values = np.asarray(var.values, dtype=float)
    return name, values if values.ndim == 3 else values[:, None, :]


def _stop_positions(ds: xr.Dataset, osc: ImpactOscillator, letters: str, npoints: int
                    ) -> dict[str, tuple[np.ndarray, np.ndarray, str]]:
    """``{letter: (normal, position at each point, coordinate text)}`` of each stop, its
    position moving with the continued parameter where that is a stop's position."""
    rates: dict[str, float] = {}
    lam = lam0 = None
    parameter = ds.attrs.get("parameter")
    var = ds.variables.get(parameter) if isinstance(parameter, str) else None
    if var is not None and var.dims == ("point",):
        try:
            mp = model_parameter(osc, parameter)
        except (ValueError, TypeError):
            mp = None
        if mp is not None and mp.data == GAP:
            rates = {UPPER: mp.upper, LOWER: mp.lower, **dict(mp.extra)}
            lam, lam0 = np.asarray(var.values, dtype=float), mp.value(osc)
    out = {}
    for letter in letters:
        stop = osc.stops.stop(letter, osc.M, osc.b, osc.R)
        position = np.full(npoints, stop.position)
        if lam is not None and rates.get(letter, 0.0):
            position = stop.position + rates[letter] * (lam - lam0)
        text = (osc.stops.coordinate if letter in (UPPER, LOWER)
                else osc.stops.extra_stop(letter).coordinate)
        out[letter] = (stop.normal, position, text)
    return out


def _pattern_of_states(pattern: str, ds: xr.Dataset, osc: ImpactOscillator) -> None:
    """The stop each stored impact state is on is the stop its letter of ``pattern`` names.

    Raises
    ------
    ValueError
        A state right after impact k is not on the stop ``pattern[k]`` (a pattern edited
        from ``UL`` to ``LU`` would make ``continuation_from`` converge to another motion),
        naming the attribute, its value and the pattern the states say.
    """
    stored = _stored_states(ds)
    if stored is None:
        return
    name, states = stored
    n = osc.n
    if states.shape[1] != len(pattern) or states.shape[2] != 2 * n:
        return  # a misshapen variable: the schema's to report
    stops = _stop_positions(ds, osc, osc.stops.names, states.shape[0])

    def distance(k: int, letter: str) -> np.ndarray:
        normal, position, _ = stops[letter]
        s = states[:, k, :n] @ normal
        return np.abs(s - position) / (1.0 + np.abs(position) + np.abs(s))

    said = []
    first = None
    for k, letter in enumerate(pattern):
        d = distance(k, letter)
        known = np.isfinite(d)
        off = np.flatnonzero(known & (d > _ON_STOP_RTOL))
        on = [other for other in osc.stops.names
              if known.any() and np.all(distance(k, other)[known] <= _ON_STOP_RTOL)]
        said.append(on[0] if on else "?")
        if off.size and first is None:
            first = (k, letter, int(off[0]))
    if first is None:
        return
    k, letter, i = first
    normal, position, text = stops[letter]
    s = float(states[i, k, :n] @ normal)
    data = "".join(said)
    allowed = (f"{data!r} (another pattern would be another motion)" if "?" not in data
               else "none ('?': a state on no stop of the oscillator; the file is corrupt)")
    raise ValueError(
        f"attribute 'pattern' = {pattern!r} contradicts the states stored (variable "
        f"{name!r}): right after impact {k} the motion is at {text} = {s:.6g}, not on the "
        f"stop {letter!r} ({text} = {float(position[i]):.6g}) (point {i}); the states say "
        f"{data!r}; allowed: {allowed}")


def _parameters(value: Any, ds: xr.Dataset, osc: Any) -> None:
    allowed = (f"two different names of {list(PARAMETERS)} or element names joined by ',' "
               "(e.g. 'omega,b', 'omega,k2')")
    names = split_parameters(value) if isinstance(value, str) else []
    if len(names) != 2 or len(set(names)) != 2 or not all(n in PARAMETERS for n in names):
        raise _refused("parameters", value, allowed)
    missing = [k for k in names if k not in ds.variables]
    if missing:
        raise ValueError(f"attribute 'parameters' = {value!r} names {missing}, which the "
                         "dataset has no variable of; allowed: the curve's two parameters, "
                         "each with its column")


# a comma between two names, not one inside an element's brackets (M[1,2])
_BETWEEN_NAMES = re.compile(r",(?![^\[]*\])")


def split_parameters(text: str) -> list[str]:
    """The names of a comma-joined attribute ``parameters`` (``"omega,b"``): a comma inside
    an element name's brackets is no separator (``"omega,M[1,2]"`` -> ``["omega",
    "M[1,2]"]``)."""
    return _BETWEEN_NAMES.split(text)


#: The attribute of a robust dataset saying how the element names of ``vary``,
#: ``nominal`` and ``argmax`` count the masses, and its value: 1-based, as the paper's
#: masses and every other parameter name (``F[2]`` is the forcing of mass 2).
ROBUST_INDEXING_ATTRIBUTE = "element_indexing"
ROBUST_INDEXING = "1-based"
# robust stability follows an N-1 motion with one stop: it cannot vary a lower stop
_LOWER_STOP = ("b_low", "R_low", "gap")
_OLD_F_ENTRY = re.compile(r"^F\[(\d+)\]$")


def upgrade_robust_attributes(attrs: Mapping[str, Any]) -> dict[str, Any]:
    """The attributes of a robust dataset in today's convention.

    Files written before the attribute ``element_indexing`` existed stored the entries
    of F in ``vary``, ``nominal`` and ``argmax`` with 0-based indices (``"F[0]"`` was the
    forcing of mass 1); the parameter names are 1-based now, as the paper's masses
    (:func:`impactcont.model.parameters.model_parameter`). Such a file's ``F[i]`` is read
    as ``F[i+1]`` (its meaning kept) and ``element_indexing`` added; a file that has the
    attribute is returned as it is. Other names had no index then (``b``, ``omega``, ...;
    robust stability varied no other element), so attributes without ``F[i]`` mean the
    same in both conventions and are returned as they are.

    Parameters
    ----------
    attrs : mapping
        The dataset's attributes.

    Returns
    -------
    dict
        A new dict (the input is not changed).

    Raises
    ------
    ValueError
        ``element_indexing`` is not ``"1-based"``, or an old attribute is not JSON.
    """
    out = dict(attrs)
    indexing = out.get(ROBUST_INDEXING_ATTRIBUTE)
    if indexing is not None:
        if indexing != ROBUST_INDEXING:
            raise _refused(ROBUST_INDEXING_ATTRIBUTE, indexing,
                           f"{ROBUST_INDEXING!r} (element names counted as the paper's masses)")
        return out

    def renamed(names: Mapping[str, Any]) -> dict[str, Any]:
        return {(f"F[{int(m.group(1)) + 1}]" if (m := _OLD_F_ENTRY.match(k)) else k): v
                for k, v in names.items()}

    changed = []
    for key in ("vary", "nominal", "argmax"):
        if key not in out:
            continue
        data = _json_object(key, out[key])
        new = ({k: renamed(v) if isinstance(v, dict) else v for k, v in data.items()}
               if key == "argmax" else renamed(data))
        if new != data:
            out[key] = json.dumps(new)
            changed.append(key)
    if changed:
        log.info("robust dataset written before element_indexing: its 0-based F[i] in %s "
                 "read as the 1-based F[i+1] (the same masses)", ", ".join(changed))
        out[ROBUST_INDEXING_ATTRIBUTE] = ROBUST_INDEXING
    return out


def _vary(value: Any, ds: xr.Dataset, osc: Any) -> None:
    allowed = ("a JSON object of parameter name to [low, high] (the box of eq. 26): names "
               f"robust stability can vary, {_ALLOWED}, not a lower stop's {list(_LOWER_STOP)}")
    box = _json_object("vary", value, allowed)
    if not box:
        raise _refused("vary", value, allowed, " (no parameter varies)")
    unknown = [k for k in box if k not in PARAMETERS or k in _LOWER_STOP]
    if unknown:
        raise _refused("vary", value, allowed, f" (names {unknown})")
    for bounds in box.values():
        if (not isinstance(bounds, list) or len(bounds) != 2 or not all(map(_real, bounds))
                or bounds[0] > bounds[1]):
            raise _refused("vary", value, allowed)


def _nominal(value: Any, ds: xr.Dataset, osc: Any) -> None:
    allowed = "a JSON object of parameter name to its nominal value"
    if not all(map(_real, _json_object("nominal", value, allowed).values())):
        raise _refused("nominal", value, allowed)


def _text(name: str) -> Callable[[Any, xr.Dataset, Any], None]:
    def check(value: Any, ds: xr.Dataset, osc: Any) -> None:
        if not isinstance(value, str):
            raise _refused(name, value, "a text")
    return check


def _curve_kind(value: Any, ds: xr.Dataset, osc: Any) -> None:
    if not isinstance(value, str) or value not in CURVE_KINDS:
        raise _refused("kind", value, f"one of {list(CURVE_KINDS)} (the kind of curve)")


def _periods(value: Any, ds: xr.Dataset, osc: Any) -> None:
    if not _real(value) or value <= 0:
        raise _refused("periods", value, "a finite number > 0 (forcing periods simulated)")


def _stored_periods(ds: xr.Dataset) -> tuple[np.ndarray, np.ndarray] | None:
    """``(period, omega)`` of the motions stored in ``ds``, where its variables give both.

    The period of an N-p branch is the sum of its flight times (and stick times, on a
    branch of motions with sticking phases: none known without ``stick_time_k``); an
    orbits dataset stores it. None where the dataset has neither (an N-1 branch, a map,
    ...).
    """
    def values(name: str, dims: tuple[str, ...]) -> np.ndarray | None:
        var = ds.variables.get(name)
        if var is None or var.dims != dims or var.dtype.kind not in "iuf":
            return None
        return np.asarray(var.values, dtype=float)

    omega = values("omega", ("point",))
    taus = values("flight_time_k", ("point", "impact"))
    if omega is not None and taus is not None:
        sticks = values("stick_time_k", ("point", "impact"))
        if sticks is not None:
            return taus.sum(axis=1) + sticks.sum(axis=1), omega
        pattern = ds.attrs.get("pattern")
        if isinstance(pattern, str) and pattern != pattern.upper():
            return None  # sticking phases whose durations are not stored
        return taus.sum(axis=1), omega
    omega, period = values("omega", ()), values("period", ("orbit",))
    if omega is not None and period is not None:
        return period, np.broadcast_to(omega, period.shape)
    return None


def _forcing_periods(value: Any, ds: xr.Dataset, osc: Any) -> None:
    N = _integer("N", value, "an integer >= 1 (forcing periods per impact)")
    stored = _stored_periods(ds)
    if stored is None:
        return
    period, omega = stored
    ok = np.isfinite(period) & np.isfinite(omega) & (omega > 0)
    # the period is 2 pi N / omega by construction (the last flight time closes it):
    # only rounding separates them, a wrong N at least a factor (N + 1) / N
    ratio = period[ok] * omega[ok] / (2 * np.pi)
    if ratio.size and np.max(np.abs(ratio - N)) > 1e-8 * N:
        stored_N = np.unique(np.round(ratio)).astype(int).tolist()
        raise ValueError(f"attribute 'N' = {N!r} does not match the motions stored: their "
                         f"period T = 2 pi N / omega gives N = {stored_N}; allowed: "
                         f"{stored_N[0] if len(stored_N) == 1 else stored_N}")


# Checks of the attributes other than oscillator, run with the dataset and its oscillator.
_CHECKS: dict[str, Callable[[Any, xr.Dataset, Any], Any]] = {
    "N": _forcing_periods,
    "parameter": _parameter,
    "parameters": _parameters,
    "kind": _curve_kind,
    "options": lambda v, ds, osc: _json_object("options", v),
    "impacts": lambda v, ds, osc: impacts_attribute(ds),
    "pattern": lambda v, ds, osc: _pattern(v, ds, osc),
    "vary": _vary,
    "nominal": _nominal,
    "argmax": lambda v, ds, osc: _json_object("argmax", v),
    ROBUST_INDEXING_ATTRIBUTE: lambda v, ds, osc: upgrade_robust_attributes(
        {ROBUST_INDEXING_ATTRIBUTE: v}),
    "start": _text("start"),
    "status": _text("status"),
    "which": _text("which"),
    "note": _text("note"),
    **{name: _text(name) for name in _TEXT},
    "periods": _periods,
    "impact_stops": _impact_stops,
}


def dataset_tag(ds: xr.Dataset) -> str | None:
    """The attribute ``impactcont_dataset`` of ``ds`` (its layout), None if absent.

    Raises
    ------
    ValueError
        The attribute is not a text.
    """
    tag = ds.attrs.get("impactcont_dataset")
    if tag is not None and not isinstance(tag, str):
        raise _refused("impactcont_dataset", tag, "a text naming the layout of the dataset "
                       "(curve, map, orbits, robust, simulation, ...), or absent (a branch)")
    return tag


def dataset_kind(ds: xr.Dataset, section: Any = None) -> str | None:
    """The kind of ``ds`` whose attributes impactcont reads (a key of :data:`KIND_ATTRIBUTES`).

    Parameters
    ----------
    ds : xarray.Dataset
    section : str, optional
        The scene section of the file holding ``ds`` (root attribute
        ``impactcont_kind``); None for a file of :func:`impactcont.dataset.save`.

    Returns
    -------
    str or None
        None for a dataset that is not one of impactcont's kinds (a plugin's,
        or a dataset without ``impactcont_dataset`` nor ``parameter``).

    Raises
    ------
    ValueError
        In a file of a built-in section, ``impactcont_dataset`` is not that
        section's kind.
    """
    tag = dataset_tag(ds)
    expected = SECTION_KINDS.get(section) if isinstance(section, str) else None
    if expected is not None:
        if expected == "branch" and tag is not None:
            raise ValueError(f"attribute 'impactcont_dataset' must be absent (a branch) in a "
                             f"file of section {section!r}; got {_shown(tag)}")
        others = SECTION_OTHER_KINDS.get(section, ())
        if tag in others:
            return tag
        if tag is None and "branch" in others and "curve_kind" in ds.attrs:
            return "branch"  # a curve followed by shooting
        if expected != "branch" and tag != expected:
            kinds = " or ".join(repr(k) for k in (expected, *SECTION_OTHER_KINDS.get(section, ())))
            raise _refused("impactcont_dataset", tag, f"{kinds} in a file of section {section!r}")
        return expected
    if tag is None:
        return "branch" if "parameter" in ds.attrs else None
    return tag if tag in KIND_ATTRIBUTES else None


def check_attributes(ds: xr.Dataset, kind: str, *, in_section: bool = False) -> None:
    """Check every attribute impactcont reads from a dataset of ``kind``, where present.

    Parameters
    ----------
    ds : xarray.Dataset
    kind : str
        A key of :data:`KIND_ATTRIBUTES` (see :func:`dataset_kind`).
    in_section : bool, optional
        ``ds`` is in a file of a built-in scene section, whose description reads
        the attributes of :data:`SECTION_ATTRIBUTES`: they must be present.

    Raises
    ------
    ValueError
        An attribute is missing (``in_section``) or has a value a reader would
        misread, or an N-p branch has no ``impacts``; the message names the
        attribute, its value and what is allowed.
    """
    missing = [name for name in SECTION_ATTRIBUTES[kind] if name not in ds.attrs]
    if in_section and missing:
        raise ValueError(f"attribute(s) {missing} missing: a {kind} dataset of a scene file "
                         f"carries {list(SECTION_ATTRIBUTES[kind])}")
    if kind == "robust":  # a file of before element_indexing: its F[i] counted from 0
        upgraded = upgrade_robust_attributes(ds.attrs)
        if upgraded != ds.attrs:
            ds.attrs.update(upgraded)
    osc = oscillator_attribute(ds) if "oscillator" in ds.attrs else None
    for name in KIND_ATTRIBUTES[kind]:
        if name != "oscillator" and name in ds.attrs:
            _CHECKS[name](ds.attrs[name], ds, osc)
    if kind == "branch" and "impact" in ds.sizes:
        impacts_attribute(ds)  # present, and the size of the impact dimension
    # which stop each impact hit: all U is the only reading without a lower stop
    stops = {"branch": "pattern", "simulation": "impact_stops"}.get(kind)
    if stops and osc is not None and osc.stops.two_sided and stops not in ds.attrs:
        raise ValueError(f"attribute {stops!r} is missing: the oscillator has a lower stop, "
                         "so the stop of each impact (letters U/L) must be stored")


def check_file_attributes(attrs: Mapping[str, Any]) -> None:
    """Check the root attributes of a scene file that readers use.

    ``impactcont_kind`` (the section) and ``scene_file`` must be text, ``scene``
    the resolved scene as a JSON object (or empty).

    Raises
    ------
    ValueError
        Naming the attribute, its value and what is allowed.
    """
    for name in _TEXT:
        if name in attrs and not isinstance(attrs[name], str):
            raise _refused(name, attrs[name], "a text")
    kind = attrs.get("impactcont_kind", "section")
    if not isinstance(kind, str) or not kind:
        raise _refused("impactcont_kind", kind, "the name of a scene section (text)")
    if not isinstance(attrs.get("scene_file", ""), str):
        raise _refused("scene_file", attrs["scene_file"], "a text (the scene file's path)")
    scene = attrs.get("scene", "")
    if not (isinstance(scene, str) and scene == ""):
        _json_object("scene", scene, "the resolved scene as a JSON object (text), or empty")
