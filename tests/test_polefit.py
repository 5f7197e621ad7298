"""Common-pole modal fit against an independent 3-DOF system with non-proportional damping."""

import numpy as np
import pytest
from scipy.linalg import eig

from toolpoint.dynamics.polefit import fit_common_poles

M = np.diag([1.0, 0.6, 0.4])  # kg
K = np.array([[3.0, -1.5, 0.0], [-1.5, 2.5, -1.0], [0.0, -1.0, 1.0]]) * 4e7  # N/m
C = np.array([[60.0, -20.0, 0.0], [-20.0, 20.0, 0.0], [0.0, 0.0, 8.0]])  # N s/m, not ∝ M or K
F = np.arange(20.0, 3000.0, 2.0)


def frfs(f):
    """H00, H01, H22 by a direct solve of (K − ω²M + iωC) x = F at each frequency."""
    w = 2 * np.pi * f
    H = np.linalg.inv(K[None] - w[:, None, None] ** 2 * M[None] + 1j * w[:, None, None] * C[None])
    return np.stack([H[:, 0, 0], H[:, 0, 1], H[:, 2, 2]], -1)


def poles():
    """Natural frequencies (Hz) and damping ratios from the state-space eigenvalues."""
    n = M.shape[0]
    A = np.block([[np.zeros((n, n)), np.eye(n)], [-np.linalg.solve(M, K), -np.linalg.solve(M, C)]])
    lam = eig(A)[0]
    lam = lam[lam.imag > 0]
    wn = np.abs(lam)
    order = np.argsort(wn)
    return wn[order] / (2 * np.pi), (-lam.real / wn)[order]


def test_noise_free_fit_recovers_poles_and_frfs():
    Y = frfs(F)
    fit = fit_common_poles(F, Y)
    fn, zeta = poles()
    in_band = (fit.fn_hz > F[0]) & (fit.fn_hz < F[-1])
    assert fit.fn_hz[in_band] == pytest.approx(fn, rel=1e-7)
    assert fit.zeta[in_band] == pytest.approx(zeta, rel=1e-5)
    assert np.all(fit.fit_error < 1e-8)
    f_new = np.linspace(25.0, 2990.0, 777)  # off the fitted grid
    assert np.abs(fit(f_new) - frfs(f_new)).max() < 1e-7 * np.abs(frfs(f_new)).max()


def test_noisy_fit_removes_noise_and_keeps_peaks():
    rng = np.random.default_rng(3)
    Y = frfs(F)
    sigma = 2e-3 * np.abs(Y).max(0)
    noisy = Y + sigma * (rng.standard_normal(Y.shape) + 1j * rng.standard_normal(Y.shape)) / np.sqrt(2)
    fit = fit_common_poles(F, noisy)
    err_fit = np.sqrt(np.mean(np.abs(fit(F) - Y) ** 2, 0))
    err_raw = np.sqrt(np.mean(np.abs(noisy - Y) ** 2, 0))
    assert np.all(err_fit < 0.2 * err_raw)  # most of the noise is gone …
    assert np.abs(fit(F)).max(0) == pytest.approx(np.abs(Y).max(0), rel=5e-3)  # … and the peaks are not rounded
    assert fit.n_modes >= 3


def test_same_data_same_fit_and_bad_input():
    Y = frfs(F)
    a, b = fit_common_poles(F, Y), fit_common_poles(F, Y)
    assert np.array_equal(a.fn_hz, b.fn_hz) and np.array_equal(a.coef, b.coef)
    with pytest.raises(ValueError, match="increasing"):
        fit_common_poles(F[::-1], Y)
