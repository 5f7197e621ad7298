"""Lobes from a measured-like FRF with the artefacts of a real lab tap test (issue: a confident wrong answer).

The FRF (``tests/lab_like.py``) rises smoothly towards 0 Hz below ~70 Hz (an accelerometer offset/drift ÷ −ω²) and
carries noise white in accelerance. The reference is the structure alone from 200 Hz — the band a careful engineer
gives. Library and CLI must agree: same band, notes and limits.
"""

import numpy as np
import pytest

from lab_like import DOMINANT_HZ, NOISE_ACCELERANCE, lab_like_frf, reference_frf, write_tsv
from toolpoint.cli.main import main
from toolpoint.errors import InputError
from toolpoint.frf import FRF
from toolpoint.stability import CuttingConditions
from toolpoint.stability.measured import lobes_from_frf
from toolpoint.trust import trusted_band

CUT = CuttingConditions(teeth=4, tangential_coeff=796e6, radial_ratio=0.212, radial_immersion=0.5)
RPM = np.linspace(500.0, 20000.0, 400)
ARGS = ["--teeth", "4", "--tangential-coeff", "796e6", "--radial-ratio", "0.212", "--immersion", "0.5",
        "--rpm", "500:20000", "--rpm-points", "400"]


@pytest.fixture(scope="module")
def reference():
    return lobes_from_frf(reference_frf(), CUT, RPM).lobes


@pytest.mark.parametrize("seed, noise", [(0, 1.0), (1, 1.0), (2, 10.0), (3, 30.0), (2, 100.0), (3, 100.0), (7, 100.0)])
def test_rise_towards_0_hz_is_cut_and_the_limit_is_the_structures(reference, seed, noise):
    frf = lab_like_frf(seed, noise=NOISE_ACCELERANCE * noise)
    tb = trusted_band(frf)
    assert 100 <= tb.lo_hz <= 300 and "rises towards 0 Hz" in tb.reason
    res = lobes_from_frf(frf, CUT, RPM)
    assert res.lobes.min_chatter_hz > 500
    assert res.lobes.min_depth_m == pytest.approx(reference.min_depth_m, rel=0.15)
    # every speed: nothing below the band's edge limits the depth
    assert np.nanmin(res.lobes.chatter_hz) >= tb.lo_hz


def test_the_whole_band_gives_the_confident_wrong_answer_that_the_rule_prevents(reference):
    """The failure the rule fixes, kept as a check that the fixture has the lab's artefact."""
    res = lobes_from_frf(lab_like_frf(0), CUT, RPM, band=(1.0, 5000.0))
    assert res.lobes.min_chatter_hz < 100 and res.lobes.min_depth_m < 0.6 * reference.min_depth_m


@pytest.mark.slow
def test_sdm_on_the_lab_like_frf_agrees_with_the_zero_order_or_refuses(reference):
    res = lobes_from_frf(lab_like_frf(1, noise=NOISE_ACCELERANCE * 10), CUT, RPM[::8], method="sdm")
    fn = res.modal[0].fn_hz
    for f0 in DOMINANT_HZ:
        assert np.min(np.abs(fn - f0)) < 0.02 * f0
    assert res.lobes.min_chatter_hz > 500
    assert res.lobes.min_depth_m == pytest.approx(reference.min_depth_m, rel=0.15)


def test_sdm_refuses_a_model_that_misses_a_dominant_peak():
    from types import SimpleNamespace

    from toolpoint.stability.measured import _check_model, dominant_peaks

    f = np.arange(200.0, 3000.0)
    h = sum(1 / (k * (1 - (f / fn) ** 2 + 2j * 0.03 * f / fn)) for fn, k in ((900.0, 2e7), (1700.0, 2.2e7)))
    frf = FRF(f, h)
    peaks = dominant_peaks(frf)
    assert peaks.size == 2 and np.allclose(peaks, [900, 1700], rtol=0.01)
    one = SimpleNamespace(fn_hz=np.array([900.0]), fit_error=np.array([0.3]), n_modes=1, band_hz=(200.0, 2999.0))
    with pytest.raises(InputError, match="dominant peak 1699|dominant peak 1700|dominant peak 1701"):
        _check_model(one, frf, "FRF", "x.csv")
    both = SimpleNamespace(fn_hz=np.array([900.0, 1700.0]), fit_error=np.array([0.01]), n_modes=2,
                           band_hz=(200.0, 2999.0))
    _check_model(both, frf, "FRF", "x.csv")
    with pytest.raises(InputError):  # and the pipeline refuses the one-mode model one way or the other
        lobes_from_frf(frf, CUT, RPM[::40], method="sdm", n_modes=1)


