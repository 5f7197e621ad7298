"""Reading and writing FRF files: CSV, UFF dataset 58 (pyuff) and CutPro .frf."""

import tempfile
import warnings
from pathlib import Path

import numpy as np
import pytest
import pyuff
from hypothesis import given, settings
from hypothesis import strategies as st

from toolpoint.errors import InputError
from toolpoint.frf import FRF
from toolpoint.io.frf_files import (
    G0, read_csv_frf, read_cutpro, read_frf, read_uff58, read_uff58_all, write_csv_frf, write_cutpro,
    write_frf, write_uff58,
)

# pyuff writes ASCII dataset 58 values with "%20.11e": 12 significant digits,
# so the relative error of each part is at most 5e-12 (measured: ~4e-12).
UFF_ASCII_RTOL = 5e-12


def sdof(f, fn=800.0, zeta=0.03, k=2e7):
    """Receptance (m/N) of a single-degree-of-freedom oscillator."""
    r = np.asarray(f) / fn
    return 1.0 / (k * (1 - r**2 + 2j * zeta * r))


def tool_frf(n=401, df=2.5, f0=0.0):
    f = f0 + df * np.arange(n)
    return FRF(f, sdof(f), "receptance", "tool")


def write_uff_raw(path, f, data, **fields):
    """A dataset 58 file written directly with pyuff (fields override FRF defaults)."""
    kw = dict(binary=0, func_type=4, rsp_node=1, rsp_dir=1, ref_node=1, ref_dir=1, abscissa_spacing=0,
              abscissa_spec_data_type=18, ordinate_spec_data_type=8, orddenom_spec_data_type=13)
    kw.update(fields)
    sets = [pyuff.prepare_58(data=np.asarray(data), x=np.asarray(f, float), **kw)]
    pyuff.UFF(str(path)).write_sets(sets, mode="add")


def n_datasets(path):
    return pyuff.UFF(str(path)).get_n_sets()


# ---------------------------------------------------------------- round trips
def test_csv_round_trip_is_exact(tmp_path):
    f = np.array([0.0, 0.1, 1 / 3, 1e-300, 5e-324 + 1, 12345.678901234567])
    f.sort()
    # extreme parts within the accepted magnitudes (0 or 1e-100 ≤ |H| ≤ 1e100; refused beyond: see below)
    v = np.array([1e-9 + 2e-9j, -0.0 + 1j / 3, 5e-324 - 1e100j, np.pi, -np.e * 1j, 1 / 7 - 1j / 11])
    p = tmp_path / "a.csv"
    write_csv_frf(p, FRF(f, v))
    assert p.read_text().splitlines()[0] == "freq_hz,real,imag"
    got = read_frf(p)
    assert np.array_equal(got.freq_hz, f) and np.array_equal(got.values, v)
    assert got.quantity == "receptance" and got.label == "a"
    assert read_csv_frf(p, label="tool").label == "tool"


@settings(max_examples=60, deadline=None)
@given(
    freqs=st.lists(st.floats(0, 1e6, allow_nan=False), min_size=1, max_size=40, unique=True),
    # every magnitude the readers accept: 0, or 1e-100 ≤ |part| ≤ 1e99 (so 1e-100 ≤ |H| ≤ 1e100)
    parts=st.lists(st.just(0.0) | st.floats(1e-100, 1e99) | st.floats(-1e99, -1e-100), min_size=80, max_size=80),
)
def test_csv_round_trip_property(freqs, parts):
    f = np.array(sorted(freqs))
    v = np.empty(f.size, complex)
    v.real, v.imag = parts[: f.size], parts[40 : 40 + f.size]
    with tempfile.TemporaryDirectory() as d:
        p = Path(d) / "h.csv"
        write_frf(p, FRF(f, v))
        got = read_frf(p)
    assert np.array_equal(got.freq_hz, f) and np.array_equal(got.values, v)


