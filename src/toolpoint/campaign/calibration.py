r"""Out-of-sample uncertainty of the learned joint parameters: cross-validation over every tool.

A model's training residuals say nothing about its error on a tool it has not seen (a flexible ANFIS drives
them to zero). So the σ that ``library`` samples the joint with comes from **K-fold cross-validation over all
the campaign's ok rows** (:data:`CV_FOLDS` folds, seeded): each fold's rows are predicted by a model trained on
the other folds, with the same settings as the saved model. From the held-out log10 residuals r_i (rows where
the parameter was identified) the predictive distribution of an unseen tool at inputs x is

.. math::

    \log_{10} p \sim \mathcal N\big(m(x),\ (\sigma\, s(x))^2\big), \qquad
    s(x) = \max\!\Big(1, \frac{d_k(x)}{d_{\rm ref}}\Big)\,(1 + w\,\delta(x)),

with d_k(x) the mean distance of x to its :data:`K_NEAREST` nearest training tools (inputs scaled by the
training range), d_ref the median of the training tools' own d_k (their typical spacing), δ(x) the distance
outside the training box in range widths and w = :data:`WIDEN_PER_RANGE` — wider where the data are sparse or
at and beyond the edge of the learned (D, L) range. σ is the split-conformal quantile (Vovk et al.; Lei et al.
2018) of |r_i|/s_i at the level ⌈(n+1)·0.9⌉/n, divided by z₀.₉₅ = 1.645 (or the RMS of r_i/s_i where larger:
steadier with few rows): the 90 % interval m ± 1.645 σ s(x) then holds the held-out values at least 90 % of the
time whatever the residuals' shape. Its coverage is reported *out of sample* by cross-conformal checking: σ
calibrated on the residuals of K − 1 folds, coverage counted on the K-th.

A parameter the campaign rarely identifies (share of identified ok rows below
:data:`~toolpoint.campaign.learn.IDENTIFIABLE_SHARE`), or whose model predicts worse out of sample than the
family's spread, is **not extrapolated by a model**: its distribution is the campaign's — locally, the median of
the :data:`K_LOCAL` nearest tools that identified it (never outside the values seen) with the σ its held-out
residuals calibrate as above, or, where that predicts no better, the whole campaign's median and standard
deviation of log10 p over the ok rows. Every sample and every median is clipped to the identification's search
bounds, the physically plausible range the campaign used.

**Where the nearby FRFs bound a parameter on one side only**, samples stay on that side. A tool whose 95 %
interval of p runs into the search bound above (the FRF hardly changes however large p is) still bounds it
below: p ≥ lo. When at least :data:`WINDOW_MAJORITY` of the :data:`K_LOCAL` tools nearest a new tool have such an
interval, the median of their lo is a lower bound of the new tool's p: the predictive log-normal is truncated
there (likewise above, from intervals that run into the lower search bound). The side the FRFs leave open stays
open. Measured on the synthetic campaigns: kr, identified only by tools of D ≤ 18 mm, was sampled 0.3–0.6
decades below the truth for the larger tools — where their FRFs say it cannot be; their lower bounds lie below
the truth in 99 % of new tools (``docs/design/recommend.md``).

Measured effect and calibration: ``docs/design/recommend.md`` and ``benchmarks/bench_calibration.py``.
"""

from __future__ import annotations

import json
import math
from dataclasses import asdict, dataclass
from pathlib import Path

import numpy as np

from ..errors import InputError
from ..io.atomic import atomic_open
from ..io.table import check_regular_file

__all__ = ["CV_FOLDS", "K_NEAREST", "WIDEN_PER_RANGE", "COVERAGE", "FILE_NAME", "WINDOW_MAJORITY",
           "ParameterUncertainty", "fit_uncertainty", "fit_power_law", "power_law", "spread_uncertainty",
           "local_median", "one_sided_bounds", "write_uncertainty", "read_uncertainty", "fold_ids"]

