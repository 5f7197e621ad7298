"""A small time-domain milling simulation for the tests and the benchmark of ``cut`` (not toolpoint's simulation).

Symmetric tool, real modes (f_m, k_m, ζ_m) in x and y; teeth at φ_j = Ω t + 2πj/N measured clockwise from +y
(toolpoint.stability.milling's conventions); chip h = f_z sin φ + s_prev − (x sin φ + y cos φ) while
φ_st ≤ φ ≤ φ_ex, s_prev the surface the previous tooth left at this angle (projected on the tooth's normal);
where h < 0 the tooth is out of the cut, h = 0 and the surface it leaves is the previous one plus the feed (the
nonlinearity that bounds chatter; Tlusty's surface-history simulation, Schmitz & Smith 2019 ch. 4); forces
F_x = a h (K_t cos φ + K_n sin φ), F_y = a h (−K_t sin φ + K_n cos φ). Each mode is stepped exactly for a force
held over the step (zero-order hold), ``steps`` steps per tooth period (the delay is a whole number of steps).
Points are simulated one after another with a Python loop over time: a test helper, not a fast simulator.

``microphone`` turns a simulated cut into a shop record: the tool's velocity (x' + y') plus 0.3 × the force's
derivative, resampled to 44.1 kHz behind an anti-aliasing filter (as a sound card: spindle harmonics above
22 kHz do not fold into the band; ``toolpoint.simulation.to_audio_rate``), between air cuts, with the room noise,
fan tones and spindle lines of ``shop_synth`` (tests/shop_synth.py). ``accelerometer`` hears it as an accelerometer
on the spindle housing does, in m/s² (its docstring gives each size and where it comes from).
"""

import numpy as np


def _zoh(fn, zeta, dt):
    """Exact one-step maps of q'' + 2ζω q' + ω² q = ω² u (u held): [q, v]' = A [q, v] + b u; per mode."""
    w = 2 * np.pi * fn
    wd = w * np.sqrt(1 - zeta ** 2)
    e = np.exp(-zeta * w * dt)
    c, s = np.cos(wd * dt), np.sin(wd * dt)
    a11 = e * (c + zeta * w / wd * s)
    a12 = e * s / wd
    a21 = -e * w * w / wd * s
    a22 = e * (c - zeta * w / wd * s)
    b1 = 1 - a11  # step response of the unit static gain
    b2 = -a21
    return a11, a12, a21, a22, b1, b2


def simulate(fn, k, zeta, *, teeth, kt, kr, phi_st, phi_ex, rpm, depth_m, feed_m=1e-4, revolutions=60,
             steps=64, seed=0):
    """Simulate points (rpm[i], depth_m[i]); returns list of (t (T,), x (T,), y (T,), fx (T,), fy (T,))."""
    rng = np.random.default_rng(seed)
    fn, k, zeta = map(np.asarray, (fn, k, zeta))
    out = []
    for n, a in zip(np.atleast_1d(rpm), np.atleast_1d(depth_m)):  # points one by one; time is the inner loop
        T = 60.0 / (n * teeth)
        dt = T / steps
        sub = max(1, int(np.ceil(dt * fn.max() * 20)))  # ≥ 20 steps per period of the highest mode
        dt /= sub
        nsteps = int(revolutions * teeth * steps * sub)
        delay = steps * sub
        a11, a12, a21, a22, b1, b2 = _zoh(fn, zeta, dt)
        q = np.zeros((2, fn.size))
        v = np.zeros((2, fn.size))
        q += 1e-9 * rng.standard_normal(q.shape)  # a seed of noise: chatter needs something to grow from
        hist = np.zeros((nsteps + 1, 2))
        surf = np.zeros((nsteps, teeth))  # surface left by tooth j at step i, along its normal, m
        force = np.zeros((nsteps, 2))
        omega = 2 * np.pi * n / 60
        jphase = 2 * np.pi * np.arange(teeth) / teeth
        nxt = (np.arange(teeth) + 1) % teeth  # the tooth that passed this angle one tooth period ago
        for i in range(nsteps):
            t = i * dt
            r = q.sum(axis=1)
            hist[i] = r
            phi = np.mod(omega * t + jphase, 2 * np.pi)
            s, c = np.sin(phi), np.cos(phi)
            prev = surf[i - delay, nxt] if i >= delay else np.zeros(teeth)  # fresh material before the first pass
            inside = (phi >= phi_st) & (phi <= phi_ex)
            nrm = s * r[0] + c * r[1]
            h = feed_m * s + prev - nrm
            cutting = inside & (h > 0)
            surf[i] = np.where(cutting, nrm, prev + feed_m * s)
            h = np.where(cutting, h, 0.0)
            fx = a * np.sum(h * (kt * c + kr * kt * s))
            fy = a * np.sum(h * (-kt * s + kr * kt * c))
            force[i] = fx, fy
            u = np.array([fx, fy])[:, None] / k[None, :]
            q, v = a11 * q + a12 * v + b1 * u, a21 * q + a22 * v + b2 * u
        hist[-1] = q.sum(axis=1)
        tt = np.arange(nsteps) * dt
        out.append((tt, hist[:-1, 0], hist[:-1, 1], force[:, 0], force[:, 1]))
    return out


