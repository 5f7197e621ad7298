"""Synthetic shop microphone records of milling cuts, written independently of the detector.

A record: air cut (spindle running, not cutting), entry, cut, exit, air cut. What a microphone in a
shop hears, and what is modelled here:

* spindle: all multiples of f_s = rpm/60 (runout), amplitude ∝ 1/k, weak in air cut;
* cutting: the tooth-passing frequency f_t = N f_s and its harmonics, strong (forced vibration),
  plus broadband cutting noise;
* room: pink-ish noise (integrated white noise, high-passed) and fan/pump tones at fixed
  frequencies that are not spindle multiples, the same in air cut and cut;
* chatter: a tone at f_c with aliases f_c ± f_t, growing in over ``onset_s`` and wandering ±0.1 % in
  frequency; at entry a decaying free vibration at the mode (stable cuts too);
* the spindle's speed (optional): a droop under load (``speed_droop`` of the speed when the tool enters, half
  of it recovered by the drive with a 0.3 s time constant), a slow wander (± ``speed_wander`` at ``wander_hz``)
  and a step (``speed_step`` of the speed over 0.2 s in the middle of the cut: the override turned, or a
  Harmonizer's new speed). Sizes: the real recording in ``examples/cuts`` runs 0.1–0.2 % faster in air than in
  the cut (its first two tooth-passing harmonics); an induction motor slips a few percent at full load, of which a
  drive without speed feedback leaves part.
"""

import numpy as np


