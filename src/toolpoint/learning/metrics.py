"""Error measures for regression models (ANFIS joint-stiffness prediction).

All functions take ``(y_true, y_pred)``: ``t`` = targets (measured values),
``o`` = model outputs, both 1-D of equal length ``n``. They return a float in the
unit stated (percent for the APE measures, the target's unit for RMSE, none for
the normalised ones).

The four measures reported in Čiča et al. (joint stiffness from ANFIS) are
NRMSE, AFV, MAPE and max APE.
"""

from __future__ import annotations

import numpy as np

__all__ = ["rmse", "nrmse", "ndei", "afv", "mape", "max_ape"]


def _pair(y_true, y_pred, *, nonzero_true: bool = False):
    t = np.asarray(y_true, dtype=float).reshape(-1)
    o = np.asarray(y_pred, dtype=float).reshape(-1)
    if t.shape != o.shape:
        raise ValueError(f"y_true has {t.size} values but y_pred has {o.size}")
    if t.size == 0:
        raise ValueError("empty y_true / y_pred")
    if not (np.all(np.isfinite(t)) and np.all(np.isfinite(o))):
        raise ValueError("y_true and y_pred must be finite (no NaN or inf)")
    if nonzero_true and np.any(t == 0):
        raise ValueError("percentage errors are undefined for a zero target value")
    return t, o


def rmse(y_true, y_pred) -> float:
    """Root-mean-square error, in the unit of the target.

    RMSE = sqrt( (1/n) Σ (t_k − o_k)² )
    """
    t, o = _pair(y_true, y_pred)
    return float(np.sqrt(np.mean((t - o) ** 2)))


def nrmse(y_true, y_pred) -> float:
    """Normalised RMSE: RMSE divided by the standard deviation of the targets.

    NRMSE = RMSE / σ_t,   σ_t = sqrt( (1/n) Σ (t_k − t̄)² )   (population std, ddof = 0)

    0 is a perfect fit; 1 is no better than predicting the mean target.
    """
    t, o = _pair(y_true, y_pred)
    sd = float(np.std(t))
    if sd == 0:
        raise ValueError("NRMSE is undefined for constant targets (zero standard deviation)")
    return rmse(t, o) / sd


def ndei(y_true, y_pred) -> float:
    """Non-dimensional error index (Jang 1993): RMSE / σ_t.

    NDEI = RMSE / σ_t with the population standard deviation of the targets —
    by Jang's definition the same number as :func:`nrmse`; kept under its own
    name so results can be compared with the ANFIS literature.
    """
    return nrmse(y_true, y_pred)


def afv(y_true, y_pred) -> float:
    """Absolute fraction of variance, as defined in Čiča et al.

    AFV = 1 − Σ (t_k − o_k)² / Σ o_k²

    (the denominator is the sum of squared model *outputs* o, as in the paper).
    1 is a perfect fit.
    """
    t, o = _pair(y_true, y_pred)
    den = float(np.sum(o**2))
    if den == 0:
        raise ValueError("AFV is undefined when every prediction is zero")
    return 1.0 - float(np.sum((t - o) ** 2)) / den


def mape(y_true, y_pred) -> float:
    """Mean absolute percentage error, in percent (Jang's APE).

    MAPE = (100 / n) Σ |t_k − o_k| / |t_k|
    """
    t, o = _pair(y_true, y_pred, nonzero_true=True)
    return float(100.0 * np.mean(np.abs(t - o) / np.abs(t)))


def max_ape(y_true, y_pred) -> float:
    """Largest absolute percentage error, in percent.

    max APE = 100 · max_k |t_k − o_k| / |t_k|
    """
    t, o = _pair(y_true, y_pred, nonzero_true=True)
    return float(100.0 * np.max(np.abs(t - o) / np.abs(t)))
