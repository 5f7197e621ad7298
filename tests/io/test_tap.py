"""Impact tests → FRF (toolpoint.io.impact and ``toolpoint tap``), against a closed-form 3-mode system."""

import warnings

import numpy as np
import pytest
import pyuff

import tap_synth as S
from toolpoint.cli.main import main
from toolpoint.errors import InputError
from toolpoint.io.frf_files import read_frf
from toolpoint.io.impact import Record, corrected_damping, find_hits, impact_frf, read_record

FS = 51200.0  # high enough that the aliased force spectrum is < 0.1 % at the modes (see tap_synth)


@pytest.fixture(scope="module")
def synth():
    return S.record(fs=FS)


def peak_errors(frf, exact):
    """Relative error and index at the grid point of each exact peak."""
    out = []
    for fn in S.FN:
        k = int(np.argmin(abs(frf.freq_hz - fn)))
        k = k - 5 + int(np.argmax(abs(exact[k - 5:k + 6])))
        out.append((abs(frf.values[k] / exact[k] - 1), k))
    return out


@pytest.mark.parametrize("estimator", ["H1", "H2"])
def test_frf_within_1_percent_at_peaks_double_hit_flagged(synth, estimator):
    rec = Record(*synth, "acceleration", "synth")
    with pytest.warns(UserWarning, match=r"synth: hit 4 at 1\.85.*double hit.*dropped"):
        res = impact_frf(rec, drop_bad=True, estimator=estimator)
    assert [h.number for h in res.hits if h.double_at_s is not None] == [4]
    # the second pulse (0.4 × 90 N at 1.853 s, 0.5 ms half-sine) crosses 10 % of 90 N a quarter-sine later
    assert res.hits[3].double_at_s == pytest.approx(1.853 + 5e-4 / np.pi * np.arcsin(9.0 / 36.0), abs=1 / FS)
    assert res.used == [1, 2, 3, 5]
    assert res.frf.quantity == "receptance" and res.frf.freq_hz[0] > 0
    for err, k in peak_errors(res.frf, S.exact_receptance(res.frf.freq_hz)):
        assert err < 0.01
        assert res.coherence[k] >= 0.99
    assert np.array_equal(res.frf.meta["coherence"], res.coherence)


def test_double_hit_kept_with_warning(synth):
    with pytest.warns(UserWarning, match="hit 4 .*double hit.*kept"):
        res = impact_frf(Record(*synth), estimator="H1")
    assert res.used == [1, 2, 3, 4, 5]
    for err, _ in peak_errors(res.frf, S.exact_receptance(res.frf.freq_hz)):
        assert err < 0.01  # H1 with the whole double pulse inside the force window is still right


def test_exponential_window_shifts_poles_by_one_over_tau():
    t, f, a = S.record(fs=FS, hits=((0.05, 100.0),), double=None, duration=0.3, noise=(0, 0))
    tau = 0.02
    with pytest.warns(UserWarning, match="one hit"):
        res = impact_frf(Record(t, f, a), exp_window_s=tau)
    # x w = (h e^{-t/τ}) * (f w) for w = e^{-(t − t_block)/τ} on both channels: the estimate is the FRF of
    # h(t) e^{-t/τ}, i.e. poles λ − 1/τ with the same residues
    lam, amp = S.poles()
    s = 2j * np.pi * res.frf.freq_hz[:, None]
    lam2 = lam - 1 / tau
    exact = np.sum(amp / (s - lam2) + np.conj(amp) / (s - np.conj(lam2)), axis=1)
    for err, _ in peak_errors(res.frf, exact):
        assert err < 0.01
    assert res.added_damping(500.0) == pytest.approx(1 / (2 * np.pi * 500 * tau))
    # corrected_damping undoes the pole shift exactly
    w2 = np.abs(lam2)
    c = corrected_damping(w2 / (2 * np.pi), -lam2.real / w2, tau)
    np.testing.assert_allclose(c.fn_hz, S.FN, rtol=1e-12)
    np.testing.assert_allclose(c.zeta, S.ZETA, rtol=1e-12)


def test_several_files_one_hit_each_equal_one_long_record(synth, tmp_path):
    t, f, a = synth
    n = int(0.6 * FS)
    paths = []
    for k in (0, 1, 2):  # hits 1–3, one per file
        i = int(round((0.05 + 0.6 * k) * FS)) - 100
        p = tmp_path / f"hit{k}.csv"
        np.savetxt(p, np.column_stack([t[i:i + n] - t[i], f[i:i + n], a[i:i + n]]), delimiter=",",
                   header="time_s,force_n,acc_ms2", comments="", fmt="%.17g")
        paths.append(p)
    recs = [read_record(p) for p in paths]
    res = impact_frf(recs)
    assert res.used == [1, 2, 3] and [h.record for h in res.hits] == [0, 1, 2]
    for err, k in peak_errors(res.frf, S.exact_receptance(res.frf.freq_hz)):
        assert err < 0.01 and res.coherence[k] >= 0.99


