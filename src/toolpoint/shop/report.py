"""Files of ``toolpoint update``: lobes, P(stable) map, parameters, next cut, figure and one HTML page.

In the output folder (written atomically, all or none of each file):

* ``lobes.csv`` — ``rpm, p05_mm, p50_mm, p95_mm, prior_p05_mm, prior_p50_mm, prior_p95_mm, p05_level,
  p95_level`` (the lobe samples' quantile levels the posterior's 5 % and 95 % lines were read at, widened for the
  few references the band rests on: :func:`~toolpoint.shop.update._band_levels`);
* ``p_stable.csv`` — first row ``depth_mm\\rpm`` and the speeds, then one row per depth (mm) of P(stable);
* ``parameters.csv`` — ``name, unit, prior_p05, prior_p50, prior_p95, post_p05, post_p50, post_p95``
  (K_t in N/mm²);
* ``update.json`` — recommended point, next test cut (rule, rpm, depth_mm, duration_s, P(chatter)), the test
  cuts (each with its record and part, where the table named one), ``precursor`` (a noisy shop's false chatter
  the likelihood allowed for, and the stable cut whose ring said the shop is noisy; null in a quiet shop),
  ``noisy_pocket`` (how late that shop was taken to hear chatter at a pocket's top; null in a quiet shop), the
  forward model and sampler diagnostics (method, ESS per tempering step, acceptance, the lobe samples' ESS by
  their own SDM limits, CPU s);
* ``lobes.png`` — prior and posterior bands, the P(stable) map, the test cuts, the next cut;
* ``report.html`` — one self-contained page (figure embedded) of all of the above.
"""

from __future__ import annotations

import base64
import csv
import html
import io
import json
import math
from pathlib import Path

import numpy as np

from ..io.atomic import atomic_open, atomic_path
from .update import Posterior

__all__ = ["write_update", "plot_update"]

_UNITS = {"hz": ("Hz", 1.0), "n_m": ("N/m", 1.0), "zeta": ("-", 1.0), "kt_n_m2": ("N/mm²", 1e-6), "kr": ("-", 1.0),
          "_ln": ("ln", 1.0)}


def _unit(name):
    for suffix, (u, s) in _UNITS.items():
        if name.endswith(suffix) or name.startswith(suffix):
            return u, s
    return "-", 1.0