def test_cutpro_round_trip_is_exact(tmp_path):
    frf = tool_frf(f0=0.1, df=1 / 3)
    p = tmp_path / "tp.frf"
    write_cutpro(p, frf)
    assert p.read_text().splitlines()[0].count("\t") == 2
    got = read_cutpro(p)
    assert np.array_equal(got.freq_hz, frf.freq_hz) and np.array_equal(got.values, frf.values)
    write_frf(p, frf)  # dispatch on .frf
    assert np.array_equal(read_frf(p).values, frf.values)


def test_cutpro_header_comments_and_spaces(tmp_path):
    p = tmp_path / "m.frf"
    p.write_text("% measured by X\n# tool T1\nFreq\tReal\tImag\n100  1e-8 -2e-8\n\n200\t3e-8\t-4e-8\n")
    got = read_frf(p)
    assert np.array_equal(got.freq_hz, [100, 200])
    assert np.array_equal(got.values, [1e-8 - 2e-8j, 3e-8 - 4e-8j])


def test_cutpro_bad_cell_names_line(tmp_path):
    p = tmp_path / "m.frf"
    p.write_text("Freq\tReal\tImag\n100\t1e-8\t-2e-8\n200\tx\t-4e-8\n")
    with pytest.raises(InputError, match=r"m\.frf: Real: line 3"):
        read_frf(p)


@pytest.mark.parametrize("binary", [False, True])
def test_uff_round_trip_even_grid(tmp_path, binary):
    frf = tool_frf()
    p = tmp_path / "tp.uff"
    write_frf(p, frf) if not binary else write_uff58(p, frf, binary=True)
    got = read_frf(p)
    assert np.array_equal(got.freq_hz, frf.freq_hz)  # 0 and 2.5 survive the %13.5e header
    if binary:
        assert np.array_equal(got.values, frf.values)
    else:
        for part in ("real", "imag"):
            a, b = getattr(got.values, part), getattr(frf.values, part)
            np.testing.assert_allclose(a, b, rtol=UFF_ASCII_RTOL, atol=0)
        assert not np.array_equal(got.values, frf.values)  # ASCII is not exact
    assert got.quantity == "receptance" and got.label == "tp" and got.meta["id1"] == "tool"


def test_uff_binary_uneven_frequencies_exact(tmp_path):
    f = np.cumsum(np.linspace(0.1234567891, 3.3, 50))
    frf = FRF(f, sdof(f))
    p = tmp_path / "b.uff"
    write_uff58(p, frf, binary=True)
    got = read_uff58(p)
    assert got.meta["binary"] == 1
    assert np.array_equal(got.freq_hz, f) and np.array_equal(got.values, frf.values)


def test_uff_ascii_uneven_frequencies(tmp_path):
    f = np.array([10.0, 12.5, 20.0, 31.25, 1000.0, 4096.5])  # ≤ 6 significant digits: exact
    p = tmp_path / "u.uff"
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        write_uff58(p, FRF(f, sdof(f)))
    assert np.array_equal(read_uff58(p).freq_hz, f)
    g = f + np.array([0, 1e-3, 0, 0, 0, 0.0123])  # 4096.5123 needs 8 digits
    with pytest.warns(UserWarning, match="6 significant digits"):
        write_uff58(p, FRF(g, sdof(g)))
    np.testing.assert_allclose(read_uff58(p).freq_hz, g, rtol=5e-6)


def test_uff_ascii_refuses_frequencies_it_would_merge(tmp_path):
    f = np.array([1000.0, 1000.0001, 1000.0002, 2000.0])
    with pytest.raises(InputError, match="freq_hz"):
        write_uff58(tmp_path / "x.uff", FRF(f, sdof(f)))
    write_uff58(tmp_path / "x.uff", FRF(f, sdof(f)), binary=True)
    assert np.array_equal(read_uff58(tmp_path / "x.uff").freq_hz, f)