def test_clipped_force_is_an_error_or_dropped(synth):
    t, f, a = synth
    f = f.copy()
    i = int(1.25 * FS)
    f[i:i + 40] = np.minimum(f[i:i + 40], 60.0)  # hit 3 (120 N) clipped at 60 N
    with pytest.raises(InputError, match=r"overload: hit 3 at 1\.25.*force clipped.*--drop-bad"):
        impact_frf(Record(t, f, a, source="rec.csv"))
    with pytest.warns(UserWarning) as got:
        res = impact_frf(Record(t, f, a, source="rec.csv"), drop_bad=True)
    assert res.used == [1, 2, 5]
    assert any("hit 3" in str(w.message) and "clipped" in str(w.message) for w in got)


RECORD_ERRORS = [
    ("no hit", lambda t, f, a: (t, 0 * f, a), "force_n", "no hit"),
    ("lengths", lambda t, f, a: (t, f[:-1], a), "length", "lengths differ"),
    ("time", lambda t, f, a: (np.r_[t[:5], t[4], t[6:]], f, a), "time_s", "sample 6"),
    ("uneven", lambda t, f, a: (np.r_[t[:5], t[5:] + 0.7 * (t[1] - t[0])], f, a), "time_s", "not uniform"),
]


@pytest.mark.parametrize("name, change, field, msg", RECORD_ERRORS, ids=[e[0] for e in RECORD_ERRORS])
def test_record_errors(name, change, field, msg):
    t, f, a = S.record(fs=5000.0, hits=((0.05, 100.0),), double=None, duration=0.2)
    with pytest.raises(InputError) as info:
        impact_frf(Record(*change(t, f, a), source="r.txt"))
    s = str(info.value)
    assert s.startswith(f"r.txt: {field}: ") and msg in s and "\n" not in s


def test_text_record_errors(tmp_path):
    p = tmp_path / "r.txt"
    p.write_text("t\tF\ta\n0\t0\t0\n1e-4\t1\t2\n0.5e-4\t1\t2\n")
    with pytest.raises(InputError, match=r"r\.txt: time_s: line 4: time must increase"):
        read_record(p)
    p.write_text("0 0 0\n1e-4 x 2\n")
    with pytest.raises(InputError, match=r"r\.txt: force_n: line 2: 'x' is not a number"):
        read_record(p)
    p.write_text("0 0 0\n1e-4 1\n")
    with pytest.raises(InputError, match=r"r\.txt: columns: line 2: expected 3"):
        read_record(p)
    # a LabVIEW export's Comment column, empty on every row, is no column; empty on some rows only it is a
    # missing value
    p.write_text("X_Value,Force (N),Accel (m/s^2),Comment\n"
                 + "".join(f"{1e-4 * k:g},{k},{2 * k},\n" for k in range(10)))
    r = read_record(p)
    assert np.allclose(r.force_n, np.arange(10)) and np.allclose(r.response, 2 * np.arange(10))
    p.write_text("0,0,0,\n1e-4,1,2,x\n")
    with pytest.raises(InputError, match=r"r\.txt: columns: line 1: column 4 is empty"):
        read_record(p)