def plot_update(post: Posterior):
    """Figure: P(stable) map, prior band (grey), posterior 5/50/95 % (blue), test cuts, next cut — over the whole
    speed range (left) and near the cuts, the recommended speed and the next cut (right), where a few % of speed
    and depth decide and the full range's markers sit on each other."""
    from matplotlib.figure import Figure

    fig = Figure(figsize=(12, 5))
    full, near = fig.subplots(1, 2, gridspec_kw={"width_ratios": [3, 2]})
    mm = 1e3
    nc, rc = post.next_cut, post.recommended
    for ax in (full, near):
        mesh = ax.pcolormesh(post.rpm, post.depth_m * mm, post.p_stable, cmap="RdYlGn", vmin=0, vmax=1,
                             shading="nearest", alpha=0.5, rasterized=True)
        ax.fill_between(post.rpm, post.prior_limit_q_m[0] * mm, post.prior_limit_q_m[2] * mm, color="grey",
                        alpha=0.25, label="prior 5–95 %")
        ax.fill_between(post.rpm, post.limit_q_m[0] * mm, post.limit_q_m[2] * mm, color="tab:blue", alpha=0.3,
                        label="posterior 5–95 %")
        ax.plot(post.rpm, post.limit_q_m[1] * mm, color="tab:blue", lw=1.5, label="posterior median")
        for stable, mark, color, label in ((True, "o", "green", "stable cut"), (False, "x", "red", "chatter cut")):
            cs = [c for c in post.cuts if c.stable == stable]
            if cs:
                ax.plot([c.rpm for c in cs], [c.depth_m * mm for c in cs], mark, color=color, ms=7, mew=2,
                        ls="none", label=label, zorder=5)
        ax.plot(nc["rpm"], nc["depth_m"] * mm, "D", mfc="none", mec="k", ms=9, label=f"next cut ({nc['rule']})",
                zorder=4)
        ax.plot(rc["rpm"], rc["depth_m"] * mm, "*", color="gold", mec="k", ms=13,
                label=f"recommended (P stable {rc['p_stable']:.2f})", zorder=4)
        ax.set_xlabel("spindle speed, rpm")
    fig.colorbar(mesh, ax=near, label="P(stable)")
    full.set_ylim(0, post.depth_m[-1] * mm)
    full.set_ylabel("axial depth, mm")
    full.set_title(f"{post.prior.name}: {len(post.cuts)} test cuts ({post.method}, {post.forward})", fontsize=10)
    full.legend(fontsize=7, loc="upper left")
    # near: the speeds of the cuts, the recommendation and the next cut, ±4 % around them; depths to 1.3 × the
    # deepest of the cuts and the band there
    r = np.array([c.rpm for c in post.cuts] + [nc["rpm"], rc["rpm"]])
    lo, hi = 0.96 * r.min(), 1.04 * r.max()
    inside = (post.rpm >= lo) & (post.rpm <= hi)
    top = max([c.depth_m for c in post.cuts] + [nc["depth_m"], rc["depth_m"]]
              + list(post.limit_q_m[2][inside]))
    near.set_xlim(lo, hi)
    near.set_ylim(0, min(1.3 * top, post.depth_m[-1]) * mm)
    near.set_title("near the cuts and the recommendation", fontsize=10)
    fig.tight_layout()
    return fig


def _doc(post: Posterior) -> dict:
    rc, nc = post.recommended, post.next_cut
    return {
        "prior": post.prior.name,
        "recommended": {"rpm": round(rc["rpm"], 1), "depth_mm": round(1e3 * rc["depth_m"], 4),
                        "p_stable": round(rc["p_stable"], 3),
                        "limit_p05_mm": round(1e3 * rc["limit_p05_m"], 4),
                        "limit_p50_mm": round(1e3 * rc["limit_p50_m"], 4),
                        "limit_p95_mm": round(1e3 * rc["limit_p95_m"], 4),
                        # forward="sdm": held-out posterior samples' own SDM 5 % limit here (the depth: the lower)
                        "own_sdm_p05_mm": (None if rc["own_sdm_p05_m"] is None
                                           else round(1e3 * rc["own_sdm_p05_m"], 4)),
                        "own_sdm_held_out": rc["own_sdm_held_out"],
                        # cut_speed_margin: a speed already cut, within the margin of the most productive one
                        "at_cut_speed": rc.get("at_cut_speed", False),
                        # the band's samples weighted by their own SDM limits at the cut speeds (update's own_sdm)
                        "lobes_own_sdm": post.own_sdm_ess is not None},
        "next_cut": {**{k: v for k, v in nc.items() if k != "depth_m"}, "depth_mm": round(1e3 * nc["depth_m"], 4)},
        "cuts": [{"rpm": c.rpm, "depth_mm": round(1e3 * c.depth_m, 6), "result": "stable" if c.stable else "chatter",
                  "chatter_hz": c.chatter_hz, "duration_s": c.duration_s, "growth_per_s": c.growth_per_s,
                  "growth_past_limit_ln": None if x is None else round(x, 4),
                  "ring_per_s": c.ring_per_s, "ring_hz": c.ring_hz,
                  "ring_under_limit_ln": None if xr is None else round(xr, 4),
                  "record": c.record,
                  "warnings": [f"line {c.line}: {w}" if c.line else w for w in c.warnings]}
                 for c, x, xr in zip(post.cuts, post.growth_past_limit or (None,) * len(post.cuts),
                                     post.ring_under_limit or (None,) * len(post.cuts))],
        "precursor": precursor_doc(post),
        "noisy_pocket": noisy_pocket_doc(post),
        "sampler": {"method": post.method, "forward": post.forward, "samples": int(post.z.shape[0]),
                    "ess": [round(e, 1) for e in post.ess],
                    "acceptance": None if not np.isfinite(post.acceptance) else round(post.acceptance, 3),
                    # the lobe samples' weights by their own SDM limits at the cut speeds (update's own_sdm)
                    "own_sdm_ess": None if post.own_sdm_ess is None else round(post.own_sdm_ess, 1),
                    # below 1: those weights left too few effective samples and were tempered (update.OWN_MIN_ESS)
                    "own_sdm_power": None if post.own_sdm_power is None else round(post.own_sdm_power, 3),
                    # the speeds where the lobe samples' own SDM limits replaced the references' ratio (own_pocket)
                    "own_pocket_rpm": [round(r, 1) for r in post.own_pocket_rpm],
                    "lobe_samples": None if post.lobe_z is None else int(post.lobe_z.shape[0]),
                    "cpu_s": round(post.cpu_s, 2)},
    }


