r"""ANFIS models of the holder–tool joint parameters from a campaign's ``identified.csv``.

:func:`learn` reads ``RESULTS_DIR/identified.csv`` (:mod:`.results`), splits
the ``ok`` rows at random into training and test data, and fits one
:class:`~toolpoint.learning.anfis.ANFIS` model per joint parameter on the inputs
(tool diameter D mm, overhang L mm), as in Čiča et al., section 5 (3×7
Gaussian MFs, linear consequents, 148 training / 30 test sets), plus two
baselines on the same split: a Gaussian process and gradient boosting.

* Targets: kt, ct, kr, cr, each if at least :data:`MIN_RELIABLE` training rows
  and one test row *identified* it (:func:`~toolpoint.identification.params.is_identified`);
  otherwise it is left out with the reason.
* Weighting: every model is trained by weighted least squares with weights
  1/σ², σ the relative standard error of each row's value from its 95 %
  interval (:func:`~toolpoint.identification.params.sigma_ln_from_interval`,
  floored at :data:`SIGMA_FLOOR`); rows without a finite interval are left out.
* Metrics: the paper's four (:data:`~toolpoint.learning.metrics.PAPER_METRICS`)
  on the training and test rows where the target was identified, in the
  target's own SI unit.
* ANFIS fits log10 of the target by default (``log_target``); the baselines
  fit log10 whenever the target is positive.

The pipeline: read rows → split → per target fit ANFIS and baselines → metrics
→ write models, ``split.csv``, ``metrics.json``/``.csv`` and plots. The GP baseline of a
log10 target is saved too (``gp_<target>.json``: training data, per-row noise and fitted kernel
hyper-parameters, from which :func:`~toolpoint.campaign.models.load_gp_models` rebuilds it exactly),
for its predictive standard deviation (``toolpoint library --model gp``). It returns a
:class:`LearnResult`; ``toolpoint campaign learn`` prints it. Why these choices
(weighting, log targets, over-fitting of the 3×7 grid) and what they measured:
``docs/design/campaign.md``.
"""

from __future__ import annotations

import csv
import dataclasses
import json
import math
import warnings
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from ..blas import single_thread_blas
from ..errors import InputError
from ..identification.params import IDENTIFIED_RATIO, PAPER_BOUNDS, PARAMS, UNITS
from ..io.atomic import atomic_open
from ..learning.anfis import ANFIS, predict_quietly
from ..learning.figures import membership_figure, per_sample_figure, regression_figure, save_png
from ..learning.metrics import PAPER_METRICS, paper_metrics
from . import calibration
from .results import FILE_NAME, IdentifiedRows, read_identified

__all__ = [
    "learn", "LearnResult", "overfit_ratio", "PAPER", "PAPER_N_TEST", "INPUTS", "IDENTIFIABLE_SHARE",
    "OVERFIT_RATIO", "MIN_TRAIN", "MIN_RELIABLE", "SIGMA_FLOOR", "GP_FORMAT", "gp_kernel",
]

#: Model inputs: columns of identified.csv, mm.
INPUTS = ("diameter_mm", "overhang_mm")
#: The joint parameter ``toolpoint predict`` cannot do without (the others fall back to a campaign median).
REQUIRED_FOR_PREDICT = "kt"
#: The file in the models folder naming the models one ``learn`` wrote.
MANIFEST = "manifest.json"
#: ``format`` of a saved GP baseline (``gp_<target>.json``; read by :func:`toolpoint.campaign.models.load_gp_models`).
GP_FORMAT = "toolpoint.gp"
#: Damping parameters: learned by default only where the file has their intervals.
DAMPING = ("ct", "cr")
#: Below this share of ok rows with an identified value, a note says how little of the data pins a target down.
IDENTIFIABLE_SHARE = 0.8
#: ANFIS test NRMSE above this multiple of its training NRMSE is reported as over-fitting.
OVERFIT_RATIO = 2.0
#: Extra ok rows needed beyond the test set (the training set must support the grid).
MIN_TRAIN = 10
#: A target needs this many training rows where it was identified.
MIN_RELIABLE = 20
#: Floor of a row's relative standard error in the training weights: below ~1 % the
#: model's own error dominates, and a few very tight rows would otherwise outweigh the rest.
SIGMA_FLOOR = 0.01

#: Čiča et al., section 5: ANFIS test-set results (30 sets); MAPE and max APE in %.
PAPER = {
    "kt": {"nrmse": 0.09427, "afv": 0.99541, "mape": 4.5, "max_ape": 11.8},
    "kr": {"nrmse": 0.08993, "afv": 0.99591, "mape": 0.7, "max_ape": 3.2},
}
#: Number of test sets behind :data:`PAPER`.
PAPER_N_TEST = 30

# learn() keyword of an ANFIS setting whose name differs
_KEYWORD = {"n_mfs": "mfs"}


