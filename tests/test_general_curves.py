"""Codim-1 curves on the first-order path (issue 14): a damping matrix C or a complex F.

A proportional C given as a matrix must give the modal path's curves; a damper on one
mass (no modal decoupling) and per-mass forcing phases are checked against the special
points of one-parameter branches and against the defining property of each curve.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from _scene_data import OSCILLATOR, write

import impactcont as ic
from impactcont.analysis.curves import curve, curve_crossings
from impactcont.errors import ParameterError
from impactcont.orbit import general
from impactcont.orbit.dense import impact_map_jacobian
from impactcont.orbit.flow import Flow
from impactcont.orbit.periodic import orbit_at_phase, periodic_orbits
from impactcont.problems.codim1 import curve_problem
from impactcont.scene import read_output, run_scene

K2 = np.array([[1.0, -1.0], [-1.0, 2.0]])
BOX = {"omega": (0.6, 2.0), "b": (0.0, 0.6)}
KINDS = ("SN", "PD", "NS", "GR", "ZV")
START_B = {"SN": 0.5, "PD": 0.0, "NS": 0.5, "GR": 0.5, "ZV": 0.5}
#: gaps at which the damper-on-mass-2 curves are compared with one-parameter points
CHECK_B = {"SN": (0.45, 0.5), "PD": (0.1, 0.3, 0.5), "NS": (0.3, 0.45),
           "GR": (0.45, 0.5), "ZV": (0.3, 0.45)}


def _paper(**damping):
    return ic.ImpactOscillator(M=np.eye(2), K=K2, F=[1.0, 0.0], R=0.6, b=0.5, omega=1.0,
                               **damping)


def _starts(osc, kinds=KINDS):
    """The first located special point of each kind on the omega-branches at START_B."""
    branches = {b: ic.continuation(osc.replace(b=b), 1, "omega", BOX["omega"],
                                   detect=[k for k in kinds if START_B[k] == b])
                for b in {START_B[k] for k in kinds}}
    out = {}
    for kind in kinds:
        ds = branches[START_B[kind]]
        k = int(np.flatnonzero((ds.special_label.values == kind)
                               & (ds.special_status.values == "located"))[0])
        out[kind] = {"omega": float(ds.special_omega[k]), "b": START_B[kind],
                     "delta": float(ds.special_delta[k])}
    return out


# -- (a) a proportional C given as a matrix: the modal path's curves -----------------------------
@pytest.mark.parametrize("damping", [{"eta": 0.1}, {"alpha": 0.05, "beta": 0.1}],
                         ids=["eta", "rayleigh"])
def test_proportional_C_as_a_matrix_gives_the_modal_curves(damping):
    modal = _paper(**damping)
    matrix = _paper(C=modal.C)
    assert matrix.general and not modal.general
    starts = _starts(modal)
    labels = set()
    for kind in KINDS:
        a = curve(modal, 1, kind, start=starts[kind], bounds=BOX)
        g = curve(matrix, 1, kind, start=starts[kind], bounds=BOX)
        assert g.sizes["point"] == a.sizes["point"] > 5, kind
        for name in ("omega", "b", "delta", "impact_velocity"):
            assert np.max(np.abs(g[name].values - a[name].values)) < 1e-9, (kind, name)
        assert float(g.residual.max()) < 1e-10
        assert g.codim2_label.values.tolist() == a.codim2_label.values.tolist(), kind
        assert g.codim2_status.values.tolist() == a.codim2_status.values.tolist(), kind
        for name in ("codim2_omega", "codim2_b"):
            assert np.max(np.abs(g[name].values - a[name].values), initial=0.0) < 1e-9, kind
        labels |= set(g.codim2_label.values.tolist())
    assert len(labels) >= 4, labels  # codim-2 points of several kinds were compared


@pytest.mark.parametrize(("kind", "parameters", "bounds"), [
    ("PD", ("omega", "R"), {"omega": (1.0, 2.0), "R": (0.4, 0.9)}),
    ("NS", ("F0", "omega"), {"F0": (0.6, 1.4), "omega": (1.2, 1.8)}),
])
def test_proportional_C_as_a_matrix_in_other_parameter_pairs(kind, parameters, bounds):
    """R and F0 as parameters: the difference columns (R) and the F0 step agree too."""
    modal = _paper(eta=0.1)
    if kind == "PD":
        modal = modal.replace(b=0.3)
        start = {"omega": 1.3737, "R": 0.6}
    else:
        found = _starts(modal, ["NS"])["NS"]
        start = {"F0": 1.0, "omega": found["omega"], "delta": found["delta"]}
    matrix = _paper(C=modal.C).replace(b=modal.b)
    a, g = (curve(osc, 1, kind, start=start, parameters=parameters, bounds=bounds)
            for osc in (modal, matrix))
    assert matrix.general and g.sizes["point"] == a.sizes["point"] > 5
    assert max(np.ptp(g[p].values) for p in parameters) > 0.1
    for name in (*parameters, "delta"):
        assert np.max(np.abs(g[name].values - a[name].values)) < 1e-9, name
    assert g.codim2_label.values.tolist() == a.codim2_label.values.tolist()


# -- (b) a damper on mass 2 only: no modal decoupling --------------------------------------------
@pytest.fixture(scope="module")
def damper():
    return _paper(C=[[0.0, 0.0], [0.0, 0.2]])


@pytest.fixture(scope="module")
def damper_curves(damper):
    starts = _starts(damper)
    return {kind: curve(damper, 1, kind, start=starts[kind], bounds=BOX) for kind in KINDS}


def _one_parameter_points(osc, kind, b, omega):
    ds = ic.continuation(osc.replace(b=b), 1, "omega", (omega - 0.015, omega + 0.015),
                         detect=[kind], ds=0.002, ds_max=0.005)
    rows = (ds.special_label.values == kind) & (ds.special_status.values == "located")
    return ds.special_omega.values[rows]


@pytest.mark.parametrize("kind", KINDS)
def test_damper_curve_passes_through_one_parameter_special_points(damper, damper_curves, kind):
    c = damper_curves[kind]
    assert float(c.residual.max()) < 1e-10
    compared = 0
    for b in CHECK_B[kind]:
        crossings = curve_crossings(c, "b", b)
        assert crossings, f"{kind} curve does not cross b={b}"
        for cr in crossings:
            found = _one_parameter_points(damper, kind, b, cr["omega"])
            assert found.size, f"no 1-parameter {kind} near omega={cr['omega']} at b={b}"
            assert np.min(np.abs(found - cr["omega"])) < 1e-8, (kind, b, cr, found)
            compared += 1
    assert compared >= 3


def test_damper_pd_curve_in_omega_and_R(damper):
    osc = damper.replace(b=0.3)
    c = curve(osc, 1, "PD", start={"omega": 0.70646, "R": 0.6}, parameters=("omega", "R"),
              bounds={"omega": (0.6, 1.0), "R": (0.4, 0.9)}, detect_codim2_points=False)
    compared = 0
    for R in (0.45, 0.85):
        for cr in curve_crossings(c, "R", R):
            found = _one_parameter_points(osc.replace(R=R), "PD", 0.3, cr["omega"])
            assert found.size and np.min(np.abs(found - cr["omega"])) < 1e-8, (R, cr, found)
            compared += 1
    assert compared >= 2


def _motion(osc, point):
    """The motion of ``periodic_orbits`` at a curve point (the root with its phase)."""
    at = osc.replace(omega=float(point.omega), b=float(point.b))
    orbits = periodic_orbits(at, 1)
    delta = float(point.delta)
    return min(orbits, key=lambda o: abs(math.remainder(o.delta - delta, 2 * math.pi)))


@pytest.mark.parametrize("kind", KINDS)
def test_damper_curve_points_are_special(damper, damper_curves, kind):
    c = damper_curves[kind]
    checked = 0
    for k in range(0, c.sizes["point"], 3):
        point = c.isel(point=k)
        osc = damper.replace(omega=float(point.omega), b=float(point.b))
        if kind == "SN":
            cs, s = general.amplitude(osc, 1)[:2]
            assert abs(cs**2 + s**2 - float(point.b) ** 2) < 1e-10
        elif kind == "ZV":
            assert abs(orbit_at_phase(osc, 1, float(point.delta)).impact_velocity) < 1e-10
        else:
            o = _motion(damper, point)
            if kind == "PD":
                assert np.min(np.abs(o.multipliers + 1.0)) < 1e-8, (k, o.multipliers)
            elif kind == "NS":
                theta = float(point.angle)
                assert np.min(np.abs(o.multipliers - np.exp(1j * theta))) < 1e-8
            elif not bool(point.physical):
                continue  # another maximum of x1 above b: gap_min is that one's
            else:
                assert abs(o.gap_min) < 1e-9, (k, o.gap_min)
        checked += 1
    assert checked >= 3


def test_damper_codim2_points_lie_on_both_curves(damper_curves):
    for a, b, la, lb in (("PD", "GR", "PD+GR", "GR+PD"), ("SN", "ZV", "SN+ZV", "ZV+SN")):
        ca, cb = damper_curves[a], damper_curves[b]
        pa = ca.isel(codim2=np.flatnonzero(ca.codim2_label.values == la))
        pb = cb.isel(codim2=np.flatnonzero(cb.codim2_label.values == lb))
        assert pa.sizes["codim2"] and pb.sizes["codim2"], (la, lb)
        assert (pa.codim2_status.values == "located").all()
        d = np.hypot(pa.codim2_omega.values[:, None] - pb.codim2_omega.values[None, :],
                     pa.codim2_b.values[:, None] - pb.codim2_b.values[None, :])
        assert d.min() < 1e-7, (la, lb, d.min())


# -- the pieces: G split, x1, Jacobian columns -----------------------------------------------------
def test_general_pieces_match_the_dense_closed_form(damper):
    osc = damper.replace(omega=1.1, b=0.3)
    pc = curve_problem("GR", osc, 1)._pieces(1.1, 0.3)
    flow = Flow(osc)
    for o in periodic_orbits(osc, 1):
        G_reg, a, b, h2 = pc.split(o.delta)
        G, h2_dense = impact_map_jacobian(flow, pc.state(o.delta), o.delta, pc.T, pc.DPhi)
        np.testing.assert_allclose(G_reg + np.outer(a, b) / h2, G, rtol=0, atol=1e-12)
        np.testing.assert_allclose(pc.jacobian(o.delta)[0], o.G, rtol=0, atol=1e-12)
        assert h2 == pytest.approx(h2_dense, abs=1e-14)
        assert pc.impact_velocity(o.delta) == pytest.approx(o.impact_velocity, abs=1e-14)
        E = pc.pole_free_pd_matrix(o.delta)
        assert np.linalg.det(E) == pytest.approx(-h2 * np.linalg.det(G + np.eye(4)), rel=1e-9)
        t = np.array([0.3, 2.0, 4.5])
        exact = flow.mass1(pc.state(o.delta), o.delta).derivatives(t)
        for j, tj in enumerate(t):
            np.testing.assert_allclose(pc.mass1_derivatives(o.delta, tj, 3),
                                       [exact[0][j], exact[1][j], exact[2][j]], atol=1e-13)


@pytest.mark.parametrize("kind", KINDS)
@pytest.mark.parametrize("parameters", [("omega", "b"), ("R", "F0"), ("F0", "omega")])
def test_general_jacobian_against_differences(damper, kind, parameters):
    osc = damper.replace(omega=1.1, b=0.3)
    o = periodic_orbits(osc, 1)[0]
    problem = curve_problem(kind, osc, 1, parameters)
    extras = {"NS": np.r_[0.7, np.linspace(0.1, 0.4, 4), np.linspace(-0.2, 0.2, 4)],
              "GR": np.array([2.0])}.get(kind, np.empty(0))
    x = np.concatenate([[getattr(osc, parameters[0]), o.delta], extras,
                        [getattr(osc, parameters[1])]])
    problem.accept(x[:-1], x[-1])  # PD borders, NS reference vector, as along a curve
    J = problem.full_jacobian(x)
    D = np.empty_like(J)  # fourth-order central differences: error ~1e-11
    for j in range(x.size):
        h = 1e-3 * max(1.0, abs(x[j]))
        F = []
        for step in (-2, -1, 1, 2):
            y = x.copy()
            y[j] += step * h
            F.append(problem.residual(y[:-1], y[-1]))
        D[:, j] = (F[0] - 8 * F[1] + 8 * F[2] - F[3]) / (12 * h)
    scale = max(1.0, np.max(np.abs(J)))
    exact = [j for j in range(x.size) if not (j in (0, x.size - 1) and
                                              parameters[min(j, 1)] in ("omega", "R"))]
    # delta, the extra unknowns, b and F0: exact; omega and R: central differences
    np.testing.assert_allclose(J[:, exact], D[:, exact], rtol=0, atol=1e-9 * scale)
    np.testing.assert_allclose(J, D, rtol=0, atol=1e-6 * scale)
    for j in set(range(x.size)) - set(exact):  # the rows through c, s alone: exact
        rows = 2 if kind == "SN" else 1
        np.testing.assert_allclose(J[:rows, j], D[:rows, j], rtol=0, atol=1e-9 * scale)


# -- (c) complex F: per-mass forcing phases ------------------------------------------------------
@pytest.fixture(scope="module")
def phased():
    return ic.ImpactOscillator(M=np.eye(2), K=K2, F=[1.0, 0.4j], R=0.6, b=0.5, omega=1.0,
                               eta=0.1)


def test_complex_F_pd_curve_passes_through_one_parameter_points(phased):
    assert phased.general and not phased.general_damping
    c = curve(phased, 1, "PD", start=_starts(phased, ["PD"])["PD"], bounds=BOX)
    compared = 0
    for b in (0.1, 0.3, 0.5):
        for cr in curve_crossings(c, "b", b):
            found = _one_parameter_points(phased, "PD", b, cr["omega"])
            assert found.size and np.min(np.abs(found - cr["omega"])) < 1e-8, (b, cr, found)
            compared += 1
    assert compared >= 2


def test_complex_F_zero_velocity_curve_in_omega_and_F0_is_the_linear_response(phased):
    """On ``h2 = 0`` the impact does nothing: ``|x1|`` of the linear response is b (eq. 7)."""
    start = _starts(phased, ["ZV"])["ZV"]
    osc = phased.replace(b=start["b"])
    c = curve(osc, 1, "ZV", start={"F0": 1.0, "omega": start["omega"]},
              parameters=("F0", "omega"), bounds={"F0": (0.5, 1.5), "omega": (1.0, 2.0)})
    assert c.sizes["point"] > 5 and np.ptp(c.F0.values) > 0.2
    assert np.max(np.abs(c.impact_velocity.values)) < 1e-10
    for F0, w in zip(c.F0.values, c.omega.values, strict=True):
        at = osc.replace(F0=float(F0), omega=float(w))
        X = np.linalg.solve(at.K - w**2 * at.M + 1j * w * at.C, at.F)
        assert abs(abs(X[0]) - osc.b) < 1e-10


def test_complex_F_pd_curve_in_omega_and_eta(phased):
    """eta exists with a complex F on C = 2 eta K: its column is a central difference."""
    osc = phased.replace(b=0.0)
    start = _starts(phased, ["PD"])["PD"]
    c = curve(osc, 1, "PD", start={"omega": start["omega"], "eta": 0.1, "delta": start["delta"]},
              parameters=("omega", "eta"), bounds={"omega": (1.0, 2.5), "eta": (0.02, 0.2)},
              detect_codim2_points=False)
    assert np.ptp(c.eta.values) > 0.15
    compared = 0
    for eta in (0.05, 0.15):
        for cr in curve_crossings(c, "eta", eta):
            found = _one_parameter_points(osc.replace(eta=eta), "PD", 0.0, cr["omega"])
            assert found.size and np.min(np.abs(found - cr["omega"])) < 1e-8, (eta, cr, found)
            compared += 1
    assert compared >= 2


# -- (d) bad input --------------------------------------------------------------------------------
@pytest.mark.parametrize("name", ["eta", "alpha", "beta"])
def test_damping_parameters_are_refused_with_a_matrix_C(damper, name):
    with pytest.raises(ParameterError, match=f"'{name}' is meaningless with a general damping "
                                             "matrix"):
        curve(damper, 1, "PD", start={"omega": 0.7, "b": 0.1}, parameters=("omega", name),
              bounds={"omega": (0.6, 2.0), name: (0.0, 1.0)})
    with pytest.raises(ParameterError, match=r"continue in omega, b, R, F0 or an element of C"):
        curve_problem("SN", damper, 1, (name, "b"))


def test_bad_inputs_on_the_first_order_path(damper):
    with pytest.raises(ParameterError, match="must be two different names"):
        curve(damper, 1, "SN", start={"omega": 1.2, "b": 0.5}, parameters=("omega", "omega"),
              bounds=BOX)
    with pytest.raises(ParameterError, match="kind must be one of"):
        curve(damper, 1, "XX", start={"omega": 0.7, "b": 0.1}, bounds=BOX)
    elastic = ic.ImpactOscillator(M=np.eye(2), K=K2, F=[1.0, 0.4j], R=1.0, b=0.5, omega=1.0,
                                  eta=0.0)
    with pytest.raises(ParameterError, match=r"R=1\.0 without damping"):
        curve(elastic, 1, "SN", start={"omega": 1.2, "b": 0.5}, bounds=BOX)


# -- (e) a scene with a damping matrix --------------------------------------------------------
def test_scene_curve_entry_with_a_damping_matrix(tmp_path):
    text = (OSCILLATOR.replace("eta = 0.1", "C = [[0.0, 0.0], [0.0, 0.2]]")
            + '[[branches]]\nname = "br"\nb = 0.5\nbounds = [0.9, 1.5]\n'
            + '[[curves]]\nname = "sn"\nkind = "SN"\nstart = "br"\n'
            + "bounds = { omega = [0.9, 1.6], b = [0.45, 0.7] }\nds_max = 0.1\n")
    result = run_scene(write(tmp_path, text), output=tmp_path / "o")
    assert result.ok, result.failures
    c = read_output(tmp_path / "o" / "curves.nc").datasets["sn"]
    osc = ic.ImpactOscillator.from_json(c.attrs["oscillator"])
    assert osc.general_damping and c.attrs["kind"] == "SN" and c.sizes["point"] > 2
    np.testing.assert_array_equal(osc.C, [[0.0, 0.0], [0.0, 0.2]])
    for w, b in zip(c.omega.values, c.b.values, strict=True):
        cs, s = general.amplitude(osc.replace(omega=float(w)), 1)[:2]
        assert abs(cs**2 + s**2 - b**2) < 1e-10
