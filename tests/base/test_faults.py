"""Issue 22 "No way in, nothing lost": tool ids that are paths, formulas or device names; a full disk; FRF files
cut short; a run killed with SIGTERM.

* Generated tool ids (Hypothesis): separators ``/`` ``\\``, ``..``, absolute paths, NUL, newlines and other control
  characters, 300+ characters, Windows device names (``CON``, ``nul.x``, ``COM1``), unicode, a leading ``= + - @``,
  ids differing only by case, an id equal to another id's hashed file name. :func:`tool_file_stem` is a safe file
  name (``[A-Za-z0-9._-]``, ≤ 64 characters, not a device), deterministic and unique across a library even where the
  file system ignores case; ``library`` writes nothing outside its output folder and ``report`` opens nothing but the
  files ``library`` wrote; every CSV cell that starts with ``= + - @``, a tab or CR is neutralised (numbers aside)
  and reads back as it was.
* A full disk: a 4 MiB tmpfs filled up (root on Linux; ``mount`` fails otherwise and the case is skipped) and,
  everywhere, the same fault injected (every atomic write of toolpoint fails with ENOSPC). ``tap --out``,
  ``tap --plot``, ``modal``, ``identify``, ``library``, ``report``, ``lobes`` exit 2 with one line naming the file and
  the reason, no traceback, no partial or temporary file, inputs untouched; ``library`` filling the disk mid-run
  keeps its finished rows and a second run completes it.
* A CutPro ``.frf`` (or text export, or CSV) cut at any byte: refused naming the file and the line, or read as the
  complete lines before the cut with the values they had (a cut exactly at a line break cannot be seen: the formats
  carry no line count). ``lobes``, ``identify``, ``modal`` on a file cut in half or mid-number: exit 2, one line,
  nothing written; a complete file without its last line break is read.
* ``library`` killed with SIGTERM after its first row: exit 143, no temporary file, lock released, a second run
  keeps the finished rows and adds the rest once each.
"""

from __future__ import annotations

import contextlib
import csv
import errno
import io
import os
import re
import shutil
import signal
import subprocess
import sys
import tempfile
import time
import warnings
from contextlib import redirect_stderr, redirect_stdout
from pathlib import Path

import numpy as np
import pytest
from hypothesis import HealthCheck, example, given, settings
from hypothesis import strategies as st

from toolpoint.cli.main import main
from toolpoint.errors import InputError
from toolpoint.io.table import csv_safe, csv_unsafe
from toolpoint.recommend.library import tool_file_stem

ROOT = Path(__file__).resolve().parents[2]
SCALE = int(os.environ.get("TOOLPOINT_PROPERTY_SCALE", "1"))


def _n(k: int) -> settings:
    return settings(max_examples=k * SCALE, deadline=None, derandomize=SCALE == 1,
                    suppress_health_check=[HealthCheck.function_scoped_fixture, HealthCheck.too_slow])


HEADER = ("id,diameter_mm,overhang_mm,teeth,holder,tangential_coeff_n_mm2,radial_ratio,material,radial_immersion,"
          "milling,rpm_min,rpm_max").split(",")
RESERVED = {"con", "prn", "aux", "nul", *(f"com{i}" for i in range(10)), *(f"lpt{i}" for i in range(10))}
FORMULA = ("=", "+", "-", "@", "\t", "\r")
STEM_MAX = 64


# ---------------------------------------------------------------- generated tool ids
EVIL = ["../../x", "..", ".", "...", "/etc/passwd", "/tmp/abs", "C:\\Windows\\system32", "\\\\server\\share\\x",
        "a/b", "a\\b", "x/", "\x00", "a\x00b", "x\ny", "x\r\n", "\x1b[31mred", "a\x7fb", "\t=x", "CON", "con", "Con",
        "NUL.txt", "nul.tar.gz", "COM1", "com9.x", "LPT1", "CON.x", "AUX ", "PRN.", "CONIN$", "=cmd|' /C calc'!A0",
        "+1+1", "-2+3", "@SUM(A1:A9)", "'=x", "''@x", "=1", "-1.5", "x" * 300, "é" * 200, "工具-1", "😀",
        "\u202eexe.txt", "\ufeffEM10", "EM10", "em10", "Em10", "x-9bdbf20b56", "X-9BDBF20B56", "tool-da39a3ee5e",
        "a" * 64, "A" * 64, "A" * 65, "EM10.", "-EM10", ".EM10", "EM 10", "EM10,45", '"EM"', "1e5", "nan"]