@dataclass(frozen=True)
class LearnResult:
    """What :func:`learn` did: settings, split, per-target metrics, files written, notes.

    All but the last four attributes are the content of ``models/metrics.json``
    (:meth:`to_dict`; NaN there is ``null``).

    Attributes
    ----------
    source : str
        The ``identified.csv`` read.
    settings : dict
        ``test_size``, ``mfs`` (per input), ``mf``, ``order``, ``epochs``,
        ``step_size``, ``seed``, ``log_target``, ``baselines``, ``identifiable_ratio``,
        ``identifiable_share``.
    inputs : list of str
        Input columns (mm).
    n_rows, n_ok, n_train, n_test : int
        Rows in the file, ok rows, training and test rows of the split.
    n_test_outside_training_range : int
        Test rows outside the training range of D or L.
    targets : list of str
        Targets learned.
    excluded : dict
        Target → why it was left out.
    identifiable_share : dict
        Parameter → share of ok rows where it was identified.
    units : dict
        Target → SI unit.
    metrics : dict
        ``metrics[target][model][set][metric]``: model ``anfis``/``gpr``/``gbr``,
        set ``train``/``test``, metric ``nrmse``, ``afv``, ``mape`` (%), ``max_ape`` (%)
        and ``n``; ``metrics[target]["anfis"]`` also has ``kept_epoch`` and ``overfit``.
    baseline_settings : dict
        Target → baseline → ``log10_target`` and the fitted hyper-parameters.
    best_test_model : dict
        Target → the model with the lowest test MAPE.
    paper : dict
        Target → the paper's test metrics (:data:`PAPER`) and ``n``.
    uncertainty : dict
        Parameter → ``kind`` (``model``/``spread``), ``sigma_log10`` (decades), ``coverage90`` (held-out
        coverage of the 90 % interval, cross-conformal), ``n`` (held-out rows), ``reason``
        (:mod:`.calibration`; saved as ``models/uncertainty.json``).
    files : dict
        What was written: ``uncertainty``, ``split``, ``<target>`` (model JSON), ``gp_<target>`` (the GP
        baseline, log10 targets only), ``<target>_plots``, ``metrics_json``, ``metrics_csv``.
    notes : list of str
        Lines for the user about the data as a whole.
    target_notes : dict
        Target → lines about that target (every target considered, in order).
    models_dir : str
        Folder of the models.
    plots_dir : str or None
        Folder of the plots (None without plots).
    """

    source: str
    settings: dict
    inputs: list
    n_rows: int
    n_ok: int
    n_train: int
    n_test: int
    n_test_outside_training_range: int
    targets: list
    excluded: dict
    identifiable_share: dict
    units: dict
    metrics: dict
    baseline_settings: dict
    best_test_model: dict
    paper: dict
    files: dict
    uncertainty: dict = field(default_factory=dict)
    notes: list = field(default_factory=list)
    target_notes: dict = field(default_factory=dict)
    models_dir: str = ""
    plots_dir: str | None = None

    def to_dict(self) -> dict:
        """The content of ``models/metrics.json`` (NaN kept; :func:`json.dump` of it needs ``_jsonable``)."""
        skip = {"notes", "target_notes", "models_dir", "plots_dir"}
        return {f.name: getattr(self, f.name) for f in dataclasses.fields(self) if f.name not in skip}


@dataclass(frozen=True)
class _Data:
    """The ok rows of identified.csv as arrays."""

    path: Path
    n_rows: int
    ids: list
    X: np.ndarray  # (n, 2) D, L in mm
    values: dict  # target → (n,) SI, NaN where not a number
    share: dict  # parameter → share of rows where identified
    identified: dict  # parameter → (n,) bool
    sigma: dict  # parameter → (n,) relative standard error (floored), inf without an interval
    test_size: int  # held-out rows of the split
    intervals: dict  # parameter → ((n,), (n,)) 95 % interval, SI (NaN where none)
    all_values: dict  # parameter → (n,) SI, NaN where not a number (every parameter in the file)


@dataclass(frozen=True)
class _Fit:
    """One target's models and scores (or why it was left out)."""

    notes: list
    excluded: str | None = None
    model: ANFIS | None = None
    metrics: dict | None = None
    baseline_settings: dict | None = None
    y_test: np.ndarray | None = None
    p_test: np.ndarray | None = None
    gp: dict | None = None  # the fitted GP baseline as saved (gp_<target>.json), log10 targets only


# --------------------------------------------------------------- settings
def _anfis_settings(mfs, mf, order, epochs, step_size, log_target, seed) -> dict:
    """ANFIS keyword arguments, validated by ANFIS itself (InputError naming learn()'s keyword)."""
    try:
        ANFIS(n_mfs=mfs, mf=mf, order=order, epochs=epochs, step_size=step_size).check_params(len(INPUTS))
    except InputError as err:
        raise InputError(err.message, field=_KEYWORD.get(err.field, err.field)) from None
    m = [int(v) for v in np.atleast_1d(mfs)]
    n_mfs = m[0] if len(m) == 1 else tuple(m)
    return dict(n_mfs=n_mfs, mf=mf, order=int(order), epochs=int(epochs), step_size=float(step_size),
                log_target=bool(log_target), input_names=list(INPUTS), random_state=int(seed))


def _check_test_size(test_size) -> None:
    if test_size == "auto":
        return
    if isinstance(test_size, bool) or not isinstance(test_size, (int, np.integer)) or test_size < 1:
        raise InputError(f"must be a whole number ≥ 1 or 'auto', got {test_size!r}", field="test_size")


def auto_test_size(n_ok: int) -> int:
    """The held-out test set of ``test_size="auto"``: the paper's 30 of 178 (17 %), at most 30 rows.

    A fixed 30 starved small campaigns (40 tools left 10 for training); the σ the library samples with comes
    from cross-validation over every tool (:mod:`.calibration`), not from this split.

    Examples
    --------
    >>> auto_test_size(178), auto_test_size(60), auto_test_size(40)
    (30, 10, 7)
    """
    return int(min(PAPER_N_TEST, max(1, round(n_ok * PAPER_N_TEST / 178))))


def _check_targets(targets) -> list[str] | None:
    if targets is None:
        return None
    names = [targets] if isinstance(targets, str) else list(targets)
    for t in names:
        if t not in PARAMS:
            raise InputError(f"unknown target {t!r} (one of {', '.join(PARAMS)})", field="targets")
    if not names or len(set(names)) != len(names):
        raise InputError(f"expected distinct targets from {', '.join(PARAMS)}, got {targets!r}", field="targets")
    return names


