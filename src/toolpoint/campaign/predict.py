"""The joint and the tool-point FRF of a tool that was never measured.

ANFIS models (one JSON per target, from ``toolpoint campaign learn``) give
kt, kr — and ct, cr where they were identifiable — from (diameter_mm,
overhang_mm). A parameter without a model takes its campaign median
(from ``identified.csv`` beside the models folder, :mod:`.results`), which is
said in the returned notes. RCSA then couples the tool to the subassembly.
"""

from __future__ import annotations

import json
import warnings
from pathlib import Path

import numpy as np

from ..learning.anfis import ANFIS
from ..dynamics.assembly import Assembly, load_assembly
from ..errors import ExtrapolationWarning, InputError
from ..frf import FRF
from ..io.table import check_regular_file
from ..dynamics.model import ToolPointModel
from ..identification.params import PARAMS
from ..dynamics.subassembly import Subassembly
from .config import ToolFamily, load_campaign
from .learn import GP_FORMAT, MANIFEST, REQUIRED_FOR_PREDICT, gp_kernel
from .results import FILE_NAME, read_identified

__all__ = ["load_models", "load_gp_models", "GPModel", "predict_joint", "predict_frf"]


def load_models(models_dir) -> dict[str, ANFIS]:
    """The ANFIS models in a ``campaign learn`` models folder.

    Parameters
    ----------
    models_dir : path-like
        Folder with ``<parameter>.json`` per learned parameter and the ``manifest.json``
        naming them (kt required; the others fall back to campaign medians in :func:`predict_joint`).

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


def _median_identified(models_dir: Path) -> dict[str, tuple[float, str]]:
    """Per parameter: (median, what it is the median of) over the campaign's ok rows —
    the rows where the parameter was identified if there are at least 3, else all ok rows."""
    path = models_dir.parent / FILE_NAME
    if not path.exists():
        return {}
    ok = read_identified(path).ok()
    out = {}
    for p in PARAMS:
        if not ok.has(p):
            continue
        v = ok.column(p, required=False)
        ident = np.isfinite(v) & (ok.identified(p) if ok.has_interval(p) else False)
        if ident.sum() >= 3:
            out[p] = (float(np.median(v[ident])), f"median of the {int(ident.sum())} tools where it was identified")
        elif np.isfinite(v).any():
            out[p] = (float(np.median(v[np.isfinite(v)])), f"median of all {int(np.isfinite(v).sum())} ok tools")
    return out


def _training_range(model: ANFIS):
    r = np.asarray(model.input_range_, float)  # (n_inputs, 2): training data range per input
    return r[:, 0], r[:, 1]


def predict_joint(models_dir, diameter_mm: float, overhang_mm: float) -> tuple[np.ndarray, list[str]]:
    """The joint of one tool from the ANFIS models (campaign medians for parameters without one).

    Parameters
    ----------
    models_dir : path-like
        ``campaign learn`` models folder (``identified.csv`` beside it for medians).
    diameter_mm, overhang_mm : float
        Tool diameter D and overhang L, mm.

    Returns
    -------
    joint : ndarray, shape (4,)
        [kt N/m, ct N s/m, kr N m/rad, cr N m s/rad].
    notes : list of str
        Fallbacks used and extrapolation.

    Warns
    -----
    ExtrapolationWarning
        (D, L) outside the range a model was trained on (also in ``notes``).

    Raises
    ------
    InputError
        Missing models, a model predicting a value ≤ 0, no median to fall back on.
    """
    d = Path(models_dir)
    models = load_models(d)
    notes = []
    x = np.array([[diameter_mm, overhang_mm]], float)
    ranges = {p: _training_range(m) for p, m in models.items()}
    outside = [p for p, (lo, hi) in ranges.items() if np.any(x[0] < lo) or np.any(x[0] > hi)]
    if outside:
        lo = np.max([ranges[p][0] for p in outside], axis=0)
        hi = np.min([ranges[p][1] for p in outside], axis=0)
        msg = (f"D = {diameter_mm:g} mm, L = {overhang_mm:g} mm lies outside the range the {', '.join(outside)} "
               f"model{'s were' if len(outside) > 1 else ' was'} trained on (D {lo[0]:g}–{hi[0]:g} mm, "
               f"L {lo[1]:g}–{hi[1]:g} mm): extrapolation")
        warnings.warn(msg, ExtrapolationWarning, stacklevel=2)
        notes.append(msg)
    med = None
    out = []
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", ExtrapolationWarning)  # said once above
        for p in PARAMS:
            if p in models:
                v = float(models[p].predict(x)[0])
                if not (v > 0 and np.isfinite(v)):
                    raise InputError(f"the {p} model predicts {v:.4g} here, not a positive finite value "
                                     "(over-fitted, or extrapolated too far?)", file=d / f"{p}.json")
            else:
                med = _median_identified(d) if med is None else med
                if p not in med:
                    raise InputError(f"no model for {p} and no identified.csv beside the models to take a median from",
                                     file=d, field="--models")
                v, what = med[p]
                notes.append(f"{p}: no model (not identifiable in the campaign); {what}, {v:.4g}, used")
            out.append(v)
    return np.array(out), notes


def predict_frf(source, diameter_mm: float, overhang_mm: float, models_dir, *, holder: str | None = None,
                freq_hz=None) -> tuple[FRF, np.ndarray, list[str]]:
    """Tool-point receptance of a tool (D, L in mm) on a campaign's holder or an assembly's spindle–holder.

    Parameters
    ----------
    source : path-like
        A campaign folder (tool family and subassembly from it) or an assembly
        TOML (spindle, holder and spindle–holder joint from it; the tool a
        cylinder of D with 0.8 D flutes over 2 D, in the file's tool material).
    diameter_mm, overhang_mm : float
        Tool diameter D and overhang L, mm.
    models_dir : path-like
        ``campaign learn`` models folder.
    holder : str, optional
        Holder name (campaigns with several; default the first).
    freq_hz : array_like, optional
        Frequencies, Hz (default: the campaign band at 1 Hz, the subassembly's
        measured grid, or the assembly's frequency range).

    Returns
    -------
    frf : FRF
        Tool-point receptance, m/N.
    joint : ndarray, shape (4,)
        The predicted joint (SI), as :func:`predict_joint`.
    notes : list of str
        As :func:`predict_joint`.
    """
    joint, notes = predict_joint(models_dir, diameter_mm, overhang_mm)
    src = Path(source)
    if src.is_dir():
        c = load_campaign(src)
        name = holder or next(iter(c.holders))
        if name not in c.holders:
            raise InputError(f"unknown holder {name!r} (one of {', '.join(c.holders)})", file=c.toml, field="--holder")
        lo, hi = c.band_hz
        if c.holders[name].kind == "model":
            f = np.arange(lo, hi + 0.5) if freq_hz is None else np.asarray(freq_hz, float)
            sub = c.subassembly(name, f)
        else:
            sub = c.subassembly(name, None)
            sub = sub if freq_hz is None else sub.at(freq_hz)
        tool = c.family.tool(diameter_mm, overhang_mm)
    else:
        a: Assembly = load_assembly(src, require_tool=False)
        f = a.frequency.array() if freq_hz is None else np.asarray(freq_hz, float)
        f = f[f > 0]
        sub = Subassembly.from_assembly(a, f)
        mat = a.tool.segments[0].material if a.tool is not None else a.materials["steel"]
        tool = ToolFamily(mat).tool(diameter_mm, overhang_mm)
    h = ToolPointModel(tool, sub, sub.freq_hz).tool_point(joint)
    frf = FRF(sub.freq_hz, h, "receptance", f"predicted D{diameter_mm:g} L{overhang_mm:g}")
    return frf, joint, notes
