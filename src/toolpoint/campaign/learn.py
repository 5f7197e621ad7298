r"""``toolpoint campaign learn`` — ANFIS joint-parameter models from a campaign.

Reads ``RESULTS_DIR/identified.csv`` (written by ``toolpoint campaign run``:
one identified holder–tool joint per tool assembly), splits the successfully
identified assemblies at random into training and test data, and fits one
:class:`~toolpoint.learning.anfis.ANFIS` model per joint parameter with the inputs
(tool diameter D, overhang L), as in Čiča et al., section 5 (3×7 Gaussian MFs,
linear consequents, 21 rules, 148 training / 30 test sets).

Targets
    All four joint parameters, each if at least :data:`MIN_RELIABLE` training
    rows and one test row identified it (95 % interval with hi/lo ≤
    :data:`IDENTIFIABLE_RATIO`); otherwise it is left out with a message, and
    ``toolpoint predict`` takes that parameter's campaign median instead. In
    the synthetic campaign cr is left out (identified for 2 % of the tools).
    An explicit ``targets`` list is checked the same way.

Weighting
    Identified values differ in precision by orders of magnitude: kr is pinned
    to a few % for slender tools and hardly at all for stubby ones, whose FRF
    is dominated by the holder. Each row's relative standard error σ follows
    from its 95 % interval, σ = ln(hi/lo)/(2·1.96) (floored at
    :data:`SIGMA_FLOOR`), and every model is trained by weighted least squares
    with weights 1/σ² (ANFIS ``sample_weight``; gradient boosting likewise; the
    GP takes σ² as each row's noise variance). Rows without a finite interval
    are left out. Training only on the identified rows instead leaves whole
    regions of the (D, L) plane empty (kr: no row with D ≥ 20 mm in the
    synthetic campaign) and the model extrapolates there — measured: a 3×7
    ANFIS predicting kr ≤ 0 for 17 of 30 test tools. The metrics are computed
    on the identified rows only (interval within :data:`IDENTIFIABLE_RATIO`),
    the only targets worth comparing with.

Target scale
    By default ANFIS fits log10 of each target (``--linear-target`` for the
    paper's linear fit). Joint parameters are positive and span decades over
    the family; a linear fit can go ≤ 0 between sparse data — measured on the
    synthetic campaign (seed 0, with the rows still split in file order) with
    the paper's 3×7 grid: one of 30 test tools got a negative ct and no FRF,
    none with log10 (and kt test MAPE 0.32 % against 0.28 %, the same).

Metrics
    The paper's four on the training and the test data: NRMSE, AFV, MAPE %
    and max APE % (:mod:`toolpoint.learning.metrics`), always in the target's own unit
    (with ``log_target`` the predictions are transformed back first). The
    paper's test numbers for kt and kr are printed beside ours.

Baselines (same split, same metrics)
    * ``gpr`` — :class:`~sklearn.gaussian_process.GaussianProcessRegressor`,
      kernel C·RBF(ℓ_D, ℓ_L) + White (one length scale per input, fitted
      noise), ``normalize_y``, inputs standardised, 3 optimiser restarts.
    * ``gbr`` — :class:`~sklearn.ensemble.GradientBoostingRegressor`
      (scikit-learn defaults, ``random_state=seed``).

    Both fit log10 of the target (stiffnesses span decades, and the metrics
    that matter most here are relative); if a target has a value ≤ 0 they fit
    it as is. They show whether ANFIS is the right choice for the data at hand.

Over-fitting
    A 3×7 grid has 21 rules × 3 linear consequents = 63 parameters plus the
    MFs; on ~150 scattered (D, L) points some rules see few samples, and the
    hybrid learning keeps the epoch with the lowest *training* error (the test
    data are never used for model selection). When the ANFIS test NRMSE
    exceeds :data:`OVERFIT_RATIO` × its training NRMSE a warning is printed and
    ``metrics[target]["anfis"]["overfit"]`` is true; the baselines show what
    the data allow.

Outputs (every file written atomically)
    ``models/split.csv``      id, set (train/test) of each ok row, ordered by id
    ``models/<target>.json``  the ANFIS model (:meth:`ANFIS.load`)
    ``models/metrics.json``   everything :func:`learn` returns
    ``models/metrics.csv``    one row per target × model × data set
    ``plots/anfis_<target>_test.png``        target and prediction per test sample (Figs. 6/7)
    ``plots/anfis_<target>_regression.png``  prediction vs target, fitted line, R (Fig. 8)
    ``plots/anfis_<target>_membership.png``  the trained membership functions
"""

