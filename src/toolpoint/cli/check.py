"""``toolpoint check FRF... [--band LO:HI] [--modes N] [--quantity Q]``: one screen on a measurement before it is
trusted — the band used and why, the modes with a confidence word (one FRF: a driving point unless
``--driving-point none``), the fit's notes, coherence, what looks wrong
(:func:`toolpoint.dynamics.check.check_measurement`). Writes nothing; exit 0 when it could check the files."""

from __future__ import annotations

from .common import parse_band, warnings_to_stderr


def register(sub) -> None:
    """Add the ``check`` sub-command to the CLI's sub-parsers."""
    p = sub.add_parser("check", help="check measured FRFs before trusting them: band, modes, coherence, problems",
                       description="One screen on measured FRFs: the band used and why, the modes with a "
                       "confidence word, coherence, and what looks wrong. Writes nothing.")
    p.add_argument("frf", nargs="+", help="FRF files (.csv/.txt/.uff/.frf) of one structure to one input")
    p.add_argument("--band", help="use this band LO:HI in Hz instead of the trusted band found in the data")
    p.add_argument("--modes", help="number of modes of the fit (default: chosen from the data)")
    p.add_argument("--quantity", choices=("receptance", "mobility", "accelerance"),
                   help="what the files hold when they do not say (default receptance)")
    p.add_argument("--driving-point", metavar="K|none",
                   help="0-based index K of the FRF that is a driving point (e.g. the tool point's direct FRF): its "
                   "modes must have positive modal mass; a mode of negative mass the data demand is named (default: "
                   "0 when one FRF is given, none when several; none: no such check)")
    p.set_defaults(func=run)


def run(args) -> int:
    """Check the files and print the screen; returns 0."""
    from ..dynamics.check import check_measurement
    from ..errors import InputError
    from ..io.frf_files import read_frf

    from .modal import parse_driving_point

    band = parse_band(args.band)
    driving = parse_driving_point(getattr(args, "driving_point", None), len(args.frf))
    n_modes = None
    if args.modes is not None:
        try:
            n_modes = int(args.modes)
        except ValueError:
            n_modes = 0
        if n_modes < 1:
            raise InputError(f"expected a positive integer, got {args.modes!r}", file="command line", field="--modes")
    with warnings_to_stderr():
        kw = {"quantity": args.quantity} if args.quantity else {}
        frfs = [read_frf(path, **kw).to_receptance() if args.quantity else read_frf(path) for path in args.frf]
        result = check_measurement(frfs, files=args.frf, band=band, n_modes=n_modes, driving_point=driving)
    print(result.report())
    return 0
