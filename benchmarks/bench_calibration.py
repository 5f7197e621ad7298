"""Calibration of ``toolpoint library``: are its recommended points stable for the real tool, and do its
probabilities of stability mean what they say?

For each campaign folder given (``campaign synth`` + ``run`` + ``learn``, any seed, size and ``--mfs``), new
tools (D, L) are drawn over the campaign's range — a share of them up to 10 % outside it — with a cut each
(teeth, immersion, milling, material preset), and ``library`` is run on them. The truth is what the campaign
hides from the pipeline: its true spindle–holder model (``truth/spindle_holder.toml``) and the joint law
(:func:`toolpoint.campaign.synth.truth_joint`), through the same zero-order lobes on the same speed grid. The
cutting coefficients of the truth are drawn from the library's stated uncertainty (``--true-cutting drawn``,
the default: a shop's K_t is not the preset's) or are the presets' (``nominal``, the check of issue 21).

Printed per campaign and over all:

* recommended points above the true limit (true limit = min over the speed tolerance ±1 %; one shop's K_t, K_r
  per tool), with the number their own P(stable) expects, Σ(1 − P); and the ratio recommended depth / true limit
  (median, min, max; not where the tool has no limit at that speed or the depth is the flute length);
* the reliability table: predicted P(stable) in bins against the observed fraction truly stable over every
  (tool, speed, depth) point of the probability maps, with the Brier score; and among points with P ≥ 0.95 the
  share truly stable. With drawn cutting coefficients the observed fraction of a point is its share of
  ``--truth-draws`` shops (16 draws of K_t, K_r per tool): one draw per tool would make a table of millions of
  points rest on a few hundred draws of the dominant source — bins then move by ±4 points from one ``--seed``
  to the next, which is noise, not calibration;
* CPU per tool.

Usage::

    python benchmarks/bench_calibration.py CAMP1 [CAMP2 ...] [--tools 30] [--seed 0] [--truth-draws 16]
        [--true-cutting drawn|nominal] [--library CSV] [--figure docs/img/calibration.png]

Each CAMP holds ``results/models`` (``campaign run CAMP --out CAMP/results``, ``campaign learn CAMP/results``).
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import tempfile
import time
import zlib
from pathlib import Path

import numpy as np

from toolpoint.campaign.config import load_campaign
from toolpoint.campaign.synth import truth_joint
from toolpoint.dynamics.assembly import load_assembly
from toolpoint.dynamics.model import ToolPointModel
from toolpoint.dynamics.subassembly import Subassembly
from toolpoint.recommend.engine import robust_min
from toolpoint.recommend.library import read_library, tool_file_stem
from toolpoint.recommend.materials import PRESETS, UNCERTAINTY
from toolpoint.recommend.run import run_library
from toolpoint.stability import CuttingConditions
from toolpoint.stability.zoa_batch import zoa_limits

HEADER = ("id,diameter_mm,overhang_mm,teeth,holder,material,radial_immersion,milling,rpm_min,rpm_max,"
          "tangential_coeff_sigma_pct,radial_ratio_sigma_pct\n")
BINS = np.array([0.0, 0.05, 0.2, 0.4, 0.6, 0.8, 0.95, 1.0001])


def tools(camp: Path, n: int, seed: int, sigma_pct=None) -> list[dict]:
    """n tools over the campaign's (D, L) range, 20 % of them up to 10 % outside it, with a cut each."""
    import csv

    with open(camp / "measurements.csv", newline="") as fh:
        rows = list(csv.DictReader(fh))
    D = np.array([float(r["diameter_mm"]) for r in rows])
    L = np.array([float(r["overhang_mm"]) for r in rows])
    rng = np.random.default_rng(seed)
    out = []
    for i in range(n):
        ext = 0.1 if rng.random() < 0.2 else 0.0
        d = rng.uniform(D.min() - ext * np.ptp(D), D.max() + ext * np.ptp(D))
        ll = rng.uniform(L.min() - ext * np.ptp(L), L.max() + ext * np.ptp(L))
        mat = str(rng.choice(list(PRESETS)))
        lo = float(rng.choice([2000, 3000, 4000]))
        out.append(dict(id=f"B{i:03d}", diameter_mm=round(float(d), 1), overhang_mm=round(float(ll), 1),
                        teeth=int(rng.choice([2, 3, 4])), holder="ER40", material=mat,
                        radial_immersion=float(rng.choice([0.1, 0.25, 0.5, 1.0])),
                        milling=str(rng.choice(["down", "up"])), rpm_min=lo, rpm_max=lo * float(rng.choice([4, 6])),
                        kt=PRESETS[mat][0], kr=PRESETS[mat][1],
                        sigma=UNCERTAINTY[mat] if sigma_pct is None else tuple(np.log1p(np.array(sigma_pct) / 100)),
                        tangential_coeff_sigma_pct="" if sigma_pct is None else sigma_pct[0],
                        radial_ratio_sigma_pct="" if sigma_pct is None else sigma_pct[1]))
    return out