#: Folds of the cross-validation.
CV_FOLDS = 5
#: Nearest training tools behind the sparsity distance d_k.
K_NEAREST = 3
#: Identified tools whose median is a rarely identified parameter's local campaign value.
K_LOCAL = 5
#: Of the K_LOCAL nearest tools, at least this many must bound a parameter on one side for the bound to hold.
WINDOW_MAJORITY = 3
#: s(x) grows by this much per range width outside the training (D, L) box.
WIDEN_PER_RANGE = 5.0
#: The interval the σ is calibrated for (two-sided).
COVERAGE = 0.90
#: File in the models folder.
FILE_NAME = "uncertainty.json"
FORMAT = "toolpoint.joint-uncertainty"
_Z = 1.6448536269514729  # standard normal quantile of 0.95: m ± _Z σ is the 90 % interval
_SIGMA_FLOOR = 1e-3  # decades (0.23 %): below this the identification itself is the limit


def fold_ids(n: int, folds: int, seed: int) -> np.ndarray:
    """Seeded assignment of n rows to ``folds`` folds of (nearly) equal size.

    Examples
    --------
    >>> np.bincount(fold_ids(11, 5, 0)).tolist()
    [3, 2, 2, 2, 2]
    """
    perm = np.random.default_rng(seed).permutation(n)
    out = np.empty(n, int)
    out[perm] = np.arange(n) % folds
    return out


def _scaled(X, lo, hi):
    return (np.asarray(X, float) - lo) / np.maximum(hi - lo, 1e-12)


def sparsity(X, X_train, lo, hi, k: int = K_NEAREST) -> np.ndarray:
    """d_k: mean distance of each row of X to its k nearest rows of X_train, inputs scaled by [lo, hi]."""
    a, b = _scaled(X, lo, hi), _scaled(X_train, lo, hi)
    d = np.sqrt(((a[:, None, :] - b[None, :, :]) ** 2).sum(-1))
    k = max(1, min(k, b.shape[0]))
    return np.sort(d, axis=1)[:, :k].mean(axis=1)


def typical_spacing(X_train, lo, hi, k: int = K_NEAREST) -> float:
    """Median over the training rows of their own d_k to the other rows: the spacing d_k is measured against.

    A held-out row in cross-validation sees a set with 1/K fewer rows than a new tool sees at prediction time;
    dividing each d_k by its own set's spacing makes the two comparable."""
    b = _scaled(X_train, lo, hi)
    if len(b) < 2:
        return 1.0
    d = np.sqrt(((b[:, None, :] - b[None, :, :]) ** 2).sum(-1))
    k = max(1, min(k, len(b) - 1))
    return float(np.median(np.sort(d, axis=1)[:, 1:k + 1].mean(axis=1)))


def outside(X, lo, hi) -> np.ndarray:
    """δ: largest distance of each row outside the box [lo, hi], in range widths (0 inside)."""
    x = np.atleast_2d(np.asarray(X, float))
    width = np.maximum(hi - lo, 1e-12)
    return np.max(np.maximum(np.maximum(lo - x, x - hi), 0.0) / width, axis=1)


def _conformal(ratio: np.ndarray, level: float = COVERAGE) -> float:
    """Split-conformal quantile of |r|/s at ⌈(n+1) level⌉/n (inf when n is too small for the level)."""
    r = np.sort(np.abs(ratio[np.isfinite(ratio)]))
    n = r.size
    k = math.ceil((n + 1) * level)
    return float(r[k - 1]) if 0 < k <= n else math.inf