def microphone(sim, *, rpm, teeth, rate=44100.0, air_s=0.7, noise=0.02, fans=(617.0, 1813.0), seed=0):
    """A shop microphone record of a simulated cut (module docstring): (samples, rate, cut start, cut end)."""
    from shop_synth import shop_record

    from toolpoint.simulation import to_audio_rate

    t, x, y, fx, fy = sim
    rng = np.random.default_rng(seed)
    dt = t[1] - t[0]
    vel = np.gradient(x + y, dt)
    df = np.gradient(fx + fy, dt)
    # drop the first 20 % (the tool starting at rest) is the detector's job (entry); record at the audio rate
    sig = to_audio_rate(vel / (np.std(vel) + 1e-30) + 0.3 * df / (np.std(df) + 1e-30), 1.0 / dt, rate)
    cut_s = (sig.size - 1) / rate
    base, _, t0, t1 = shop_record(rpm=rpm, teeth=teeth, rate=rate, air_s=air_s, cut_s=cut_s, fans=fans,
                                  fan_amp=0.05, noise=noise, seed=int(rng.integers(1 << 30)))
    # the record's spindle lines and noise stay; its synthetic cut harmonics are replaced by the simulation
    n0 = int(t0 * rate)
    out = base * 0.2
    seg = out[n0:n0 + sig.size]
    seg += 0.5 * sig[:seg.size] / np.max(np.abs(sig))
    return out / (1.2 * np.max(np.abs(out))), rate, t0, t1


