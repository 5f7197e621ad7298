"""A realistic virtual impact (tap) test: hammer + accelerometer time records of a known grounded structure.

The structure is a set of real modes of a grounded tool point seen at the
driving point, mode r with natural frequency f_r (Hz), damping ratio ζ_r and
modal stiffness k_r (N/m):

    H(ω) = Σ_r (ω_r²/k_r) / (ω_r² − ω² + 2iζ_r ω_r ω)      (receptance, m/N; H(0) = Σ 1/k_r finite).

The hammer force is a sum of half-sine pulses f(t) = F sin(π (t − t₀)/T_c) on
[t₀, t₀ + T_c], whose Fourier transform is known in closed form,
F(ω) = F Ω (1 + e^{−iωT_c}) e^{−iωt₀} / (Ω² − ω²), Ω = π/T_c. Both channels
are computed **exactly** in the frequency domain, as an ideal delta-sigma
DAQ samples them: the continuous spectra F(ω) and −ω² H(ω) F(ω), times the
DAQ's anti-aliasing filter (flat to :data:`AA_PASS` · f_s, a raised-cosine
roll-off to zero at f_s/2), on the DFT grid of a period long enough for every
response to decay to e^{−30} before it wraps, and back by one inverse FFT.
The sampled signals are then the exact samples of band-limited signals
(Poisson summation: no aliasing), so the FRF of the record equals H(ω)
in the pass band up to the estimator's own errors. (Sampling the continuous
half-sine directly is not good enough: its rectangle-rule sum misses ∫f dt by
≈ π²/(12 N²) for N samples per pulse, and at 10 Hz the acceleration of a tool
point is 1e-5 of its mass-line part, so that error shows up as an f⁻² rise of
the receptance.)

Then the measurement chain adds, in the order a real one does (sizes in
:class:`Chain`, each with where it comes from):

1. accelerometer/conditioner high-pass (1st order, corner ``highpass_hz``) on the
   acceleration, started at rest, with a conditioner offset ``settling_ms2`` at
   its input: the output carries ``settling_ms2`` · e^{−2π f_c t} (the AC
   coupling still settling) — the slow, smooth part of the low-frequency artefact;
2. a DAQ offset ``offset_ms2`` / ``offset_n`` and a linear drift ``drift_ms2_per_s``;
3. mains hum ``hum_ms2`` at ``mains_hz`` and its odd harmonics (1, 1/3, 1/5);
4. white sensor noise ``noise_ms2`` / ``noise_n`` (rms over the band);
5. ADC quantisation to ``adc_bits`` over ±``range_ms2`` / ±``range_n``, and
   clipping at the range (an overload ``toolpoint tap`` must catch).

Hammer tips set the contact time :data:`TIPS` (half-sine of length T_c: its
spectrum is flat to ≈ 0.3/T_c and has its first zero at 1.5/T_c).

Only NumPy and SciPy; every random choice from a seeded
:class:`numpy.random.Generator`.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, replace

import numpy as np

__all__ = ["TIPS", "Mode", "Chain", "VirtualRecord", "LAB_MODES", "close_xy_modes", "receptance",
           "chain_receptance", "simulate_tap", "lab_like_tap", "write_record"]

TIPS = {"steel": 0.15e-3, "plastic": 0.4e-3, "rubber": 1.5e-3}
"""Hammer tip → contact time T_c, s (half-sine). Middle of the ranges of small modal hammers with a tool-point
load (PCB 086C03 tip curves; Schmitz & Smith, *Machining Dynamics*, 2nd ed., 2019, ch. 2): steel 0.1–0.2 ms,
plastic 0.3–0.5 ms, rubber 1–2 ms. First spectral zero ≈ 1.5/T_c: 10, 3.75, 1 kHz."""


@dataclass(frozen=True)
class Mode:
    """One real mode at the driving point: natural frequency (Hz), damping ratio, modal stiffness (N/m)."""

    fn_hz: float
    zeta: float
    stiffness_n_per_m: float


LAB_MODES = (
    Mode(1071.0, 0.037, 2.1e7),
    Mode(1981.0, 0.041, 1.9e7),
    Mode(2607.0, 0.021, 3.6e7),
    Mode(293.0, 0.05, 4.0e8),
    Mode(1265.0, 0.03, 2.5e8),
    Mode(2723.0, 0.02, 3.0e8),
)
"""Tool point modelled on the lab test of issue 20 (end mill in a collet holder): −Im H peaks at 1071 / 1981 /
2607 Hz with ζ 3.7 / 4.1 / 2.1 %, |H| ≈ 6.8e-7 m/N at the first peak; weaker modes near 293, 1265, 2723 Hz."""


def close_xy_modes(modes, *, split: float = 0.015, angle_deg: float = 10.0) -> tuple:
    """x modes and their close y twins as seen along a measurement direction off the principal axes.

    A slightly asymmetric tool has each bending mode twice, along its principal
    axes x' and y', at f and f (1 + split). Hammer and accelerometer along a
    direction at ``angle_deg`` to x' see H = cos²φ H_x' + sin²φ H_y': the x
    mode with stiffness k / cos²φ and the twin with k / sin²φ (both positive:
    a driving point). Split 1–3 % and misalignment 5–15° are typical of
    collet-held end mills (runout and clamping asymmetry; Schmitz & Smith 2019, ch. 2).
    """
    c2, s2 = math.cos(math.radians(angle_deg)) ** 2, math.sin(math.radians(angle_deg)) ** 2
    out = []
    for m in modes:
        out.append(Mode(m.fn_hz, m.zeta, m.stiffness_n_per_m / c2))
        if s2 > 0:
            out.append(Mode(m.fn_hz * (1 + split), m.zeta, m.stiffness_n_per_m / s2))
    return tuple(out)


def _poles(modes):
    fn = np.array([m.fn_hz for m in modes], float)
    z = np.array([m.zeta for m in modes], float)
    k = np.array([m.stiffness_n_per_m for m in modes], float)
    wn = 2 * np.pi * fn
    wd = wn * np.sqrt(1 - z**2)
    return -z * wn + 1j * wd, wn**2 / (2j * k * wd)


def receptance(modes, freq_hz) -> np.ndarray:
    """Exact receptance of the structure, m/N, on ``freq_hz`` (Hz).

    Examples
    --------
    At 0 Hz it is the static compliance Σ 1/k_r:

    >>> float(receptance([Mode(1000.0, 0.05, 1e7), Mode(2000.0, 0.03, 4e7)], [0.0])[0].real)
    1.25e-07
    """
    lam, a = _poles(modes)
    s = 2j * np.pi * np.asarray(freq_hz, float)[:, None]
    return np.sum(a / (s - lam) + np.conj(a) / (s - np.conj(lam)), axis=1)


@dataclass(frozen=True)
class Chain:
    """Transducers and acquisition: the size of each artefact, and where it comes from.

    Attributes
    ----------
    fs_hz : float
        Sampling rate, Hz (51.2 kHz: the lab test of issue 20; a common delta-sigma DAQ rate).
    adc_bits : int
        ADC resolution (24: delta-sigma DAQ modules; 16: older boards).
    range_n, range_ms2 : float
        Full scale ±, N and m/s²: a ±5 V input with the hammer's 2.25 mV/N (PCB 086C03: ±2224 N) and a
        5 mV/g accelerometer (PCB 352C23: ±1000 g ≈ ±9810 m/s²).
    noise_n, noise_ms2 : float
        White noise rms over the band: hammer 0.01 N (086C03 broadband resolution ≈ 0.009 N rms); accelerometer
        0.05 m/s² (352C23 broadband resolution ≈ 0.005 g rms) — the DAQ's own noise is below both at 24 bits.
    offset_n, offset_ms2 : float
        DC offsets after AC coupling: ±0.1 mV-class DAQ offset (0.05 N; 0.2 m/s² at 5 mV/g).
    settling_ms2 : float
        Conditioner input offset still settling through its high-pass (record taken seconds after the bias
        was switched on or after a cable move): ≈ 0.1 mV → 0.2 m/s², decaying as e^{−2π f_c t}.
    drift_ms2_per_s : float
        Slow drift (temperature, triboelectric cable): 0.1 m/s² per s; with one hit of ≈ 0.02 N s this alone
        puts an f⁻³ artefact of ≈ 1e-5 m/N at 10 Hz into the receptance — the size of the lab file's.
    highpass_hz : float
        1st-order high-pass corner of accelerometer + conditioner (PCB 352C23: 2 Hz at −5 %, i.e. a ≈ 0.6 Hz
        corner; conditioners 0.1–5 Hz).
    mains_hz, hum_ms2 : float
        Ground-loop hum on the acceleration channel: 50 Hz (60 in the Americas), 0.1 m/s² (0.05 mV at 5 mV/g)
        with odd harmonics 1/3, 1/5 of it.
    """

    fs_hz: float = 51200.0
    adc_bits: int = 24
    range_n: float = 2224.0
    range_ms2: float = 9810.0
    noise_n: float = 0.01
    noise_ms2: float = 0.05
    offset_n: float = 0.05
    offset_ms2: float = 0.2
    settling_ms2: float = 0.2
    drift_ms2_per_s: float = 0.1
    highpass_hz: float = 0.6
    mains_hz: float = 50.0
    hum_ms2: float = 0.1

    def clean(self) -> "Chain":
        """The same chain with every artefact off (no noise, offset, drift, hum, high-pass; 64-bit floats)."""
        return replace(self, adc_bits=0, noise_n=0.0, noise_ms2=0.0, offset_n=0.0, offset_ms2=0.0, settling_ms2=0.0,
                       drift_ms2_per_s=0.0, highpass_hz=0.0, hum_ms2=0.0, range_n=math.inf, range_ms2=math.inf)


def chain_receptance(modes, freq_hz, chain: Chain) -> np.ndarray:
    """What the chain measures as receptance on ``freq_hz`` without noise: H(ω) · iω/(iω + ω_c) (the high-pass)."""
    f = np.asarray(freq_hz, float)
    h = receptance(modes, f)
    if chain.highpass_hz > 0:
        s = 2j * np.pi * f
        h = h * s / (s + 2 * np.pi * chain.highpass_hz)
    return h


@dataclass(frozen=True)
class VirtualRecord:
    """A virtual impact record and its truth.

    Attributes
    ----------
    time_s, force_n, acceleration_ms2 : numpy.ndarray
        The record as the DAQ gives it (s, N, m/s²).
    hit_times_s, peaks_n : numpy.ndarray
        Start and peak force of each intended hit.
    double : tuple or None
        (hit index, delay s, relative amplitude) of a double hit.
    contact_s : float
        Half-sine contact time, s.
    modes : tuple of Mode
    chain : Chain
    """

    time_s: np.ndarray
    force_n: np.ndarray
    acceleration_ms2: np.ndarray
    hit_times_s: np.ndarray
    peaks_n: np.ndarray
    double: tuple | None
    contact_s: float
    modes: tuple
    chain: Chain = field(default_factory=Chain)

    def receptance(self, freq_hz) -> np.ndarray:
        """Exact receptance of the virtual structure, m/N."""
        return receptance(self.modes, freq_hz)


AA_PASS = 0.4
"""Anti-aliasing filter: flat to 0.4 f_s, raised-cosine roll-off to 0 at 0.5 f_s (delta-sigma DAQs: flat to
≈ 0.45 f_s with > 100 dB stop band)."""


def _half_sine_ft(w, width):
    """Fourier transform of sin(π t/T) on [0, T] (unit peak), N s per N: Ω (1 + e^{−iωT}) / (Ω² − ω²)."""
    om = np.pi / width
    den = om**2 - w**2
    near = np.abs(den) < 1e-9 * om**2
    with np.errstate(all="ignore"):
        ft = om * (1 + np.exp(-1j * w * width)) / np.where(near, 1.0, den)
    return np.where(near, -0.5j * width, ft)  # at ω = Ω: ∫ sin(Ωt) e^{−iΩt} dt = −iT/2


def simulate_tap(modes, *, hit_times_s=(0.02,), peaks_n=(150.0,), duration_s: float = 1.0, tip: str = "steel",
                 contact_s: float | None = None, double: tuple | None = None, chain: Chain | None = None,
                 rng: np.random.Generator | int | None = 0) -> VirtualRecord:
    """A virtual impact record of ``modes`` (exact response, then the chain's artefacts).

    Parameters
    ----------
    modes : sequence of Mode
        The grounded structure at the driving point.
    hit_times_s, peaks_n : sequence of float
        Start (s) and peak force (N) of each hit.
    duration_s : float
        Record length, s.
    tip : str
        ``"steel"``, ``"plastic"`` or ``"rubber"`` (:data:`TIPS`), unless ``contact_s`` is given.
    contact_s : float, optional
        Half-sine contact time, s.
    double : (int, float, float), optional
        (hit index, delay s, relative amplitude): a second pulse making that hit a double hit (the tool
        springs back into the hammer: delays of 1–3 ms and 20–50 % of the first pulse are typical).
    chain : Chain, optional
        Measurement chain (default :class:`Chain`); ``Chain().clean()`` for none.
    rng : numpy.random.Generator or int
        Seed of the noise.

    Returns
    -------
    VirtualRecord

    Examples
    --------
    One steel-tip hit on a 1 kHz mode, no artefacts: the force peaks at the given 100 N.

    >>> r = simulate_tap([Mode(1000.0, 0.03, 1e7)], peaks_n=(100.0,), duration_s=0.1, chain=Chain().clean())
    >>> r.time_s.size, round(float(r.force_n.max()))
    (5120, 100)
    """
    chain = Chain() if chain is None else chain
    rng = rng if isinstance(rng, np.random.Generator) else np.random.default_rng(rng)
    width = TIPS[tip] if contact_s is None else float(contact_s)
    hits = np.asarray(hit_times_s, float)
    peaks = np.asarray(peaks_n, float)
    n = int(round(duration_s * chain.fs_hz))
    lam, _ = _poles(modes)
    pulses = list(zip(hits, peaks))
    if double is not None:
        k, delay, rel = double
        pulses.append((hits[k] + delay, rel * peaks[k]))
    from scipy.fft import irfft, next_fast_len

    # one period holds the record and the decay of the last response to e^-30 (below round-off): no wrap-around
    t_decay = width + 30.0 / float(np.min(-lam.real))
    m = next_fast_len(int(np.ceil((max(duration_s, max(t0 for t0, _ in pulses) + t_decay) + t_decay)
                                  * chain.fs_hz)), real=True)
    freq = np.fft.rfftfreq(m, 1.0 / chain.fs_hz)
    w = 2 * np.pi * freq
    x = freq / chain.fs_hz
    aa = np.where(x <= AA_PASS, 1.0, 0.5 * (1 + np.cos(np.pi * (x - AA_PASS) / (0.5 - AA_PASS))))
    spec = _half_sine_ft(w, width) * sum(p * np.exp(-1j * w * t0) for t0, p in pulses) * aa
    force = irfft(spec, m)[:n] * chain.fs_hz
    acc = irfft(-(w**2) * receptance(modes, freq) * spec, m)[:n] * chain.fs_hz
    t = np.arange(n) / chain.fs_hz
    if chain.highpass_hz > 0:
        from scipy.signal import bilinear, lfilter

        wc = 2 * np.pi * chain.highpass_hz
        b, aa = bilinear([1.0, 0.0], [1.0, wc], fs=chain.fs_hz)
        acc = lfilter(b, aa, acc + chain.settling_ms2)  # starts at rest: the input offset settles out
    else:
        acc = acc + chain.settling_ms2
    acc = acc + chain.offset_ms2 + chain.drift_ms2_per_s * t
    if chain.hum_ms2:
        phase = rng.uniform(0, 2 * np.pi)
        for h, rel in ((1, 1.0), (3, 1 / 3), (5, 1 / 5)):
            acc = acc + chain.hum_ms2 * rel * np.sin(2 * np.pi * h * chain.mains_hz * t + h * phase)
    force = force + chain.offset_n + chain.noise_n * rng.standard_normal(n)
    acc = acc + chain.noise_ms2 * rng.standard_normal(n)
    if chain.adc_bits:
        force = _adc(force, chain.range_n, chain.adc_bits)
        acc = _adc(acc, chain.range_ms2, chain.adc_bits)
    return VirtualRecord(t, force, acc, hits, peaks, double, width, tuple(modes), chain)


def _adc(x, full_scale, bits):
    """Quantise to ``bits`` over ±full_scale and clip at the range (an overload)."""
    q = 2 * full_scale / 2**bits
    return np.clip(np.round(x / q) * q, -full_scale, full_scale - q)


def lab_like_tap(*, seed: int = 0, hits: int = 3, spacing_s: float = 0.08, first_s: float = 0.01,
                 duration_s: float | None = None, tip: str = "steel", peak_n: float = 150.0,
                 double: tuple | None = None, xy: bool = True, chain: Chain | None = None) -> VirtualRecord:
    """The lab test of issue 20 as a virtual record: :data:`LAB_MODES` (with close x/y twins), several hits.

    Peak forces scatter ±15 % (rms) around ``peak_n`` as a hand-held hammer does; the hits are
    ``spacing_s`` apart (the response of the 1071 Hz, ζ 3.7 % mode decays to 1e-4 in 37 ms).
    """
    rng = np.random.default_rng(seed)
    modes = close_xy_modes(LAB_MODES) if xy else LAB_MODES
    times = first_s + spacing_s * np.arange(hits)
    peaks = peak_n * np.clip(1 + 0.15 * rng.standard_normal(hits), 0.5, 1.5)
    dur = first_s + spacing_s * hits if duration_s is None else duration_s
    return simulate_tap(modes, hit_times_s=times, peaks_n=peaks, duration_s=dur, tip=tip, double=double,
                        chain=chain, rng=rng)


def write_record(path, rec: VirtualRecord, *, note: str = "") -> None:
    """Write a record as ``toolpoint tap`` reads it: CSV ``time_s,force_n,acceleration_ms2``, ``#`` comments first.

    Time with 8 significant digits, force and acceleration with 6 (finer than the noise: 0.01 N, 0.05 m/s²).
    """
    from .atomic import atomic_open

    c = rec.chain
    head = [
        "# SYNTHETIC impact record made by toolpoint.io.virtual_tap (not a measurement)",
        "# modes (f_n Hz, zeta, k N/m): " + "; ".join(f"{m.fn_hz:g} {m.zeta:g} {m.stiffness_n_per_m:.4g}"
                                                       for m in rec.modes),
        f"# half-sine contact {rec.contact_s * 1e3:g} ms; hits at {', '.join(f'{x:g}' for x in rec.hit_times_s)} s",
        f"# chain: fs {c.fs_hz:g} Hz, {c.adc_bits} bit, high-pass {c.highpass_hz:g} Hz, noise {c.noise_n:g} N / "
        f"{c.noise_ms2:g} m/s2, drift {c.drift_ms2_per_s:g} m/s2/s, hum {c.hum_ms2:g} m/s2 at {c.mains_hz:g} Hz",
    ] + ([f"# {note}"] if note else []) + ["time_s,force_n,acceleration_ms2"]
    body = "\n".join(f"{t:.8g},{f:.6g},{a:.6g}" for t, f, a in zip(rec.time_s, rec.force_n, rec.acceleration_ms2))
    with atomic_open(path, "w", encoding="utf-8", newline="\n") as fh:
        fh.write("\n".join(head) + "\n" + body + "\n")
