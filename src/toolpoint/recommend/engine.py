r"""One tool: sampled joints → tool-point FRFs → stability limits → recommended operating points.

For tool i the joint is sampled ``n_samples`` times from its predictive
distribution (:mod:`.uncertainty`), the tool-point receptance of every sample
is computed at once (:meth:`~toolpoint.dynamics.model.ToolPointModel.tool_point`
on an (n, 4) array) and the zero-order limit of every sample on the speed grid
(:func:`.zoa_batch.zoa_limits`). From the n limits a_s(Ω):

* the 5 / 50 / 95 % limits per speed (``numpy.quantile``);
* the probability of stability P(a, Ω) = #{s : a_s(Ω) > a} / n on a depth grid;
* the recommended points: the pockets (local maxima strictly inside the speed
  range) of the *robust* 5 % limit r(Ω) = min of the 5 % limit over
  [Ω(1 − tol), Ω(1 + tol)] (a spindle does not hold its speed exactly), best
  first; the recommended depth is r(Ω)(1 − margin). Where r has no pocket the
  best speed in the range is given (kind ``edge``).

Depths above ``CAP_FACTOR`` × the absolute minimum of the median-joint limit
are not resolved (the limit is then "at least that").
"""

from __future__ import annotations

import time
from dataclasses import dataclass, replace

import numpy as np

from ..blas import single_thread_blas
from ..campaign.config import ToolFamily
from ..dynamics.model import ToolPointModel
from ..dynamics.subassembly import Subassembly
from ..identification.params import PARAMS
from ..stability.cutting import CuttingConditions
from ..stability.milling import average_directional_matrix
from ..stability.zoa_batch import zoa_limits

__all__ = ["CAP_FACTOR", "QUANTILES", "ToolJob", "evaluate_tool", "pockets", "robust_min"]

#: Limits are resolved up to this multiple of the absolute minimum depth of the median joint's lobes.
CAP_FACTOR = 20.0
#: Quantiles of the limit and of the joint that are reported.
QUANTILES = (0.05, 0.5, 0.95)
#: Depth grid points of the probability-of-stability map.
N_DEPTHS = 100


@dataclass(frozen=True)
class ToolJob:
    """Everything one tool's evaluation needs (picklable, no file access).

    Attributes
    ----------
    id : str
        Tool id.
    family : ToolFamily
        The campaign's tool family (material, flute ratios).
    diameter_mm, overhang_mm : float
        D and L, mm.
    flute_length_mm : float or None
        Flute length, mm (None: the family's rule).
    freq_hz : ndarray
        Frequencies of the subassembly, Hz.
    sub_R : ndarray, shape (F, 2, 2)
        Spindle–holder receptances, SI.
    holder : str
        Holder name.
    cutting : CuttingConditions
        The cut.
    rpm : ndarray
        Speed grid, rpm.
    log10_median, sigma_log10 : ndarray, shape (4,)
        Joint distribution (log10 SI, decades).
    n_samples : int
        Joint samples.
    seed : int
        Seed of the samples.
    margin : float
        Recommended depth = robust 5 % limit × (1 − margin).
    rpm_tolerance : float
        Relative speed tolerance of the robust limit.
    """

    id: str
    family: ToolFamily
    diameter_mm: float
    overhang_mm: float
    flute_length_mm: float | None
    freq_hz: np.ndarray
    sub_R: np.ndarray
    holder: str
    cutting: CuttingConditions
    rpm: np.ndarray
    log10_median: np.ndarray
    sigma_log10: np.ndarray
    n_samples: int = 200
    seed: int = 0
    margin: float = 0.1
    rpm_tolerance: float = 0.01


def robust_min(rpm: np.ndarray, depth: np.ndarray, tolerance: float) -> np.ndarray:
    """Minimum of ``depth`` over speeds within ±``tolerance`` (relative) of each grid speed.

    Parameters
    ----------
    rpm : ndarray, shape (G,)
        Increasing speeds, rpm.
    depth : ndarray, shape (G,)
        Depth per speed (any unit).
    tolerance : float
        Relative half-width of the window (0.01 = ±1 %).

    Returns
    -------
    ndarray, shape (G,)

    Examples
    --------
    >>> robust_min(np.array([100., 101., 102., 110.]), np.array([3., 1., 2., 5.]), 0.015).tolist()
    [1.0, 1.0, 1.0, 5.0]
    """
    lo = np.searchsorted(rpm, rpm * (1 - tolerance), "left")
    hi = np.searchsorted(rpm, rpm * (1 + tolerance), "right")
    w = int(np.max(hi - lo))
    idx = lo[:, None] + np.arange(w)[None, :]
    inside = idx < hi[:, None]
    vals = np.where(inside, depth[np.minimum(idx, depth.size - 1)], np.inf)
    return vals.min(axis=1)


