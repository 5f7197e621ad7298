"""The models folder of ``campaign learn``: its ANFIS models and saved GP baselines, read back.

Read by :mod:`.distribution` (the predictive joint distribution) and so by ``predict`` and ``library``.
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np

from ..errors import InputError
from ..identification.params import PARAMS
from ..io.table import check_regular_file
from ..learning.anfis import ANFIS
from .learn import GP_FORMAT, MANIFEST, REQUIRED_FOR_PREDICT, gp_kernel

__all__ = ["load_models", "load_gp_models", "GPModel"]


def load_models(models_dir) -> dict[str, ANFIS]:
    """The ANFIS models in a ``campaign learn`` models folder.

    Parameters
    ----------
    models_dir : path-like
        Folder with ``<parameter>.json`` per learned parameter and the ``manifest.json``
        naming them (kt required; the others take the distribution uncertainty.json names, :mod:`.distribution`).

    Returns
    -------
    dict
        Parameter name → :class:`~toolpoint.learning.anfis.ANFIS`.

    Raises
    ------
    InputError
        Missing folder or kt model, a file that is not a model, a bad manifest.
    """
    d = Path(models_dir)
    if not d.is_dir():
        raise InputError("models folder not found", file=d, field="--models")
    names = _manifest(d)
    models = {}
    for p in names:
        f = d / f"{p}.json"
        if not f.exists():
            raise InputError(f"{MANIFEST} names {p}.json, which is missing (re-run `toolpoint campaign learn`)",
                             file=d, field="--models")
        try:
            models[p] = ANFIS.load(f)
        except (ValueError, KeyError, OSError) as e:
            raise InputError(f"not a toolpoint ANFIS model ({e})", file=f) from None
    if REQUIRED_FOR_PREDICT not in models:
        raise InputError(f"no model for {REQUIRED_FOR_PREDICT} ({REQUIRED_FOR_PREDICT}.json)", file=d,
                         field="--models")
    return models


class GPModel:
    """A GP baseline saved by ``campaign learn`` (``gp_<target>.json``): predictive mean and std of log10 p.

    Rebuilt exactly from the file: scikit-learn's ``GaussianProcessRegressor`` with the saved kernel
    hyper-parameters held fixed (no optimiser), the saved per-row noise ``alpha``, refitted on the saved
    training data (standardised inputs, normalised log10 targets) — the same computation as at training.

    Parameters
    ----------
    doc : dict
        The file's content.

    Attributes
    ----------
    target : str
        Joint parameter.
    input_range_ : ndarray, shape (2, 2)
        Training range of (D, L), mm: rows [min, max] per input (as ANFIS).
    kernel : str
        The fitted kernel.
    """

    def __init__(self, doc: dict):
        from sklearn.gaussian_process import GaussianProcessRegressor
        from sklearn.preprocessing import StandardScaler

        X = np.asarray(doc["X_mm"], float)
        y = np.asarray(doc["log10_y"], float)
        alpha = np.asarray(doc["alpha"], float)
        if doc.get("format") != GP_FORMAT or X.ndim != 2 or X.shape != (y.size, 2) or alpha.shape != y.shape:
            raise ValueError("not a toolpoint GP baseline (format or array shapes)")
        self.target = str(doc["target"])
        self.kernel = str(doc.get("kernel", ""))
        self.input_range_ = np.column_stack([X.min(axis=0), X.max(axis=0)])
        self._scaler = StandardScaler().fit(X)
        kernel = gp_kernel().clone_with_theta(np.asarray(doc["theta"], float))
        self._gp = GaussianProcessRegressor(kernel=kernel, alpha=alpha, optimizer=None,
                                            normalize_y=bool(doc.get("normalize_y", True)))
        self._gp.fit(self._scaler.transform(X), y)

    @classmethod
    def load(cls, path) -> "GPModel":
        """Read ``gp_<target>.json`` (ValueError, KeyError or OSError if it is not one)."""
        check_regular_file(path, what="GP model file")
        return cls(json.loads(Path(path).read_text(encoding="utf-8")))

    def predict(self, X) -> tuple[np.ndarray, np.ndarray]:
        """Predictive mean and standard deviation of log10 p at inputs X (n, 2) = (D, L) in mm.

        The standard deviation is that of a new tool's value: the posterior of the latent function plus
        the fitted white noise (the scatter no input explains); the per-row identification noise of the
        training rows is not added.

        Returns
        -------
        mean, std : ndarray, shape (n,)
            log10 of p in SI, and decades.
        """
        m, sd = self._gp.predict(self._scaler.transform(np.atleast_2d(np.asarray(X, float))), return_std=True)
        return m, sd


def load_gp_models(models_dir) -> dict[str, GPModel]:
    """The GP baselines that ``campaign learn`` saved (``manifest.json`` key ``gp``).

    Parameters
    ----------
    models_dir : path-like
        A ``campaign learn`` models folder.

    Returns
    -------
    dict
        Parameter → :class:`GPModel`.

    Raises
    ------
    InputError
        No folder, no manifest, no saved GP for kt (learn ran with ``baselines=False`` or before GP
        baselines were saved), a file that is not a GP baseline.
    """
    d = Path(models_dir)
    if not d.is_dir():
        raise InputError("models folder not found", file=d, field="--models")
    path = d / MANIFEST
    if path.exists():
        check_regular_file(path, what="models manifest")
    try:
        names = dict(json.loads(path.read_text(encoding="utf-8")).get("gp", {}))
    except (OSError, UnicodeDecodeError, ValueError, TypeError, AttributeError) as e:
        raise InputError(f"cannot read the models manifest ({type(e).__name__})", file=path) from None
    if REQUIRED_FOR_PREDICT not in names:
        raise InputError(f"no GP baseline for {REQUIRED_FOR_PREDICT} saved: re-run `toolpoint campaign learn` with "
                         "its baselines on", file=path, field="gp")
    models = {}
    for p, name in names.items():
        if p not in PARAMS:
            raise InputError(f"unknown parameter {p!r} (one of {', '.join(PARAMS)})", file=path, field="gp")
        f = d / str(name)
        try:
            models[p] = GPModel.load(f)
        except (ValueError, KeyError, TypeError, OSError) as e:
            raise InputError(f"not a toolpoint GP baseline ({type(e).__name__}: {e})", file=f) from None
    return models


def _manifest(d: Path) -> list[str]:
    """The parameters whose models the last ``learn`` wrote (its manifest); every model file present
    when there is no manifest (a folder written before manifests existed)."""
    path = d / MANIFEST
    if not path.exists():
        return [p for p in PARAMS if (d / f"{p}.json").exists()]
    check_regular_file(path, what="models manifest")
    try:
        doc = json.loads(path.read_text(encoding="utf-8"))
        names = list(doc["models"])
    except (OSError, UnicodeDecodeError, ValueError, KeyError, TypeError) as e:
        raise InputError(f"not a models manifest ({type(e).__name__})", file=path) from None
    unknown = [n for n in names if n not in PARAMS]
    if unknown:
        raise InputError(f"unknown parameter {unknown[0]!r} (one of {', '.join(PARAMS)})", file=path, field="models")
    return names
