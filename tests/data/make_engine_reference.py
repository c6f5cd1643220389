"""Write ``engine_reference.json``: the special points of representative runs, frozen.

Run on the code whose results are to be kept (``python tests/data/make_engine_reference.py``);
``tests/integration/test_engine_regression.py`` recomputes the same runs and compares each point to
1e-10 or to the precision both runs claim for it, whichever is larger.
"""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np

import impactcont as ic

HERE = Path(__file__).resolve().parent
REFERENCE = HERE / "engine_reference.json"

#: the paper's two-degree-of-freedom system (Cao & Shu)
PAPER = dict(M=np.eye(2), K=[[1.0, -1.0], [-1.0, 2.0]], F=[1.0, 0.0], R=0.6, eta=0.1)


def paper(b: float, omega: float) -> ic.ImpactOscillator:
    return ic.ImpactOscillator(b=b, omega=omega, **PAPER)


def _branch_n1():
    return ic.continuation(paper(0.0, 1.5), N=1, parameter="omega", bounds=(1.4, 2.0),
                           components="start")


def run_all() -> dict[str, object]:
    """Every run by name: a branch or curve dataset."""
    branch_n1 = _branch_n1()
    sn = ic.curve(paper(1.3204359424, 1.0), 1, "SN", start={"omega": 1.0, "b": 1.3204359424},
                  bounds={"omega": (0.6, 2.0), "b": (0.0, 2.0)})
    b0 = ic.continuation(paper(0.0, 1.0), N=1, parameter="omega", bounds=(0.6, 2.0),
                         detect=["PD"])
    return {
        "omega_N1_b0": ic.continuation(paper(0.0, 1.0), N=1, parameter="omega",
                                       bounds=(0.5, 6.0)),
        "omega_N1_b05": ic.continuation(paper(0.5, 1.0), N=1, parameter="omega",
                                        bounds=(0.5, 3.0)),
        "omega_N2_b05": ic.continuation(paper(0.5, 1.0), N=2, parameter="omega",
                                        bounds=(0.5, 6.0)),
        "b_N1_omega25": ic.continuation(paper(0.3, 2.5), N=1, parameter="b",
                                        bounds=(-1.0, 1.0)),
        "np_N1_start": branch_n1,
        "np_PD_switch": ic.period_doubling_switch(branch_n1, bounds=(1.6, 1.9)),
        "curve_PD": ic.curve(paper(0.0, 1.0), None, "PD", start=b0,
                             bounds={"omega": (0.6, 2.0), "b": (0.0, 0.6)}),
        "curve_SN": sn,
    }


def summary(ds) -> dict[str, object]:
    """The special (or codim-2) points of a dataset and its number of points."""
    dim = "codim2" if "codim2" in ds.dims else "special"
    pre = "codim2_" if dim == "codim2" else "special_"
    rows = []
    for k in range(ds.sizes.get(dim, 0)):
        row = ds.isel({dim: k})
        rows.append({"label": str(row[pre + "label"].values),
                     "omega": float(row[pre + "omega"]), "b": float(row[pre + "b"]),
                     "delta": math.remainder(float(row[pre + "delta"]), 2 * math.pi),
                     "precision": float(row[pre + "precision"]),
                     "status": str(row[pre + "status"].values)})
    return {"points": int(ds.sizes["point"]), "special": rows}


def main() -> None:
    reference = {name: summary(ds) for name, ds in run_all().items()}
    REFERENCE.write_text(json.dumps(reference, indent=1) + "\n")
    for name, entry in reference.items():
        print(name, entry["points"], [r["label"] for r in entry["special"]])


if __name__ == "__main__":
    main()
