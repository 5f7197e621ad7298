"""Stability chart of a :class:`~toolpoint.stability.milling.LobeResult` (speed in rpm, depth in mm)."""

from __future__ import annotations

import numpy as np


def chart_top_mm(result) -> float:
    """Upper depth of the chart, mm.

    The highest finite limit (+10 %), at most 10 × the absolute minimum —
    lobe flanks rise steeply and one tall pocket would flatten everything
    else — but always above the best pocket (+10 %), so its marker is inside
    the axes.

    Parameters
    ----------
    result : LobeResult

    Returns
    -------
    float
        mm.
    """
    d = result.depth_mm
    fin = d[np.isfinite(d)]
    if fin.size == 0:
        return 1.0
    top = 1.1 * fin.max()
    low = 1e3 * result.min_depth_m if np.isfinite(result.min_depth_m) else fin.min()
    top = float(min(top, 10 * low)) if low > 0 else float(top)
    pocket = 1e3 * result.pocket().depth_m
    return max(top, 1.1 * pocket) if np.isfinite(pocket) else top


def plot_lobes(result, ax=None, *, show_lobes: bool | None = None, ymax_mm: float | None = None, annotate: bool = True):
    """Draw the stability limit, shade the unstable region above it, and the lobes.

    Axes: spindle speed [rpm] against axial depth of cut [mm]. ``inf`` limits
    (no instability found) are drawn at the top of the chart.

    Parameters
    ----------
    result : LobeResult
    ax : matplotlib.axes.Axes, optional
        Axes to draw on (a new figure by default).
    show_lobes : bool, optional
        Draw every lobe thin (default: for the zero-order approximation, whose
        lobes extend beyond the limit).
    ymax_mm : float, optional
        Top of the depth axis, mm (default :func:`chart_top_mm`).
    annotate : bool
        Mark the absolute minimum and the best pocket (when they lie inside the axes).

    Returns
    -------
    matplotlib.axes.Axes
    """
    if ax is None:
        import matplotlib.pyplot as plt

        _, ax = plt.subplots(figsize=(8, 4.5), constrained_layout=True)
    top = chart_top_mm(result) if ymax_mm is None else float(ymax_mm)
    rpm = result.rpm
    d = np.minimum(result.depth_mm, top)  # inf and tall pockets clip to the chart top
    # blue limit over an orange unstable region: told apart with every common colour-vision deficiency
    ax.fill_between(rpm, d, top, color="tab:orange", alpha=0.25, linewidth=0, label="unstable (chatter)")
    if show_lobes is None:
        show_lobes = result.method == "zoa"
    if show_lobes:
        span = rpm[-1] - rpm[0]
        for i, lobe in enumerate(result.lobes):
            r, dd = np.asarray(lobe.rpm, float), 1e3 * np.asarray(lobe.depth_m, float)
            # lobe points come one per FRF frequency; where they are further apart than 2 % of the axis a
            # straight chord would draw a lobe the data do not give: leave a gap instead
            gap = np.flatnonzero(np.abs(np.diff(r)) > 0.02 * span) + 1
            r, dd = np.insert(r, gap, np.nan), np.insert(dd, gap, np.nan)
            ax.plot(r, dd, color="0.55", lw=0.7, label="lobes" if i == 0 else None)
    ax.plot(rpm, d, color="tab:blue", lw=1.6, label=f"stability limit ({result.method.upper()})")
    if annotate:
        # Markers only where they fall inside the axes (a given ymax_mm can be lower).
        def inside(r, d_mm):
            return np.isfinite(d_mm) and rpm[0] <= r <= rpm[-1] and 0 <= d_mm <= top

        mr, md = result.min_rpm, 1e3 * result.min_depth_m
        if inside(mr, md):
            ax.plot([mr], [md], "v", color="k", ms=6, label=f"minimum {md:.3g} mm @ {mr:.0f} rpm")
        best = result.pocket()
        pr, pd = best.rpm, best.depth_m
        if inside(pr, 1e3 * pd):
            ax.plot([pr], [1e3 * pd], "^", mfc="white", mec="k", ms=7,
                    label=f"best pocket {1e3 * pd:.3g} mm @ {pr:.0f} rpm")
    ax.set_xlim(rpm[0], rpm[-1])
    ax.set_ylim(0, top)
    ax.set_xlabel("spindle speed [rpm]")
    ax.set_ylabel("axial depth of cut [mm]")
    ax.grid(True, alpha=0.3)
    ax.legend(loc="upper left", fontsize="small")
    return ax
