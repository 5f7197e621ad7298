"""``library``: recommend speeds and depths for every tool of a library, resumably.

Rows go to ``OUT/recommendations.csv`` as tools finish (flushed and synced),
each after the tool's files ``OUT/tools/<stem>.npz`` (arrays) and
``OUT/tools/<stem>.json`` (summary, with the id) were written atomically — ``<stem>`` is
:func:`~toolpoint.recommend.library.tool_file_stem` of the id, never the id as it is; a killed run loses at
most the tools being computed. A re-run keeps the ``ok`` rows whose files
exist, and computes the rest (bad rows are checked again). Tools run in a local
process pool or on an existing Dask cluster, like ``campaign run``.

``recommendations.csv`` columns (:data:`COLUMNS`; depths mm, speeds rpm, joint SI):
``id, status`` (``ok``/``failed``), ``holder, diameter_mm, overhang_mm, teeth, material, cutting_source,
outside_range`` (δ, range widths), ``<p>_p05, <p>_p50, <p>_p95`` for kt, ct, kr, cr, ``rpm, kind``
(``pocket``/``minimum``/``edge``), ``limit_nominal_mm, limit_p50_mm, limit_p05_mm, depth_mm`` (recommended),
(``minimum`` where no pocket is worth its uncertainty (the depth stable at every speed)),
``p_stable`` (at the recommended point, for any speed within the tolerance), ``dominant_uncertainty`` (the input
whose uncertainty makes most of the band there: joint, cutting K_t, cutting K_r, subassembly),
``min_limit_p05_mm`` (stable at every speed with 95 %),
``notes, error``.
"""

from __future__ import annotations

import csv
import io
import json
import os
import sys
import time
import warnings
import zlib
from pathlib import Path

import numpy as np

from ..campaign.config import load_campaign
from ..campaign.run import BatchResult, execute
from ..errors import ExtrapolationWarning, InputError
from ..identification.params import PARAMS
from ..io.atomic import atomic_open, atomic_path
from ..io.table import csv_safe, csv_unsafe, read_table
from .engine import ToolJob, evaluate_tool
from .library import read_library, tool_file_stem
from ..campaign.distribution import JointPredictor

__all__ = ["COLUMNS", "FILE_NAME", "run_library"]

FILE_NAME = "recommendations.csv"
COLUMNS = (["id", "status", "holder", "diameter_mm", "overhang_mm", "teeth", "material", "cutting_source",
            "outside_range"] + [f"{p}_{q}" for p in PARAMS for q in ("p05", "p50", "p95")]
           + ["rpm", "kind", "limit_nominal_mm", "limit_p50_mm", "limit_p05_mm", "depth_mm", "p_stable",
              "dominant_uncertainty", "min_limit_p05_mm", "notes", "error"])


def _resume(path: Path, tools_dir: Path, ids: set, model: str) -> set:
    """Rewrite ``path`` with its finished ok rows of ``ids`` whose files exist and were computed with
    ``model`` (a run with the other joint model starts those tools again); their ids."""
    keep = []
    if path.exists():
        rows = [{k: csv_unsafe(v) if isinstance(v, str) else v for k, v in r.items()}
                for _, r in read_table(path, what="the results to resume")[1]]
        keep = [r for r in rows if r.get("status") == "ok" and r.get("id") in ids and r.get("error") is not None
                and (tools_dir / f"{tool_file_stem(r['id'])}.npz").exists()
                and _tool_model(tools_dir / f"{tool_file_stem(r['id'])}.json") == model]
    with atomic_open(path, "w", newline="", encoding="utf-8") as fh:
        w = csv.DictWriter(fh, COLUMNS, extrasaction="ignore")
        w.writeheader()
        w.writerows(keep)
    return {r["id"] for r in keep}


def _tool_model(path: Path) -> str | None:
    """The joint model (``"anfis"``/``"gp"``) a finished tool's JSON records; None if unreadable."""
    try:
        return json.loads(path.read_text(encoding="utf-8")).get("model", "anfis")
    except (OSError, UnicodeDecodeError, ValueError, AttributeError):
        return None


def _seed(seed: int, tool_id: str) -> int:
    return int(np.random.SeedSequence([seed, zlib.crc32(tool_id.encode())]).generate_state(1)[0])


def _fmt(v) -> str:
    return f"{v:.6g}" if isinstance(v, (float, np.floating)) else str(v)