# ------------------------------------------------------------------- input
def _read(path: Path, candidates: list[str], explicit: bool, test_size: int) -> _Data:
    """The ok rows (ordered by id) with inputs, targets and their precision; InputError on trouble."""
    required = ["id", *INPUTS, "status", *candidates]
    if not explicit:
        required += [f"{t}_{b}" for t in DAMPING for b in ("lo", "hi")]
    table = read_identified(path, list(dict.fromkeys(required)))
    ok: IdentifiedRows = table.ok()
    if test_size == "auto":
        test_size = auto_test_size(len(ok))
    if len(ok) < test_size + MIN_TRAIN:
        raise InputError(f"{len(ok)} rows with status ok, need at least test_size + {MIN_TRAIN} = "
                         f"{test_size + MIN_TRAIN}", file=path, field="status")
    ids = ok.ids()
    X = np.column_stack([ok.column(c) for c in INPUTS])
    values = {t: ok.column(t, required=False) for t in candidates}
    share, identified, sigma = {}, {}, {}
    for t in PARAMS:
        if table.has_interval(t):
            identified[t] = ok.identified(t)
            share[t] = float(np.mean(identified[t])) if len(ok) else 0.0
            sigma[t] = np.maximum(ok.sigma_ln(t), SIGMA_FLOOR)
    for t in candidates:  # a target that is learned must be a number in every ok row
        ok.check_numbers(t)
    return _Data(path, len(table), ids, X, values, share, identified, sigma, int(test_size),
                 {t: ok.interval(t) for t in PARAMS if table.has_interval(t)},
                 {t: ok.column(t, required=False) for t in PARAMS if ok.has(t)})


def _split(n: int, test_size: int, seed: int) -> tuple[np.ndarray, np.ndarray]:
    """Seeded random split of n rows: sorted (train, test) indices."""
    perm = np.random.default_rng(seed).permutation(n)
    return np.sort(perm[test_size:]), np.sort(perm[:test_size])


# --------------------------------------------------------------- baselines
def _exp10(v):
    return np.power(10.0, v)


def gp_kernel():
    """The GP baseline's kernel before fitting: C · RBF(ARD over the standardised inputs) + white noise.

    Returns
    -------
    sklearn.gaussian_process.kernels.Kernel
        A fitted kernel is this one with its hyper-parameters ``theta`` (what ``gp_<target>.json`` stores).

    Examples
    --------
    >>> gp_kernel().n_dims  # log constant, two length scales, log noise level
    4
    """
    from sklearn.gaussian_process.kernels import RBF, ConstantKernel, WhiteKernel

    rbf = RBF(length_scale=[1.0] * len(INPUTS), length_scale_bounds=(1e-2, 1e2))
    return ConstantKernel(1.0, (1e-3, 1e3)) * rbf + WhiteKernel(1e-3, (1e-10, 1.0))


def _baselines(seed: int, log: bool) -> dict:
    """Unfitted baseline regressors {key: estimator} (target in log10 if ``log``)."""
    from sklearn.compose import TransformedTargetRegressor
    from sklearn.ensemble import GradientBoostingRegressor
    from sklearn.gaussian_process import GaussianProcessRegressor
    from sklearn.pipeline import make_pipeline
    from sklearn.preprocessing import StandardScaler

    gpr = make_pipeline(
        StandardScaler(),
        GaussianProcessRegressor(kernel=gp_kernel(), normalize_y=True, n_restarts_optimizer=3, random_state=seed),
    )
    gbr = GradientBoostingRegressor(random_state=seed)

    def wrap(est):
        return TransformedTargetRegressor(regressor=est, func=np.log10, inverse_func=_exp10) if log else est

    return {"gpr": wrap(gpr), "gbr": wrap(gbr)}


def _weights(y, sigma, log: bool) -> np.ndarray:
    """1/variance of each target value (relative standard errors σ), up to a common factor.

    σ is relative: the absolute error of y is y·σ, that of log10 y is σ/ln 10 (a common factor).
    """
    return 1.0 / sigma**2 if log else 1.0 / (y * sigma) ** 2


def _fit_weighted(key, est, X, y, sigma, log: bool) -> None:
    """Fit a baseline with the same per-row precision as ANFIS: sample weights for gradient
    boosting; for the GP, each row's own noise variance on the kernel diagonal (``alpha``,
    in the units of the normalised target) beside the fitted white noise."""
    if key == "gbr":
        est.fit(X, y, sample_weight=_weights(y, sigma, log))
        return
    var = (sigma / np.log(10)) ** 2 if log else (y * sigma) ** 2
    target = np.log10(y) if log else y
    alpha = var / max(float(np.var(target)), 1e-300)
    name = "regressor__gaussianprocessregressor__alpha" if log else "gaussianprocessregressor__alpha"
    est.set_params(**{name: alpha})
    est.fit(X, y)


def _gp_document(t: str, est, X, y) -> dict:
    """What reproduces a fitted log10-target GP baseline exactly (refit with the kernel fixed):
    training inputs (mm), log10 targets, per-row noise ``alpha`` and the kernel's ``theta``."""
    gpr = est.regressor_.steps[-1][1]
    return {"format": GP_FORMAT, "version": 1, "target": t, "unit": UNITS[t], "inputs": list(INPUTS),
            "log10_target": True, "X_mm": np.asarray(X, float).tolist(), "log10_y": np.log10(y).tolist(),
            "alpha": np.broadcast_to(gpr.alpha, (len(y),)).tolist(), "normalize_y": True,
            "theta": gpr.kernel_.theta.tolist(), "kernel": str(gpr.kernel_)}


def _describe_baseline(key, est) -> str:
    """Fitted hyper-parameters worth recording (GP kernel)."""
    inner = getattr(est, "regressor_", est)
    if key == "gpr":
        return str(inner.steps[-1][1].kernel_)
    return f"{inner.n_estimators_} trees, depth {inner.max_depth}, learning rate {inner.learning_rate}"


# ----------------------------------------------------------------- metrics
def _metrics(y, pred) -> dict:
    out = paper_metrics(y, pred)
    out["n"] = int(len(y))
    return out


