"""The ``toolpoint`` dispatcher: lazy start-up and one error format."""

import subprocess
import sys

import pytest

from toolpoint.cli.main import COMMANDS, build_parser, main


def _run(code: str) -> str:
    return subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout


def test_version_and_help_import_no_numerics():
    # start-up cost is import cost: --version and --help must not import NumPy, SciPy or matplotlib
    code = (
        "import sys\n"
        "from toolpoint.cli.main import main\n"
        "for argv in (['--version'], ['--help']):\n"
        "    try:\n"
        "        main(argv)\n"
        "    except SystemExit:\n"
        "        pass\n"
        "print(sorted(m for m in ('numpy', 'scipy', 'matplotlib') if m in sys.modules))\n"
    )
    assert _run(code).strip().splitlines()[-1] == "[]"


def test_only_the_named_command_is_imported():
    code = (
        "import sys\n"
        "from toolpoint.cli.main import build_parser\n"
        "build_parser(['frf', '--help'])\n"
        "names = [m for m in sys.modules if m.startswith('toolpoint.cli.') and m != 'toolpoint.cli.main']\n"
        "print(sorted(m.split('.')[-1] for m in names))\n"
    )
    assert _run(code).strip() == "['common', 'frf']"


def test_every_command_builds():
    p = build_parser()  # argv None: all commands in full, each with its own options (not a stub)
    sub = next(a for a in p._actions if a.dest == "command")
    for name in COMMANDS:
        assert len(sub.choices[name]._actions) > 1, name


@pytest.mark.parametrize("argv", [["frf"], ["identify", "a.toml", "m.csv", "--seed", "abc"], ["nosuchcommand"]])
def test_bad_command_line_is_one_line_and_exit_2(argv, capsys):
    with pytest.raises(SystemExit) as e:
        main(argv)
    assert e.value.code == 2
    err = capsys.readouterr().err
    assert len(err.strip().splitlines()) == 1 and "error:" in err and "usage:" not in err


def test_output_paths_are_checked_before_any_work(tmp_path, capsys):
    from toolpoint.cli.common import out_path
    from toolpoint.errors import InputError

    (tmp_path / "a").write_text("")
    with pytest.raises(InputError, match="it is a file"):
        out_path(str(tmp_path / "a" / "o.csv"), "--out")
    with pytest.raises(InputError, match="cannot write a figure"):
        out_path(str(tmp_path / "f.xyz"), "--plot")
    with pytest.raises(InputError, match="is a folder"):
        out_path(str(tmp_path), "--out")
    with pytest.raises(InputError, match="inputs"):
        out_path(str(tmp_path / "a"), "--out", inputs=[tmp_path / "a"])
    assert out_path(str(tmp_path / "new" / "f.png"), "--plot") == tmp_path / "new" / "f.png"


def test_outputs_get_the_users_umask(tmp_path):
    import os

    from toolpoint.io.atomic import atomic_open

    old = os.umask(0o022)
    try:
        with atomic_open(tmp_path / "o.txt") as fh:
            fh.write("x")
    finally:
        os.umask(old)
    assert (tmp_path / "o.txt").stat().st_mode & 0o777 == 0o644


