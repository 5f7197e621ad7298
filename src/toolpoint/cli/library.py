"""``toolpoint library LIB --campaign CAMP --models MODELS --out DIR [--dask ADDRESS] [--model gp] [--report]``.

For every tool of a tool library (CSV, :mod:`toolpoint.recommend.library`):
the predicted joint with its uncertainty, the tool-point FRF band, the
stability lobes with their 5/50/95 % limits and probability of stability, and
the recommended operating points, in ``DIR/recommendations.csv`` (one row per
tool, written as tools finish; a killed run is resumed) and ``DIR/tools/``.
A bad row gives one line on stderr naming its id (and a ``failed`` row); the
other tools go on. An unreadable or empty library is one line, exit 2.
"""

from __future__ import annotations

import sys

from ..errors import InputError

#: run_library() keyword → CLI option, to name the option in an InputError.
_OPTIONS = {"n_samples": "--samples", "rpm_points": "--rpm-points", "margin": "--margin",
            "rpm_tolerance": "--rpm-tolerance", "outside": "--outside", "sub_replicates": "--subassembly-replicates"}


def register(sub) -> None:
    """Add the ``library`` sub-command."""
    p = sub.add_parser("library", help="safe spindle speeds and depths for every tool of a tool library",
                       description="Predicted FRF, lobes with their uncertainty, and recommended operating points "
                       "for every tool of a library CSV. Depths in mm, speeds in rpm.")
    p.add_argument("library", help="tool library CSV (columns: see docs/design/recommend.md)")
    p.add_argument("--campaign", required=True, help="campaign folder (tool family, holders)")
    p.add_argument("--models", required=True, help="models folder of 'campaign learn'")
    p.add_argument("--out", required=True, help="output folder (recommendations.csv, tools/)")
    p.add_argument("--workers", type=int, help="local processes (default: all cores)")
    p.add_argument("--dask", metavar="ADDRESS", help="run on an existing Dask scheduler")
    p.add_argument("--samples", type=int, default=200, help="joint samples per tool (default 200)")
    p.add_argument("--rpm-points", type=int, default=500, help="speeds per tool (default 500)")
    p.add_argument("--margin", type=float, default=0.1,
                   help="recommended depth = robust 5 %% limit × (1 − margin) (default 0.1)")
    p.add_argument("--rpm-tolerance", type=float, default=0.01,
                   help="relative spindle-speed tolerance of the robust limit (default 0.01)")
    p.add_argument("--outside", choices=("widen", "refuse"), default="widen",
                   help="a tool outside the learned (D, L) range: widen its uncertainty (default) or refuse it")
    p.add_argument("--model", choices=("anfis", "gp"), default="anfis",
                   help="joint distribution as 'campaign learn' calibrated it (ANFIS or the family's power law with a "
                   "cross-validated σ, or the campaign's spread; default) or from the GP baselines it saved (their "
                   "own predictive σ, not calibrated out of sample)")
    p.add_argument("--subassembly-replicates", type=int, default=8,
                   help="bootstrap replicates of a blank-measured holder's subassembly the samples spread over (its "
                   "measurement uncertainty; 0: exact; default 8)")
    p.add_argument("--seed", type=int, default=0,
                   help="seed of the joint samples (each tool its own from it; default 0)")
    p.add_argument("--report", action="store_true", help="also write DIR/report.html")
    p.set_defaults(func=run)


def run(args) -> int:
    """Run ``toolpoint library``."""
    from ..recommend.run import run_library
    from .common import check_number, out_folder

    check_number(args.seed, "--seed", minimum=0)  # NumPy's generator refuses a negative seed with a ValueError
    if args.workers is not None:
        check_number(args.workers, "--workers", minimum=1)
    out_folder(args.out, "--out")  # checked before any work

    def say(line):
        print(line, file=sys.stderr)

    try:
        counts = run_library(args.library, args.campaign, args.models, args.out, workers=args.workers,
                             dask=args.dask, n_samples=args.samples, rpm_points=args.rpm_points, seed=args.seed,
                             margin=args.margin, rpm_tolerance=args.rpm_tolerance, outside=args.outside,
                             sub_replicates=args.subassembly_replicates,
                             model=args.model, on_bad=say)
    except InputError as err:  # a setting: name its option
        if err.file is None and err.field in _OPTIONS:
            raise InputError(err.message, file="command line", field=_OPTIONS[err.field]) from None
        raise
    print(f"{counts.ok} tools ok, {counts.failed} failed, {counts.skipped} already done, "
          f"{counts.seconds:.1f} s → {counts.path}")
    if args.report:
        from ..recommend.report import write_report

        try:
            print(f"report → {write_report(args.out)}")
        except OSError as e:
            raise InputError(f"cannot write the report: {e}", file=args.out) from None
    if counts.failed:  # a script can trust the code: 0 only when every tool succeeded (as make -k, rsync)
        print(f"finished, {counts.failed} tools failed (their rows say why)", file=sys.stderr)
        return 1
    return 0