def overfit_ratio(test: float, train: float) -> float:
    """Test error / training error, as judged for over-fitting (:data:`OVERFIT_RATIO`).

    Parameters
    ----------
    test, train : float
        The same error measure (e.g. NRMSE) on the test and the training data.

    Returns
    -------
    float
        test/train; inf if the test error is not finite (or the training error is
        0 and the test error is not), 1 if it cannot be judged.

    Examples
    --------
    >>> overfit_ratio(0.3, 0.1), overfit_ratio(float("nan"), 0.1), overfit_ratio(0.2, float("nan"))
    (2.9999999999999996, inf, 1.0)
    """
    if not math.isfinite(test):
        return math.inf
    if not math.isfinite(train):
        return 1.0
    if train <= 0:
        return math.inf if test > 0 else 1.0
    return test / train


def _best_model(scores: dict) -> str | None:
    """The model with the lowest finite test MAPE."""
    scored = {k: v["test"]["mape"] for k, v in scores.items() if math.isfinite(v["test"]["mape"])}
    return min(scored, key=scored.get) if scored else None


# --------------------------------------------------------------- per target
def _fit_target(t: str, data: _Data, train_idx, test_idx, anfis: dict, *, baselines: bool, seed: int) -> _Fit:
    """ANFIS (and the baselines) of one target, and their scores on the rows where it was identified."""
    n_ok = len(data.ids)
    y = data.values[t]
    keep = data.identified.get(t, np.ones(n_ok, bool))
    sig = data.sigma.get(t, np.full(n_ok, SIGMA_FLOOR))
    usable = np.isfinite(sig) & np.isfinite(y)
    # Training: every row with a finite interval, weighted by 1/σ²; scores: only rows where the
    # parameter was identified (the others are not trustworthy targets). See docs/design/campaign.md.
    t_fit = train_idx[usable[train_idx]]
    t_tr, t_te = train_idx[keep[train_idx]], test_idx[keep[test_idx]]
    notes = []
    if keep.sum() < n_ok:
        notes.append(f"{t}: trained on {t_fit.size} rows weighted by 1/σ² from their 95 % intervals "
                     f"({len(train_idx) - t_fit.size} without a finite interval left out); metrics on the "
                     f"{t_tr.size} training and {t_te.size} test rows where it was identified "
                     f"(interval within a factor {IDENTIFIED_RATIO:g})")
    if t_tr.size < MIN_RELIABLE or t_te.size == 0:
        return _Fit(notes, excluded=f"{t}: too few identified rows ({t_tr.size} train, {t_te.size} test)")
    rules = int(np.prod(np.broadcast_to(anfis["n_mfs"], (len(INPUTS),))))
    n_par = rules * (len(INPUTS) + 1 if anfis["order"] == 1 else 1)
    if t_tr.size < n_par:
        notes.append(f"note: {t} was identified in {t_tr.size} training rows, fewer than the {n_par} consequent "
                     f"parameters of {rules} rules: where it was not identified, the model rests on weak rows only")
    Xfit, yfit, sfit = data.X[t_fit], y[t_fit], sig[t_fit]
    Xtr, Xte, ytr, yte = data.X[t_tr], data.X[t_te], y[t_tr], y[t_te]
    if anfis["log_target"] and np.any(yfit <= 0):
        raise InputError("log_target needs positive values", file=data.path, field=t)

    model = ANFIS(**anfis, target_name=t)
    try:
        with single_thread_blas():  # ~150 × 150 matrices: threads only cost
            model.fit(Xfit, yfit, sample_weight=_weights(yfit, sfit, anfis["log_target"]))
    except ValueError as err:
        raise InputError(f"ANFIS training failed: {err}", file=data.path, field=t) from None
    p_tr, _ = predict_quietly(model, Xtr)
    p_te, _ = predict_quietly(model, Xte)  # extrapolation is reported once, as a note
    scores = {"anfis": {"train": _metrics(ytr, p_tr), "test": _metrics(yte, p_te)}}
    scores["anfis"]["kept_epoch"] = int(model.best_epoch_)
    ratio = overfit_ratio(scores["anfis"]["test"]["nrmse"], scores["anfis"]["train"]["nrmse"])
    scores["anfis"]["overfit"] = bool(ratio > OVERFIT_RATIO)

    settings, gp = None, None
    if baselines:
        log = bool(np.all(y > 0))
        settings = {}
        for key, est in _baselines(seed, log).items():
            with warnings.catch_warnings(), single_thread_blas():
                warnings.simplefilter("ignore")  # GP optimiser convergence chatter
                _fit_weighted(key, est, Xfit, yfit, sfit, log)
                b_tr, b_te = est.predict(Xtr), est.predict(Xte)
            scores[key] = {"train": _metrics(ytr, b_tr), "test": _metrics(yte, b_te)}
            settings[key] = {"log10_target": log, "fitted": _describe_baseline(key, est)}
            if key == "gpr" and log:
                gp = _gp_document(t, est, Xfit, yfit)
        if not log:
            notes.append(f"{t}: not all values > 0, so its GP baseline fits {t} itself and is not saved "
                         "(the library's GP option needs a log-normal joint)")
    return _Fit(notes, model=model, metrics=scores, baseline_settings=settings, y_test=yte, p_test=p_te, gp=gp)


# ------------------------------------------------------------- uncertainty
def _clip_log10(data: _Data, t: str) -> tuple[float, float]:
    """log10 of the physically plausible range of ``t``: the paper's search bounds, widened to every value and
    interval the campaign found (a campaign may search wider). ``library`` narrows it to the campaign's own search
    bounds. Not the range of the values found: a tool beyond the campaign's tools may lie beyond them too."""
    lo, hi = PAPER_BOUNDS[t]
    v = [data.all_values.get(t, np.array([])), np.array([lo, hi], float)]
    if t in data.intervals:
        v += list(data.intervals[t])
    v = np.concatenate(v)
    v = v[np.isfinite(v) & (v > 0)]
    return float(np.log10(v.min())), float(np.log10(v.max()))


