"""The spindle–holder subassembly seen from the holder tip.

Its 2×2 receptance matrix R(ω) = [[h, l], [n, p]] at the holder tip (h = y/F m/N,
l = y/M 1/N, n = θ/F rad/N, p = θ/M rad/(N m)) is all the tool needs to be
coupled (Eq. 3). It can come from the model (spindle + holder + spindle–holder
joint, Eq. 1), from measurements (inverse RCSA with a blank, or four FRF files),
and is kept separate from the tool so that one subassembly serves many tools.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .assembly import Assembly
from .components import end_receptances
from .coupling import couple


@dataclass(frozen=True)
class Subassembly:
    """Holder-tip receptance matrices R (F, 2, 2) on frequencies freq_hz (F,), Hz (no 0 Hz)."""

    freq_hz: np.ndarray
    R: np.ndarray
    label: str = "spindle–holder"

    def __post_init__(self):
        f = np.asarray(self.freq_hz, float).reshape(-1)
        R = np.asarray(self.R, complex)
        if R.shape != (f.size, 2, 2):
            raise ValueError(f"subassembly: R has shape {R.shape}, expected ({f.size}, 2, 2)")
        if f.size and (np.any(f <= 0) or np.any(np.diff(f) <= 0)):
            raise ValueError("subassembly: frequencies must be > 0 and strictly increasing")
        object.__setattr__(self, "freq_hz", f)
        object.__setattr__(self, "R", R)

    @classmethod
    def from_assembly(cls, assembly: Assembly, freq_hz) -> "Subassembly":
        """Spindle (on its bearings) + holder + spindle–holder joint, Eq. (1)."""
        f = np.asarray(freq_hz, float).reshape(-1)
        S = end_receptances(assembly.spindle, f, "end")
        H = end_receptances(assembly.holder, f)
        return cls(f, couple(H, S, assembly.spindle_holder.as_array(), 2 * np.pi * f), "spindle–holder (model)")

    def at(self, freq_hz) -> "Subassembly":
        """Linear interpolation of every entry, only inside the band (no extrapolation)."""
        fq = np.asarray(freq_hz, float).reshape(-1)
        if np.array_equal(fq, self.freq_hz):
            return self
        lo, hi = self.freq_hz[0], self.freq_hz[-1]
        tol = 1e-9 * hi
        if fq.min() < lo - tol or fq.max() > hi + tol:
            raise ValueError(
                f"{self.label} is known on {lo:g}–{hi:g} Hz; asked for {fq.min():g}–{fq.max():g} Hz "
                "(no extrapolation outside the measured band)"
            )
        flat = self.R.reshape(self.freq_hz.size, 4)
        out = np.empty((fq.size, 4), complex)
        for k in range(4):  # four entries, each vectorised over frequency
            out[:, k] = np.interp(fq, self.freq_hz, flat[:, k].real) + 1j * np.interp(fq, self.freq_hz, flat[:, k].imag)
        return Subassembly(fq, out.reshape(-1, 2, 2), self.label)
