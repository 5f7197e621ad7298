"""The joint and the tool-point FRF of a tool that was never measured.

The joint comes from the predictive distribution ``campaign learn`` calibrated
(:class:`~.distribution.JointPredictor`: per parameter its ANFIS, the family's power law, or the campaign's
spread, whichever predicted held-out tools best, with a cross-validated 90 % interval) — the same distribution
``library`` samples. RCSA then couples the tool to the subassembly.
"""

from __future__ import annotations

import warnings
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ..dynamics.assembly import Assembly, load_assembly
from ..errors import ExtrapolationWarning, InputError
from ..frf import FRF
from ..dynamics.model import ToolPointModel
from ..identification.params import PARAMS
from ..dynamics.subassembly import Subassembly
from .config import ToolFamily, load_campaign
from .distribution import JointPredictor

__all__ = ["PredictedJoint", "PredictedFRF", "predict_joint", "predict_frf"]


@dataclass(frozen=True)
class PredictedJoint:
    """The predicted joint of one tool.

    Attributes
    ----------
    joint : ndarray, shape (4,)
        Median [kt N/m, ct N s/m, kr N m/rad, cr N m s/rad].
    p05, p95 : ndarray, shape (4,)
        Its calibrated 90 % interval (5 % and 95 % quantiles), SI.
    notes : list of str
        How each parameter is predicted, and extrapolation.
    """

    joint: np.ndarray
    p05: np.ndarray
    p95: np.ndarray
    notes: list


@dataclass(frozen=True)
class PredictedFRF:
    """The predicted tool-point FRF of one tool (:func:`predict_frf`).

    Attributes
    ----------
    frf : FRF
        Tool-point receptance of the median joint, m/N.
    joint : PredictedJoint
        The joint it was computed with.
    """

    frf: FRF
    joint: PredictedJoint


def predict_joint(models_dir, diameter_mm: float, overhang_mm: float) -> PredictedJoint:
    """The joint of one tool (D, L in mm) from a ``campaign learn`` models folder.

    Parameters
    ----------
    models_dir : path-like
        Models folder (``uncertainty.json`` and the models it names).
    diameter_mm, overhang_mm : float
        Tool diameter D and overhang L, mm.

    Returns
    -------
    PredictedJoint

    Warns
    -----
    ExtrapolationWarning
        (D, L) outside the range the models were trained on (also in ``notes``; the interval is widened there).

    Raises
    ------
    InputError
        Missing models or ``uncertainty.json``, an ANFIS predicting a value ≤ 0.
    """
    pred = JointPredictor(models_dir)
    dist = pred.predict([diameter_mm], [overhang_mm])
    notes = [f"{p}: {pred.source[p]}" for p in PARAMS]
    if dist.outside[0] > 0:
        msg = (f"D = {diameter_mm:g} mm, L = {overhang_mm:g} mm lies outside the range the models were trained on "
               f"(D {pred.lo[0]:g}–{pred.hi[0]:g} mm, L {pred.lo[1]:g}–{pred.hi[1]:g} mm): extrapolation, "
               "interval widened")
        warnings.warn(msg, ExtrapolationWarning, stacklevel=2)
        notes.insert(0, msg)
    bad = [p for j, p in enumerate(PARAMS) if not np.isfinite(dist.log10_median[0, j])]
    if bad:
        raise InputError(f"the {bad[0]} model predicts a value ≤ 0 here (over-fitted, or extrapolated too far?)",
                         file=Path(models_dir) / f"{bad[0]}.json")
    q = dist.quantiles([0.05, 0.5, 0.95])[:, 0, :]
    return PredictedJoint(q[1], q[0], q[2], notes)


def predict_frf(source, diameter_mm: float, overhang_mm: float, models_dir, *, holder: str | None = None,
                freq_hz=None) -> PredictedFRF:
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
    PredictedFRF
        The receptance of the median joint and the joint (:func:`predict_joint`).
    """
    joint = predict_joint(models_dir, diameter_mm, overhang_mm)
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
    h = ToolPointModel(tool, sub, sub.freq_hz).tool_point(joint.joint)
    frf = FRF(sub.freq_hz, h, "receptance", f"predicted D{diameter_mm:g} L{overhang_mm:g}")
    return PredictedFRF(frf, joint)
