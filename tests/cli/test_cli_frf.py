"""`toolpoint frf`: output, plot, and one-line errors for bad assembly files."""

import re

import numpy as np
import pytest

from toolpoint.cli.main import main
from toolpoint.io.frf_files import read_csv_frf


def test_frf_csv_and_plot(tmp_path, example_path):
    out, png = tmp_path / "frf.csv", tmp_path / "frf.png"
    assert main(["frf", str(example_path), "--out", str(out), "--plot", str(png)]) == 0
    assert out.read_text().splitlines()[0] == "freq_hz,real,imag"
    frf = read_csv_frf(out)
    assert frf.freq_hz[0] == 0 and frf.freq_hz[-1] == 3000 and len(frf) == 3001
    assert np.all(np.isfinite(frf.values))
    assert png.read_bytes()[:4] == b"\x89PNG"


def test_spindle_holder_point(tmp_path, example_path):
    out = tmp_path / "sh.csv"
    assert main(["frf", str(example_path), "--point", "spindle_holder", "--out", str(out)]) == 0
    sh = read_csv_frf(out)
    assert sh.freq_hz[0] == 0 and np.all(np.isfinite(sh.values))


BASE = (
    "[spindle]\n"
    "segments = [{ length_mm = 300, od_mm = 70, id_mm = 20 }]\n"
    "bearings = [{ x_mm = 50, k = 2e8, c = 1000 }, { x_mm = 250, k = 3e8, c = 2000 }]\n"
    "[holder]\nsegments = [{ length_mm = 60, od_mm = 40 }]\n"
    "[tool]\nsegments = [{ length_mm = 50, od_mm = 12 }]\n"
    "[joints.spindle_holder]\nkt = 5e8\nct = 300.0\nkr = 1.5e7\ncr = 50.0\n"
    "[joints.holder_tool]\nkt = 2.1e7\nct = 15.0\nkr = 1.4e6\ncr = 3.0\n"
)

BAD = {
    "malformed": ("[spindle\n", "syntax"),
    "missing section": (BASE.replace("[holder]\nsegments = [{ length_mm = 60, od_mm = 40 }]\n", ""), "holder"),
    "zero length": (BASE.replace("length_mm = 60", "length_mm = 0"), "holder.segments[0].length_mm"),
    "negative diameter": (BASE.replace("od_mm = 12", "od_mm = -12"), "tool.segments[0].od_mm"),
    "id >= od": (BASE.replace("od_mm = 70, id_mm = 20", "od_mm = 70, id_mm = 70"), "spindle.segments[0].id_mm"),
    "bearing outside": (BASE.replace("x_mm = 250", "x_mm = 350"), "spindle.bearings[1].x_mm"),
    "unknown material": (BASE.replace("od_mm = 40 }", "od_mm = 40, material = \"unobtainium\" }"),
                         "holder.segments[0].material"),
    "stop <= start": ("[frequency]\nstart_hz = 100\nstop_hz = 50\n" + BASE, "frequency.stop_hz"),
    "step <= 0": ("[frequency]\nstep_hz = 0\n" + BASE, "frequency.step_hz"),
    "text as number": (BASE.replace("kt = 5e8", 'kt = "stiff"'), "joints.spindle_holder.kt"),
}


@pytest.mark.parametrize("case", sorted(BAD))
def test_bad_assembly_is_one_line_exit_2_no_output(case, tmp_path, capsys):
    text, field = BAD[case]
    src = tmp_path / "bad.toml"
    src.write_text(text)
    out, png = tmp_path / "o.csv", tmp_path / "o.png"
    assert main(["frf", str(src), "--out", str(out), "--plot", str(png)]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1
    assert str(src) in err and field in err, err
    assert "Traceback" not in err
    assert not out.exists() and not png.exists()
    assert not [p for p in tmp_path.iterdir() if p.name.startswith(".o.")]  # no temporary left


def test_good_base_runs(tmp_path):
    src = tmp_path / "ok.toml"
    src.write_text(BASE)
    assert main(["frf", str(src), "--out", str(tmp_path / "o.csv")]) == 0


def test_missing_file(tmp_path, capsys):
    assert main(["frf", str(tmp_path / "nope.toml"), "--out", str(tmp_path / "o.csv")]) == 2
    assert re.search(r"nope\.toml: file not found", capsys.readouterr().err)


def test_output_format_follows_the_extension(tmp_path, example_path, capsys):
    from toolpoint.io.frf_files import read_frf

    uff = tmp_path / "frf.uff"
    assert main(["frf", str(example_path), "--out", str(uff)]) == 0
    csv_ = tmp_path / "frf.csv"
    assert main(["frf", str(example_path), "--out", str(csv_)]) == 0
    a, b = read_frf(uff), read_csv_frf(csv_)
    assert np.allclose(a.values, b.values, rtol=5e-12, atol=0)  # UFF58 ASCII keeps 12 digits
    bad = tmp_path / "frf.xyz"
    assert main(["frf", str(example_path), "--out", str(bad)]) == 2
    assert "--out" in capsys.readouterr().err and not bad.exists()


def test_grids_and_segment_counts_are_bounded_before_allocating(tmp_path, example_path):
    from toolpoint.dynamics.assembly import MAX_FREQUENCIES, MAX_SEGMENTS, parse_assembly
    from toolpoint.errors import InputError
    from toolpoint.io.toml import load_toml

    doc = load_toml(example_path)
    doc["frequency"]["step_hz"] = 3000.0 / (MAX_FREQUENCIES + 10)
    with pytest.raises(InputError, match="frequency.step_hz: .*at most 1,000,000"):
        parse_assembly(doc, "a.toml")
    doc = load_toml(example_path)
    doc["tool"]["segments"] = [{"length_mm": 0.01, "od_mm": 16}] * (MAX_SEGMENTS + 1)
    with pytest.raises(InputError, match="tool.segments: .* at most"):
        parse_assembly(doc, "a.toml")