def test_library_and_cli_give_the_same_band_notes_and_limits(tmp_path, capsys):
    path = tmp_path / "lab.txt"
    write_tsv(lab_like_frf(0), path)
    out = tmp_path / "lobes.csv"
    assert main(["lobes", str(path), *ARGS, "--out", str(out)]) == 0
    err = capsys.readouterr().err.strip().splitlines()
    from toolpoint.io.frf_files import read_frf

    lib = lobes_from_frf(read_frf(path), CUT, RPM, files={"FRF": str(path)})
    assert err == list(lib.notes)
    data = np.loadtxt(out, delimiter=",", skiprows=1)
    assert np.allclose(data[:, 1], lib.lobes.depth_m * 1e3, rtol=1e-9)


def test_a_rise_that_never_levels_off_is_refused_pointing_to_band():
    f = np.arange(1.0, 2000.0)
    h = 0.5 / (2j * np.pi * f) ** 2 + 1e-8  # a free mass all the way: not a grounded tool
    with pytest.raises(InputError, match="--band"):
        lobes_from_frf(FRF(f, h), CUT, RPM)


@pytest.mark.parametrize("seed, noise", [(0, 1.0), (2, 10.0), (3, 100.0)])
def test_modal_fit_of_the_lab_like_frf_in_its_trusted_band(seed, noise):
    """Issue numbers: a mode within 2 % of each dominant one with ζ 1.5–7 %, nothing below the band (200 Hz
    on the lab data), positive modal masses (driving point: Im A_r < 0)."""
    from lab_like import DOMINANT_ZETA
    from toolpoint.dynamics.modal import fit_frfs
    from toolpoint.trust import common_band

    frf = lab_like_frf(seed, noise=NOISE_ACCELERANCE * noise)
    b = common_band([frf])
    fit = fit_frfs([b.cut(frf)], noise=b.noise_quantity or None)
    for f0, z0 in zip(DOMINANT_HZ, DOMINANT_ZETA):
        r = np.argmin(np.abs(fit.fn_hz - f0))
        assert abs(fit.fn_hz[r] - f0) < 0.02 * f0 and 0.015 <= fit.zeta[r] <= 0.07
        assert fit.zeta[r] == pytest.approx(z0, rel=0.1)
    assert fit.fn_hz.min() >= b.lo_hz and fit.n_modes <= 8
    assert np.all(fit.residues[:, 0].imag < 0)


def test_check_screen_on_the_lab_like_file(tmp_path, capsys):
    path = tmp_path / "lab.txt"
    write_tsv(lab_like_frf(0), path)
    assert main(["check", str(path)]) == 0
    out = capsys.readouterr().out
    assert "band used: 148–5000 Hz" in out and "rises towards 0 Hz" in out
    for f0 in DOMINANT_HZ:
        assert f"{f0:.1f}" in out
    assert "looks wrong: nothing found" in out


def test_a_receptance_in_mm_per_newton_is_named(tmp_path, capsys):
    """Issue: an FRF in mm/N was accepted silently (lobes 0.00076 mm)."""
    f = np.arange(1.0, 3001.0)
    h = 1e3 / (1e7 * (1 - (f / 900) ** 2 + 0.04j * f / 900))  # written in mm/N
    path = tmp_path / "mm.csv"
    np.savetxt(path, np.column_stack([f, h.real, h.imag]), delimiter=",", header="freq_hz,real,imag", comments="")
    out = tmp_path / "o.csv"
    assert main(["lobes", str(path), *ARGS, "--out", str(out)]) == 0
    err = capsys.readouterr().err
    assert "mm/N" in err and "mm.csv" in err
    assert main(["check", str(path)]) == 0
    assert "mm/N" in capsys.readouterr().out


def test_modal_plot_shows_the_stabilisation_diagram(tmp_path):
    from toolpoint.dynamics.modal import fit_frfs

    path, png, out = tmp_path / "lab.txt", tmp_path / "m.png", tmp_path / "m.csv"
    write_tsv(lab_like_frf(0), path)
    assert main(["modal", str(path), "--out", str(out), "--plot", str(png)]) == 0
    assert png.stat().st_size > 20_000
    fit = fit_frfs([reference_frf()])
    orders = [o for o, _ in fit.diagram]
    assert len(orders) > 5 and orders == sorted(orders)
    # every mode kept is a pole at (almost) every order of the diagram: stable
    for f0 in DOMINANT_HZ:
        hits = sum(np.any(np.abs(np.abs(lam) / (2 * np.pi) - f0) < 0.01 * f0) for _, lam in fit.diagram)
        assert hits >= 0.8 * len(orders)


