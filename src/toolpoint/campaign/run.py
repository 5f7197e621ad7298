"""Identify the holder–tool joint of every measurement of a campaign.

Each finished item is appended to ``identified.csv`` (:mod:`.results`) at
once (flushed and synced), so a killed run loses nothing; a re-run keeps the
``ok`` rows, skips those ids and retries the rest. An item that fails
(unreadable FRF, band outside the subassembly's, optimiser error) becomes a
``failed`` row with its error, and the campaign goes on. Items run in a local
process pool (all cores by default) or on an existing Dask distributed cluster.
"""

from __future__ import annotations

import os
import threading
import time
import warnings
import zlib
from concurrent.futures import ProcessPoolExecutor, as_completed
from contextlib import contextmanager
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ..blas import single_thread_blas
from ..progress import Progress
from ..dynamics.assembly import Component
from ..dynamics.subassembly import Subassembly
from ..errors import IdentifiabilityWarning, InputError
from ..frf import FRF
from ..identification.optim import check_method
from ..identification.params import PARAMS, Bounds
from ..io.frf_files import read_frf
from .config import Campaign, load_campaign
from .results import COLUMNS, FILE_NAME, Appender, new_row, resume

__all__ = ["COLUMNS", "MIN_POINTS", "BatchResult", "Item", "identify_item", "item_seed", "prepare", "run_campaign",
           "dask_client", "execute", "worker_init", "holder_subassemblies", "trusted_part"]

#: Fewest frequency points of a measurement inside the campaign's band.
MIN_POINTS = 10


@dataclass(frozen=True)
class Item:
    """Everything one identification needs (picklable, no file access).

    Attributes
    ----------
    id, holder : str
        Measurement id and holder name.
    diameter_mm, overhang_mm : float
        Tool diameter and overhang, mm.
    freq_hz, values : ndarray
        The measured tool-point receptance (Hz, m/N) inside the band.
    tool : Component
        The tool's overhang as a beam (SI).
    sub_R : ndarray, shape (n, 2, 2)
        The spindle–holder subassembly's receptances on ``freq_hz`` (SI).
    method : str
        Optimiser (:data:`~toolpoint.identification.optim.METHODS`).
    seed : int
        The item's own seed (:func:`item_seed`).
    bounds_lo, bounds_hi : ndarray, shape (4,)
        Search bounds of kt, ct, kr, cr (SI).
    note : str
        Why the fitted band is narrower than ``campaign.band_hz`` (the measured
        FRF's trusted band, :func:`toolpoint.trust.trusted_band`), or ``""``;
        written into the row's ``warnings`` cell.
    """

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
    note: str = ""


# warnings.catch_warnings changes process-wide state: with several identifications on threads
# (Dask workers with threads), one would restore the filters while another still runs. So the
# filter is installed while any identification runs and restored when the last one ends.
_QUIET_LOCK = threading.Lock()
_quiet_users = 0
_quiet_ctx = None


@contextmanager
def _identifiability_warnings_off():
    """Silence IdentifiabilityWarning while identifying: the row records them (178 would spam)."""
    global _quiet_users, _quiet_ctx
    with _QUIET_LOCK:
        if _quiet_users == 0:
            _quiet_ctx = warnings.catch_warnings()
            _quiet_ctx.__enter__()
            warnings.simplefilter("ignore", IdentifiabilityWarning)
        _quiet_users += 1
    try:
        yield
    finally:
        with _QUIET_LOCK:
            _quiet_users -= 1
            if _quiet_users == 0:
                _quiet_ctx.__exit__(None, None, None)
                _quiet_ctx = None