PARTS = ["/", "\\", "..", ".", "\x00", "\n", "\r", "\t", "\x1b", "\x7f", "\x85", "\u2028", "=", "+", "-", "@", "'",
         ",", '"', " ", "C:", "CON", "nul", "COM1", "LPT9", "é", "工", "\u202e", "\ufeff", "EM10", "em10", "x",
         "-9bdbf20b56", "$"]


def _reserved_names():
    return st.builds(lambda name, ext, up: (name.upper() if up else name) + ext, st.sampled_from(sorted(RESERVED)),
                     st.sampled_from(["", ".", ".x", ".tar.gz", " ", ":", "$"]), st.booleans())


def tool_ids():
    """Tool ids anyone might type into a spreadsheet, and ids written to break things."""
    return st.one_of(st.sampled_from(EVIL), st.lists(st.sampled_from(PARTS), min_size=1, max_size=8).map("".join),
                     st.text(max_size=30), st.text(min_size=295, max_size=320), _reserved_names(),
                     st.builds(lambda c, s: c + s, st.sampled_from("=+-@\t\r'"), st.text(max_size=12)))


def _is_safe_stem(stem: str) -> bool:
    return (re.fullmatch(r"[A-Za-z0-9][A-Za-z0-9._-]*", stem) is not None and len(stem) <= STEM_MAX
            and stem.split(".")[0].lower() not in RESERVED and not stem.endswith("."))


@_n(150)
@given(tool_id=tool_ids())
def test_tool_file_stem_is_a_safe_bounded_file_name(tool_id):
    stem = tool_file_stem(tool_id)
    assert _is_safe_stem(stem), (tool_id, stem)
    assert tool_file_stem(tool_id) == stem  # deterministic
    base = Path("/srv/out/tools")
    assert (base / f"{stem}.npz").parent == base and os.path.basename(f"{stem}.json") == f"{stem}.json"
    if re.fullmatch(r"[A-Z0-9][A-Z0-9._-]{0,63}", tool_id) and _is_safe_stem(tool_id) \
            and not re.fullmatch(r".*-[0-9a-fA-F]{10}", tool_id):
        assert stem == tool_id  # a plain shop id (EM10-45, T001) is its own file name


@_n(150)
@given(ids=st.lists(tool_ids(), min_size=1, max_size=10))
@example(ids=["../../x", "x-9bdbf20b56"])  # an id equal to another's hashed stem
@example(ids=["EM10", "em10", "Em10"])  # one file on macOS and Windows
def test_tool_file_stems_are_unique_across_a_library_even_ignoring_case(ids):
    ids = set(ids)
    ids |= {f(i) for i in list(ids) for f in (str.lower, str.upper, str.swapcase)}
    ids |= {tool_file_stem(i) for i in list(ids)}  # an id that is another id's file name
    stems = {tool_file_stem(i).casefold() for i in ids}
    assert len(stems) == len(ids)


def test_tool_file_stem_is_the_same_in_another_process():
    code = "import sys\nfrom toolpoint.recommend.library import tool_file_stem as s\n" \
           "print(repr([s(i) for i in eval(sys.stdin.read())]))"
    run = subprocess.run([sys.executable, "-c", code], input=repr(EVIL), capture_output=True, text=True, timeout=120,
                         env={**os.environ, "PYTHONHASHSEED": "12345"})
    assert run.returncode == 0, run.stderr
    assert run.stdout.strip() == repr([tool_file_stem(i) for i in EVIL])


def _neutral(cell: str) -> bool:
    """Not run as a formula by a spreadsheet: no leading = + - @ tab CR, unless it is a number."""
    if not cell.startswith(FORMULA):
        return True
    try:
        float(cell)
        return True
    except ValueError:
        return False


