"""The synthetic campaign end to end (issue: experimental campaign).

synth (178 tools) → run (hybrid, 2 workers: timed) → learn (ANFIS 3×7 gauss,
order 1, log10 targets, 148/30) → predict the FRF of the 30 test tools → compare with the
truth (true subassembly + truth-law joint, noise-free): dominant peak
frequency and magnitude errors. Only this script reads truth/.

    python benchmarks/bench_campaign.py [--workdir DIR] [--n 178]
"""

from __future__ import annotations

import argparse
import csv
import tempfile
import time
from pathlib import Path

import numpy as np

from toolpoint.dynamics.assembly import load_assembly
from toolpoint.campaign.config import load_campaign
from toolpoint.campaign.learn import learn
from toolpoint.campaign.predict import predict_frf
from toolpoint.campaign.results import read_identified
from toolpoint.campaign.run import run_campaign
from toolpoint.campaign.synth import synthesise, truth_joint
from toolpoint.cli.campaign import report_lines
from toolpoint.errors import InputError
from toolpoint.dynamics.model import ToolPointModel
from toolpoint.dynamics.subassembly import Subassembly


def _read_csv(path: Path) -> dict:
    """Rows of a CSV with an ``id`` column, by id."""
    with open(path, newline="") as fh:
        return {x["id"]: x for x in csv.DictReader(fh)}


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--workdir")
    ap.add_argument("--n", type=int, default=178)
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--reuse", action="store_true", help="keep an existing campaign and results in --workdir")
    ap.add_argument("--mfs", default="3,7")
    ap.add_argument("--linear-target", action="store_true", help="ANFIS on the targets themselves (paper)")
    a = ap.parse_args()
    work = Path(a.workdir or tempfile.mkdtemp(prefix="toolpoint-campaign-"))
    camp, res = work / "campaign", work / "results"
    if not (a.reuse and (res / "identified.csv").exists()):
        t = time.perf_counter()
        synthesise(camp, n=a.n, seed=0)
        print(f"synth: {a.n} tools in {time.perf_counter() - t:.1f} s → {camp}")
        r = run_campaign(camp, res, workers=a.workers, progress=False)
        print(f"run (hybrid, {a.workers} workers): {r.ok} ok, {r.failed} failed in {r.seconds:.1f} s "
              f"(target < 60 s for 178 on 2 cores)")

    ident = {x["id"]: x for _, x in read_identified(res / "identified.csv").rows}
    truth = _read_csv(camp / "truth" / "truth.csv")
    print("\nidentified vs truth law (all tools): median / 90th percentile |relative error|")
    for p in ("kt", "ct", "kr", "cr"):
        e = np.array([abs(float(ident[i][p]) / float(truth[i][p]) - 1) for i in ident if ident[i]["status"] == "ok"])
        cover = np.mean([float(ident[i][f"{p}_lo"]) <= float(truth[i][p]) <= float(ident[i][f"{p}_hi"])
                         for i in ident if ident[i]["status"] == "ok"])
        print(f"  {p}: {np.median(e) * 100:7.2f} % / {np.percentile(e, 90) * 100:7.2f} %   "
              f"(truth inside 95 % CI: {cover:.0%})")

    print()
    mfs = tuple(int(v) for v in a.mfs.split(","))
    result = learn(res, test_size=30, mfs=mfs, mf="gauss", order=1, seed=0, log_target=not a.linear_target)
    print("\n".join(report_lines(result)))

    split = {i: x["set"] for i, x in _read_csv(res / "models" / "split.csv").items()}
    c = load_campaign(camp)
    f = c.subassembly("ER40", None).freq_hz
    true_sub = Subassembly.from_assembly(load_assembly(camp / "truth" / "spindle_holder.toml", require_tool=False), f)
    df, dm, failed, jerr = [], [], 0, []
    for m in c.measurements:
        if split.get(m.id) != "test":
            continue
        try:
            r = predict_frf(camp, m.diameter_mm, m.overhang_mm, res / "models")
            pred, joint = r.frf, r.joint.joint
        except InputError as e:
            print(f"  {m.id} (D {m.diameter_mm:g}, L {m.overhang_mm:g}): no prediction — {e}")
            failed += 1
            continue
        tool = c.family.tool(m.diameter_mm, m.overhang_mm)
        tj = truth_joint(m.diameter_mm, m.overhang_mm)
        jerr.append(abs(joint / tj - 1))
        true = ToolPointModel(tool, true_sub, f).tool_point(tj)
        k = int(np.argmax(abs(true)))
        kp = int(np.argmax(abs(pred.values)))
        df.append(abs(f[kp] - f[k]) / f[k])
        dm.append(abs(abs(pred.values[kp]) / abs(true[k]) - 1))
    df, dm, jerr = np.array(df), np.array(dm), np.array(jerr)
    print(f"\npredicted joint of the {len(jerr)} test tools vs the truth law (median / max |relative error|; "
          "a parameter without a model is its campaign median):")
    for k, p in enumerate(("kt", "ct", "kr", "cr")):
        print(f"  {p}: {np.median(jerr[:, k]) * 100:6.2f} % / {jerr[:, k].max() * 100:6.2f} %")
    print(f"\npredicted FRF of the {df.size} test tools vs truth ({failed} without a prediction):")
    print(f"  dominant peak frequency error: median {np.median(df) * 100:.2f} %, max {df.max() * 100:.2f} % "
          "(goal median < 1 %)")
    print(f"  dominant peak magnitude error: median {np.median(dm) * 100:.1f} %, max {dm.max() * 100:.1f} % "
          "(goal median < 10 %)")


if __name__ == "__main__":
    main()
