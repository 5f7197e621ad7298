"""Figures: the paper's Fig. 4 (measured vs identified FRF) and convergence histories."""

from __future__ import annotations

import numpy as np

from ..frf import FRF


def fit_figure(measured: FRF, fitted: dict[str, FRF], histories: dict[str, np.ndarray] | None = None, title: str = ""):
    """Magnitude and phase of the measured FRF with identified ones overlaid (the paper's Fig. 4).

    Parameters
    ----------
    measured : FRF
        Measured tool-point receptance, m/N.
    fitted : dict
        Label → identified model FRF (e.g. ``IdentificationResult.model_frf``).
    histories : dict, optional
        Label → best objective per iteration, m/N, drawn on log axes in a third panel.
    title : str, optional

    Returns
    -------
    matplotlib.figure.Figure
    """
    import matplotlib.pyplot as plt

    rows = 3 if histories else 2
    fig = plt.figure(figsize=(8, 3.0 * rows), constrained_layout=True)
    gs = fig.add_gridspec(rows, 1, height_ratios=[2, 1.2] + ([1.4] if histories else []))
    a0 = fig.add_subplot(gs[0])
    a1 = fig.add_subplot(gs[1], sharex=a0)
    measured.plot(ax=(a0, a1), color="k", lw=2.2, alpha=0.45, label=measured.label or "measured")
    styles = ["--", "-.", ":", (0, (5, 1)), (0, (3, 1, 1, 1))]
    for (name, frf), ls in zip(fitted.items(), styles * 3):
        frf.plot(ax=(a0, a1), lw=1.2, ls=ls, label=name)
    a0.set_title(title or "tool-point receptance: measured and identified")
    if histories:
        a2 = fig.add_subplot(gs[2])
        for name, h in histories.items():
            h = np.asarray(h, float)
            if h.size:
                a2.loglog(np.arange(1, h.size + 1), h, label=name)
        a2.set_xlabel("iteration (generation)")
        a2.set_ylabel("best objective ‖h − h_meas‖ [m/N]")
        a2.grid(True, which="both", alpha=0.3)
        a2.legend(fontsize="small")
    return fig
