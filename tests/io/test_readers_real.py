"""FRF and record readers on real files nobody here wrote: the pyuff project's samples (tests/data/pyuff, MIT)."""

from pathlib import Path

import numpy as np
import pytest
import pyuff

from toolpoint.errors import InputError
from toolpoint.io.frf_files import read_frf
from toolpoint.io.impact import read_record

DATA = Path(__file__).parents[1] / "data" / "pyuff"


def measured(k):
    """Measured accelerance (m/s²/N) of impact point k, 0–1000 Hz at 1 Hz (pyuff's pairing)."""
    a = np.genfromtxt(DATA / f"meas_point_{k}.txt", dtype=complex)
    return np.arange(a.size, dtype=float), a


def test_vendor_frf_with_non_ascii_units_is_accelerance():
    ref = pyuff.UFF(str(DATA / "non_ascii_header.uff")).read_sets(0)
    with pytest.warns(UserWarning, match="dropped the 0 Hz point"):
        got = read_frf(DATA / "non_ascii_header.uff")
    assert got.meta["file_quantity"] == "accelerance"  # from the unit label '(1/N)*(m/s²)'
    f = np.asarray(ref["x"], float)[1:]
    np.testing.assert_array_equal(got.freq_hz, f)
    np.testing.assert_allclose(got.values, np.asarray(ref["data"])[1:] / -((2 * np.pi * f) ** 2), rtol=1e-15)


@pytest.mark.parametrize("name, field, msg", [
    ("sample_dataset58_psd.uff", "func_type", r"function type 9 \(power spectral density\)"),
    ("binary8byte.uff", "func_type", r"function type 1 \(time response\)"),
    ("1858.uff", "dataset", r"no dataset 58 found \(dataset types in file: 1858\)"),
])
def test_non_frf_files_refused(name, field, msg):
    with pytest.raises(InputError, match=rf"{name}: {field}: .*{msg}"):
        read_frf(DATA / name)


def test_time_history_without_force_refused():
    with pytest.raises(InputError, match=r"binary8byte\.uff: ordinate_spec_data_type: need one force .* found 0 and 1"):
        read_record(DATA / "binary8byte.uff")


def test_lab_tab_file_without_header(tmp_path):
    f, a = measured(1)
    p = tmp_path / "lab.txt"
    np.savetxt(p, np.column_stack([f, a.real, a.imag]), delimiter="\t", fmt="%.17g")
    with pytest.warns(UserWarning, match="0 Hz"):
        got = read_frf(p, quantity="accelerance")
    w = 2 * np.pi * f[1:]
    np.testing.assert_allclose(got.values, a[1:] / -(w**2), rtol=1e-15)
    # physical sanity: the resonances (peaks of |accelerance| well above its median) are receptance peaks too,
    # and above the first resonance the receptance falls off much faster than the accelerance (1/ω²)
    mag_a, mag_r = np.abs(a[1:]), np.abs(got.values)
    peaks = [k for k in range(1, mag_a.size - 1) if mag_a[k] > 5 * np.median(mag_a)
             and mag_a[k] == mag_a[max(0, k - 10):k + 11].max()]
    assert len(peaks) >= 3
    for k in peaks:
        assert mag_r[k] == mag_r[max(0, k - 3):k + 4].max()
    assert np.median(mag_r[800:]) / np.median(mag_r[100:200]) < 0.1 * np.median(mag_a[800:]) / np.median(
        mag_a[100:200])


@pytest.fixture
def three_frfs(tmp_path):
    """The three measured FRFs as one UFF (as pyuff's README builds it), with a coherence for impact 2."""
    p = tmp_path / "meas.uff"
    sets = []
    for k in (1, 2, 3):
        f, a = measured(k)
        sets.append(pyuff.prepare_58(func_type=4, rsp_node=1, rsp_dir=1, ref_node=k, ref_dir=1, data=a, x=f,
                                     ord_data_type=6, abscissa_spacing=1, abscissa_spec_data_type=18,
                                     ordinate_spec_data_type=12, orddenom_spec_data_type=13, binary=0))
    coh = np.linspace(0.5, 1.0, f.size)
    sets.append(pyuff.prepare_58(func_type=6, rsp_node=1, rsp_dir=1, ref_node=2, ref_dir=1, data=coh, x=f,
                                 ord_data_type=4, abscissa_spacing=1, abscissa_spec_data_type=18, binary=0,
                                 ordinate_spec_data_type=0, orddenom_spec_data_type=0))
    pyuff.UFF(str(p)).write_sets(sets, mode="add")
    return p, coh


