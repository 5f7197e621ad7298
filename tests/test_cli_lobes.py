"""``toolpoint lobes`` end to end."""

import csv

import numpy as np
import pytest

from toolpoint.cli.main import main
from toolpoint.stability import ModalModel

MODE = ModalModel([922.0], [0.011], [0.03993])
BASE = ["--teeth", "2", "--kt", "6e8", "--kr", "0.3333333333333333", "--immersion", "1", "--rpm", "5000:25000"]


def write_csv(path, freq, values, header="freq_hz,real,imag"):
    with open(path, "w") as fh:
        fh.write(header + "\n")
        np.savetxt(fh, np.column_stack([freq, values.real, values.imag]), delimiter=",", fmt="%.17g")
    return path


@pytest.fixture
def frf_files(tmp_path):
    f = np.linspace(0.0, 3000.0, 3001)
    x = write_csv(tmp_path / "x.csv", f, MODE.frf(f).values)
    rigid = write_csv(tmp_path / "rigid.csv", f, np.zeros(f.size, complex))
    return x, rigid


def read(path):
    with open(path, newline="") as fh:
        rows = list(csv.reader(fh))
    return rows[0], np.array(rows[1:], dtype=float)


def test_zoa_end_to_end(tmp_path, frf_files, capsys):
    x, rigid = frf_files
    out, all_, png = tmp_path / "lobes.csv", tmp_path / "all.csv", tmp_path / "lobes.png"
    code = main(["lobes", str(x), "--frf-y", str(rigid), *BASE, "--rpm-points", "400",
                 "--out", str(out), "--lobes-out", str(all_), "--plot", str(png)])
    assert code == 0
    header, data = read(out)
    assert header[:2] == ["rpm", "depth_mm"] and header == ["rpm", "depth_mm", "chatter_hz"]
    assert data.shape == (400, 3)
    assert data[0, 0] == 5000 and data[-1, 0] == 25000
    assert data[:, 1].min() == pytest.approx(0.298, abs=0.001)  # mm: the benchmark's closed form
    header, lobes = read(all_)
    assert header == ["lobe", "rpm", "depth_mm", "chatter_hz", "branch"]
    assert set(lobes[:, 0].astype(int)) >= {1, 2, 3}
    assert png.stat().st_size > 10_000 and png.read_bytes()[:4] == b"\x89PNG"
    text = capsys.readouterr().out
    assert "absolute minimum depth: 0.298 mm" in text
    assert "best stable pocket:" in text


def test_symmetric_default_and_up_milling(tmp_path, frf_files, capsys):
    x, _ = frf_files
    out = tmp_path / "l.csv"
    assert main(["lobes", str(x), *BASE[:-4], "--immersion", "0.5", "--up", "--rpm", "3000:9000",
                 "--rpm-points", "50", "--out", str(out)]) == 0
    header, data = read(out)
    assert data.shape == (50, 3) and np.all(data[:, 1] > 0)


def test_sdm_end_to_end(tmp_path, frf_files, capsys):
    x, _ = frf_files
    out, png = tmp_path / "sdm.csv", tmp_path / "sdm.svg"
    code = main(["lobes", str(x), *BASE[:-4], "--immersion", "0.05", "--rpm", "14000:20000", "--rpm-points", "25",
                 "--method", "sdm", "--modes", "1", "--out", str(out), "--plot", str(png)])
    assert code == 0
    text = capsys.readouterr().out
    assert "922.00" in text and "fit error" in text  # the fitted modes are printed
    header, data = read(out)
    assert header == ["rpm", "depth_mm", "chatter_hz"] and data.shape == (25, 3)
    assert png.read_text().lstrip().startswith("<?xml")


def test_assembly_toml_input(tmp_path, example_path, capsys):
    out = tmp_path / "t.csv"
    code = main(["lobes", str(example_path), "--teeth", "4", "--kt", "8e8", "--kr", "0.3", "--immersion", "0.5",
                 "--rpm", "5000:30000", "--rpm-points", "200", "--out", str(out)])
    assert code == 0
    _, data = read(out)
    assert np.all(np.isfinite(data[:, 1])) and data[:, 1].min() > 0


@pytest.mark.parametrize(
    "change",
    [
        ["--teeth", "0"],
        ["--teeth", "-2"],
        ["--teeth", "two"],
        ["--kt", "0"],
        ["--kt", "-6e8"],
        ["--immersion", "0"],
        ["--immersion", "1.5"],
        ["--rpm", "20000:2000"],
        ["--rpm", "2000"],
        ["--rpm-points", "1"],
        ["--method", "fem"],
    ],
)
def test_bad_options(tmp_path, frf_files, capsys, change):
    x, _ = frf_files
    args = dict(zip(BASE[::2], BASE[1::2]))
    args[change[0]] = change[1]
    out, png = tmp_path / "o.csv", tmp_path / "o.png"
    argv = ["lobes", str(x), *[f"{k}={v}" for k, v in args.items()], "--out", str(out), "--plot", str(png)]
    if change[0] not in args:
        argv += [f"{change[0]}={change[1]}"]
    assert main(argv) == 2
    err = capsys.readouterr().err
    assert len(err.strip().splitlines()) == 1 and change[0] in err
    assert not out.exists() and not png.exists()
    assert {p.name for p in tmp_path.iterdir()} == {"x.csv", "rigid.csv"}  # no temporary files left either


@pytest.mark.parametrize(
    "make",
    [
        lambda d: write_csv(d / "bad.csv", np.arange(5.0), np.ones(5, complex), header="f,re,im"),
        lambda d: d / "missing.csv",
        lambda d: (d / "x.txt").write_text("hello") and d / "x.txt",
    ],
)
def test_wrong_frf_file(tmp_path, capsys, make):
    bad = make(tmp_path)
    out = tmp_path / "o.csv"
    assert main(["lobes", str(bad), *BASE, "--out", str(out), "--lobes-out", str(tmp_path / "a.csv")]) == 2
    err = capsys.readouterr().err
    assert len(err.strip().splitlines()) == 1 and str(bad.name) in err
    assert not out.exists() and not (tmp_path / "a.csv").exists()