@dataclass(frozen=True)
class ParameterUncertainty:
    """Predictive distribution of one joint parameter for unseen tools (module docstring).

    Attributes
    ----------
    param : str
        kt, ct, kr or cr.
    kind : {"model", "powerlaw", "neighbours", "spread"}
        The learned model (ANFIS) or the family's power law log10 p = c₀ + c₁ log10 D + c₂ log10 L, each with the
        cross-validated σ; for a rarely identified parameter the local campaign value (median of the nearest
        identified tools, cross-validated σ) or the campaign's spread.
    sigma_log10 : float
        σ, decades (for ``model`` multiplied by s(x)).
    centre_log10 : float
        ``spread``: the campaign's median of log10 p (``model``: NaN, the model gives m(x)).
    clip_log10 : (float, float)
        The physically plausible range, log10 SI (the paper's search bounds widened to every value the campaign
        found; ``library`` narrows it to the campaign's own bounds): medians and samples are clipped to it.
    X_train : list of [D mm, L mm]
        Training inputs of the saved model (for d_k).
    lo, hi : list of float
        Training range of (D, L), mm.
    d_ref : float
        Typical spacing of the training rows (:func:`typical_spacing`).
    cv : dict
        ``n`` held-out rows, ``coverage90`` (cross-conformal, out of sample), ``rms_log10`` of the residuals,
        ``spread_rms_log10`` (of the family's spread as a predictor), ``folds``.
    reason : str
        One line: how the distribution is made.
    coef : list of float
        ``powerlaw``: [c₀, c₁, c₂] (D, L in mm); else empty.
    y_log10 : list of float
        ``neighbours``: log10 p of the identified tools ``X_train`` (m(x) the median of the :data:`K_LOCAL`
        nearest); else empty.
    window_X : list of [D mm, L mm]
        Every ok tool of the campaign (for the one-sided bounds); empty: no bounds.
    window_lo, window_hi : list of float or None
        Per tool of ``window_X``: log10 of the lower end of its 95 % interval where the interval runs into the
        upper search bound (a lower bound only), and of the upper end where it runs into the lower one; None
        (NaN) otherwise.
    """

    param: str
    kind: str
    sigma_log10: float
    centre_log10: float
    clip_log10: tuple
    X_train: list
    lo: list
    hi: list
    d_ref: float
    cv: dict
    reason: str
    coef: tuple = ()
    y_log10: tuple = ()
    window_X: tuple = ()
    window_lo: tuple = ()
    window_hi: tuple = ()

    def centre(self, X) -> np.ndarray | None:
        """m(x) in log10 SI for ``spread`` and ``powerlaw`` (clipped to the bounds); None for ``model``."""
        X = np.atleast_2d(np.asarray(X, float))
        if self.kind == "spread":
            m = np.full(len(X), self.centre_log10)
        elif self.kind == "powerlaw":
            m = power_law(self.coef, X)
        elif self.kind == "neighbours":
            m = local_median(X, np.asarray(self.X_train), np.asarray(self.y_log10), np.asarray(self.lo),
                             np.asarray(self.hi))
        else:
            return None
        return np.clip(m, *self.clip_log10)

    def scale(self, X) -> np.ndarray:
        """s(x) per row of X (D, L mm); 1 for ``spread``."""
        X = np.atleast_2d(np.asarray(X, float))
        if self.kind == "spread":
            return np.ones(len(X))
        lo, hi = np.asarray(self.lo), np.asarray(self.hi)
        d = sparsity(X, np.asarray(self.X_train), lo, hi)
        return np.maximum(1.0, d / max(self.d_ref, 1e-12)) * (1.0 + WIDEN_PER_RANGE * outside(X, lo, hi))

    def window(self, X) -> tuple[np.ndarray, np.ndarray]:
        """(lower, upper) bound of log10 p per row of X (D, L mm) from the nearby tools' one-sided intervals
        (module docstring); −inf / +inf where fewer than :data:`WINDOW_MAJORITY` of the :data:`K_LOCAL` nearest
        bound that side."""
        X = np.atleast_2d(np.asarray(X, float))
        lo, hi = np.full(len(X), -np.inf), np.full(len(X), np.inf)
        if not len(self.window_X):
            return lo, hi
        W = np.asarray(self.window_X, float)
        a, b = _scaled(X, W.min(axis=0), W.max(axis=0)), _scaled(W, W.min(axis=0), W.max(axis=0))
        idx = np.argsort(((a[:, None, :] - b[None, :, :]) ** 2).sum(-1), axis=1)[:, :min(K_LOCAL, len(W))]
        for bounds, out in ((self.window_lo, lo), (self.window_hi, hi)):
            v = np.asarray(bounds, float)[idx]  # (n, K)
            ok = np.isfinite(v).sum(axis=1) >= WINDOW_MAJORITY
            if ok.any():
                out[ok] = np.nanmedian(v[ok], axis=1)
        return lo, hi

    def sigma(self, X) -> np.ndarray:
        """σ s(x) per row of X, decades; for ``neighbours`` at most the campaign's spread (its median never
        leaves the values seen, so far from the tools that identified it, it is the campaign's value)."""
        out = self.sigma_log10 * self.scale(X)
        if self.kind == "neighbours":
            out = np.minimum(out, max(self.cv.get("spread_rms_log10", np.inf), self.sigma_log10))
        return out


