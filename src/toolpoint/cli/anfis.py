"""``toolpoint anfis`` — train an ANFIS model on a CSV table and apply it.

::

    toolpoint anfis train DATA.csv --inputs diameter_mm,overhang_mm --target kt \\
        --mfs 3,7 --mf gauss --order 1 --epochs 100 [--step-size 0.01] \\
        [--test-fraction 0.2 | --test TEST.csv] [--seed 0] [--log-target] \\
        --out MODEL.json [--plots DIR]
    toolpoint anfis predict MODEL.json DATA.csv --out PRED.csv

CSV files have a header row of column names; the named columns must hold finite
numbers. ``train`` prints NRMSE, AFV, MAPE % and max APE % (Čiča et al.) for the
training and test data, writes the model as JSON and, with ``--plots``, PNGs of
predicted vs target per sample (paper Figs. 6/7), regression plots (Fig. 8) and
the membership functions. The test data are only evaluated, never used for
model selection. ``--log-target`` fits log10 of the target (stiffnesses span
decades; this balances relative errors) — predictions are transformed back, so
all reported metrics are in the target's own unit; the default fits the target
as is, as in the paper.

``predict`` writes the model's input columns plus one column named after the
target with the predictions.
"""

from __future__ import annotations

import csv
import warnings
from pathlib import Path

import numpy as np

from ..learning.anfis import ANFIS, MF_PARAMS, plot_membership
from ..io.atomic import atomic_open, atomic_path
from ..errors import ExtrapolationWarning, InputError
from ..learning.metrics import afv, mape, max_ape, nrmse

PAPER_METRICS = (("NRMSE", nrmse), ("AFV", afv), ("MAPE %", mape), ("max APE %", max_ape))


def register(subparsers) -> None:
    p = subparsers.add_parser(
        "anfis",
        help="train / apply an ANFIS (Sugeno fuzzy) regression model",
        description="Train an ANFIS model on CSV data (MATLAB anfis-compatible hybrid learning) or predict with one.",
    )
    sub = p.add_subparsers(dest="anfis_command", required=True, metavar="ACTION")

    t = sub.add_parser("train", help="fit a model to a CSV table", description="Fit an ANFIS model to a CSV table.")
    t.add_argument("data", help="training CSV (header row of column names)")
    t.add_argument("--inputs", required=True, help="comma-separated input column names, e.g. diameter_mm,overhang_mm")
    t.add_argument("--target", required=True, help="target column name, e.g. kt")
    t.add_argument("--mfs", default="3", help="MFs per input: one number or one per input, e.g. 3,7 (default 3)")
    t.add_argument("--mf", default="gauss", choices=tuple(MF_PARAMS), help="membership function type (default gauss)")
    t.add_argument("--order", type=int, default=1, choices=(0, 1), help="consequent order: 0 constant, 1 linear (default 1)")
    t.add_argument("--epochs", type=int, default=100, help="training epochs (default 100)")
    t.add_argument("--step-size", type=float, default=0.01, help="initial step size, in input units (default 0.01)")
    split = t.add_mutually_exclusive_group()
    split.add_argument("--test-fraction", type=float, help="hold out this random fraction of DATA as test data")
    split.add_argument("--test", help="separate test CSV with the same columns")
    t.add_argument("--seed", type=int, default=0, help="seed of the random test split (default 0)")
    t.add_argument("--log-target", action="store_true", help="fit log10(target) (target > 0); predictions are transformed back")
    t.add_argument("--out", required=True, help="model JSON to write")
    t.add_argument("--plots", help="directory for PNG plots")
    t.set_defaults(func=train)

    q = sub.add_parser("predict", help="apply a model to a CSV table", description="Predict with a saved ANFIS model.")
    q.add_argument("model", help="model JSON written by 'toolpoint anfis train'")
    q.add_argument("data", help="CSV with the model's input columns")
    q.add_argument("--inputs", help="input column names, if the model does not name its inputs")
    q.add_argument("--out", required=True, help="CSV to write (input columns + predicted target)")
    q.set_defaults(func=predict)


