r"""Predictive distribution of the holder–tool joint of an unmeasured tool.

Each joint parameter p is log-normal: log10 p ~ Normal(m(D, L), σ²), with

* a learned parameter (an ANFIS model in the models folder): m the model's
  output (the models fit log10 p), and
  σ² = mean over the training rows where p was identified of
  (log10 p_identified − m)²  +  mean of their identification variances
  (σ_ln/ln 10)², σ_ln from each row's 95 % interval
  (:func:`~toolpoint.identification.params.sigma_ln_from_interval`);
* a parameter without a model (not identifiable in the campaign): m the
  log10 of the campaign median (as :func:`~toolpoint.campaign.predict.predict_joint`
  uses), σ the standard deviation of log10 p over the campaign's ok rows (the
  spread of the family, since D and L are not used).

With ``model="gp"`` a learned parameter takes the GP baseline that
``campaign learn`` saved instead (:class:`~toolpoint.campaign.predict.GPModel`):
m its predictive mean of log10 p and σ its own predictive standard deviation
(posterior of the latent function plus the fitted white noise), per tool.

The four parameters are sampled independently. A tool outside the (D, L) range
the models were trained on gets its ANFIS σ widened by the factor 1 + 5 δ, δ the
largest distance outside the range in units of the range's width (or is
refused); the GP's σ grows away from its data by itself and is not widened.
Why these choices and what they gave: ``docs/design/recommend.md``.
"""

from __future__ import annotations

import csv
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ..campaign.learn import INPUTS
from ..campaign.predict import load_gp_models, load_models
from ..campaign.results import FILE_NAME, read_identified
from ..errors import InputError
from ..identification.params import PARAMS
from ..learning.anfis import predict_quietly

__all__ = ["WIDEN_PER_RANGE", "MODELS", "JointPredictor", "JointDistribution"]

