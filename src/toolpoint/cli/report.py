"""``toolpoint report DIR [--out FILE]``: one self-contained HTML page of a ``toolpoint library`` run."""

from __future__ import annotations

from pathlib import Path


def register(sub) -> None:
    """Add the ``report`` sub-command."""
    p = sub.add_parser("report", help="HTML report of a 'toolpoint library' run",
                       description="One self-contained HTML page (no network): a sortable, filterable overview "
                       "of all tools, and per tool the FRF band, lobes with the probability map, and the joint.")
    p.add_argument("dir", help="output folder of 'toolpoint library'")
    p.add_argument("--out", help="HTML file (default DIR/report.html)")
    p.set_defaults(func=run)


def run(args) -> int:
    """Run ``toolpoint report``."""
    from .common import out_path, use_agg, warnings_to_stderr
    from ..recommend.report import write_report

    use_agg()
    d = Path(args.dir)
    inputs = [d / "recommendations.csv", *sorted((d / "tools").glob("*"))]  # what the report reads
    out = out_path(args.out, "--out", inputs=inputs) if args.out else None
    with warnings_to_stderr():
        print(f"report → {write_report(args.dir, out)}")
    return 0