def shop_record(*, rpm=6000.0, teeth=4, rate=44100.0, chatter_hz=None, chatter_amp=1.0, air_s=1.0, cut_s=2.0,
                fans=(617.0, 1813.0), fan_amp=0.3, noise=0.05, mode_hz=None, speed_droop=0.0, speed_wander=0.0,
                wander_hz=0.5, speed_step=0.0, air_lines=0.02, chatter_swing_db=0.0, swing_hz=0.4, ring_per_s=None,
                ramp_s=0.05, seed=0):
    """(samples, rate, cut start s, cut end s).

    ``air_lines``: the spindle's k-th harmonic in air, ``air_lines``/k (0.3–1: a spindle that rings in air).
    ``chatter_swing_db``: developed chatter waxes and wanes by this much (peak to peak, dB) at ``swing_hz``, as the
    real recording's chatter line does (±5 dB over a second or two, ``examples/cuts``). ``ring_per_s`` σ < 0: the
    line at ``chatter_hz`` is not a chatter's steady tone but a ring the cutting noise drives — a complex AR(1)
    process whose spectrum is a Lorentzian of half-width |σ|/2π (a stable cut's least damped mode just under its
    limit), of the same rms as the tone, with the same tooth-passing aliases. ``ramp_s``: the tool comes into the part
    over this long (its engagement growing over half its diameter of feed: 0.3 s for a 12 mm cutter at 1.2 m/min), the
    cut's lines, its noise and the ring or chatter with it."""
    rng = np.random.default_rng(seed)
    n = int((2 * air_s + cut_s) * rate)
    t = np.arange(n) / rate
    f_s = rpm / 60.0
    t0, t1 = air_s, air_s + cut_s
    ramp = np.clip((t - t0) / ramp_s, 0, 1) * np.clip((t1 - t) / 0.05, 0, 1)  # tool in the part
    x = np.zeros(n)
    kmax = int(min(8000.0, 0.45 * rate) / f_s)
    phases = rng.uniform(0, 2 * np.pi, kmax + 1)
    if speed_droop or speed_wander or speed_step:  # the spindle's phase, 2π ∫ f_s(t) dt
        te = np.clip(t - t0, 0, None)
        f_inst = f_s * (1 - speed_droop * ramp * (0.5 + 0.5 * np.exp(-te / 0.3)))
        f_inst = f_inst * (1 + speed_wander * np.sin(2 * np.pi * wander_hz * t))
        f_inst = f_inst * (1 + speed_step * np.clip((t - 0.5 * (t0 + t1)) / 0.2, 0, 1))
        spin = 2 * np.pi * np.cumsum(f_inst) / rate
    else:
        spin = None
    # the harmonics' sum is a Fourier series in the spindle's phase θ: tabulated once over a revolution by an inverse
    # FFT (M = 2^20 points: linear interpolation is off by (2π k / M)² / 8 of harmonic k's line, 3e-6 for k = 800)
    # and read at each sample's θ, instead of kmax sines over every sample (800 of them at 600 rpm: seconds per record)
    k = np.arange(1, kmax + 1)
    a_air = air_lines / k
    a_cut = np.where(k % teeth == 0, 1.0, 0.1) / (k / teeth) ** 1.2
    m = 2 ** 20
    tables = []
    for amp in (a_air, a_cut):
        c = np.zeros(m // 2 + 1, complex)
        c[k] = -0.5j * m * amp * np.exp(1j * phases[k])
        # Σ a_k sin(kθ + φ_k) at θ = grid: Im of m · ifft of c_k = a_k e^{iφ_k}, as a real inverse FFT (the same to
        # 1e-15, half the time)
        tables.append(np.fft.irfft(c, m))
    theta = np.mod(2 * np.pi * f_s * t if spin is None else spin, 2 * np.pi)
    # linear interpolation on the uniform periodic grid by index: np.interp(..., period=) sorts and pads the 2^20-point
    # table on every call (0.1 s a record, half of this function's time)
    pos = theta * (m / (2 * np.pi))
    j = np.minimum(pos.astype(np.int64), m - 1)
    fr = pos - j
    j1 = np.where(j + 1 == m, 0, j + 1)
    x += tables[0][j] + fr * (tables[0][j1] - tables[0][j])
    x += ramp * (tables[1][j] + fr * (tables[1][j1] - tables[1][j]))
    for f in fans:
        x += fan_amp * np.sin(2 * np.pi * f * t + rng.uniform(0, 2 * np.pi))
    room = np.cumsum(rng.standard_normal(n))
    room -= np.convolve(room, np.ones(441) / 441, mode="same")  # high-pass: pink-ish, no drift
    x += noise * room / room.std()
    x += 3 * noise * ramp * rng.standard_normal(n)  # cutting noise
    f_t = teeth * f_s
    if mode_hz is not None:  # entry transient: free vibration of the mode, decaying in 0.05 s
        te = np.clip(t - t0, 0, None)
        x += 0.5 * (t >= t0) * np.exp(-te / 0.05) * np.sin(2 * np.pi * mode_hz * te)
    if chatter_hz is not None:
        grow = np.clip((t - t0 - 0.1) / 0.3, 0, 1) * ramp
        if chatter_swing_db:
            grow = grow * 10 ** (chatter_swing_db / 40 * np.sin(2 * np.pi * swing_hz * t + rng.uniform(0, 2 * np.pi)))
        wander = 1 + 1e-3 * np.sin(2 * np.pi * 0.7 * t)
        phase = 2 * np.pi * np.cumsum(chatter_hz * wander) / rate
        if ring_per_s is None:
            line = np.exp(1j * phase)
        else:  # e^{(σ + i2πf)/rate} per sample, driven by complex white noise: unit mean power
            from scipy.signal import lfilter

            pole = np.exp((ring_per_s + 2j * np.pi * chatter_hz) / rate)
            e = (rng.standard_normal(n) + 1j * rng.standard_normal(n)) / np.sqrt(2.0)
            line = lfilter([np.sqrt(1 - abs(pole) ** 2)], [1.0, -pole], e)
        x += chatter_amp * grow * line.imag
        for j, a in ((-1, 0.3), (1, 0.2)):
            x += chatter_amp * a * grow * (line * np.exp(2j * np.pi * j * f_t * t)).imag
    return x / (1.5 * np.abs(x).max()), rate, t0, t1


def phone_agc(x, rate, attack_s, release_s, block=64):
    """A phone recorder's automatic gain control: the record divided by its RMS envelope, which follows a rise within
    ``attack_s`` and a fall within ``release_s`` (block by block; the envelope starts at the first 0.3 s's level)."""
    p = np.add.reduceat(x ** 2, np.arange(0, x.size, block)) / block
    env, e = np.empty_like(p), p[: int(0.3 * rate / block)].mean()
    a_up, a_down = np.exp(-block / (attack_s * rate)), np.exp(-block / (release_s * rate))
    for i, v in enumerate(p):  # a loop over blocks: the envelope is recursive
        a = a_up if v > e else a_down
        e = a * e + (1 - a) * v
        env[i] = e
    y = x * np.repeat(env ** -0.5, block)[: x.size]
    return 0.9 * y / np.abs(y).max()


def noise_driven_mode(fn, zeta, dur, seed, rate=20000.0):
    """A mode (f_n Hz, ζ) driven by white force noise — the exact discrete resonator, poles r e^{±iθ},
    r = e^{−ζω_n/rate}: its response's autocorrelation decays as e^{−ζω_n |τ|} — over a spindle's harmonic (100 Hz:
    6000 rpm) and sensor noise; ``dur`` s at ``rate`` Hz. The closed form of its ring: σ = −ζω_n."""
    import math

    from scipy.signal import lfilter

    rng = np.random.default_rng(seed)
    w = 2 * np.pi * fn
    r, th = math.exp(-zeta * w / rate), w * math.sqrt(1 - zeta ** 2) / rate
    y = lfilter([1.0], [1.0, -2 * r * math.cos(th), r * r], rng.standard_normal(int(dur * rate)))
    t = np.arange(y.size) / rate
    return y / y.std() + 3 * np.sin(2 * np.pi * 100 * t) + 0.05 * rng.standard_normal(y.size)