def test_the_header_s_units_are_read(synth, tmp_path):
    """A DAQ exports the response in g and names it ("Accel (g)", or a units row under the names): read as m/s² it
    was an FRF 9.8 × too small — a tool 9.8 × too stiff, lobes far too high. The header's units are now read (time
    ms/µs, force kN/lbf, acceleration g, mm/s² …) and the record is the same as in SI; a voltage, a response of
    another kind than --response, a force in g are refused naming the column."""
    t, f, a = (c[:20000] for c in synth)  # the header is the subject: a 0.4 s stretch (the whole record took 14 s)
    ref = read_record(_write(tmp_path / "si.csv", "time_s,force_n,acceleration_ms2", t, f, a))
    cases = (("g.csv", "Time (s),Force (N),Accel (g)", t, f, a / 9.80665),
             ("units.csv", "Time;Force;Accel\nms;kN;g", 1e3 * t, 1e-3 * f, a / 9.80665),
             ("lbf.csv", "t [us],F [lbf],a [mm/s^2]", 1e6 * t, f / 4.4482216, 1e3 * a))
    for name, head, *cols in cases:
        r = read_record(_write(tmp_path / name, head, *cols))
        assert np.allclose(r.time_s, ref.time_s, rtol=1e-9, atol=1e-12), name
        assert np.allclose(r.force_n, ref.force_n, rtol=1e-6) and np.allclose(r.response, ref.response, rtol=1e-6)
    bad = (("t (s),F (N),v (mm/s)", "response",
            r"column 'v \(mm/s\)' holds a velocity and the record is read as acceleration: give --response velocity"),
           ("t (s),F (V),a (g)", "force_n", r"column 'F \(V\)' is a voltage: divide it by the sensor's"),
           ("t (s),F (g),a (g)", "force_n", r"column 'F \(g\)' holds an acceleration, where a force"))
    for head, field, msg in bad:
        with pytest.raises(InputError, match=f"{field}: {msg}"):
            read_record(_write(tmp_path / "bad.csv", head, t, f, a))
    assert np.allclose(read_record(_write(tmp_path / "v.csv", "t (s),F (N),v (mm/s)", t, f, a),
                                   response="velocity").response, 1e-3 * a)


def _write(path, head, t, f, a):
    sep = ";" if ";" in head else ","
    rows = "".join(f"{x:.12g}{sep}{y:.10g}{sep}{z:.10g}\n" for x, y, z in zip(t, f, a))
    path.write_text(head + "\n" + (rows.replace(".", ",") if sep == ";" else rows))
    return path


def uff_record(path, t, f, a, rsp_type=12, force_inc=None):
    sets = []
    for data, odt in ((f, 13), (a, rsp_type)):
        x = t if odt != 13 or force_inc is None else t[0] + force_inc * np.arange(t.size)
        sets.append(pyuff.prepare_58(binary=0, func_type=1, rsp_node=1, rsp_dir=3, ref_node=1, ref_dir=3,
                                     ord_data_type=4, abscissa_spacing=1, abscissa_spec_data_type=17,
                                     ordinate_spec_data_type=odt, orddenom_spec_data_type=0,
                                     abscissa_axis_units_lab="s", data=np.asarray(data, float), x=x))
    pyuff.UFF(str(path)).write_sets(sets, mode="add")


def test_uff_time_records(tmp_path):
    t, f, a = S.record(fs=5000.0, hits=((0.05, 100.0),), double=None, duration=0.4)
    p = tmp_path / "rec.uff"
    uff_record(p, t, f, a)
    rec = read_record(p)
    assert rec.response_kind == "acceleration"
    np.testing.assert_allclose(rec.force_n, f, rtol=1e-10, atol=1e-10 * abs(f).max())
    np.testing.assert_allclose(rec.response, a, rtol=1e-10, atol=1e-10 * abs(a).max())
    q = tmp_path / "bad.uff"
    uff_record(q, t, f, a, force_inc=1.01 / 5000)
    with pytest.raises(InputError, match=r"bad\.uff: abscissa_inc: force and response sampling differ"):
        read_record(q)



