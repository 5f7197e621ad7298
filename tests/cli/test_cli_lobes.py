"""``toolpoint lobes`` end to end."""

import csv

import numpy as np
import pytest

from toolpoint.cli.main import main
from toolpoint.stability import ModalModel

MODE = ModalModel([922.0], [0.011], [0.03993])
BASE = ["--teeth", "2", "--tangential-coeff", "6e8", "--radial-ratio", "0.3333333333333333", "--immersion", "1",
        "--rpm", "5000:25000"]


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
    assert header == ["rpm", "depth_mm", "chatter_hz", "lobe"]
    assert data.shape == (400, 4)
    # The lobe column is k = floor(f_c T) of the limiting lobe: f_c T = k + ε/2π.
    waves = data[:, 2] * 60.0 / (2 * data[:, 0])
    assert np.all((waves >= data[:, 3] - 1e-6) & (waves < data[:, 3] + 1 + 1e-6))
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
    assert data.shape == (50, 4) and np.all(data[:, 1] > 0)


def test_sdm_end_to_end(tmp_path, frf_files, capsys):
    x, _ = frf_files
    out, png = tmp_path / "sdm.csv", tmp_path / "sdm.svg"
    code = main(["lobes", str(x), *BASE[:-4], "--immersion", "0.05", "--rpm", "14000:20000", "--rpm-points", "25",
                 "--method", "sdm", "--modes", "1", "--out", str(out), "--plot", str(png)])
    assert code == 0
    text = capsys.readouterr().out
    assert "922.00" in text and "fit error" in text  # the fitted modes are printed
    header, data = read(out)
    assert header == ["rpm", "depth_mm", "chatter_hz", "lobe"] and data.shape == (25, 4)
    assert png.read_text().lstrip().startswith("<?xml")


def test_assembly_toml_input(tmp_path, example_path, capsys):
    out = tmp_path / "t.csv"
    code = main(["lobes", str(example_path), "--teeth", "4", "--tangential-coeff", "8e8", "--radial-ratio", "0.3",
                 "--immersion", "0.5", "--rpm", "5000:30000", "--rpm-points", "200", "--out", str(out)])
    assert code == 0
    _, data = read(out)
    assert np.all(np.isfinite(data[:, 1])) and data[:, 1].min() > 0