@_n(300)
@given(text=st.one_of(st.text(), st.builds(lambda q, c, s: q + c + s, st.sampled_from(["", "'", "''"]),
                                           st.sampled_from(FORMULA), st.text(max_size=10)),
                      st.floats(allow_nan=True).map(repr), st.sampled_from(EVIL)))
def test_csv_cells_never_formulas_and_read_back_as_written(text):
    cell = csv_safe(text)
    assert _neutral(cell), (text, cell)
    assert csv_unsafe(cell) == text


def _write_library(path: Path, ids, **cells) -> None:
    row = dict(diameter_mm="12", overhang_mm="50", teeth="3", holder="ER40", tangential_coeff_n_mm2="",
               radial_ratio="", material="al7075", radial_immersion="0.5", milling="down", rpm_min="4000",
               rpm_max="20000", **cells)
    with open(path, "w", newline="", encoding="utf-8") as fh:
        w = csv.DictWriter(fh, HEADER)
        w.writeheader()
        for i in ids:
            w.writerow({**row, "id": i})


_OPENED: list | None = None  # paths opened while a test records (sys.addaudithook cannot be removed)
_HOOKED: list = []


def _audit(event, args):
    if _OPENED is not None and event == "open" and isinstance(args[0], (str, bytes, os.PathLike)):
        _OPENED.append(os.fsdecode(args[0]))


@contextlib.contextmanager
def _recording_opens():
    global _OPENED
    if not _HOOKED:
        sys.addaudithook(_audit)
        _HOOKED.append(True)
    _OPENED = []
    try:
        yield _OPENED
    finally:
        _OPENED = None


def _tree(folder: Path) -> set:
    return {p for p in folder.rglob("*")}


@pytest.mark.slow
@_n(3)
@given(ids=st.lists(tool_ids(), min_size=1, max_size=3))
@example(ids=["../../x", "x-9bdbf20b56", "em10", "=cmd|' /C calc'!A0", "CON.x\x00/../" + "z" * 300])
def test_library_writes_only_inside_its_folder_and_report_reads_only_what_it_wrote(seeds, camp, tmp_path, ids):
    """Each example: a library of generated ids, run in-process (tiny settings), then ``report``."""
    from toolpoint.recommend.library import read_library
    from toolpoint.recommend.report import write_report
    from toolpoint.recommend.run import run_library

    root = Path(tempfile.mkdtemp(dir=tmp_path))
    work = root / "a" / "b"
    work.mkdir(parents=True)
    lib = root / "lib.csv"
    _write_library(lib, ids)
    try:
        tools, bad = read_library(lib)
    except InputError:  # e.g. every id blank: nothing to run
        return
    out = work / "out"
    before = _tree(root)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", UserWarning)
        counts = run_library(lib, camp, seeds / "results" / "models", out, workers=1, n_samples=4,
                             rpm_points=8, progress=False)
    assert counts.ok == len(tools) and counts.failed == len(bad)
    new = _tree(root) - before
    assert all(p == out or out in p.parents for p in new), sorted(map(str, new))
    wrote = {p.name for p in (out / "tools").iterdir()}
    assert wrote == {f"{tool_file_stem(t.id)}{ext}" for t in tools for ext in (".npz", ".json")}
    with open(out / "recommendations.csv", newline="", encoding="utf-8") as fh:
        rows = list(csv.reader(fh))
    assert all(_neutral(c) for r in rows for c in r), [c for r in rows for c in r if not _neutral(c)]
    got = [csv_unsafe(r[0]) for r in rows[1:]]
    assert sorted(got) == sorted([t.id for t in tools] + [b.id for b in bad])  # each id once, as it was
    page = out / "report.html"
    allowed = {out / "recommendations.csv", page, *((out / "tools" / n) for n in wrote)}
    with _recording_opens() as opened, warnings.catch_warnings():
        warnings.simplefilter("ignore", UserWarning)
        write_report(out)
    under = {Path(p).resolve() for p in opened if Path(p).resolve().is_relative_to(root.resolve())}
    extra = {p for p in under if p not in {a.resolve() for a in allowed}
             and not (p.parent == page.parent.resolve() and p.name.startswith(".report.html."))}
    assert not extra, sorted(map(str, extra))
    assert "files missing or unreadable" not in page.read_text(encoding="utf-8")


