"""`toolpoint modal`: modes CSV against exact systems and real measured FRFs; one-line errors, no output.

The synthetic systems (tests/modal_systems.py) have exactly as many modes as DOFs, so the
modal sum of the CSV's constants alone (no residual terms) must reproduce the exact
receptance (direct solve of M, C, K) everywhere, and the CSV's frequencies and damping
the state-space eigenvalues.
"""

import numpy as np
import pytest
from scipy.signal import find_peaks

from modal_systems import FOUR
from toolpoint.cli.main import main

DATA = __import__("pathlib").Path(__file__).parents[1] / "data" / "pyuff"
F = np.arange(1.0, 3001.0)


def write_csv(path, f, values):
    np.savetxt(path, np.c_[f, values.real, values.imag], delimiter=",", header="freq_hz,real,imag", comments="",
               fmt="%.17g")
    return str(path)


def read_modes(path):
    """(header, fn Hz, ζ, A (n, m) complex) from a modes CSV."""
    head = path.read_text().splitlines()[0].split(",")
    d = np.atleast_2d(np.loadtxt(path, delimiter=",", skiprows=1))
    return head, d[:, 0], d[:, 1], d[:, 2::2] + 1j * d[:, 3::2]


def modal_sum(fn, ze, A, f):
    """Σ_r A_r/(iω − λ_r) + c.c. (m/N) with λ_r = −ζω_r + iω_r√(1 − ζ²), from the CSV columns only."""
    wn = 2 * np.pi * fn
    lam = wn * (-ze + 1j * np.sqrt(1 - ze**2))
    s = 2j * np.pi * np.asarray(f)[:, None, None]
    return np.sum(A[None] / (s - lam[None, :, None]) + np.conj(A[None]) / (s - np.conj(lam)[None, :, None]), 1)


@pytest.mark.parametrize("quantity", ["receptance", "accelerance"])
def test_modes_csv_reproduces_the_exact_system(quantity, tmp_path, capsys):
    Y = FOUR.frf(F, quantity)
    paths = [write_csv(tmp_path / f"y{k}.csv", F, Y[:, k]) for k in range(Y.shape[1])]
    out, png = tmp_path / "modes.csv", tmp_path / "fit.png"
    argv = ["modal", *paths, "--band", "100:3000", "--out", str(out), "--plot", str(png)]
    if quantity != "receptance":
        argv += ["--quantity", quantity]
    assert main(argv) == 0
    head, fn, ze, A = read_modes(out)
    assert head == ["freq_hz", "damping_ratio", "A1_real", "A1_imag", "A2_real", "A2_imag", "A3_real", "A3_imag"]
    fn_true, ze_true = FOUR.poles()
    np.testing.assert_allclose(fn, fn_true, rtol=1e-7)
    np.testing.assert_allclose(ze, ze_true, rtol=1e-5)
    H = FOUR.receptance(F)  # all 4 modes of the 4-DOF system: the modal sum is the whole receptance
    assert np.abs(modal_sum(fn, ze, A, F) - H).max() < 1e-6 * np.abs(H).max()
    assert png.read_bytes()[:4] == b"\x89PNG"
    assert "4 modes" in capsys.readouterr().out


def test_fixed_number_of_modes(tmp_path):
    Y = FOUR.frf(F, "receptance")
    paths = [write_csv(tmp_path / f"y{k}.csv", F, Y[:, k]) for k in range(2)]
    out = tmp_path / "modes.csv"
    assert main(["modal", *paths, "--band", "100:3000", "--modes", "2", "--out", str(out)]) == 0
    head, fn, _, A = read_modes(out)
    assert fn.size == 2 and A.shape == (2, 2) and len(head) == 6
    fn_true, _ = FOUR.poles()  # the two modes kept are two of the system's, not compromises between them
    assert np.all(np.min(abs(fn[:, None] - fn_true[None]) / fn_true, 1) < 0.01)