def identify_item(item: Item) -> dict:
    """Run one identification (in a worker).

    Parameters
    ----------
    item : Item

    Returns
    -------
    dict
        Its ``identified.csv`` row (:data:`COLUMNS`), status ``ok``; the
        identifiability warnings are in the row's ``warnings`` cell, not emitted.
    """
    from ..dynamics.model import ToolPointModel
    from ..identification.identify import identify

    t0 = time.perf_counter()
    # one BLAS thread per item: the workers already use every core
    with single_thread_blas(), _identifiability_warnings_off():
        sub = Subassembly(item.freq_hz, item.sub_R, item.holder)
        model = ToolPointModel(item.tool, sub, item.freq_hz)
        res = identify(model, FRF(item.freq_hz, item.values), item.method, item.seed,
                       bounds=Bounds(item.bounds_lo, item.bounds_hi))
    row = new_row(item.id, item.holder, item.diameter_mm, item.overhang_mm, status="ok",
                  objective=f"{res.fun:.6g}", evaluations=int(res.nfev),
                  seconds=f"{time.perf_counter() - t0:.3f}",
                  warnings="; ".join(([item.note] if item.note else []) + list(res.warnings)))
    for p in PARAMS:
        row[p] = repr(res.params[p])
        row[f"{p}_lo"], row[f"{p}_hi"] = (repr(v) for v in res.ci95[p])
    return row


def item_seed(seed: int, item_id: str) -> int:
    """A per-item seed that does not depend on the order or the set of items.

    Parameters
    ----------
    seed : int
        The campaign run's seed.
    item_id : str
        Measurement id.

    Returns
    -------
    int
        Seed derived from both (:class:`numpy.random.SeedSequence` of the seed and the id's CRC-32).

    Examples
    --------
    >>> item_seed(0, "T001") == item_seed(0, "T001") != item_seed(1, "T001")
    True
    """
    return int(np.random.SeedSequence([seed, zlib.crc32(item_id.encode())]).generate_state(1)[0])


def holder_subassemblies(c: Campaign, holders) -> dict[str, Subassembly]:
    """The measured subassembly (blank or four files) of each of ``holders`` that has one.

    A holder's subassembly serves every tool on it, so its errors (a bad blank
    FRF, a failed modal fit) are campaign-wide: they raise here, once, naming the
    file and field, instead of failing every tool of that holder.
    """
    return {h: c.subassembly(h, None) for h in sorted(holders) if c.holders[h].kind != "model"}


def prepare(c: Campaign, todo, method: str, seed: int, native: dict | None = None) -> tuple[list[Item], list[dict]]:
    """Read and check every FRF of ``todo``.

    Parameters
    ----------
    c : Campaign
    todo : iterable of Measurement
        The measurements to identify.
    method : str
        Optimiser name.
    seed : int
        The run's seed (each item gets :func:`item_seed`).
    native : dict, optional
        Holder name → its measured subassembly (:func:`holder_subassemblies`), if already computed.

    Returns
    -------
    items : list of Item
        Runnable items.
    failed : list of dict
        ``failed`` rows of measurements that cannot be run (the error in the row).
    """
    items, failed = [], []
    if native is None:
        native = holder_subassemblies(c, {m.holder for m in todo})
    lo, hi = c.band_hz
    for m in todo:
        try:
            meas, note = trusted_part(read_frf(m.frf, min_points=MIN_POINTS), m.frf, (lo, hi))
            if len(meas) < MIN_POINTS:
                raise InputError(f"only {len(meas)} points inside the band {lo:g}–{hi:g} Hz", file=m.frf,
                                 field="freq_hz")
            kind = c.holders[m.holder].kind
            if kind == "model":
                sub = c.subassembly(m.holder, meas.freq_hz)
            else:
                try:
                    sub = native[m.holder].at(meas.freq_hz)
                except ValueError as e:
                    raise InputError(f"{e}", file=m.frf, field="freq_hz") from None
            items.append(Item(m.id, m.holder, m.diameter_mm, m.overhang_mm, meas.freq_hz, meas.values,
                              c.family.tool(m.diameter_mm, m.overhang_mm), sub.R, method, item_seed(seed, m.id),
                              c.bounds.lo, c.bounds.hi, note))
        except InputError as e:
            failed.append(new_row(m.id, m.holder, m.diameter_mm, m.overhang_mm, status="failed", error=str(e)))
    return items, failed