def _cross_validate(t: str, data: _Data, anfis: dict, folds: int, seed: int):
    """Held-out log10 residuals of ``t``: every ok row predicted by an ANFIS (same settings, same weighting)
    trained on the other folds; only rows where ``t`` was identified are scored.

    Returns (X, residual, fold, fold → training inputs) or None when a fold cannot be trained."""
    n = len(data.ids)
    y = data.values[t]
    keep = data.identified.get(t, np.ones(n, bool))
    sig = data.sigma.get(t, np.full(n, SIGMA_FLOOR))
    usable = np.isfinite(sig) & np.isfinite(y) & (y > 0 if anfis["log_target"] else True)
    fold = calibration.fold_ids(n, folds, seed)
    res = np.full(n, np.nan)
    trained = {}
    for k in range(folds):
        fit = usable & (fold != k)
        test = keep & (fold == k) & np.isfinite(y) & (y > 0)
        if not test.any():
            continue
        if fit.sum() < 3 or np.any(np.ptp(data.X[fit], axis=0) == 0):
            return None
        model = ANFIS(**anfis, target_name=t)
        try:
            with single_thread_blas(), warnings.catch_warnings():
                warnings.simplefilter("ignore")
                model.fit(data.X[fit], y[fit], sample_weight=_weights(y[fit], sig[fit], anfis["log_target"]))
        except ValueError:
            return None
        pred, _ = predict_quietly(model, data.X[test])
        with np.errstate(divide="ignore", invalid="ignore"):
            res[test] = np.log10(y[test]) - np.log10(np.where(pred > 0, pred, np.nan))
        trained[k] = data.X[fit]
    scored = np.isfinite(res)
    # a prediction ≤ 0 of a positive parameter is an infinitely wrong prediction, not a missing one
    bad = keep & np.isfinite(y) & (y > 0) & ~scored & np.isin(fold, list(trained))
    res[bad] = np.inf
    rows = scored | bad
    return data.X[rows], res[rows], fold[rows], trained


def _cross_validate_power_law(t: str, data: _Data, folds: int, seed: int):
    """Held-out log10 residuals of the family's power law in (D, L), fitted to identified rows only."""
    n = len(data.ids)
    y = data.values.get(t, data.all_values.get(t))
    keep = data.identified.get(t, np.ones(n, bool)) & np.isfinite(y) & (y > 0)
    fold = calibration.fold_ids(n, folds, seed)
    res = np.full(n, np.nan)
    trained = {}
    for k in range(folds):
        fit, test = keep & (fold != k), keep & (fold == k)
        if not test.any():
            continue
        if fit.sum() < 5:
            return None
        coef = calibration.fit_power_law(data.X[fit], np.log10(y[fit]))
        res[test] = np.log10(y[test]) - calibration.power_law(coef, data.X[test])
        trained[k] = data.X[fit]
    rows = np.isfinite(res)
    return data.X[rows], res[rows], fold[rows], trained, keep


def _cross_validate_neighbours(t: str, data: _Data, folds: int, seed: int):
    """Held-out log10 residuals of the local campaign value: median of the nearest identified tools."""
    n = len(data.ids)
    y = data.all_values.get(t)
    keep = data.identified.get(t, np.zeros(n, bool)) & np.isfinite(y) & (y > 0)
    if keep.sum() < 2 * calibration.K_LOCAL:
        return None
    fold = calibration.fold_ids(n, folds, seed)
    res = np.full(n, np.nan)
    trained = {}
    lo, hi = data.X.min(axis=0), data.X.max(axis=0)
    for k in range(folds):
        fit, test = keep & (fold != k), keep & (fold == k)
        if not test.any():
            continue
        m = calibration.local_median(data.X[test], data.X[fit], np.log10(y[fit]), lo, hi)
        res[test] = np.log10(y[test]) - m
        trained[k] = data.X[fit]
    rows = np.isfinite(res)
    return data.X[rows], res[rows], fold[rows], trained, keep