def _row(tool, status, **cells) -> dict:
    row = dict.fromkeys(COLUMNS, "")
    row.update(id=tool.id, status=status)
    if hasattr(tool, "cutting"):
        row.update(holder=tool.holder, diameter_mm=_fmt(tool.diameter_mm), overhang_mm=_fmt(tool.overhang_mm),
                   teeth=tool.cutting.teeth, material=tool.material, cutting_source=tool.cutting_source)
    row.update({k: _fmt(v) for k, v in cells.items()})
    return {k: csv_safe(v) for k, v in row.items()}  # the file is opened in spreadsheets: no formula cells


def _ok_row(tool, summary, delta, notes) -> dict:
    best = summary["points"][0]
    cells = {f"{p}_{q}": summary["joint"][p][q] for p in PARAMS for q in ("p05", "p50", "p95")}
    cells.update({k: best[k] for k in ("rpm", "kind", "limit_nominal_mm", "limit_p50_mm", "limit_p05_mm",
                                       "depth_mm", "p_stable")})
    cells["rpm"] = f"{best['rpm']:.0f}"
    for k in best.get("capped", ()):  # not a computed limit: above the depth searched
        if k in cells:
            cells[k] = f">={summary['cap_mm']:.4g}"
    cells["dominant_uncertainty"] = summary.get("dominant_source") or ""
    return _row(tool, "ok", outside_range=float(delta), min_limit_p05_mm=summary["min_limit_mm"]["p05"],
                notes="; ".join(notes), **cells)


def _write_tool(tools_dir: Path, tool_id: str, result, extra: dict) -> None:
    buf = io.BytesIO()
    np.savez_compressed(buf, **result.arrays)
    stem = tool_file_stem(tool_id)  # never the id as it is: ids come from a file anyone may have written
    with atomic_path(tools_dir / f"{stem}.npz") as tmp:
        Path(tmp).write_bytes(buf.getvalue())
    with atomic_open(tools_dir / f"{stem}.json", "w", encoding="utf-8") as fh:
        json.dump({**result.summary, **extra}, fh, indent=1, allow_nan=True)


def run_library(library, campaign, models, out_dir, *, workers: int | None = None, dask: str | None = None,
                n_samples: int = 200, rpm_points: int = 500, seed: int = 0, margin: float = 0.1,
                rpm_tolerance: float = 0.01, outside: str = "widen", model: str = "anfis", progress: bool = True,
                on_bad=None, sub_replicates: int = 8) -> BatchResult:
    """Recommend operating points for every tool of a library (module docstring).

    Parameters
    ----------
    library : path-like
        Tool library CSV (:mod:`.library`).
    campaign : path-like
        Campaign folder (tool family, holders' subassemblies).
    models : path-like
        ``campaign learn`` models folder (``identified.csv`` beside it).
    out_dir : path-like
        Output folder (made if missing; an existing run is resumed).
    workers : int, optional
        Local processes (default all cores; 1 runs here).
    dask : str, optional
        Address of a running Dask scheduler.
    n_samples : int, default 200
        Joint samples per tool.
    rpm_points : int, default 500
        Speeds per tool, evenly spaced over the tool's [rpm_min, rpm_max].
    seed : int, default 0
        Seed (each tool gets its own from it and its id).
    margin : float, default 0.1
        Recommended depth = robust 5 % limit × (1 − margin).
    rpm_tolerance : float, default 0.01
        Relative spindle-speed tolerance of the robust limit.
    outside : {"widen", "refuse"}
        A tool outside the learned (D, L) range: widen its σ (warn; the GP's σ is its own) or refuse it.
    model : {"anfis", "gp"}, default "anfis"
        Predictive joint distribution from the ANFIS models or from the GP baselines ``campaign learn``
        saved (:class:`~.uncertainty.JointPredictor`).
    progress : bool
        Progress bar on stderr.
    on_bad : callable, optional
        Called with one line per bad tool (default: warnings are not emitted; lines are in the table).
    sub_replicates : int, default 8
        Bootstrap replicates of each blank-measured holder's subassembly that the samples are spread over (its
        own measurement uncertainty; 0: taken as exact). About 0.5 s CPU each, once per holder.

    Returns
    -------
    toolpoint.campaign.run.BatchResult
        ``ok``, ``failed``, ``skipped`` counts, ``seconds``, ``path``.

    Raises
    ------
    InputError
        An unreadable or empty library, a bad campaign or models folder, a bad
        setting, a Dask scheduler that does not answer (before anything is written).
    """
    if outside not in ("widen", "refuse"):
        raise InputError(f"must be 'widen' or 'refuse', got {outside!r}", field="outside")
    for name, v, lo in (("n_samples", n_samples, 2), ("rpm_points", rpm_points, 3),
                        ("sub_replicates", sub_replicates, 0)):
        if not isinstance(v, (int, np.integer)) or v < lo:
            raise InputError(f"must be a whole number ≥ {lo}, got {v!r}", field=name)
    if not (0 <= margin < 1):
        raise InputError(f"must be in [0, 1), got {margin!r}", field="margin")
    if not (0 <= rpm_tolerance < 0.5):
        raise InputError(f"must be in [0, 0.5), got {rpm_tolerance!r}", field="rpm_tolerance")
    tools, bad = read_library(library)
    c = load_campaign(campaign)
    predictor = JointPredictor(models, model, bounds=c.bounds)
    from ..campaign.run import dask_client, folder_lock

    client = dask_client(dask) if dask else None
    out = Path(out_dir)
    tools_dir = out / "tools"
    tools_dir.mkdir(parents=True, exist_ok=True)
    with folder_lock(out, "library run"):  # a second run into this folder refuses instead of doubling rows
        return _run_locked(tools, bad, c, predictor, client, out, tools_dir, workers=workers, n_samples=n_samples,
                           rpm_points=rpm_points, seed=seed, margin=margin, rpm_tolerance=rpm_tolerance,
                           outside=outside, model=model, progress=progress, on_bad=on_bad,
                           sub_replicates=sub_replicates)