def write_update(post: Posterior, out_dir) -> list:
    """Write the files listed in the module docstring into ``out_dir``; returns their paths."""
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    mm = 1e3
    paths = []
    with atomic_open(out / "lobes.csv", newline="") as fh:
        w = csv.writer(fh)
        w.writerow(["rpm", "p05_mm", "p50_mm", "p95_mm", "prior_p05_mm", "prior_p50_mm", "prior_p95_mm",
                    "p05_level", "p95_level"])
        lv = post.levels
        for g in range(post.rpm.size):
            w.writerow([f"{post.rpm[g]:.6g}"] + [f"{mm * v:.6g}" for v in post.limit_q_m[:, g]]
                       + [f"{mm * v:.6g}" for v in post.prior_limit_q_m[:, g]]
                       + [f"{lv[0, g]:.4f}", f"{lv[1, g]:.4f}"])
    paths.append(out / "lobes.csv")
    with atomic_open(out / "p_stable.csv", newline="") as fh:
        w = csv.writer(fh)
        w.writerow(["depth_mm\\rpm"] + [f"{r:.6g}" for r in post.rpm])
        for d in range(post.depth_m.size):
            w.writerow([f"{mm * post.depth_m[d]:.6g}"] + [f"{p:.3f}" for p in post.p_stable[d]])
    paths.append(out / "p_stable.csv")
    rows = []
    with atomic_open(out / "parameters.csv", newline="") as fh:
        w = csv.writer(fh)
        w.writerow(["name", "unit", "prior_p05", "prior_p50", "prior_p95", "post_p05", "post_p50", "post_p95"])
        for name, (pq, qq) in post.parameter_quantiles().items():
            unit, s = _unit(name)
            row = [name, unit] + [f"{s * v:.5g}" for v in (*pq, *qq)]
            rows.append(row)
            w.writerow(row)
    paths.append(out / "parameters.csv")
    doc = _doc(post)
    with atomic_open(out / "update.json") as fh:
        json.dump(doc, fh, indent=2)
    paths.append(out / "update.json")
    fig = plot_update(post)
    buf = io.BytesIO()
    fig.savefig(buf, format="png", dpi=110)
    png = buf.getvalue()
    with atomic_path(out / "lobes.png") as tmp:
        Path(tmp).write_bytes(png)
    paths.append(out / "lobes.png")
    with atomic_open(out / "report.html", encoding="utf-8") as fh:
        fh.write(_html(post, doc, rows, png))
    paths.append(out / "report.html")
    return paths


