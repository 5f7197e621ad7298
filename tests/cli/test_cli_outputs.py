"""No command writes its output over one of its own inputs (issue 13: inputs never overwritten)."""

import shutil
from pathlib import Path

import pytest

from toolpoint.cli.main import main

EXAMPLE = Path(__file__).resolve().parents[2] / "examples" / "numerical_case.toml"


@pytest.fixture
def case(tmp_path):
    toml = tmp_path / "case.toml"
    shutil.copy(EXAMPLE, toml)
    meas = tmp_path / "m.csv"
    assert main(["frf", str(toml), "--out", str(meas)]) == 0
    return toml, meas


def _unchanged(paths, argv, capsys):
    before = {p: p.read_bytes() for p in paths}
    assert main(argv) == 2
    err = capsys.readouterr().err
    assert "is one of this command's inputs" in err and "Traceback" not in err
    assert {p: p.read_bytes() for p in paths} == before


@pytest.mark.parametrize("flag", ["--out", "--plot"])
def test_identify_refuses_to_write_over_its_measured_file(case, capsys, flag):
    toml, meas = case
    argv = ["identify", str(toml), str(meas), "--method", "ga", flag, str(meas)]
    _unchanged([toml, meas], argv, capsys)


def test_identify_general_form_refuses_to_write_over_its_assembly(case, capsys):
    toml, meas = case
    argv = ["identify", str(toml), str(meas), "--joint", "holder_tool", "--at", "tool_tip", "--out", str(toml)]
    _unchanged([toml, meas], argv, capsys)


def test_frf_refuses_to_write_over_its_assembly(case, capsys):
    toml, _ = case
    _unchanged([toml], ["frf", str(toml), "--out", str(toml)], capsys)
