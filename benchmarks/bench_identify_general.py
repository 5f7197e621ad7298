"""Objective throughput of the general identification (issue 14) on one core.

Spindle–holder joint (4 parameters) from a 3001-point holder-tip FRF of the spindle–holder subassembly of
examples/numerical_case.toml (1–3001 Hz, 1 Hz): ``FRFProblem.evaluate`` on population batches of 50, 400
and 2000 points (target ≥ 5 000 evaluations/s), with the holder–tool ``JointProblem`` beside it, and the
general (Woodbury) path for the joint plus two front bearings.

Run: .venv/bin/python benchmarks/bench_identify_general.py (thread variables default to 1 here when unset).
"""

from __future__ import annotations

import os

for _v in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_v, "1")  # before numpy is imported: one core unless the caller says otherwise

import datetime  # noqa: E402
import platform  # noqa: E402
import time  # noqa: E402
from pathlib import Path  # noqa: E402

import numpy as np  # noqa: E402

from toolpoint.dynamics.assembly import load_assembly  # noqa: E402
from toolpoint.dynamics.points import ReceptanceModel, parse_point  # noqa: E402
from toolpoint.frf import FRF  # noqa: E402
from toolpoint.identification.identify import model_for  # noqa: E402
from toolpoint.identification.objective import JointProblem  # noqa: E402
from toolpoint.identification.problem import FRFProblem, Measured, joint_names  # noqa: E402


def rate(problem, n: int, repeat: int = 5) -> float:
    X = problem.xl + np.random.default_rng(0).random((n, problem.n_var)) * (problem.xu - problem.xl)
    best = np.inf
    for _ in range(repeat):
        t = time.perf_counter()
        problem.evaluate(X)
        best = min(best, time.perf_counter() - t)
    return n / best


def main() -> None:
    a = load_assembly(Path(__file__).resolve().parents[1] / "examples" / "numerical_case.toml")
    f = np.arange(1.0, 3002.0, 1.0)
    ht = parse_point("holder_tip")
    m = ReceptanceModel(a, f, [ht], [], with_tool=False)
    meas = Measured(FRF(f, m.G0[:, m.dof(ht), m.dof(ht)]), ht, ht)
    sh = FRFProblem(a, joint_names("spindle_holder"), [meas], with_tool=False)
    mo = model_for(a, f)
    hto = JointProblem(mo.coupler, mo.tool_point(a.holder_tool.as_array()))
    gen = FRFProblem(a, ["spindle_holder.kt", "bearings[1].k", "bearings[2].k"], [meas], with_tool=False)
    print(f"{platform.node()} {platform.processor() or platform.machine()}, Python {platform.python_version()}, "
          f"NumPy {np.__version__}, {datetime.datetime.now().isoformat(timespec='seconds')}, "
          f"OMP/OPENBLAS threads {os.environ['OMP_NUM_THREADS']}/{os.environ['OPENBLAS_NUM_THREADS']}")
    print(f"F = {f.size} frequencies; evaluations/s (best of 5)")
    for n in (50, 400, 2000):
        print(f"  batch {n:5d}: spindle–holder joint (rational) {rate(sh, n):9.0f}   "
              f"holder–tool JointProblem {rate(hto, n):9.0f}")
    print(f"  batch    40: joint kt + 2 bearings (general)  {rate(gen, 40, 2):9.0f}")


if __name__ == "__main__":
    main()
