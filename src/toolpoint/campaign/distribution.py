r"""Predictive distribution of the holder–tool joint of an unmeasured tool.

Each joint parameter p is log-normal, log10 p ~ Normal(m(D, L), σ(D, L)²), clipped to the range the
campaign's identification searched (the physically plausible range), parameters independent. How m and σ are
made is decided and calibrated by ``campaign learn`` (``models/uncertainty.json``,
:mod:`toolpoint.campaign.calibration`):

* ``model``: m the ANFIS output; σ from its **cross-validated** (held-out) residuals over every campaign tool,
  larger where the training tools are sparse and at or beyond the edge of the learned (D, L) range;
* ``powerlaw``: the family's power law in D and L where it predicted held-out tools better than the ANFIS (an
  over-fitted ANFIS), σ as above;
* ``neighbours`` / ``spread``: a parameter the campaign rarely identifies is not extrapolated: the median of the
  nearest tools that identified it, or the campaign's median and spread.

Where the nearby tools' FRFs bound a parameter on one side only (their intervals run into the search bound on
the other), the log-normal is **truncated** at that bound (:meth:`ParameterUncertainty.window
<toolpoint.campaign.calibration.ParameterUncertainty.window>`): quantiles and samples are those of the
truncated distribution, so a sample never goes where those FRFs say the parameter cannot be.

With ``model="gp"`` a learned parameter takes the GP baseline that ``campaign learn`` saved instead
(:class:`~toolpoint.campaign.models.GPModel`): m its predictive mean of log10 p and σ its own predictive
standard deviation (not calibrated out of sample: ``benchmarks/bench_calibration.py`` measures it).
Why these choices and what they gave: ``docs/design/recommend.md``.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np

from . import calibration
from .models import load_gp_models, load_models
from ..errors import InputError
from ..identification.params import PARAMS
from ..learning.anfis import predict_quietly

__all__ = ["MODELS", "JointPredictor", "JointDistribution", "truncated_log10"]

#: The learned models a predictive distribution can come from.
MODELS = ("anfis", "gp")


def truncated_log10(m, s, window, z) -> np.ndarray:
    """log10 p at standard-normal scores ``z`` of Normal(m, s²) truncated to ``window``.

    The score z maps to the quantile Φ(z) of the truncated distribution, Φ⁻¹(Φ(a) + Φ(z) (Φ(b) − Φ(a))) with
    a, b the window's ends in standard units — the untruncated value where the window is (−inf, inf).

    Parameters
    ----------
    m, s : array_like
        Median and σ of log10 p (decades), broadcast with ``z``'s trailing axes.
    window : array_like, shape (2, ...) or None
        Lower and upper bound of log10 p (±inf: open).
    z : array_like
        Standard-normal scores (samples or quantile levels as scores).

    Examples
    --------
    >>> round(float(truncated_log10(0.0, 1.0, np.array([0.0, np.inf]), 0.0)), 4)  # median of a half-normal
    0.6745
    >>> float(truncated_log10(2.0, 0.5, None, 1.0))
    2.5
    """
    from scipy.special import ndtr, ndtri

    m, s, z = np.asarray(m, float), np.asarray(s, float), np.asarray(z, float)
    if window is None:
        return m + s * z
    lo, hi = np.asarray(window, float)
    if not (np.isfinite(lo).any() or np.isfinite(hi).any()):
        return m + s * z
    with np.errstate(divide="ignore", invalid="ignore"):
        a = np.where(s > 0, ndtr((lo - m) / s), 0.0)
        b = np.where(s > 0, ndtr((hi - m) / s), 1.0)
        u = a + ndtr(z) * (b - a)
        out = m + s * ndtri(np.clip(u, 1e-300, 1 - 1e-16))
    # a window the distribution hardly reaches (b − a ≈ 0): its nearer end
    return np.clip(np.where(np.isfinite(out), out, np.where(m < lo, lo, hi)), lo, hi)


@dataclass(frozen=True)
class JointDistribution:
    """Log-normal joints of a set of tools.

    Attributes
    ----------
    log10_median : ndarray, shape (n, 4)
        m, log10 of [kt N/m, ct N s/m, kr N m/rad, cr N m s/rad].
    sigma_log10 : ndarray, shape (n, 4)
        σ, decades.
    outside : ndarray, shape (n,)
        δ, the distance outside the training (D, L) range in range widths (0 inside).
    clip_log10 : ndarray, shape (2, 4)
        The identification's range per parameter, log10 SI: samples are clipped to it.
    window_log10 : ndarray, shape (n, 2, 4), optional
        Per tool, the one-sided bounds the nearby tools' FRFs give (±inf: none): the log-normal is truncated
        there (:func:`truncated_log10`). ``log10_median`` is the untruncated m; :meth:`quantiles` (0.5) is the
        median of what is sampled.
    """

    log10_median: np.ndarray
    sigma_log10: np.ndarray
    outside: np.ndarray
    clip_log10: np.ndarray
    window_log10: np.ndarray | None = None

    def window(self, index: int) -> np.ndarray | None:
        """(2, 4) bounds of tool ``index`` (None: none)."""
        return None if self.window_log10 is None else self.window_log10[index]

    def quantiles(self, q) -> np.ndarray:
        """Quantiles of each parameter, SI: shape (len(q), n, 4).

        Parameters
        ----------
        q : array_like
            Probabilities in (0, 1).
        """
        from scipy.stats import norm

        z = norm.ppf(np.asarray(q, float))[:, None, None]
        w = None if self.window_log10 is None else np.moveaxis(self.window_log10, 1, 0)[:, None]  # (2, 1, n, 4)
        v = truncated_log10(self.log10_median[None], self.sigma_log10[None], w, z)
        return 10.0 ** np.clip(v, *self.clip_log10)

    def sample(self, index: int, n: int, rng: np.random.Generator) -> np.ndarray:
        """``n`` joints of tool ``index``, SI, shape (n, 4) (independent log-normal parameters, truncated to the
        tool's window, clipped)."""
        z = rng.standard_normal((n, len(PARAMS)))
        v = truncated_log10(self.log10_median[index], self.sigma_log10[index], self.window(index), z)
        return 10.0 ** np.clip(v, *self.clip_log10)


class JointPredictor:
    """The predictive joint distribution of a ``campaign learn`` models folder.

    Parameters
    ----------
    models_dir : path-like
        Models folder (``<p>.json``, ``uncertainty.json``, for ``gp`` the saved ``gp_<p>.json``).
    model : {"anfis", "gp"}, default "anfis"
        The calibrated distribution ``campaign learn`` chose per parameter (module docstring), or the GP
        baselines with their own predictive σ for the learned parameters.
    bounds : toolpoint.identification.params.Bounds, optional
        The campaign's search bounds: medians and samples are clipped to them too.

    Attributes
    ----------
    kind : str
        ``model``.
    models : dict
        Parameter → ANFIS (or :class:`~toolpoint.campaign.models.GPModel`).
    parameters : dict
        Parameter → :class:`~toolpoint.campaign.calibration.ParameterUncertainty`.
    source : dict
        Parameter → how its distribution is made (one line).
    lo, hi : ndarray, shape (2,)
        Training range of (D, L), mm (intersection over the models).

    Raises
    ------
    InputError
        Missing models, ``uncertainty.json`` (models of an older ``learn``), saved GP baselines for ``gp``;
        an unknown ``model``.
    """

    def __init__(self, models_dir, model: str = "anfis", bounds=None):
        if model not in MODELS:
            raise InputError(f"must be one of {', '.join(MODELS)}, got {model!r}", field="model")
        d = Path(models_dir)
        self.kind = model
        self.models = load_models(d) if model == "anfis" else load_gp_models(d)
        self.parameters = calibration.read_uncertainty(d / calibration.FILE_NAME)
        missing = [p for p in PARAMS if p not in self.parameters]
        if missing:
            raise InputError(f"no predictive distribution for {', '.join(missing)}; rerun `toolpoint campaign learn`",
                             file=d / calibration.FILE_NAME)
        self.lo = np.max([m.input_range_[:, 0] for m in self.models.values()], axis=0)
        self.hi = np.min([m.input_range_[:, 1] for m in self.models.values()], axis=0)
        clip = np.array([self.parameters[p].clip_log10 for p in PARAMS], float).T  # (2, 4)
        if bounds is not None:
            clip = np.array([np.maximum(clip[0], bounds.log_lo), np.minimum(clip[1], bounds.log_hi)])
        self.clip_log10 = clip
        self.source = {}
        for p in PARAMS:
            u = self.parameters[p]
            if model == "gp" and p in self.models:
                self.source[p] = f"GP baseline {self.models[p].kernel}; σ its predictive standard deviation per tool"
            elif u.kind == "model" and p not in self.models:
                raise InputError(f"uncertainty.json names an ANFIS model of {p} that the folder does not hold; rerun "
                                 "`toolpoint campaign learn`", file=d / calibration.FILE_NAME, field=p)
            else:
                self.source[p] = u.reason

    def outside(self, diameter_mm, overhang_mm) -> np.ndarray:
        """δ per tool: largest distance outside the training (D, L) range, in range widths (0 inside)."""
        x = np.column_stack([np.atleast_1d(diameter_mm), np.atleast_1d(overhang_mm)]).astype(float)
        return calibration.outside(x, self.lo, self.hi)

    def predict(self, diameter_mm, overhang_mm) -> JointDistribution:
        """The joint distributions of tools (D, L in mm; arrays of equal length).

        Returns
        -------
        JointDistribution
            Medians clipped to the identification's range; NaN median where an ANFIS predicts ≤ 0.
        """
        D, L = np.atleast_1d(np.asarray(diameter_mm, float)), np.atleast_1d(np.asarray(overhang_mm, float))
        X = np.column_stack([D, L])
        m = np.empty((len(D), len(PARAMS)))
        sig = np.empty_like(m)
        win = np.empty((len(D), 2, len(PARAMS)))
        for j, p in enumerate(PARAMS):
            u = self.parameters[p]
            win[:, 0, j], win[:, 1, j] = u.window(X)
            if self.kind == "gp" and p in self.models:
                m[:, j], sig[:, j] = self.models[p].predict(X)
                continue
            sig[:, j] = u.sigma(X)
            if u.kind == "model":
                pred, _ = predict_quietly(self.models[p], X)
                with np.errstate(divide="ignore", invalid="ignore"):
                    m[:, j] = np.where(pred > 0, np.log10(np.where(pred > 0, pred, 1.0)), np.nan)
            else:
                m[:, j] = u.centre(X)
        m = np.where(np.isfinite(m), np.clip(m, self.clip_log10[0], self.clip_log10[1]), m)
        return JointDistribution(m, sig, self.outside(D, L), self.clip_log10,
                                 win if np.isfinite(win).any() else None)
