"""Synthetic impact records of a known 3-mode system, exact in closed form (used by test_tap and bench_tap).

The response is NOT computed from an FRF: each mode's impulse response
2 Re(A e^{λt}) is integrated against the half-sine force pulse in closed form
(Duhamel integral), so the only differences between the sampled record and the
continuous FRF are the added noise and the aliasing of the sampled force.
"""

from __future__ import annotations

import numpy as np

# Three modes: natural frequency Hz, damping ratio, modal mass kg.
FN = np.array([250.0, 700.0, 1300.0])
ZETA = np.array([0.02, 0.03, 0.025])
MASS = np.array([0.8, 1.5, 2.5])


def poles():
    """(λ_r, A_r): receptance H(s) = Σ A/(s − λ) + conj(A)/(s − conj λ); A = 1/(2i m ω_d) (so h(0) = 0)."""
    wn = 2 * np.pi * FN
    wd = wn * np.sqrt(1 - ZETA**2)
    return -ZETA * wn + 1j * wd, 1.0 / (2j * MASS * wd)


def exact_receptance(freq_hz):
    """Exact receptance (m/N) of the 3-mode system on ``freq_hz``."""
    lam, a = poles()
    s = 2j * np.pi * np.asarray(freq_hz, float)[:, None]
    return np.sum(a / (s - lam) + np.conj(a) / (s - np.conj(lam)), axis=1)


def half_sine_response(t, t0, amp, width):
    """Force f(t) = amp sin(π (t − t0)/width) on [t0, t0 + width] and the exact acceleration (m/s²) it causes.

    y_r(t) = ∫ e^{λ(t−u)} f(u) du in closed form; acceleration = Σ 2 Re(A (λ² y + λ f)) (Σ 2 Re A = 0).
    """
    lam, a = poles()
    om = np.pi / width
    tt = t - t0
    on = tt > 0
    tau = np.clip(tt, 0.0, width)[:, None]
    f = np.where((tt >= 0) & (tt <= width), amp * np.sin(om * np.clip(tt, 0, width)), 0.0)
    # ∫_0^τ e^{-λu} sin(Ωu) du = (e^{-λτ}(−λ sin Ωτ − Ω cos Ωτ) + Ω) / (λ² + Ω²)
    integral = (np.exp(-lam * tau) * (-lam * np.sin(om * tau) - om * np.cos(om * tau)) + om) / (lam**2 + om**2)
    y = np.where(on[:, None], amp * np.exp(lam * np.maximum(tt, 0)[:, None]) * integral, 0.0)
    acc = np.sum(2 * np.real(a * (lam**2 * y + lam * f[:, None])), axis=1)
    return f, acc


def record(fs=25600.0, hits=((0.05, 100.0), (0.65, 80.0), (1.25, 120.0), (1.85, 90.0), (2.45, 110.0)),
           width=5e-4, double=(3, 0.003, 0.4), noise=(0.002, 0.002), duration=3.05, seed=0):
    """One long record (time s, force N, acceleration m/s²) with several hits.

    ``hits``: (time s, peak force N) of each hit; ``double``: (hit index, delay s,
    relative amplitude) of a second pulse making that hit a double hit (None: none);
    ``noise``: rms of white noise on force and response relative to each channel's peak.
    """
    t = np.arange(int(round(duration * fs))) / fs
    force, acc = np.zeros(t.size), np.zeros(t.size)
    pulses = [(t0, p) for t0, p in hits]
    if double is not None:
        k, delay, rel = double
        pulses.append((hits[k][0] + delay, rel * hits[k][1]))
    for t0, p in pulses:
        f, a = half_sine_response(t, t0, p, width)
        force += f
        acc += a
    rng = np.random.default_rng(seed)
    force += noise[0] * np.abs(force).max() * rng.standard_normal(t.size)
    acc += noise[1] * np.abs(acc).max() * rng.standard_normal(t.size)
    return t, force, acc