def fit_power_law(X, log10_y) -> np.ndarray:
    """[c₀, c₁, c₂] of log10 p = c₀ + c₁ log10 D + c₂ log10 L by least squares (D, L mm).

    Examples
    --------
    >>> X = np.array([[10., 40.], [20., 40.], [10., 80.], [16., 50.]])
    >>> np.round(fit_power_law(X, np.log10(3.0 * X[:, 0] ** 1.5 * X[:, 1] ** -0.2)), 6).tolist()
    [0.477121, 1.5, -0.2]
    """
    A = np.column_stack([np.ones(len(X)), np.log10(np.asarray(X, float))])
    return np.linalg.lstsq(A, np.asarray(log10_y, float), rcond=None)[0]


def power_law(coef, X) -> np.ndarray:
    """log10 p of the power law ``coef`` at X (D, L mm)."""
    X = np.atleast_2d(np.asarray(X, float))
    return coef[0] + np.log10(X) @ np.asarray(coef[1:], float)


def local_median(X, X_known, y_known, lo, hi, k: int | None = None) -> np.ndarray:
    """Median of y over the k nearest known rows of each row of X (inputs scaled by [lo, hi]).

    Never outside the range of the known values: a local campaign spread, not a model that extrapolates.
    """
    k = K_LOCAL if k is None else k
    a, b = _scaled(X, lo, hi), _scaled(X_known, lo, hi)
    d = np.sqrt(((a[:, None, :] - b[None, :, :]) ** 2).sum(-1))
    idx = np.argsort(d, axis=1)[:, :max(1, min(k, len(b)))]
    return np.median(np.asarray(y_known, float)[idx], axis=1)


def one_sided_bounds(lo, hi, rel: float = 1e-6) -> tuple[np.ndarray, np.ndarray]:
    """Per tool, log10 of the side its 95 % interval bounds when the other side runs into the search bound.

    Parameters
    ----------
    lo, hi : ndarray
        The intervals (SI, > 0; NaN where none).
    rel : float
        An end within this many decades of the campaign's extreme end is "at the bound" (the search bound is the
        extreme end that intervals reach; a lone extreme that is not a bound is outvoted by its neighbours).

    Returns
    -------
    (lower, upper) : ndarrays
        log10 lo where only the upper end is at the bound, else NaN; log10 hi where only the lower end is.

    Examples
    --------
    >>> lo, hi = np.array([1.0, 2.0, 1.0, 3.0]), np.array([10.0, 100.0, 100.0, 4.0])
    >>> [np.round(v, 3).tolist() for v in one_sided_bounds(lo, hi)]
    [[nan, 0.301, nan, nan], [1.0, nan, nan, nan]]
    """
    with np.errstate(divide="ignore", invalid="ignore"):
        a, b = np.log10(np.asarray(lo, float)), np.log10(np.asarray(hi, float))
    ok = np.isfinite(a) & np.isfinite(b)
    if not ok.any():
        return np.full(a.shape, np.nan), np.full(a.shape, np.nan)
    at_lo = ok & (a <= np.min(a[ok]) + rel)
    at_hi = ok & (b >= np.max(b[ok]) - rel)
    return np.where(at_hi & ~at_lo, a, np.nan), np.where(at_lo & ~at_hi, b, np.nan)


