"""Campaign: synthetic folder → identification (pool, resume, failures, Dask) → prediction."""

import csv
import shutil

import numpy as np
import pytest

from toolpoint.campaign.config import load_campaign
from toolpoint.campaign.run import COLUMNS, run_campaign
from toolpoint.campaign.synth import synthesise, truth_joint
from toolpoint.cli.main import main
from toolpoint.errors import InputError


@pytest.fixture(scope="module")
def small(tmp_path_factory):
    d = tmp_path_factory.mktemp("camp") / "c"
    synthesise(d, n=8, seed=1)
    return d


def _rows(path):
    with open(path, newline="") as fh:
        return list(csv.DictReader(fh))


def test_synth_writes_a_campaign_the_pipeline_can_read(small):
    c = load_campaign(small)
    assert len(c.measurements) == 8 and c.holders["ER40"].kind == "blank"
    assert (small / "truth" / "truth.csv").exists()
    # truth law at the reference tool is the paper's Table 1 joint
    assert np.allclose(truth_joint(16, 50), [2.1e7, 15.0, 1.4e6, 3.0])


@pytest.mark.slow
def test_run_identifies_every_tool_and_resumes(small, tmp_path):
    out = tmp_path / "res"
    r = run_campaign(small, out, workers=2, progress=False)
    assert r.ok == 8 and r.failed == 0
    rows = _rows(out / "identified.csv")
    assert list(rows[0]) == COLUMNS and len(rows) == 8
    truth = {t["id"]: t for t in _rows(small / "truth" / "truth.csv")}
    errs = [abs(float(x["kt"]) / float(truth[x["id"]]["kt"]) - 1) for x in rows]
    assert np.median(errs) < 0.05  # kt is well identified through the measured subassembly
    # a re-run skips what is done
    r2 = run_campaign(small, out, workers=1, progress=False)
    assert r2.skipped == 8 and r2.ok == 0
    assert len(_rows(out / "identified.csv")) == 8


@pytest.mark.slow
def test_a_broken_item_is_recorded_and_the_rest_goes_on(small, tmp_path):
    broken = tmp_path / "c"
    shutil.copytree(small, broken)
    (broken / "frf" / "T003.csv").unlink()
    (broken / "frf" / "T005.csv").write_text("freq_hz,real,imag\n1,2,3\n")
    out = tmp_path / "res"
    r = run_campaign(broken, out, workers=1, progress=False)
    assert r.ok == 6 and r.failed == 2
    rows = {x["id"]: x for x in _rows(out / "identified.csv")}
    assert rows["T003"]["status"] == "failed" and "not found" in rows["T003"]["error"]
    assert rows["T005"]["status"] == "failed" and "T005.csv" in rows["T005"]["error"]
    # simulate a killed run: a half-written last line is dropped, finished rows kept
    with open(out / "identified.csv", "a") as fh:
        fh.write("T009,ER40,9.0,40")
    r2 = run_campaign(broken, out, workers=1, progress=False)
    assert r2.skipped == 6 and r2.failed == 2


@pytest.mark.slow
def test_dask_local_cluster(small, tmp_path):
    import distributed

    with distributed.LocalCluster(n_workers=1, threads_per_worker=2, processes=False, dashboard_address=None) as lc:
        r = run_campaign(small, tmp_path / "res", dask=lc.scheduler_address, progress=False)
    assert r.ok == 8


@pytest.mark.slow
def test_dask_address_that_does_not_answer(small, tmp_path, capsys):
    out = tmp_path / "res"
    assert main(["campaign", "run", str(small), "--out", str(out), "--dask", "tcp://127.0.0.1:9"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "--dask" in err[0]
    assert not out.exists()


def test_bad_campaign_inputs(small, tmp_path):
    bad = tmp_path / "c"
    shutil.copytree(small, bad)
    m = (bad / "measurements.csv").read_text().splitlines()
    (bad / "measurements.csv").write_text("\n".join(m + [m[1]]) + "\n")  # duplicate id
    with pytest.raises(InputError, match="duplicate id"):
        load_campaign(bad)
    (bad / "measurements.csv").write_text("id,diameter_mm,frf\nA,10,x.csv\n")
    with pytest.raises(InputError, match="overhang_mm"):
        load_campaign(bad)


@pytest.mark.slow
def test_band_outside_the_subassembly_is_refused_per_item(small, tmp_path):
    from toolpoint.frf import FRF
    from toolpoint.io.frf_files import read_frf, write_frf

    c2 = tmp_path / "c"
    shutil.copytree(small, c2)
    frf = read_frf(c2 / "frf" / "T002.csv")
    f = frf.freq_hz * 2  # extends to 8000 Hz, beyond the blank measurement (4000 Hz)
    write_frf(c2 / "frf" / "T002.csv", FRF(f, frf.values))
    text = (c2 / "campaign.toml").read_text().replace("band_hz = [20.0, 4000.0]", "band_hz = [20.0, 8000.0]")
    (c2 / "campaign.toml").write_text(text)
    r = run_campaign(c2, tmp_path / "res", workers=1, progress=False)
    rows = {x["id"]: x for x in _rows(tmp_path / "res" / "identified.csv")}
    assert rows["T002"]["status"] == "failed" and "no extrapolation" in rows["T002"]["error"]
    assert r.failed == 1


def test_blank_subassembly_with_modal_fit(small, tmp_path):
    """synth's campaign.toml asks for smooth = "modal": the blank FRFs' noise goes, the peaks stay."""
    from toolpoint.dynamics.assembly import load_assembly
    from toolpoint.dynamics.subassembly import Subassembly

    c = load_campaign(small)
    sub = c.subassembly("ER40", None)
    assert "modal fit" in sub.label
    true = Subassembly.from_assembly(load_assembly(small / "truth" / "spindle_holder.toml", require_tool=False),
                                     sub.freq_hz)
    err = np.abs(sub.R - true.R) / np.abs(true.R)
    assert np.median(err[:, 0, 0]) < 2e-3 and np.median(err[:, 1, 1]) < 1e-2
    assert np.abs(sub.R[:, 0, 0]).max() == pytest.approx(np.abs(true.R[:, 0, 0]).max(), rel=1e-2)

    bad = tmp_path / "c"
    shutil.copytree(small, bad)
    text = (bad / "campaign.toml").read_text()
    for repl, field in (('smooth = "spline"', "holders.ER40.blank.smooth"),
                        ('smooth = "modal", smooth_hz = 50', "holders.ER40.blank"),
                        ("smooth_hz = -5", "holders.ER40.blank.smooth_hz")):
        (bad / "campaign.toml").write_text(text.replace('smooth = "modal"', repl))
        with pytest.raises(InputError) as e:
            load_campaign(bad)
        assert e.value.field == field
