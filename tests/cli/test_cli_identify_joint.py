"""`toolpoint identify ASSEMBLY MEASURED --joint spindle_holder` and the general `--params/--at` form, and
a campaign whose subassembly comes from such an identification."""

import json

import numpy as np
import pytest

from toolpoint.cli.main import main
from toolpoint.dynamics.points import ReceptanceModel, parse_point
from toolpoint.frf import FRF
from toolpoint.io.frf_files import write_csv_frf

SH_TOML = """
[spindle]
segments = [{ length_mm = 300, od_mm = 70, id_mm = 20 }]
bearings = [{ x_mm = 50, k = 2e8, c = 1e3 }, { x_mm = 250, k = 3e8, c = 2e3 }]
[holder]
segments = [{ length_mm = 60, od_mm = 40 }]
"""
TRUE = {"kt": 5e8, "ct": 300.0, "kr": 1.5e7, "cr": 50.0}


@pytest.fixture(scope="module")
def case(tmp_path_factory):
    from toolpoint.dynamics.assembly import parse_assembly
    import tomllib

    d = tmp_path_factory.mktemp("sh")
    (d / "sh.toml").write_text(SH_TOML)
    doc = tomllib.loads(SH_TOML)
    doc["joints"] = {"spindle_holder": TRUE}
    a = parse_assembly(doc, require_tool=False)
    f = np.arange(10.0, 3001.0, 5.0)
    ht = parse_point("holder_tip")
    m = ReceptanceModel(a, f, [ht], [], with_tool=False)
    write_csv_frf(d / "ht.csv", FRF(f, m.G0[:, m.dof(ht), m.dof(ht)]))
    return d


def test_joint_spindle_holder_writes_the_usual_keys(case, capsys):
    out = case / "sh_identified.json"
    assert main(["identify", str(case / "sh.toml"), str(case / "ht.csv"), "--joint", "spindle_holder",
                 "--out", str(out)]) == 0
    doc = json.loads(out.read_text())
    for key in ("kt", "ct", "kr", "cr", "ci95", "method", "seed", "evaluations", "seconds", "objective", "warnings"):
        assert key in doc
    for k, v in TRUE.items():
        assert doc[k] == pytest.approx(v, rel=1e-6), k
    assert set(doc["ci95"]) == set(TRUE) and doc["joint"] == "spindle_holder"
    assert doc["ci95_method"] == "profile"


def test_general_params_with_at(case, tmp_path):
    out = tmp_path / "r.json"
    assert main(["identify", str(case / "sh.toml"), str(case / "ht.csv"), "--params",
                 "spindle_holder.kt,spindle_holder.ct,spindle_holder.kr,spindle_holder.cr", "--at", "holder_tip",
                 "--out", str(out)]) == 0
    doc = json.loads(out.read_text())
    assert doc["spindle_holder.kt"] == pytest.approx(5e8, rel=1e-6)


@pytest.mark.parametrize("extra, field", [
    (["--params", "spindle_holder.kq"], "--params"),
    (["--joint", "spindle_holder", "--at", "holder:x_mm=900"], "--at"),
    (["--joint", "spindle_holder", "--at", "tool_tip"], "--at"),
    (["--joint", "spindle_holder", "--at", "holder_tip", "--at", "holder_tip"], "--at"),
    (["--params", "bearings[0].k", "--at", "spindle_nose", "--no-tool", "--bounds", "bearings[0].k=1e6:1e7"],
     "spindle.bearings[0].k"),
])
def test_bad_input_exit_2_one_line_no_output(case, tmp_path, capsys, example_path, extra, field):
    out = tmp_path / "r.json"
    # a start value outside its bounds: the example gives bearings[0].k = 2e8 N/m
    assembly = example_path if field.startswith("spindle.") else case / "sh.toml"
    assert main(["identify", str(assembly), str(case / "ht.csv"), *extra, "--out", str(out)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and field in err[0], err
    assert not out.exists()


def test_campaign_holder_from_an_identified_joint(case, tmp_path):
    from toolpoint.campaign.config import _holders
    from toolpoint.io.toml import TomlReader
    from toolpoint.errors import InputError

    out = case / "sh_identified.json"
    if not out.exists():
        assert main(["identify", str(case / "sh.toml"), str(case / "ht.csv"), "--joint", "spindle_holder",
                     "--out", str(out)]) == 0
    r = TomlReader("campaign.toml")
    hs = _holders(r, {"holders": {"SH": {"model": "sh.toml", "joint": "sh_identified.json"}}}, case)
    assert hs["SH"].spec["joint"] == "sh_identified.json"
    from toolpoint.campaign.config import Campaign

    c = Campaign(case, (10.0, 3000.0), None, hs, (), "hybrid", None, {})
    f = np.arange(10.0, 3001.0, 5.0)
    h = c.subassembly("SH", f).R[:, 0, 0]
    meas = np.loadtxt(case / "ht.csv", delimiter=",", skiprows=1)
    assert np.max(abs(h - (meas[:, 1] + 1j * meas[:, 2]))) < 1e-6 * np.max(abs(h))
    (case / "bad.json").write_text('{"kt": -1}')
    with pytest.raises(InputError, match="holders.SH.joint"):
        _holders(r, {"holders": {"SH": {"model": "sh.toml", "joint": "bad.json"}}}, case)