def _uncertainty(data: _Data, fits: dict, train_idx, anfis: dict, folds: int, seed: int) -> dict:
    """Parameter → :class:`~.calibration.ParameterUncertainty`.

    A parameter identified in at least :data:`IDENTIFIABLE_SHARE` of the ok rows takes the predictor with the
    lower cross-validated error — its ANFIS or the family's power law in (D, L) (an over-fitted ANFIS loses to
    it) — with the σ its held-out residuals calibrate; one rarely identified, or not learned, takes the
    campaign's spread."""
    out = {}
    n = len(data.ids)
    for t in PARAMS:
        values = data.all_values.get(t)
        if values is None:
            continue
        clip = _clip_log10(data, t)
        share = data.share.get(t, 1.0)
        if share >= IDENTIFIABLE_SHARE:
            options = []
            if t in fits:
                cv = _cross_validate(t, data, anfis, folds, seed)
                if cv is not None:
                    X, r, fold, trained = cv
                    usable = np.isfinite(data.sigma.get(t, np.full(n, SIGMA_FLOOR))) & np.isfinite(values)
                    t_fit = train_idx[usable[train_idx]]
                    rng = fits[t].model.input_range_
                    options.append(calibration.fit_uncertainty(
                        t, X, r, fold, trained, data.X[t_fit], rng[:, 0], rng[:, 1], clip, values,
                        what=f"ANFIS {'x'.join(map(str, np.broadcast_to(anfis['n_mfs'], (2,))))}"))
            cv = _cross_validate_power_law(t, data, folds, seed)
            if cv is not None:
                X, r, fold, trained, keep = cv
                coef = calibration.fit_power_law(data.X[keep], np.log10(values[keep]))
                Xk = data.X[keep]
                options.append(calibration.fit_uncertainty(
                    t, X, r, fold, trained, Xk, Xk.min(axis=0), Xk.max(axis=0), clip, values, kind="powerlaw",
                    coef=coef, what=f"power law {t} ∝ D^{coef[1]:.2f} L^{coef[2]:.2f} (ANFIS: see its own row)"
                    if t in fits else f"power law {t} ∝ D^{coef[1]:.2f} L^{coef[2]:.2f}"))
            learned = [u for u in options if u.kind != "spread"]
            if learned:
                best = min(learned, key=lambda u: u.cv["rms_log10"])
                if len(options) > 1:
                    other = [u for u in options if u is not best][0]
                    best = dataclasses.replace(best, reason=best.reason + (
                        f"; chosen over the {'power law' if best.kind == 'model' else 'ANFIS'} (held-out RMS "
                        f"{best.cv['rms_log10']:.3g} vs {other.cv.get('rms_log10', math.nan):.3g} decades)"))
                out[t] = best
                continue
            if options:
                out[t] = options[0]
                continue
            why = "too few identified rows to cross-validate a model"
        else:
            why = (f"identified in only {100 * share:.0f} % of the ok rows (< {100 * IDENTIFIABLE_SHARE:.0f} %): "
                   "a model would extrapolate what the campaign did not measure" if t in data.share else
                   "no intervals to judge it by")
            cv = _cross_validate_neighbours(t, data, folds, seed) if t in data.share else None
            if cv is not None:
                X, r, fold, trained, keep = cv
                Xk = data.X[keep]
                out[t] = calibration.fit_uncertainty(  # edge and outside: of the tools that identified it
                    t, X, r, fold, trained, Xk, Xk.min(axis=0), Xk.max(axis=0), clip, values,
                    kind="neighbours", y_log10=np.log10(values[keep]),
                    what=f"local campaign value (median of the {calibration.K_LOCAL} nearest of the "
                         f"{int(keep.sum())} tools that identified it; {why})")
                continue
        try:
            out[t] = calibration.spread_uncertainty(t, values, clip, f"campaign spread: {why}")
        except InputError as err:
            raise InputError(err.message, file=data.path, field=t) from None
    for t in out:  # the side the nearby FRFs bound, where they bound only one (calibration module docstring)
        if t in data.intervals:
            lower, upper = calibration.one_sided_bounds(*data.intervals[t])
            if np.isfinite(lower).any() or np.isfinite(upper).any():
                n_lo, n_hi = int(np.isfinite(lower).sum()), int(np.isfinite(upper).sum())
                why = (f"; truncated where the nearest tools' FRFs bound it on one side ({n_lo} of {len(lower)} tools "
                       f"bound it below only, {n_hi} above only)")
                out[t] = dataclasses.replace(out[t], window_X=tuple(map(tuple, data.X.tolist())),
                                             window_lo=tuple(lower.tolist()), window_hi=tuple(upper.tolist()),
                                             reason=out[t].reason + why)
    return out


# ------------------------------------------------------------------ output
def _writing(path: Path, what: str = "cannot write"):
    """InputError for an OSError while writing ``path``."""

    def error(err: OSError) -> InputError:
        return InputError(f"{what}: {err.strerror or err}", file=path)

    return error


def _check_folders(models_dir: Path, plots_dir: Path | None) -> None:
    for d in (models_dir, plots_dir):
        if d is not None and d.exists() and not d.is_dir():
            raise InputError("exists and is not a folder", file=d)


def _write_manifest(models_dir: Path, learned: list[str], gps: list[str]) -> None:
    """``manifest.json``: the models this run wrote (what ``predict`` uses: ANFIS under ``models``, the
    saved GP baselines under ``gp``); model files of other parameters, left by an earlier run on other
    data or targets, are removed so none is used stale."""
    with atomic_open(models_dir / MANIFEST, "w", encoding="utf-8") as fh:
        json.dump({"format": "toolpoint.models", "version": 1, "models": {t: f"{t}.json" for t in learned},
                   "gp": {t: f"gp_{t}.json" for t in gps}}, fh, indent=1)
    for t in PARAMS:
        if t not in learned:
            (models_dir / f"{t}.json").unlink(missing_ok=True)
        if t not in gps:
            (models_dir / f"gp_{t}.json").unlink(missing_ok=True)


def _write_split(path: Path, ids: list, test_idx) -> None:
    is_test = np.zeros(len(ids), dtype=bool)
    is_test[test_idx] = True
    try:
        with atomic_open(path, "w", newline="", encoding="utf-8") as fh:
            w = csv.writer(fh)
            w.writerow(["id", "set"])
            for i, t in zip(ids, is_test):
                w.writerow([i, "test" if t else "train"])
    except OSError as err:
        raise _writing(path)(err) from None


def _save_model(model: ANFIS, path: Path) -> None:
    try:
        model.save(path)
    except OSError as err:
        raise _writing(path)(err) from None


def _plot_paths(t: str, plots_dir: Path) -> tuple[Path, Path, Path]:
    """Per-sample, regression and membership figure paths of target ``t``."""
    return tuple(plots_dir / f"anfis_{t}_{kind}.png" for kind in ("test", "regression", "membership"))


def _write_plots(t: str, fit: _Fit, plots_dir: Path) -> list[str]:
    """The test-set figures of one target (Čiča et al. Figs. 6/7 and 8) and its MFs."""
    label = f"{t} [{UNITS[t]}]"
    test, regression, membership = _plot_paths(t, plots_dir)
    figures = {
        test: per_sample_figure(fit.y_test, fit.p_test, label, f"{t}: experimental vs ANFIS, test data"),
        regression: regression_figure(fit.y_test, fit.p_test, label, f"{t}, test data"),
        membership: membership_figure(fit.model, title=f"{t}: ANFIS membership functions",
                                      input_names=["tool diameter D [mm]", "overhang L [mm]"]),
    }
    try:
        for path, fig in figures.items():
            save_png(fig, path)
    except OSError as err:
        raise _writing(plots_dir, "cannot write plots")(err) from None
    return [str(p) for p in figures]