def _run_locked(tools, bad, c, predictor, client, out, tools_dir, *, workers, n_samples, rpm_points, seed, margin,
                rpm_tolerance, outside, model, progress, on_bad, sub_replicates) -> BatchResult:
    """The locked part of :func:`run_library`: stale temporary files cleared, resume, compute, write rows."""
    for stale in tools_dir.glob(".*.tmp*"):  # left by a run killed while writing (atomic writes' temporaries)
        stale.unlink(missing_ok=True)
    path = out / FILE_NAME
    done = _resume(path, tools_dir, {t.id for t in tools}, model)
    todo = [t for t in tools if t.id not in done]
    t0 = time.perf_counter()
    report = on_bad or (lambda line: None)
    failed_rows = [_row(b, "failed", error=b.error) for b in bad]
    jobs, notes_of = [], {}
    dist = predictor.predict([t.diameter_mm for t in todo], [t.overhang_mm for t in todo]) if todo else None
    subs, reps = {}, {}
    for k, t in enumerate(todo):
        notes = []
        if t.holder not in c.holders:
            failed_rows.append(_row(t, "failed", error=f"{t.id}: holder {t.holder!r} is not in the campaign "
                                                          f"(it has {', '.join(c.holders)})"))
            continue
        if not np.all(np.isfinite(dist.log10_median[k])):
            failed_rows.append(_row(t, "failed", error=f"{t.id}: a model predicts a value ≤ 0 at D {t.diameter_mm:g}"
                                                          f" mm, L {t.overhang_mm:g} mm"))
            continue
        delta = float(dist.outside[k])
        if delta > 0:
            where = (f"D {t.diameter_mm:g} mm, L {t.overhang_mm:g} mm is outside the learned range (D "
                     f"{predictor.lo[0]:g}–{predictor.hi[0]:g} mm, L {predictor.lo[1]:g}–{predictor.hi[1]:g} mm)")
            if outside == "refuse":
                failed_rows.append(_row(t, "failed", outside_range=delta, error=f"{t.id}: {where}: refused "
                                                                                "(--outside widen to allow)"))
                continue
            widen = float(dist.sigma_log10[k, 0] / max(predictor.parameters["kt"].sigma_log10, 1e-300))
            notes.append(f"{where}: σ of kt widened ×{widen:.2g}" if model == "anfis" else
                         f"{where}: the GP's own σ (not widened)")
            report(f"warning: {t.id}: {notes[-1]}")
        if t.holder not in subs:
            kind = c.holders[t.holder].kind
            if kind == "model":
                lo, hi = c.band_hz
                subs[t.holder] = c.subassembly(t.holder, np.arange(lo, hi + 0.5))
            else:
                subs[t.holder] = c.subassembly(t.holder, None)
            keep = subs[t.holder].freq_hz > 0
            reps[t.holder] = _replicates(c, t.holder, subs[t.holder].freq_hz[keep], sub_replicates, seed)
        sub = subs[t.holder]
        keep = sub.freq_hz > 0
        rep_R, rep_note = reps[t.holder]
        notes_of[t.id] = (t, notes, delta, [rep_note] if rep_note else [])  # the holder's note: in the tool file
        jobs.append(ToolJob(t.id, c.family, t.diameter_mm, t.overhang_mm, t.flute_length_mm, sub.freq_hz[keep],
                            sub.R[keep], t.holder, t.cutting, np.linspace(t.rpm_min, t.rpm_max, rpm_points),
                            dist.log10_median[k], dist.sigma_log10[k], n_samples, _seed(seed, t.id), margin,
                            rpm_tolerance, dist.clip_log10, tuple(t.cutting_sigma_ln), rep_R, dist.window(k)))
    counts = {"ok": 0, "failed": 0, "skipped": len(done)}
    from tqdm import tqdm

    bar = tqdm(total=len(todo) + len(bad), desc="library", unit="tool", disable=not progress or None,
               file=sys.stderr)
    try:
        # unbuffered: a row is on disk when append returns, and a full disk is met there, not again at close
        with open(path, "ab", buffering=0) as fh:

            def append(row):
                text = io.StringIO(newline="")
                csv.DictWriter(text, COLUMNS).writerow(row)
                data = memoryview(text.getvalue().encode("utf-8"))
                try:
                    while data:  # a raw write may take part of it
                        data = data[fh.write(data):]
                    os.fsync(fh.fileno())
                except OSError as e:  # a full disk mid-run: finished rows stay; named like every other write
                    raise InputError(f"cannot write: {e.strerror or e}", file=path) from None
                counts[row["status"]] += 1
                bar.update(1)

            for row in failed_rows:
                report(f"error: {row['error']}")
                append(row)
            for job, result in _execute(jobs, workers, client):
                t, notes, delta, holder_notes = notes_of[job.id]
                if isinstance(result, Exception):
                    msg = f"{t.id}: {' '.join(f'{type(result).__name__}: {result}'.split())}"
                    report(f"error: {msg}")
                    append(_row(t, "failed", error=msg))
                    continue
                notes = notes + result.summary.get("engine_notes", [])
                _write_tool(tools_dir, t.id, result, {"notes": holder_notes + notes, "outside_range": delta,
                                                      "cutting": {"teeth": t.cutting.teeth,
                                                                  "tangential_coeff": t.cutting.tangential_coeff,
                                                                  "radial_ratio": t.cutting.radial_ratio,
                                                                  "radial_immersion": t.cutting.radial_immersion,
                                                                  "milling": t.cutting.milling,
                                                                  "source": t.cutting_source},
                                                      "holder": t.holder, "diameter_mm": t.diameter_mm,
                                                      "overhang_mm": t.overhang_mm, "material": t.material,
                                                      "model": model})
                append(_ok_row(t, result.summary, delta, notes))
    finally:
        bar.close()
        if client is not None:
            client.close()
    return BatchResult(ok=counts["ok"], failed=counts["failed"], skipped=counts["skipped"],
                       seconds=time.perf_counter() - t0, path=str(path))


#: The subassembly is sampled only where its bootstrap spread matters: 90th percentile over frequency of the
#: replicates' standard deviation of ln |h| (holder-tip receptance) at least this (1 %).
SUB_SPREAD_MIN = 0.01


def _replicates(c, holder: str, freq_hz, n: int, seed: int):
    """(replicates (B, F, 2, 2) or None, note): the holder's bootstrap replicates when their spread matters."""
    reps = c.subassembly_replicates(holder, freq_hz, n, seed)
    if not reps:
        return None, ""
    R = np.stack([r.R for r in reps])
    spread = float(np.percentile(np.std(np.log(np.abs(R[:, :, 0, 0])), axis=0), 90))
    if spread < SUB_SPREAD_MIN:  # measured and negligible: not worth the tool-point FRFs of every replicate
        return None, (f"subassembly {holder}: bootstrap spread of |h| {100 * spread:.2g} % (90th percentile over "
                      f"frequency) < {100 * SUB_SPREAD_MIN:g} %: taken as exact")
    return R, ""


def _execute(jobs, workers, client):
    """Yield (job, result or exception) as tools finish (extrapolation is said once per tool in its row)."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", ExtrapolationWarning)
        yield from execute(evaluate_tool, jobs, workers, client)
