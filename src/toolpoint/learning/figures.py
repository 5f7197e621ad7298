"""Figures of an ANFIS model and its predictions (Čiča et al., Figs. 6–8).

* :func:`plot_membership` / :func:`membership_figure` — the trained membership
  functions of each input over its training range;
* :func:`per_sample_figure` — target and prediction per sample (Figs. 6/7);
* :func:`regression_figure` — prediction against target with the fitted line
  and the correlation coefficient R (Fig. 8);
* :func:`save_png` — write a figure atomically.

The ``*_figure`` functions build a :class:`matplotlib.figure.Figure` without
pyplot (no global figure registry, no GUI backend), so the library and the CLI
can make many of them without closing anything.

Examples
--------
>>> import numpy as np
>>> fig = regression_figure(np.array([1.0, 2.0, 3.0]), np.array([1.1, 1.9, 3.0]), "kt [N/m]", "test data")
>>> fig.axes[0].get_title().startswith("test data: R = ")
True
"""

from __future__ import annotations

import os

import numpy as np

from ..io.atomic import atomic_path
from .anfis import ANFIS, membership

__all__ = ["plot_membership", "membership_figure", "per_sample_figure", "regression_figure", "save_png"]


def plot_membership(model: ANFIS, ax=None, input_names=None, n_points: int = 400):
    """Plot the MFs of each input over its training range (one axes per input).

    Parameters
    ----------
    model : ANFIS
        A fitted model.
    ax : None or sequence of matplotlib axes
        None: a new pyplot figure; else d axes (a single axes for a one-input model).
    input_names : list of str, optional
        x-axis labels (default: the model's input names, else "input 1", …).
    n_points : int, default 400
        Points per curve.

    Returns
    -------
    matplotlib.figure.Figure
        The figure holding the axes.
    """
    model._check_fitted()
    d = model.n_features_in_
    if ax is None:
        import matplotlib.pyplot as plt

        fig, axes = plt.subplots(d, 1, figsize=(6.0, 2.2 * d), squeeze=False)
        axes = axes[:, 0]
    else:
        axes = np.atleast_1d(np.asarray(ax, dtype=object)).ravel()
        if axes.size != d:
            raise ValueError(f"need {d} axes (one per input), got {axes.size}")
        fig = axes[0].figure
    names = input_names or model.input_names_ or [f"input {i + 1}" for i in range(d)]
    for i, axi in enumerate(axes):
        lo, hi = model.input_range_[i]
        x = np.linspace(lo, hi, n_points)
        mu = membership(model.mf, model.premise_[i], x)
        for j in range(mu.shape[1]):
            axi.plot(x, mu[:, j], label=f"MF {j + 1}")
        axi.set_xlim(lo, hi)
        axi.set_ylim(-0.02, 1.05)
        axi.set_xlabel(names[i])
        axi.set_ylabel("membership")
    fig.tight_layout()
    return fig


def membership_figure(model: ANFIS, *, title: str | None = None, input_names=None):
    """A new (pyplot-free) figure of the model's membership functions, one panel per input.

    Parameters
    ----------
    model : ANFIS
        A fitted model.
    title : str, optional
        Figure title (e.g. the target the model predicts).
    input_names : list of str, optional
        Axis labels of the inputs with units (default: the model's input names).

    Returns
    -------
    matplotlib.figure.Figure
    """
    from matplotlib.figure import Figure

    d = model.n_features_in_
    fig = Figure(figsize=(6.0, 2.2 * d + (0.4 if title else 0.0)))
    plot_membership(model, ax=fig.subplots(d, 1, squeeze=False)[:, 0], input_names=input_names)
    if title:
        fig.suptitle(title)
        fig.tight_layout()
    return fig


def per_sample_figure(y_true, y_pred, label: str, title: str):
    """Target and ANFIS prediction against the sample number (Čiča et al., Figs. 6/7).

    Parameters
    ----------
    y_true, y_pred : array_like, shape (n,)
        Targets and predictions, in the unit named by ``label``.
    label : str
        y-axis label with the unit, e.g. ``"kt [N/m]"``.
    title : str
        Axes title.

    Returns
    -------
    matplotlib.figure.Figure
    """
    from matplotlib.figure import Figure

    y, o = np.asarray(y_true, float), np.asarray(y_pred, float)
    fig = Figure(figsize=(7.0, 4.0))
    ax = fig.subplots()
    k = np.arange(1, y.size + 1)
    ax.plot(k, y, "o", mfc="none", label="target")
    ax.plot(k, o, "x", label="ANFIS prediction")
    ax.set_xlabel("sample number")
    ax.set_ylabel(label)
    ax.set_title(title)
    ax.legend()
    fig.tight_layout()
    return fig


def regression_figure(y_true, y_pred, label: str, title: str):
    """Prediction against target, the line output = target, and the least-squares line (Fig. 8).

    The title gets the correlation coefficient R of prediction and target when
    there are at least two distinct targets.

    Parameters
    ----------
    y_true, y_pred : array_like, shape (n,)
        Targets and predictions, in the unit named by ``label``.
    label : str
        Quantity and unit, e.g. ``"kt [N/m]"`` (axes read "target …", "output …").
    title : str
        Axes title (": R = …" is appended).

    Returns
    -------
    matplotlib.figure.Figure
    """
    from matplotlib.figure import Figure

    y, o = np.asarray(y_true, float), np.asarray(y_pred, float)
    fig = Figure(figsize=(5.0, 5.0))
    ax = fig.subplots()
    lo, hi = float(min(y.min(), o.min())), float(max(y.max(), o.max()))
    ax.plot(y, o, "o", mfc="none", label="data")
    ax.plot([lo, hi], [lo, hi], ":", color="grey", label="output = target")
    if y.size >= 2 and np.ptp(y) > 0:
        m, b = np.polyfit(y, o, 1)
        r = np.corrcoef(y, o)[0, 1]
        sign = "+" if b >= 0 else "−"
        ax.plot([lo, hi], [m * lo + b, m * hi + b], "-", label=f"fit: output = {m:.3g}·target {sign} {abs(b):.3g}")
        title = f"{title}: R = {r:.4f}"
    if lo > 0 and hi / lo > 20:  # targets over decades (kr, dampings): one outlier would squash the rest
        ax.set_xscale("log")
        ax.set_yscale("log")
    ax.set_xlabel(f"target {label}")
    ax.set_ylabel(f"output {label}")
    ax.set_title(title)
    ax.legend(loc="upper left", fontsize="small")
    fig.tight_layout()
    return fig


def save_png(fig, path: str | os.PathLike, dpi: int = 120) -> None:
    """Write ``fig`` as a PNG at ``path``, atomically (a failed write leaves no file).

    Parameters
    ----------
    fig : matplotlib.figure.Figure
    path : path-like
        Output file.
    dpi : int, default 120
        Resolution, dots per inch.

    Raises
    ------
    OSError
        The file cannot be written.
    """
    with atomic_path(path) as tmp:
        fig.savefig(tmp, format="png", dpi=dpi)