# ---------------------------------------------------------------- a full disk
class Disk:
    """A folder where writes fail with ENOSPC once :meth:`fill` is called.

    ``kind == "tmpfs"``: a 4 MiB tmpfs, filled with a file up to its last byte (the operating system's own error,
    raised by ``write()``/``close()`` with no file name). ``kind == "injected"``: every atomic write of toolpoint (the
    writer of :mod:`toolpoint.io.atomic`, wherever it is imported) raises ``OSError(ENOSPC)`` after its caller wrote
    the temporary file, as a full disk does at ``close()``.
    """

    def __init__(self, path: Path, kind: str):
        self.path, self.kind, self.full = path, kind, False

    def fill(self) -> None:
        self.full = True
        if self.kind != "tmpfs":
            return
        with open(self.path / ".filler", "ab", buffering=0) as fh:
            for size in (65536, 4096, 512, 64, 8, 1):
                with contextlib.suppress(OSError):
                    while True:
                        fh.write(b"\0" * size)

    def free(self) -> None:
        self.full = False
        (self.path / ".filler").unlink(missing_ok=True)

    def files(self) -> set:
        return {p.relative_to(self.path).as_posix() for p in self.path.rglob("*") if p.name != ".filler"}


def _patch_atomic_writers(monkeypatch, disk: Disk) -> None:
    import importlib

    from toolpoint.io import atomic

    for name in ("toolpoint.cli.common", "toolpoint.cli.tap", "toolpoint.cli.modal", "toolpoint.cli.identify",
                 "toolpoint.cli.lobes", "toolpoint.cli.library", "toolpoint.cli.report", "toolpoint.recommend.run",
                 "toolpoint.recommend.report", "toolpoint.io.frf_files"):
        importlib.import_module(name)
    real = atomic.atomic_path

    @contextlib.contextmanager
    def atomic_path(path):
        with real(path) as tmp:
            yield tmp
            if disk.full and Path(path).is_relative_to(disk.path):
                raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC))  # as write()/close() raise it: no file name

    for mod in [m for n, m in list(sys.modules.items()) if n.startswith("toolpoint") and m is not None]:
        if getattr(mod, "atomic_path", None) is real:
            monkeypatch.setattr(mod, "atomic_path", atomic_path)


@pytest.fixture(params=["tmpfs", "injected"])
def disk(request, tmp_path, monkeypatch):
    d = tmp_path / "disk"
    d.mkdir()
    if request.param == "injected":
        _patch_atomic_writers(monkeypatch, disk := Disk(d, "injected"))
        yield disk
        return
    if not sys.platform.startswith("linux") or shutil.which("mount") is None:
        pytest.skip("a tmpfs needs Linux and mount")
    mount = subprocess.run(["mount", "-t", "tmpfs", "-o", "size=4m", "tmpfs", str(d)], capture_output=True, text=True)
    if mount.returncode != 0:
        pytest.skip(f"cannot mount a tmpfs here ({mount.stderr.strip() or 'not root'}): the injected case runs")
    try:
        yield Disk(d, "tmpfs")
    finally:
        subprocess.run(["umount", "-l", str(d)], capture_output=True)


def _snapshot_inputs(paths) -> dict:
    return {p: (p.read_bytes(), p.stat().st_mtime_ns) for p in map(Path, paths) if p.is_file()}


def _main(argv) -> tuple[int, str]:
    err = io.StringIO()
    with redirect_stderr(err), redirect_stdout(io.StringIO()), warnings.catch_warnings():
        warnings.simplefilter("ignore")
        try:
            code = main([str(a) for a in argv])
        except SystemExit as e:
            code = e.code
    return code, err.getvalue()


