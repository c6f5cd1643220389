"""Maps of (N, omega, b): the batched closed form against the per-motion one; executors."""

from __future__ import annotations

import concurrent.futures as cf
import math
import os

import matplotlib

matplotlib.use("Agg")
import numpy as np
import pytest
import xarray as xr

import impactcont as ic
from impactcont.analysis.maps import stability_map

OMEGA = np.linspace(0.5, 6.0, 23)
GAP = np.linspace(-1.0, 2.0, 13)


@pytest.fixture(scope="module")
def paper():
    return ic.ImpactOscillator(M=np.eye(2), K=[[1.0, -1.0], [-1.0, 2.0]], F=[1.0, 0.0], R=0.6,
                               b=0.5, omega=1.0, eta=0.1)


@pytest.fixture(scope="module")
def serial_map(paper):
    return stability_map(paper, [1, 2, 3], OMEGA, GAP)


def test_map_agrees_with_every_single_motion(paper, serial_map):
    rng = np.random.default_rng(7)
    compared = 0
    for _ in range(60):
        k, i, j = rng.integers(3), rng.integers(OMEGA.size), rng.integers(GAP.size)
        cell = serial_map.isel(N=k, omega=i, b=j)
        orbits = ic.periodic_orbits(paper.replace(omega=float(OMEGA[i]), b=float(GAP[j])),
                                    int(cell.N))
        assert bool(cell.exists) == bool(orbits)
        assert int(cell.n_physical) == sum(o.physical for o in orbits)
        assert int(cell.n_stable) == sum(o.physical and o.stable for o in orbits)
        for o in orbits:
            r = cell.sel(root=o.root)
            assert math.remainder(float(r.delta) - o.delta, 2 * math.pi) == pytest.approx(
                0, abs=1e-10)
            assert float(r.impact_velocity) == pytest.approx(o.impact_velocity, abs=1e-10)
            if math.isfinite(o.gap_min):
                assert float(r.gap_min) == pytest.approx(o.gap_min, abs=1e-10)
            else:
                assert not math.isfinite(float(r.gap_min))
            assert float(r.spectral_radius) == pytest.approx(o.spectral_radius, rel=1e-8)
            assert bool(r.physical) == o.physical and bool(r.stable) == o.stable
            compared += 1
    assert compared > 20


def test_process_pool_and_any_executor_give_the_same_map(paper, serial_map):
    pooled = stability_map(paper, [1, 2, 3], OMEGA, GAP, executor="process", max_workers=2)
    xr.testing.assert_identical(pooled.drop_attrs(), serial_map.drop_attrs())
    with cf.ThreadPoolExecutor(2) as pool:
        threaded = stability_map(paper, [1, 2, 3], OMEGA, GAP, executor=pool, omega_block=5)
    xr.testing.assert_identical(threaded.drop_attrs(), serial_map.drop_attrs())
    assert threaded.attrs["options"].count("ThreadPoolExecutor") == 1


def test_dask_distributed_local_cluster(paper, serial_map):
    distributed = pytest.importorskip("dask.distributed")
    with distributed.LocalCluster(n_workers=1, threads_per_worker=1, processes=True,
                                  dashboard_address=None) as cluster, \
            distributed.Client(cluster) as client:
        with_client = stability_map(paper, [1, 2, 3], OMEGA, GAP, executor=client)
        with_executor = stability_map(paper, [1, 2, 3], OMEGA, GAP,
                                      executor=client.get_executor())
    xr.testing.assert_identical(with_client.drop_attrs(), serial_map.drop_attrs())
    xr.testing.assert_identical(with_executor.drop_attrs(), serial_map.drop_attrs())
    assert '"executor": "dask.distributed"' in with_client.attrs["options"]


def test_two_parameter_figure(paper, serial_map, tmp_path):
    from impactcont.analysis.curves import curve
    from impactcont.plots.maps import region_codes, two_parameter_figure

    codes = region_codes(serial_map, 1)
    assert set(np.unique(codes.values)) <= {0, 1, 2, 3}
    assert ((codes == 0) == ~serial_map.exists.sel(N=1)).all()
    zv = curve(paper, 1, "ZV", start={"omega": 1.3012, "b": 0.4},
               bounds={"omega": (0.5, 6.0), "b": (-1.0, 2.0)}, detect_codim2_points=False)
    fig = two_parameter_figure(serial_map, [zv])
    path = tmp_path / "map.png"
    fig.savefig(path)
    assert path.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    texts = [t.get_text() for ax in fig.axes for t in ax.texts]
    assert "ZV" in texts


def test_results_are_bit_identical_for_every_block_size_and_executor(paper, serial_map):
    for block, executor in ((1, None), (5, None), (7, "process"), (23, "process")):
        other = stability_map(paper, [1, 2, 3], OMEGA, GAP, omega_block=block, executor=executor,
                              max_workers=2)
        xr.testing.assert_identical(other.drop_attrs(), serial_map.drop_attrs())


def test_a_map_written_to_disk_opens_lazily_and_equals_the_in_memory_one(paper, serial_map,
                                                                       tmp_path):
    pytest.importorskip("dask")
    lazy = stability_map(paper, [1, 2, 3], OMEGA, GAP, out=tmp_path / "map.nc", omega_block=4)
    assert hasattr(lazy.n_stable.data, "dask")  # nothing read yet
    xr.testing.assert_identical(lazy.load().drop_attrs(), serial_map.drop_attrs())
    pooled = stability_map(paper, [1, 2, 3], OMEGA, GAP, out=tmp_path / "pooled.nc",
                           executor="process", max_workers=2, omega_block=6)
    xr.testing.assert_identical(pooled.load().drop_attrs(), serial_map.drop_attrs())


def test_a_map_larger_than_the_memory_limit_goes_to_a_file(paper, serial_map, caplog):
    pytest.importorskip("dask")
    with caplog.at_level("WARNING", logger="impactcont.analysis.maps"):
        lazy = stability_map(paper, [1, 2, 3], OMEGA, GAP, memory_limit=1e4)
    assert "more than memory_limit" in caplog.text
    path = lazy.encoding["source"]
    xr.testing.assert_identical(lazy.load().drop_attrs(), serial_map.drop_attrs())
    lazy.close()
    assert not os.path.exists(path)  # a temporary map is removed when it is closed


def test_map_without_eigenvalues_has_the_same_stability(paper, serial_map):
    quick = stability_map(paper, [1, 2, 3], OMEGA, GAP, spectral_radius=False)
    assert "spectral_radius" not in quick and "critical_multiplier" not in quick
    for key in ("exists", "n_physical", "n_stable", "delta", "gap_min", "stable", "physical"):
        xr.testing.assert_identical(quick[key], serial_map[key])
    rho = serial_map.spectral_radius.values
    decided = np.isfinite(rho) & (np.abs(rho - 1.0) > 1e-9)
    assert np.array_equal(serial_map.stable.values[decided], rho[decided] < 1.0)
