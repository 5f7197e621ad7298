"""``toolpoint frf ASSEMBLY.toml --out FRF.csv [--plot FRF.png] [--point tool|spindle_holder]``."""

from __future__ import annotations

from pathlib import Path

from ..dynamics.assembly import load_assembly
from ..errors import InputError
from ..io.frf_files import write_frf
from ..dynamics.model import AssemblyModel
from .common import out_path, save_figure, use_agg, warnings_to_stderr


def register(sub) -> None:
    """Add the ``frf`` sub-command to the argparse sub-parsers ``sub``."""
    p = sub.add_parser("frf", help="tool-point (or holder-tip) receptance of an assembly by RCSA")
    p.add_argument("assembly", help="assembly TOML file")
    p.add_argument("--out", required=True,
                   help="FRF file to write, receptance m/N: .csv (freq_hz,real,imag), .uff or .frf")
    p.add_argument("--plot", help="PNG/PDF/SVG file with magnitude and phase")
    p.add_argument(
        "--point",
        choices=("tool", "spindle_holder"),
        default="tool",
        help="tool tip of the whole assembly (default) or holder tip of the spindle–holder subassembly (Eq. 1)",
    )
    p.set_defaults(func=run)


def run(args) -> int:
    """Compute the receptance FRF of ``args.assembly``, write ``--out`` (and ``--plot``); returns exit code 0.

    Bad input raises :class:`~toolpoint.errors.InputError` before anything is written
    (the CLI turns it into one line and exit code 2).
    """
    out = out_path(args.out, "--out", inputs=[args.assembly])
    if out.suffix.lower() not in (".csv", ".uff", ".unv", ".uf", ".frf"):
        raise InputError("use .csv, .uff/.unv or .frf (the format follows the extension)", file=out, field="--out")
    plot = out_path(args.plot, "--plot", inputs=[args.assembly]) if args.plot else None
    with warnings_to_stderr():
        assembly = load_assembly(args.assembly, require_holder_tool=(args.point == "tool"))
        model = AssemblyModel(assembly)
        frf = model.tool_point_frf() if args.point == "tool" else model.spindle_holder_frf()
    if plot:  # render first: a plotting failure must not leave a CSV without its figure
        use_agg()
        import matplotlib.pyplot as plt

        fig, ax = plt.subplots(2, 1, sharex=True, figsize=(7, 5.5), constrained_layout=True)
        frf.plot(ax=ax, label=f"{frf.label} — {Path(args.assembly).name}")
        ax[0].set_title("RCSA receptance h = y/F")
    write_frf(out, frf)
    if plot:
        save_figure(fig, plot)
    f_pk, h_pk = frf.peak()
    static = f"; static {frf.values[0].real:.4g} m/N" if frf.freq_hz[0] == 0 else ""
    print(f"{frf.label}: {len(frf)} points {frf.freq_hz[0]:g}–{frf.freq_hz[-1]:g} Hz; "
          f"dominant peak {f_pk:g} Hz, |h| = {h_pk:.4g} m/N{static} → {out}")
    return 0