def spread_uncertainty(param: str, values, clip_log10, reason: str, cv: dict | None = None) -> ParameterUncertainty:
    """The campaign's spread of a parameter: median and standard deviation of log10 p over ``values`` (> 0)."""
    v = np.asarray(values, float)
    v = np.log10(v[np.isfinite(v) & (v > 0)])
    if v.size < 3:
        raise InputError(f"fewer than 3 values of {param} to take its campaign spread from", field=param)
    return ParameterUncertainty(param, "spread", max(float(np.std(v, ddof=1)), _SIGMA_FLOOR), float(np.median(v)),
                                tuple(map(float, clip_log10)), [], [], [], math.nan, cv or {"n": int(v.size)}, reason)


def fit_uncertainty(param: str, X, residual_log10, fold, X_fold_train, X_train, lo, hi, clip_log10,
                    spread_values, *, kind: str = "model", coef=(), what: str = "model",
                    y_log10=()) -> ParameterUncertainty:
    """Calibrate σ of a learned parameter from its cross-validation residuals.

    Parameters
    ----------
    param : str
        Parameter name.
    X : ndarray, shape (n, 2)
        Held-out rows' inputs (D, L mm), rows where the parameter was identified.
    residual_log10 : ndarray, shape (n,)
        log10(identified) − log10(predicted by the model of the other folds).
    fold : ndarray of int, shape (n,)
        Each row's fold.
    X_fold_train : dict
        Fold → inputs the model of that fold was trained on (for d_k as the held-out row saw it).
    X_train, lo, hi :
        The saved model's training inputs and range (mm).
    clip_log10 : (float, float)
        Search bounds, log10 SI.
    spread_values : ndarray
        The parameter over the ok rows (the spread alternative).
    kind, coef :
        ``"model"`` (ANFIS) or ``"powerlaw"`` with its coefficients.
    what : str
        How the reason names the predictor.

    Returns
    -------
    ParameterUncertainty
        ``kind="spread"`` when the model predicts held-out rows worse than the spread does.
    """
    X = np.asarray(X, float)
    r = np.asarray(residual_log10, float)
    lo, hi = np.asarray(lo, float), np.asarray(hi, float)
    d = np.empty(r.size)
    delta = np.empty(r.size)
    for k in np.unique(fold):
        rows = fold == k
        Xt = np.asarray(X_fold_train[int(k)], float)
        tlo, thi = Xt.min(axis=0), Xt.max(axis=0)
        d[rows] = sparsity(X[rows], Xt, tlo, thi) / max(typical_spacing(Xt, tlo, thi), 1e-12)
        delta[rows] = outside(X[rows], tlo, thi)
    d_ref = typical_spacing(X_train, lo, hi)
    s = np.maximum(1.0, d) * (1.0 + WIDEN_PER_RANGE * delta)
    ratio = r / s
    q = _conformal(ratio)
    covered = []
    for k in np.unique(fold):  # cross-conformal: calibrate on the other folds, count on this one
        rows = fold == k
        rest = ratio[~rows][np.isfinite(ratio[~rows])]
        qk = max(_conformal(ratio[~rows]), _Z * float(np.sqrt(np.mean(rest**2))) if rest.size else math.inf)
        covered.append(np.abs(ratio[rows]) <= qk)
    coverage = float(np.mean(np.concatenate(covered))) if covered else math.nan
    sv = np.log10(np.asarray(spread_values, float)[np.isfinite(spread_values) & (np.asarray(spread_values) > 0)])
    spread_rms = float(np.std(sv, ddof=1)) if sv.size > 2 else math.inf
    rms = float(np.sqrt(np.mean(r**2)))
    cv = {"n": int(r.size), "coverage90": coverage, "rms_log10": rms, "spread_rms_log10": spread_rms,
          "folds": int(np.unique(fold).size)}
    if not math.isfinite(q) or rms >= spread_rms:
        why = ("too few held-out rows to calibrate an interval" if not math.isfinite(q) else
               f"its cross-validated RMS error {rms:.3g} decades is no better than the campaign's spread "
               f"{spread_rms:.3g}")
        return spread_uncertainty(param, spread_values, clip_log10,
                                  f"campaign spread, not the {what}: {why}", cv)
    # the conformal quantile alone varies much from campaign to campaign with few rows (its coverage has a
    # standard deviation of √(0.09/n), 5 points at n = 40); the RMS of the same ratios is steadier, and for
    # Gaussian residuals equal in expectation: the larger of the two
    sigma = max(q / _Z, float(np.sqrt(np.mean(ratio[np.isfinite(ratio)] ** 2))), _SIGMA_FLOOR)
    reason = (f"{what}; σ {sigma:.3g} decades from {r.size} held-out rows ({cv['folds']}-fold cross-validation, "
              f"90 % interval held {100 * coverage:.0f} % out of sample), wider where tools are sparse or outside "
              f"the learned range")
    return ParameterUncertainty(param, kind, sigma, math.nan, tuple(map(float, clip_log10)),
                                np.asarray(X_train, float).tolist(), lo.tolist(), hi.tolist(), d_ref, cv, reason,
                                tuple(float(c) for c in coef), tuple(float(v) for v in y_log10))


