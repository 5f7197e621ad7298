"""`toolpoint anfis train|predict` end to end (CSV in, model/plots/CSV out)."""

import csv
import re

import numpy as np
import pytest

import toolpoint.cli.main as cli_main
from toolpoint.errors import InputError
from toolpoint.learning.anfis import ANFIS


def run(argv, capsys):
    """Through the real dispatcher (InputError → exit 2); it imports only the command it runs."""
    code = cli_main.main([str(a) for a in argv])
    out, err = capsys.readouterr()
    return code, out, err


def write_csv(path, header, rows):
    with open(path, "w", newline="") as fh:
        w = csv.writer(fh)
        w.writerow(header)
        w.writerows(rows)
    return path


def stiffness_rows(n, seed):
    rng = np.random.default_rng(seed)
    d = rng.uniform(6, 25, n)
    L = rng.uniform(30, 120, n)
    kt = 1e7 * (d / 10) ** 2.5 * (60 / L) ** 1.5
    return [[f"T{k}", a, b, c] for k, (a, b, c) in enumerate(zip(d, L, kt))]


HEADER = ["tool", "diameter_mm", "overhang_mm", "kt"]
TRAIN = ["anfis", "train", None, "--inputs", "diameter_mm,overhang_mm", "--target", "kt", "--mfs", "3,4",
         "--mf", "gauss"]


@pytest.fixture
def data(tmp_path):
    return write_csv(tmp_path / "data.csv", HEADER, stiffness_rows(60, 0))


def test_train_and_predict(tmp_path, data, capsys):
    model, plots = tmp_path / "model.json", tmp_path / "plots"
    argv = TRAIN[:2] + [data] + TRAIN[3:]
    argv += ["--epochs", 20, "--test-fraction", 0.25, "--seed", 1, "--out", model, "--plots", plots]
    code, out, err = run(argv, capsys)
    assert code == 0, err
    for word in ("NRMSE", "AFV", "MAPE %", "max APE %", "train", "test", "12 rules"):
        assert word in out
    test_line = [line for line in out.splitlines() if line.startswith("test")][0]
    assert test_line.split()[1] == "15"  # 25 % of 60
    names = sorted(p.name for p in plots.iterdir())
    assert names == sorted(
        ["membership_functions.png"]
        + [f"{kind}_{s}.png" for kind in ("predicted_vs_target", "regression") for s in ("train", "test")]
    )
    assert all((plots / n).read_bytes()[:4] == b"\x89PNG" for n in names)
    m = ANFIS.load(model)
    assert m.input_names_ == ["diameter_mm", "overhang_mm"] and m.target_name_ == "kt" and m.n_mfs_ == (3, 4)

    new = write_csv(tmp_path / "new.csv", ["overhang_mm", "diameter_mm"], [[50.0, 10.0], [80.0, 20.0]])
    pred = tmp_path / "pred.csv"
    code, out, err = run(["anfis", "predict", model, new, "--out", pred], capsys)
    assert code == 0, err
    with open(pred, newline="") as fh:
        rows = list(csv.reader(fh))
    assert rows[0] == ["diameter_mm", "overhang_mm", "kt"]
    got = np.array(rows[1:], dtype=float)
    np.testing.assert_array_equal(got[:, :2], [[10.0, 50.0], [20.0, 80.0]])
    np.testing.assert_array_equal(got[:, 2], m.predict(got[:, :2]))  # full precision written


def test_separate_test_file_and_log_target(tmp_path, data, capsys):
    test = write_csv(tmp_path / "test.csv", HEADER, stiffness_rows(10, 5))
    model = tmp_path / "m.json"
    argv = TRAIN[:2] + [data] + TRAIN[3:] + ["--epochs", 5, "--test", test, "--log-target", "--out", model]
    code, out, err = run(argv, capsys)
    assert code == 0, err
    assert "log10" in out
    test_line = [line for line in out.splitlines() if line.startswith("test")][0]
    assert test_line.split()[1] == "10"
    assert ANFIS.load(model).log_target is True


def test_missing_column_exit_2_nothing_written(tmp_path, data, capsys):
    model, plots = tmp_path / "model.json", tmp_path / "plots"
    argv = ["anfis", "train", data, "--inputs", "diameter_mm,length", "--target", "kt", "--out", model,
            "--plots", plots]
    code, out, err = run(argv, capsys)
    assert code == 2
    assert len(err.strip().splitlines()) == 1
    assert str(data) in err and "length" in err and "no such column" in err
    assert not model.exists() and not plots.exists()


@pytest.mark.parametrize("bad,what", [("nan", "not a finite number"), ("", "not a number"), ("abc", "not a number"),
                                      ("1e300", "beyond ±1e+100")])
def test_bad_cell_exit_2(tmp_path, capsys, bad, what):
    rows = stiffness_rows(20, 0)
    rows[4][2] = bad
    data = write_csv(tmp_path / "d.csv", HEADER, rows)
    model = tmp_path / "m.json"
    code, _, err = run(TRAIN[:2] + [data] + TRAIN[3:] + ["--out", model], capsys)
    assert code == 2 and what in err and "overhang_mm" in err and "line 6" in err
    assert not model.exists()