def _jsonable(obj):
    """NaN → None, NumPy → Python, tuples → lists, recursively."""
    if isinstance(obj, dict):
        return {str(k): _jsonable(v) for k, v in obj.items()}
    if isinstance(obj, (list, tuple)):
        return [_jsonable(v) for v in obj]
    if isinstance(obj, np.generic):
        obj = obj.item()
    if isinstance(obj, float) and not math.isfinite(obj):
        return None
    return obj


def _write_metrics(result: LearnResult, json_path: Path, csv_path: Path) -> None:
    """``metrics.json`` (everything but the notes) and ``metrics.csv`` (target × model × set)."""
    keys = list(PAPER_METRICS)

    def cell(v):
        return repr(v) if math.isfinite(v) else ""

    try:
        with atomic_open(json_path, "w", encoding="utf-8") as fh:
            json.dump(_jsonable(result.to_dict()), fh, indent=1, ensure_ascii=False, allow_nan=False)
            fh.write("\n")
        with atomic_open(csv_path, "w", newline="", encoding="utf-8") as fh:
            w = csv.writer(fh)
            w.writerow(["target", "unit", "model", "set", "n", *keys])
            for t, res in result.metrics.items():
                for key, sets in res.items():
                    for s in ("train", "test"):
                        w.writerow([t, UNITS[t], key, s, sets[s]["n"], *(cell(sets[s][k]) for k in keys)])
                if t in PAPER:
                    w.writerow([t, UNITS[t], "paper", "test", PAPER_N_TEST, *(repr(PAPER[t][k]) for k in keys)])
    except OSError as err:
        raise _writing(json_path.parent)(err) from None


# -------------------------------------------------------------------- main
def learn(
    results_dir,
    *,
    test_size="auto",
    cv_folds=calibration.CV_FOLDS,
    mfs=(3, 7),
    mf="gauss",
    order=1,
    epochs=200,
    step_size=0.01,
    seed=0,
    targets=None,
    log_target=True,
    baselines=True,
    plots=True,
) -> LearnResult:
    """Train ANFIS (and baseline) models of the joint parameters on a campaign's results.

    Parameters
    ----------
    results_dir : path-like
        Folder holding ``identified.csv``; models go to ``results_dir/models``,
        plots to ``results_dir/plots``.
    test_size : int or "auto", default "auto"
        Ok rows held out for the test metrics (paper: 30 of 178); ``"auto"``: :func:`auto_test_size`.
    cv_folds : int, default 5
        Folds of the cross-validation over every ok row that calibrates each parameter's predictive σ
        (``models/uncertainty.json``, :mod:`.calibration`).
    mfs : int or (int, int), default (3, 7)
        MFs per input (D, L): ANFIS ``n_mfs``.
    mf, order, epochs, step_size : ANFIS settings
        :class:`~toolpoint.learning.anfis.ANFIS` ``mf``, ``order``, ``epochs``,
        ``step_size`` (mm, the inputs' unit).
    seed : int, default 0
        Seed of the random split (``numpy.random.default_rng``) and of the baselines.
    targets : list of str, optional
        Parameters to learn (default: kt, ct, kr, cr where identifiable).
    log_target : bool, default True
        ANFIS fits log10 of each target (False: the target itself, as the paper).
    baselines : bool, default True
        Also fit the GP and gradient-boosting baselines.
    plots : bool, default True
        Write the PNG plots.

    Returns
    -------
    LearnResult
        Metrics in the targets' SI units (NaN where undefined), files written, notes.

    Raises
    ------
    InputError
        Missing ``identified.csv`` or column, a non-number in an ok row, fewer
        than ``test_size + 10`` ok rows, a bad setting (``field`` is the
        keyword), or an output that cannot be written.

    Examples
    --------
    >>> r = learn("results", mfs=(3, 3))  # doctest: +SKIP
    >>> r.metrics["kt"]["anfis"]["test"]["mape"]  # doctest: +SKIP
    """
    _check_test_size(test_size)
    if isinstance(cv_folds, bool) or not isinstance(cv_folds, (int, np.integer)) or cv_folds < 2:
        raise InputError(f"must be a whole number ≥ 2, got {cv_folds!r}", field="cv_folds")
    anfis = _anfis_settings(mfs, mf, order, epochs, step_size, log_target, seed)
    explicit = _check_targets(targets)
    results_dir = Path(results_dir)
    path = results_dir / FILE_NAME
    models_dir, plots_dir = results_dir / "models", (results_dir / "plots" if plots else None)
    candidates = explicit if explicit is not None else list(PARAMS)

    data = _read(path, candidates, explicit is not None, test_size)
    train_idx, test_idx = _split(len(data.ids), data.test_size, seed)
    _check_inputs(data, train_idx, explicit)
    _check_folders(models_dir, plots_dir)
    fitted = _fit_all(data, candidates, train_idx, test_idx, anfis, baselines=baselines, seed=int(seed))
    with single_thread_blas():
        unc = _uncertainty(data, fitted.fits, train_idx, anfis, int(cv_folds), int(seed))
    settings = {"test_size": data.test_size, "mfs": list(np.broadcast_to(anfis["n_mfs"], (len(INPUTS),)).tolist()),
                "mf": mf, "order": anfis["order"], "epochs": anfis["epochs"], "step_size": anfis["step_size"],
                "seed": int(seed), "log_target": anfis["log_target"], "baselines": bool(baselines),
                "identifiable_ratio": IDENTIFIED_RATIO, "identifiable_share": IDENTIFIABLE_SHARE,
                "cv_folds": int(cv_folds)}
    result = _result(data, candidates, train_idx, test_idx, fitted, unc, settings, models_dir, plots_dir)
    # everything is fitted: only now write, so that a failure above leaves the folder as it was
    _write_all(result, data, test_idx, fitted.fits, unc, models_dir, plots_dir)
    return result


