"""Stability and surface location error over a (speed, depth) grid, and the stability boundary by bisection.

Both run the time-domain simulation (:func:`~toolpoint.simulation.time_domain.simulate_milling`) on all
points at once: the points are grouped by the steps per tooth period their speed needs (slow speeds need
more to resolve the modes), and every group is one vectorised batch.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from ..errors import InputError
from ..stability.cutting import check_cutting
from .structure import as_modal_dynamics
from .time_domain import simulate_milling, steps_per_tooth_needed

__all__ = ["SimulationMap", "simulate_map", "stability_boundary"]


@dataclass(frozen=True)
class SimulationMap:
    """Simulated stability and SLE on a speed × depth grid.

    Attributes
    ----------
    rpm : numpy.ndarray
        (n_s,) spindle speeds, rpm.
    depth_m : numpy.ndarray
        (n_d,) axial depths, m.
    stable : numpy.ndarray
        (n_d, n_s) bool verdict of the simulation.
    metric, growth_per_rev : numpy.ndarray
        (n_d, n_s) Honeycutt & Schmitz metric (dimensionless) and growth rate (1/rev).
    sle_m : numpy.ndarray
        (n_d, n_s) surface location error, m (> 0 undercut).
    surface_pv_m : numpy.ndarray
        (n_d, n_s) peak-to-valley of the simulated wall, m.
    chatter_hz : numpy.ndarray
        (n_d, n_s) chatter frequency, Hz (nan where stable).
    params : dict
        Conditions and settings.
    """

    rpm: np.ndarray
    depth_m: np.ndarray
    stable: np.ndarray
    metric: np.ndarray
    growth_per_rev: np.ndarray
    sle_m: np.ndarray
    surface_pv_m: np.ndarray
    chatter_hz: np.ndarray
    params: dict = field(default_factory=dict, compare=False)

    @property
    def limit_m(self) -> np.ndarray:
        """(n_s,) the largest depth of the grid below which every depth is stable, m (0 if the first is not)."""
        ok = np.cumprod(self.stable, axis=0).astype(bool)
        idx = ok.sum(axis=0)
        return np.where(idx > 0, self.depth_m[np.maximum(idx - 1, 0)], 0.0)


def _grouped(modes_x, modes_y, cutting, rpm, depth, kw, keys):
    """Run the points grouped by the steps per tooth their speeds need; returns the ``keys`` fields (P,)."""
    dyn = as_modal_dynamics(modes_x, modes_y)
    cut = check_cutting(cutting)
    S = steps_per_tooth_needed(dyn.max_frequency_hz, rpm, cut.teeth, kw.get("steps_per_tooth"),
                               kw.get("substeps"))
    out = {k: np.empty(rpm.size, dtype=bool if k == "stable" else float) for k in keys}
    for s in np.unique(S):
        idx = np.flatnonzero(S == s)
        sub = dict(kw)
        sub["steps_per_tooth"], sub["substeps"] = int(s), 1
        res = simulate_milling(dyn.model, None, cut, rpm=rpm[idx], depth_m=depth[idx], **sub)
        for k in keys:
            out[k][idx] = getattr(res, k)
    return out


def simulate_map(modes_x, modes_y=None, cutting=None, *, rpm, depth_m, feed_m: float = 1e-4, tool=None,
                 revolutions: int = 40, record_revolutions: int = 4, **kw) -> SimulationMap:
    """Stability, SLE and chatter frequency at every (speed, depth) of a grid, simulated in one batch.

    Parameters
    ----------
    modes_x, modes_y, cutting, feed_m, tool, revolutions
        As in :func:`~toolpoint.simulation.time_domain.simulate_milling`.
    rpm : array_like
        (n_s,) spindle speeds, rpm.
    depth_m : array_like
        (n_d,) axial depths, m.
    record_revolutions : int
        Last revolutions kept for SLE and chatter frequency (≥ 2).
    **kw
        Further options of ``simulate_milling`` (``steps_per_tooth``, ``substeps``, ``start``, ``seed``, …).

    Returns
    -------
    SimulationMap
    """
    r = np.asarray(rpm, float).reshape(-1)
    a = np.asarray(depth_m, float).reshape(-1)
    if r.size < 1 or a.size < 1:
        raise InputError("need at least one speed and one depth", field="rpm/depth_m")
    R, A = np.meshgrid(r, a)
    keys = ("stable", "metric", "growth_per_rev", "sle_m", "surface_pv_m", "chatter_hz")
    kw.update(feed_m=feed_m, tool=tool, revolutions=revolutions, record_revolutions=record_revolutions)
    out = _grouped(modes_x, modes_y, cutting, R.reshape(-1), A.reshape(-1), kw, keys)
    shaped = {k: v.reshape(A.shape) for k, v in out.items()}
    return SimulationMap(rpm=r, depth_m=a, params=dict(cutting=cutting, feed_m=feed_m, revolutions=revolutions),
                         **shaped)


def stability_boundary(modes_x, modes_y=None, cutting=None, *, rpm, depth_lo, depth_hi, rtol: float = 2e-3,
                       revolutions: int = 60, **kw) -> np.ndarray:
    """Stability limit per speed by bisection (in log depth) on the simulation's verdict, all speeds at once.

    Parameters
    ----------
    modes_x, modes_y, cutting
        As in :func:`~toolpoint.simulation.time_domain.simulate_milling`.
    rpm : array_like
        (n,) spindle speeds, rpm.
    depth_lo, depth_hi : float or array_like
        Bracket, m: stable at ``depth_lo`` and chattering at ``depth_hi`` (checked; nan where not).
    rtol : float
        Relative width of the final bracket.
    revolutions : int
        Revolutions per simulation (long enough for a slow growth to show).
    **kw
        Further options of ``simulate_milling``.

    Returns
    -------
    numpy.ndarray
        (n,) depth limit (geometric middle of the final bracket), m; nan where the bracket did not hold.
    """
    r = np.asarray(rpm, float).reshape(-1)
    lo = np.broadcast_to(np.asarray(depth_lo, float), r.shape).copy()
    hi = np.broadcast_to(np.asarray(depth_hi, float), r.shape).copy()
    if np.any(~(lo > 0) | ~(hi > lo)):
        raise InputError("need 0 < depth_lo < depth_hi", field="depth_lo/depth_hi")
    kw["revolutions"] = revolutions
    kw.setdefault("record_revolutions", 2)

    def stable(rr, aa):
        return _grouped(modes_x, modes_y, cutting, rr, aa, kw, ("stable",))["stable"]

    ends = stable(np.r_[r, r], np.r_[lo, hi])
    ok = ends[: r.size] & ~ends[r.size:]
    while True:
        open_ = ok & (hi / lo > 1 + rtol)
        if not open_.any():
            break
        mid = np.sqrt(lo[open_] * hi[open_])
        st = stable(r[open_], mid)
        idx = np.flatnonzero(open_)
        lo[idx[st]] = mid[st]
        hi[idx[~st]] = mid[~st]
    return np.where(ok, np.sqrt(lo * hi), np.nan)