def _main_out(argv) -> tuple[int, str, str]:
    """Exit code, stdout, stderr of ``toolpoint argv`` run here."""
    out, err = io.StringIO(), io.StringIO()
    with redirect_stderr(err), redirect_stdout(out), warnings.catch_warnings():
        warnings.simplefilter("ignore")
        code = main([str(a) for a in argv])
    return code, out.getvalue(), err.getvalue()


def _one_error_line(text: str) -> str:
    """The one ``error:`` line, last on stderr; no traceback."""
    assert "Traceback" not in text, text
    lines = [s for s in text.splitlines() if s.strip()]
    errors = [s for s in lines if "error:" in s]
    assert len(errors) == 1 and errors[0] == lines[-1], text
    return errors[0]


def _commands(seeds, heavy, d: Path) -> dict:
    lobes = ["lobes", seeds / "tp.csv", "--teeth", "2", "--immersion", "1", "--rpm", "5000:20000", "--rpm-points",
             "40", "--tangential-coeff", "6e8", "--radial-ratio", "0.3"]
    lib = ["library", heavy / "lib.csv", "--campaign", seeds / "camp", "--models", seeds / "results" / "models",
           "--workers", "1", "--samples", "4", "--rpm-points", "8"]
    ok = d.parent / "ok"  # the other output of a --plot case: on a disk with space
    return {  # name: (argv, the file named in the message)
        "tap --out": (["tap", seeds / "rec.csv", "--out", d / "h.csv"], d / "h.csv"),
        "tap --plot": (["tap", seeds / "rec.csv", "--out", ok / "h.csv", "--plot", d / "h.png"], d / "h.png"),
        "modal --out": (["modal", seeds / "tp.csv", "--modes", "2", "--band", "100:2800", "--out", d / "m.csv"],
                        d / "m.csv"),
        "modal --plot": (["modal", seeds / "tp.csv", "--modes", "2", "--band", "100:2800", "--out", ok / "m.csv",
                          "--plot", d / "m.png"], d / "m.png"),
        "identify --out": (["identify", heavy / "a.toml", heavy / "tool.csv", "--method", "hybrid", "--band",
                            "100:2900", "--out", d / "r.json"], d / "r.json"),
        "lobes --out": (lobes + ["--out", d / "l.csv"], d / "l.csv"),
        "lobes --plot": (lobes + ["--out", ok / "l.csv", "--plot", d / "l.png"], d / "l.png"),
        "library": (lib + ["--out", d / "lib"], d / "lib"),
        "report": (["report", heavy / "libout", "--out", d / "r.html"], d / "r.html"),
    }


COMMANDS = ["tap --out", "tap --plot", "modal --out", "modal --plot", "identify --out", "lobes --out", "lobes --plot",
            "library", "report"]


@pytest.mark.parametrize("name", COMMANDS)
def test_a_full_disk_is_one_line_naming_the_file_and_nothing_is_left(seeds, heavy, disk, name,
                                                                      request):
    argv, named = _commands(seeds, heavy, disk.path)[name]
    inputs = _snapshot_inputs([a for a in argv if isinstance(a, Path) and not a.is_relative_to(disk.path)]
                              + [p for p in (heavy / "libout").rglob("*")])
    disk.fill()
    code, err = _main(argv)
    assert code == 2, err
    line = _one_error_line(err)
    assert "No space left on device" in line, line
    ok = disk.path.parent / "ok"
    assert not ok.exists() or not list(ok.iterdir()), list(ok.iterdir())  # exit 2: no other output either
    left = disk.files()
    assert not [f for f in left if ".tmp" in f], left  # no temporary file
    if name == "library":  # its folder and lock may stay (empty), never a table or a tool file
        assert left <= {"lib", "lib/tools", "lib/.toolpoint-run.lock"}, left
        assert not (disk.path / "lib" / "recommendations.csv").exists() or \
            (disk.path / "lib" / "recommendations.csv").read_text().count("\n") <= 1
    else:
        assert not left, left
    assert _snapshot_inputs(inputs) == inputs  # no input overwritten
    assert "file system:" not in line and str(named) in line, line  # names the file, not "the file system"