def trusted_part(frf: FRF, path, band_hz: tuple[float, float]) -> tuple[FRF, str]:
    """A measured FRF cut to ``campaign.band_hz`` and to its own trusted band (:func:`toolpoint.trust.trusted_band`).

    Returns the cut FRF and a note (``""`` unless the trusted band cuts into
    ``band_hz``). A trusted band that misses ``band_hz`` is an InputError (the item fails).
    """
    from ..trust import trusted_band

    lo, hi = band_hz
    tb = trusted_band(frf, file=path)
    lo2, hi2 = max(lo, tb.lo_hz), min(hi, tb.hi_hz)
    if lo2 >= hi2:
        raise InputError(f"its trusted band {tb.lo_hz:g}–{tb.hi_hz:g} Hz ({tb.reason}) misses campaign.band_hz "
                         f"{lo:g}–{hi:g} Hz", file=path, field="freq_hz")
    note = ""
    if tb.reason and (lo2 > lo or hi2 < hi):
        note = f"note: fitted {lo2:g}–{hi2:g} Hz of campaign.band_hz {lo:g}–{hi:g} Hz ({tb.reason})"
    return frf.band(lo2, hi2), note


def run_campaign(folder, out_dir, *, method: str | None = None, workers: int | None = None,
                 dask: str | None = None, seed: int = 0, progress: bool = True) -> BatchResult:
    """Identify every measurement of the campaign in ``folder``; rows go to ``out_dir/identified.csv``.

    Parameters
    ----------
    folder : path-like
        Campaign folder (:func:`~toolpoint.campaign.config.load_campaign`).
    out_dir : path-like
        Results folder (made if missing); an existing ``identified.csv`` is resumed.
    method : str, optional
        Optimiser (default: the campaign's ``identify.method``).
    workers : int, optional
        Local processes (default: all cores; 1 runs in this process).
    dask : str, optional
        Address of a running Dask scheduler to run the items on instead.
    seed : int, default 0
        Seed of the run (each item gets :func:`item_seed`).
    progress : bool, default True
        Show a progress bar on stderr.

    Returns
    -------
    BatchResult
        ``ok``, ``failed`` and ``skipped`` (already done) counts, ``seconds``
        (wall time, s) and ``path`` (the CSV).

    Raises
    ------
    InputError
        A bad campaign folder or method, a holder whose subassembly cannot be
        built, or a Dask scheduler that does not answer (all before anything is
        written); a results folder that another run is writing to.
    """
    c = load_campaign(folder)
    method = check_method(method or c.method, file="command line", field="--method")
    out = Path(out_dir)
    if out.exists() and not out.is_dir():
        raise InputError("is a file, expected a results folder", file=out, field="--out")
    t0 = time.perf_counter()
    # campaign-wide errors (a holder's blank or files) stop the run here, before anything is written
    native = holder_subassemblies(c, {m.holder for m in c.measurements})
    client = dask_client(dask) if dask else None
    try:
        try:
            out.mkdir(parents=True, exist_ok=True)
        except OSError as e:
            raise InputError(f"cannot make the results folder ({e.strerror})", file=out, field="--out") from None
        with folder_lock(out):
            return _run_locked(c, out, method, seed, workers, client, progress, t0, native)
    finally:
        if client is not None:
            with quiet_distributed():
                client.close()


