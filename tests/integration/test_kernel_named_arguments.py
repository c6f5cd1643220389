"""The N-p shooting path and the map sweep pass named structures, not long positional lists
(issue 29, item 3: ``sweep_stops`` took 63 positional arguments, ``_evaluate`` 42,
``motion_checks`` 34; the flow's 16 arrays were sliced by position, ``*arrays[6:8]``, and
results read by index, ``sh[7]``).

Two guards read the source (every compiled function's parameters; every subscript of the
flow's kernel arrays and of a compiled function's tuple result) and one calls the entry
points and checks that what they return is a named record of :mod:`impactcont.kernel.arrays`.
"""

from __future__ import annotations

import ast
from pathlib import Path

import numpy as np
import pytest

import impactcont as ic
from impactcont.kernel import arrays as kernel_arrays

ROOT = Path(ic.__file__).parent

#: The modules of the N-p path: the compiled shooting, its flights, the sweep, and the
#: Python that builds their inputs and reads their results. (The N-1 closed form and the
#: contact search, ``kernel/closed_form.py`` and ``kernel/contact.py``, still take their
#: arrays one by one.)
KERNEL = ("kernel/shooting.py", "kernel/sweep.py", "kernel/flights.py", "kernel/arrays.py")
CALLERS = ("orbit/multi_impact.py", "orbit/flow.py", "orbit/symmetry.py",
           "problems/multi_impact_branch.py", "problems/codim1.py",
           "problems/symmetric_branch.py",
           "analysis/family_maps.py")
MAX_PARAMETERS = 12
#: The flow's methods whose results are the kernel's inputs.
FLOW_ARRAYS = {"shooting_arrays", "static_arrays", "omega_arrays", "forcing_arrays",
               "flight_arrays"}


def _compiled(node: ast.FunctionDef) -> bool:
    """Decorated by numba (``@_jit``, ``@_inner``, ``@nb.njit(...)``, ...)."""
    for deco in node.decorator_list:
        text = ast.unparse(deco)
        if text.split("(")[0] in ("_jit", "_inner", "entry", "inner", "nb.njit", "njit",
                                  "numba.njit", "typed_entry", "_typed"):
            return True
    return False


def _functions(relative: str) -> list[ast.FunctionDef]:
    tree = ast.parse((ROOT / relative).read_text())
    return [node for node in ast.walk(tree) if isinstance(node, ast.FunctionDef)]


def _records() -> set[str]:
    """Names of the NamedTuple records of :mod:`impactcont.kernel.arrays`."""
    return {name for name, value in vars(kernel_arrays).items()
            if isinstance(value, type) and issubclass(value, tuple) and hasattr(value, "_fields")}


def _tuple_returning() -> set[str]:
    """The compiled functions of the N-p kernel that return several values: a bare tuple,
    a record, or what such a function returns (reading such a result by index is reading
    it by position)."""
    records = _records()
    returns = {}
    for relative in KERNEL:
        for fn in _functions(relative):
            if _compiled(fn):
                returns[fn.name] = [node.value for node in ast.walk(fn)
                                    if isinstance(node, ast.Return) and node.value is not None]
    out: set[str] = set()
    while True:
        more = {name for name, values in returns.items() if any(
            isinstance(value, ast.Tuple) or _called_name(value) in records | out
            for value in values)}
        if more == out:
            return out
        out = more


def _called_name(call: ast.AST) -> str | None:
    """``f`` of ``f(..)``, ``mod.f(..)`` or ``_kernel().f(..)``."""
    if not isinstance(call, ast.Call):
        return None
    if isinstance(call.func, ast.Name):
        return call.func.id
    if isinstance(call.func, ast.Attribute):
        return call.func.attr
    return None


def positional_reads(source: str, producers: set[str]) -> list[str]:
    """Every subscript of a value produced by a call of `producers` (directly, or through a
    name bound to such a call in the same function), as ``line: text``."""
    tree = ast.parse(source)
    found = []
    scopes = [node for node in ast.walk(tree) if isinstance(node, ast.FunctionDef)]
    for scope in scopes:
        bound = set()
        for node in ast.walk(scope):
            if (isinstance(node, ast.Assign) and len(node.targets) == 1
                    and isinstance(node.targets[0], ast.Name)
                    and _called_name(node.value) in producers):
                bound.add(node.targets[0].id)
        for node in ast.walk(scope):
            if not isinstance(node, ast.Subscript):
                continue
            value = node.value
            if _called_name(value) in producers or (isinstance(value, ast.Name)
                                                    and value.id in bound):
                found.append(f"{node.lineno}: {ast.unparse(node)}")
    return sorted(set(found))


def test_no_compiled_function_of_the_np_path_takes_more_than_twelve_arguments():
    long = [f"{relative}:{fn.name} ({len(fn.args.args)})"
            for relative in KERNEL + CALLERS for fn in _functions(relative)
            if _compiled(fn) and len(fn.args.args) > MAX_PARAMETERS]
    assert long == []