def test_a_record_of_several_responses_reads_the_channel_chosen(tmp_path, capsys):
    """A lab's tap record often holds the hammer and a triaxial accelerometer (or two directions): time, force and
    three responses. It was refused ("expected 3 columns, found 5"); ``channel`` (CLI ``--channel``) now picks one,
    read exactly as a three-column file of it is, and several without a choice are refused naming them."""
    t, f, a = S.record(fs=5000.0, hits=((0.05, 100.0),), double=None, duration=0.4)
    ref = read_record(_write(tmp_path / "y.csv", "Time (s),Force (N),Ay (g)", t, f, a))
    tri = tmp_path / "tri.csv"
    tri.write_text("Time (s),Force (N),Ax (g),Ay (g),Az (g)\n" + "".join(
        f"{x:.12g},{y:.10g},{0.3 * z:.10g},{z:.10g},{-0.1 * z:.10g}\n" for x, y, z in zip(t, f, a)))
    got = read_record(tri, channel=1)
    assert np.array_equal(got.response, ref.response) and np.array_equal(got.force_n, ref.force_n)
    with pytest.raises(InputError) as exc:
        read_record(tri)
    assert exc.value.field == "channel" and "3 response columns: choose one with --channel (0: Ax (g), 1: Ay (g), " \
        "2: Az (g))" in exc.value.message
    with pytest.raises(InputError, match=r"tri\.csv: channel: channel 3 does not exist \(the record has 3 response "
                                         r"columns: 0\.\.2\)"):
        read_record(tri, channel=3)
    assert np.array_equal(read_record(ref.source, channel=0).response, ref.response)  # one response: 0 or nothing
    # the force where the header puts it (a DAQ orders its channels by number): by its unit, or by its name
    for head, cols, ch in (("Time (s),Ay (g),Force (N)", (t, a / 9.80665, f), None),
                           ("time,ax,hammer,ay", (t, 0.5 * a, f, a), 1)):
        q = tmp_path / "order.csv"
        q.write_text(head + "\n" + "".join(",".join(f"{v:.12g}" for v in row) + "\n" for row in zip(*cols)))
        got = read_record(q, channel=ch)
        assert np.allclose(got.force_n, f, rtol=1e-9) and np.allclose(got.response, a, rtol=1e-6), head
    # a UFF file's response time histories, in file order
    u = tmp_path / "two.uff"
    uff_record(u, t, f, a)
    pyuff.UFF(str(u)).write_sets([pyuff.prepare_58(
        binary=0, func_type=1, rsp_node=1, rsp_dir=2, ref_node=1, ref_dir=3, ord_data_type=4, abscissa_spacing=1,
        abscissa_spec_data_type=17, ordinate_spec_data_type=12, orddenom_spec_data_type=0,
        abscissa_axis_units_lab="s", data=np.asarray(2 * a, float), x=t)], mode="add")
    assert np.allclose(read_record(u, channel=1).response, 2 * a) and np.allclose(read_record(u, channel=0).response,
                                                                                   a)
    with pytest.raises(InputError, match=r"two\.uff: channel: 2 response time histories: choose one with --channel "
                                         r"\(0: dataset 1"):
        read_record(u)
    # the command line: the FRF of the channel chosen is that of its own file; none chosen is one line, exit 2
    one, three = tmp_path / "one.csv", tmp_path / "three.csv"
    assert main(["tap", str(ref.source), "--out", str(one)]) == 0
    assert main(["tap", str(tri), "--channel", "1", "--out", str(three)]) == 0
    assert three.read_text() == one.read_text()
    capsys.readouterr()
    assert main(["tap", str(tri), "--out", str(tmp_path / "none.csv")]) == 2
    err = capsys.readouterr().err.strip()
    assert "\n" not in err and "choose one with --channel" in err and not (tmp_path / "none.csv").exists()
    assert main(["tap", str(tri), "--channel", "x", "--out", str(tmp_path / "none.csv")]) == 2
    assert "--channel: must be a whole number, got 'x'" in capsys.readouterr().err

def test_uff_without_time_data(tmp_path):
    from toolpoint.io.frf_files import write_frf
    from toolpoint.frf import FRF

    p = tmp_path / "frf.uff"
    write_frf(p, FRF([1.0, 2.0, 3.0], [1j, 2j, 3j]))
    with pytest.raises(InputError, match=r"frf\.uff: func_type: no time history"):
        read_record(p)


def test_find_hits_threshold_checked(synth):
    with pytest.raises(InputError, match="threshold: threshold must be in"):
        find_hits(Record(*synth), threshold=1.5)


# ---------------------------------------------------------------- CLI
@pytest.fixture(scope="module")
def synth_file(synth, tmp_path_factory):
    p = tmp_path_factory.mktemp("tap") / "rec.tsv"
    np.savetxt(p, np.column_stack(synth), delimiter="\t", fmt="%.10e")
    return p


@pytest.mark.slow
def test_cli_csv_uff_frf_and_plot(synth_file, tmp_path, capsys):
    out, png = tmp_path / "h.csv", tmp_path / "h.png"
    assert main(["tap", str(synth_file), "--out", str(out), "--drop-bad", "--plot", str(png), "--fmax", "2000"]) == 0
    err = capsys.readouterr().err
    assert "hit 4" in err and "dropped" in err and "4 of 5 hits averaged" in err
    assert out.read_text().splitlines()[0] == "freq_hz,real,imag,coherence"
    got = read_frf(out)
    assert got.freq_hz[-1] <= 2000 and png.stat().st_size > 0
    for e, k in peak_errors(got, S.exact_receptance(got.freq_hz)):
        assert e < 0.01 and got.meta["coherence"][k] >= 0.99
    uff = tmp_path / "h.uff"
    assert main(["tap", str(synth_file), "--out", str(uff), "--drop-bad", "--fmax", "2000"]) == 0
    ug = read_frf(uff)
    assert pyuff.UFF(str(uff)).get_n_sets() == 2
    np.testing.assert_allclose(ug.values, got.values, rtol=1e-10)
    np.testing.assert_allclose(ug.meta["coherence"], got.meta["coherence"], atol=1e-10)
    cp = tmp_path / "h.frf"
    assert main(["tap", str(synth_file), "--out", str(cp), "--drop-bad", "--fmax", "2000"]) == 0
    np.testing.assert_array_equal(read_frf(cp).values, got.values)
    meas = tmp_path / "m.uff"
    assert main(["tap", str(synth_file), "--out", str(meas), "--drop-bad", "--fmax", "2000",
                 "--output-quantity", "measured"]) == 0
    with pytest.warns(UserWarning, match="dropped the 0 Hz point"):
        m = read_frf(meas)  # the UFF says accelerance: read back as receptance
    # accelerance / (−ω²) with ω from ASCII UFF's 6-digit abscissa (relative rounding ≤ 5e-6, squared)
    np.testing.assert_allclose(m.values, got.values, rtol=1.1e-5)