def accelerometer(sim, *, rpm, teeth, rate=25600.0, air_s=0.7, seed=0, housing_hz=2500.0, housing_zeta=0.04,
                  housing_kg=10.0, tool_share=0.01, noise=5e-3, chip_noise=0.02, imbalance_mm_s=0.5, bearing=0.02,
                  preload_n=200.0, balls=17, ball_ratio=0.193, mains_hz=50.0, mains=0.1, offset=0.5, drift=0.2,
                  clip=None):
    """An accelerometer on the spindle housing during a simulated cut, m/s²: (samples, rate, cut start s, cut end s).

    What reaches the housing, in physical units so that a quiet cut is quiet (the sizes are this model's choices,
    each with where it comes from; Schmitz & Smith, *Machining Dynamics*, 2019, ch. 6 for the sensor's place):

    * the cutting force F_x + F_y through a housing mode at ``housing_hz`` (ζ ``housing_zeta``, modal mass
      ``housing_kg``: a housing's first modes lie at a few kHz, its mass is tens of kg), a = F/m ω²/(ω_h² − ω² +
      2iζω_hω) — 100 N of force fluctuation at the mode gives ~1 g; chatter modulates the force, so it reaches the
      housing even where the tool's mode barely moves the spindle nose; plus ``tool_share`` of the tool's own
      acceleration x'' + y'' (the part of the tool's vibration the bearings pass on: assumed);
    * chip formation: white force noise of ``chip_noise`` × the mean cutting force, through the same housing mode,
      while the tool is in the part (assumed);
    * in air and in the cut, the spindle's own lines: imbalance at f_s with ``imbalance_mm_s`` mm/s RMS velocity (ISO
      10816-3 calls < 1.4 mm/s good) and 1/4 of it at 2 f_s; the ball-pass and cage lines of an angular-contact
      bearing with ``balls`` balls, ball/pitch diameter ``ball_ratio``, 15° contact angle — non-synchronous: BPFO =
      Z/2 (1 − r cos α) f_s ≈ 6.86 f_s, BPFI ≈ 10.1 f_s, FTF ≈ 0.40 f_s — at ``bearing`` m/s² (≈ 2 mg, a healthy
      spindle) in air, scaled by 1 + |F̄|/``preload_n`` under the mean cutting force F̄ and with tooth-passing
      sidebands in proportion to the force's fluctuation at f_t (the load the bearings carry);
    * mains hum from a ground loop (``mains_hz`` and its 3rd harmonic, ``mains`` and ``mains``/3 m/s²: 1 mV of hum on a
      100 mV/g sensor), an offset (``offset`` m/s²: a DC-coupled channel or a MEMS sensor) with a slow drift
      (``drift`` m/s², a random walk low-passed to ≲ 1 Hz: temperature), the sensor's and the DAQ's white noise
      (``noise`` m/s² RMS: an IEPE sensor of 100 mV/g resolves ~1.5e-4 g over 1–10 kHz, a 24-bit ±5 V input ~5e-4 g);
    * sampled at ``rate`` (25.6 kS/s, an IEPE module's usual rate) behind an anti-aliasing filter; ``clip`` (m/s²)
      clips it as an overloaded input range would.
    """
    from scipy import signal

    from toolpoint.simulation import to_audio_rate

    t, x, y, fx, fy = sim
    rng = np.random.default_rng(seed)
    dt = t[1] - t[0]
    f = np.asarray(fx) + np.asarray(fy)
    f_mean = float(np.mean(np.hypot(fx, fy)))
    acc_tool = np.gradient(np.gradient(np.asarray(x) + np.asarray(y), dt), dt)
    n_sim = f.size
    force = f - f.mean() + chip_noise * f_mean * rng.standard_normal(n_sim)
    fr = np.fft.rfftfreq(n_sim, dt)
    wh, w = 2 * np.pi * housing_hz, 2 * np.pi * fr
    h = w**2 / (housing_kg * (wh**2 - w**2 + 2j * housing_zeta * wh * w))  # housing acceleration per N
    cut = np.fft.irfft(np.fft.rfft(force) * h, n_sim) + tool_share * acc_tool
    cut = to_audio_rate(cut, 1.0 / dt, rate)
    f_s, f_t = rpm / 60.0, teeth * rpm / 60.0
    # the force's fluctuation at the tooth passing, relative to the preload: how much the bearings' load swings
    ft_amp = 2 * np.abs(np.mean((f - f.mean()) * np.exp(-2j * np.pi * f_t * (np.asarray(t) - t[0]))))
    n0, nc = int(air_s * rate), cut.size
    n = nc + 2 * n0
    tt = np.arange(n) / rate
    inside = np.zeros(n)
    inside[n0:n0 + nc] = 1.0
    sig = np.zeros(n)
    sig[n0:n0 + nc] = cut
    for k, v in ((1, imbalance_mm_s), (2, imbalance_mm_s / 4)):  # a = ω v, v an RMS velocity in mm/s
        amp = np.sqrt(2) * 2 * np.pi * k * f_s * v * 1e-3
        sig += amp * np.sin(2 * np.pi * k * f_s * tt + rng.uniform(0, 2 * np.pi))
    cos_a = np.cos(np.radians(15.0))
    for order in (balls / 2 * (1 - ball_ratio * cos_a), balls / 2 * (1 + ball_ratio * cos_a),
                  0.5 * (1 - ball_ratio * cos_a)):
        fb = order * f_s
        ph = rng.uniform(0, 2 * np.pi)
        sig += bearing * (1 + inside * f_mean / preload_n) * np.sin(2 * np.pi * fb * tt + ph)
        for j in (-1, 1):
            sig += bearing * inside * 0.5 * ft_amp / preload_n * np.sin(2 * np.pi * (fb + j * f_t) * tt + ph)
    sig += mains * (np.sin(2 * np.pi * mains_hz * tt) + np.sin(2 * np.pi * 3 * mains_hz * tt + 1.0) / 3)
    walk = np.cumsum(rng.standard_normal(n))
    k = max(1, int(rate / 1.0))
    walk = signal.fftconvolve(walk, np.ones(k) / k, mode="same")  # np.convolve's to 1e-15, 35× faster for k = 25600
    walk -= walk.mean()
    sig += offset + drift * walk / (walk.std() + 1e-30)
    sig += noise * rng.standard_normal(n)
    if clip is not None:
        sig = np.clip(sig, -clip, clip)
    return sig, rate, n0 / rate, (n0 + nc) / rate
