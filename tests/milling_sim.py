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
fan tones and spindle lines of ``shop_synth`` (tests/shop_synth.py).
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