def write_uncertainty(path: Path, items: dict) -> None:
    """Write ``uncertainty.json`` (parameter → :class:`ParameterUncertainty`) atomically."""
    def cell(v):
        if isinstance(v, float) and not math.isfinite(v):
            return None
        if isinstance(v, (list, tuple)):
            return [cell(x) for x in v]
        return v

    doc = {"format": FORMAT, "version": 1,
           "parameters": {p: {k: cell(v) for k, v in asdict(u).items()} for p, u in items.items()}}
    with atomic_open(path, "w", encoding="utf-8") as fh:
        json.dump(doc, fh, indent=1, allow_nan=False)


def read_uncertainty(path: Path) -> dict:
    """Parameter → :class:`ParameterUncertainty` from ``uncertainty.json``; InputError when unreadable."""
    try:
        check_regular_file(path, what="joint-uncertainty file")
        doc = json.loads(Path(path).read_text(encoding="utf-8"))
        if doc.get("format") != FORMAT:
            raise ValueError(f"format is not {FORMAT!r}")
        out = {}
        for p, d in doc["parameters"].items():
            d = {k: (math.nan if v is None else v) for k, v in d.items()}
            d["clip_log10"] = tuple(d["clip_log10"])
            d["coef"] = tuple(d.get("coef", ()))
            d["y_log10"] = tuple(d.get("y_log10", ()))
            for k in ("window_lo", "window_hi"):
                d[k] = tuple(math.nan if v is None else float(v) for v in d.get(k, ()))
            d["window_X"] = tuple(tuple(map(float, x)) for x in d.get("window_X", ()))
            if not len(d["window_X"]) == len(d["window_lo"]) == len(d["window_hi"]):
                raise ValueError(f"{p}: window_X, window_lo and window_hi differ in length")
            out[p] = ParameterUncertainty(**d)
            if not (out[p].sigma_log10 > 0):
                raise ValueError(f"{p}: sigma_log10 must be > 0")
        return out
    except InputError:
        raise
    except OSError as e:
        raise InputError(f"cannot read the joint uncertainty ({e.strerror or e}); rerun `toolpoint campaign learn`",
                         file=path) from None
    except (ValueError, KeyError, TypeError, AttributeError) as e:
        raise InputError(f"not a joint-uncertainty file ({e}); rerun `toolpoint campaign learn`", file=path) from None
