"""A measured-like tool-point receptance with the artefacts of a real lab tap test.

Modelled on a university lab's impact test of an end mill in a collet holder (issue 20): receptance derived
from accelerance, 0–5000 Hz at 1 Hz, tab-separated text. Every size below comes from that measurement:

* **Modes** (grounded structure, driving point, positive modal masses): the three dominant ones at
  1071 / 1981 / 2607 Hz (−Im H peaks of the lab file) with half-power damping 3.7 / 4.1 / 2.1 %; weaker ones
  near 293, 1265 and 2723 Hz. The first mode's modal stiffness (2.1e7 N/m) puts |H| at its peak near the
  measured 6.8e-7 m/N; the others are set so the three dominant peaks have similar height, as measured.
  Small residue phases (non-proportional damping) shift the |H| peak below the −Im peak, as in the lab file
  (1056 vs 1071 Hz).
* **Low-frequency artefact** — smooth, not noise: an offset/drift in the acceleration channel divided by −ω²
  (and by the force spectrum). Its size follows the lab file: |H| ≈ 1.2e-2 m/N at 1 Hz, 7.7e-5 at 5 Hz,
  1.3e-5 at 10 Hz, 3.6e-6 at 20 Hz, 7e-7 at 40 Hz — between f⁻³ and f⁻²; modelled as
  [c₁ / (1 + i f / f_c) + c₂] / (iω)² with f_c = 1 Hz, matching those five values within a factor 1.6.
* **Noise white in accelerance** (accelerometer noise floor after averaging): σ_A = 2e-4 m/(N s²) per line,
  ~0.1 % of the accelerance at the first peak, so the receptance noise grows as 1/ω² below a few hundred Hz.

``reference_frf`` is the same structure without artefact or noise: the answer a careful engineer's
``--band 200:5000`` stands for.
"""

from __future__ import annotations

import numpy as np

from toolpoint import FRF

# (f_n Hz, ζ, modal stiffness N/m, residue phase rad): dominant three, then the small ones
MODES = (
    (1071.0, 0.037, 2.1e7, -0.12),
    (1981.0, 0.041, 1.9e7, 0.05),
    (2607.0, 0.021, 3.6e7, 0.0),
    (293.0, 0.05, 4.0e8, 0.0),
    (1265.0, 0.03, 2.5e8, 0.1),
    (2723.0, 0.02, 3.0e8, 0.0),
)
DOMINANT_HZ = (1071.0, 1981.0, 2607.0)
DOMINANT_ZETA = (0.037, 0.041, 0.021)
ARTEFACT_C1 = 0.54  # m/N · (rad/s)²: the f⁻³ part, dominant below ~10 Hz
ARTEFACT_C2 = 0.03  # m/N · (rad/s)²: the f⁻² tail, dominant at 20–60 Hz
ARTEFACT_FC_HZ = 1.0
NOISE_ACCELERANCE = 2e-4  # m/(N s²) per line


def structure(freq_hz) -> np.ndarray:
    """Receptance of the grounded structure alone, m/N (sum of complex modes; finite static compliance)."""
    f = np.asarray(freq_hz, float)
    w = 2 * np.pi * f
    h = np.zeros(f.shape, complex)
    for fn, zeta, k, phase in MODES:
        wn = 2 * np.pi * fn
        wd = wn * np.sqrt(1 - zeta**2)
        s = -zeta * wn + 1j * wd
        # complex mode pair with residue A = r e^{iφ}; r chosen so that a real (φ = 0) mode has stiffness k
        r = wn**2 / (2j * wd * k) * np.exp(1j * phase)
        h += r / (1j * w - s) + np.conj(r) / (1j * w - np.conj(s))
    return h


def artefact(freq_hz) -> np.ndarray:
    """The smooth low-frequency artefact, m/N: acceleration offset/drift divided by −ω²."""
    f = np.asarray(freq_hz, float)
    w = 2 * np.pi * np.maximum(f, 1e-3)
    return (ARTEFACT_C1 / (1 + 1j * f / ARTEFACT_FC_HZ) + ARTEFACT_C2) / (1j * w) ** 2


def lab_like_frf(seed: int = 0, *, fmax_hz: float = 5000.0, df_hz: float = 1.0, noise: float = NOISE_ACCELERANCE,
                 with_artefact: bool = True) -> FRF:
    """The measured-like receptance, 0 (or df) … fmax Hz: structure + artefact + noise white in accelerance.

    The 0 Hz line is left out (a receptance derived from accelerance is undefined there), so the grid starts at
    ``df_hz``.
    """
    f = np.arange(df_hz, fmax_hz + df_hz / 2, df_hz)
    w = 2 * np.pi * f
    h = structure(f)
    if with_artefact:
        h = h + artefact(f)
    rng = np.random.default_rng(seed)
    e = noise * (rng.standard_normal(f.size) + 1j * rng.standard_normal(f.size)) / np.sqrt(2)
    h = h + e / (-(w**2))
    return FRF(f, h, label=f"lab-like seed {seed}")


def reference_frf(*, fmax_hz: float = 5000.0, df_hz: float = 1.0, f_lo_hz: float = 200.0) -> FRF:
    """The structure alone over ``f_lo_hz`` … fmax: what the trusted band should leave to the lobes."""
    f = np.arange(f_lo_hz, fmax_hz + df_hz / 2, df_hz)
    return FRF(f, structure(f), label="lab-like reference")


def write_tsv(frf: FRF, path) -> None:
    """Write as the lab's file: tab-separated ``freq Hz, Re, Im`` in m/N, no header."""
    np.savetxt(path, np.column_stack([frf.freq_hz, frf.values.real, frf.values.imag]), delimiter="\t", fmt="%.9g")