from __future__ import annotations

import csv
import json
import math
import warnings
from pathlib import Path

import numpy as np

from ..learning.anfis import ANFIS, MF_PARAMS
from ..io.atomic import atomic_open
from ..cli.anfis import PAPER_METRICS, _plot_membership, _plot_per_sample, _plot_regression, _predict_quietly
from ..errors import InputError

__all__ = ["learn", "add_arguments", "run_cli", "PAPER", "IDENTIFIABLE_RATIO", "IDENTIFIABLE_SHARE"]

INPUTS = ("diameter_mm", "overhang_mm")
ALL_TARGETS = ("kt", "ct", "kr", "cr")
DAMPING = ("ct", "cr")
UNITS = {"kt": "N/m", "ct": "N s/m", "kr": "N m/rad", "cr": "N m s/rad"}
#: A 95 % interval is "narrow" if hi/lo ≤ this ratio …
IDENTIFIABLE_RATIO = 2.0
#: … and below this share of ok rows with one, learn() says how little of the data pins it down.
IDENTIFIABLE_SHARE = 0.8
#: ANFIS test NRMSE above this multiple of its training NRMSE is reported as over-fitting.
OVERFIT_RATIO = 2.0
#: Extra ok rows needed beyond the test set (the training set must support the grid).
MIN_TRAIN = 10
#: A target needs this many training rows where it was identified (narrow interval).
MIN_RELIABLE = 20
#: Floor of a row's relative standard error in the training weights: below ~1 % the
#: model's own error dominates, and a few very tight rows would otherwise outweigh the rest.
SIGMA_FLOOR = 0.01

#: Keys of the metrics (JSON/CSV/return value) → (column title, function). MAPE and max APE in %.
METRICS = {key: (title, fn) for key, (title, fn) in zip(("nrmse", "afv", "mape", "max_ape"), PAPER_METRICS)}

#: Čiča et al., section 5: ANFIS test-set results (30 sets).
PAPER = {
    "kt": {"nrmse": 0.09427, "afv": 0.99541, "mape": 4.5, "max_ape": 11.8},
    "kr": {"nrmse": 0.08993, "afv": 0.99591, "mape": 0.7, "max_ape": 3.2},
}
PAPER_N_TEST = 30

MODEL_LABELS = {"anfis": "ANFIS", "gpr": "GP regression", "gbr": "gradient boosting", "paper": "Čiča et al. ANFIS"}


# -------------------------------------------------------------------- input
def _read_identified(path: Path, required: list[str]):
    """Rows of identified.csv as dicts (plus their line numbers); InputError on trouble."""
    if not path.is_file():
        raise InputError("file not found (run 'toolpoint campaign run' first)", file=path)
    try:
        with open(path, newline="", encoding="utf-8-sig") as fh:
            reader = csv.DictReader(fh)
            header = [h.strip() for h in (reader.fieldnames or [])]
            reader.fieldnames = header
            rows = [(reader.line_num, row) for row in reader]
    except (OSError, UnicodeDecodeError, csv.Error) as err:
        raise InputError(f"cannot read CSV: {err}", file=path) from None
    if not header:
        raise InputError("empty file (no header row)", file=path)
    for name in required:
        if name not in header:
            raise InputError(f"no such column (columns: {', '.join(header)})", file=path, field=name)
    return rows


def _number(path, line, row, name, *, required=True) -> float:
    cell = (row.get(name) or "").strip()
    try:
        v = float(cell)
    except ValueError:
        if required:
            raise InputError(f"line {line}: {cell!r} is not a number (status ok)", file=path, field=name) from None
        return math.nan
    if not math.isfinite(v):
        if required:
            raise InputError(f"line {line}: {cell!r} is not a finite number (status ok)", file=path, field=name)
        return math.nan
    return v