@pytest.mark.parametrize("binary", [False, True])
def test_uff_writing_twice_gives_one_dataset(tmp_path, binary):
    p = tmp_path / "twice.uff"
    write_uff58(p, tool_frf(n=50), binary=binary)
    write_uff58(p, tool_frf(n=60), binary=binary)
    assert n_datasets(p) == 1
    assert len(read_uff58(p)) == 60
    assert [q.name for q in tmp_path.iterdir()] == ["twice.uff"]  # no temporary files left


def test_failed_write_keeps_old_file(tmp_path):
    p = tmp_path / "keep.csv"
    write_csv_frf(p, tool_frf(n=5))
    before = p.read_bytes()
    # an FRF cannot hold non-finite values any more; a mobility at 0 Hz has no receptance to write
    with pytest.raises(InputError, match="keep.csv: values: .*cannot convert mobility at 0 Hz"):
        write_csv_frf(p, FRF([0.0, 2.0], [1.0, 1.0], "mobility"))
    assert p.read_bytes() == before
    with pytest.raises(InputError, match="keep.csv: values: .*one response"):
        write_frf(p, FRF([1.0, 2.0], np.ones((2, 2, 2))))
    assert p.read_bytes() == before


def test_write_converts_to_receptance(tmp_path):
    frf = tool_frf(f0=10.0)
    mob = FRF(frf.freq_hz, 1j * frf.omega * frf.values, "mobility")
    p = tmp_path / "m.csv"
    write_frf(p, mob)
    np.testing.assert_allclose(read_frf(p).values, frf.values, rtol=1e-14)


# ---------------------------------------------------------------- UFF semantics
@pytest.mark.parametrize("odt, factor", [(11, lambda w: 1j * w), (12, lambda w: -(w**2))])
def test_uff_mobility_and_accelerance_convert_to_receptance(tmp_path, odt, factor):
    f = 5.0 + 2.5 * np.arange(300)
    h = sdof(f)
    p = tmp_path / "ma.uff"
    write_uff_raw(p, f, factor(2 * np.pi * f) * h, ordinate_spec_data_type=odt)
    got = read_frf(p)
    assert got.quantity == "receptance" and got.meta["file_quantity"] in ("mobility", "accelerance")
    np.testing.assert_allclose(got.values, h, rtol=2 * UFF_ASCII_RTOL)


def test_uff_accelerance_in_g_is_converted(tmp_path):
    f = 10.0 * np.arange(1, 50)
    h = sdof(f)
    p = tmp_path / "g.uff"
    write_uff_raw(p, f, -((2 * np.pi * f) ** 2) * h / G0, ordinate_spec_data_type=12, ordinate_axis_units_lab="g")
    with pytest.warns(UserWarning, match="g to m/s"):
        got = read_frf(p)
    np.testing.assert_allclose(got.values, h, rtol=2 * UFF_ASCII_RTOL)


def test_zero_hz_point_dropped_from_accelerance(tmp_path):
    f = 10.0 * np.arange(0, 20)
    h = sdof(f)
    p = tmp_path / "acc0.uff"
    write_uff_raw(p, f, -((2 * np.pi * f) ** 2) * h, ordinate_spec_data_type=12)
    with pytest.warns(UserWarning, match=r"acc0\.uff.*0 Hz"):
        got = read_frf(p)
    assert np.array_equal(got.freq_hz, f[1:])
    np.testing.assert_allclose(got.values, h[1:], rtol=2 * UFF_ASCII_RTOL)
    # the same through `quantity=` on a CSV file
    q = tmp_path / "acc0.csv"
    write_csv_frf(q, FRF(f, -((2 * np.pi * f) ** 2) * h))
    with pytest.warns(UserWarning, match=r"acc0\.csv.*0 Hz"):
        assert len(read_frf(q, quantity="accelerance")) == f.size - 1


