"""Benchmark and validation of ``toolpoint library`` (recommend/).

1. Coverage: on a real synthetic campaign (``campaign synth`` + ``run`` + ``learn``), for the held-out tools
   of ``models/split.csv``, the share of (tool, speed) pairs where the limit of the truth-law joint
   (camp/truth/) lies inside the predicted 5–95 % band — for the ANFIS distribution and for the GP
   baseline's own (``--model gp``).
2. Speed: N tools (default 1000; zero-order lobes at 500 speeds, 200 samples each) with a local process
   pool of --workers (wall time, and the CPU time the tools took, summed from their JSON files), and
   on a Dask LocalCluster with 1 and 2 worker processes of 1 thread each on the first --dask-tools tools.

Usage::

    python benchmarks/bench_library.py --campaign CAMP --results CAMP/results [--tools 1000] [--workers 2]
        [--dask] [--dask-tools 100]

(CAMP from ``toolpoint campaign synth --n 178 CAMP``, ``campaign run CAMP --out CAMP/results``,
``campaign learn CAMP/results --mfs 3,3``.) Results: docs/design/recommend.md.
"""

from __future__ import annotations

import argparse
import csv
import json
import os
import tempfile
import time
from pathlib import Path

import numpy as np

from toolpoint.campaign.config import load_campaign
from toolpoint.campaign.synth import truth_joint
from toolpoint.dynamics.model import ToolPointModel
from toolpoint.stability.zoa_batch import zoa_limits
from toolpoint.recommend.run import run_library
from toolpoint.campaign.distribution import JointPredictor
from toolpoint.stability import CuttingConditions

HEADER = ("id,diameter_mm,overhang_mm,teeth,holder,tangential_coeff_n_mm2,radial_ratio,material,radial_immersion,"
          "milling,rpm_min,rpm_max")


def coverage(camp: Path, results: Path, model="anfis", n_samples=200, cap_m=0.02) -> float:
    c = load_campaign(camp)
    sub = c.subassembly("ER40", None)
    f = sub.freq_hz
    pred = JointPredictor(results / "models", model)
    with open(results / "models" / "split.csv", newline="") as fh:
        test = [r["id"] for r in csv.DictReader(fh) if r["set"] == "test"]
    with open(camp / "truth" / "truth.csv", newline="") as fh:
        truth = {r["id"]: (float(r["diameter_mm"]), float(r["overhang_mm"])) for r in csv.DictReader(fh)}
    rng = np.random.default_rng(0)
    cuts = [CuttingConditions(3, 796e6, 0.212, 0.5, "down"), CuttingConditions(2, 600e6, 1 / 3, 1.0, "up")]
    grid = np.linspace(3000, 20000, 500)
    hits = []
    for tid in test:
        D, L = truth[tid]
        tp = ToolPointModel(c.family.tool(D, L), sub, f)
        H = tp.tool_point(pred.predict(D, L).sample(0, n_samples, rng))
        h_true = tp.tool_point(truth_joint(D, L))
        for cut in cuts:
            lo, hi = np.quantile(zoa_limits(f, H, cut, grid, cap_m=cap_m), [0.05, 0.95], axis=0)
            true = zoa_limits(f, h_true, cut, grid, cap_m=cap_m)
            hits.append((true >= lo * (1 - 1e-9)) & (true <= hi * (1 + 1e-9)))
    cov = float(np.mean(hits))
    per_tool = np.mean(hits, axis=1)
    print(f"{model}: coverage of the true limit by the 5–95 % band: {cov:.3f} over {len(test)} held-out tools × "
          f"2 cuts × {grid.size} speeds (per tool-cut: min {per_tool.min():.2f}, median {np.median(per_tool):.2f}, "
          f"share of tool-cuts ≥ 0.85: {np.mean(per_tool >= 0.85):.2f})")
    return cov


