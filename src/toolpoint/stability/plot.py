"""Stability chart of a :class:`~toolpoint.stability.milling.LobeResult`."""

from __future__ import annotations

import numpy as np


def chart_top_mm(result) -> float:
    """Upper depth of the chart, mm: the highest finite limit (+10 %), at most 10 × the absolute minimum.

    Lobe flanks rise steeply toward the stable pockets; without the cap one
    tall pocket would flatten everything else.
    """
    d = result.depth_mm
    fin = d[np.isfinite(d)]
    if fin.size == 0:
        return 1.0
    top = 1.1 * fin.max()
    low = 1e3 * result.min_depth_m if np.isfinite(result.min_depth_m) else fin.min()
    return float(min(top, 10 * low)) if low > 0 else float(top)


def plot_lobes(result, ax=None, *, show_lobes: bool | None = None, ymax_mm: float | None = None, annotate: bool = True):
    """Draw the stability limit, shade the unstable region above it, and the lobes.

    Axes: spindle speed [rpm] against axial depth of cut [mm]. ``inf`` limits
    (no instability found) are drawn at the top of the chart. ``show_lobes``
    (default: for the zero-order approximation, whose lobes extend beyond the
    limit) draws every lobe thin. Returns ``ax``.
    """
    if ax is None:
        import matplotlib.pyplot as plt

        _, ax = plt.subplots(figsize=(8, 4.5), constrained_layout=True)
    top = chart_top_mm(result) if ymax_mm is None else float(ymax_mm)
    rpm = result.rpm
    d = np.minimum(result.depth_mm, top)  # inf and tall pockets clip to the chart top
    ax.fill_between(rpm, d, top, color="tab:red", alpha=0.18, linewidth=0, label="unstable (chatter)")
    if show_lobes is None:
        show_lobes = result.method == "zoa"
    if show_lobes:
        for i, lobe in enumerate(result.lobes):
            ax.plot(lobe.rpm, 1e3 * lobe.depth_m, color="0.55", lw=0.7, label="lobes" if i == 0 else None)
    ax.plot(rpm, d, color="tab:blue", lw=1.6, label=f"stability limit ({result.method.upper()})")
    if annotate and np.isfinite(result.min_depth_m):
        ax.plot([result.min_rpm], [1e3 * result.min_depth_m], "v", color="k", ms=6,
                label=f"minimum {1e3 * result.min_depth_m:.3g} mm @ {result.min_rpm:.0f} rpm")
        pr, pd = result.pocket()
        if np.isfinite(pd):
            ax.plot([pr], [1e3 * pd], "^", color="tab:green", ms=7, label=f"best pocket {1e3 * pd:.3g} mm @ {pr:.0f} rpm")
    ax.set_xlim(rpm[0], rpm[-1])
    ax.set_ylim(0, top)
    ax.set_xlabel("spindle speed [rpm]")
    ax.set_ylabel("axial depth of cut [mm]")
    ax.grid(True, alpha=0.3)
    ax.legend(loc="upper left", fontsize="small")
    return ax