def library_tools(path: Path) -> list[dict]:
    """The tools of a library CSV (e.g. ``examples/tool_library.csv``) as :func:`tools` gives them."""
    good, _ = read_library(path)
    return [dict(id=t.id, diameter_mm=t.diameter_mm, overhang_mm=t.overhang_mm, teeth=t.cutting.teeth,
                 holder=t.holder, material=t.material, radial_immersion=t.cutting.radial_immersion,
                 milling=t.cutting.milling, rpm_min=t.rpm_min, rpm_max=t.rpm_max, kt=t.cutting.tangential_coeff,
                 kr=t.cutting.radial_ratio, sigma=t.cutting_sigma_ln) for t in good]


def truth_limits(camp: Path, tool: dict, rpm: np.ndarray, f: np.ndarray, kt_factor, kr) -> list:
    """The true limits (m) on the speed grid: true subassembly, truth-law joint, per pair of the given K_t factors
    and K_r values (one limit array per pair)."""
    c = load_campaign(camp)
    a = load_assembly(camp / "truth" / "spindle_holder.toml", require_tool=False)
    sub = Subassembly.from_assembly(a, f)
    tp = ToolPointModel(c.family.tool(tool["diameter_mm"], tool["overhang_mm"]), sub, f)
    h = tp.tool_point(truth_joint(tool["diameter_mm"], tool["overhang_mm"]))
    return [zoa_limits(f, h, CuttingConditions(tool["teeth"], tool["kt"] * kf, k, tool["radial_immersion"],
                                               tool["milling"]), rpm)
            for kf, k in zip(np.atleast_1d(kt_factor), np.atleast_1d(kr))]


