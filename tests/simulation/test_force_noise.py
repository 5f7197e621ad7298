"""The cutting force's random fluctuation (``simulate_milling(force_noise=…)``) against closed forms: its spectrum
(white, one-sided PSD s²/B relative to the force) and the random vibration of a single mode it drives (σ_x² =
S_F π f_n / (4 ζ k²), the SDOF response to white force of one-sided PSD S_F)."""

import numpy as np
import pytest

from toolpoint.errors import InputError
from toolpoint.simulation import simulate_milling
from toolpoint.simulation.time_domain import NOISE_BAND_HZ
from toolpoint.stability import CuttingConditions

CUT = CuttingConditions(teeth=2, tangential_coeff=6e8, radial_ratio=1 / 3, radial_immersion=0.5)


def test_the_force_fluctuation_is_white_with_the_stated_level():
    # a tool so stiff that the noise does not move it: the noisy force over the quiet one is 1 + ξ exactly
    s = 0.05
    res = simulate_milling([(3000.0, 1e12, 0.05)], None, CUT, rpm=[12000.0] * 8, depth_m=[1e-3] * 8,
                           revolutions=60, steps_per_tooth=32, force_noise=s)
    quiet = simulate_milling([(3000.0, 1e12, 0.05)], None, CUT, rpm=[12000.0] * 8, depth_m=[1e-3] * 8,
                             revolutions=60, steps_per_tooth=32)
    fn, fq = res.force_n[..., 0], quiet.force_n[..., 0]
    cutting = np.abs(fq) > 1e-3 * np.abs(fq).max()
    xi = (fn[cutting] / fq[cutting]) - 1.0
    dt = float(res.dt_s[0])
    # per-step samples of std s / sqrt(2 Δt B): one-sided PSD 2 σ² Δt = s² / B
    want = s / np.sqrt(2 * dt * NOISE_BAND_HZ)
    assert abs(np.std(xi) / want - 1) < 0.03
    # white: consecutive steps uncorrelated (the steps where the tooth stays in the cut)
    rows = fn / np.where(cutting, fq, 1.0) - 1.0
    both = cutting[:, 1:] & cutting[:, :-1]
    r1 = np.mean(rows[:, 1:][both] * rows[:, :-1][both]) / np.var(xi)
    assert abs(r1) < 0.03
    # the verdict is the noise-free run's
    assert np.array_equal(res.stable, quiet.stable)
    assert res.params["force_noise"] == s


@pytest.mark.parametrize("fn_hz, zeta", [(900.0, 0.03), pytest.param(1500.0, 0.05, marks=pytest.mark.slow)])
def test_a_mode_driven_by_the_force_noise_vibrates_as_the_closed_form_says(fn_hz, zeta):
    # a shallow cut (0.05 % of the SDM limit there, 43 mm: the regeneration does not move the mode's damping), one mode
    # in x; the noisy run less its noise-free twin is the mode's response to the noise force F_x(t) ξ(t), whose
    # mean one-sided PSD is mean(F_x²) s² / B (a periodic force times white noise)
    k, s, P = 2e7, 0.05, 24
    res = simulate_milling([(fn_hz, k, zeta)], None, CUT, rpm=[9000.0] * P, depth_m=[2e-5] * P, revolutions=300,
                           record_revolutions=240, force_noise=s)
    quiet = simulate_milling([(fn_hz, k, zeta)], None, CUT, rpm=[9000.0] * P, depth_m=[2e-5] * P, revolutions=300,
                             record_revolutions=240)
    x = res.displacement_m[..., 0] - quiet.displacement_m[..., 0]
    s_f = np.mean(quiet.force_n[..., 0] ** 2) * s**2 / NOISE_BAND_HZ  # N²/Hz
    want = s_f * np.pi * fn_hz / (4 * zeta * k**2)
    got = np.mean(x**2)
    # 24 × 1.6 s of a response whose correlation time is 1/(ζ ω_n) ≈ 2–6 ms: a few % of sampling error (measured
    # 0.99 and 0.97 of the closed form)
    assert abs(got / want - 1) < 0.1, (got, want)


def test_force_noise_out_of_range_names_the_field():
    for bad in (-0.01, 0.5, float("nan"), "x"):
        with pytest.raises(InputError) as e:
            simulate_milling([(900.0, 2e7, 0.03)], None, CUT, rpm=[9000.0], depth_m=[1e-4], revolutions=8,
                             force_noise=bad)
        assert e.value.field == "force_noise"