def test_cli_bad_input_exit_2_no_output(tmp_path, capsys):
    p = tmp_path / "flat.csv"
    np.savetxt(p, np.column_stack([np.arange(100) / 1e3, np.zeros(100), np.zeros(100)]), delimiter=",")
    out = tmp_path / "o.csv"
    assert main(["tap", str(p), "--out", str(out)]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "flat.csv: force_n: no hit" in err
    assert not out.exists() and sorted(x.name for x in tmp_path.iterdir()) == ["flat.csv"]
    assert main(["tap", str(p), "--out", str(p)]) == 2
    assert "is one of this command's inputs" in capsys.readouterr().err
    assert main(["tap", str(p), "--out", str(tmp_path / "o.xyz")]) == 2
    assert "unknown FRF file extension" in capsys.readouterr().err
    assert main(["tap", str(p), "--out", str(out), "--threshold", "2"]) == 2
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        assert "--threshold: must be in (0, 1)" in capsys.readouterr().err


# ---------------------------------------------------------------- the realistic virtual impact test (issue 20)
from dataclasses import replace  # noqa: E402
from pathlib import Path  # noqa: E402

from scipy.optimize import brentq  # noqa: E402

from toolpoint.io import virtual_tap as V  # noqa: E402

EXAMPLE = Path(__file__).resolve().parents[2] / "examples" / "tap_record.csv"
LAB_HZ, LAB_ZETA = (1071.0, 1981.0, 2607.0), (0.037, 0.041, 0.021)


def tap_of(rec, **kw):
    return impact_frf(Record(rec.time_s, rec.force_n, rec.acceleration_ms2, source="virtual"), **kw)


def at(f, hz):
    return [int(np.argmin(abs(f - x))) for x in hz]


def test_virtual_record_clean_gives_the_exact_receptance():
    # no artefacts: what is left is the estimator and the sampling. Independent: the record is made from the
    # hammer's and structure's continuous spectra, the FRF by DFTs of hit blocks of the time record
    rec = V.lab_like_tap(seed=1, hits=3, spacing_s=0.07, chain=V.Chain().clean())
    res = tap_of(rec)
    f = res.frf.freq_hz
    err = np.abs(res.frf.values / rec.receptance(f) - 1)
    assert err[f >= 100].max() < 1e-3  # measured 3.4e-4 (the force window cuts the anti-aliasing filter's ringing)
    assert err[at(f, LAB_HZ)].max() < 5e-4  # measured 1.8e-4
    assert err[f >= 20].max() < 5e-3


@pytest.mark.parametrize("tip", ["steel", "plastic", "rubber"])
@pytest.mark.parametrize("drop_db", [10.0, 15.0, 20.0])
def test_band_ends_where_the_half_sine_force_spectrum_has_dropped(tip, drop_db):
    # closed form of a half-sine of contact time T: |F(f)/F(0)| = |cos(π f T)| / |1 − (2 f T)²|
    tc = V.TIPS[tip]
    x = brentq(lambda x: abs(np.cos(np.pi * x / 2) / (1 - x * x)) - 10 ** (-drop_db / 20), 1.01, 2.99)
    f_drop = x / (2 * tc)
    rec = V.lab_like_tap(seed=0, hits=2, spacing_s=0.1, tip=tip)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # rubber: leakage of nothing; the band is what is checked
        res = tap_of(rec, force_drop_db=drop_db)
    df = res.frf.freq_hz[1] - res.frf.freq_hz[0]
    # the level is the median over 0–0.1/T_pulse, a hair below F(0): the band may end one line later
    assert abs(res.band_hz[1] - f_drop) <= 2 * df + 0.01 * f_drop
    assert f"{drop_db:g} dB below" in res.notes[0] and "band ends at" in res.notes[0]
    assert f_drop < 1.5 / tc  # before the first zero of the spectrum


def test_realistic_chain_within_the_band():
    rec = V.lab_like_tap(seed=3, hits=3, spacing_s=0.07)  # every artefact of Chain(), close x/y modes
    res = tap_of(rec)
    f = res.frf.freq_hz
    assert res.band_hz[1] == pytest.approx(1.19 / V.TIPS["steel"], rel=0.01)  # 15 dB of the steel tip's spectrum
    df = f[1] - f[0]
    hum = np.any([abs(f - h * 50.0) <= 2 * df for h in (1, 3, 5)], axis=0)
    exact = rec.receptance(f)
    err = np.abs(res.frf.values / exact - 1)
    assert err[(f >= 500) & ~hum].max() < 0.01  # measured 1.7e-3–3.3e-3 over seeds 0–5
    assert err[(f >= 200) & ~hum].max() < 0.05  # 1.2e-2–2.8e-2 (noise × 1/ω² grows towards 0 Hz)
    k = at(f, LAB_HZ)
    assert err[k].max() < 2e-3 and res.coherence[k].min() > 0.999
    # at the modes what is left is the accelerometer's high-pass, |1 − iω/(iω + ω_c)| ≈ f_c/f
    chain = np.abs(res.frf.values / V.chain_receptance(rec.modes, f, rec.chain) - 1)
    assert chain[k].max() < 5e-4  # measured 1.8e-4–2.1e-4 (noise)


def test_detrend_removes_the_drift_artefact():
    # offset and linear drift only (the other artefacts off), one hit in 0.5 s as the lab's record
    chain = replace(V.Chain().clean(), offset_ms2=0.2, drift_ms2_per_s=0.1)
    rec = V.lab_like_tap(seed=0, hits=1, spacing_s=0.5, chain=chain)
    with pytest.warns(UserWarning, match="one hit"):
        raw = tap_of(rec, detrend="none")
    with pytest.warns(UserWarning, match="one hit"):
        fixed = tap_of(rec)
    f = raw.frf.freq_hz
    exact = rec.receptance(f)
    e_raw, e_fix = (np.abs(r.frf.values / exact - 1) for r in (raw, fixed))
    low = (f >= 5) & (f <= 40)
    slope = np.polyfit(np.log(f[low]), np.log(np.abs(raw.frf.values - exact)[low]), 1)[0]
    assert -3.2 < slope < -2.8  # drift b·t: b T/(iω) in acceleration, ÷ ω² F: f⁻³ in the receptance
    assert e_raw[at(f, [10.0])][0] > 50 and e_fix[low].max() < 0.05  # measured 97 → 0.016 at 10 Hz
    assert any("drift of the acceleration removed" in n for n in fixed.notes)
    assert not any("drift" in n for n in raw.notes)


def test_single_hit_has_no_coherence(tmp_path, capsys):
    rec = V.lab_like_tap(seed=0, hits=1, spacing_s=0.3)
    with pytest.warns(UserWarning, match=r"virtual: one hit: its coherence is 1 by construction"):
        res = tap_of(rec)
    assert res.single_hit and "coherence" not in res.frf.meta
    p = tmp_path / "one.csv"
    V.write_record(p, rec)
    out = tmp_path / "h.csv"
    assert main(["tap", str(p), "--out", str(out)]) == 0
    err = capsys.readouterr().err
    assert "one hit: its coherence is 1 by construction" in err and "one hit: no coherence" in err
    assert out.read_text().splitlines()[0] == "freq_hz,real,imag"


def test_example_record_is_the_virtual_test():
    # the shipped example is what examples/make_tap_record.py writes (to the 6 digits of the file)
    rec = V.lab_like_tap(seed=2026, hits=3, spacing_s=0.07)
    got = read_record(EXAMPLE)
    np.testing.assert_allclose(got.time_s, rec.time_s, rtol=0, atol=1e-8)
    np.testing.assert_allclose(got.force_n, rec.force_n, rtol=1e-5, atol=1e-3)
    np.testing.assert_allclose(got.response, rec.acceleration_ms2, rtol=1e-5, atol=1e-3)
    assert EXAMPLE.stat().st_size < 400_000
    assert EXAMPLE.read_text().startswith("# SYNTHETIC impact record")


def test_tap_output_gives_sane_lobes_and_modes(tmp_path, capsys):
    # tap → lobes and tap → modal with defaults on the example record, against the same commands on the exact
    # receptance of the virtual structure (issue 20: chatter above 500 Hz, the three modes within 2 %)
    from toolpoint.frf import FRF
    from toolpoint.io.frf_files import write_frf

    h = tmp_path / "tap.csv"
    assert main(["tap", str(EXAMPLE), "--out", str(h)]) == 0
    capsys.readouterr()
    f = read_frf(h).freq_hz
    ref = tmp_path / "exact.csv"
    write_frf(ref, FRF(f, V.receptance(V.close_xy_modes(V.LAB_MODES), f)))
    lobes = ["--teeth", "4", "--tangential-coeff", "7.96e8", "--radial-ratio", "0.212", "--immersion", "0.5",
             "--rpm", "2000:20000", "--rpm-points", "400"]
    got = {}
    for name, src in (("tap", h), ("exact", ref)):
        out = tmp_path / f"lobes_{name}.csv"
        assert main(["lobes", str(src), *lobes, "--out", str(out)]) == 0
        got[name] = np.genfromtxt(out, delimiter=",", names=True)
    capsys.readouterr()
    k = int(np.argmin(got["tap"]["depth_mm"]))
    assert got["tap"]["chatter_hz"][k] > 500
    assert got["tap"]["depth_mm"].min() == pytest.approx(got["exact"]["depth_mm"].min(), rel=0.02)
    np.testing.assert_allclose(got["tap"]["depth_mm"], got["exact"]["depth_mm"], rtol=0.05)
    modes = tmp_path / "modes.csv"
    assert main(["modal", str(h), "--out", str(modes)]) == 0
    m = np.genfromtxt(modes, delimiter=",", names=True)
    for fn, z in zip(LAB_HZ, LAB_ZETA):
        j = int(np.argmin(abs(m["freq_hz"] - fn)))
        assert m["freq_hz"][j] == pytest.approx(fn, rel=0.02)
        assert 0.015 < m["damping_ratio"][j] < 0.07 and m["damping_ratio"][j] == pytest.approx(z, rel=0.1)


# ---------------------------------------------------------------- bad input (issue 22)
def small_record(path, t, f, a):
    np.savetxt(path, np.column_stack([t, f, a]), delimiter=",", fmt="%.17g")
    return path


def one_pulse(n=2000, fs=1e4, at=100):
    t = np.arange(n) / fs
    f = np.zeros(n)
    f[at:at + 5] = [1, 3, 5, 3, 1]
    a = np.random.default_rng(0).standard_normal(n)
    return t, f, a


def cli_error(capsys, argv):
    assert main(argv) == 2
    err = capsys.readouterr().err
    lines = err.splitlines()
    assert "Traceback" not in err and [x for x in lines if "error" in x] == lines[-1:]  # warnings may precede
    return lines[-1]


def test_subnormal_time_step_refused(tmp_path, capsys):
    t, f, a = one_pulse()
    with pytest.raises(InputError, match=r"r\.csv: time_s: time step 4\.94e-324 s is outside"):
        Record(t * 0 + np.arange(t.size) * 5e-324, f, a, source="r.csv")
    p = small_record(tmp_path / "tiny.csv", np.arange(t.size) * 5e-324, f, a)
    assert "tiny.csv: time_s: time step" in cli_error(capsys, ["tap", str(p), "--out", str(tmp_path / "o.csv")])
    assert sorted(x.name for x in tmp_path.iterdir()) == ["tiny.csv"]


def test_huge_pretrigger_refused(tmp_path, capsys):
    p = small_record(tmp_path / "r.csv", *one_pulse())
    err = cli_error(capsys, ["tap", str(p), "--out", str(tmp_path / "o.csv"), "--pretrigger", "1e9"])
    assert "--pretrigger: must be shorter than --min-gap" in err
    with pytest.raises(InputError, match=r"r\.csv: pretrigger_s: pretrigger 1e\+09 s must be"):
        find_hits(read_record(p), pretrigger_s=1e9)
    with pytest.raises(InputError, match=r"min_gap_s: min_gap_s must be a finite time"):
        find_hits(read_record(p), min_gap_s=float("inf"))
    assert sorted(x.name for x in tmp_path.iterdir()) == ["r.csv"]


def test_hit_at_the_last_sample_refused(tmp_path, capsys):
    t, f, a = one_pulse()
    f = np.zeros_like(f)
    f[-1] = 5.0
    p = small_record(tmp_path / "last.csv", t, f, a)
    err = cli_error(capsys, ["tap", str(p), "--out", str(tmp_path / "o.csv")])
    assert "last.csv: hits: hit 1 at 0.1999 s: cut off by the end of the record" in err
    assert sorted(x.name for x in tmp_path.iterdir()) == ["last.csv"]


def test_hit_cut_off_at_the_end_is_dropped_from_the_others(synth):
    t, f, a = synth
    n = int(2.47 * FS)  # the record ends 20 ms into hit 5 (at 2.45 s)
    with pytest.warns(UserWarning) as got:
        res = impact_frf(Record(t[:n], f[:n], a[:n], source="r"), drop_bad=True)
    assert res.used == [1, 2, 3] and res.hits[4].cut_s == pytest.approx(0.02, abs=2 / FS)
    assert any("hit 5" in str(w.message) and "cut off" in str(w.message) for w in got)
    # blocks keep their full length (0.6 s, not the 20 ms left of hit 5)
    assert res.frf.freq_hz[1] - res.frf.freq_hz[0] == pytest.approx(1 / 0.6, rel=0.01)


def test_zero_response_names_the_file_and_column(tmp_path, capsys):
    t, f, a = one_pulse()
    p = small_record(tmp_path / "z.csv", t, f, 0 * a)
    err = cli_error(capsys, ["tap", str(p), "--out", str(tmp_path / "o.csv")])
    assert "z.csv: response: the response is 0 at every sample" in err and "force" not in err


@pytest.mark.parametrize("where", ["inside", "before", "after", "last cell"])
def test_nul_bytes_in_numbers_refused(tmp_path, capsys, where):
    p = small_record(tmp_path / "r.csv", *one_pulse())
    lines = p.read_text().splitlines()
    s = lines[50]
    lines[50] = {"inside": s[:3] + "\x00" + s[3:], "before": "\x00" + s, "after": s + "\x00",
                 "last cell": s[:-2] + "\x00" + s[-2:]}[where]
    p.write_text("\n".join(lines) + "\n")
    err = cli_error(capsys, ["tap", str(p), "--out", str(tmp_path / "o.csv")])
    assert "r.csv: " in err and "line 51: " in err and "is not a number" in err
    with pytest.raises(InputError, match="line 51"):
        read_record(p)


def test_full_disk_for_the_figure_writes_nothing(synth_file, tmp_path, capsys, monkeypatch):
    import errno

    import toolpoint.cli.tap as tap_cli

    def full(fig, path):
        raise OSError(errno.ENOSPC, "No space left on device")

    monkeypatch.setattr(tap_cli, "save_figure", full)
    out, png = tmp_path / "frf.csv", tmp_path / "frf.png"
    err = cli_error(capsys, ["tap", str(synth_file), "--out", str(out), "--plot", str(png), "--drop-bad"])
    assert "frf.png: --plot: cannot write (No space left on device); nothing written" in err
    assert list(tmp_path.iterdir()) == []


@pytest.mark.slow
def test_full_disk_for_the_frf_removes_the_figure(synth_file, tmp_path, capsys, monkeypatch):
    import errno

    import toolpoint.io.frf_files as frf_files

    def full(*args, **kw):
        raise OSError(errno.ENOSPC, "No space left on device")

    monkeypatch.setattr(frf_files, "write_frf", full)
    out, png = tmp_path / "frf.csv", tmp_path / "frf.png"
    err = cli_error(capsys, ["tap", str(synth_file), "--out", str(out), "--plot", str(png), "--drop-bad"])
    assert "frf.csv: --out: cannot write (No space left on device)" in err
    assert list(tmp_path.iterdir()) == []


def test_phase_panel_greys_out_low_coherence_and_stays_in_the_band():
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from toolpoint.io.impact import plot_tap
    from toolpoint.trust import COHERENCE_MIN

    rec = V.lab_like_tap(seed=0, hits=3, spacing_s=0.07)
    res = tap_of(rec)
    low = res.coherence < COHERENCE_MIN
    assert low.any() and not low.all()  # the hum lines and the noise near 0 Hz
    fig = plot_tap(res)
    for ax in fig.axes[1:3]:
        grey, blue = ax.get_lines()[:2]
        for line in (grey, blue):
            x = np.asarray(line.get_xdata())
            assert x.min() >= res.band_hz[0] and x.max() <= res.band_hz[1]  # nothing outside the band
        g, b = np.asarray(grey.get_ydata(), float), np.asarray(blue.get_ydata(), float)
        np.testing.assert_array_equal(np.isfinite(g), low)
        np.testing.assert_array_equal(np.isfinite(b), ~low)
        assert ax.get_xlim() == pytest.approx(res.band_hz)
    plt.close(fig)