def test_real_measured_accelerances(tmp_path):
    """The pyuff sample FRFs (measured accelerance, 1 Hz grid; tests/data/pyuff, MIT).

    Every prominent measured peak has a fitted mode within one frequency step, every
    fitted mode sits at a measured peak (none spurious), and the modal sum of the CSV's
    constants (converted to accelerance, −ω² H) matches the measured value at each peak.
    (Residual terms are not in the CSV: at the peaks they change the value by ≈ 1 %.)
    """
    Y = np.stack([np.genfromtxt(DATA / f"meas_point_{k}.txt", dtype=complex) for k in (1, 2, 3)], -1)
    f = np.arange(Y.shape[0], dtype=float)  # 0, 1, … Hz (pyuff's pairing); 0 Hz left out
    paths = [write_csv(tmp_path / f"p{k}.csv", f[1:], Y[1:, k]) for k in range(3)]
    out = tmp_path / "modes.csv"
    assert main(["modal", *paths, "--quantity", "accelerance", "--out", str(out)]) == 0
    _, fn, ze, A = read_modes(out)
    mag = np.sqrt(np.sum(np.abs(Y[1:]) ** 2, 1))
    pk, _ = find_peaks(mag, prominence=0.05 * mag.max())
    peaks = f[1:][pk]
    assert peaks.size >= 5
    assert np.all(np.min(abs(peaks[:, None] - fn[None]), 1) <= 1.0)  # no measured mode lost
    assert np.all(np.min(abs(fn[:, None] - peaks[None]), 1) <= 1.0)  # no mode where the data have none
    assert np.all((ze > 0) & (ze < 0.01))  # lightly damped structure: sharp peaks on a 1 Hz grid
    fit = -((2 * np.pi * peaks) ** 2)[:, None] * modal_sum(fn, ze, A, peaks)
    meas = Y[1:][pk]
    big = np.abs(meas) > 0.1 * np.abs(meas).max(0)  # the FRFs where that mode shows clearly
    assert np.all(abs(np.abs(fit) - np.abs(meas))[big] < 0.05 * np.abs(meas)[big])  # peak heights
    rel = (np.abs(fit - meas) / np.abs(meas))[big]
    # complex values: ≈ 1 % at the well-excited modes; ≈ 12 % (a 7° phase) at 52 Hz, where the
    # hammer's low-frequency accelerance is noisiest and the peak (ζ ≈ 0.03 %) falls between grid points
    assert np.median(rel) < 0.02 and rel.max() < 0.15


def bad_cases(tmp_path):
    Y = FOUR.frf(F, "receptance")
    good = [write_csv(tmp_path / f"y{k}.csv", F, Y[:, k]) for k in range(2)]
    zero = write_csv(tmp_path / "zero.csv", F, np.zeros(F.size, complex))
    nan = tmp_path / "nan.csv"
    nan.write_text("freq_hz,real,imag\n1,1e-6,0\n2,nan,0\n3,1e-6,0\n")
    short = write_csv(tmp_path / "short.csv", F[:500], Y[:500, 0])
    return {
        "band outside data": ([*good, "--band", "4000:5000"], "--band"),
        "too few points": ([*good, "--band", "100:105"], "at least 10"),
        "malformed band": ([*good, "--band", "100-200"], "LO:HI"),
        "band reversed": ([*good, "--band", "300:200"], "LO:HI"),
        "modes 0": ([*good, "--modes", "0"], "positive integer"),
        "modes text": ([*good, "--modes", "many"], "positive integer"),
        "all-zero FRF": ([good[0], zero], "zero.csv: values: .*zero everywhere"),
        "NaN": ([good[0], str(nan)], "nan.csv"),
        "other grid": ([good[0], short], "short.csv: freq_hz: .*differs"),
        "missing file": ([good[0], str(tmp_path / "nope.csv")], "nope.csv"),
        "output is an input": ([*good[:1], "--out", good[0]], "inputs"),
    }


CASES = ["band outside data", "too few points", "malformed band", "band reversed", "modes 0", "modes text",
         "all-zero FRF", "NaN", "other grid", "missing file", "output is an input"]