def test_no_kernel_input_or_result_is_read_by_position():
    producers = FLOW_ARRAYS | _tuple_returning()
    reads = {relative: positional_reads((ROOT / relative).read_text(), producers)
             for relative in KERNEL + CALLERS}
    assert {k: v for k, v in reads.items() if v} == {}


def test_the_guard_sees_the_old_positional_forms():
    """The scan above flags what the N-p path did before (so that it can fail)."""
    old = '''
def f(flow, osc):
    arrays = flow.shooting_arrays()
    out = _kernel().motion_checks(*arrays[:5], *arrays[6:8], flow.static_arrays()[0])
    sh = shooting_system(1, 2)
    return sh[7]
'''
    assert positional_reads(old, FLOW_ARRAYS | {"shooting_system"}) == [
        "4: arrays[6:8]", "4: arrays[:5]", "4: flow.static_arrays()[0]", "6: sh[7]"]
    assert "shooting_system" in _tuple_returning() and "sweep_stops" in _tuple_returning()


@pytest.fixture(scope="module")
def motion():
    osc = ic.ImpactOscillator(M=np.eye(2), K=[[1.0, -1.0], [-1.0, 2.0]], F=[1.0, 0.0], R=0.6,
                              b=0.0, omega=1.5, eta=0.1)
    orbit = next(o for o in ic.periodic_orbits(osc, 1) if o.physical)
    return ic.multi_impact_orbit(osc, 1, 1, orbit)


def test_the_entry_points_results_are_named_by_their_records(motion):
    """The entry points return plain tuples (numba boxes a named tuple through a Python call
    of its class, about 0.7 us a record); each is read through its record of
    :mod:`impactcont.kernel.arrays`, whose fields it fills exactly."""
    from impactcont.kernel import shooting as kernel
    from impactcont.orbit.flow import flow_of
    from impactcont.orbit.multi_impact import (
        _geometry,
        checked_flights,
        contact_stops,
        impact_sequence,
        shooting,
    )

    flow = flow_of(motion.oscillator)
    geo = _geometry(flow, "U")
    assert isinstance(flow.shooting_arrays(), kernel_arrays.ShootingFlow)
    assert isinstance(flow.forcing_arrays(), kernel_arrays.Forcing)
    assert isinstance(flow.omega_arrays(), kernel_arrays.ForcingDerivatives)
    assert flow.flight_arrays() == tuple(flow.shooting_arrays().flight_arrays())
    args = (flow.flight_arrays(), tuple(flow.forcing_arrays()), tuple(impact_sequence(geo)),
            motion.period)
    shot = kernel_arrays.ShotFlights._make(kernel.shooting_system(*args, motion.unknowns.copy(),
                                                                  True))
    assert shot.jacobian.shape == (motion.unknowns.size,) * 2
    solved = kernel_arrays.NewtonResult.from_kernel(
        kernel.newton_solve(*args, motion.unknowns.copy(), 1e-12, 40))
    assert isinstance(solved.shot, kernel_arrays.ShotFlights)
    assert solved.status == kernel.CONVERGED
    np.testing.assert_array_equal(solved.x, motion.unknowns)
    checked = kernel_arrays.MotionChecks._make(kernel.motion_checks(
        tuple(flow.shooting_arrays()), *args[1:3], tuple(contact_stops(geo)),
        tuple(checked_flights(shooting(flow, 1, 1, solved.x))), True))
    np.testing.assert_array_equal(checked.G, motion.G)
    np.testing.assert_array_equal(checked.multipliers, motion.multipliers)


def test_stack_flows_names_the_field_whose_shape_differs():
    from impactcont.orbit.flow import Flow

    K = [[1.0, -1.0], [-1.0, 2.0]]
    modal = Flow(ic.ImpactOscillator(M=np.eye(2), K=K, F=[1.0, 0.0], R=0.6, b=0.0,
                                     omega=1.5, eta=0.1))
    general = Flow(ic.ImpactOscillator(M=np.eye(2), K=K, F=[1.0, 0.0], R=0.6, b=0.0,
                                       omega=1.5, C=[[0.2, -0.2], [-0.2, 0.2]]))
    pairs = [(f.shooting_arrays(), f.forcing_arrays()) for f in (modal, modal)]
    tables = kernel_arrays.stack_flows(pairs, np.zeros((1, 2), dtype=np.int64))
    assert tables.w.shape == (2, 2) and tables.omega.tolist() == [1.5, 1.5]
    assert tables.general is False and tables.index.dtype == np.int64
    mixed = [(f.shooting_arrays(), f.forcing_arrays()) for f in (modal, general)]
    with pytest.raises(ValueError, match="field 'w' has shapes"):
        kernel_arrays.stack_flows(mixed, np.zeros((1, 2), dtype=np.int64))
    with pytest.raises(ValueError, match="at least one"):
        kernel_arrays.stack_flows([], np.zeros((1, 1), dtype=np.int64))