def campaign(camp: Path, n: int, seed: int, true_cutting: str, workers: int, library: Path | None = None,
             sigma_pct=None, draws: int = 1) -> dict:
    tmp = Path(tempfile.mkdtemp(prefix="bench_cal_"))
    if library is None:
        ts = tools(camp, n, seed, sigma_pct)
        lib = tmp / "lib.csv"
        lib.write_text(HEADER + "".join(",".join(str(t[k]) for k in HEADER.strip().split(",")) + "\n" for t in ts))
    else:
        ts, lib = library_tools(library), library
    t0 = time.perf_counter()
    r = run_library(lib, camp, camp / "results" / "models", tmp / "out", workers=workers, progress=False)
    wall = time.perf_counter() - t0
    # each campaign its own shops (truth draws): the tools drawn are the same in every campaign of a --seed
    rng = np.random.default_rng([seed, 1000, zlib.crc32(camp.name.encode())])
    above, ratio, pred, obs, cpu, kinds, claimed = [], [], [], [], [], [], []
    for t in ts:
        stem = tool_file_stem(t["id"])
        js = json.loads((tmp / "out" / "tools" / f"{stem}.json").read_text())
        arr = np.load(tmp / "out" / "tools" / f"{stem}.npz")
        rpm, f = arr["rpm"], arr["freq_hz"]
        s_kt, s_kr = t["sigma"]
        z = rng.standard_normal((draws, 2)) if true_cutting == "drawn" else np.zeros((1, 2))
        trues = [1e3 * v for v in truth_limits(camp, t, rpm, f, np.exp(s_kt * z[:, 0]),
                                               t["kr"] * np.exp(s_kr * z[:, 1]))]
        true = trues[0]  # the recommended point is judged against one shop's cutting coefficients
        robust_true = robust_min(rpm, true, js["rpm_tolerance"])
        best = js["points"][0]
        j = int(np.argmin(np.abs(rpm - best["rpm"])))
        above.append(best["depth_mm"] > robust_true[j])
        claimed.append(1.0 - best["p_stable"])  # the chance the library itself gives the point of being above
        # no ratio where the tool is stable at every depth at that speed (no true limit) or the depth is the flute
        # length (the limit lies deeper than the tool can cut)
        ratio.append(best["depth_mm"] / robust_true[j] if np.isfinite(robust_true[j])
                     and not best.get("flute_limited") else np.nan)
        kinds.append(best["kind"])
        depth = arr["depth_mm"]
        cap = js["cap_mm"]
        p = arr["p_stable"].astype(float) / 100  # (D, G)
        ok = depth[:, None] < cap  # above the cap the map says nothing
        # share of the shops (truth draws of K_t, K_r) where the point is stable: the same expectation as one draw
        # per tool, without the noise of a few hundred draws deciding a table of millions of points
        stable = np.mean([depth[:, None] < tr[None, :] for tr in trues], axis=0)
        pred.append(p[np.broadcast_to(ok, p.shape)])
        obs.append(stable[np.broadcast_to(ok, p.shape)])
        cpu.append(js["cpu_seconds"])
        if above[-1]:
            print(f"  ABOVE: {t['id']} D {t['diameter_mm']} L {t['overhang_mm']} {t['material']} {best['kind']} "
                  f"{best['rpm']:.0f} rpm {best['depth_mm']:.3g} mm (p {best['p_stable']:.2f}) vs true "
                  f"{robust_true[j]:.3g} mm")
        elif ratio[-1] < 0.2:  # uselessly conservative: say which tool
            print(f"  LOW: {t['id']} D {t['diameter_mm']} L {t['overhang_mm']} {t['material']} {best['kind']} "
                  f"{best['rpm']:.0f} rpm {best['depth_mm']:.3g} mm (p {best['p_stable']:.2f}) vs true "
                  f"{robust_true[j]:.3g} mm; {js.get('note', '')}")
    return dict(above=np.array(above), claimed=np.array(claimed), ratio=np.array(ratio), pred=np.concatenate(pred),
                obs=np.concatenate(obs),
                cpu=np.array(cpu), wall=wall, ok=r.ok, kinds=kinds)