@dataclass(frozen=True)
class _Fitted:
    """Every target's fit, by what learn() reports of it."""

    fits: dict  # target → _Fit (learned only)
    target_notes: dict
    excluded: dict
    metrics: dict
    baseline_settings: dict
    best: dict


def _check_inputs(data: _Data, train_idx, explicit) -> None:
    for i, name in enumerate(INPUTS):
        if np.ptp(data.X[train_idx, i]) == 0:
            raise InputError("constant in the training data; a grid partition needs a range", file=data.path,
                             field=name)
    if explicit is not None and REQUIRED_FOR_PREDICT not in explicit:
        raise InputError(f"must include {REQUIRED_FOR_PREDICT}: `toolpoint predict` needs a {REQUIRED_FOR_PREDICT} "
                         f"model (got {', '.join(explicit)})", field="targets")


def _fit_all(data: _Data, candidates, train_idx, test_idx, anfis: dict, *, baselines: bool, seed: int) -> _Fitted:
    """ANFIS (and baselines) of every candidate target; InputError when kt cannot be learned."""
    out = _Fitted({}, {}, {}, {}, {}, {})
    for t in candidates:
        fit = _fit_target(t, data, train_idx, test_idx, anfis, baselines=baselines, seed=seed)
        out.target_notes[t] = fit.notes
        if fit.excluded is not None:
            out.excluded[t] = fit.excluded
            continue
        out.fits[t] = fit
        if fit.baseline_settings is not None:
            out.baseline_settings[t] = fit.baseline_settings
        out.metrics[t] = fit.metrics
        if _best_model(fit.metrics) is not None:
            out.best[t] = _best_model(fit.metrics)
    if REQUIRED_FOR_PREDICT not in out.fits:
        why = out.excluded.get(REQUIRED_FOR_PREDICT, "not among the targets")
        raise InputError(f"no {REQUIRED_FOR_PREDICT} model could be learned ({why}); `toolpoint predict` needs one, "
                         "so nothing was written", file=data.path, field=REQUIRED_FOR_PREDICT)
    return out


def _result(data: _Data, candidates, train_idx, test_idx, fitted: _Fitted, unc: dict, settings: dict,
            models_dir: Path, plots_dir: Path | None) -> LearnResult:
    """The :class:`LearnResult` of a finished fit: notes, files to write, metrics, uncertainty."""
    Xtr, Xte = data.X[train_idx], data.X[test_idx]
    notes = [f"note: only {100 * data.share[t]:.0f} % of the ok rows have a narrow 95 % interval for {t} "
             "(the FRF hardly depends on it elsewhere); weighted training keeps the rest from dominating, "
             "and the test metrics use the identified rows only"
             for t in candidates if t in data.share and data.share[t] < IDENTIFIABLE_SHARE]
    outside = int(np.sum(np.any((Xte < Xtr.min(axis=0)) | (Xte > Xtr.max(axis=0)), axis=1)))
    if outside:
        notes.append(f"note: {outside} of {len(test_idx)} test samples lie outside the training range of D, L "
                     "(models extrapolate there)")
    learned = [t for t in candidates if t in fitted.metrics]
    files = {"split": str(models_dir / "split.csv")}
    for t, fit in fitted.fits.items():
        files[t] = str(models_dir / f"{t}.json")
        if fit.gp is not None:
            files[f"gp_{t}"] = str(models_dir / f"gp_{t}.json")
        if plots_dir is not None:
            files[f"{t}_plots"] = [str(p) for p in _plot_paths(t, plots_dir)]
    files["uncertainty"] = str(models_dir / calibration.FILE_NAME)
    files["metrics_json"] = str(models_dir / "metrics.json")
    files["metrics_csv"] = str(models_dir / "metrics.csv")
    return LearnResult(
        source=str(data.path), settings=settings, inputs=list(INPUTS), n_rows=data.n_rows, n_ok=len(data.ids),
        n_train=int(len(train_idx)), n_test=int(len(test_idx)), n_test_outside_training_range=outside,
        targets=learned, excluded=fitted.excluded, identifiable_share=data.share,
        units={t: UNITS[t] for t in learned}, metrics=fitted.metrics, baseline_settings=fitted.baseline_settings,
        best_test_model=fitted.best, paper={t: dict(PAPER[t], n=PAPER_N_TEST) for t in candidates if t in PAPER},
        files=files,
        uncertainty={t: {"kind": u.kind, "sigma_log10": u.sigma_log10, "coverage90": u.cv.get("coverage90", math.nan),
                         "n": u.cv.get("n", 0), "reason": u.reason} for t, u in unc.items()},
        notes=notes, target_notes=fitted.target_notes, models_dir=str(models_dir),
        plots_dir=None if plots_dir is None else str(plots_dir),
    )


def _write_all(result: LearnResult, data: _Data, test_idx, fits: dict, unc: dict, models_dir: Path,
               plots_dir: Path | None) -> None:
    """Split, models, GP baselines, plots, uncertainty, metrics and the manifest (each file atomically)."""
    _write_split(models_dir / "split.csv", data.ids, test_idx)
    for t, fit in fits.items():
        _save_model(fit.model, models_dir / f"{t}.json")
        if fit.gp is not None:
            try:
                with atomic_open(models_dir / f"gp_{t}.json", "w", encoding="utf-8") as fh:
                    json.dump(fit.gp, fh, allow_nan=False)
            except OSError as err:
                raise _writing(models_dir / f"gp_{t}.json")(err) from None
        if plots_dir is not None:
            _write_plots(t, fit, plots_dir)
    try:
        calibration.write_uncertainty(models_dir / calibration.FILE_NAME, unc)
    except OSError as err:
        raise _writing(models_dir / calibration.FILE_NAME)(err) from None
    _write_metrics(result, models_dir / "metrics.json", models_dir / "metrics.csv")
    _write_manifest(models_dir, result.targets, [t for t, fit in fits.items() if fit.gp is not None])
