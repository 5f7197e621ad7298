"""Fixtures of the property and fault tests (``test_properties``, ``test_faults``): valid inputs of every format
and of the heavier commands, built once per session (per pytest worker) — as module fixtures each of the two modules
built its own on each worker. A plugin (``pytest_plugins`` in ``tests/conftest.py``), so that both modules share one
definition: a second ``conftest.py`` here would clash with the top one by module name (every test folder is on
``sys.path``)."""
import io
from contextlib import redirect_stdout
from pathlib import Path

import numpy as np
import pytest

ROOT = Path(__file__).resolve().parents[2]


@pytest.fixture(scope="session")
def seeds(tmp_path_factory):
    """Valid seed files of every format, written once."""
    import tap_synth
    from test_properties import _small_frf

    from toolpoint.campaign.results import Appender, new_row, resume
    from toolpoint.campaign.synth import synthesise
    from toolpoint.cli.main import main
    from toolpoint.io.frf_files import write_frf
    from toolpoint.learning.anfis import ANFIS

    d = tmp_path_factory.mktemp("seeds")
    frf = _small_frf()
    frf.meta["coherence"] = np.linspace(0.9, 1.0, len(frf))
    for ext in ("csv", "frf", "uff"):
        write_frf(d / f"tp.{ext}", frf)
    (d / "tp.txt").write_text("Freq\tReal\tImag\n" + (d / "tp.frf").read_text())
    t, force, acc = tap_synth.record(fs=6400.0, hits=((0.05, 100.0), (0.45, 90.0)), double=None, duration=0.8)
    np.savetxt(d / "rec.csv", np.column_stack([t, force, acc]), delimiter=",", header="time_s,force_n,acc",
               comments="")
    rng = np.random.default_rng(0)
    x = rng.uniform(0, 1, (30, 2))
    y = 1 + x[:, 0] + x[:, 1] ** 2
    np.savetxt(d / "anfis.csv", np.column_stack([x, y]), delimiter=",", header="a,b,y", comments="", fmt="%.6g")
    ANFIS(n_mfs=2, epochs=3, input_names=["a", "b"], target_name="y").fit(x, y).save(d / "model.json")
    res = d / "results"
    res.mkdir()
    resume(res / "identified.csv", set())  # writes the header
    with Appender(res / "identified.csv") as append:
        for k in range(24):
            D, L = 8 + k % 6 * 3.0, 30 + k * 2.0
            kt, ct, kr, cr = 2e7 * D / 16, 15.0, 1.4e6 * (D / 16) ** 2, 3.0
            append(new_row(f"T{k:03d}", "ER40", D, L, status="ok", kt=repr(kt), ct=repr(ct), kr=repr(kr),
                           cr=repr(cr), kt_lo=repr(0.95 * kt), kt_hi=repr(1.05 * kt), kr_lo=repr(0.9 * kr),
                           kr_hi=repr(1.1 * kr), objective="0.01", evaluations="100", seconds="1"))
    synthesise(d / "camp", n=3, seed=2)
    with redirect_stdout(io.StringIO()):  # models for `predict`
        assert main(["campaign", "learn", str(res), "--no-baselines", "--no-plots", "--epochs", "2",
                     "--test-size", "4", "--mfs", "2,2"]) == 0
    return d


@pytest.fixture(scope="session")
def camp(seeds, tmp_path_factory):
    """The seeds' campaign with its holder as a model (no inverse RCSA of the measured holder, ~3.5 s: a library
    run then costs ~0.1 s a tool). The measured holder's path runs where ``seeds / "camp"`` is given."""
    import shutil

    d = tmp_path_factory.mktemp("fastcamp") / "camp"
    shutil.copytree(seeds / "camp", d)
    toml = (d / "campaign.toml").read_text()
    head, tail = toml.split("[holders.ER40]")[0], toml.split("[identify]", 1)[1]
    (d / "campaign.toml").write_text(head + '[holders.ER40]\nmodel = "truth/spindle_holder.toml"\n[identify]' + tail)
    return d


@pytest.fixture(scope="session")
def heavy(seeds, camp, tmp_path_factory):
    """Valid inputs of the heavier commands, built once: a coarse assembly (20–3000 Hz, 20 Hz) with its
    tool-point and holder-tip FRFs, a 2-tool campaign, a 1-tool library and its finished output folder (made with
    the model holder of ``camp``)."""
    from test_properties import _quiet_main

    from toolpoint.campaign.synth import synthesise

    d = tmp_path_factory.mktemp("heavy")
    text = (ROOT / "examples" / "numerical_case.toml").read_text()
    coarse = text.replace("start_hz = 0.0", "start_hz = 20.0").replace("step_hz = 1.0", "step_hz = 20.0")
    assert coarse != text
    (d / "a.toml").write_text(coarse)
    assert _quiet_main(["frf", d / "a.toml", "--out", d / "tool.csv"]) == 0
    assert _quiet_main(["frf", d / "a.toml", "--point", "spindle_holder", "--out", d / "holder.csv"]) == 0
    synthesise(d / "camp", n=2, seed=1)
    for f in [*(d / "camp" / "frf").glob("*.csv"), *(d / "camp" / "sh").glob("*.csv")]:  # every 8th point
        lines = f.read_text().splitlines(keepends=True)
        f.write_text("".join(lines[:1] + lines[1::8]))
    lines = (ROOT / "examples" / "tool_library.csv").read_text().splitlines(keepends=True)
    (d / "lib.csv").write_text("".join(lines[:2]))
    assert _quiet_main(["library", d / "lib.csv", "--campaign", camp, "--models",
                        seeds / "results" / "models", "--out", d / "libout", "--workers", "1", "--samples", "8",
                        "--rpm-points", "20"]) == 0
    return d
