"""Maps that outgrow memory: points/s and peak memory for 1e6 and 1e7 points.

Each configuration runs in its own interpreter (warm numba cache) while this script
samples the resident memory of that process and all its children (pool workers,
dask workers) every 0.1 s with psutil; the peak of the sum is reported. The map is
written block by block to a chunked, compressed NetCDF-4 file (``out=``) and
opened lazily; the child then sums ``n_stable`` through dask (a full read).

    OPENBLAS_NUM_THREADS=1 .venv/bin/python studies/performance/big_maps.py [--quick]

Writes ``output/big_maps.json`` and ``output/big_maps.md`` (``output/quick/`` with
``--quick``).
"""

from __future__ import annotations

import argparse
import contextlib
import json
import logging
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import psutil

log = logging.getLogger("big_maps")
HERE = Path(__file__).resolve().parent

CHILD = r"""
import json, sys, time
import numpy as np
import impactcont as ic
side, executor, path = int(sys.argv[1]), sys.argv[2], sys.argv[3]
osc = ic.ImpactOscillator(M=np.eye(2), K=[[1, -1], [-1, 2]], F=[1, 0], R=0.6, b=0.5,
                          omega=1.0, eta=0.1)
omega, b = np.linspace(0.5, 6.0, side), np.linspace(-1.0, 1.5, side)
kw = {}
if executor == "process":
    kw = {"executor": "process", "max_workers": 2}
elif executor == "dask":
    from dask.distributed import Client, LocalCluster
    cluster = LocalCluster(n_workers=2, threads_per_worker=1, processes=True,
                           dashboard_address=None)
    kw = {"executor": Client(cluster)}
t = time.perf_counter()
ds = ic.stability_map(osc, [1, 2, 3, 4], omega, b, spectral_radius=False, out=path, **kw)
elapsed = time.perf_counter() - t
lazy = hasattr(ds.n_stable.data, "dask")
total = int(ds.n_stable.sum().compute())
if executor == "dask":
    kw["executor"].close()
    cluster.close()
print(json.dumps({"elapsed": elapsed, "lazy": lazy, "n_stable": total}))
"""


def _tree_rss(proc: psutil.Process) -> int:
    total = 0
    for p in [proc, *proc.children(recursive=True)]:
        with contextlib.suppress(psutil.Error):  # a worker may exit while we look
            total += p.memory_info().rss
    return total


def run_one(side: int, executor: str, directory: str) -> dict:
    path = os.path.join(directory, f"map_{side}_{executor}.nc")
    child = subprocess.Popen([sys.executable, "-c", CHILD, str(side), executor, path],
                             stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    proc = psutil.Process(child.pid)
    peak = 0
    while child.poll() is None:
        peak = max(peak, _tree_rss(proc))
        time.sleep(0.1)
    out, err = child.communicate()
    if child.returncode != 0:
        raise RuntimeError(f"{executor} map of side {side} failed:\n{err}")
    result = json.loads(out.strip().splitlines()[-1])
    points = 4 * side * side
    row = {"points": points, "executor": executor, "seconds": round(result["elapsed"], 2),
           "points_per_s": points / result["elapsed"], "peak_gb": peak / 1e9,
           "file_mb": os.path.getsize(path) / 1e6, "lazy": result["lazy"],
           "n_stable": result["n_stable"]}
    os.unlink(path)
    log.info("%s", row)
    return row


def main(quick: bool) -> list[dict]:
    sides = (500,) if quick else (500, 1600)  # 1e6 and 1.02e7 points (N = 1..4)
    executors = ("serial", "process") if quick else ("serial", "process", "dask")
    with tempfile.TemporaryDirectory() as directory:
        rows = [run_one(side, ex, directory) for side in sides for ex in executors]
    out = HERE / "output" / ("quick" if quick else "")
    out.mkdir(parents=True, exist_ok=True)
    (out / "big_maps.json").write_text(json.dumps(rows, indent=2))
    lines = ["| points | executor | time (s) | points/s | peak memory (GB) | file (MB) | "
             "opens lazily |", "|---|---|---|---|---|---|---|"]
    for r in rows:
        lines.append(f"| {r['points']:.3g} | {r['executor']} | {r['seconds']} | "
                     f"{r['points_per_s']:.3g} | {r['peak_gb']:.2f} | {r['file_mb']:.0f} | "
                     f"{'yes' if r['lazy'] else 'no'} |")
    (out / "big_maps.md").write_text("\n".join(lines) + "\n")
    for line in lines:
        log.info(line)
    return rows


if __name__ == "__main__":
    logging.basicConfig(level=logging.INFO, format="%(message)s")
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="1e6 points only, no dask")
    main(parser.parse_args().quick)