def _check_settings(test_size, mfs, mf, order, epochs, step_size, targets):
    if isinstance(test_size, bool) or not isinstance(test_size, (int, np.integer)) or test_size < 1:
        raise InputError(f"must be a whole number ≥ 1, got {test_size!r}", field="test_size")
    m = [mfs] if isinstance(mfs, (int, np.integer)) else list(mfs)
    if len(m) not in (1, len(INPUTS)) or not all(isinstance(v, (int, np.integer)) and not isinstance(v, bool) for v in m):
        raise InputError(f"expected one whole number or one per input ({', '.join(INPUTS)}), got {mfs!r}", field="mfs")
    if min(m) < 2:
        raise InputError("each input needs at least 2 membership functions", field="mfs")
    if mf not in MF_PARAMS:
        raise InputError(f"must be one of {', '.join(MF_PARAMS)}, got {mf!r}", field="mf")
    if isinstance(order, bool) or order not in (0, 1):
        raise InputError(f"must be 0 (constant) or 1 (linear), got {order!r}", field="order")
    if isinstance(epochs, bool) or not isinstance(epochs, (int, np.integer)) or epochs < 1:
        raise InputError(f"must be a whole number ≥ 1, got {epochs!r}", field="epochs")
    if not (isinstance(step_size, (int, float)) and math.isfinite(step_size) and step_size > 0):
        raise InputError(f"must be a positive number, got {step_size!r}", field="step_size")
    n_mfs = int(m[0]) if len(m) == 1 else tuple(int(v) for v in m)
    if targets is None:
        return n_mfs, None
    names = [targets] if isinstance(targets, str) else list(targets)
    for t in names:
        if t not in ALL_TARGETS:
            raise InputError(f"unknown target {t!r} (one of {', '.join(ALL_TARGETS)})", field="targets")
    if not names or len(set(names)) != len(names):
        raise InputError(f"expected distinct targets from {', '.join(ALL_TARGETS)}, got {targets!r}", field="targets")
    return n_mfs, names


# ---------------------------------------------------------------- baselines
def _one_thread():
    """Single-threaded BLAS while fitting: the matrices are ~150 × 150, where
    threads only cost (and oversubscribe a machine running several jobs)."""
    from threadpoolctl import threadpool_limits

    return threadpool_limits(limits=1, user_api="blas")


def _exp10(v):
    return np.power(10.0, v)


def _baselines(seed: int, log: bool):
    """Unfitted baseline regressors {key: estimator} (target in log10 if ``log``)."""
    from sklearn.compose import TransformedTargetRegressor
    from sklearn.ensemble import GradientBoostingRegressor
    from sklearn.gaussian_process import GaussianProcessRegressor
    from sklearn.gaussian_process.kernels import RBF, ConstantKernel, WhiteKernel
    from sklearn.pipeline import make_pipeline
    from sklearn.preprocessing import StandardScaler

    kernel = ConstantKernel(1.0, (1e-3, 1e3)) * RBF(length_scale=[1.0] * len(INPUTS), length_scale_bounds=(1e-2, 1e2)) + WhiteKernel(
        1e-3, (1e-10, 1.0)
    )
    gpr = make_pipeline(
        StandardScaler(),
        GaussianProcessRegressor(kernel=kernel, normalize_y=True, n_restarts_optimizer=3, random_state=seed),
    )
    gbr = GradientBoostingRegressor(random_state=seed)

    def wrap(est):
        return TransformedTargetRegressor(regressor=est, func=np.log10, inverse_func=_exp10) if log else est

    return {"gpr": wrap(gpr), "gbr": wrap(gbr)}


def _weights(y, sigma, log: bool) -> np.ndarray:
    """1/variance of each target value (relative standard errors σ), up to a common factor."""
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


def _describe_baseline(key, est) -> str:
    """Fitted hyper-parameters worth recording (GP kernel)."""
    inner = getattr(est, "regressor_", est)
    if key == "gpr":
        return str(inner.steps[-1][1].kernel_)
    return f"{inner.n_estimators_} trees, depth {inner.max_depth}, learning rate {inner.learning_rate}"