def _run_locked(c, out: Path, method, seed, workers, client, progress, t0, native) -> BatchResult:
    path = out / FILE_NAME
    done = resume(path, {m.id for m in c.measurements})
    todo = [m for m in c.measurements if m.id not in done]
    items, failed = prepare(c, todo, method, seed, native)
    counts = {"ok": 0, "failed": 0, "skipped": len(done)}
    bar = Progress(len(todo), "campaign", "tool", enabled=progress)
    try:
        with Appender(path) as append:
            for row in failed:
                append(row)
                counts["failed"] += 1
                bar.update(1)
            for it, row in execute(identify_item, items, workers, client):
                if isinstance(row, Exception):
                    row = _failed_row(it, row)
                append(row)
                counts[row["status"]] += 1
                bar.update(1)
    finally:
        bar.close()
    return BatchResult(ok=counts["ok"], failed=counts["failed"], skipped=counts["skipped"],
                       seconds=time.perf_counter() - t0, path=str(path))


@dataclass(frozen=True)
class BatchResult:
    """What a batch run (``campaign run``, ``library``) did.

    Attributes
    ----------
    ok, failed, skipped : int
        Items finished in this run, items that failed (their rows say why), items kept from an earlier run.
    seconds : float
        Wall time of this run, s.
    path : str
        The results table.
    """

    ok: int
    failed: int
    skipped: int
    seconds: float
    path: str


LOCK_NAME = ".toolpoint-run.lock"


