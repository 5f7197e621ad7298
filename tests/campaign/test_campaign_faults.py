"""Campaign runs under faults: a second run into the same folder, a killed parent, a silent Dask port,
and configuration errors that concern every tool."""

import os
import re
import shutil
import signal
import socket
import subprocess
import sys
import textwrap
import threading
import time

import pytest

from toolpoint.campaign import run as run_mod
from toolpoint.campaign.run import run_campaign
from toolpoint.campaign.synth import synthesise
from toolpoint.cli.main import main
from toolpoint.errors import InputError


@pytest.fixture(scope="module")
def small(tmp_path_factory):
    d = tmp_path_factory.mktemp("camp") / "c"
    synthesise(d, n=6, seed=2)
    return d


@pytest.mark.slow
def test_a_second_run_into_the_same_folder_refuses(small, tmp_path):
    out = tmp_path / "res"
    out.mkdir()
    with run_mod.folder_lock(out):  # a run in progress
        with pytest.raises(InputError, match="another campaign run .pid"):
            run_campaign(small, out, workers=1, progress=False)
    assert not (out / "identified.csv").exists()
    r = run_campaign(small, out, workers=1, progress=False)  # the lock went with the first run
    assert r.ok + r.failed == 6


@pytest.mark.parametrize("edit, field", [
    (('x2_mm = 45.0', 'x2_mm = "abc"'), "holders.ER40.blank.x2_mm"),
    (('G11 = "sh/G11.csv"', 'G11 = 5'), "holders.ER40.blank.G11"),
    (('G22 = "sh/G22.csv"', 'G22 = "sh/none.csv"'), "holders.ER40.blank.G22"),
])
def test_a_campaign_wide_error_stops_the_run_once_naming_the_field(small, tmp_path, capsys, edit, field):
    camp = tmp_path / "c"
    shutil.copytree(small, camp)
    toml = camp / "campaign.toml"
    text = toml.read_text()
    assert edit[0] in text
    toml.write_text(text.replace(*edit))
    out = tmp_path / "res"
    assert main(["campaign", "run", str(camp), "--out", str(out), "--workers", "1"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and field in err[0]
    assert not out.exists()


def test_a_broken_blank_file_stops_the_run_before_any_row(small, tmp_path, capsys):
    camp = tmp_path / "c"
    shutil.copytree(small, camp)
    (camp / "sh" / "G12.csv").write_bytes(b"\x00\xff garbage")
    out = tmp_path / "res"
    assert main(["campaign", "run", str(camp), "--out", str(out), "--workers", "1"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "G12.csv" in err[0]
    assert not out.exists()


@pytest.mark.slow
def test_a_dask_port_that_never_answers_fails_in_bounded_time(small, tmp_path, monkeypatch, capsys):
    srv = socket.socket()
    srv.bind(("127.0.0.1", 0))
    srv.listen(8)
    held = []
    threading.Thread(target=lambda: [held.append(srv.accept()) for _ in range(8)], daemon=True).start()
    monkeypatch.setattr(run_mod, "DASK_CONNECT_S", 3.0)
    t0 = time.perf_counter()
    out = tmp_path / "res"
    code = main(["campaign", "run", str(small), "--out", str(out), "--dask", f"tcp://127.0.0.1:{srv.getsockname()[1]}"])
    assert code == 2 and time.perf_counter() - t0 < 10
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "--dask" in err[0] and "no answer within 3 s" in err[0]
    assert not out.exists()
    srv.close()


def _children(pid: int) -> list[int]:
    out = subprocess.run(["ps", "-o", "pid=", "--ppid", str(pid)], capture_output=True, text=True).stdout
    return [int(p) for p in out.split()]


def _alive(pid: int) -> bool:
    try:
        with open(f"/proc/{pid}/stat") as fh:
            return fh.read().split()[2] != "Z"
    except FileNotFoundError:
        return False


@pytest.mark.slow
@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="uses /proc and ps")
@pytest.mark.parametrize("sig", [signal.SIGKILL, signal.SIGTERM])
def test_pool_workers_end_with_their_parent(small, tmp_path, sig):
    code = textwrap.dedent(f"""
        from toolpoint.campaign.run import run_campaign
        run_campaign({str(small)!r}, {str(tmp_path / 'res')!r}, workers=2, progress=False)
    """)
    parent = subprocess.Popen([sys.executable, "-c", code])
    try:
        deadline = time.time() + 60
        workers: list[int] = []
        while time.time() < deadline and len(workers) < 2 and parent.poll() is None:
            time.sleep(0.2)
            workers = _children(parent.pid)
        assert len(workers) >= 2, "the pool never started"
        os.kill(parent.pid, sig)
        parent.wait(10)
        deadline = time.time() + 10
        while time.time() < deadline and any(_alive(w) for w in workers):
            time.sleep(0.2)
        assert not any(_alive(w) for w in workers), "pool workers outlived their parent"
    finally:
        if parent.poll() is None:
            parent.kill()


@pytest.mark.slow
def test_progress_goes_to_a_log_when_stderr_is_not_a_terminal(small, tmp_path):
    # a log gets plain lines (not a redrawn bar, not nothing): the command runs with stderr to a pipe
    proc = subprocess.run([sys.executable, "-m", "toolpoint.cli.main", "campaign", "run", str(small), "--out",
                           str(tmp_path / "res"), "--workers", "1"], capture_output=True, text=True, timeout=300)
    assert proc.returncode == 0, proc.stderr
    lines = [s for s in proc.stderr.splitlines() if s.startswith("campaign: ")]
    assert lines and lines[-1].startswith("campaign: 6/6 tools (100 %)") and "\r" not in proc.stderr


def _free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def test_a_dask_scheduler_lost_mid_run_is_one_error_and_no_traceback(capfd):
    # a real scheduler (a process of its own) that dies while jobs are queued on it: the jobs' futures are
    # cancelled, distributed logs reconnect tracebacks; execute must stop with one InputError naming --dask
    import distributed  # noqa: F401  (a dependency: its absence is a failure, not a skip)
    port = _free_port()
    sched = subprocess.Popen([sys.executable, "-m", "distributed.cli.dask_scheduler", "--port", str(port),
                              "--no-dashboard", "--host", "127.0.0.1"],
                             stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    try:
        deadline = time.time() + 30
        while time.time() < deadline:  # wait until it listens
            with socket.socket() as s:
                if s.connect_ex(("127.0.0.1", port)) == 0:
                    break
            time.sleep(0.2)
        client = run_mod.dask_client(f"tcp://127.0.0.1:{port}")
        threading.Timer(1.0, sched.kill).start()  # no worker: the jobs wait until the scheduler dies
        t0 = time.perf_counter()
        with pytest.raises(InputError, match=r"--dask: the Dask scheduler .* was lost after 0 of 5 jobs"):
            list(run_mod.execute(time.sleep, [0.1] * 5, client=client))
        with run_mod.quiet_distributed():
            client.close()
        assert time.perf_counter() - t0 < 60
    finally:
        sched.kill()
        sched.wait(10)
    err = capfd.readouterr().err
    assert "Traceback" not in err and "ERROR" not in err, err


@pytest.mark.parametrize("column, value, msg", [
    ("diameter_mm", "1e300", "'1e300' mm is not a tool size"),
    ("overhang_mm", "-5", "'-5' mm is not a tool size"),
    ("kt", "1e300", "'1e300' is beyond ±1e+100"),
])
def test_identified_csv_numbers_that_overflow_the_models_are_refused(tmp_path, column, value, msg):
    from toolpoint.campaign.results import Appender, new_row, read_identified, resume

    path = tmp_path / "identified.csv"
    resume(path, set())
    with Appender(path) as append:
        for k in range(3):
            cells = dict(diameter_mm="12.0", overhang_mm="40.0", kt="2e7", ct="15", kr="1e6", cr="3")
            if k == 1:
                cells[column] = value
            d, L = cells.pop("diameter_mm"), cells.pop("overhang_mm")
            append(new_row(f"T{k}", "ER40", d, L, status="ok", **cells))
    rows = read_identified(path, required=["kt"]).ok()
    with pytest.raises(InputError, match=rf"identified\.csv: {column}: line 3: {re.escape(msg)}"):
        rows.column(column)