def pockets(depth: np.ndarray) -> np.ndarray:
    """Indices of the pockets of a limit curve, deepest first.

    A pocket is a run of equal finite values whose neighbours on both sides are
    lower, strictly inside the range (as :meth:`~toolpoint.stability.milling.LobeResult.pocket`);
    its index is the run's middle.

    Parameters
    ----------
    depth : ndarray, shape (G,)

    Returns
    -------
    ndarray of int

    Examples
    --------
    >>> pockets(np.array([1., 3., 2., 5., 5., 1., 9.])).tolist()
    [3, 1]
    """
    d = np.asarray(depth, float)
    if d.size < 3:
        return np.zeros(0, int)
    start = np.r_[0, np.flatnonzero(d[1:] != d[:-1]) + 1]
    stop = np.r_[start[1:], d.size]
    inner = (start > 0) & (stop < d.size)
    start, stop = start[inner], stop[inner]
    val = d[start]
    peak = np.isfinite(val) & (d[start - 1] < val) & (d[stop] < val)
    mid = ((start + stop - 1) // 2)[peak]
    return mid[np.argsort(-d[mid], kind="stable")]


def evaluate_tool(job: ToolJob) -> dict:
    """Evaluate one tool (in a worker).

    Returns
    -------
    dict
        ``summary`` (JSON-able: joint quantiles SI, points, notes, ``seconds`` wall and ``cpu_seconds``
        of this process) and
        ``arrays`` (name → ndarray: FRF band, limits in mm, probability map).
    """
    t0, c0 = time.perf_counter(), time.process_time()
    family = job.family
    if job.flute_length_mm is not None:
        family = replace(family, flute_length_ratio=job.flute_length_mm / job.diameter_mm)
    rng = np.random.default_rng(job.seed)
    z = rng.standard_normal((job.n_samples, len(PARAMS)))
    median = 10.0 ** job.log10_median
    joints = np.vstack([median, 10.0 ** (job.log10_median + z * job.sigma_log10)])
    with single_thread_blas():
        sub = Subassembly(job.freq_hz, job.sub_R, job.holder)
        model = ToolPointModel(family.tool(job.diameter_mm, job.overhang_mm), sub, job.freq_hz)
        H = model.tool_point(joints)  # (1 + n, F), m/N
    cut = job.cutting
    h0 = average_directional_matrix(cut.teeth, cut.tangential_coeff, cut.radial_ratio, *cut.immersion_angles)
    q = -2.0 * (np.linalg.eigvals(h0)[:, None] * H[0][None, :]).real
    cap = CAP_FACTOR / q.max() if q.max() > 0 else np.inf
    limits = zoa_limits(job.freq_hz, H, cut, job.rpm, cap_m=cap)  # (1 + n, G), m
    nominal, samples = limits[0], limits[1:]
    lq = np.quantile(samples, QUANTILES, axis=0)  # (3, G), m
    robust = robust_min(job.rpm, lq[0], job.rpm_tolerance)
    finite = samples[np.isfinite(samples)]
    top = min(1.2 * float(np.max(lq[2][np.isfinite(lq[2])], initial=0.0)), cap) if finite.size else 1e-3
    top = top if top > 0 else 1e-3
    depths = np.linspace(0.0, top, N_DEPTHS + 1)[1:]
    p_stable = (samples[None, :, :] > depths[:, None, None]).mean(axis=1)  # (D, G)
    idx = pockets(robust)
    points = []
    for j in idx[:3]:
        points.append(_point(job, j, "pocket", nominal, lq, robust, samples, cap))
    if not points:
        j = int(np.argmax(np.where(np.isfinite(robust), robust, -np.inf)))
        points.append(_point(job, j, "edge", nominal, lq, robust, samples, cap))
    jq = 10.0 ** (job.log10_median[None, :] + np.array([-1.6448536269514729, 0.0, 1.6448536269514729])[:, None]
                  * job.sigma_log10[None, :])
    hq = np.quantile(np.abs(H[1:]), QUANTILES, axis=0)
    summary = {
        "id": job.id,
        "joint": {p: {"p05": jq[0, k], "p50": jq[1, k], "p95": jq[2, k], "sigma_log10": job.sigma_log10[k]}
                  for k, p in enumerate(PARAMS)},
        "points": points,
        "min_limit_mm": {"p05": 1e3 * float(np.min(lq[0])), "p50": 1e3 * float(np.min(lq[1])),
                         "nominal": 1e3 * float(np.min(nominal))},
        "cap_mm": 1e3 * float(cap),
        "n_samples": int(job.n_samples),
        "seed": int(job.seed),
        "margin": job.margin,
        "rpm_tolerance": job.rpm_tolerance,
        "seconds": time.perf_counter() - t0,
        "cpu_seconds": time.process_time() - c0,
    }
    arrays = {
        "freq_hz": job.freq_hz, "frf_nominal": H[0], "frf_abs_q": hq,
        "rpm": job.rpm, "limit_nominal_mm": 1e3 * nominal, "limit_q_mm": 1e3 * lq, "limit_robust_mm": 1e3 * robust,
        "depth_mm": 1e3 * depths, "p_stable": np.round(100 * p_stable).astype(np.uint8),
        "joint_q": jq, "quantiles": np.array(QUANTILES),
    }
    return {"summary": summary, "arrays": arrays}


def _point(job, j, kind, nominal, lq, robust, samples, cap) -> dict:
    depth = robust[j] * (1.0 - job.margin)
    limits = {"limit_nominal_mm": nominal[j], "limit_p50_mm": lq[1, j], "limit_p05_mm": lq[0, j],
              "limit_robust_p05_mm": robust[j]}
    return {
        "kind": kind, "rpm": float(job.rpm[j]), **{k: 1e3 * float(v) for k, v in limits.items()},
        "depth_mm": 1e3 * float(depth), "p_stable": float(np.mean(samples[:, j] > depth)),
        # a limit at the depth cap was not computed: it lies somewhere above the cap (shown as "≥ cap")
        "capped": sorted(k for k, v in limits.items() if np.isfinite(cap) and v >= cap * (1 - 1e-9)),
    }
