"""The spindle–holder subassembly seen from the holder tip: a 2×2 receptance FRF.

Its receptance matrix R(ω) = [[h, l], [n, p]] at the holder tip (h = y/F m/N,
l = y/M 1/N, n = θ/F rad/N, p = θ/M rad/(N m)) is all the tool needs to be
coupled (Eq. 3). It can come from the model (spindle + holder + spindle–holder
joint, Eq. 1), from measurements (inverse RCSA with a blank, or four FRF files),
and is kept separate from the tool so that one subassembly serves many tools.
"""

from __future__ import annotations

import numpy as np

from .assembly import Assembly
from .components import end_receptances
from .coupling import couple
from ..frf import FRF, check_freq_hz

__all__ = ["Subassembly"]


class Subassembly(FRF):
    """Holder-tip receptance matrices R (F, 2, 2) on frequencies > 0 Hz: a 2×2 receptance :class:`FRF`.

    Everything of :class:`~toolpoint.frf.FRF` applies (``at`` interpolates all four
    entries inside the band only, ``band``, ``entry``); the quantity is always
    receptance and 0 Hz is refused (the free–free holder is singular there).

    Parameters
    ----------
    freq_hz : array_like
        (F,) frequencies, Hz, > 0 and strictly increasing.
    R : array_like
        (F, 2, 2) complex [[h, l], [n, p]]: m/N, 1/N, rad/N, rad/(N m).
    label : str
        Where it came from (model, inverse RCSA, files).
    meta : dict, optional
        Free-form provenance.

    Examples
    --------
    >>> import numpy as np
    >>> R = np.zeros((3, 2, 2), complex) + np.eye(2) * 1e-8
    >>> sub = Subassembly([100.0, 200.0, 300.0], R)
    >>> sub.at([150.0]).R[0].real.tolist()
    [[1e-08, 0.0], [0.0, 1e-08]]
    >>> Subassembly([0.0, 1.0, 2.0], R)
    Traceback (most recent call last):
    ...
    toolpoint.errors.InputError: freq_hz: frequencies must be > 0 Hz, got 0
    """

    _positive_freq = True
    _entry_shape = (2, 2)

    def __init__(self, freq_hz, R, label: str = "spindle–holder", meta: dict | None = None):
        FRF.__init__(self, freq_hz, R, "receptance", label, {} if meta is None else meta)

    @property
    def R(self) -> np.ndarray:
        """The receptance matrices (F, 2, 2) [[h, l], [n, p]] (the FRF's ``values``)."""
        return self.values

    @classmethod
    def from_assembly(cls, assembly: Assembly, freq_hz, *, max_beta_l: float | None = None) -> "Subassembly":
        """Spindle (on its bearings) + holder + spindle–holder joint, Eq. (1).

        C = H_ii − H_ic (H_cc + S + K⁻¹)⁻¹ H_ci with S the spindle's end receptance,
        H the free–free holder's and K the spindle–holder joint stiffness.

        Parameters
        ----------
        assembly : Assembly
            Its tool is not used.
        freq_hz : array_like
            (F,) frequencies > 0 Hz.
        max_beta_l : float, optional
            Mesh parameter of :func:`~toolpoint.dynamics.components.mesh` (default
            ``MAX_BETA_L``); only for convergence checks.
        """
        f = check_freq_hz(freq_hz, positive=True, min_points=0)
        S = end_receptances(assembly.spindle, f, "end", max_beta_l=max_beta_l)
        H = end_receptances(assembly.holder, f, max_beta_l=max_beta_l)
        return cls(f, couple(H, S, assembly.spindle_holder.as_array(), 2 * np.pi * f), "spindle–holder (model)")