@pytest.mark.parametrize("argv, field", [
    (["campaign", "synth", "{tmp}/c", "--noise", "nan"], "--noise"),
    (["campaign", "synth", "{tmp}/c", "--seed", "-1"], "--seed"),
    (["reproduce", "--out", "{tmp}/r", "--noise", "inf"], "--noise"),
    (["reproduce", "--out", "{tmp}/r", "--methods", ","], "--methods"),
    (["predict", "{tmp}", "--diameter", "inf", "--overhang", "40", "--models", "{tmp}", "--out", "{tmp}/p.csv"],
     "--diameter"),
    (["lobes", "examples/numerical_case.toml", "--teeth", "2", "--immersion", "1", "--rpm", "5000:6000",
      "--tangential-coeff", "-6e8", "--radial-ratio", "0.3", "--out", "{tmp}/l.csv"],
     "--tangential-coeff"),  # a negative number in e-notation is a value to judge, not an unknown option
    (["lobes", "examples/numerical_case.toml", "--teeth", "2", "--immersion", "1", "--rpm", "5000:6000",
      "--tangential-coeff", "1e300", "--radial-ratio", "0.3", "--out", "{tmp}/l.csv"],
     "--tangential-coeff"),  # finite, but overflows the lobe arithmetic
])
def test_bad_numbers_are_one_line_exit_2_and_write_nothing(argv, field, tmp_path, capsys, monkeypatch):
    from pathlib import Path

    monkeypatch.chdir(Path(__file__).resolve().parents[2])
    before = sorted(tmp_path.rglob("*"))
    assert main([a.replace("{tmp}", str(tmp_path)) for a in argv]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and field in err[0]
    assert sorted(tmp_path.rglob("*")) == before


def test_anfis_refuses_to_overwrite_its_input(tmp_path, capsys):
    data = tmp_path / "d.csv"
    data.write_text("x,y\n" + "".join(f"{i},{i * i}\n" for i in range(20)))
    before = data.read_bytes()
    assert main(["anfis", "train", str(data), "--inputs", "x", "--target", "y", "--out", str(data)]) == 2
    assert "inputs" in capsys.readouterr().err and data.read_bytes() == before


@pytest.mark.parametrize("argv, named, suggestion", [
    (["lobes", "x.csv", "--outt", "a.csv", "--teeth", "2"], "--outt", "--out"),
    (["lobes", "x.csv", "--teth", "2", "--immersion", "1", "--rpm", "1:2"], "--teth", "--teeth"),
    (["frf", "a.toml", "--out", "f.csv", "--plott", "p.png"], "--plott", "--plot"),
])
def test_a_mistyped_option_is_named_with_the_closest_valid_one(argv, named, suggestion, capsys):
    # argparse alone reports the required --out missing after --outt; the typo is the cause and is named first
    with pytest.raises(SystemExit) as exc:
        main(argv)
    assert exc.value.code == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1
    assert f"unknown option {named} (did you mean {suggestion}?)" in err[0]


def test_an_option_with_no_close_match_is_named_alone(capsys):
    with pytest.raises(SystemExit):
        main(["frf", "a.toml", "--out", "f.csv", "--zzzzzz"])
    err = capsys.readouterr().err
    assert "unknown option --zzzzzz" in err and "did you mean" not in err


def test_every_command_has_a_description_and_every_option_a_help_text():
    import argparse

    def walk(parser, path):
        for a in parser._actions:
            if isinstance(a, argparse._SubParsersAction):
                for name, sp in a.choices.items():
                    assert sp.description, f"toolpoint {' '.join(path + [name])} has no description"
                    walk(sp, path + [name])
            elif not isinstance(a, argparse._HelpAction):
                assert a.help, f"toolpoint {' '.join(path)}: {a.option_strings or a.dest} has no help text"

    walk(build_parser(None), [])


def test_an_os_error_is_one_line_exit_2(monkeypatch, capsys, tmp_path):
    """A full disk (ENOSPC) anywhere in a command: one line naming the file and the reason, no traceback."""
    import errno

    from toolpoint.cli import frf as frf_cmd

    def full(args):
        raise OSError(errno.ENOSPC, "No space left on device", str(tmp_path / "frf.csv"))

    monkeypatch.setattr(frf_cmd, "run", full)
    assert main(["frf", "examples/numerical_case.toml", "--out", str(tmp_path / "frf.csv")]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "frf.csv: No space left on device" in err[0]


def test_a_file_name_with_a_newline_keeps_the_error_on_one_line(tmp_path, capsys):
    bad = tmp_path / "a\nb.csv"
    assert main(["modal", str(bad), "--out", str(tmp_path / "o.csv")]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "a\\nb.csv" in err
