"""``toolpoint anfis`` — train an ANFIS model on a CSV table and apply it.

::

    toolpoint anfis train DATA.csv --inputs diameter_mm,overhang_mm --target kt \\
        --mfs 3,7 --mf gauss --order 1 --epochs 200 [--step-size 0.01] \\
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
from pathlib import Path

import numpy as np

from .common import out_path
from ..errors import InputError
from ..io.atomic import atomic_open
from ..learning.anfis import ANFIS, MF_PARAMS, predict_quietly
from ..learning.figures import membership_figure, per_sample_figure, regression_figure, save_png
from ..learning.metrics import PAPER_METRICS, paper_metrics

#: Largest magnitude accepted in a data column: squares and sums of squares in training stay finite.
MAX_ABS_VALUE = 1e100

#: ANFIS parameter → the option that sets it (to name the option in an InputError).
_OPTIONS = {"n_mfs": "--mfs", "mf": "--mf", "order": "--order", "epochs": "--epochs", "step_size": "--step-size"}


def register(subparsers) -> None:
    """Add ``toolpoint anfis train|predict`` to the ``toolpoint`` sub-command parsers."""
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
    t.add_argument("--order", type=int, default=1, choices=(0, 1),
                   help="consequent order: 0 constant, 1 linear (default 1)")
    t.add_argument("--epochs", type=int, default=200, help="training epochs (default 200, as `campaign learn`)")
    t.add_argument("--step-size", type=float, default=0.01, help="initial step size, in input units (default 0.01)")
    split = t.add_mutually_exclusive_group()
    split.add_argument("--test-fraction", type=float, help="hold out this random fraction of DATA as test data")
    split.add_argument("--test", help="separate test CSV with the same columns")
    t.add_argument("--seed", type=int, default=0, help="seed of the random test split (default 0)")
    t.add_argument("--log-target", action="store_true",
                   help="fit log10(target) (target > 0); predictions are transformed back")
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
    column, an empty table, and an empty, non-numeric or non-finite cell, or one
    beyond ±:data:`MAX_ABS_VALUE`.
    """
    from ..io.table import read_rows

    path = Path(path)
    rows = read_rows(path)
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
            if abs(v) > MAX_ABS_VALUE:
                raise InputError(f"line {line}: {cell!r} is beyond ±{MAX_ABS_VALUE:g} (training squares it)",
                                 file=path, field=name)
            values[k] = v
        out[name] = values
    return out


def _check_plots_folder(path, option: str) -> None:
    """Fail before any work if the plots folder cannot be made or written."""
    p = Path(path)
    if p.exists() and not p.is_dir():
        raise InputError("exists and is not a folder", file=p, field=option)
    out_path(str(p / "anfis_plot.png"), option)  # an ancestor that is a file, or not writable


def _names(text: str, option: str) -> list[str]:
    """Comma-separated column names (non-empty, distinct)."""
    names = [s.strip() for s in text.split(",")]
    if not names or any(not s for s in names):
        raise InputError(f"expected comma-separated column names, got {text!r}", field=option)
    if len(set(names)) != len(names):
        raise InputError(f"a column is named twice in {text!r}", field=option)
    return names


def _ranges(model, names) -> str:
    """The model's training range per input, e.g. ``a 0–1, b 2–5``."""
    return ", ".join(f"{n} {lo:.6g}–{hi:.6g}" for n, (lo, hi) in zip(names, model.input_range_))


def _write_csv(path, header, columns) -> None:
    """Write columns of floats under ``header``, atomically."""
    with atomic_open(path, "w", newline="", encoding="utf-8") as fh:
        w = csv.writer(fh)
        w.writerow(header)
        for row in zip(*columns):
            w.writerow([repr(float(v)) for v in row])  # shortest exact float text


