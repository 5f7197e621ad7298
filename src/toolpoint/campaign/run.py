"""Identify the holder–tool joint of every measurement of a campaign.

Each finished item is appended to ``identified.csv`` at once (flushed and
synced), so a killed run loses nothing; a re-run keeps the ``ok`` rows, skips
those ids and retries the rest. An item that fails (unreadable FRF, band
outside the subassembly's, optimiser error) becomes a ``failed`` row with its
error, and the campaign goes on. Items run in a local process pool (all cores
by default) or on an existing Dask distributed cluster.
"""

from __future__ import annotations

import csv
import os
import sys
import time
import zlib
from concurrent.futures import ProcessPoolExecutor, as_completed
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ..dynamics.assembly import Component
from ..io.atomic import atomic_open
from ..errors import InputError
from ..frf import FRF
from ..io.frf_files import read_frf
from ..identification.params import PARAMS, Bounds
from ..dynamics.subassembly import Subassembly
from .config import Campaign, load_campaign

COLUMNS = (
    ["id", "holder", "diameter_mm", "overhang_mm", *PARAMS]
    + [f"{p}_{s}" for p in PARAMS for s in ("lo", "hi")]
    + ["objective", "evaluations", "seconds", "status", "warnings", "error"]
)
MIN_POINTS = 10


@dataclass(frozen=True)
class Item:
    """Everything one identification needs (picklable, no file access)."""

    id: str
    holder: str
    diameter_mm: float
    overhang_mm: float
    freq_hz: np.ndarray
    values: np.ndarray
    tool: Component
    sub_R: np.ndarray
    method: str
    seed: int
    bounds_lo: np.ndarray
    bounds_hi: np.ndarray


def _row(item_id, holder, d, l, **kw) -> dict:
    row = dict.fromkeys(COLUMNS, "")
    row.update(id=item_id, holder=holder, diameter_mm=d, overhang_mm=l, **kw)
    return row


def identify_item(item: Item) -> dict:
    """Run one identification (in a worker); returns its identified.csv row."""
    from threadpoolctl import threadpool_limits

    from ..identification.identify import identify
    from ..dynamics.model import ToolPointModel

    t0 = time.perf_counter()
    # one BLAS thread per item: the workers already use every core
    with threadpool_limits(1, user_api="blas"):
        sub = Subassembly(item.freq_hz, item.sub_R, item.holder)
        model = ToolPointModel(item.tool, sub, item.freq_hz)
        res = identify(model, FRF(item.freq_hz, item.values), item.method, item.seed,
                       Bounds(item.bounds_lo, item.bounds_hi))
    row = _row(item.id, item.holder, item.diameter_mm, item.overhang_mm, status="ok",
               objective=f"{res.fun:.6g}", evaluations=int(res.nfev), seconds=f"{time.perf_counter() - t0:.3f}",
               warnings="; ".join(res.warnings))
    for p in PARAMS:
        row[p] = repr(res.params[p])
        row[f"{p}_lo"], row[f"{p}_hi"] = (repr(v) for v in res.ci95[p])
    return row


def item_seed(seed: int, item_id: str) -> int:
    """A per-item seed that does not depend on the order or the set of items."""
    return int(np.random.SeedSequence([seed, zlib.crc32(item_id.encode())]).generate_state(1)[0])


def prepare(c: Campaign, todo, method: str, seed: int) -> tuple[list[Item], list[dict]]:
    """Read and check every FRF; returns runnable items and rows of items that failed already."""
    items, failed = [], []
    native: dict[str, Subassembly] = {}
    lo, hi = c.band_hz
    for m in todo:
        try:
            meas = read_frf(m.frf, min_points=MIN_POINTS).band(lo, hi)
            if len(meas) < MIN_POINTS:
                raise InputError(f"only {len(meas)} points inside the band {lo:g}–{hi:g} Hz", file=m.frf,
                                 field="freq_hz")
            kind = c.holders[m.holder].kind
            if kind == "model":
                sub = c.subassembly(m.holder, meas.freq_hz)
            else:
                if m.holder not in native:
                    native[m.holder] = c.subassembly(m.holder, None)
                try:
                    sub = native[m.holder].at(meas.freq_hz)
                except ValueError as e:
                    raise InputError(f"{e}", file=m.frf, field="freq_hz") from None
            items.append(Item(m.id, m.holder, m.diameter_mm, m.overhang_mm, meas.freq_hz, meas.values,
                              c.family.tool(m.diameter_mm, m.overhang_mm), sub.R, method, item_seed(seed, m.id),
                              c.bounds.lo, c.bounds.hi))
        except InputError as e:
            failed.append(_row(m.id, m.holder, m.diameter_mm, m.overhang_mm, status="failed", error=str(e)))
    return items, failed


