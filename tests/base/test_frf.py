"""The FRF type owns its invariants; `at` is np.interp on every entry, inside the band only."""

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from toolpoint.dynamics.subassembly import Subassembly
from toolpoint.errors import InputError
from toolpoint.frf import FRF, check_freq_hz

F = np.array([10.0, 20.0, 35.0, 50.0])
V = np.array([1 + 2j, -3 + 0.5j, 4 - 1j, 0.25 + 0j]) * 1e-8


def interp_entries(fq, f, v):
    """Reference: np.interp on the real and imaginary part of each entry separately."""
    flat = v.reshape(f.size, -1)
    out = np.stack([np.interp(fq, f, c.real) + 1j * np.interp(fq, f, c.imag) for c in flat.T], -1)
    return out.reshape((fq.size,) + v.shape[1:])


# ---------------------------------------------------------------- invariants
@pytest.mark.parametrize("freq, values, field, text", [
    ([3.0, 1.0, 2.0], [1, 2, 3], "freq_hz", "strictly increasing (3 Hz is followed by 1 Hz)"),
    ([1.0, 2.0, 2.0], [1, 2, 3], "freq_hz", "2 Hz repeated"),
    ([1.0, np.nan, 3.0], [1, 2, 3], "freq_hz", "finite"),
    ([-1.0, 2.0, 3.0], [1, 2, 3], "freq_hz", "≥ 0 Hz"),
    ([1.0, 2.0, 3.0], [1, np.nan, 3], "values", "finite (first non-finite value at 2 Hz)"),
    ([1.0, 2.0, 3.0], [1, 2, np.inf * 1j], "values", "finite"),
    ([1.0, 2.0, 3.0], [1, 2], "values", "does not match 3 frequencies"),
    ([1.0, 2.0, 3.0], np.ones((3, 2)), "values", "need (3,) or (3, n, m)"),
    ([1.0, 2.0], np.ones((3, 2, 2)), "values", "does not match 2 frequencies"),
])
def test_bad_frf_is_a_one_line_input_error(freq, values, field, text):
    with pytest.raises(InputError) as e:
        FRF(freq, values)
    assert isinstance(e.value, ValueError)
    assert e.value.field == field and text in str(e.value) and "\n" not in str(e.value)


def test_unknown_quantity_and_nonnumeric_values():
    with pytest.raises(InputError, match="quantity: unknown quantity 'compliance'"):
        FRF(F, V, "compliance")
    with pytest.raises(InputError, match="values: "):
        FRF(F, ["a", "b", "c", "d"])


def test_frf_copies_its_values():
    v = V.copy()
    frf = FRF(F, v)
    v[0] = 99
    assert frf.values[0] == V[0]


def test_subassembly_is_a_2x2_receptance_frf():
    R = np.arange(16).reshape(4, 2, 2) * (1 + 1j) * 1e-9
    sub = Subassembly(F, R, label="sh")
    assert isinstance(sub, FRF) and sub.quantity == "receptance" and sub.label == "sh"
    assert sub.R is sub.values and sub.R.shape == (4, 2, 2)
    assert Subassembly(F, R).label == "spindle–holder"
    with pytest.raises(InputError, match=r"values: shape \(4, 3, 3\), expected \(4, 2, 2\)"):
        Subassembly(F, np.ones((4, 3, 3)))
    with pytest.raises(InputError, match="freq_hz: frequencies must be > 0 Hz"):
        Subassembly(np.r_[0.0, F[1:]], R)
    # at, band keep the type; entry gives a SISO FRF
    mid = sub.at([15.0, 42.5])
    assert type(mid) is Subassembly and mid.label == "sh"
    assert np.allclose(mid.R, interp_entries(np.array([15.0, 42.5]), F, R), rtol=1e-14, atol=0)
    assert type(sub.band(20.0, 35.0)) is Subassembly and len(sub.band(20.0, 35.0)) == 2
    assert np.array_equal(sub.entry(1, 0).values, R[:, 1, 0])
    assert sub.at(F) is sub


# ---------------------------------------------------------------- at
@pytest.mark.parametrize("shape", [(), (2, 2), (1, 3)])
def test_at_equals_np_interp_on_every_entry(shape):
    rng = np.random.default_rng(3)
    v = (rng.standard_normal((F.size,) + shape) + 1j * rng.standard_normal((F.size,) + shape)) * 1e-7
    frf = FRF(F, v)
    fq = np.array([10.0, 12.5, 20.0, 33.3, 35.0, 49.999, 50.0])
    got = frf.at(fq)
    assert got.values.shape == (fq.size,) + shape and np.array_equal(got.freq_hz, fq)
    np.testing.assert_allclose(got.values, interp_entries(fq, F, v), rtol=1e-14, atol=1e-14 * np.abs(v).max())
    on_grid = np.isin(fq, F)
    assert np.array_equal(got.values[on_grid], v[np.searchsorted(F, fq[on_grid])])  # exact at grid points


def test_at_empty_query_and_single_point():
    for v in (V, np.ones((4, 2, 2), complex)):
        e = FRF(F, v).at([])
        assert len(e) == 0 and e.values.shape == (0,) + v.shape[1:]
    one = FRF([7.0], [2j])
    assert one.at([7.0]).values.tolist() == [2j]
    with pytest.raises(InputError, match="covers 7–7 Hz"):
        one.at([7.5])
    with pytest.raises(InputError, match="empty"):
        FRF([], []).at([1.0])