#: σ is multiplied by 1 + WIDEN_PER_RANGE · δ outside the training range (δ in range widths; ANFIS only).
WIDEN_PER_RANGE = 5.0
#: The learned models a predictive distribution can come from.
MODELS = ("anfis", "gp")


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
    """

    log10_median: np.ndarray
    sigma_log10: np.ndarray
    outside: np.ndarray

    def quantiles(self, q) -> np.ndarray:
        """Quantiles of each parameter, SI: shape (len(q), n, 4).

        Parameters
        ----------
        q : array_like
            Probabilities in (0, 1).
        """
        from scipy.stats import norm

        z = norm.ppf(np.asarray(q, float))[:, None, None]
        return 10.0 ** (self.log10_median[None] + z * self.sigma_log10[None])

    def sample(self, index: int, n: int, rng: np.random.Generator) -> np.ndarray:
        """``n`` joints of tool ``index``, SI, shape (n, 4) (independent log-normal parameters)."""
        z = rng.standard_normal((n, len(PARAMS)))
        return 10.0 ** (self.log10_median[index] + z * self.sigma_log10[index])


class JointPredictor:
    """The predictive joint distribution of a ``campaign learn`` models folder.

    Parameters
    ----------
    models_dir : path-like
        Models folder (``<p>.json``, ``split.csv``, for ``gp`` the saved ``gp_<p>.json``);
        ``identified.csv`` beside it.
    model : {"anfis", "gp"}, default "anfis"
        The ANFIS models with σ from their training residuals and the identification intervals, or
        the GP baselines with their own predictive σ.

    Attributes
    ----------
    kind : str
        ``model``.
    models : dict
        Parameter → ANFIS (or :class:`~toolpoint.campaign.predict.GPModel`).
    sigma_log10 : ndarray, shape (4,)
        σ of each parameter inside the training range, decades (GP: NaN for a learned parameter,
        whose σ depends on the tool).
    source : dict
        Parameter → how its distribution is made (one line).
    lo, hi : ndarray, shape (2,)
        Training range of (D, L), mm (intersection over the models).

    Raises
    ------
    InputError
        Missing models (no saved GP baselines for ``gp``), ``identified.csv`` or ``split.csv``, an
        unknown ``model``.
    """

    def __init__(self, models_dir, model: str = "anfis"):
        if model not in MODELS:
            raise InputError(f"must be one of {', '.join(MODELS)}, got {model!r}", field="model")
        d = Path(models_dir)
        self.kind = model
        self.models = load_models(d) if model == "anfis" else load_gp_models(d)
        rows = read_identified(d.parent / FILE_NAME, required=list(INPUTS) + list(PARAMS)).ok()
        split = d / "split.csv"
        try:
            with open(split, newline="") as fh:
                train = {r["id"] for r in csv.DictReader(fh) if r.get("set") == "train"}
        except (OSError, KeyError) as e:
            raise InputError(f"cannot read the train/test split ({e})", file=split) from None
        ids = np.array(rows.ids())
        X = np.column_stack([rows.column(c) for c in INPUTS])
        is_train = np.isin(ids, sorted(train))
        self.lo = np.max([m.input_range_[:, 0] for m in self.models.values()], axis=0)
        self.hi = np.min([m.input_range_[:, 1] for m in self.models.values()], axis=0)
        self.median = np.zeros(len(PARAMS))
        self.sigma_log10 = np.zeros(len(PARAMS))
        self.source = {}
        for j, p in enumerate(PARAMS):
            v = rows.column(p, required=False)
            if p in self.models and model == "gp":
                self.sigma_log10[j] = np.nan
                self.source[p] = f"GP baseline {self.models[p].kernel}; σ its predictive standard deviation per tool"
            elif p in self.models:
                use = is_train & np.isfinite(v) & (v > 0) & rows.identified(p)
                if use.sum() < 3:
                    raise InputError(f"fewer than 3 training rows identified {p}: no residual spread",
                                     file=rows.path, field=p)
                pred, _ = predict_quietly(self.models[p], X[use])
                res = np.log10(v[use]) - np.log10(pred)
                ident = (rows.sigma_ln(p)[use] / np.log(10)) ** 2
                self.sigma_log10[j] = np.sqrt(np.mean(res**2) + np.mean(ident))
                self.source[p] = (f"ANFIS; σ {self.sigma_log10[j]:.3g} decades = √(training RMS residual² "
                                  f"{np.sqrt(np.mean(res**2)):.3g}² + mean identification variance "
                                  f"{np.sqrt(np.mean(ident)):.3g}²) over {int(use.sum())} training rows")
            else:
                ok = np.isfinite(v) & (v > 0)
                if ok.sum() < 3:
                    raise InputError(f"no model for {p} and fewer than 3 values to take a median from",
                                     file=rows.path, field=p)
                ident = ok & rows.identified(p)
                base = ident if ident.sum() >= 3 else ok
                self.median[j] = np.median(v[base])
                self.sigma_log10[j] = np.std(np.log10(v[ok]))
                self.source[p] = (f"no model: campaign median {self.median[j]:.4g} of {int(base.sum())} rows, σ "
                                  f"{self.sigma_log10[j]:.3g} decades = spread of log10 {p} over {int(ok.sum())} "
                                  "ok rows")

    def outside(self, diameter_mm, overhang_mm) -> np.ndarray:
        """δ per tool: largest distance outside the training (D, L) range, in range widths (0 inside)."""
        x = np.column_stack([np.atleast_1d(diameter_mm), np.atleast_1d(overhang_mm)]).astype(float)
        width = np.maximum(self.hi - self.lo, 1e-12)
        return np.max(np.maximum(np.maximum(self.lo - x, x - self.hi), 0.0) / width, axis=1)

    def predict(self, diameter_mm, overhang_mm) -> JointDistribution:
        """The joint distributions of tools (D, L in mm; arrays of equal length).

        Returns
        -------
        JointDistribution
            ANFIS σ widened by 1 + :data:`WIDEN_PER_RANGE` · δ outside the training range (GP σ as it is).
        """
        D, L = np.atleast_1d(np.asarray(diameter_mm, float)), np.atleast_1d(np.asarray(overhang_mm, float))
        X = np.column_stack([D, L])
        m = np.empty((len(D), len(PARAMS)))
        delta = self.outside(D, L)
        sig = self.sigma_log10[None, :] * (1.0 + WIDEN_PER_RANGE * delta[:, None])
        for j, p in enumerate(PARAMS):
            if p in self.models and self.kind == "gp":
                m[:, j], sig[:, j] = self.models[p].predict(X)
            elif p in self.models:
                pred, _ = predict_quietly(self.models[p], X)
                with np.errstate(divide="ignore", invalid="ignore"):
                    m[:, j] = np.where(pred > 0, np.log10(np.where(pred > 0, pred, 1.0)), np.nan)
            else:
                m[:, j] = np.log10(self.median[j])
        return JointDistribution(m, sig, delta)
