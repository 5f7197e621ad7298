"""``toolpoint simulate`` and ``toolpoint map``: outputs written, bad input one line and exit 2 with nothing written."""

import json

import numpy as np
import pytest
import soundfile

from toolpoint.cli.main import main

BASE = ["--mode-x", "922:1.34e6:0.011", "--teeth", "2", "--tangential-coeff", "6e8", "--radial-ratio", "0.3333",
        "--immersion", "1"]


@pytest.mark.slow  # matplotlib's import and a PNG: ≈ 3–4 s on a shared machine
def test_simulate_writes_json_plot_audio(tmp_path, capsys):
    out, fig, wav = tmp_path / "r.json", tmp_path / "r.png", tmp_path / "r.wav"
    code = main(["simulate", *BASE, "--rpm", "10000", "--depth-mm", "0.2", "--revolutions", "8",
                 "--out", str(out), "--plot", str(fig), "--audio", str(wav), "--rate", "20000"])
    assert code == 0
    data = json.loads(out.read_text())
    assert data["stable"] is True and data["chatter_hz"] is None
    assert fig.stat().st_size > 1000
    x, rate = soundfile.read(wav)
    assert rate == 20000 and x.size > 100 and np.max(np.abs(x)) <= 0.91
    assert "stable at 10000 rpm" in capsys.readouterr().out


def test_simulate_with_force_noise_keeps_the_noise_free_verdict(tmp_path, capsys):
    # the Insperger–Stépán example at 0.2 mm (its SDM limit at 10000 rpm is 0.32 mm): stable with and without the
    # noise; the force history differs by it
    outs = {}
    for fn in ("0", "0.05"):
        out = tmp_path / f"r{fn}.csv"
        assert main(["simulate", *BASE, "--rpm", "10000", "--depth-mm", "0.2", "--revolutions", "12",
                     "--force-noise", fn, "--out", str(out)]) == 0
        assert "stable at 10000 rpm" in capsys.readouterr().out
        outs[fn] = np.genfromtxt(out, delimiter=",", names=True)
    f0, f1 = outs["0"]["fx_n"], outs["0.05"]["fx_n"]
    cut = np.abs(f0) > 1e-3 * np.abs(f0).max()
    assert 0.02 < np.std(f1[cut] / f0[cut] - 1) < 0.5


def test_simulate_csv_histories(tmp_path):
    out, audio = tmp_path / "r.csv", tmp_path / "a.csv"
    assert main(["simulate", *BASE, "--rpm", "10000", "--depth-mm", "0.2", "--revolutions", "8",
                 "--out", str(out), "--audio", str(audio), "--sensor", "accelerometer"]) == 0
    head = out.read_text().splitlines()[0]
    assert head == "t_s,x_m,y_m,fx_n,fy_n"
    assert audio.read_text().startswith("t_s,value\n")


def test_simulate_bad_input_one_line_exit_2_nothing_written(tmp_path, capsys):
    out = tmp_path / "r.json"
    bad = [
        (["--teeth", "0"], "--teeth"),
        (["--depth-mm", "-1"], "--depth-mm"),
        (["--steps-per-tooth", "8", "--substeps", "1"], "--substeps"),
        (["--mode-x", "922:0:0.01"], "--mode-x"),
        (["--force-noise", "0.5"], "--force-noise"),
        (["--force-noise", "-0.1"], "--force-noise"),
    ]
    for extra, flag in bad:
        args = ["simulate", *BASE, "--rpm", "10000", "--depth-mm", "0.2", "--out", str(out)]
        for i in range(0, len(extra), 2):
            if extra[i] in args and extra[i] != "--mode-x":
                args[args.index(extra[i]) + 1] = extra[i + 1]
            elif extra[i] == "--mode-x":
                args[args.index("--mode-x") + 1] = extra[i + 1]
            else:
                args += extra[i: i + 2]
        assert main(args) == 2
        err = capsys.readouterr().err
        assert err.count("\n") == 1 and flag in err, err
        assert not out.exists()


def test_simulate_no_mode(tmp_path, capsys):
    modal = tmp_path / "m.toml"
    modal.write_text("modes_x = []\n")
    args = ["simulate", *BASE[2:], "--modal", str(modal), "--rpm", "1e4", "--depth-mm", "0.1",
            "--out", str(tmp_path / "r.json")]
    assert main(args) == 2
    assert "no mode" in capsys.readouterr().err
    assert not (tmp_path / "r.json").exists()


@pytest.mark.slow
def test_map_writes_csv_and_plot_from_modal_file(tmp_path, capsys):
    modal = tmp_path / "m.json"
    modal.write_text(json.dumps({"modes_x": [{"fn_hz": 922.0, "k_n_per_m": 1.34e6, "zeta": 0.011}]}))
    out, fig, lobes = tmp_path / "map.csv", tmp_path / "map.png", tmp_path / "lobes.csv"
    code = main(["map", *BASE[2:], "--modal", str(modal), "--rpm", "8000:16000", "--rpm-points", "5",
                 "--depth-mm", "0.1:1", "--depth-points", "4", "--revolutions", "16", "--out", str(out),
                 "--plot", str(fig), "--lobes-out", str(lobes)])
    assert code == 0, capsys.readouterr().err
    rows = np.genfromtxt(out, delimiter=",", names=True)
    assert rows.size == 20 and set(np.unique(rows["stable"])) <= {0, 1}
    assert rows["stable"][rows["depth_mm"] == 0.1].all()  # far below every limit
    assert not rows["stable"][rows["depth_mm"] == 1.0].all()
    assert fig.stat().st_size > 1000 and lobes.read_text().startswith("rpm,depth_mm,chatter_hz\n")


def test_map_bad_range(tmp_path, capsys):
    out = tmp_path / "map.csv"
    assert main(["map", *BASE, "--rpm", "16000:8000", "--depth-mm", "0.1:1", "--out", str(out)]) == 2
    err = capsys.readouterr().err
    assert "--rpm" in err and err.count("\n") == 1 and not out.exists()