def pocket_note(rc: dict) -> str | None:
    """One line where the band's 5 % limit at the recommended speed lies > 5 % above the posterior samples' own SDM 5 %
    limit there (``rc``: the report's ``recommended``, mm), else None. The band's SDM correction rests on a few
    reference samples' ratio, and at a pocket's peak that ratio varies from sample to sample: on the tap prior of the
    README (0 cuts, 13166 rpm) 26 % of 150 truths drawn from the prior lay below the band's 5 % line and 4 % below the
    recommended depth (docs/design/shop.md, *Limits*). Where the band's samples were weighted by their own SDM limits
    at the cut speeds (``rc["lobes_own_sdm"]``, :func:`~toolpoint.shop.update.update`'s ``own_sdm``) and the held-out
    samples only by the cuts at the recommended speed, the line says that instead: the gap is then the two samples'
    difference, not the references'."""
    band, own = rc.get("limit_p05_mm"), rc.get("own_sdm_p05_mm")
    if band is None or own is None or not band > 1.05 * own:
        return None
    head = (f"at {rc['rpm']:.0f} rpm the band's 5 % limit ({band:.3f} mm) lies {100 * (band / own - 1):.0f} % above "
            f"the held-out posterior samples' own SDM 5 % limit ({own:.3f} mm): ")
    if rc.get("lobes_own_sdm"):
        return head + ("the band's samples were weighted by their own SDM limits at the cut speeds, the held-out ones "
                       "only by the cuts at this speed, if any; the recommended depth is the lower, the more cautious")
    return head + ("the band is optimistic at this pocket (its SDM correction rests on a few reference samples); the "
                   "recommended depth is the lower")


def away_note(cuts) -> str:
    """One line on how far the band can be trusted: ``cuts`` are the report's rows (``rpm`` keys)."""
    rpm = [c["rpm"] for c in cuts]
    # measured on 180 campaigns without a stop (nine sets of 20 truths of four tools, 1–6 cuts, 2026-12-01/02;
    # docs/design/shop.md, *The recommended depth's check weighs the cuts at its speed*): the band is calibrated on
    # average away from the cuts on some tools, not on all, and a tool in the prior's tail falls outside it over a
    # range; the recommended depth's 5 % held on three tools, not on EM12-60 (0.10 ± 0.02 of its updates; 140 of
    # the 180 truths ran before the held-out samples were weighted by the cuts at the recommended speed: the same cuts).
    # Since the per-sample ratio fit: EM12-60 30 of 600 updates on 100 fresh truths (0.050 ± 0.011), EM16-50 2,
    # EM28-80 5 and the two-mode case 2 of 120 (2026-12-02; docs/design/shop.md, *EM12-60's recommended depth on 40
    # more fresh truths*). On fresh truths 200–219 of six tools (2026-12-04, *Where the targets stand on fresh truths
    # 200–219*): 1 of 120 (the two-mode case) to 10 of 120 (EM28-80, 8 %; EM12-60 8 of 120), 26 of 600 in all — the
    # note said 2–5 % until then, which those truths exceeded on two tools
    return (f"the band is tested by your cuts at {min(rpm):.0f}–{max(rpm):.0f} rpm; away from those speeds it rests "
            "on the model alone — in virtual campaigns it held the true limit at 85–96 % of those speeds on average "
            "(it claims 90 %), yet at under 90 % of all speeds for 15–40 % of the tools, and the true limit lay under "
            "the recommended depth after 1–8 % of the updates by tool on fresh truths (it claims 5 %; "
            "docs/design/shop.md): make a test cut at a speed before trusting the band there")


def _growth_cell(c) -> str:
    """A cut's growth rate, 1/s, with how far past the limit (ln) the SDM's growth curves read it, where they did; a
    stable cut's ring, with how close under the limit (ln) the SDM's decay curves said it was at least."""
    if c.get("ring_per_s") is not None:
        xr = c.get("ring_under_limit_ln")
        return f"ring {c['ring_per_s']:.3g}" + ("" if xr is None else f" (x ≥ {xr:.3f})")
    if c["growth_per_s"] is None:
        return ""
    x = c.get("growth_past_limit_ln")
    return format(c["growth_per_s"], ".3g") + ("" if x is None else f" (x {x:.3f})")


