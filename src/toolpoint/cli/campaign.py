"""``toolpoint campaign synth|run|learn`` — the experimental campaign (paper section 5)."""

from __future__ import annotations

import argparse
import math
import sys

from ..errors import InputError
from .common import check_number, out_folder

#: Model key → the name printed in the ``campaign learn`` table.
MODEL_LABELS = {"anfis": "ANFIS", "gpr": "GP regression", "gbr": "gradient boosting", "paper": "Čiča et al. ANFIS"}

#: learn() keyword → CLI option, to name the option in an InputError.
_OPTIONS = {
    "test_size": "--test-size",
    "cv_folds": "--cv-folds",
    "mfs": "--mfs",
    "mf": "--mf",
    "order": "--order",
    "epochs": "--epochs",
    "step_size": "--step-size",
    "targets": "--targets",
}


def register(sub) -> None:
    """Add ``toolpoint campaign synth|run|learn`` to the ``toolpoint`` sub-command parsers."""
    p = sub.add_parser("campaign", help="many tools on one spindle–holder: synthesise, identify all, learn ANFIS")
    cs = p.add_subparsers(dest="campaign_command", required=True, metavar="STEP")

    s = cs.add_parser("synth", help="write a realistic synthetic campaign (truth law documented, kept in truth/)")
    s.add_argument("out_dir", help="new campaign folder to write (campaign.toml, FRFs, measurements.csv, truth/)")
    s.add_argument("--n", type=int, default=178, help="number of tool assemblies (default 178)")
    s.add_argument("--seed", type=int, default=0, help="seed of the tools, joints and noise drawn (default 0)")
    s.add_argument("--noise", type=float, default=0.01,
                   help="tool-point FRF noise, fraction of the peak (default 0.01)")
    s.add_argument("--blank-noise", type=float, default=5e-5,
                   help="noise of the blank FRFs for inverse RCSA, fraction of the peak (default 5e-5)")
    s.add_argument("--format", choices=("csv", "uff"), default="csv", help="FRF file format (default csv)")
    s.set_defaults(func=_synth)

    r = cs.add_parser("run", help="identify the joint of every measurement (resumable)")
    r.add_argument("campaign_dir", help="campaign folder (campaign.toml, measurements.csv, FRF files)")
    r.add_argument("--out", required=True, help="results folder (identified.csv)")
    r.add_argument("--method", help="hybrid, ga, sa, pso or de (default: campaign.toml, else hybrid)")
    r.add_argument("--workers", type=int, help="local processes (default: all cores)")
    r.add_argument("--dask", metavar="ADDRESS", help="run on an existing Dask scheduler, e.g. tcp://10.0.0.5:8786")
    r.add_argument("--seed", type=int, default=0, help="seed of every identification (default 0)")
    r.set_defaults(func=_run)

    lp = cs.add_parser("learn", help="ANFIS per target on (diameter_mm, overhang_mm), with baselines")
    lp.add_argument("results_dir", help="results folder of `campaign run` (identified.csv); models/ go beside it")
    add_arguments(lp)
    lp.set_defaults(func=run_cli)


def add_arguments(parser) -> None:
    """Add the options of ``toolpoint campaign learn`` (not the positional RESULTS_DIR) to ``parser``."""
    from ..learning.anfis import MF_PARAMS

    add = parser.add_argument
    add("--test-size", type=_test_size, default="auto",
        help="ok rows held out for the test metrics (default auto: 30 of 178 as in the paper, 17 %% of smaller "
             "campaigns; the library's σ comes from cross-validation over every tool)")
    add("--cv-folds", type=int, default=5,
        help="folds of the cross-validation that calibrates each parameter's predictive σ (default 5)")
    add("--mfs", default="3,7", help="MFs per input (diameter, overhang): one number or two, e.g. 3,7 (default)")
    add("--mf", default="gauss", choices=tuple(MF_PARAMS), help="membership function type (default gauss)")
    add("--order", type=int, default=1, choices=(0, 1), help="consequent order: 0 constant, 1 linear (default 1)")
    add("--epochs", type=int, default=200, help="ANFIS training epochs (default 200)")
    add("--step-size", type=float, default=0.01, help="ANFIS initial step size, in input units (default 0.01)")
    add("--seed", type=int, default=0, help="seed of the random train/test split and the baselines (default 0)")
    add("--linear-target", dest="log_target", action="store_false",
        help="ANFIS fits the target itself, as the paper (default: its log10, which keeps predictions "
             "positive; metrics are in SI units either way)")
    add("--no-baselines", action="store_true", help="skip the GP and gradient-boosting comparison models")
    add("--targets", help="comma-separated targets from kt,ct,kr,cr (default: kt,kr and identifiable dampings)")
    add("--no-plots", action="store_true", help="do not write PNG plots")