@pytest.mark.parametrize("case", CASES)
def test_bad_input_is_one_line_exit_2_no_output(case, tmp_path, capsys):
    argv, match = bad_cases(tmp_path)[case]
    out, png = tmp_path / "modes.csv", tmp_path / "fit.png"
    before = sorted(p.name for p in tmp_path.iterdir())
    if "--out" not in argv:
        argv = [*argv, "--out", str(out)]
    assert main(["modal", *argv, "--plot", str(png)]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and err.startswith("toolpoint modal: error: ")
    assert __import__("re").search(match, err), err
    assert sorted(p.name for p in tmp_path.iterdir()) == before  # nothing written, not even a temporary file


# --------------------------------------------------------------------------- trusted band (issue 11 item 3)
def test_trusted_band_of_real_measured_accelerances(tmp_path, capsys):
    """The pyuff sample accelerances (tests/data/pyuff): converted to receptance, their lowest lines are noise
    ×1/ω²; the fit leaves them out with one note per file and uses the intersection of the trusted bands."""
    Y = np.stack([np.genfromtxt(DATA / f"meas_point_{k}.txt", dtype=complex) for k in (1, 2, 3)], -1)
    f = np.arange(Y.shape[0], dtype=float)
    paths = [write_csv(tmp_path / f"p{k}.csv", f[1:], Y[1:, k]) for k in range(3)]
    out = tmp_path / "modes.csv"
    assert main(["modal", *paths, "--quantity", "accelerance", "--out", str(out)]) == 0
    cap = capsys.readouterr()
    notes = [n for n in cap.err.splitlines() if n.startswith("note:")]
    assert len(notes) == 3
    edges = [float(n.split("trusted band ")[1].split("–")[0]) for n in notes]
    assert all(2 <= e <= 10 for e in edges)  # a few hertz of junk; the first mode (52 Hz) is kept
    assert all("the accelerance's noise ×1/ω² exceeds the signal" in n for n in notes)
    assert f"{max(edges):g}–1000 Hz" in cap.out


def test_given_band_is_noted_and_outside_names_the_file(tmp_path, capsys):
    Y = FOUR.frf(F, "receptance")
    paths = [write_csv(tmp_path / f"y{k}.csv", F, Y[:, k]) for k in range(2)]
    out = tmp_path / "modes.csv"
    assert main(["modal", *paths, "--band", "100:3000", "--out", str(out)]) == 0
    assert capsys.readouterr().err == "note: band 100–3000 Hz given by --band (no automatic trimming)\n"
    assert main(["modal", *paths, "--out", str(out)]) == 0
    assert capsys.readouterr().err == ""  # exact FRFs: nothing to exclude, nothing said
    out.unlink()
    assert main(["modal", *paths, "--band", "4000:5000", "--out", str(out)]) == 2
    err = capsys.readouterr().err
    assert err == (f"toolpoint modal: error: {paths[0]}: --band: band 4000–5000 Hz holds 0 of the data's points "
                   "(the data cover 1–3000 Hz)\n") and not out.exists()


# --------------------------------------------------------------------------- driving point (issue 20)
def test_one_frf_is_a_driving_point_lab_like(tmp_path, capsys):
    """One FRF is a driving point by default: the lab-like tool point (positive modal masses) fits with every
    a_r = −2 Re(A_r conj λ_r) > 0 from the CSV's columns, and nothing about negative masses is said."""
    from lab_like import DOMINANT_HZ, NOISE_ACCELERANCE, lab_like_frf, write_tsv

    path = tmp_path / "lab.txt"
    write_tsv(lab_like_frf(1, noise=NOISE_ACCELERANCE * 30), path)
    out = tmp_path / "modes.csv"
    assert main(["modal", str(path), "--out", str(out)]) == 0
    err = capsys.readouterr().err
    assert "negative modal mass" not in err
    _, fn, ze, A = read_modes(out)
    lam = 2 * np.pi * fn * (-ze + 1j * np.sqrt(1 - ze**2))
    assert np.all(-2 * (A[:, 0] * np.conj(lam)).real > 0)
    for f0 in DOMINANT_HZ:
        assert np.min(np.abs(fn - f0)) < 0.02 * f0


def test_driving_point_with_wrong_sign_modes_is_named_once_and_kept(tmp_path, capsys):
    """pyuff's meas_point_1.txt (said to be a driving point; docs/design/measurements.md) swings the other way at
    142, 460 and 959 Hz: every measured mode is kept, one warning names exactly those; `--driving-point none`
    says nothing, and gives the same modes."""
    y = np.genfromtxt(DATA / "meas_point_1.txt", dtype=complex)
    f = np.arange(y.size, dtype=float)
    path = write_csv(tmp_path / "p1.csv", f[1:], y[1:])
    out, off = tmp_path / "modes.csv", tmp_path / "off.csv"
    assert main(["modal", path, "--quantity", "accelerance", "--out", str(out)]) == 0
    err = capsys.readouterr().err.splitlines()
    dp = [x for x in err if "driving point" in x]
    assert len(dp) == 1 and dp[0].startswith("warning: driving point: modes of negative modal mass kept")
    named = np.array([float(x) for x in dp[0].split(" kept at ")[1].split(" Hz")[0].split(", ")])
    assert named == pytest.approx([142.2, 460.4, 958.5], abs=1.0)
    _, fn, _, _ = read_modes(out)
    peaks = np.array([52.0, 142.0, 279.0, 460.0, 687.0, 959.0])
    assert np.all(np.min(abs(peaks[:, None] - fn[None]), 1) <= 1.0)  # no measured mode lost
    assert main(["modal", path, "--quantity", "accelerance", "--driving-point", "none", "--out", str(off)]) == 0
    assert "driving point" not in capsys.readouterr().err
    assert np.array_equal(read_modes(off)[1], fn)


def test_driving_point_of_several_frfs_is_off_unless_given(tmp_path, capsys):
    """Several FRFs: no driving point by default; `--driving-point 0` declares the first (pyuff point 1) one."""
    Y = np.stack([np.genfromtxt(DATA / f"meas_point_{k}.txt", dtype=complex) for k in (1, 2)], -1)
    f = np.arange(Y.shape[0], dtype=float)
    paths = [write_csv(tmp_path / f"p{k}.csv", f[1:], Y[1:, k]) for k in range(2)]
    out = tmp_path / "modes.csv"
    assert main(["modal", *paths, "--quantity", "accelerance", "--out", str(out)]) == 0
    assert "driving point" not in capsys.readouterr().err
    assert main(["modal", *paths, "--quantity", "accelerance", "--driving-point", "0", "--out", str(out)]) == 0
    assert "driving point: modes of negative modal mass" in capsys.readouterr().err


@pytest.mark.parametrize("value", ["2", "-1", "x", "0.5"])
def test_bad_driving_point_is_one_line_exit_2(value, tmp_path, capsys):
    Y = FOUR.frf(F, "receptance")
    paths = [write_csv(tmp_path / f"y{k}.csv", F, Y[:, k]) for k in range(2)]
    out = tmp_path / "modes.csv"
    assert main(["modal", *paths, "--driving-point", value, "--out", str(out)]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "--driving-point" in err and not out.exists()