def _noisy_evidence(post: Posterior) -> dict:
    c = post.cuts[post.noisy_evidence]
    return {"line": c.line, "cut": post.noisy_evidence + 1, "ring_per_s": c.ring_per_s, "ring_hz": c.ring_hz}


def precursor_doc(post: Posterior) -> dict | None:
    """The noisy shop's false chatter the likelihood used (``update.json``'s ``precursor``), or None (a quiet shop,
    or left out)."""
    if post.precursor is None:
        return None
    pi, reach, sd = post.precursor
    return {"share": pi, "reach_ln": reach, "sd_ln": sd, "evidence": _noisy_evidence(post)}


def noisy_pocket_doc(post: Posterior) -> dict | None:
    """The noisy shop's late chatter at a pocket's top the likelihood used (``update.json``'s ``noisy_pocket``: ν,
    :data:`~toolpoint.shop.update.NOISY_POCKET`), or None (a quiet shop, or left out)."""
    if post.noisy_pocket is None:
        return None
    return {"per_ln_pocket_height": post.noisy_pocket, "evidence": _noisy_evidence(post)}


def noisy_pocket_note(npd: dict) -> str:
    """One line on the noisy shop's late chatter at a pocket's top (the CLI's summary and the report say the same)."""
    nu = npd["per_ln_pocket_height"]
    return (f"chatter may be heard late at a pocket's top, where the tooth passing rings the mode and its line hides "
            f"chatter the noise has spread: each label is taken as heard {nu:g} × ln(the limit there / the lobes' "
            f"floor) above the limit (~{100 * (math.exp(nu * math.log(75)) - 1):.0f} % at a pocket 75 × its floor); "
            "labels checked on the surface leave it out (--no-precursor)")


def precursor_note(pc: dict) -> str:
    """One line on the noisy shop's false chatter (the CLI's summary and the report say the same)."""
    ev = pc["evidence"]
    where = f"line {ev['line']}" if ev["line"] is not None else f"cut {ev['cut']}"
    return (f"the stable cut of {where} rings ({ev['ring_per_s']:.3g} /s at {ev['ring_hz']:.1f} Hz): the cutting "
            f"noise drives the tool's modes, so a chatter label without a growth reading is taken as possibly a "
            f"stable cut ~{100 * (1 - math.exp(-pc['reach_ln'])):.0f} % or less under the limit, ringing "
            f"(P ≤ {pc['share']:g}); a cut that chatters strongly, or the surface, settles such a label")