def test_quantity_argument_overrides_file(tmp_path):
    f = 10.0 * np.arange(1, 20)
    h = sdof(f)
    p = tmp_path / "q.uff"
    write_uff_raw(p, f, 1j * 2 * np.pi * f * h, ordinate_spec_data_type=0)  # unknown ordinate
    with pytest.warns(UserWarning, match="assuming receptance"):
        assert read_frf(p).meta["file_quantity"] == "receptance"
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        got = read_frf(p, quantity="mobility")
    np.testing.assert_allclose(got.values, h, rtol=2 * UFF_ASCII_RTOL)
    with pytest.raises(InputError, match="quantity"):
        read_frf(p, quantity="compliance")


def test_uff_non_frf_function_type_refused(tmp_path):
    p = tmp_path / "cross.uff"
    write_uff_raw(p, [1.0, 2.0, 3.0], [1 + 1j, 2 + 0j, 3 - 1j], func_type=3)
    with pytest.raises(InputError, match=r"cross\.uff: func_type: .*function type 3 \(cross spectrum\)"):
        read_frf(p)


def test_uff_real_ordinate_refused(tmp_path):
    p = tmp_path / "real.uff"
    write_uff_raw(p, [1.0, 2.0, 3.0], [1.0, 2.0, 3.0])
    with pytest.raises(InputError, match="ord_data_type: .*real"):
        read_frf(p)


def test_uff_abscissa_must_be_frequency(tmp_path):
    p = tmp_path / "t.uff"
    write_uff_raw(p, [1.0, 2.0, 3.0], [1j, 2j, 3j], abscissa_spec_data_type=17)  # time
    with pytest.raises(InputError, match="abscissa_spec_data_type: .*17"):
        read_frf(p)
    write_uff_raw(p2 := tmp_path / "u.uff", [1.0, 2.0, 3.0], [1j, 2j, 3j], abscissa_spec_data_type=0)
    with pytest.warns(UserWarning, match="assuming frequency in Hz"):
        assert len(read_frf(p2)) == 3


def test_uff_without_dataset_58(tmp_path):
    p = tmp_path / "none.unv"
    p.write_text("    -1\n    15\n         1         0         0         0 0.0 0.0 0.0\n    -1\n")
    with pytest.raises(InputError, match=r"none\.unv: dataset: no dataset 58 .*15"):
        read_frf(p)
    (q := tmp_path / "empty.uff").write_text("")
    with pytest.raises(InputError, match="no dataset 58"):
        read_frf(q)


def test_uff_several_datasets(tmp_path):
    f = 10.0 * np.arange(1, 30)
    p = tmp_path / "multi.uff"
    write_uff_raw(p, f, np.ones(f.size), func_type=6)  # coherence first
    write_uff_raw(p, f, sdof(f))
    write_uff_raw(p, f, 2 * sdof(f), rsp_node=2)
    assert n_datasets(p) == 3
    # two FRFs: ambiguous without a choice (issue 11: no silent pick of the first), the error lists both
    with pytest.raises(InputError, match=r"response: 2 FRFs match.*#1: response 1:1 reference 1:1; #2: response 2:1"):
        read_uff58(p)
    np.testing.assert_allclose(read_frf(p, response=1).values, sdof(f), rtol=UFF_ASCII_RTOL)
    np.testing.assert_allclose(read_frf(p, response="2:1", reference=1).values, 2 * sdof(f), rtol=UFF_ASCII_RTOL)
    with pytest.raises(InputError, match=r"response: no FRF with response 3"):
        read_frf(p, response=3)
    second = read_uff58(p, index=2)
    assert second.meta["rsp_node"] == 2 and second.meta["index"] == 2
    np.testing.assert_allclose(second.values, 2 * sdof(f), rtol=UFF_ASCII_RTOL)
    with pytest.raises(InputError, match="func_type: .*coherence"):
        read_uff58(p, index=0)
    with pytest.raises(InputError, match="index: .*3 datasets 58"):
        read_uff58(p, index=3)
    frfs = read_uff58_all(p)
    assert [x.label for x in frfs] == ["multi#1", "multi#2"]