# ------------------------------------------------------------------ CSV I/O
def read_columns(path, names) -> dict[str, np.ndarray]:
    """Read the named numeric columns of a CSV with a header row.

    Raises :class:`InputError` (file and column named) for a missing file or
    column, an empty table, and an empty, non-numeric or non-finite cell.
    """
    path = Path(path)
    if not path.is_file():
        raise InputError("file not found", file=path)
    try:
        with open(path, newline="", encoding="utf-8-sig") as fh:
            reader = csv.reader(fh)
            rows = [(reader.line_num, row) for row in reader if any(c.strip() for c in row)]
    except (OSError, UnicodeDecodeError, csv.Error) as err:
        raise InputError(f"cannot read CSV: {err}", file=path) from None
    if not rows:
        raise InputError("empty file (no header row)", file=path)
    header = [h.strip() for h in rows[0][1]]
    data = rows[1:]
    if not data:
        raise InputError("no data rows below the header", file=path)
    out = {}
    for name in names:
        if header.count(name) != 1:
            what = "no such column" if name not in header else "column name appears more than once"
            raise InputError(f"{what} (columns: {', '.join(header)})", file=path, field=name)
        j = header.index(name)
        values = np.empty(len(data))
        for k, (line, row) in enumerate(data):
            cell = row[j].strip() if j < len(row) else ""
            try:
                v = float(cell)
            except ValueError:
                raise InputError(f"line {line}: {cell!r} is not a number", file=path, field=name) from None
            if not np.isfinite(v):
                raise InputError(f"line {line}: {cell!r} is not a finite number", file=path, field=name)
            values[k] = v
        out[name] = values
    return out


def _check_out(path, option: str, *, folder: bool = False) -> None:
    """Fail before any work if an output path cannot be what it must be."""
    p = Path(path)
    if folder and p.exists() and not p.is_dir():
        raise InputError("exists and is not a folder", file=p, field=option)
    if not folder and p.is_dir():
        raise InputError("is a folder, expected a file name", file=p, field=option)


def _names(text: str, option: str) -> list[str]:
    names = [s.strip() for s in text.split(",")]
    if not names or any(not s for s in names):
        raise InputError(f"expected comma-separated column names, got {text!r}", field=option)
    if len(set(names)) != len(names):
        raise InputError(f"a column is named twice in {text!r}", field=option)
    return names


def _write_csv(path, header, columns) -> None:
    with atomic_open(path, "w", newline="", encoding="utf-8") as fh:
        w = csv.writer(fh)
        w.writerow(header)
        for row in zip(*columns):
            w.writerow([repr(float(v)) for v in row])  # shortest exact float text


# ----------------------------------------------------------------- metrics
def paper_metrics(y_true, y_pred) -> dict[str, float]:
    """NRMSE, AFV, MAPE %, max APE % (NaN where undefined, e.g. a zero target)."""
    out = {}
    for name, fn in PAPER_METRICS:
        try:
            out[name] = fn(y_true, y_pred)
        except ValueError:
            out[name] = float("nan")
    return out


def _predict_quietly(model, X):
    """Predict; return (prediction, whether any sample lay outside the training range)."""
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always", ExtrapolationWarning)
        y = model.predict(X)
    return y, any(issubclass(w.category, ExtrapolationWarning) for w in caught)


# ------------------------------------------------------------------- plots
def _savefig(fig, path) -> None:
    with atomic_path(path) as tmp:
        fig.savefig(tmp, format="png", dpi=120)


def _plot_per_sample(path, y, o, label, title) -> None:
    from matplotlib.figure import Figure

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
    _savefig(fig, path)


def _plot_regression(path, y, o, label, title) -> None:
    from matplotlib.figure import Figure

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
    ax.set_xlabel(f"target {label}")
    ax.set_ylabel(f"output {label}")
    ax.set_title(title)
    ax.legend(loc="upper left", fontsize="small")
    fig.tight_layout()
    _savefig(fig, path)


def _plot_membership(path, model) -> None:
    from matplotlib.figure import Figure

    d = model.n_features_in_
    fig = Figure(figsize=(6.0, 2.2 * d))
    axes = fig.subplots(d, 1, squeeze=False)[:, 0]
    plot_membership(model, ax=axes)
    _savefig(fig, path)


