"""Surface location error in the frequency domain (Schmitz & Mann 2006), independent of the time stepping.

In a stable cut without runout the surfaces repeat, every chip is the
static one h_j = f_j sin φ_j, and the cutting force is the rigid-tool force
F(t), periodic with the revolution (the tooth period with equal pitch). Its
Fourier series F(t) = Σ_k F_k e^{ikΩt} through the receptance matrix Φ gives
the steady displacement

    r(t) = Re Σ_{k≥0} w_k Φ(ikΩ) F_k e^{ikΩt},   w_0 = 1, w_k = 2,            (1)

and the SLE is the tooth tip's deviation along the wall normal
n_g = (sin φ_g, cos φ_g) at the surface generation angle φ_g (exit in
down-milling, entry in up-milling): SLE = n_g · r(t_g), averaged over teeth
and slices, > 0 an undercut (the conventions of
:mod:`~toolpoint.simulation.time_domain`). F_k are computed by an FFT of F
sampled at ``samples`` midpoints per revolution; harmonics are kept up to
``HARMONIC_FACTOR`` × the highest natural frequency (Φ falls as 1/ω² above it).
"""

from __future__ import annotations

import numpy as np

from ..errors import InputError
from ..stability.cutting import check_cutting
from .structure import as_modal_dynamics
from .tool import Tool

__all__ = ["sle_frequency_domain", "HARMONIC_FACTOR"]

HARMONIC_FACTOR = 40.0
"""Harmonics of the revolution frequency are summed up to this multiple of the highest natural frequency."""


def sle_frequency_domain(modes_x, modes_y=None, cutting=None, *, rpm, depth_m, feed_m: float = 1e-4,
                         tool: Tool | None = None, samples: int = 1 << 14) -> np.ndarray:
    """Surface location error of stable cuts from the FRF and the Fourier series of the cutting force.

    Parameters
    ----------
    modes_x, modes_y, cutting
        As in :func:`~toolpoint.simulation.time_domain.simulate_milling`.
    rpm, depth_m : array_like
        Spindle speeds (rpm) and axial depths (m), broadcast.
    feed_m : float
        Mean feed per tooth, m.
    tool : Tool, optional
        Helix, slices, tooth angles and edge coefficients; runout is refused (the chips are then not the
        static ones).
    samples : int
        Force samples per revolution of the FFT.

    Returns
    -------
    numpy.ndarray
        SLE, m (> 0 undercut), shape of the broadcast.
    """
    cut = check_cutting(cutting)
    dyn = as_modal_dynamics(modes_x, modes_y)
    tool = Tool() if tool is None else tool
    if np.any(tool.runout(cut.teeth) != 0):
        raise InputError("the frequency-domain SLE assumes no runout", field="runout_m")
    r, a = np.broadcast_arrays(np.asarray(rpm, float), np.asarray(depth_m, float))
    if np.any(~np.isfinite(r) | (r <= 0)):
        raise InputError("spindle speeds must be finite and > 0 rpm", field="rpm")
    if np.any(~np.isfinite(a) | (a < 0)):
        raise InputError("axial depths must be finite and ≥ 0 m", field="depth_m")
    N = cut.teeth
    theta = tool.angles(N)
    pitch = (np.roll(theta, -1) - theta) % (2 * np.pi)
    pitch[pitch == 0] = 2 * np.pi
    feed = feed_m * N * pitch / (2 * np.pi)
    phi_st, phi_ex = cut.immersion_angles
    phi_g = phi_ex if cut.milling == "down" else phi_st
    n_g = np.array([np.sin(phi_g), np.cos(phi_g)])
    kt, kn, kte, kne = cut.tangential_coeff, cut.normal_coeff, tool.edge_tangential, tool.edge_normal
    grid = 2 * np.pi * (np.arange(samples) + 0.5) / samples  # tooth-0 angle at the samples, rad
    out = np.empty(r.size)
    for p, (rpm_p, a_p) in enumerate(zip(r.reshape(-1), a.reshape(-1))):  # per point: one FFT and one FRF
        psi, L = tool.lag(np.array([a_p]))
        psi = psi[:, 0]
        phi = grid[None, None, :] + theta[:, None, None] - psi[None, :, None]  # (N, L, K)
        inside = np.mod(phi - phi_st, 2 * np.pi) <= phi_ex - phi_st
        s, c = np.sin(phi), np.cos(phi)
        h = feed[:, None, None] * s
        on = inside & (h > 0)
        ft = np.where(on, kt * h + kte, 0.0) * a_p / L
        fn = np.where(on, kn * h + kne, 0.0) * a_p / L
        F = np.stack([(ft * c + fn * s).sum(axis=(0, 1)), (-ft * s + fn * c).sum(axis=(0, 1))])  # (2, K)
        f_rev = rpm_p / 60.0
        nh = int(min(samples // 2 - 1, np.ceil(HARMONIC_FACTOR * dyn.max_frequency_hz / f_rev)))
        Fk = np.fft.rfft(F, axis=1)[:, : nh + 1] / samples
        # the samples sit at midpoints: shift the coefficients to a series in the angle from 0
        k = np.arange(nh + 1)
        Fk = Fk * np.exp(-1j * k * np.pi / samples)[None, :]
        Phi = dyn.model.frf(k * f_rev)  # (nh+1, 2, 2)
        Rk = np.einsum("kij,jk->ik", Phi, Fk)
        Rk[:, 1:] *= 2
        # time (as tooth-0 angle) at which tooth j, slice l is at φ_g
        ang = np.mod(phi_g - theta[:, None] + psi[None, :], 2 * np.pi)  # (N, L)
        rr = np.real(np.einsum("ik,nlk->inl", Rk, np.exp(1j * k[None, None, :] * ang[:, :, None])))
        out[p] = float(np.mean(n_g[0] * rr[0] + n_g[1] * rr[1]))
    return out.reshape(r.shape)