# ---------------------------------------------------------------- input errors
CSV_ERRORS = [
    ("", "header", "empty file"),
    ("freq,re,im\n1,2,3\n", "header", "found 'freq,re,im'"),
    (" freq_hz , real ,imag\n", "data", "no data points"),
    ("freq_hz,real,imag\n1,2,3\n2,abc,3\n", "real", "line 3: 'abc' is not a number"),
    ("freq_hz,real,imag\n1,2,3\n2,3\n", "columns", "line 3: expected 3 columns"),
    ("freq_hz,real,imag\n1,2,3\n2,nan,3\n", "real", "non-finite value nan at line 3"),
    ("freq_hz,real,imag\n1,2,inf\n", "imag", "non-finite value inf at line 2"),
    ("freq_hz,real,imag\n1,2,3\n5,2,3\n5,2,3\n", "freq_hz", "strictly increasing (5 Hz repeated) at line 4"),
    ("freq_hz,real,imag\n1,2,3\n5,2,3\n4,2,3\n", "freq_hz", "(5 Hz is followed by 4 Hz) at line 4"),
    ("freq_hz,real,imag\n-1,2,3\n5,2,3\n", "freq_hz", "must be ≥ 0 Hz, got -1 at line 2"),
    ("freq_hz,real,imag\n1,2,3\nnan,2,3\n", "freq_hz", "must be finite, got nan at line 3"),
    ("freq_hz,real,imag\n1,2,3\n2,1_000,3\n", "real", "line 3: '1_000' is not a number"),  # Python-only syntax
]


@pytest.mark.parametrize("text, field, msg", CSV_ERRORS)
def test_csv_errors_name_file_and_field(tmp_path, text, field, msg):
    p = tmp_path / "bad.csv"
    p.write_text(text)
    with pytest.raises(InputError) as info:
        read_frf(p)
    s = str(info.value)
    assert "\n" not in s and str(p) in s and f": {field}: " in s and msg in s


def test_min_points_and_missing_file(tmp_path):
    p = tmp_path / "few.csv"
    write_csv_frf(p, tool_frf(n=3))
    with pytest.raises(InputError, match=r"few\.csv: data: 3 points, need at least 10"):
        read_frf(p, min_points=10)
    with pytest.raises(InputError, match=r"nothere\.csv: file not found"):
        read_frf(tmp_path / "nothere.csv")
    with pytest.raises(InputError, match=r"nothere\.uff: file not found"):
        read_frf(tmp_path / "nothere.uff")
    with pytest.raises(InputError, match="extension: unknown FRF file extension '.xyz'"):
        read_frf(tmp_path / "x.xyz")


def test_truncated_uff_refused(tmp_path):
    p = tmp_path / "cut.uff"
    write_uff58(p, tool_frf(n=40))
    lines = p.read_text().splitlines(keepends=True)
    p.write_text("".join(lines[:-5]) + "    -1\n")  # drop the last data lines, keep the end tag
    with pytest.raises(InputError, match=r"cut\.uff: num_pts: .*40 points but holds"):
        read_frf(p)


def test_uff_keeps_dof_on_rewrite(tmp_path):
    f = 10.0 * np.arange(1, 10)
    write_uff_raw(p := tmp_path / "dof.uff", f, sdof(f), rsp_node=7, rsp_dir=-2, ref_node=3, ref_dir=3)
    write_uff58(q := tmp_path / "again.uff", read_frf(p))
    got = read_uff58(q)
    assert (got.meta["rsp_node"], got.meta["rsp_dir"], got.meta["ref_node"], got.meta["ref_dir"]) == (7, -2, 3, 3)


