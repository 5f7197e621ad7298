"""Error measures for regression models (ANFIS joint-stiffness prediction).

All functions take ``(y_true, y_pred)``: ``t`` = targets (measured values),
``o`` = model outputs, both 1-D of equal length ``n``. They return a float in the
unit stated (percent for the APE measures, the target's unit for RMSE, none for
the normalised ones).

The four measures reported in Čiča et al. (joint stiffness from ANFIS) are
NRMSE, AFV, MAPE and max APE (:data:`PAPER_METRICS`, :func:`paper_metrics`).

Examples
--------
>>> from toolpoint.learning.metrics import paper_metrics
>>> {k: round(v, 4) for k, v in paper_metrics([1.0, 2.0, 4.0], [1.1, 2.0, 3.8]).items()}
{'nrmse': 0.1035, 'afv': 0.9975, 'mape': 5.0, 'max_ape': 10.0}
"""

from __future__ import annotations

import numpy as np

__all__ = ["rmse", "nrmse", "ndei", "afv", "mape", "max_ape", "PAPER_METRICS", "paper_metrics"]


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

    Parameters
    ----------
    y_true, y_pred : array_like, shape (n,)
        Targets t and model outputs o, in the same unit (finite).

    Returns
    -------
    float
        RMSE, in the unit of the target.

    Raises
    ------
    ValueError
        Unequal lengths, no values, or a non-finite value.

    Examples
    --------
    >>> rmse([1.0, 2.0], [1.0, 4.0])
    1.4142135623730951
    """
    t, o = _pair(y_true, y_pred)
    return float(np.sqrt(np.mean((t - o) ** 2)))


def nrmse(y_true, y_pred) -> float:
    """Normalised RMSE: RMSE divided by the standard deviation of the targets.

    NRMSE = RMSE / σ_t,   σ_t = sqrt( (1/n) Σ (t_k − t̄)² )   (population std, ddof = 0)

    0 is a perfect fit; 1 is no better than predicting the mean target.

    Parameters
    ----------
    y_true, y_pred : array_like, shape (n,)
        Targets and model outputs, in the same unit.

    Returns
    -------
    float
        NRMSE (dimensionless).

    Raises
    ------
    ValueError
        As :func:`rmse`, or constant targets (σ_t = 0).

    Examples
    --------
    >>> nrmse([1.0, 3.0], [1.0, 3.0])
    0.0
    >>> nrmse([1.0, 3.0], [2.0, 2.0])  # the mean of the targets
    1.0
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

    Parameters
    ----------
    y_true, y_pred : array_like, shape (n,)
        Targets and model outputs, in the same unit.

    Returns
    -------
    float
        NDEI (dimensionless).

    Examples
    --------
    >>> ndei([1.0, 3.0], [2.0, 2.0])
    1.0
    """
    return nrmse(y_true, y_pred)


def afv(y_true, y_pred) -> float:
    """Absolute fraction of variance, as defined in Čiča et al.

    AFV = 1 − Σ (t_k − o_k)² / Σ o_k²

    (the denominator is the sum of squared model *outputs* o, as in the paper).
    1 is a perfect fit.

    Parameters
    ----------
    y_true, y_pred : array_like, shape (n,)
        Targets and model outputs, in the same unit.

    Returns
    -------
    float
        AFV (dimensionless).

    Raises
    ------
    ValueError
        As :func:`rmse`, or every prediction zero.

    Examples
    --------
    >>> afv([1.0, 2.0], [1.0, 2.0])
    1.0
    >>> afv([1.0, 3.0], [1.0, 2.0])  # 1 − 1/5
    0.8
    """
    t, o = _pair(y_true, y_pred)
    den = float(np.sum(o**2))
    if den == 0:
        raise ValueError("AFV is undefined when every prediction is zero")
    return 1.0 - float(np.sum((t - o) ** 2)) / den


def mape(y_true, y_pred) -> float:
    """Mean absolute percentage error, in percent (Jang's APE).

    MAPE = (100 / n) Σ |t_k − o_k| / |t_k|

    Parameters
    ----------
    y_true, y_pred : array_like, shape (n,)
        Targets (non-zero) and model outputs, in the same unit.

    Returns
    -------
    float
        MAPE, percent.

    Raises
    ------
    ValueError
        As :func:`rmse`, or a zero target.

    Examples
    --------
    >>> mape([1.0, 2.0], [1.1, 2.0])
    5.000000000000004
    """
    t, o = _pair(y_true, y_pred, nonzero_true=True)
    return float(100.0 * np.mean(np.abs(t - o) / np.abs(t)))


def max_ape(y_true, y_pred) -> float:
    """Largest absolute percentage error, in percent.

    max APE = 100 · max_k |t_k − o_k| / |t_k|

    Parameters
    ----------
    y_true, y_pred : array_like, shape (n,)
        Targets (non-zero) and model outputs, in the same unit.

    Returns
    -------
    float
        Largest APE, percent.

    Raises
    ------
    ValueError
        As :func:`rmse`, or a zero target.

    Examples
    --------
    >>> max_ape([1.0, 2.0], [1.1, 2.0])
    10.000000000000009
    """
    t, o = _pair(y_true, y_pred, nonzero_true=True)
    return float(100.0 * np.max(np.abs(t - o) / np.abs(t)))


#: The four measures of Čiča et al., in the paper's order: key → (column title, function).
#: MAPE and max APE are in percent, NRMSE and AFV dimensionless.
PAPER_METRICS = {
    "nrmse": ("NRMSE", nrmse),
    "afv": ("AFV", afv),
    "mape": ("MAPE %", mape),
    "max_ape": ("max APE %", max_ape),
}


def paper_metrics(y_true, y_pred) -> dict[str, float]:
    """The paper's four measures (:data:`PAPER_METRICS`) of one prediction.

    Parameters
    ----------
    y_true, y_pred : array_like, shape (n,)
        Targets and model outputs, in the same unit.

    Returns
    -------
    dict
        ``{"nrmse", "afv", "mape" (%), "max_ape" (%)}`` → float; NaN where a
        measure is undefined (e.g. MAPE of a zero target, NRMSE of constant targets).

    Examples
    --------
    >>> paper_metrics([1.0, 1.0], [1.0, 1.5])["nrmse"]  # constant targets
    nan
    """
    out = {}
    for key, (_, fn) in PAPER_METRICS.items():
        try:
            out[key] = float(fn(y_true, y_pred))
        except ValueError:
            out[key] = float("nan")
    return out