def reliability(pred, obs) -> list[str]:
    lines = [f"{'P(stable) bin':<16}{'points':>9}{'mean P':>9}{'observed':>10}{'diff':>8}"]
    for lo, hi in zip(BINS[:-1], BINS[1:]):
        m = (pred >= lo) & (pred < hi)
        if m.sum():
            lines.append(f"[{lo:.2f}, {min(hi, 1):.2f}){'':<3}{m.sum():>9}{pred[m].mean():>9.3f}{obs[m].mean():>10.3f}"
                         f"{100 * (obs[m].mean() - pred[m].mean()):>+7.1f}")
    hi = pred >= 0.95
    # obs is the share of truth draws where the point is stable: E(p − 1{stable})² = p² − 2 p obs + obs
    lines.append(f"Brier score {np.mean(pred ** 2 - 2 * pred * obs + obs):.4f}; points with P ≥ 0.95: {hi.sum()}, "
                 f"truly stable "
                 f"{100 * obs[hi].mean():.1f} %")
    return lines


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("campaigns", nargs="+", type=Path)
    ap.add_argument("--tools", type=int, default=30)
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--true-cutting", choices=("drawn", "nominal"), default="drawn")
    ap.add_argument("--truth-draws", type=int, default=16,
                    help="shops per tool: draws of the true K_t, K_r (drawn truth) the observed fraction averages over")
    ap.add_argument("--figure", type=Path)
    ap.add_argument("--library", type=Path, help="a tool library CSV instead of drawn tools")
    ap.add_argument("--cutting-sigma-pct", help="KT,KR: the drawn tools' cutting-coefficient uncertainty, %% "
                    "(default: the presets')")
    a = ap.parse_args()
    print(f"{time.strftime('%Y-%m-%d %H:%M UTC', time.gmtime())}, {platform.processor() or platform.machine()}, "
          f"{os.cpu_count()} cores; truth's cutting coefficients: {a.true_cutting}")
    allp, allo, allr, alla, allc = [], [], [], [], []
    for camp in a.campaigns:
        meta = json.loads((camp / "results" / "models" / "metrics.json").read_text())
        sig = None if a.cutting_sigma_pct is None else [float(v) for v in a.cutting_sigma_pct.split(",")]
        r = campaign(camp, a.tools, a.seed, a.true_cutting, a.workers, a.library, sig, a.truth_draws)
        print(f"{camp}: {meta['n_ok']} tools, mfs {meta['settings']['mfs']}: {r['ok']} recommendations, "
              f"{int(r['above'].sum())} above the true limit (expected from their P(stable): "
              f"{r['claimed'].sum():.1f}); depth/true limit median {np.nanmedian(r['ratio']):.2f} "
              f"(min {np.nanmin(r['ratio']):.2f}, max {np.nanmax(r['ratio']):.2f}; "
              f"{int(np.isnan(r['ratio']).sum())} without a true limit or at the flute length); kinds "
              f"{ {k: r['kinds'].count(k) for k in set(r['kinds'])} }; CPU per tool mean {r['cpu'].mean():.2f} s")
        for line in reliability(r["pred"], r["obs"]):
            print("   " + line)
        allp.append(r["pred"]), allo.append(r["obs"]), allr.append(r["ratio"]), alla.append(r["above"])
        allc.append(r["claimed"])
    p, o, ratio, above, claimed = map(np.concatenate, (allp, allo, allr, alla, allc))
    print(f"all: {int(above.sum())} of {above.size} recommended points above the true limit (expected from their "
          f"P(stable): {claimed.sum():.1f}); depth/true limit median "
          f"{np.nanmedian(ratio):.2f} (min {np.nanmin(ratio):.2f}, max {np.nanmax(ratio):.2f}; "
          f"{int(np.isnan(ratio).sum())} without a true limit or at the flute length)")
    for line in reliability(p, o):
        print("   " + line)
    if a.figure:
        import matplotlib

        matplotlib.use("Agg")
        import matplotlib.pyplot as plt

        fig, ax = plt.subplots(1, 2, figsize=(9, 4))
        mids, fr, cnt = [], [], []
        for lo, hi in zip(BINS[:-1], BINS[1:]):
            m = (p >= lo) & (p < hi)
            if m.sum():
                mids.append(p[m].mean()), fr.append(o[m].mean()), cnt.append(m.sum())
        ax[0].plot([0, 1], [0, 1], color="0.6", lw=1)
        ax[0].plot(mids, fr, "o-", color="#0072B2")
        ax[0].set(xlabel="predicted P(stable)", ylabel="observed fraction stable", title="reliability")
        ax[1].hist(ratio[np.isfinite(ratio)], bins=20, color="#E69F00")
        ax[1].axvline(1.0, color="k", lw=1)
        ax[1].set(xlabel="recommended depth / true limit", ylabel="tools", title="recommended points")
        fig.tight_layout()
        fig.savefig(a.figure, dpi=110)


if __name__ == "__main__":
    main()
