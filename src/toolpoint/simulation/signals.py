"""Synthetic sensor signals of a simulated cut: microphone or accelerometer, resampled, as WAV or CSV.

The signal is the tool's velocity (``"microphone"``: a microphone hears the
radiating structure, roughly its velocity) or acceleration (``"accelerometer"``)
along x + y, obtained from the simulated displacement by central
differences, resampled to ``rate`` Hz as a recorder does (:func:`to_audio_rate`:
an anti-aliasing low-pass, then the new rate), plus white Gaussian noise of
standard deviation ``noise`` × the signal's RMS (a documented, seeded noise
floor). It is normalised to a peak of 0.9 for a WAV file.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from ..errors import InputError
from ..io.atomic import atomic_open, atomic_path

__all__ = ["sensor_signal", "write_signal", "to_audio_rate"]


def to_audio_rate(x, rate_in: float, rate: float) -> np.ndarray:
    """Resample a uniformly sampled signal to ``rate`` as a recorder's ADC does: band-limited first.

    A sound card or DAQ low-passes its input below the Nyquist frequency before sampling (the anti-aliasing
    filter of a sigma-delta converter, flat to about 0.45 ``rate``); sampling a simulation's fine steps
    without it folds every spindle harmonic above ``rate``/2 back into the band as a line at
    ``rate − k f_s`` that no microphone would record. Polyphase resampling (:func:`scipy.signal.resample_poly`,
    Kaiser-windowed FIR, ≈ 60 dB stop band) by the ratio ``up/down`` nearest to ``rate/rate_in`` with
    ``down ≤ 10000``: the samples are ``1/rate`` apart to within 40 ppm (measured over 2000 ratios from 30 kHz
    to 1 MHz in; a sound card's clock is good to 20–100 ppm).

    Parameters
    ----------
    x : array_like, shape (n,)
        Samples at ``rate_in``.
    rate_in, rate : float
        Sample rates in and out, Hz.

    Returns
    -------
    numpy.ndarray
        The signal at ``rate`` (``floor(n · rate / rate_in)`` samples, the first at the same time as ``x[0]``).

    Examples
    --------
    A 30 kHz tone sampled at 200 kHz is not heard at 44.1 kHz (it would fold to 14.1 kHz):

    >>> import numpy as np
    >>> t = np.arange(20000) / 200e3
    >>> y = to_audio_rate(np.sin(2 * np.pi * 30e3 * t), 200e3, 44100.0)
    >>> bool(np.max(np.abs(y[100:-100])) < 0.01)
    True
    """
    from fractions import Fraction

    from scipy.signal import resample_poly

    x = np.asarray(x, float)
    n_out = int(x.size * rate / rate_in)
    q = Fraction(rate / rate_in).limit_denominator(10000)
    y = resample_poly(x, q.numerator, q.denominator, padtype="line") if q != 1 else x
    if y.size < n_out:
        y = np.pad(y, (0, n_out - y.size), mode="edge")
    return y[:n_out]


def sensor_signal(result, point: int = 0, *, kind: str = "microphone", rate: float = 44100.0, noise: float = 0.01,
                  seed: int = 0) -> tuple[np.ndarray, np.ndarray]:
    """Synthetic sensor record of one point of a :class:`~toolpoint.simulation.time_domain.SimulationResult`.

    Parameters
    ----------
    result : SimulationResult
        The simulation (its recorded part is used).
    point : int
        Index of the point.
    kind : {"microphone", "accelerometer"}
        Velocity (m/s) or acceleration (m/s²) along x + y.
    rate : float
        Sample rate, Hz (1 kHz … 1 MHz).
    noise : float
        Noise standard deviation relative to the signal's RMS (≥ 0).
    seed : int
        Noise seed.

    Returns
    -------
    (t, x) : tuple of numpy.ndarray
        Times, s, and the signal (m/s or m/s², noise included).
    """
    if kind not in ("microphone", "accelerometer"):
        raise InputError(f"must be 'microphone' or 'accelerometer', got {kind!r}", field="kind")
    rate = float(rate)
    if not (np.isfinite(rate) and 1e3 <= rate <= 1e6):
        raise InputError(f"must be from 1e3 to 1e6 Hz, got {rate:g}", field="rate")
    if not (np.isfinite(noise) and noise >= 0):
        raise InputError(f"must be finite and ≥ 0, got {noise!r}", field="noise")
    t = result.time_s[point]
    d = result.displacement_m[point].sum(axis=1)
    dt = float(result.dt_s[point])
    sig = np.gradient(d, dt)
    if kind == "accelerometer":
        sig = np.gradient(sig, dt)
    out = to_audio_rate(sig, 1.0 / dt, rate)
    tn = t[0] + np.arange(out.size) / rate
    rms = float(np.sqrt(np.mean(out**2))) if out.size else 0.0
    out = out + noise * rms * np.random.default_rng(seed).standard_normal(out.size)
    return tn, out


def write_signal(path, t, x, rate: float) -> Path:
    """Write a sensor signal atomically: WAV (``.wav``, 24-bit PCM, peak 0.9) or CSV (``t_s,value``).

    Parameters
    ----------
    path : str or PathLike
        Output file; the extension chooses the format.
    t, x : numpy.ndarray
        Times (s) and values.
    rate : float
        Sample rate, Hz (WAV).

    Returns
    -------
    pathlib.Path
    """
    p = Path(path)
    if p.suffix.lower() == ".wav":
        import soundfile

        peak = float(np.max(np.abs(x))) if len(x) else 0.0
        data = 0.9 * np.asarray(x) / peak if peak > 0 else np.zeros(len(x))
        with atomic_path(p) as tmp:
            soundfile.write(tmp, data, int(round(rate)), subtype="PCM_24", format="WAV")
    elif p.suffix.lower() == ".csv":
        with atomic_open(p, "w", newline="") as fh:
            fh.write("t_s,value\n")
            np.savetxt(fh, np.column_stack([t, x]), fmt="%.10g", delimiter=",")
    else:
        raise InputError(f"expected .wav or .csv, got {p.suffix or 'no extension'!r}", file=p, field="audio")
    return p