def _library_args(seeds, camp, lib: Path, out: Path, samples="4", rpm_points="8") -> list:
    return ["library", lib, "--campaign", camp, "--models", seeds / "results" / "models", "--out", out,
            "--workers", "1", "--samples", samples, "--rpm-points", rpm_points]


def _ids_in(table: Path) -> list[str]:
    with open(table, newline="", encoding="utf-8") as fh:
        return [csv_unsafe(r["id"]) for r in csv.DictReader(fh) if r.get("error") is not None]


@pytest.mark.parametrize("at", ["tool files", "row"])
def test_library_filling_the_disk_mid_run_keeps_finished_rows(seeds, camp, tmp_path, disk, monkeypatch,
                                                              request, at):
    """The disk fills while the second of three tools is written (its files, or its row: ids of 5000 characters make
    a row longer than a page, so the append cannot fit in the table's last page): exit 2, one line naming the file,
    the first tool's row and files kept, nothing temporary; a second run (space freed) keeps the first tool and does
    the other two once each (a half-written row is dropped)."""
    from toolpoint.recommend import run as run_mod

    if at == "row":
        if disk.kind != "tmpfs":
            pytest.skip("the row is appended with a plain write: only a real full disk fails it")
    lib = tmp_path / "lib.csv"
    ids = [f"T{k}" + ("x" * 5000 if at == "row" else "") for k in (1, 2, 3)]
    _write_library(lib, ids)
    out = disk.path / "lib"
    real = run_mod._write_tool
    calls = []

    def write_tool(*args, **kwargs):
        calls.append(args[1])
        if len(calls) == 2 and at == "tool files":
            disk.fill()
        real(*args, **kwargs)
        if len(calls) == 2 and at == "row":
            disk.fill()

    monkeypatch.setattr(run_mod, "_write_tool", write_tool)
    code, err = _main(_library_args(seeds, camp, lib, out))
    assert code == 2, err
    line = _one_error_line(err)
    assert "No space left on device" in line, line
    assert not [f for f in disk.files() if ".tmp" in f], disk.files()
    assert _ids_in(out / "recommendations.csv") == ids[:1]  # the finished row, complete
    assert {f"lib/tools/{tool_file_stem(ids[0])}{ext}" for ext in (".npz", ".json")} <= disk.files()
    disk.free()
    monkeypatch.setattr(run_mod, "_write_tool", real)
    code, err2 = _main(_library_args(seeds, camp, lib, out))
    assert code == 0, err2
    assert sorted(_ids_in(out / "recommendations.csv")) == ids  # T1 kept, T2 and T3 once each
    with open(out / "recommendations.csv", encoding="utf-8") as fh:
        assert fh.read().count("\n") == 1 + len(ids)  # no half row left
    named = out / "tools" / f"{tool_file_stem(ids[1])}.npz" if at == "tool files" else out / "recommendations.csv"
    assert "file system:" not in line and str(named) in line, line


# ---------------------------------------------------------------- FRF files cut short
def _frf_seed(kind: str, n: int = 12) -> bytes:
    """A valid FRF file as toolpoint writes it (``frf``: CutPro, ``csv``: with coherence) or as a lab exports it
    (``export``: two FRFs side by side under a header and a unit line, 6 digits)."""
    from test_properties import _small_frf

    from toolpoint.io.frf_files import write_frf

    frf = _small_frf(n)
    with tempfile.TemporaryDirectory() as d:
        if kind == "csv":
            frf.meta["coherence"] = np.linspace(0.9, 1.0, n)
        if kind in ("csv", "frf"):
            write_frf(Path(d) / f"x.{kind}", frf)
            return (Path(d) / f"x.{kind}").read_bytes()
    rows = "".join(f"{f:.6g}\t{h.real * 1e3:.6e}\t{h.imag * 1e3:.6e}\t{f:.6g}\t{2e3 * h.real:.6e}\t{2e3 * h.imag:.6e}\n"
                   for f, h in zip(frf.freq_hz, frf.values))
    return ("Freq\tReal\tImag\tFreq\tReal\tImag\nHz\tmm/N\tmm/N\tHz\tmm/N\tmm/N\n" + rows).encode()