def _test_size(text: str):
    if text == "auto":
        return text
    try:
        return int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a whole number or 'auto', got {text!r}") from None


def run_cli(args) -> int:
    """``toolpoint campaign learn``: run :func:`~toolpoint.campaign.learn.learn` and print its report.

    Parameters
    ----------
    args : argparse.Namespace
        ``results_dir`` plus the options of :func:`add_arguments`.

    Returns
    -------
    int
        Exit code 0 (bad input raises :class:`~toolpoint.errors.InputError` naming the option).
    """
    from ..campaign.learn import learn

    text = str(getattr(args, "mfs", "3,7"))
    try:
        mfs = tuple(int(s) for s in text.split(","))
    except ValueError:
        raise InputError(f"expected an integer or comma-separated integers, got {text!r}", field="--mfs") from None
    targets = getattr(args, "targets", None)
    if targets is not None:
        targets = [s.strip() for s in targets.split(",")]
    try:
        result = learn(
            args.results_dir,
            test_size=args.test_size,
            cv_folds=getattr(args, "cv_folds", 5),
            mfs=mfs[0] if len(mfs) == 1 else mfs,
            mf=args.mf,
            order=args.order,
            epochs=args.epochs,
            step_size=args.step_size,
            seed=args.seed,
            targets=targets,
            log_target=getattr(args, "log_target", True),
            baselines=not args.no_baselines,
            plots=not getattr(args, "no_plots", False),
        )
    except InputError as err:
        if err.file is None and err.field in _OPTIONS:
            raise InputError(err.message, field=_OPTIONS[err.field]) from None
        raise
    for line in report_lines(result):
        print(line)
    return 0


def _fmt(v) -> str:
    return f"{v:>10.4g}" if v is not None and math.isfinite(v) else f"{'—':>10}"