@pytest.mark.parametrize("fq", [[9.0], [10.0, 50.1], [51.0], [5.0, 60.0]])
def test_at_refuses_to_extrapolate(fq):
    with pytest.raises(InputError) as e:
        FRF(F, V, label="tip").at(fq)
    s = str(e.value)
    assert s.startswith("freq_hz: 'tip' covers 10–50 Hz") and "no extrapolation" in s


def test_at_edge_tolerance_is_round_off_only():
    frf = FRF(F, V)
    eps = 0.5e-9 * 50.0  # inside the tolerance 1e-9 · f_max: read as the edge values
    got = frf.at([10.0 - eps, 50.0 + eps])
    assert np.array_equal(got.values, V[[0, -1]])
    with pytest.raises(InputError):
        frf.at([50.0 + 4 * eps])


def test_at_query_must_be_a_grid():
    with pytest.raises(InputError, match="strictly increasing"):
        FRF(F, V).at([30.0, 20.0])


@settings(max_examples=80, deadline=None)
@given(
    st.lists(st.floats(0.01, 100.0), min_size=1, max_size=30),
    st.floats(0.0, 1e4),
    st.lists(st.floats(-1e3, 1e3), min_size=60, max_size=60),
    st.lists(st.floats(0.0, 1.0), min_size=0, max_size=20, unique=True),
    st.booleans(),
)
def test_at_property_random_grids(steps, f0, parts, fractions, matrix):
    f = f0 + np.cumsum(steps)
    f = f[np.r_[True, np.diff(f) > 0]]  # round-off can merge neighbours at large f0
    n = f.size
    re, im = np.array(parts[:n]), np.array(parts[30:30 + n])
    v = re + 1j * im
    if matrix:
        v = np.moveaxis(np.array([[v, 2 * v], [-v, 1j * v]]), -1, 0)  # (n, 2, 2)
    fq = np.sort(f[0] + np.array(fractions) * (f[-1] - f[0]))
    fq = fq[np.r_[True, np.diff(fq) > 0]] if fq.size else fq
    got = FRF(f, v).at(fq)
    ref = interp_entries(fq, f, v)
    scale = max(1.0, np.abs(v).max())
    np.testing.assert_allclose(got.values, ref, rtol=0, atol=1e-12 * scale)
    # linear interpolation stays inside the range of its neighbours
    if fq.size and not matrix:
        j = np.clip(np.searchsorted(f, fq, side="right") - 1, 0, max(n - 2, 0))
        k = np.minimum(j + 1, n - 1)
        lo = np.minimum(v[j].real, v[k].real) - 1e-12 * scale
        hi = np.maximum(v[j].real, v[k].real) + 1e-12 * scale
        assert np.all((got.values.real >= lo) & (got.values.real <= hi))


# ---------------------------------------------------------------- band, peak, receptance
def test_band_peak_and_conversions_for_both_shapes():
    frf = FRF(F, V)
    assert np.array_equal(frf.band(20.0, 35.0).freq_hz, [20.0, 35.0])
    assert frf.peak() == (35.0, pytest.approx(abs(V[2])))
    mat = FRF(F, np.stack([V, 2 * V], -1)[:, None, :])  # (F, 1, 2)
    with pytest.raises(InputError, match="peak.*SISO"):
        mat.peak()
    with pytest.raises(InputError, match="plot.*SISO"):
        mat.plot()
    with pytest.raises(InputError, match="entry.*matrix"):
        frf.entry(0, 0)
    w = 2 * np.pi * F
    for q, factor in (("mobility", 1j * w), ("accelerance", -(w**2))):
        r = FRF(F, factor * V, q).to_receptance()
        assert r.quantity == "receptance" and np.allclose(r.values, V, rtol=1e-14, atol=0)
        rm = FRF(F, factor[:, None, None] * mat.values, q).to_receptance()
        assert np.allclose(rm.values, mat.values, rtol=1e-14, atol=0)
    with pytest.raises(InputError, match="cannot convert mobility at 0 Hz"):
        FRF([0.0, 1.0], [1.0, 1.0], "mobility").to_receptance()


def test_check_freq_hz_options():
    assert check_freq_hz([], min_points=0).size == 0
    with pytest.raises(InputError, match="a.csv: f: needs at least 2 frequencies, got 1"):
        check_freq_hz([1.0], file="a.csv", field="f", min_points=2)
    with pytest.raises(InputError, match=r"> 0 Hz, got 0 at row 1$"):
        check_freq_hz([0.0, 1.0], positive=True, where=lambda i: f"row {i + 1}")
    with pytest.raises(InputError, match="numbers"):
        check_freq_hz(["x"])


def test_at_interpolates_per_frequency_meta_like_the_values():
    f = np.array([10.0, 20.0, 30.0])
    h = FRF(f, np.array([1.0, 2.0, 4.0]) + 0j, meta={"coherence": np.array([0.9, 0.7, 0.5]), "source": "x"})
    g = h.at([15.0, 25.0])
    np.testing.assert_allclose(g.meta["coherence"], [0.8, 0.6])  # linear, like the values (1.5, 3.0)
    np.testing.assert_allclose(g.values, [1.5, 3.0])
    assert g.meta["source"] == "x"
    assert h.at(np.empty(0)).meta["coherence"].shape == (0,)