# ---------------------------------------------------------------- commands
def train(args) -> int:
    """``toolpoint anfis train``: fit, report the paper's metrics, write the model (and plots); exit code."""
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
    try:  # before reading any data: the model's own checks, reported under the option's name
        model.check_params(len(inputs))
    except InputError as err:
        raise InputError(err.message, field=_OPTIONS.get(err.field, err.field)) from None
    if args.test_fraction is not None and not 0 < args.test_fraction < 1:
        raise InputError("must be between 0 and 1", field="--test-fraction")
    out_path(args.out, "--out", inputs=[args.data])
    if args.plots:
        _check_plots_folder(args.plots, "--plots")

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
            raise InputError("constant in the training data; a grid partition needs a range", file=args.data,
                             field=name)
    span = float(np.max(np.ptp(X, axis=0)))
    if args.step_size > span:  # κ moves premise parameters, in input units: beyond the span it leaves the data
        raise InputError(f"{args.step_size:g} is larger than the span of the training inputs ({span:g}); "
                         "the step moves membership functions in input units", field="--step-size")
    if args.log_target and np.any(y <= 0):
        raise InputError("--log-target needs positive target values", file=args.data, field=target)

    try:
        model.fit(X, y)
    except ValueError as err:
        raise InputError(str(err), file=args.data) from None

    sets = [("train", X, y)] + ([("test", Xt, yt)] if Xt is not None else [])
    results = []
    for name, Xs, ys in sets:
        pred, outside = predict_quietly(model, Xs)
        results.append((name, ys, pred, paper_metrics(ys, pred), outside))

    # plots first, the model last; a failure removes what this run wrote, so no model is left without its plots
    plots = Path(args.plots) if args.plots else None
    made = plots is not None and not plots.exists()
    figures = [] if plots is None else [
        (f"{kind}_{name}.png", lambda f=figure, ys=ys, pred=pred, name=name: f(ys, pred, target, f"{name} data"))
        for name, ys, pred, _, _ in results
        for kind, figure in (("predicted_vs_target", per_sample_figure), ("regression", regression_figure))
    ] + [("membership_functions.png", lambda: membership_figure(model))]
    written = []
    try:
        for file_name, draw in figures:
            written.append(plots / file_name)
            try:
                save_png(draw(), written[-1])
            except OSError as err:
                raise InputError(f"cannot write plots: {err.strerror or err}", file=plots, field="--plots") from None
        try:
            model.save(args.out)
        except OSError as err:
            raise InputError(f"cannot write: {err.strerror or err}", file=args.out, field="--out") from None
    except BaseException:
        for f in written:
            f.unlink(missing_ok=True)
        if made and plots.is_dir() and not any(plots.iterdir()):
            plots.rmdir()
        raise

    rules = int(np.prod(model.n_mfs_))
    print(
        f"ANFIS: {len(inputs)} inputs, {'x'.join(map(str, model.n_mfs_))} {args.mf} MFs ({rules} rules), "
        f"order {args.order}, {len(model.history_['train_rmse'])} epochs, kept epoch {model.best_epoch_}"
        + (", target fitted as log10" if args.log_target else "")
    )
    print(f"{'data':<6} {'n':>5} " + " ".join(f"{title:>10}" for title, _ in PAPER_METRICS.values()))
    for name, ys, _, met, outside in results:
        print(f"{name:<6} {len(ys):>5} " + " ".join(f"{met[k]:>10.4g}" for k in PAPER_METRICS))
        if outside:
            print(f"note: some {name} samples lie outside the training input range (extrapolation)")
    print(f"model written to {args.out}" + (f"; plots in {args.plots}" if args.plots else ""))
    return 0


def predict(args) -> int:
    """``toolpoint anfis predict``: apply a saved model to a CSV table; exit code."""
    if not Path(args.model).is_file():
        raise InputError("file not found", file=args.model)
    out_path(args.out, "--out", inputs=[args.data, args.model])
    try:
        model = ANFIS.load(args.model)
    except InputError:
        raise
    except (ValueError, OSError) as err:
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
    with np.errstate(all="ignore"):  # far outside the training range the arithmetic overflows: checked below
        pred, outside = predict_quietly(model, X)
    bad = np.flatnonzero(~np.isfinite(pred))
    if bad.size:
        row = ", ".join(f"{c} = {X[bad[0], i]:.6g}" for i, c in enumerate(inputs))
        raise InputError(f"data row {bad[0] + 1} ({row}) is so far outside the training range "
                         f"({_ranges(model, inputs)}) that the prediction is not a finite number", file=args.data)
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