def library(path: Path, n: int, seed=0) -> Path:
    rng = np.random.default_rng(seed)
    rows = []
    for i in range(n):
        D = rng.choice([10, 12, 14, 16, 18, 20, 22, 25])
        rows.append(f"T{i:04d},{D},{rng.uniform(25, 80):.1f},{rng.choice([2, 3, 4])},ER40,,,al7075,"
                    f"{rng.choice([0.25, 0.5, 1.0])},down,4000,20000")
    path.write_text(HEADER + "\n" + "\n".join(rows) + "\n")
    return path


def cpu_seconds(out: Path) -> np.ndarray:
    """CPU time each tool took in its worker (``cpu_seconds`` of the tools' JSON files)."""
    return np.array([json.loads(p.read_text())["cpu_seconds"] for p in sorted((out / "tools").glob("*.json"))])


def speed(camp: Path, results: Path, n: int, workers: int, dask: bool, dask_tools: int) -> None:
    tmp = Path(tempfile.mkdtemp(prefix="bench_library_"))
    lib = library(tmp / "lib.csv", n)
    load = os.getloadavg()[0]
    t = time.perf_counter()
    r = run_library(lib, camp, results / "models", tmp / "pool", workers=workers, progress=False)
    dt = time.perf_counter() - t
    cpu = cpu_seconds(tmp / "pool")
    print(f"{n} tools, process pool of {workers}: {dt:.1f} s wall ({r.ok} ok); CPU per tool mean "
          f"{cpu.mean():.3f} s, max {cpu.max():.2f} s, sum {cpu.sum():.0f} s (sum/{workers} = "
          f"{cpu.sum() / workers:.0f} s); load average 1 min before {load:.1f}, after {os.getloadavg()[0]:.1f}")
    if dask:
        import dask
        from distributed import LocalCluster

        # Dask starts its workers with MALLOC_TRIM_THRESHOLD_=65536, which turns off glibc's adaptive mmap
        # threshold: every MB-sized NumPy temporary is then mapped and zeroed afresh, +50 % CPU per tool here
        # (docs/design/recommend.md). Workers get only the single-thread BLAS settings; the statistical
        # profiler (a thread sampling every 10 ms) is off as well.
        environ = {k: v for k, v in dask.config.get("distributed.nanny.pre-spawn-environ").items()
                   if k != "MALLOC_TRIM_THRESHOLD_"}
        dask.config.set({"distributed.worker.profile.enabled": False, "distributed.nanny.pre-spawn-environ": environ})
        sub = library(tmp / "lib_dask.csv", dask_tools)  # the first dask_tools tools of the same library
        base = None
        for w in (1, 2):
            with LocalCluster(n_workers=w, threads_per_worker=1, processes=True, dashboard_address=None) as cluster:
                load = os.getloadavg()[0]
                t = time.perf_counter()
                r = run_library(sub, camp, results / "models", tmp / f"dask{w}", dask=cluster.scheduler_address,
                                progress=False)
                dt = time.perf_counter() - t
            base = base or dt
            cpu = cpu_seconds(tmp / f"dask{w}")
            print(f"{dask_tools} tools, Dask LocalCluster {w} worker(s) × 1 thread: {dt:.1f} s wall ({r.ok} ok), "
                  f"speed-up ×{base / dt:.2f}; CPU sum {cpu.sum():.0f} s; load average before {load:.1f}")


if __name__ == "__main__":
    ap = argparse.ArgumentParser()
    ap.add_argument("--campaign", type=Path, required=True)
    ap.add_argument("--results", type=Path, required=True)
    ap.add_argument("--tools", type=int, default=1000)
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--dask", action="store_true")
    ap.add_argument("--dask-tools", type=int, default=100)
    ap.add_argument("--no-coverage", action="store_true")
    ap.add_argument("--no-speed", action="store_true")
    a = ap.parse_args()
    print(f"{time.strftime('%Y-%m-%d %H:%M UTC', time.gmtime())}, {os.cpu_count()} cores, "
          f"OMP_NUM_THREADS={os.environ.get('OMP_NUM_THREADS')}")
    if not a.no_coverage:
        for m in ("anfis", "gp"):
            coverage(a.campaign, a.results, m)
    if not a.no_speed:
        speed(a.campaign, a.results, a.tools, a.workers, a.dask, a.dask_tools)