def report_lines(result) -> list[str]:
    """The ``campaign learn`` report of a :class:`~toolpoint.campaign.learn.LearnResult`, line by line.

    The split and the ANFIS settings, notes, then per target its notes and a
    table of the paper's metrics (train and test) for ANFIS, the baselines and
    the paper's own test numbers, an over-fitting warning and the model with
    the lowest test MAPE.

    Parameters
    ----------
    result : LearnResult

    Returns
    -------
    list of str
    """
    from ..campaign.learn import PAPER, PAPER_N_TEST, overfit_ratio
    from ..learning.metrics import PAPER_METRICS

    st = result.settings
    mfs = st["mfs"]
    rules = math.prod(mfs)
    n_failed = result.n_rows - result.n_ok
    split = (result.n_train, result.n_test)
    lines = [
        f"{result.source}: {result.n_rows} rows, {result.n_ok} ok"
        + (f", {n_failed} failed/other (ignored)" if n_failed else "")
        + f"; split (seed {st['seed']}): {split[0]} train / {split[1]} test"
        + (" (paper: 148 / 30)" if split != (148, 30) else " (as in the paper)"),
        f"ANFIS: inputs {', '.join(result.inputs)}; {'x'.join(map(str, mfs))} {st['mf']} MFs ({rules} rules), "
        f"order {st['order']}, {st['epochs']} epochs, step size {st['step_size']:g}"
        + (", target fitted as log10" if st["log_target"] else ""),
        *result.notes,
    ]
    for t, notes in result.target_notes.items():
        lines += notes
        if t in result.excluded:
            lines.append(f"{t} left out: {result.excluded[t]}")
            continue
        res, unit = result.metrics[t], result.units[t]
        titles = " ".join(f"{title:>10}" for title, _ in PAPER_METRICS.values())
        lines += ["", f"{t} [{unit}]   (ANFIS kept epoch {res['anfis']['kept_epoch']})",
                  f"{'model':<20} {'set':<5} {'n':>4} " + titles]
        for key in ("anfis", "gpr", "gbr"):
            for s in ("train", "test") if key in res else ():
                m = res[key][s]
                lines.append(f"{MODEL_LABELS[key]:<20} {s:<5} {m['n']:>4} "
                             + " ".join(_fmt(m[k]) for k in PAPER_METRICS))
        if t in PAPER:
            lines.append(f"{MODEL_LABELS['paper']:<20} {'test':<5} {PAPER_N_TEST:>4} "
                         + " ".join(_fmt(PAPER[t][k]) for k in PAPER_METRICS))
        if res["anfis"]["overfit"]:
            ratio = overfit_ratio(res["anfis"]["test"]["nrmse"], res["anfis"]["train"]["nrmse"])
            lines.append(f"warning: ANFIS test NRMSE is {ratio:.3g}× its training NRMSE — {rules} rules over-fit "
                         f"{res['anfis']['train']['n']} training rows; try fewer MFs (e.g. --mfs 3,3), fewer --epochs, "
                         "and compare the baselines")
        scored = {k: v["test"]["mape"] for k, v in res.items() if math.isfinite(v["test"]["mape"])}
        best = result.best_test_model.get(t)
        if best is not None and len(scored) > 1:
            line = f"lowest test MAPE: {MODEL_LABELS[best]} {scored[best]:.3g} %"
            if best != "anfis" and "anfis" in scored:
                line += f" (ANFIS {scored['anfis']:.3g} %)"
                if scored["anfis"] > 1.5 * scored[best]:
                    line += f" — {MODEL_LABELS[best]} suits these data better than this ANFIS"
            lines.append(line)
    if result.uncertainty:
        lines += ["", "predictive uncertainty for unseen tools (what `library` samples; models/uncertainty.json):",
                  f"{'':<3}{'from':<8}{'σ decades':>10}{'held-out 90 % coverage':>24}  why"]
        for t, u in result.uncertainty.items():
            cov = u["coverage90"]
            cell = f"{100 * cov:.0f} % of {u['n']}" if cov is not None and math.isfinite(cov) else "—"
            lines.append(f"{t:<3}{u['kind']:<8}{u['sigma_log10']:>10.3g}{cell:>24}  {u['reason']}")
    lines += ["", f"models and metrics in {result.models_dir}"
              + (f"; plots in {result.plots_dir}" if result.plots_dir else "")]
    return lines


def _synth(args) -> int:
    from ..campaign.synth import synthesise

    check_number(args.n, "--n", minimum=1)
    check_number(args.seed, "--seed", minimum=0)
    check_number(args.noise, "--noise", minimum=0)
    check_number(args.blank_noise, "--blank-noise", minimum=0)
    out = out_folder(args.out_dir, "OUT_DIR")  # checked before any work
    if out.exists() and any(out.iterdir()):
        raise InputError("folder exists and is not empty", file=out, field="OUT_DIR")
    s = synthesise(out, n=args.n, seed=args.seed, noise=args.noise, blank_noise=args.blank_noise, fmt=args.format)
    print(f"wrote a campaign of {s['n']} tools to {out} (truth in {out / 'truth'}, not read by the pipeline)")
    return 0


def _run(args) -> int:
    from ..campaign.run import run_campaign

    if args.workers is not None:
        check_number(args.workers, "--workers", minimum=1)
    check_number(args.seed, "--seed", minimum=0)
    r = run_campaign(args.campaign_dir, args.out, method=args.method, workers=args.workers, dask=args.dask,
                     seed=args.seed)
    print(f"{r.ok} identified, {r.failed} failed, {r.skipped} already done; "
          f"{r.seconds:.1f} s → {r.path}")
    if r.failed:  # like `library`: a bad row is reported (one line each, and in its row), the others go on
        print(f"finished, {r.failed} tools failed: their rows in {r.path} say why; fix them and run again "
              "(finished rows are kept)", file=sys.stderr)
        return 1  # 0 only when every tool succeeded, 2 for input that stops the run
    return 0
