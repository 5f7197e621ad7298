"""``toolpoint predict ASSEMBLY_OR_CAMPAIGN --diameter D --overhang L --models DIR --out FRF.csv [--plot PNG]``."""

from __future__ import annotations

import math
import sys

from ..errors import InputError
from ..io.frf_files import write_frf
from ..identification.params import PARAMS, UNITS
from .common import out_path, save_figure, use_agg, warnings_to_stderr


def register(sub) -> None:
    """Add the ``predict`` command to the ``toolpoint`` sub-parsers."""
    p = sub.add_parser("predict", help="tool-point FRF of an unmeasured tool from the ANFIS-predicted joint")
    p.add_argument("source", help="campaign folder or assembly TOML (spindle, holder, spindle–holder joint)")
    p.add_argument("--diameter", type=float, required=True, help="tool diameter D, mm")
    p.add_argument("--overhang", type=float, required=True, help="tool overhang L, mm")
    p.add_argument("--models", required=True, help="models folder from `toolpoint campaign learn`")
    p.add_argument("--holder", help="holder name (campaigns with several)")
    p.add_argument("--out", required=True, help="FRF file (.csv, .uff or .frf; receptance m/N)")
    p.add_argument("--plot", help="figure of the predicted FRF")
    p.set_defaults(func=run)


def run(args) -> int:
    """Predict the joint of a tool (D, L in mm) from the learned models and write its tool-point FRF."""
    from ..campaign.predict import predict_frf

    from ..campaign.results import MAX_LENGTH_MM, MIN_LENGTH_MM

    for name in ("diameter", "overhang"):
        if not (math.isfinite(getattr(args, name)) and MIN_LENGTH_MM <= getattr(args, name) <= MAX_LENGTH_MM):
            raise InputError(f"must be a number from {MIN_LENGTH_MM:g} to {MAX_LENGTH_MM:g} mm, got "
                             f"{getattr(args, name):g}",
                             file="command line", field=f"--{name}")
    inputs = _inputs(args)
    out = out_path(args.out, "--out", inputs=inputs)
    plot = out_path(args.plot, "--plot", inputs=inputs) if args.plot else None
    with warnings_to_stderr():
        pred = predict_frf(args.source, args.diameter, args.overhang, args.models, holder=args.holder)
    frf, joint = pred.frf, pred.joint
    for n in joint.notes:
        print(f"note: {n}", file=sys.stderr)
    fig = None
    if plot:
        use_agg()
        import matplotlib.pyplot as plt

        fig, ax = plt.subplots(2, 1, sharex=True, figsize=(7, 5.5), constrained_layout=True)
        frf.plot(ax=ax)
        ax[0].set_title(f"predicted tool point: D {args.diameter:g} mm, L {args.overhang:g} mm")
    write_frf(out, frf)
    if fig is not None:
        save_figure(fig, plot)
    f_pk, h_pk = frf.peak()
    print("predicted joint (median, 90 % interval calibrated on held-out tools):")
    for k, p in enumerate(PARAMS):
        print(f"  {p} = {joint.joint[k]:.4g} {UNITS[p]}  [{joint.p05[k]:.4g}, {joint.p95[k]:.4g}]")
    print(f"dominant peak {f_pk:g} Hz, |h| = {h_pk:.4g} m/N → {out}")
    return 0


def _inputs(args) -> list:
    """Every file ``predict`` reads: the source (or, for a campaign folder, its files) and the models."""
    from pathlib import Path

    files = []
    for root in (Path(args.source), Path(args.models)):
        files += [q for q in root.rglob("*") if q.is_file()] if root.is_dir() else [root]
    return files
