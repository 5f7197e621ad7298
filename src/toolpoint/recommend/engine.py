r"""One tool: sampled joints and cutting coefficients → tool-point FRFs → stability limits → operating points.

For tool i, ``n_samples`` draws of every uncertain input are propagated together:

* the holder–tool joint from its predictive distribution (:mod:`.uncertainty`: calibrated out of sample by
  ``campaign learn``), clipped to the identification's range;
* the spindle–holder subassembly, as bootstrap replicates of its inverse RCSA
  (:func:`~toolpoint.dynamics.inverse_rcsa.subassembly_replicates`) when it was measured with a blank;
* the cutting coefficients, log-normal around the library's or the preset's values (:mod:`.materials`):
  each sample's own K_t and K_r set its directional eigenvalues in the zero-order limit
  (:func:`~toolpoint.stability.zoa_batch.directional_eigenvalues`).

The tool-point receptance of every joint sample is computed at once
(:meth:`~toolpoint.dynamics.model.ToolPointModel.tool_point` on an (n, 4) array) and the zero-order limit of
every sample on the speed grid (:func:`~toolpoint.stability.zoa_batch.zoa_limits`). From the n limits
a_s(Ω):

* the 5 / 50 / 95 % limits per speed (``numpy.quantile``);
* the probability of stability P(a, Ω) = #{s : a_s(Ω) > a} / n on a depth grid;
* the **robust** limit of each sample, R_s(Ω) = min of a_s over [Ω(1 − tol), Ω(1 + tol)] (a spindle does not
  hold its speed exactly, and a pocket is narrowest at its top), and its 5 % quantile r(Ω);
* the recommended points: the pockets (local maxima strictly inside the speed range) of r, best first, at
  depth r(Ω)(1 − margin), with P(stable) = #{s : R_s(Ω) > depth}/n — stable with that probability for any
  speed within the tolerance. Where no pocket gives :data:`POCKET_GAIN` × more than the depth stable at
  every speed (the 5 % quantile of min_Ω a_s — uncertainty too large for a meaningful pocket), the
  recommendation is that depth (kind ``minimum``), and says so. Without a pocket the best speed of the range
  (kind ``edge``).

Which source dominates the spread of ln a at the recommended speed is estimated from the samples: K_t exactly
(its variance σ_ln²), K_r and the subassembly as the variance between their groups, the joint as the rest.

Depths above ``CAP_FACTOR`` × the absolute minimum of the median-joint limit are not resolved (the limit is
then "at least that").
"""

from __future__ import annotations

import time
from dataclasses import dataclass, replace

import numpy as np

from ..blas import single_thread_blas
from ..campaign.config import ToolFamily
from ..campaign.distribution import truncated_log10
from ..dynamics.model import ToolPointModel
from ..dynamics.subassembly import Subassembly
from ..identification.params import PARAMS
from ..stability.cutting import CuttingConditions
from ..stability.milling import average_directional_matrix
from ..stability.zoa_batch import directional_eigenvalues, zoa_limits

__all__ = ["CAP_FACTOR", "QUANTILES", "KR_BINS", "POCKET_GAIN", "ToolJob", "ToolEvaluation", "evaluate_tool",
           "pockets", "robust_min"]

#: Limits are resolved up to this multiple of the absolute minimum depth of the median joint's lobes.
CAP_FACTOR = 20.0
#: Quantiles of the limit and of the joint that are reported.
QUANTILES = (0.05, 0.5, 0.95)
#: Depth grid points of the probability-of-stability map.
N_DEPTHS = 100
#: Quantile bins of the sampled K_r for its first-order share of the variance (the limits use each sample's K_r).
KR_BINS = 4
#: Parts per refined FRF interval in the batched limits (zoa_batch.zoa_limits).
SUBDIVIDE = 2
#: A pocket is recommended only where its robust 5 % limit exceeds the everywhere-stable depth by this factor.
POCKET_GAIN = 1.25


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
    clip_log10 : ndarray, shape (2, 4), optional
        The identification's range of each joint parameter, log10 SI (samples are clipped to it).
    cutting_sigma_ln : (float, float)
        One standard deviation of ln K_t and ln K_r.
    sub_R_replicates : ndarray, shape (B, F, 2, 2), optional
        Bootstrap replicates of the subassembly (its own measurement uncertainty); sample i uses replicate
        i mod B after a seeded shuffle (None: the subassembly is taken as exact).
    window_log10 : ndarray, shape (2, 4), optional
        One-sided bounds of the joint parameters from the nearby tools' FRFs, log10 SI (±inf: none): the
        log-normal is truncated there (:func:`~toolpoint.campaign.distribution.truncated_log10`).
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
    clip_log10: np.ndarray | None = None
    cutting_sigma_ln: tuple = (0.0, 0.0)
    sub_R_replicates: np.ndarray | None = None
    window_log10: np.ndarray | None = None