# ------------------------------------------------------------------ metrics
def _metrics(y, pred) -> dict[str, float]:
    out = {}
    for key, (_, fn) in METRICS.items():
        try:
            out[key] = float(fn(y, pred))
        except ValueError:  # e.g. MAPE of a zero target
            out[key] = math.nan
    out["n"] = int(len(y))
    return out


def _ratio(test: float, train: float) -> float:
    """test / train error (inf if the test error is not finite, 1 if it cannot be judged)."""
    if not math.isfinite(test):
        return math.inf
    if not math.isfinite(train):
        return 1.0
    if train <= 0:
        return math.inf if test > 0 else 1.0
    return test / train


def _jsonable(obj):
    """NaN → None, NumPy → Python, recursively."""
    if isinstance(obj, dict):
        return {str(k): _jsonable(v) for k, v in obj.items()}
    if isinstance(obj, (list, tuple)):
        return [_jsonable(v) for v in obj]
    if isinstance(obj, np.generic):
        obj = obj.item()
    if isinstance(obj, float) and not math.isfinite(obj):
        return None
    return obj


def _fmt(v) -> str:
    return f"{v:>10.4g}" if v is not None and math.isfinite(v) else f"{'—':>10}"


# --------------------------------------------------------------------- main
def learn(
    results_dir,
    *,
    test_size=30,
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
    out=print,
) -> dict:
    """Train ANFIS (and baseline) models of the joint parameters on a campaign's results.

    Parameters
    ----------
    results_dir : folder holding ``identified.csv``; models go to
        ``results_dir/models``, plots to ``results_dir/plots``.
    test_size : number of ok rows held out for testing (paper: 30 of 178).
    mfs, mf, order, epochs, step_size, log_target : ANFIS settings
        (:class:`~toolpoint.learning.anfis.ANFIS` ``n_mfs``, ``mf``, …).
    seed : seed of the random split (``numpy.random.default_rng``) and of the baselines.
    targets : None (kt, kr, and ct/cr where identifiable) or a list of names.
    baselines : also fit the GP and gradient-boosting baselines.
    plots : write the PNG plots.
    out : callable taking one line of text (default :func:`print`).

    Returns
    -------
    dict, the content of ``models/metrics.json`` (NaN where a metric is undefined;
    ``null`` in the JSON file). The numbers are under
    ``result["metrics"][target][model][set][metric]`` with model in
    ``anfis``/``gpr``/``gbr``, set in ``train``/``test`` and metric in
    ``nrmse``, ``afv``, ``mape`` (%), ``max_ape`` (%), plus ``n``.

    Raises
    ------
    InputError : missing identified.csv or column, a non-number in an ok row,
        fewer than ``test_size + 10`` ok rows, a bad setting, or an output that
        cannot be written.
    """
    n_mfs, explicit = _check_settings(test_size, mfs, mf, order, epochs, step_size, targets)
    results_dir = Path(results_dir)
    path = results_dir / "identified.csv"
    models_dir, plots_dir = results_dir / "models", results_dir / "plots"

    candidates = explicit if explicit is not None else list(ALL_TARGETS)
    required = ["id", *INPUTS, "status"] + candidates
    if explicit is None:
        required += [f"{t}_{b}" for t in DAMPING for b in ("lo", "hi")]
    required = list(dict.fromkeys(required))
    rows = _read_identified(path, required)

    ok = [(line, row) for line, row in rows if (row.get("status") or "").strip().lower() == "ok"]
    # campaign run appends rows as items finish (worker timing): order by id so the seeded
    # split, and the training itself, do not depend on which identification finished first
    ok.sort(key=lambda lr: (lr[1].get("id") or "").strip())
    n_failed = len(rows) - len(ok)
    if len(ok) < test_size + MIN_TRAIN:
        raise InputError(
            f"{len(ok)} rows with status ok, need at least test_size + {MIN_TRAIN} = {test_size + MIN_TRAIN}",
            file=path,
            field="status",
        )
    ids = [(row.get("id") or "").strip() for _, row in ok]
    seen = set()
    for (line, _), i in zip(ok, ids):
        if not i:
            raise InputError(f"line {line}: empty id", file=path, field="id")
        if i in seen:
            raise InputError(f"line {line}: id {i!r} appears more than once", file=path, field="id")
        seen.add(i)
    X = np.array([[_number(path, line, row, c) for c in INPUTS] for line, row in ok])
    # lenient here (NaN); a target that is learned must be a number in every ok row (checked below)
    values = {t: np.array([_number(path, line, row, t, required=False) for line, row in ok]) for t in candidates}

    # identifiability: share of ok rows with a narrow 95 % interval, per parameter
    share, narrow, sigma = {}, {}, {}
    for t in ALL_TARGETS:
        lo_c, hi_c = f"{t}_lo", f"{t}_hi"
        if rows and lo_c in rows[0][1] and hi_c in rows[0][1]:
            lo = np.array([_number(path, line, row, lo_c, required=False) for line, row in ok])
            hi = np.array([_number(path, line, row, hi_c, required=False) for line, row in ok])
            with np.errstate(over="ignore", invalid="ignore", divide="ignore"):
                r = np.where((lo > 0) & np.isfinite(hi), hi / np.where(lo > 0, lo, 1.0), np.inf)
            narrow[t] = r <= IDENTIFIABLE_RATIO
            share[t] = float(np.mean(narrow[t])) if len(ok) else 0.0
            # relative standard error from the 95 % interval (log-symmetric): σ = ln(hi/lo) / (2·1.96)
            sigma[t] = np.maximum(np.log(r) / (2 * 1.96), SIGMA_FLOOR)

    excluded = {}
    chosen = []
    for t in candidates:
        chosen.append(t)
        bad = np.flatnonzero(~np.isfinite(values[t]))
        if bad.size:
            line, row = ok[bad[0]]
            _number(path, line, row, t)  # raises, naming the line
    for t in chosen:
        if t in share and share[t] < IDENTIFIABLE_SHARE:
            out(f"note: only {100 * share[t]:.0f} % of the ok rows have a narrow 95 % interval for {t} "
                "(the FRF hardly depends on it elsewhere); weighted training keeps the rest from "
                "dominating, and the test metrics use the identified rows only")

    # seeded random split
    perm = np.random.default_rng(seed).permutation(len(ok))
    test_idx, train_idx = np.sort(perm[:test_size]), np.sort(perm[test_size:])
    is_test = np.zeros(len(ok), dtype=bool)
    is_test[test_idx] = True
    Xtr, Xte = X[train_idx], X[test_idx]
    for i, name in enumerate(INPUTS):
        if np.ptp(Xtr[:, i]) == 0:
            raise InputError("constant in the training data; a grid partition needs a range", file=path, field=name)

    if models_dir.exists() and not models_dir.is_dir():
        raise InputError("exists and is not a folder", file=models_dir)
    if plots and plots_dir.exists() and not plots_dir.is_dir():
        raise InputError("exists and is not a folder", file=plots_dir)
    try:
        with atomic_open(models_dir / "split.csv", "w", newline="", encoding="utf-8") as fh:
            w = csv.writer(fh)
            w.writerow(["id", "set"])
            for i, t in zip(ids, is_test):
                w.writerow([i, "test" if t else "train"])
    except OSError as err:
        raise InputError(f"cannot write: {err.strerror or err}", file=models_dir / "split.csv") from None

    rules = int(np.prod(np.broadcast_to(n_mfs, (len(INPUTS),))))
    mfs_text = "x".join(map(str, np.broadcast_to(n_mfs, (len(INPUTS),))))
    out(
        f"{path}: {len(rows)} rows, {len(ok)} ok"
        + (f", {n_failed} failed/other (ignored)" if n_failed else "")
        + f"; split (seed {seed}): {len(train_idx)} train / {len(test_idx)} test"
        + (" (paper: 148 / 30)" if (len(train_idx), len(test_idx)) != (148, 30) else " (as in the paper)")
    )
    out(
        f"ANFIS: inputs {', '.join(INPUTS)}; {mfs_text} {mf} MFs ({rules} rules), order {order}, "
        f"{epochs} epochs, step size {step_size:g}" + (", target fitted as log10" if log_target else "")
    )

    lo, hi = Xtr.min(axis=0), Xtr.max(axis=0)
    outside = int(np.sum(np.any((Xte < lo) | (Xte > hi), axis=1)))
    if outside:
        out(f"note: {outside} of {len(test_idx)} test samples lie outside the training range of D, L (models extrapolate there)")

    result = {
        "source": str(path),
        "settings": {
            "test_size": int(test_size),
            "mfs": list(np.broadcast_to(n_mfs, (len(INPUTS),)).tolist()),
            "mf": mf,
            "order": int(order),
            "epochs": int(epochs),
            "step_size": float(step_size),
            "seed": int(seed),
            "log_target": bool(log_target),
            "baselines": bool(baselines),
            "identifiable_ratio": IDENTIFIABLE_RATIO,
            "identifiable_share": IDENTIFIABLE_SHARE,
        },
        "inputs": list(INPUTS),
        "n_rows": len(rows),
        "n_ok": len(ok),
        "n_train": int(len(train_idx)),
        "n_test": int(len(test_idx)),
        "n_test_outside_training_range": outside,
        "targets": list(chosen),
        "excluded": excluded,
        "identifiable_share": share,
        "units": {t: UNITS[t] for t in chosen},
        "metrics": {},
        "baseline_settings": {},
        "best_test_model": {},
        "paper": {t: dict(PAPER[t], n=PAPER_N_TEST) for t in chosen if t in PAPER},
        "files": {"split": str(models_dir / "split.csv")},
    }

    for t in chosen:
        y = values[t]
        # Rows whose identification did not pin this parameter down (95 % interval wider
        # than a factor IDENTIFIABLE_RATIO, e.g. a fit that ran to a bound) are not data
        # about the joint: they are left out of this target's training and test sets.
        keep = narrow.get(t, np.ones(len(ok), bool))
        sig = sigma.get(t, np.full(len(ok), SIGMA_FLOOR))
        usable = np.isfinite(sig) & np.isfinite(y)
        # Training: every row with a finite interval, weighted by 1/σ² (weighted least squares);
        # where the FRF barely depends on the parameter the weights are small but the model still
        # sees plausible values there instead of extrapolating from a corner of the (D, L) plane.
        # Metrics: only rows where the parameter was identified (interval within a factor
        # IDENTIFIABLE_RATIO): the others are not trustworthy targets.
        t_fit = train_idx[usable[train_idx]]
        t_tr, t_te = train_idx[keep[train_idx]], test_idx[keep[test_idx]]
        if keep.sum() < len(ok):
            out(f"{t}: trained on {t_fit.size} rows weighted by 1/σ² from their 95 % intervals "
                f"({len(train_idx) - t_fit.size} without a finite interval left out); metrics on the "
                f"{t_tr.size} training and {t_te.size} test rows where it was identified "
                f"(interval within a factor {IDENTIFIABLE_RATIO:g})")
        if t_tr.size < MIN_RELIABLE or t_te.size == 0:
            excluded[t] = f"{t}: too few identified rows ({t_tr.size} train, {t_te.size} test)"
            out(f"{t} left out: {excluded[t]}")
            continue
        n_par = rules * (len(INPUTS) + 1 if order == 1 else 1)
        if t_tr.size < n_par:
            out(f"note: {t} was identified in {t_tr.size} training rows, fewer than the {n_par} consequent "
                f"parameters of {rules} rules: where it was not identified, the model rests on weak rows only")
        Xfit, yfit, sfit = X[t_fit], y[t_fit], sig[t_fit]
        Xtr, Xte = X[t_tr], X[t_te]
        ytr, yte = y[t_tr], y[t_te]
        if log_target and np.any(yfit <= 0):
            raise InputError("log_target needs positive values", file=path, field=t)
        model = ANFIS(
            n_mfs=n_mfs,
            mf=mf,
            order=order,
            epochs=int(epochs),
            step_size=float(step_size),
            log_target=bool(log_target),
            input_names=list(INPUTS),
            target_name=t,
            random_state=int(seed),
        )
        try:
            with _one_thread():
                # σ is relative: the absolute error of y is y·σ, of log10 y it is σ/ln 10
                model.fit(Xfit, yfit, sample_weight=_weights(yfit, sfit, log_target))
        except ValueError as err:
            raise InputError(f"ANFIS training failed: {err}", file=path, field=t) from None
        model_path = models_dir / f"{t}.json"
        try:
            model.save(model_path)
        except OSError as err:
            raise InputError(f"cannot write: {err.strerror or err}", file=model_path) from None
        result["files"][t] = str(model_path)

        p_tr, _ = _predict_quietly(model, Xtr)
        p_te, _ = _predict_quietly(model, Xte)  # extrapolation reported once, above
        res = {"anfis": {"train": _metrics(ytr, p_tr), "test": _metrics(yte, p_te)}}
        res["anfis"]["kept_epoch"] = int(model.best_epoch_)
        ratio = _ratio(res["anfis"]["test"]["nrmse"], res["anfis"]["train"]["nrmse"])
        res["anfis"]["overfit"] = bool(ratio > OVERFIT_RATIO)

        if baselines:
            log = bool(np.all(y > 0))
            settings = {}
            for key, est in _baselines(int(seed), log).items():
                with warnings.catch_warnings(), _one_thread():
                    warnings.simplefilter("ignore")  # GP optimiser convergence chatter
                    _fit_weighted(key, est, Xfit, yfit, sfit, log)
                    b_tr, b_te = est.predict(Xtr), est.predict(Xte)
                res[key] = {"train": _metrics(ytr, b_tr), "test": _metrics(yte, b_te)}
                settings[key] = {"log10_target": log, "fitted": _describe_baseline(key, est)}
            result["baseline_settings"][t] = settings
        result["metrics"][t] = res

        if plots:
            label = f"{t} [{UNITS[t]}]"
            files = {
                "test": plots_dir / f"anfis_{t}_test.png",
                "regression": plots_dir / f"anfis_{t}_regression.png",
                "membership": plots_dir / f"anfis_{t}_membership.png",
            }
            try:
                _plot_per_sample(files["test"], yte, p_te, label, f"{t}: experimental vs ANFIS, test data")
                _plot_regression(files["regression"], yte, p_te, label, f"{t}, test data")
                _plot_membership(files["membership"], model)
            except OSError as err:
                raise InputError(f"cannot write plots: {err.strerror or err}", file=plots_dir) from None
            result["files"][f"{t}_plots"] = [str(p) for p in files.values()]

        # table
        out("")
        out(f"{t} [{UNITS[t]}]   (ANFIS kept epoch {model.best_epoch_})")
        out(f"{'model':<20} {'set':<5} {'n':>4} " + " ".join(f"{title:>10}" for title, _ in METRICS.values()))
        for key in ("anfis", "gpr", "gbr"):
            if key in res:
                for s in ("train", "test"):
                    m = res[key][s]
                    out(f"{MODEL_LABELS[key]:<20} {s:<5} {m['n']:>4} " + " ".join(_fmt(m[k]) for k in METRICS))
        if t in PAPER:
            out(f"{MODEL_LABELS['paper']:<20} {'test':<5} {PAPER_N_TEST:>4} " + " ".join(_fmt(PAPER[t][k]) for k in METRICS))
        if res["anfis"]["overfit"]:
            out(
                f"warning: ANFIS test NRMSE is {ratio:.3g}× its training NRMSE — {rules} rules over-fit "
                f"{len(train_idx)} samples; try fewer MFs (e.g. --mfs 3,3), fewer --epochs, "
                "and compare the baselines"
            )
        scored = {k: v["test"]["mape"] for k, v in res.items() if math.isfinite(v["test"]["mape"])}
        if scored:
            best = min(scored, key=scored.get)
            result["best_test_model"][t] = best
            if len(scored) > 1:
                line = f"lowest test MAPE: {MODEL_LABELS[best]} {scored[best]:.3g} %"
                if best != "anfis" and "anfis" in scored:
                    line += f" (ANFIS {scored['anfis']:.3g} %)"
                    if scored["anfis"] > 1.5 * scored[best]:
                        line += f" — {MODEL_LABELS[best]} suits these data better than this ANFIS"
                out(line)

    result["targets"] = [t for t in chosen if t in result["metrics"]]  # minus those left out above
    result["units"] = {t: UNITS[t] for t in result["targets"]}
    # files
    metrics_json, metrics_csv = models_dir / "metrics.json", models_dir / "metrics.csv"
    result["files"]["metrics_json"] = str(metrics_json)
    result["files"]["metrics_csv"] = str(metrics_csv)
    try:
        with atomic_open(metrics_json, "w", encoding="utf-8") as fh:
            json.dump(_jsonable(result), fh, indent=1, ensure_ascii=False, allow_nan=False)
            fh.write("\n")
        with atomic_open(metrics_csv, "w", newline="", encoding="utf-8") as fh:
            w = csv.writer(fh)
            w.writerow(["target", "unit", "model", "set", "n", *METRICS])
            for t, res in result["metrics"].items():
                for key, sets in res.items():
                    for s in ("train", "test"):
                        m = sets[s]
                        w.writerow([t, UNITS[t], key, s, m["n"], *("" if not math.isfinite(m[k]) else repr(m[k]) for k in METRICS)])
                if t in PAPER:
                    w.writerow([t, UNITS[t], "paper", "test", PAPER_N_TEST, *(repr(PAPER[t][k]) for k in METRICS)])
    except OSError as err:
        raise InputError(f"cannot write: {err.strerror or err}", file=models_dir) from None
    out("")
    out(f"models and metrics in {models_dir}" + (f"; plots in {plots_dir}" if plots else ""))
    return result