# ------------------------------------------------------------------------- issue 20: the tool point, a driving point
PYUFF_1 = __import__("pathlib").Path(__file__).resolve().parents[1] / "data" / "pyuff" / "meas_point_1.txt"


def named_hz(note):
    """The frequencies a driving-point note names ("… at 142.2, 460.4 Hz …")."""
    import re

    return np.array([float(x) for x in re.search(r" at ([\d., ]+) Hz", note).group(1).split(", ")])


def test_sdm_fit_of_the_lab_like_tool_point_has_positive_modal_masses():
    """The tool point is a driving point: the SDM's modal fit is declared one, and every mode of the lab-like FRF
    (a grounded structure, positive masses) comes out with a positive real-mode-equivalent a_r = 1/m_r; nothing to
    drop or name."""
    res = lobes_from_frf(lab_like_frf(1, noise=NOISE_ACCELERANCE * 10), CUT, RPM[::40], method="sdm")
    (fit,) = res.modal
    for f0 in DOMINANT_HZ:
        assert np.min(np.abs(fit.fn_hz - f0)) < 0.02 * f0
    a = -2 * (fit.residues[:, 0] * np.conj(fit.poles)).real  # independent of ModalFit.real_modes
    assert np.all(a > 0) and fit.notes == ()
    assert not any("driving point" in n for n in res.notes)


def test_sdm_fit_of_a_driving_point_with_wrong_sign_modes_keeps_them_and_says_so():
    """pyuff's meas_point_1.txt (said to be a driving point) swings the other way at 142, 460 and 959 Hz: the SDM's
    fit keeps those measured modes and the result's notes name exactly them (once, no Python warning)."""
    import warnings

    y = np.genfromtxt(PYUFF_1, dtype=complex)
    f = np.arange(y.size, dtype=float)
    frf = FRF(f[1:], y[1:] / (2j * np.pi * f[1:]) ** 2, meta={"file_quantity": "accelerance"})
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # the driving-point warning is a note of the result, not a Python warning
        res = lobes_from_frf(frf, CUT, np.linspace(500.0, 5000.0, 6), method="sdm")
    peaks = np.array([52.0, 142.0, 279.0, 460.0, 687.0, 959.0])  # the measured peaks (tests/dynamics/test_modal.py)
    assert np.all(np.min(abs(peaks[:, None] - res.modal[0].fn_hz[None]), 1) <= 1.0)  # no measured mode lost
    dp = [n for n in res.notes if "driving point" in n]
    assert len(dp) == 1 and dp[0].startswith("warning: driving point: modes of negative modal mass kept")
    assert named_hz(dp[0]) == pytest.approx([142.2, 460.4, 958.5], abs=1.0)


def test_check_declares_one_frf_a_driving_point(tmp_path, capsys):
    """`toolpoint check` on one FRF: a driving point — the lab-like file has no negative modal mass (nothing said);
    the pyuff file's wrong-sign modes are named as a problem and marked doubtful, and `--driving-point none` turns
    the rule off."""
    path = tmp_path / "lab.txt"
    write_tsv(lab_like_frf(2, noise=NOISE_ACCELERANCE * 10), path)
    assert main(["check", str(path)]) == 0
    cap = capsys.readouterr()
    assert "negative modal mass" not in cap.out + cap.err
    assert "looks wrong: nothing found" in cap.out
    assert main(["check", str(path), "--driving-point", "none"]) == 0
    assert capsys.readouterr().out == cap.out  # nothing to drop or mark: the same screen
    y = np.genfromtxt(PYUFF_1, dtype=complex)
    f = np.arange(y.size, dtype=float)
    csv = tmp_path / "p1.csv"
    np.savetxt(csv, np.c_[f[1:], y[1:].real, y[1:].imag], delimiter=",", header="freq_hz,real,imag", comments="")
    assert main(["check", str(csv), "--quantity", "accelerance"]) == 0
    cap = capsys.readouterr()
    lines = [x for x in cap.out.splitlines() if "negative modal mass kept" in x]
    assert len(lines) == 1 and "warning" not in cap.err
    assert named_hz(lines[0]) == pytest.approx([142.2, 460.4, 958.5], abs=1.0)
    rows = [x.split() for x in cap.out.splitlines() if x.strip().endswith(("clear", "weak", "doubtful"))]
    doubtful = sorted(float(r[1]) for r in rows if r[-1] == "doubtful")
    assert doubtful == pytest.approx([142.2, 460.4, 958.5], abs=1.0)
    assert main(["check", str(csv), "--quantity", "accelerance", "--driving-point", "none"]) == 0
    assert "negative modal mass" not in capsys.readouterr().out