def _resume(path: Path, ids: set[str]) -> set[str]:
    """Keep the ok rows of a previous run (rewritten atomically); return their ids."""
    if not path.exists():
        with atomic_open(path, newline="") as fh:
            csv.DictWriter(fh, COLUMNS).writeheader()
        return set()
    with open(path, newline="") as fh:
        rows = [r for r in csv.DictReader(fh) if r.get("status") == "ok" and r.get("id") in ids
                and all(r.get(p) not in (None, "") for p in PARAMS)]
    with atomic_open(path, newline="") as fh:
        w = csv.DictWriter(fh, COLUMNS, extrasaction="ignore")
        w.writeheader()
        w.writerows(rows)
    return {r["id"] for r in rows}


class _Appender:
    def __init__(self, path: Path):
        self.fh = open(path, "a", newline="")
        self.w = csv.DictWriter(self.fh, COLUMNS)

    def __call__(self, row: dict) -> None:
        self.w.writerow(row)
        self.fh.flush()
        os.fsync(self.fh.fileno())

    def close(self):
        self.fh.close()


def run_campaign(folder, out_dir, *, method: str | None = None, workers: int | None = None,
                 dask: str | None = None, seed: int = 0, progress: bool = True) -> dict:
    """Identify all measurements of the campaign in ``folder``; rows go to ``out_dir/identified.csv``."""
    c = load_campaign(folder)
    method = method or c.method
    from ..identification.optim import METHODS

    if method not in METHODS:
        raise InputError(f"unknown method {method!r} (one of {', '.join(METHODS)})", file="command line",
                         field="--method")
    client = _dask_client(dask) if dask else None  # before writing anything
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    path = out / "identified.csv"
    done = _resume(path, {m.id for m in c.measurements})
    todo = [m for m in c.measurements if m.id not in done]
    t0 = time.perf_counter()
    items, failed = prepare(c, todo, method, seed)
    append = _Appender(path)
    counts = {"ok": 0, "failed": 0, "skipped": len(done)}
    from tqdm import tqdm

    bar = tqdm(total=len(todo), desc="campaign", unit="tool", disable=not progress or None, file=sys.stderr)
    try:
        for row in failed:
            append(row)
            counts["failed"] += 1
            bar.update(1)
        for _, row in _execute(items, workers, client):
            append(row)
            counts[row["status"]] += 1
            bar.update(1)
    finally:
        bar.close()
        append.close()
        if client is not None:
            client.close()
    counts["seconds"] = time.perf_counter() - t0
    counts["path"] = str(path)
    return counts


def _one_line(err) -> str:
    return " ".join(f"{type(err).__name__}: {err}".split())


def _execute(items: list[Item], workers: int | None, client):
    """Yield (item, row) as items finish; a failed item gives a ``failed`` row."""
    if not items:
        return
    if client is not None:
        from distributed import as_completed as dask_completed

        futs = {client.submit(identify_item, it, pure=False): it for it in items}
        for fut in dask_completed(futs):
            it = futs[fut]
            try:
                yield it, fut.result()
            except Exception as e:  # noqa: BLE001 — a failed item is recorded, the rest goes on
                yield it, _failed_row(it, e)
        return
    n = workers or os.cpu_count() or 1
    if n == 1:
        for it in items:
            try:
                yield it, identify_item(it)
            except Exception as e:  # noqa: BLE001
                yield it, _failed_row(it, e)
        return
    with ProcessPoolExecutor(max_workers=n) as ex:
        futs = {ex.submit(identify_item, it): it for it in items}
        for fut in as_completed(futs):
            it = futs[fut]
            try:
                yield it, fut.result()
            except Exception as e:  # noqa: BLE001
                yield it, _failed_row(it, e)


def _failed_row(it: Item, err: Exception) -> dict:
    return _row(it.id, it.holder, it.diameter_mm, it.overhang_mm, status="failed", error=_one_line(err))


def _dask_client(address: str):
    from distributed import Client

    try:
        return Client(address, timeout="5s")
    except (OSError, TimeoutError, ValueError) as e:
        raise InputError(f"no Dask scheduler answers at {address!r} ({_one_line(e)})", file="command line",
                         field="--dask") from None
