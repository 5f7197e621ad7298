"""Modal fit of receptance FRFs (variable-projection least squares)."""

import numpy as np
import pytest

from toolpoint.errors import InputError
from toolpoint.frf import FRF
from toolpoint.stability import ModalModel, fit_modes

TRUE = ModalModel([650.0, 1480.0, 2310.0], [0.03, 0.012, 0.02], [0.35, 0.08, 0.2])
F = np.linspace(0.0, 3000.0, 3001)


def noisy(model, level=0.005, seed=1, f=F):
    """The model's receptance plus complex white noise of ``level`` × the peak magnitude."""
    h = model.frf(f).values
    rng = np.random.default_rng(seed)
    noise = level * np.abs(h).max() * (rng.standard_normal(f.size) + 1j * rng.standard_normal(f.size)) / np.sqrt(2)
    return FRF(f, h + noise, label="synthetic")


@pytest.mark.parametrize("n_modes", [None, 3])
@pytest.mark.parametrize("seed", [1, 2])
def test_recovers_three_modes_from_noisy_frf(n_modes, seed):
    fit = fit_modes(noisy(TRUE, seed=seed), n_modes=n_modes)
    assert fit.n_modes == 3
    assert fit.fn_hz == pytest.approx(TRUE.fn_hz, rel=1e-3)
    assert fit.zeta == pytest.approx(TRUE.zeta, rel=0.03)
    assert fit.mass_kg == pytest.approx(TRUE.mass_kg, rel=0.03)
    # The error reported is the relative RMS misfit: here the noise level.
    h = noisy(TRUE, seed=seed)
    resid = np.linalg.norm(fit.frf(F[1:]).values - h.values[1:]) / np.linalg.norm(h.values[1:])
    assert fit.fit_error == pytest.approx(resid, rel=1e-6)
    assert fit.fit_error < 0.05


def test_exact_data_fits_exactly():
    fit = fit_modes(TRUE.frf(F), n_modes=3)
    assert fit.fit_error < 1e-8
    assert fit.fn_hz == pytest.approx(TRUE.fn_hz, rel=1e-9)
    assert fit.zeta == pytest.approx(TRUE.zeta, rel=1e-7)
    assert fit.mass_kg == pytest.approx(TRUE.mass_kg, rel=1e-7)
    assert fit.stiffness == pytest.approx(TRUE.stiffness, rel=1e-7)


def test_close_modes_in_one_peak_are_separated():
    """Two modes 4 % apart make one peak: peak picking sees one, the fit finds both."""
    true = ModalModel([1000.0, 1040.0], [0.02, 0.02], [0.05, 0.07])
    fit = fit_modes(noisy(true, level=0.002), n_modes=2)
    assert fit.fn_hz == pytest.approx(true.fn_hz, rel=1e-3)
    assert fit.zeta == pytest.approx(true.zeta, rel=0.05)
    assert fit.mass_kg == pytest.approx(true.mass_kg, rel=0.05)
    auto = fit_modes(noisy(true, level=0.002))
    assert auto.n_modes == 2


def test_band_with_residuals():
    """Fitting only around the middle mode: residual terms absorb the modes outside the band."""
    fit = fit_modes(noisy(TRUE, level=0.002), n_modes=1, band=(1200.0, 1800.0))
    assert fit.fn_hz == pytest.approx([1480.0], rel=1e-3)
    assert fit.zeta == pytest.approx([0.012], rel=0.05)
    assert fit.mass_kg == pytest.approx([0.08], rel=0.05)
    assert fit.lower_residual > 0  # the 650 Hz mode, below the band, looks like −1/(M ω²)


def test_accelerance_input():
    h = TRUE.frf(F[1:])
    acc = FRF(h.freq_hz, -(h.omega**2) * h.values, "accelerance")
    fit = fit_modes(acc, n_modes=3)
    assert fit.fn_hz == pytest.approx(TRUE.fn_hz, rel=1e-6)


def test_table_lists_modes():
    text = fit_modes(TRUE.frf(F), n_modes=3).table()
    assert "650.00" in text and "1480.00" in text and "fit error" in text


@pytest.mark.parametrize("kw", [dict(n_modes=0), dict(n_modes=1.5), dict(band=(10.0, 12.0))])
def test_bad_input(kw):
    with pytest.raises(InputError):
        fit_modes(TRUE.frf(F), **kw)


def test_modal_model_validation():
    with pytest.raises(InputError):
        ModalModel([100.0, 200.0], [0.01], [1.0, 1.0])
    with pytest.raises(InputError):
        ModalModel([-100.0], [0.01], [1.0])
    with pytest.raises(InputError):
        ModalModel([100.0], [0.01], [0.0])