def test_uff_pick_by_reference_with_coherence(three_frfs):
    p, coh = three_frfs
    with pytest.raises(InputError, match=r"meas\.uff: response: 3 FRFs match.*#0: response 1:1 reference 1:1; "
                                         r"#1: response 1:1 reference 2:1; #2: response 1:1 reference 3:1"):
        read_frf(p)
    with pytest.warns(UserWarning, match="0 Hz"):
        got = read_frf(p, reference=2, response="1:1")
    ref = pyuff.UFF(str(p)).read_sets(1)
    f = np.asarray(ref["x"], float)[1:]
    np.testing.assert_allclose(got.values, np.asarray(ref["data"])[1:] / -((2 * np.pi * f) ** 2), rtol=1e-15)
    np.testing.assert_allclose(got.meta["coherence"], coh[1:], atol=1e-11)
    with pytest.warns(UserWarning, match="0 Hz"):
        assert "coherence" not in read_frf(p, reference=3).meta
    with pytest.raises(InputError, match="reference: no FRF with reference 4"):
        read_frf(p, reference=4)
    with pytest.raises(InputError, match=r"response: 'x' is not a node"):
        read_frf(p, response="x")


def test_cutpro_nine_columns_with_units(tmp_path):
    cols = [measured(k) for k in (1, 2, 3)]
    f = cols[0][0][1:]
    recs = [a[1:] / -((2 * np.pi * f) ** 2) for _, a in cols]  # receptances in m/N
    p = tmp_path / "export.frf"
    with open(p, "w") as fh:
        fh.write("Freq\tReal\tImag\tFreq\tReal\tImag\tFreq\tReal\tImag\n")
        fh.write("Hz\tmm/N\tmm/N\tHz\tmm/N\tmm/N\tHz\tmm/N\tmm/N\n")
        data = np.column_stack([c for r in recs for c in (f, r.real * 1e3, r.imag * 1e3)])
        np.savetxt(fh, data, delimiter="\t", fmt="%.17g")
    got = read_frf(p)
    np.testing.assert_allclose(got.values, recs[0], rtol=1e-15)  # mm/N → m/N
    lines = p.read_text().splitlines()
    (q := tmp_path / "nohead.frf").write_text("\n".join(lines[2:]) + "\n")
    with pytest.raises(InputError, match=r"nohead\.frf: columns: line 1: 9 columns and no header"):
        read_frf(q)
    (q := tmp_path / "badunit.frf").write_text("\n".join([lines[0], lines[1].replace("mm/N", "g/N")] + lines[2:]))
    with pytest.raises(InputError, match=r"badunit\.frf: units: line 2: FRF unit 'g/N'"):
        read_frf(q)
    (q := tmp_path / "coh.tsv").write_text("Frequency [Hz]\tRe(H11)\tIm(H11)\tCoherence\n100\t1e-8\t-2e-8\t0.98\n"
                                           "200\t2e-8\t-1e-8\t1.2\n")
    with pytest.raises(InputError, match=r"coh\.tsv: Coherence: coherence 1\.2 outside \[0, 1\] at line 3"):
        read_frf(q)
    q.write_text(q.read_text().replace("1.2", "0.9"))
    got = read_frf(q)
    assert got.meta["coherence"].tolist() == [0.98, 0.9] and got.values[1] == 2e-8 - 1e-8j


def test_csv_coherence_round_trip_and_range(tmp_path):
    from toolpoint.frf import FRF
    from toolpoint.io.frf_files import write_frf

    frf = FRF([1.0, 2.0], [1e-8j, 2e-8 + 0j], meta={"coherence": np.array([0.25, 1.0])})
    write_frf(p := tmp_path / "c.csv", frf)
    assert p.read_text().splitlines()[0] == "freq_hz,real,imag,coherence"
    assert read_frf(p).meta["coherence"].tolist() == [0.25, 1.0]
    p.write_text("freq_hz,real,imag,coherence\n1,0,1,-0.5\n")
    with pytest.raises(InputError, match=r"c\.csv: coherence: coherence -0\.5 outside \[0, 1\] at line 2"):
        read_frf(p)
    with pytest.raises(InputError, match=r"x\.csv: coherence: .*3 values for 2 frequencies"):
        write_frf(tmp_path / "x.csv", FRF([1.0, 2.0], [1, 2], meta={"coherence": np.ones(3)}))
    assert not (tmp_path / "x.csv").exists()