EXT = {"frf": ".frf", "csv": ".csv", "export": ".txt"}


def _data_rows(blob: bytes) -> list[int]:
    """Byte offsets where each data line ends (after its line break)."""
    ends, pos = [], 0
    for line in blob.splitlines(keepends=True):
        pos += len(line)
        if line[:1].isdigit():
            ends.append(pos)
    return ends


@pytest.mark.parametrize("kind", ["frf", "csv", "export"])
@_n(60)
@given(data=st.data())
def test_an_frf_file_cut_anywhere_is_refused_or_read_as_its_complete_lines(tmp_path, kind, data):
    """Refused with the file and a line named, or exactly the lines before the cut. From the end of the second data
    line on: a number cut in the first or second line may have nothing, or one number, to be compared with (numbers
    without an exponent are compared with at least two others, so that a complete hand-written file is not refused)."""
    from toolpoint.io.frf_files import read_frf

    blob = _frf_seed(kind)
    ends = _data_rows(blob)
    full = read_frf(_put(tmp_path / f"full{EXT[kind]}", blob))
    at = data.draw(st.integers(ends[1], len(blob) - 1))
    p = _put(tmp_path / f"cut{EXT[kind]}", blob[:at])
    try:
        got = read_frf(p)
    except InputError as err:
        assert "\n" not in str(err) and str(p) in str(err) and re.search(r"line \d+", str(err)), str(err)
        return
    k = len(got)
    assert k >= 1 and np.array_equal(got.freq_hz, full.freq_hz[:k]), (blob[max(0, at - 40):at], k)
    if kind == "export":  # 6 digits and an exponent everywhere: any cut inside a line shows (the columns not read too)
        assert at in ends or blob[at:at + 1] in (b"\r", b"\n"), blob[max(0, at - 40):at]
    np.testing.assert_allclose(got.values, full.values[:k], rtol=1e-15, atol=0)
    if "coherence" in full.meta:
        np.testing.assert_allclose(got.meta["coherence"], full.meta["coherence"][:k], rtol=1e-15)


@pytest.mark.parametrize("text, line", [
    pytest.param("100\t1.5e-08\t-1.5e-09\n200\t2.5e-08\t-2.5e-0", 2, id="2-lines-exponent"),
    pytest.param("100\t1.5e-08\t-1.5e-09\n200\t2.5e-08\t-2.5", 2, id="2-lines-mantissa"),
    pytest.param("Freq\tReal\tImag\tFreq\tReal\tImag\n100\t1e-08\t-1e-09\t100\t2e-08\t-2e-09\n"
                 "200\t1e-08\t-1e-09\t200\t2e-08\t-2e-0", 3, id="a-column-not-read"),
    pytest.param("Freq\tReal\tImag\tFreq\tReal\tImag\n100\t1e-08\t-1e-09\t100\t2e-08\t-2e-09\n"
                 "200\t1e-08\t-1e-09\t200\t2", 3, id="ragged"),
])
def test_cuts_the_reader_took_before(tmp_path, text, line):
    """Accepted before issue 22: the cut number of a file of two lines, the columns of an export that are not read."""
    from toolpoint.io.frf_files import read_frf

    p = _put(tmp_path / "cut.frf", text.encode())
    with pytest.raises(InputError, match=rf"cut\.frf: \w+: line {line}: .*end it with a line break"):
        read_frf(p)
    _put(p, (text + "\n").encode())  # ended by a line break: taken as written
    assert len(read_frf(p)) == 2


def _put(path: Path, blob: bytes) -> Path:
    path.write_bytes(blob)
    return path


def _cut(blob: bytes, how: str) -> bytes:
    """``half``: at half its bytes (moved off a line break); ``number``: inside the last number of the line at the
    middle; ``no-newline``: the complete file without its last line break."""
    if how == "no-newline":
        return blob.rstrip(b"\r\n")
    at = len(blob) // 2
    if how == "number":
        at = blob.index(b"\n", at) - 4  # "…e-0|9": the exponent loses a digit
    while blob[at - 1:at] in (b"\n", b"\t", b","):
        at += 1
    return blob[:at]