@contextmanager
def folder_lock(out: Path, what: str = "campaign run"):
    """One run per results folder: a second concurrent run refuses instead of interleaving rows.

    An advisory ``flock`` on a file in the folder; the kernel drops it when the
    process ends, however it ends, so a killed run never leaves a stale lock.
    """
    import fcntl

    path = out / LOCK_NAME
    try:
        fh = open(path, "a+")
    except OSError as e:
        raise InputError(f"cannot write in the results folder ({e.strerror})", file=out, field="--out") from None
    with fh:
        try:
            fcntl.flock(fh, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except OSError:
            fh.seek(0)
            who = fh.read().strip() or "another process"
            raise InputError(f"another {what} ({who}) is writing to this folder; wait for it or choose "
                             "another --out", file=out, field="--out") from None
        try:  # who holds it, for a second run's message; a full disk is named like every other write
            fh.seek(0)
            fh.truncate()
            os.write(fh.fileno(), f"pid {os.getpid()}\n".encode())  # unbuffered: nothing left to fail at close
        except OSError as e:
            fcntl.flock(fh, fcntl.LOCK_UN)
            raise InputError(f"cannot write: {e.strerror or e}", file=path) from None
        try:
            yield
        finally:
            fh.seek(0)
            fh.truncate()
            fcntl.flock(fh, fcntl.LOCK_UN)


def worker_init(parent_pid: int) -> None:
    """Make a pool worker end with its parent, however the parent ends (SIGKILL included), and keep freed memory
    as the ``toolpoint`` command does (:func:`toolpoint.memory.keep_freed_memory`).

    Linux delivers PR_SET_PDEATHSIG on the parent's death; a watchdog thread
    covers other systems (and the race before prctl took effect).
    """
    import signal

    try:
        import ctypes

        ctypes.CDLL(None, use_errno=True).prctl(1, signal.SIGKILL)  # 1 = PR_SET_PDEATHSIG
    except (OSError, AttributeError):
        pass
    if os.getppid() != parent_pid:
        os._exit(1)
    from ..memory import keep_freed_memory

    keep_freed_memory()  # as the parent command: a spawned worker does not inherit it (toolpoint.memory)

    def watch():
        while os.getppid() == parent_pid:
            time.sleep(1.0)
        os._exit(1)

    threading.Thread(target=watch, daemon=True, name="toolpoint-parent-watch").start()


def _one_line(err) -> str:
    return " ".join(f"{type(err).__name__}: {err}".split())


def execute(fn, jobs, workers: int | None = None, client=None):
    """Run ``fn(job)`` for every job; yield ``(job, result)`` as each finishes, in completion order.

    A job that raises yields ``(job, exception)`` instead, and the others go on.
    Jobs run on the Dask ``client`` if given, else in ``workers`` local processes
    (default: all cores; 1 runs them here). Pool workers end with this process
    however it ends (:func:`worker_init`).

    Parameters
    ----------
    fn : callable
        A picklable, module-level function of one job.
    jobs : list
        Picklable job descriptions.
    workers : int, optional
        Local processes.
    client : distributed.Client, optional
        Run on this Dask cluster instead.
    """
    if not jobs:
        return
    if client is not None:
        from distributed import as_completed as dask_completed

        with quiet_distributed():
            futs = {client.submit(fn, j, pure=False): j for j in jobs}
            done = 0
            for fut in dask_completed(futs):
                if fut.status == "cancelled" or client.status not in ("running", "connecting"):
                    break  # the scheduler went away: its futures are cancelled, the rest never come
                try:
                    result = fut.result()
                except Exception as e:  # noqa: BLE001 — a failed job is reported to the caller, the rest goes on
                    result = e
                done += 1
                yield futs[fut], result
            if done < len(futs):
                raise InputError(f"the Dask scheduler at {client.scheduler.address!r} was lost after {done} of "
                                 f"{len(futs)} jobs (their results are kept; run again to do the rest)",
                                 file="command line", field="--dask")
        return
    n = workers or os.cpu_count() or 1
    if n == 1:
        for j in jobs:
            try:
                yield j, fn(j)
            except Exception as e:  # noqa: BLE001
                yield j, e
        return
    with ProcessPoolExecutor(max_workers=n, initializer=worker_init, initargs=(os.getpid(),)) as ex:
        futs = {ex.submit(fn, j): j for j in jobs}
        for fut in as_completed(futs):
            try:
                yield futs[fut], fut.result()
            except Exception as e:  # noqa: BLE001
                yield futs[fut], e


#: Loggers through which distributed (and the asyncio/tornado loop under it) report a lost scheduler
#: with tracebacks; a lost scheduler is reported as one line (:func:`execute`) instead.
_DASK_LOGGERS = ("distributed", "distributed.client", "distributed.core", "distributed.comm", "distributed.utils",
                 "distributed.batched", "distributed.worker", "asyncio", "tornado", "tornado.application")


@contextmanager
def quiet_distributed():
    """Silence distributed's own error logging while a Dask client runs jobs or closes (levels restored)."""
    import logging

    loggers = [logging.getLogger(n) for n in _DASK_LOGGERS]
    old = [lg.level for lg in loggers]
    for lg in loggers:
        lg.setLevel(logging.CRITICAL + 1)
    try:
        yield
    finally:
        for lg, level in zip(loggers, old):
            lg.setLevel(level)


def _failed_row(it: Item, err: Exception) -> dict:
    return new_row(it.id, it.holder, it.diameter_mm, it.overhang_mm, status="failed", error=_one_line(err))


#: Longest wait for a Dask scheduler to answer, s. distributed's own connect timeout does not cover a
#: port that accepts the connection and then never speaks (measured: > 300 s), so the wait is bounded here.
DASK_CONNECT_S = 20.0


def dask_client(address: str):
    """A :class:`distributed.Client` of the scheduler at ``address``, or an InputError (``--dask``) within
    :data:`DASK_CONNECT_S` seconds, whatever the other end does (refuse, accept and stay silent, speak HTTP)."""
    from distributed import Client

    box: dict = {}

    def connect():
        try:
            box["client"] = Client(address, timeout=f"{DASK_CONNECT_S / 2:g}s")
        except Exception as e:  # noqa: BLE001 — reported below as one line
            box["error"] = e

    th = threading.Thread(target=connect, daemon=True, name="toolpoint-dask-connect")
    th.start()
    th.join(DASK_CONNECT_S)
    if "client" in box:
        return box["client"]
    why = _one_line(box["error"]) if "error" in box else f"no answer within {DASK_CONNECT_S:g} s"
    raise InputError(f"no Dask scheduler answers at {address!r} ({why})", file="command line", field="--dask")