def test_missing_file_and_bad_options_exit_2(tmp_path, data, capsys):
    model = tmp_path / "m.json"
    code, _, err = run(TRAIN[:2] + [tmp_path / "nope.csv"] + TRAIN[3:] + ["--out", model], capsys)
    assert code == 2 and "nope.csv" in err and "not found" in err
    code, _, err = run(TRAIN[:2] + [data] + TRAIN[3:7] + ["--mfs", "3,1", "--out", model], capsys)
    assert code == 2 and "--mfs" in err
    code, _, err = run(TRAIN[:2] + [data] + TRAIN[3:] + ["--test-fraction", "1.5", "--out", model], capsys)
    assert code == 2 and "--test-fraction" in err
    const = write_csv(tmp_path / "c.csv", HEADER, [[f"T{k}", 10.0, 30.0 + k, 1e7 + k] for k in range(10)])
    code, _, err = run(TRAIN[:2] + [const] + TRAIN[3:] + ["--out", model], capsys)
    assert code == 2 and "diameter_mm" in err and "constant" in err
    code, _, err = run(TRAIN[:2] + [data] + TRAIN[3:] + ["--out", tmp_path], capsys)
    assert code == 2 and "is a folder" in err
    assert not model.exists()


def test_predict_errors_exit_2(tmp_path, data, capsys):
    model, pred = tmp_path / "m.json", tmp_path / "p.csv"
    assert run(TRAIN[:2] + [data] + TRAIN[3:] + ["--epochs", 2, "--out", model], capsys)[0] == 0
    partial = write_csv(tmp_path / "x.csv", ["diameter_mm"], [[10.0]])
    code, _, err = run(["anfis", "predict", model, partial, "--out", pred], capsys)
    assert code == 2 and "overhang_mm" in err and "x.csv" in err
    junk = tmp_path / "junk.json"
    junk.write_text("{not json")
    code, _, err = run(["anfis", "predict", junk, data, "--out", pred], capsys)
    assert code == 2 and "junk.json" in err
    code, _, err = run(["anfis", "predict", tmp_path / "none.json", data, "--out", pred], capsys)
    assert code == 2 and "not found" in err
    assert not pred.exists()


# ---------------------------------------------------------------- issue 13: bad models, failed plots, wild values
@pytest.fixture
def model_doc(tmp_path, data, capsys):
    import json

    model = tmp_path / "good.json"
    assert run(TRAIN[:2] + [data] + TRAIN[3:] + ["--epochs", 2, "--out", model], capsys)[0] == 0
    return json.loads(model.read_text())


@pytest.mark.parametrize("key, value, field", [
    ("history", [1], "history"),
    ("history", {"train_rmse": "abc"}, "history.train_rmse"),
    ("best_epoch", -3, "best_epoch"),
    ("premise", [[1, 2]], "premise"),
    ("consequents", [[1e400]], "consequents"),
    ("n_mfs", [3, 10**400], "n_mfs"),
    ("params", [1], "params"),
    ("target_name", {"a": 1}, "target_name"),
])
def test_a_malformed_model_is_one_line_naming_the_field(tmp_path, data, model_doc, capsys, key, value, field):
    import json

    model_doc[key] = value
    bad = tmp_path / "bad.json"
    bad.write_text(json.dumps(model_doc).replace("Infinity", "1e400"))
    with pytest.raises(InputError, match=rf"bad\.json: {re.escape(field)}: "):
        ANFIS.load(bad)
    pred = tmp_path / "p.csv"
    code, _, err = run(["anfis", "predict", bad, data, "--out", pred], capsys)
    assert code == 2 and len(err.strip().splitlines()) == 1 and f"bad.json: {field}: " in err
    assert not pred.exists()


def test_failed_plots_leave_no_model_and_no_plots(tmp_path, data, capsys, monkeypatch):
    # running as root, a read-only folder is still writable: the failure is made in the plot writer itself
    import toolpoint.cli.anfis as cli_anfis

    calls = []

    def failing_save(fig, path, dpi=120):
        calls.append(path)
        if len(calls) == 3:
            raise OSError(30, "Read-only file system")
        real_save(fig, path, dpi)

    real_save = cli_anfis.save_png
    monkeypatch.setattr(cli_anfis, "save_png", failing_save)
    model, plots = tmp_path / "m.json", tmp_path / "plots"
    argv = TRAIN[:2] + [data] + TRAIN[3:] + ["--epochs", 2, "--test-fraction", 0.25, "--out", model, "--plots", plots]
    code, _, err = run(argv, capsys)
    assert code == 2 and "--plots" in err and "Read-only" in err and len(err.strip().splitlines()) == 1
    assert len(calls) == 3 and not model.exists() and not plots.exists()


def test_predict_far_outside_the_training_range_is_refused(tmp_path, data, capsys):
    model, pred = tmp_path / "m.json", tmp_path / "p.csv"
    assert run(TRAIN[:2] + [data] + TRAIN[3:] + ["--epochs", 2, "--out", model], capsys)[0] == 0
    far = write_csv(tmp_path / "far.csv", ["diameter_mm", "overhang_mm"], [[10.0, 50.0], [1e300, 1e300]])
    code, _, err = run(["anfis", "predict", model, far, "--out", pred], capsys)
    assert code == 2 and "far.csv: diameter_mm: line 3: '1e+300' is beyond ±1e+100" in err
    assert "Warning" not in err and not pred.exists()
    edge = write_csv(tmp_path / "edge.csv", ["diameter_mm", "overhang_mm"], [[10.0, 50.0], [1e100, -1e100]])
    code, out, err = run(["anfis", "predict", model, edge, "--out", pred], capsys)  # extrapolates, finitely
    assert code == 0 and "outside the training input range" in out and "Warning" not in err
    assert np.all(np.isfinite(np.loadtxt(pred, delimiter=",", skiprows=1)))


def test_a_step_size_beyond_the_inputs_span_is_refused(tmp_path, data, capsys):
    model = tmp_path / "m.json"
    code, _, err = run(TRAIN[:2] + [data] + TRAIN[3:] + ["--step-size", "1e300", "--out", model], capsys)
    assert code == 2 and "--step-size" in err and "span" in err and not model.exists()