@pytest.mark.parametrize("how", ["half", "number", "no-newline"])
@pytest.mark.parametrize("kind", ["frf", "csv"])
@pytest.mark.parametrize("command", ["lobes", "modal", "identify"])
def test_commands_refuse_an_frf_cut_short_with_one_line(heavy, tmp_path, command, kind, how):
    """The tool-point FRF of the coarse assembly (150 points), cut: exit 2, one line naming the file and the line,
    nothing written; complete but without its last line break: read (exit 0)."""
    from toolpoint.io.frf_files import read_frf, write_frf

    src = tmp_path / f"tp.{kind}"
    write_frf(src, read_frf(heavy / "tool.csv"))
    p = _put(tmp_path / f"cut.{kind}", _cut(src.read_bytes(), how))
    out = tmp_path / "out"
    out.mkdir()
    argv = {"lobes": ["lobes", p, "--teeth", "2", "--immersion", "1", "--rpm", "5000:20000", "--rpm-points", "30",
                      "--tangential-coeff", "6e8", "--radial-ratio", "0.3", "--out", out / "l.csv"],
            "modal": ["modal", p, "--modes", "2", "--band", "100:2900", "--out", out / "m.csv"],
            "identify": ["identify", heavy / "a.toml", p, "--method", "hybrid", "--band", "100:2900", "--out",
                         out / "r.json"]}[command]
    before = _snapshot_inputs([p])
    if how == "no-newline" and command == "identify":
        pytest.skip("identify of a complete FRF: the identify tests (a few seconds)")
    code, err = _main(argv)
    assert _snapshot_inputs([p]) == before
    if how == "no-newline":
        assert code in (0, 1), err
        return
    assert code == 2, err
    line = _one_error_line(err)
    assert str(p) in line and re.search(r"line \d+", line), line
    assert not list(out.iterdir())


# ---------------------------------------------------------------- SIGTERM
@pytest.mark.slow
@pytest.mark.skipif(sys.platform == "win32", reason="SIGTERM")
def test_library_killed_with_sigterm_resumes_keeping_its_rows(seeds, camp, tmp_path):
    from toolpoint.campaign.run import folder_lock

    ids = [f"T{k:02d}" for k in range(8)]
    lib = tmp_path / "lib.csv"
    _write_library(lib, ids)
    out = tmp_path / "out"
    argv = [str(a) for a in _library_args(seeds, camp, lib, out, samples="200", rpm_points="600")]  # ~0.5 s a tool
    proc = subprocess.Popen([sys.executable, "-m", "toolpoint.cli.main", *argv], stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE, text=True)
    table = out / "recommendations.csv"
    try:
        deadline = time.time() + 120
        while time.time() < deadline and proc.poll() is None:
            if table.exists() and len(_ids_in(table)) >= 1:
                break
            time.sleep(0.02)
        assert proc.poll() is None, "the run ended before it could be killed: make the fixture bigger"
        proc.send_signal(signal.SIGTERM)
        _, err = proc.communicate(timeout=60)
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.wait()
    assert proc.returncode == 143, err
    assert "Traceback" not in err, err
    done = _ids_in(table)
    assert 1 <= len(done) < len(ids) and len(set(done)) == len(done)
    assert not [p for p in out.rglob("*") if ".tmp" in p.name]
    assert all((out / "tools" / f"{tool_file_stem(i)}.npz").exists() for i in done)
    with folder_lock(out, "library run"):  # released: a second run may start
        pass
    code, said, err = _main_out(_library_args(seeds, camp, lib, out))  # the rest cheaply: kept rows are not recomputed
    assert code == 0, err
    assert f"{len(ids) - len(done)} tools ok, 0 failed, {len(done)} already done" in said, said
    again = _ids_in(table)
    assert again[:len(done)] == done and sorted(again) == ids  # the finished rows kept, the rest once each
