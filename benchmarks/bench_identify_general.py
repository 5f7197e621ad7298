"""Objective throughput of the general identification (issue 14) on one core.

Spindle–holder joint (4 parameters) from a 3001-point holder-tip FRF of the spindle–holder subassembly of
examples/numerical_case.toml (1–3001 Hz, 1 Hz): ``FRFProblem.evaluate`` on population batches of 50, 400
and 2000 points (target ≥ 5 000 evaluations/s), with the holder–tool ``JointProblem`` beside it, and the
general path (several elements) in its polynomial form and, for comparison, by the Woodbury solves it
replaced: the joint's kt plus two front bearings (4 spring DOFs), the joint's kt, kr with two bearings
from the holder-tip and a spindle-nose cross FRF together (4 DOFs), the whole joint with two bearings
with rotational springs (6 DOFs) and with all three bearings with rotational springs (8 DOFs: above
``POLY_MAX_DOF``, Woodbury only).

CPU time (``time.process_time``), best of the repeats.

``--coverage N`` instead measures the 95 % intervals: the spindle–holder joint from the FE holder-tip FRF
(0.5 mm elements, 2–3000 Hz every 2 Hz) with 1 % complex noise, noise seeds 0 … N−1, hybrid seed 0 from a
start 5× off; it prints, per parameter, how many profile-likelihood and how many linearised intervals hold
the truth.

Run: .venv/bin/python benchmarks/bench_identify_general.py (thread variables default to 1 here when unset).
"""

from __future__ import annotations

import os

for _v in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_v, "1")  # before numpy is imported: one core unless the caller says otherwise

import datetime  # noqa: E402
import sys  # noqa: E402
import warnings  # noqa: E402
import platform  # noqa: E402
import time  # noqa: E402
from pathlib import Path  # noqa: E402

import numpy as np  # noqa: E402

from toolpoint.dynamics.assembly import load_assembly  # noqa: E402
from toolpoint.dynamics.points import ReceptanceModel, fe_frf, parse_point  # noqa: E402
from toolpoint.frf import FRF  # noqa: E402
from toolpoint.identification.identify import model_for  # noqa: E402
from toolpoint.identification.objective import JointProblem  # noqa: E402
from toolpoint.identification.problem import FRFProblem, Measured, identify_frfs, joint_names  # noqa: E402


def rate(problem, n: int, repeat: int = 5, woodbury: bool = False) -> float:
    X = problem.xl + np.random.default_rng(0).random((n, problem.n_var)) * (problem.xu - problem.xl)
    poly = getattr(problem, "_poly", None)
    if woodbury:
        problem._poly = None
    best = np.inf
    try:
        for _ in range(repeat):
            t = time.process_time()
            problem.evaluate(X)
            best = min(best, time.process_time() - t)
    finally:
        if woodbury:
            problem._poly = poly
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
    nose = parse_point("spindle_nose")
    m2 = ReceptanceModel(a, f, [ht, nose], [], with_tool=False)
    two = [meas, Measured(FRF(f, m2.G0[:, m2.dof(nose), m2.dof(ht)]), nose, ht)]
    gen6 = FRFProblem(a, ["spindle_holder.kt", "spindle_holder.kr", "bearings[1].k", "bearings[2].k"], two,
                      with_tool=False)
    rot = ["bearings[1].kr", "bearings[2].kr"]
    gen7 = FRFProblem(a, joint_names("spindle_holder") + ["bearings[1].k", "bearings[2].k"] + rot, [meas],
                      start={k: 1e6 for k in rot}, with_tool=False)
    rot3 = ["bearings[0].kr", *rot]
    gen8 = FRFProblem(a, joint_names("spindle_holder") + ["bearings[0].k", "bearings[1].k", "bearings[2].k"] + rot3,
                      [meas], start={k: 1e6 for k in rot3}, with_tool=False)
    print(f"{platform.node()} {platform.processor() or platform.machine()}, Python {platform.python_version()}, "
          f"NumPy {np.__version__}, {datetime.datetime.now().isoformat(timespec='seconds')}, "
          f"OMP/OPENBLAS threads {os.environ['OMP_NUM_THREADS']}/{os.environ['OPENBLAS_NUM_THREADS']}")
    print(f"F = {f.size} frequencies; evaluations/s (best of 5)")
    for n in (50, 400, 2000):
        print(f"  batch {n:5d}: spindle–holder joint (rational) {rate(sh, n):9.0f}   "
              f"holder–tool JointProblem {rate(hto, n):9.0f}")
    for label, p in (("joint kt + 2 bearings, 4 DOFs", gen), ("joint kt, kr + 2 bearings, 2 FRFs, 4 DOFs", gen6),
                     ("joint + 2 bearings with kr, 6 DOFs", gen7), ("joint + 3 bearings with kr, 8 DOFs", gen8)):
        poly = f"{rate(p, 400, 3):9.0f}" if p._poly is not None else "        –"
        print(f"  batch 400 (polynomial) / 40 (Woodbury): {label:44s} {poly} / {rate(p, 40, 2, woodbury=True):6.0f}")


def coverage(n_seeds: int) -> None:
    a = load_assembly(Path(__file__).resolve().parents[1] / "examples" / "numerical_case.toml")
    f = np.arange(2.0, 3001.0, 2.0)
    ht = parse_point("holder_tip")
    h = fe_frf(a, f, ht, with_tool=False, max_element_m=0.5e-3)
    names = joint_names("spindle_holder")
    truth = a.spindle_holder.as_array()
    start = dict(zip(names, truth * np.array([5.0, 0.2, 5.0, 0.2])))
    sigma = 0.01 * np.abs(h).max() / np.sqrt(2)
    held = {m: np.zeros(4, int) for m in ("profile", "linear")}
    flagged = np.zeros(4, int)
    all_held = 0
    t0 = time.process_time()
    for seed in range(n_seeds):
        rng = np.random.default_rng(seed)
        noisy = h + sigma * (rng.standard_normal(f.size) + 1j * rng.standard_normal(f.size))
        p = FRFProblem(a, names, [Measured(FRF(f, noisy), ht, ht)], start=start, with_tool=False)
        for mode in ("profile", "linear"):
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")
                r = identify_frfs(p, "hybrid", seed=0, intervals=mode)
            inside = np.array([r.ci95[k][0] <= v <= r.ci95[k][1] for k, v in zip(names, truth)])
            held[mode] += inside
            if mode == "profile":
                all_held += inside.all()
                flagged += [any(w.startswith(k + " is not identifiable") for w in r.warnings) for k in names]
                print(f"seed {seed:3d}: " + "  ".join(
                    f"{k.split('.')[1]} {r.params[k] / v - 1:+.3f} [{r.ci95[k][0] / v:.3g}, {r.ci95[k][1] / v:.3g}]"
                    f"{'' if ok else ' MISS'}" for k, v, ok in zip(names, truth, inside)), flush=True)
    print(f"{n_seeds} seeds, {time.process_time() - t0:.0f} s CPU; intervals holding the truth (of {n_seeds}):")
    for k, i in zip(names, range(4)):
        print(f"  {k:20s} profile {held['profile'][i]:3d}   linearised {held['linear'][i]:3d}   "
              f"flagged not identifiable {flagged[i]:3d}")
    print(f"  all four inside (profile): {all_held} of {n_seeds} seeds")


if __name__ == "__main__":
    if len(sys.argv) == 3 and sys.argv[1] == "--coverage":
        coverage(int(sys.argv[2]))
    else:
        main()