@pytest.mark.parametrize(
    "change",
    [
        ["--teeth", "0"],
        ["--teeth", "-2"],
        ["--teeth", "two"],
        ["--tangential-coeff", "0"],
        ["--tangential-coeff", "-6e8"],
        ["--tangential-coeff", "nan"],
        ["--radial-ratio", "-1"],
        ["--rpm-points", "100001"],
        ["--immersion", "0"],
        ["--immersion", "1.5"],
        ["--rpm", "20000:2000"],
        ["--rpm", "2000"],
        ["--rpm", "5000:1e300"],  # beyond MAX_RPM: a typo, not a spindle speed
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


@pytest.mark.parametrize("old, new", [("--kt", "--tangential-coeff"), ("--kr", "--radial-ratio")])
def test_removed_flags_name_their_replacement(tmp_path, example_path, capsys, old, new):
    """--kt/--kr were the cutting coefficient and force ratio, easily taken for the joint stiffnesses."""
    out = tmp_path / "lobes.csv"
    argv = ["lobes", str(example_path), "--teeth", "2", "--tangential-coeff", "6e8", "--radial-ratio", "0.3",
            "--immersion", "0.5", "--rpm", "5000:30000", "--out", str(out), old, "1"]
    with pytest.raises(SystemExit) as exc:
        main(argv)
    assert exc.value.code == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and old in err[0] and new in err[0]
    assert not out.exists()


@pytest.mark.parametrize("what", ["zero", "nan"])
def test_unusable_x_frf_is_refused_not_reported_stable(tmp_path, frf_files, capsys, what):
    """An all-zero x FRF must not come out as 'no chatter'; a NaN in the file is refused."""
    _, rigid = frf_files
    f = np.linspace(0.0, 3000.0, 3001)
    v = MODE.frf(f).values
    v[100] = np.nan
    bad = rigid if what == "zero" else write_csv(tmp_path / "nan.csv", f, v)
    out = tmp_path / "o.csv"
    assert main(["lobes", str(bad), *BASE, "--out", str(out)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and bad.name in err[0]
    assert not out.exists()


def test_pocket_is_an_interior_maximum_and_markers_lie_in_the_axes(tmp_path, frf_files, capsys):
    from toolpoint.stability import CuttingConditions, zoa_lobes

    x, rigid = frf_files
    out = tmp_path / "o.csv"
    assert main(["lobes", str(x), "--frf-y", str(rigid), *BASE, "--rpm-points", "400", "--out", str(out)]) == 0
    text = capsys.readouterr().out
    _, data = read(out)
    d = data[:, 1]
    peaks = np.flatnonzero((d[1:-1] > d[:-2]) & (d[1:-1] > d[2:])) + 1  # strict interior local maxima
    assert peaks.size >= 2 and d[-1] > d[peaks].max()  # the limit is highest at the range end: not a pocket
    j = peaks[np.argmax(d[peaks])]
    assert f"best stable pocket: {data[j, 1]:.4g} mm at {data[j, 0]:.0f} rpm" in text
    # A range where the limit only rises: no pocket, and the CLI says so.
    assert main(["lobes", str(x), "--frf-y", str(rigid), *BASE[:-2], "--rpm", "15500:17000", "--rpm-points", "50",
                 "--out", str(out)]) == 0
    assert "best stable pocket: none inside the speed range" in capsys.readouterr().out
    # Every marker of the chart lies inside its axes (README's figure had the pocket above them).
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    f = np.linspace(0.0, 3000.0, 3001)
    cut = CuttingConditions(teeth=2, tangential_coeff=6e8, radial_ratio=0.3, radial_immersion=0.5)
    res = zoa_lobes(MODE.frf(f), None, cut, rpm=np.linspace(5000, 30000, 400))
    ax = res.plot()
    (x0, x1), (y0, y1) = ax.get_xlim(), ax.get_ylim()
    markers = [ln for ln in ax.get_lines() if ln.get_marker() not in ("None", None, "")]
    assert len(markers) == 2  # the minimum and the best pocket
    for ln in markers:
        (xm,), (ym,) = ln.get_xdata(), ln.get_ydata()
        assert x0 <= xm <= x1 and y0 <= ym <= y1
    plt.close("all")


# ----------------------------------------------------------------- semi-discretisation options
SDM = ["--teeth", "2", "--tangential-coeff", "6e8", "--radial-ratio", "0.3333333333333333", "--immersion", "1",
       "--rpm", "5000:25000", "--rpm-points", "20", "--method", "sdm"]


def _refused(argv, capsys, out):
    assert main(argv) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and not out.exists()
    return err[0]


@pytest.mark.parametrize("seed", [1, 2, 3])
def test_sdm_on_noise_only_is_refused(tmp_path, capsys, seed):
    """White noise, no resonance: one line naming the file, quickly (the probe fit, not the 8-mode search)."""
    f = np.linspace(0.0, 3000.0, 3001)
    rng = np.random.default_rng(seed)
    values = 1e-7 * (rng.standard_normal(f.size) + 1j * rng.standard_normal(f.size))
    noise = write_csv(tmp_path / "noise.csv", f, values)
    out = tmp_path / "o.csv"
    err = _refused(["lobes", str(noise), *SDM, "--out", str(out)], capsys, out)
    assert "noise.csv" in err and "no resonance" in err
    # With a fixed number of modes the fit is made, and refused for not describing the FRF.
    err = _refused(["lobes", str(noise), *SDM, "--modes", "2", "--out", str(out)], capsys, out)
    assert "noise.csv" in err and "unexplained" in err


def test_sdm_on_all_zero_frf_is_refused(tmp_path, frf_files, capsys):
    x, rigid = frf_files
    out = tmp_path / "o.csv"
    err = _refused(["lobes", str(rigid), *SDM, "--out", str(out)], capsys, out)
    assert "rigid.csv" in err and "zero at every frequency" in err  # the zero-order check comes first
    err = _refused(["lobes", str(x), "--frf-y", str(rigid), *SDM, "--out", str(out)], capsys, out)
    assert "rigid.csv" in err and "--frf-y" in err


def test_sdm_with_no_mode_in_the_band_is_refused(tmp_path, capsys):
    """The FRF covers 1000–3000 Hz, the only resonance is at 500 Hz: the fit can only put a mode on the band edge."""
    f = np.linspace(1000.0, 3000.0, 2001)
    tail = write_csv(tmp_path / "tail.csv", f, ModalModel([500.0], [0.02], [0.1]).frf(f).values)
    out = tmp_path / "o.csv"
    err = _refused(["lobes", str(tail), *SDM, "--out", str(out)], capsys, out)
    assert "tail.csv" in err and "no mode inside the FRF's band 1000–3000 Hz" in err


@pytest.mark.parametrize("value", ["0.1", "17", "fast"])
def test_bad_accuracy(tmp_path, frf_files, capsys, value):
    x, _ = frf_files
    out = tmp_path / "o.csv"
    err = _refused(["lobes", str(x), *SDM, "--accuracy", value, "--out", str(out)], capsys, out)
    assert "--accuracy" in err


def test_sdm_accuracy_and_progress(tmp_path, frf_files, capsys):
    """--accuracy reaches the SDM (more steps over the cut); the progress report ends with every speed done."""
    x, _ = frf_files
    steps = {}
    for acc in ("1", "2"):
        out = tmp_path / f"o{acc}.csv"
        assert main(["lobes", str(x), *SDM[:-6], "--immersion", "0.05", "--rpm", "9000:11000", "--rpm-points", "4",
                     "--method", "sdm", "--modes", "1", "--accuracy", acc, "--out", str(out)]) == 0
        cap = capsys.readouterr()
        steps[acc] = int(cap.out.split("semi-discretisation: ")[1].split()[0].split("–")[-1])
        assert cap.err.strip().splitlines()[-1].startswith("semi-discretisation: 4/4 speeds (100 %)")
    assert steps["2"] >= 2 * steps["1"] - 4  # the step ladder is ≈ 2^(1/4) apart


@pytest.mark.slow
def test_sdm_with_cross_frfs_matches_the_exact_model(tmp_path, capsys):
    """Orthotropic tool, principal axes turned 35°: the four receptance files → common-pole fits → 2×2
    state-space model must give the lobes of the exact model (built from its poles and residue matrices,
    independently of the fit); dropping the cross FRFs changes them by > 5 %."""
    from test_stability_sdm_statespace import rotated_by_poles

    from toolpoint.stability import CuttingConditions, sdm_lobes

    exact = rotated_by_poles(np.deg2rad(35.0))
    f = np.linspace(0.0, 3000.0, 3001)
    phi = exact.frf(f)
    files = {k: write_csv(tmp_path / f"{k}.csv", f, phi[:, i, j])
             for k, (i, j) in dict(x=(0, 0), y=(1, 1), xy=(0, 1), yx=(1, 0)).items()}
    args = ["--teeth", "3", "--tangential-coeff", "6e8", "--radial-ratio", "0.3", "--immersion", "0.5",
            "--rpm", "6000:20000", "--rpm-points", "6", "--method", "sdm"]
    out, plain = tmp_path / "o.csv", tmp_path / "plain.csv"
    assert main(["lobes", str(files["x"]), "--frf-y", str(files["y"]), "--frf-xy", str(files["xy"]),
                 "--frf-yx", str(files["yx"]), *args, "--out", str(out)]) == 0
    assert "common-pole fit, force y" in capsys.readouterr().out
    c = CuttingConditions(teeth=3, tangential_coeff=6e8, radial_ratio=0.3, radial_immersion=0.5)
    ref = sdm_lobes(exact, cutting=c, rpm=np.linspace(6000.0, 20000.0, 6))
    _, data = read(out)
    assert data[:, 1] == pytest.approx(1e3 * ref.depth_m, rel=2e-3)
    assert main(["lobes", str(files["x"]), "--frf-y", str(files["y"]), *args, "--out", str(plain)]) == 0
    _, no_cross = read(plain)
    assert np.max(np.abs(no_cross[:, 1] / data[:, 1] - 1)) > 0.05


# --------------------------------------------------------------------------- trusted band (issue 11 item 3)
NOISY_CUT = ["--teeth", "3", "--tangential-coeff", "6e8", "--radial-ratio", "0.3", "--immersion", "0.5",
             "--rpm", "2000:20000", "--rpm-points", "400"]


@pytest.fixture
def noisy_files(tmp_path):
    """A tool-point receptance from an accelerance with white noise (tests/test_trust.py), and its clean twin."""
    from test_trust import noisy_toolpoint

    f, clean, noisy = noisy_toolpoint(0)
    return write_csv(tmp_path / "noisy.csv", f, noisy), write_csv(tmp_path / "clean.csv", f, clean)


def test_lobes_on_noisy_frf_use_the_trusted_band_only(tmp_path, noisy_files, capsys):
    """Over the whole band (the old behaviour, now only with --band given) the limit rests on chatter in the
    low-frequency junk; by default the band starts where the noise falls below the signal, every limiting
    chatter frequency lies inside it and the limit is the noise-free FRF's."""
    noisy, clean = noisy_files
    out = tmp_path / "l.csv"
    assert main(["lobes", str(noisy), *NOISY_CUT, "--band", "0:5000", "--out", str(out)]) == 0
    _, whole = read(out)
    assert np.mean(whole[:, 2] < 100) > 0.5  # most speeds limited by "chatter" below 100 Hz: noise
    assert whole[:, 1].min() < 0.6  # mm (the noise-free FRF: 2.88 mm)
    capsys.readouterr()

    assert main(["lobes", str(noisy), *NOISY_CUT, "--out", str(out)]) == 0
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith(f"note: {noisy}: trusted band ")
    lo = float(err[0].split("trusted band ")[1].split("–")[0])
    assert 126 < lo < 230  # the noise crosses the clean receptance at 126 Hz (tests/test_trust.py)
    assert "override with --band LO:HI" in err[0]
    _, trusted = read(out)
    assert np.all(trusted[:, 2] >= lo) and np.all(trusted[:, 2] > 600)  # near the modes, none in the junk

    assert main(["lobes", str(clean), *NOISY_CUT, "--out", str(out)]) == 0
    assert capsys.readouterr().err == ""  # the clean FRF keeps its band: no note
    _, ref = read(out)
    np.testing.assert_allclose(trusted[:, 1], ref[:, 1], rtol=0.01)  # the noise-free limit, within 1 %


def _fitted_fn_hz(text):
    """Natural frequencies of the modal-fit table printed by ``lobes --method sdm``."""
    rows = [ln.split() for ln in text.splitlines()]
    return [float(r[1]) for r in rows if len(r) == 3 and r[0].isdigit()]


@pytest.mark.slow
def test_sdm_on_noisy_frf_weighs_the_fit_as_accelerance_noise(tmp_path, noisy_files, capsys):
    """The receptance's noise grows as 1/ω² (tests/test_trust.py): the trusted band says so and the SDM path's
    modal fit is weighted in accelerance. Weighted in receptance it put three ultra-light modes (177–219 Hz,
    ζ 0.07–0.17 %) on the noise just above the band edge; now it finds only the three modes (650, 1056,
    2400 Hz) and the noise-free FRF's limit."""
    noisy, clean = noisy_files
    cut = [*NOISY_CUT[:-1], "60", "--method", "sdm"]
    out = tmp_path / "l.csv"
    assert main(["lobes", str(noisy), *cut, "--out", str(out)]) == 0
    fn = _fitted_fn_hz(capsys.readouterr().out)
    assert len(fn) == 3 and min(fn) > 300
    assert fn == pytest.approx([650.0, 1056.0, 2400.0], rel=1e-3)
    _, data = read(out)
    assert main(["lobes", str(clean), *cut, "--out", str(out)]) == 0
    _, ref = read(out)
    assert np.nanmin(data[:, 1]) == pytest.approx(np.nanmin(ref[:, 1]), rel=0.05)


def test_limit_at_the_band_edge_is_not_trusted(tmp_path, noisy_files, capsys):
    """--band cuts into the 1056 Hz mode: the speeds limited at the band edge are named on stderr."""
    _, clean = noisy_files
    out = tmp_path / "l.csv"
    assert main(["lobes", str(clean), *NOISY_CUT, "--band", "1065:5000", "--out", str(out)]) == 0
    cap = capsys.readouterr()
    warn = [w for w in cap.err.splitlines() if w.startswith("warning:")]
    assert len(warn) == 1 and "the limiting chatter frequency lies at the edge of the band 1065–5000 Hz" in warn[0]
    assert "not trusted" in warn[0] and "--band LO:HI" in warn[0]
    assert "— not trusted: chatter at the band edge" in cap.out and "lowest trusted limit:" in cap.out
    _, data = read(out)
    n = int(warn[0].split("at ")[1].split(" of")[0])
    assert n == int(np.sum(data[:, 2] <= 1067.0))


@pytest.mark.parametrize("band", ["6000:7000", "4999.5:4999.9"])
def test_lobes_band_outside_the_data(tmp_path, noisy_files, capsys, band):
    noisy, _ = noisy_files
    out = tmp_path / "l.csv"
    err = _refused(["lobes", str(noisy), *NOISY_CUT, "--band", band, "--out", str(out)], capsys, out)
    assert err.startswith(f"toolpoint lobes: error: {noisy}: --band: band ") and "the data cover 0–5000 Hz" in err


def test_lobes_low_coherence_is_left_out(tmp_path, capsys):
    """A coherence column below 0.8 above 2000 Hz: the band ends there and the note says why."""
    f = np.linspace(0.0, 3000.0, 3001)
    g = np.where(f > 2000, 0.3, 0.99)
    x = tmp_path / "coh.csv"
    with open(x, "w") as fh:
        fh.write("freq_hz,real,imag,coherence\n")
        v = MODE.frf(f).values
        np.savetxt(fh, np.column_stack([f, v.real, v.imag, g]), delimiter=",", fmt="%.17g")
    out = tmp_path / "l.csv"
    assert main(["lobes", str(x), *BASE, "--rpm-points", "100", "--out", str(out)]) == 0
    err = capsys.readouterr().err.strip()
    assert err == (f"note: {x}: trusted band 0–2000 Hz (coherence γ² < 0.8 above 2000 Hz); override with "
                   "--band LO:HI")
    _, data = read(out)
    assert np.nanmax(data[:, 2]) <= 2000


def test_trusted_bands_of_x_and_y_on_other_grids_intersect(tmp_path, capsys):
    """x on a 1 Hz grid, y on a 2 Hz grid, each with its own junk: one band for both, one note each."""
    from test_trust import noisy_toolpoint

    f, _, nx = noisy_toolpoint(0)
    _, _, ny = noisy_toolpoint(1)
    x = write_csv(tmp_path / "x.csv", f, nx)
    y = write_csv(tmp_path / "y.csv", f[::2], ny[::2])
    out = tmp_path / "l.csv"
    assert main(["lobes", str(x), "--frf-y", str(y), *NOISY_CUT, "--out", str(out)]) == 0
    notes = capsys.readouterr().err.strip().splitlines()
    assert [n.split(":")[1].strip() for n in notes] == [str(x), str(y)]
    edges = [float(n.split("trusted band ")[1].split("–")[0]) for n in notes]
    _, data = read(out)
    assert np.all(data[:, 2] >= max(edges)) and data[:, 1].min() == pytest.approx(2.88, abs=0.02)


def test_no_chatter_is_not_claimed_from_a_band_below_the_resonance(tmp_path, capsys):
    """A soft hammer tip's FRF ends below the tool's dominant mode (the virtual tap with a rubber tip: band 71–786 Hz,
    the 1071 Hz mode above it): no lobe reaches the speeds, and `lobes` wrote inf everywhere with "no chatter found" —
    a safe-looking answer the data do not hold. Now refused in one line saying what would decide. Where limits are
    found but the band's largest |H| still sits at its edge (a mode above a band given too narrow), it is warned."""
    import warnings

    from toolpoint.io.frf_files import write_frf
    from toolpoint.io.impact import Record, impact_frf
    from toolpoint.io.virtual_tap import lab_like_tap

    rec = lab_like_tap(seed=1, hits=3, spacing_s=0.07, tip="rubber")
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        frf = impact_frf(Record(rec.time_s, rec.force_n, rec.acceleration_ms2, source="v")).frf
    soft = tmp_path / "rubber.csv"
    write_frf(soft, frf)
    cut = ["--teeth", "4", "--tangential-coeff", "796e6", "--radial-ratio", "0.212", "--immersion", "0.5"]
    out = tmp_path / "l.csv"
    assert main(["lobes", str(soft), *cut, "--rpm", "5000:20000", "--out", str(out)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "rubber.csv: FRF: no lobe within the band" in err[0] and "upper edge" in err[0]
    assert not out.exists()
    # two modes, the band given up to below the stronger: limits from the weaker one, and a warning
    f = np.linspace(0.0, 3000.0, 3001)
    two = ModalModel([500.0, 1000.0], [0.03, 0.02], [1.0, 0.05]).frf(f)
    path = write_csv(tmp_path / "two.csv", f, two.values)
    assert main(["lobes", str(path), *BASE, "--band", "50:900", "--out", str(out)]) == 0
    cap = capsys.readouterr()
    assert "the largest |H| sits at the band's upper edge (900 Hz)" in cap.err and out.exists()