# ---------------------------------------------------------------- implausible values and cut files (issue 13)
@pytest.mark.parametrize("ext, sep", [(".csv", ","), (".txt", "\t"), (".frf", "\t")])
@pytest.mark.parametrize("row, field, msg", [
    ("300,1e300,0", "real", "|H| = 1e+300 at line {n} is not a plausible FRF value"),
    ("300,1e-8,-1e101", "imag", "|H| = 1e+101 at line {n}"),
    ("300,1e-320,0", "real", "|H| = 1e-320 at line {n}"),  # subnormal: 1/H overflows
    ("2e9,1e-8,-1e-8", "freq", "frequency 2e+09 Hz at line {n} is above 1e+09 Hz"),
])
def test_values_that_overflow_downstream_are_refused(tmp_path, ext, sep, row, field, msg):
    head = "freq_hz,real,imag\n" if ext == ".csv" else ""
    body = "".join(f"{f}{sep}{1e-8 * f:.6e}{sep}{-1e-9:.6e}\n" for f in (100, 200))
    p = tmp_path / f"big{ext}"
    p.write_text(head + body + row.replace(",", sep) + "\n")
    n = 4 if ext == ".csv" else 3
    with pytest.raises(InputError) as info:
        read_frf(p)
    s = str(info.value)
    assert "\n" not in s and str(p) in s and msg.format(n=n) in s
    assert field in s.split(": ")[1].lower()


def test_a_zero_value_is_accepted(tmp_path):
    p = tmp_path / "z.csv"
    p.write_text("freq_hz,real,imag\n0,0,0\n10,1e-8,-1e-9\n")
    assert read_frf(p).values[0] == 0


@pytest.mark.parametrize("last", ["300,3.1e-08,-1.2e-0", "300,3.1e-08,-1.2", "300,3.1e-08,-1", "300,3.1e-08,-1."])
def test_a_file_cut_mid_number_is_refused_naming_the_line(tmp_path, last):
    # the last number of a file that ends without a line break lost digits: -1.2e-09 read as -1.2 m/N
    body = "freq_hz,real,imag\n100,1.0e-08,-1.5e-09\n200,2.0e-08,-2.5e-09\n"
    p = tmp_path / "cut.csv"
    p.write_text(body + last)
    with pytest.raises(InputError, match=r"cut\.csv: imag: line 4: .* looks cut short .* end it with a line break"):
        read_frf(p)
    p.write_text(body + last + "\n")  # with a line break it is taken as written (and then judged as a value)
    assert len(read_frf(p)) == 3


def test_a_complete_file_without_final_line_break_is_accepted(tmp_path):
    for name, text in (("a.csv", "freq_hz,real,imag\n100,1.5e-08,-1.5e-09\n200,2.5e-08,-2.5e-09\n300,3e-08,-3e-09"),
                       ("b.frf", "100\t1.5e-08\t-1.5e-09\n200\t2.5e-08\t-2.5e-09\n300\t3.5e-08\t-3.5e-09")):
        (tmp_path / name).write_text(text)
        assert len(read_frf(tmp_path / name)) == 3


def test_a_cut_impact_record_is_refused(tmp_path):
    from toolpoint.io.impact import read_record

    p = tmp_path / "rec.csv"
    rows = "".join(f"{k * 1e-3:.6e},{k * 0.5:.6e},{-k * 0.25:.6e}\n" for k in range(5))
    p.write_text("t,f,a\n" + rows + "5.000000e-03,2.500000e+00,-1.2")
    with pytest.raises(InputError, match=r"rec\.csv: response: line 7: '-1\.2' looks cut short"):
        read_record(p)


def test_header_cell_that_is_empty_is_a_header_error_not_a_crash(tmp_path):
    p = tmp_path / "h.txt"
    p.write_text(",\tReal\tImag\n50\t1e-8\t-1e-9\n")
    with pytest.raises(InputError, match="h.txt"):
        read_frf(p)