# ---------------------------------------------------------------- commands
def train(args) -> int:
    inputs = _names(args.inputs, "--inputs")
    target = args.target.strip()
    if not target:
        raise InputError("empty target column name", field="--target")
    if target in inputs:
        raise InputError(f"{target!r} is both an input and the target", field="--target")
    try:
        mfs = [int(s) for s in args.mfs.split(",")]
    except ValueError:
        raise InputError(f"expected an integer or comma-separated integers, got {args.mfs!r}", field="--mfs") from None
    if len(mfs) not in (1, len(inputs)):
        raise InputError(f"{len(mfs)} numbers for {len(inputs)} inputs", field="--mfs")
    if min(mfs) < 2:
        raise InputError("each input needs at least 2 membership functions", field="--mfs")
    if args.epochs < 1:
        raise InputError("must be at least 1", field="--epochs")
    if not (np.isfinite(args.step_size) and args.step_size > 0):
        raise InputError("must be a positive number", field="--step-size")
    if args.test_fraction is not None and not 0 < args.test_fraction < 1:
        raise InputError("must be between 0 and 1", field="--test-fraction")
    _check_out(args.out, "--out")
    if args.plots:
        _check_out(args.plots, "--plots", folder=True)

    cols = read_columns(args.data, inputs + [target])
    X, y = np.column_stack([cols[c] for c in inputs]), cols[target]
    Xt = yt = None
    if args.test is not None:
        tcols = read_columns(args.test, inputs + [target])
        Xt, yt = np.column_stack([tcols[c] for c in inputs]), tcols[target]
    elif args.test_fraction is not None:
        n_test = int(round(args.test_fraction * len(y)))
        if n_test < 1 or len(y) - n_test < 2:
            raise InputError(f"{len(y)} rows cannot be split with test fraction {args.test_fraction}", file=args.data)
        perm = np.random.default_rng(args.seed).permutation(len(y))
        test_idx, train_idx = np.sort(perm[:n_test]), np.sort(perm[n_test:])
        X, y, Xt, yt = X[train_idx], y[train_idx], X[test_idx], y[test_idx]
    for i, name in enumerate(inputs):
        if np.ptp(X[:, i]) == 0:
            raise InputError("constant in the training data; a grid partition needs a range", file=args.data, field=name)
    if args.log_target and np.any(y <= 0):
        raise InputError("--log-target needs positive target values", file=args.data, field=target)

    model = ANFIS(
        n_mfs=mfs[0] if len(mfs) == 1 else tuple(mfs),
        mf=args.mf,
        order=args.order,
        epochs=args.epochs,
        step_size=args.step_size,
        log_target=args.log_target,
        input_names=inputs,
        target_name=target,
        random_state=args.seed,
    )
    try:
        model.fit(X, y)
    except ValueError as err:
        raise InputError(str(err), file=args.data) from None

    sets = [("train", X, y)] + ([("test", Xt, yt)] if Xt is not None else [])
    results = []
    for name, Xs, ys in sets:
        pred, outside = _predict_quietly(model, Xs)
        results.append((name, ys, pred, paper_metrics(ys, pred), outside))

    try:
        model.save(args.out)
    except OSError as err:
        raise InputError(f"cannot write: {err.strerror or err}", file=args.out, field="--out") from None
    if args.plots:
        plots = Path(args.plots)
        try:
            for name, ys, pred, _, _ in results:
                _plot_per_sample(plots / f"predicted_vs_target_{name}.png", ys, pred, target, f"{name} data")
                _plot_regression(plots / f"regression_{name}.png", ys, pred, target, f"{name} data")
            _plot_membership(plots / "membership_functions.png", model)
        except OSError as err:
            raise InputError(f"cannot write plots: {err.strerror or err}", file=plots, field="--plots") from None

    rules = int(np.prod(model.n_mfs_))
    print(
        f"ANFIS: {len(inputs)} inputs, {'x'.join(map(str, model.n_mfs_))} {args.mf} MFs ({rules} rules), "
        f"order {args.order}, {len(model.history_['train_rmse'])} epochs, kept epoch {model.best_epoch_}"
        + (", target fitted as log10" if args.log_target else "")
    )
    print(f"{'data':<6} {'n':>5} " + " ".join(f"{m:>10}" for m, _ in PAPER_METRICS))
    for name, ys, _, met, outside in results:
        print(f"{name:<6} {len(ys):>5} " + " ".join(f"{met[m]:>10.4g}" for m, _ in PAPER_METRICS))
        if outside:
            print(f"note: some {name} samples lie outside the training input range (extrapolation)")
    print(f"model written to {args.out}" + (f"; plots in {args.plots}" if args.plots else ""))
    return 0


def predict(args) -> int:
    if not Path(args.model).is_file():
        raise InputError("file not found", file=args.model)
    _check_out(args.out, "--out")
    try:
        model = ANFIS.load(args.model)
    except (ValueError, OSError, UnicodeDecodeError) as err:
        raise InputError(f"not a valid ANFIS model: {err}", file=args.model) from None
    if args.inputs is not None:
        inputs = _names(args.inputs, "--inputs")
    elif model.input_names_ is not None:
        inputs = list(model.input_names_)
    else:
        raise InputError("the model does not name its inputs; give --inputs", file=args.model, field="input_names")
    if len(inputs) != model.n_features_in_:
        raise InputError(f"the model has {model.n_features_in_} inputs, {len(inputs)} names given", field="--inputs")
    cols = read_columns(args.data, inputs)
    X = np.column_stack([cols[c] for c in inputs])
    pred, outside = _predict_quietly(model, X)
    out_name = model.target_name_ or "prediction"
    if out_name in inputs:
        out_name += "_predicted"
    try:
        _write_csv(args.out, inputs + [out_name], [X[:, i] for i in range(X.shape[1])] + [pred])
    except OSError as err:
        raise InputError(f"cannot write: {err.strerror or err}", file=args.out, field="--out") from None
    if outside:
        print("note: some samples lie outside the training input range (extrapolation)")
    print(f"{len(pred)} predictions of {out_name} written to {args.out}")
    return 0