def _html(post, doc, rows, png) -> str:
    e = html.escape
    rc, nc = doc["recommended"], doc["next_cut"]
    cut_rows = "".join(f"<tr><td>{c['rpm']:.0f}</td><td>{c['depth_mm']:.3f}</td><td>{c['result']}</td>"
                       f"<td>{'' if c['chatter_hz'] is None else format(c['chatter_hz'], '.1f')}</td>"
                       f"<td>{_growth_cell(c)}</td>"
                       f"<td>{e(c['record'] or '')}</td></tr>" for c in doc["cuts"])
    par_rows = "".join("<tr>" + "".join(f"<td>{e(str(v))}</td>" for v in r) + "</tr>" for r in rows)
    s = doc["sampler"]
    caveat = f"<p><b>Note</b>: {e(away_note(doc['cuts']))}</p>" if doc["cuts"] else ""
    if (pocket := pocket_note(rc)) is not None:
        caveat += f"<p><b>Note</b>: {e(pocket)}</p>"
    if doc.get("precursor") is not None and any(c["result"] == "chatter" and c["growth_per_s"] is None
                                                for c in doc["cuts"]):
        caveat += f"<p><b>Noisy shop</b>: {e(precursor_note(doc['precursor']))}.</p>"
    if doc.get("noisy_pocket") is not None:
        caveat += f"<p><b>Noisy shop</b>: {e(noisy_pocket_note(doc['noisy_pocket']))}.</p>"
    warns = [w for c in doc["cuts"] for w in c["warnings"]]
    if warns:  # what the records' analysis could not rule out: the labels above rest on it
        caveat += "<p><b>Warnings from the records</b>:</p><ul>" + "".join(f"<li>{e(w)}</li>" for w in warns) + "</ul>"
    return (
        "<!doctype html><html><head><meta charset='utf-8'><title>toolpoint update</title><style>"
        "body{font-family:sans-serif;max-width:960px;margin:auto}table{border-collapse:collapse}"
        "td,th{border:1px solid #ccc;padding:2px 6px;text-align:right}</style></head><body>"
        f"<h1>Test cuts → lobes: {e(post.prior.name)}</h1>"
        f"<p><b>Recommended</b>: {rc['rpm']:.0f} rpm at {rc['depth_mm']:.3f} mm (P(stable) {rc['p_stable']:.2f}; "
        + (f"the band's 5 % limit {rc['limit_p05_mm']:.3f} mm, lowered by posterior samples' own SDM limits; "
           if rc["limit_p05_mm"] > rc["depth_mm"] else "") +
        f"median limit {rc['limit_p50_mm']:.3f} mm).<br><b>Next test cut</b> ({e(nc['rule'])}: "
        f"{e(nc['description'])}): {nc['rpm']:.0f} rpm at {nc['depth_mm']:.3f} mm"
        + (f" for at least {nc['duration_s']:.1f} s ({nc['revolutions']} revolutions"
           + (": chatter a few % past the limit grows slowly at this speed (κ ≤ "
              f"{nc['growth_rate_p25_per_s']:.0f} /s for a quarter of the samples), and a shorter cut would sound "
              "stable" if nc.get("duration_by_growth") else "")
           + ")" if nc.get("duration_s") is not None else "")
        + f", P(chatter) {nc['p_chatter']:.2f}.</p>{caveat}"
        f"<img alt='lobes' style='max-width:100%' src='data:image/png;base64,{base64.b64encode(png).decode()}'>"
        "<h2>Test cuts</h2><table><tr><th>rpm</th><th>depth mm</th><th>result</th><th>chatter Hz</th>"
        "<th>growth or ring 1/s (x: ln from the limit)</th><th>record</th></tr>"
        f"{cut_rows}</table>"
        "<h2>Parameters (5 / 50 / 95 %)</h2><table><tr><th>name</th><th>unit</th><th>prior 5</th><th>prior 50</th>"
        f"<th>prior 95</th><th>post 5</th><th>post 50</th><th>post 95</th></tr>{par_rows}</table>"
        f"<p>Forward model: {e(s['forward'])}. Sampler: {e(s['method'])}, {s['samples']} samples, ESS per step "
        f"{e(str(s['ess']))}, acceptance "
        f"{s['acceptance']}"
        + (f"; the {s['lobe_samples']} lobe samples weighted by their own SDM limits at the cut speeds, ESS "
           f"{s['own_sdm_ess']}" if s.get("own_sdm_ess") is not None else "")
        + (f" (the weights tempered to the power {s['own_sdm_power']}: in full they left too few effective samples, "
           "so the band lies between the references' SDM correction and the samples' own)"
           if s.get("own_sdm_power") is not None and s["own_sdm_power"] < 1 else "")
        + (f"; at {', '.join(f'{r:.0f}' for r in s['own_pocket_rpm'])} rpm the lobe samples' own SDM limits, between "
           "them linearly" if s.get("own_pocket_rpm") else "")
        + f", {s['cpu_s']} s CPU. Files: lobes.csv, p_stable.csv, parameters.csv, update.json.</p>"
        "</body></html>")