@dataclass(frozen=True)
class ToolEvaluation:
    """What :func:`evaluate_tool` returns.

    Attributes
    ----------
    summary : dict
        JSON-able: ``id``, ``joint`` quantiles (SI), ``points`` (recommended, best first: ``kind``, ``rpm``,
        limits mm, ``depth_mm``, ``p_stable``, ``capped``, ``flute_limited``: the depth is the modelled flute length
        min(L, flute ratio × D), the limit lies deeper), ``min_limit_mm``, ``cap_mm``, ``sources`` (share of
        the variance of ln a at the best point per source), ``dominant_source``, ``notes``, settings and
        ``seconds`` / ``cpu_seconds`` of this process.
    arrays : dict
        Name → ndarray: FRF band, limits in mm (quantiles at each speed, robust 5 %), probability map (%).
    """

    summary: dict
    arrays: dict


def robust_min(rpm: np.ndarray, depth: np.ndarray, tolerance: float) -> np.ndarray:
    """Minimum of ``depth`` over speeds within ±``tolerance`` (relative) of each grid speed.

    Parameters
    ----------
    rpm : ndarray, shape (G,)
        Increasing speeds, rpm.
    depth : ndarray, shape (..., G)
        Depth per speed (any unit); leading axes (e.g. samples) are kept.
    tolerance : float
        Relative half-width of the window (0.01 = ±1 %).

    Returns
    -------
    ndarray, shape (..., G)

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
    depth = np.asarray(depth)
    vals = np.where(inside, depth[..., np.minimum(idx, depth.shape[-1] - 1)], np.inf)
    return vals.min(axis=-1)


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


def _samples(job: ToolJob, rng: np.random.Generator):
    """(1 + n, 4) joints (row 0 the median), K_t factors (n,), K_r values (n,)."""
    z = rng.standard_normal((job.n_samples, len(PARAMS)))
    logj = truncated_log10(job.log10_median, job.sigma_log10, job.window_log10, np.vstack([np.zeros(len(PARAMS)), z]))
    if job.clip_log10 is not None:
        logj = np.clip(logj, job.clip_log10[0], job.clip_log10[1])
    joints = 10.0 ** logj  # row 0: the median of what is sampled
    s_kt, s_kr = job.cutting_sigma_ln
    zc = rng.standard_normal((2, job.n_samples))
    return joints, np.exp(s_kt * zc[0]), job.cutting.radial_ratio * np.exp(s_kr * zc[1])


def _limits(job: ToolJob, H: np.ndarray, kt_factor: np.ndarray, kr: np.ndarray, cap: float):
    """Limits (m) of the median (G,) and of every sample with its own K_t, K_r (n, G), and each sample's K_r
    quartile (for the variance shares)."""
    cut = job.cutting
    # each sample its own cutting coefficients, exactly; row 0 the median joint with the nominal ones; one call
    lam = np.vstack([directional_eigenvalues(cut), directional_eigenvalues(cut, kt_factor, kr)])
    limits = zoa_limits(job.freq_hz, H, cut, job.rpm, cap_m=cap, directional=lam, subdivide=SUBDIVIDE)
    nominal, samples = limits[0], limits[1:]
    n = len(kr)
    bins = min(KR_BINS, n) if job.cutting_sigma_ln[1] > 0 else 1
    bin_of = np.empty(n, int)
    for b, idx in enumerate(np.array_split(np.argsort(kr, kind="stable"), bins)):
        bin_of[idx] = b
    return nominal, samples, bin_of


def _between(ln: np.ndarray, group: np.ndarray) -> float:
    """Variance of the group means of ``ln`` (weighted by group size): a first-order variance share."""
    keys = np.unique(group)
    if keys.size < 2:
        return 0.0
    means = np.array([ln[group == k].mean() for k in keys])
    counts = np.array([(group == k).sum() for k in keys])
    return float(np.sum(counts * (means - ln.mean()) ** 2) / counts.sum())


def _sources(samples_j: np.ndarray, bin_of: np.ndarray, rep_of: np.ndarray, sigma_kt: float) -> dict:
    """Share of the variance of ln a at one speed per source (K_t exact; K_r and the subassembly between their
    groups; the joint the rest)."""
    ok = np.isfinite(samples_j) & (samples_j > 0)
    if ok.sum() < 3:
        return {}
    ln = np.log(samples_j[ok])
    total = float(np.var(ln))
    if total <= 0:
        return {}
    kt = min(sigma_kt**2, total)
    kr = min(_between(ln, bin_of[ok]), total - kt)
    sub = min(_between(ln, rep_of[ok]), total - kt - kr)
    return {"joint": (total - kt - kr - sub) / total, "cutting K_t": kt / total, "cutting K_r": kr / total,
            "subassembly": sub / total}


def evaluate_tool(job: ToolJob) -> ToolEvaluation:
    """Evaluate one tool (in a worker): the module docstring's steps.

    Parameters
    ----------
    job : ToolJob

    Returns
    -------
    ToolEvaluation
    """
    t0, c0 = time.perf_counter(), time.process_time()
    family = job.family
    if job.flute_length_mm is not None:
        family = replace(family, flute_length_ratio=job.flute_length_mm / job.diameter_mm)
    rng = np.random.default_rng(job.seed)
    joints, kt_factor, kr = _samples(job, rng)
    reps = job.sub_R_replicates
    rep_of = (rng.permutation(job.n_samples) % len(reps)) if reps is not None and len(reps) else \
        np.zeros(job.n_samples, int)
    tool = family.tool(job.diameter_mm, job.overhang_mm)
    with single_thread_blas():
        H = ToolPointModel(tool, Subassembly(job.freq_hz, job.sub_R, job.holder), job.freq_hz).tool_point(joints)
        if reps is not None and len(reps):  # each sample through its own replicate of the subassembly
            for b in range(len(reps)):
                idx = np.flatnonzero(rep_of == b)
                model = ToolPointModel(tool, Subassembly(job.freq_hz, reps[b], job.holder), job.freq_hz)
                H[1 + idx] = model.tool_point(joints[1 + idx])  # (1 + n, F), m/N
    cut = job.cutting
    h0 = average_directional_matrix(cut.teeth, cut.tangential_coeff, cut.radial_ratio, *cut.immersion_angles)
    q = -2.0 * (np.linalg.eigvals(h0)[:, None] * H[0][None, :]).real
    cap = CAP_FACTOR / q.max() if q.max() > 0 else np.inf
    nominal, samples, bin_of = _limits(job, H, kt_factor, kr, cap)
    lq = np.quantile(samples, QUANTILES, axis=0)  # (3, G), m
    per_sample_robust = robust_min(job.rpm, samples, job.rpm_tolerance)  # (n, G)
    robust = np.quantile(per_sample_robust, QUANTILES[0], axis=0)
    floor = float(np.quantile(samples.min(axis=1), QUANTILES[0]))  # stable at every speed with 95 %
    finite = samples[np.isfinite(samples)]
    top = min(1.2 * float(np.max(lq[2][np.isfinite(lq[2])], initial=0.0)), cap) if finite.size else 1e-3
    top = top if top > 0 else 1e-3
    depths = np.linspace(0.0, top, N_DEPTHS + 1)[1:]
    p_stable = (samples[None, :, :] > depths[:, None, None]).mean(axis=1)  # (D, G)
    # no depth deeper than the modelled flutes (min(L, flute ratio × D)): the stability limit of a stubby tool
    # can lie far beyond what the tool can cut at all
    flutes_m = 1e-3 * min(job.overhang_mm, family.flute_length_ratio * job.diameter_mm)
    ctx = (job, nominal, lq, robust, per_sample_robust, cap, flutes_m)
    idx = [j for j in pockets(robust) if robust[j] >= POCKET_GAIN * floor]
    notes = []
    points = [_point(*ctx, j, "pocket", robust[j]) for j in idx[:3]]
    if not points and pockets(robust).size:
        j = int(np.argmax(np.where(np.isfinite(robust), robust, -np.inf)))
        points.append(_point(*ctx, j, "minimum", floor))
        notes.append(f"no pocket is {POCKET_GAIN:g}× deeper than the depth stable at every speed with 95 % "
                     f"({1e3 * floor:.3g} mm): the uncertainty is too large for a pocket to be trusted, so the "
                     "recommendation is that depth")
    elif not points:
        j = int(np.argmax(np.where(np.isfinite(robust), robust, -np.inf)))
        points.append(_point(*ctx, j, "edge", robust[j]))
    if points[0]["flute_limited"]:
        notes.append(f"the stability limit lies deeper than the flutes: the depth is the flute length "
                     f"{1e3 * flutes_m:.3g} mm")
    sources = _sources(samples[:, int(np.searchsorted(job.rpm, points[0]["rpm"]))], bin_of, rep_of,
                       job.cutting_sigma_ln[0])
    sampled = {"joint": True, "cutting K_t": job.cutting_sigma_ln[0] > 0, "cutting K_r": job.cutting_sigma_ln[1] > 0,
               "subassembly": reps is not None and len(reps) > 1}
    sources = {k: v for k, v in sources.items() if sampled[k]}  # a source taken as exact is not named
    jq = 10.0 ** truncated_log10(job.log10_median, job.sigma_log10, job.window_log10,
                                 np.array([-1.6448536269514729, 0.0, 1.6448536269514729])[:, None])
    if job.clip_log10 is not None:
        jq = np.clip(jq, 10.0 ** job.clip_log10[0], 10.0 ** job.clip_log10[1])
    hq = np.quantile(np.abs(H[1:]), QUANTILES, axis=0)
    summary = {
        "id": job.id,
        "joint": {p: {"p05": jq[0, k], "p50": jq[1, k], "p95": jq[2, k], "sigma_log10": job.sigma_log10[k]}
                  for k, p in enumerate(PARAMS)},
        "cutting_sigma_ln": {"K_t": job.cutting_sigma_ln[0], "K_r": job.cutting_sigma_ln[1]},
        "subassembly_replicates": 0 if reps is None else int(len(reps)),
        "points": points,
        "min_limit_mm": {"p05": 1e3 * floor, "p50": 1e3 * float(np.min(lq[1])),
                         "nominal": 1e3 * float(np.min(nominal))},
        "sources": sources,
        "dominant_source": max(sources, key=sources.get) if sources else None,
        "cap_mm": 1e3 * float(cap),
        "n_samples": int(job.n_samples),
        "seed": int(job.seed),
        "margin": job.margin,
        "rpm_tolerance": job.rpm_tolerance,
        "engine_notes": notes,
        "seconds": time.perf_counter() - t0,
        "cpu_seconds": time.process_time() - c0,
    }
    arrays = {
        "freq_hz": job.freq_hz, "frf_nominal": H[0], "frf_abs_q": hq,
        "rpm": job.rpm, "limit_nominal_mm": 1e3 * nominal, "limit_q_mm": 1e3 * lq, "limit_robust_mm": 1e3 * robust,
        "depth_mm": 1e3 * depths, "p_stable": np.round(100 * p_stable).astype(np.uint8),
        "joint_q": jq, "quantiles": np.array(QUANTILES),
    }
    return ToolEvaluation(summary, arrays)


def _point(job, nominal, lq, robust, per_sample_robust, cap, flutes_m, j, kind, base) -> dict:
    depth = min(base * (1.0 - job.margin), flutes_m)
    limits = {"limit_nominal_mm": nominal[j], "limit_p50_mm": lq[1, j], "limit_p05_mm": lq[0, j],
              "limit_robust_p05_mm": robust[j]}
    return {
        "kind": kind, "rpm": float(job.rpm[j]), **{k: 1e3 * float(v) for k, v in limits.items()},
        "depth_mm": 1e3 * float(depth),
        # stable for every speed within the tolerance: each sample's limit over the window
        "p_stable": float(np.mean(per_sample_robust[:, j] > depth)),
        # a limit at the depth cap was not computed: it lies somewhere above the cap (shown as "≥ cap")
        "capped": sorted(k for k, v in limits.items() if np.isfinite(cap) and v >= cap * (1 - 1e-9)),
        "flute_limited": bool(base * (1.0 - job.margin) > flutes_m),
    }