# ---------------------------------------------------------------------- CLI
#: learn() keyword → CLI option, to name the option in an InputError.
_OPTIONS = {
    "test_size": "--test-size",
    "mfs": "--mfs",
    "mf": "--mf",
    "order": "--order",
    "epochs": "--epochs",
    "step_size": "--step-size",
    "targets": "--targets",
}


def add_arguments(parser) -> None:
    """Add the options of ``toolpoint campaign learn`` (not the positional RESULTS_DIR)."""
    parser.add_argument("--test-size", type=int, default=30, help="ok rows held out for testing (default 30, as in the paper)")
    parser.add_argument("--mfs", default="3,7", help="MFs per input (diameter, overhang): one number or two, e.g. 3,7 (default)")
    parser.add_argument("--mf", default="gauss", choices=tuple(MF_PARAMS), help="membership function type (default gauss)")
    parser.add_argument("--order", type=int, default=1, choices=(0, 1), help="consequent order: 0 constant, 1 linear (default 1)")
    parser.add_argument("--epochs", type=int, default=200, help="ANFIS training epochs (default 200)")
    parser.add_argument("--step-size", type=float, default=0.01, help="ANFIS initial step size, in input units (default 0.01)")
    parser.add_argument("--seed", type=int, default=0, help="seed of the random train/test split and the baselines (default 0)")
    parser.add_argument("--linear-target", dest="log_target", action="store_false",
                        help="ANFIS fits the target itself, as the paper (default: its log10, which keeps predictions "
                             "positive; metrics are in SI units either way)")
    parser.add_argument("--no-baselines", action="store_true", help="skip the GP and gradient-boosting comparison models")
    parser.add_argument("--targets", help="comma-separated targets from kt,ct,kr,cr (default: kt,kr and identifiable dampings)")
    parser.add_argument("--no-plots", action="store_true", help="do not write PNG plots")


def run_cli(args) -> int:
    """Run :func:`learn` from parsed arguments (``args.results_dir`` plus :func:`add_arguments`' options)."""
    text = str(getattr(args, "mfs", "3,7"))
    try:
        mfs = tuple(int(s) for s in text.split(","))
    except ValueError:
        raise InputError(f"expected an integer or comma-separated integers, got {text!r}", field="--mfs") from None
    targets = getattr(args, "targets", None)
    if targets is not None:
        targets = [s.strip() for s in targets.split(",")]
    plots = not getattr(args, "no_plots", False)
    if plots:
        import matplotlib

        matplotlib.use("Agg")
    try:
        learn(
            args.results_dir,
            test_size=args.test_size,
            mfs=mfs[0] if len(mfs) == 1 else mfs,
            mf=args.mf,
            order=args.order,
            epochs=args.epochs,
            step_size=args.step_size,
            seed=args.seed,
            targets=targets,
            log_target=getattr(args, "log_target", True),
            baselines=not args.no_baselines,
            plots=plots,
        )
    except InputError as err:
        if err.file is None and err.field in _OPTIONS:
            raise InputError(err.message, field=_OPTIONS[err.field]) from None
        raise
    return 0
