"""Peak memory of one stability_map over the whole process tree (docs/two_parameter.md).

The table of docs/two_parameter.md ("Memory") was measured with this script: the map
runs in a child interpreter (numba warmed, xarray, dask and netCDF4 imported before the
baseline), and its peak is the larger of the child's own high-water mark (VmHWM) and the
proportional set size of the child and its workers sampled every 50 ms (psutil, which
this script needs), both above the baseline. Grid: N = 1..4 on SIDE x SIDE points of
omega in [0.5, 6] and b in [-1, 1.5] of the paper's 2-DOF system. Run::

    .venv/bin/python studies/performance/map_memory.py 500                       # 1e6 points
    .venv/bin/python studies/performance/map_memory.py 500 --executor process
    .venv/bin/python studies/performance/map_memory.py 500 --memory-limit 5e7
    .venv/bin/python studies/performance/map_memory.py 1581                      # 1e7, lazy
    .venv/bin/python studies/performance/map_memory.py 1581 --out /tmp/map.nc
"""
import argparse
import contextlib
import json
import subprocess
import sys
import time

import psutil

CHILD = r"""
import json, sys, time, os
import numpy as np
import impactcont as ic
from impactcont.analysis.maps import stability_map
side = int(sys.argv[1]); kw = json.loads(sys.argv[2])
osc = ic.ImpactOscillator(M=np.eye(2), K=[[1, -1], [-1, 2]], F=[1, 0], R=0.6, b=0.5,
                          omega=1.0, eta=0.1)
stability_map(osc, [1], np.linspace(0.5, 6, 8), np.linspace(-1, 1.5, 8))  # warm numba
import xarray, dask.array, netCDF4  # imports counted in the baseline
def rss(key="VmRSS"):
    for line in open("/proc/self/status"):
        if line.startswith(key): return int(line.split()[1]) * 1024
print(json.dumps({"baseline": rss()}), flush=True)
time.sleep(0.3)
omega, b = np.linspace(0.5, 6.0, side), np.linspace(-1.0, 1.5, side)
t = time.perf_counter()
ds = stability_map(osc, [1, 2, 3, 4], omega, b, **kw)
elapsed = time.perf_counter() - t
lazy = hasattr(ds.n_stable.data, "dask")
result = sum(v.dtype.itemsize * v.size for v in ds.variables.values())
print(json.dumps({"elapsed": elapsed, "lazy": lazy, "result": result,
                  "source": ds.encoding.get("source"), "hwm": rss("VmHWM")}), flush=True)
"""

def tree_rss(proc):
    """Proportional set size of the process and its children (shared pages counted once)."""
    total = 0
    for p in [proc, *proc.children(recursive=True)]:
        with contextlib.suppress(psutil.Error):
            total += p.memory_full_info().pss
    return total


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("side", type=int)
    ap.add_argument("--executor")
    ap.add_argument("--out")
    ap.add_argument("--memory-limit", type=float)
    a = ap.parse_args()
    kw = {}
    if a.executor:
        kw.update(executor=a.executor, max_workers=2)
    if a.out:
        kw["out"] = a.out
    if a.memory_limit:
        kw["memory_limit"] = a.memory_limit
    child = subprocess.Popen([sys.executable, "-c", CHILD, str(a.side), json.dumps(kw)],
                             stdout=subprocess.PIPE, text=True)
    proc = psutil.Process(child.pid)
    rss_baseline = json.loads(child.stdout.readline())["baseline"]
    baseline = tree_rss(proc)
    peak = 0
    while child.poll() is None:
        peak = max(peak, tree_rss(proc))
        time.sleep(0.05)
    res = json.loads(child.stdout.read().strip().splitlines()[-1])
    inc = max(peak - baseline, res["hwm"] - rss_baseline)
    print(json.dumps({
        "points": 4 * a.side ** 2, **kw, "baseline_MB": round(baseline / 1e6),
        "peak_MB": round(peak / 1e6), "increment_MB": round(inc / 1e6),
        "tree_pss_inc_MB": round((peak - baseline) / 1e6),
        "self_hwm_inc_MB": round((res["hwm"] - rss_baseline) / 1e6),
        "result_MB": round(res["result"] / 1e6), "ratio": round(inc / res["result"], 2),
        "lazy": res["lazy"], "seconds": round(res["elapsed"], 1), "source": res["source"]}))


if __name__ == "__main__":
    main()
