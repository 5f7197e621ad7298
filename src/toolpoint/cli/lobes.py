"""``toolpoint lobes FRF [--frf-y FRF_Y] --teeth N --tangential-coeff KT --radial-ratio KR --immersion A
--rpm LO:HI --out LOBES.csv``.

Stability lobes of a milling cut from tool-point receptances: zero-order
approximation (default) or semi-discretisation of modal-fitted FRFs
(``--method sdm``: complex modes per direction, or with ``--frf-xy``/``--frf-yx``
a common-pole fit per force direction realised as a 2×2 state-space model;
``--accuracy`` scales its resolution; progress on stderr). An FRF with no
resonance in its band (noise, all zero, the mode outside the band) is refused
for the SDM.

Every FRF is first cut to its trusted band (:func:`toolpoint.trust.trusted_band`:
low-frequency noise ×1/ω² of a receptance derived from accelerance — the SDM's
modal fit is then weighted in accelerance —, ends of low coherence; the
intersection over the FRFs given), with a one-line note on stderr;
``--band LO:HI`` sets the band instead. Speeds whose limiting chatter frequency
lies on a cutting edge of the band are named on stderr as not trusted.

``--tangential-coeff`` is the cutting coefficient K_t in N/m² and
``--radial-ratio`` the force ratio K_r = K_n/K_t (not the joint stiffnesses
kt, kr of ``identify``; ``--kt``/``--kr`` are refused with one line naming these).

Outputs (written only when everything succeeded, all or none):

* ``--out``: header ``rpm,depth_mm,chatter_hz,lobe`` — the stability limit
  (minimum over lobes) at each speed in mm, the chatter frequency (Hz) and
  the lobe number k (whole chatter waves per tooth period) of the limiting
  lobe. ``inf`` (with chatter ``nan``, lobe −1) means no chatter found at
  that speed (no lobe covers it with the FRF band given, or stable up to the
  SDM's search depth).
* ``--lobes-out``: header ``lobe,rpm,depth_mm,chatter_hz,branch`` — every lobe
  point in the range; ``lobe`` is k (whole chatter waves per tooth period),
  ``branch`` the eigenvalue branch (0/1) that two curves with the same k
  belong to (zero-order approximation; always 0 for SDM).
* ``--plot``: the chart (PNG/PDF/SVG…), unstable region shaded.
"""

from __future__ import annotations

import contextlib
import sys
import warnings
from pathlib import Path

import numpy as np

from ..errors import InputError
from ..io.atomic import atomic_open, atomic_path
from ..stability.milling import MAX_RPM, MAX_RPM_POINTS
from .common import out_path, parse_band, use_agg, warnings_to_stderr

# Flags of earlier versions → what to give instead (one line naming it, exit 2).
REMOVED = {"--kt": "--tangential-coeff (the cutting coefficient Kt, N/m²; not the joint stiffness kt)",
           "--kr": "--radial-ratio (the force ratio Kn/Kt; not the joint stiffness kr)"}


def register(sub) -> None:
    """Add the ``lobes`` sub-command to the CLI's sub-parsers."""
    p = sub.add_parser(
        "lobes",
        help="chatter stability lobes from tool-point FRFs (zero-order or semi-discretisation)",
        description="Stability lobe diagram of a milling cut. Units: Kt in N/m² (600 N/mm² = 6e8), "
        "depths written in mm, speeds in rpm.",
    )
    # Numbers are parsed in run() so bad values give one error line, not argparse's usage block.
    p.add_argument("frf", help="x (feed) receptance: FRF file (.csv/.uff/.unv/.frf) or assembly .toml")
    p.add_argument("--frf-y", help="y receptance (default: the same as x, symmetric tool)")
    p.add_argument("--frf-xy", help="cross receptance x/Fy (default 0)")
    p.add_argument("--frf-yx", help="cross receptance y/Fx (default 0)")
    p.add_argument("--teeth", required=True, help="number of teeth N (integer ≥ 1)")
    p.add_argument("--tangential-coeff", help="tangential cutting coefficient Kt, N/m² (e.g. 6e8 = 600 N/mm²)")
    p.add_argument("--radial-ratio", help="radial force ratio Kr = Kn/Kt, dimensionless (≥ 0)")
    p.removed = REMOVED
    p.add_argument("--immersion", required=True, help="radial immersion a_e/D in (0, 1] (1 = slotting)")
    g = p.add_mutually_exclusive_group()
    g.add_argument("--down", dest="milling", action="store_const", const="down", help="down-milling (default)")
    g.add_argument("--up", dest="milling", action="store_const", const="up", help="up-milling")
    p.set_defaults(milling="down")
    p.add_argument("--rpm", required=True, help="spindle speed range LO:HI in rpm, e.g. 2000:20000")
    p.add_argument("--rpm-points", default="1000",
                   help=f"number of speeds in the range (default 1000, at most {MAX_RPM_POINTS})")
    p.add_argument("--method", default="zoa", help="zoa (zero-order, default) or sdm (semi-discretisation)")
    p.add_argument("--modes", help="sdm: modes to fit per direction (default: chosen by the fit)")
    p.add_argument("--accuracy", default="1",
                   help="sdm: resolution factor 0.25–16 (default 1: within ≈ 1 %% of the converged limit); "
                   "time grows with it: 0.5 → ≈ 0.7×, 2 → ≈ 2.3×, 4 → ≈ 8× the CPU time of 1 (4 modes per direction)")
    p.add_argument("--band", metavar="LO:HI",
                   help="use the FRFs from LO to HI Hz only (default: the trusted band found in the data — "
                   "low-frequency noise ×1/ω² and low coherence left out, with a note on stderr)")
    p.add_argument("--out", required=True, help="CSV of the limit: rpm,depth_mm,chatter_hz,lobe")
    p.add_argument("--lobes-out", help="CSV of every lobe: lobe,rpm,depth_mm,chatter_hz,branch")
    p.add_argument("--plot", help="chart file (.png, .pdf, .svg, …)")
    p.set_defaults(func=run)


# ----------------------------------------------------------------- parsing
def _number(text: str, flag: str, kind=float):
    """``text`` as a finite float (or int), else an InputError naming ``flag``."""
    try:
        v = kind(text)
    except (TypeError, ValueError):
        raise InputError(f"not a{'n integer' if kind is int else ' number'}: {text!r}", field=flag) from None
    if kind is float and not np.isfinite(v):
        raise InputError(f"must be finite, got {text!r}", field=flag)
    return v


def _rpm_range(text: str) -> tuple[float, float]:
    """``LO:HI`` as two speeds in rpm, 0 < LO < HI."""
    parts = text.split(":")
    if len(parts) != 2:
        raise InputError(f"expected LO:HI (e.g. 2000:20000), got {text!r}", field="--rpm")
    lo, hi = (_number(s, "--rpm") for s in parts)
    if lo <= 0:
        raise InputError(f"speeds must be > 0 rpm, got {text!r}", field="--rpm")
    if hi <= lo:
        raise InputError(f"range reversed or empty: {text!r} (LO must be below HI)", field="--rpm")
    if hi > MAX_RPM:
        raise InputError(f"speeds above {MAX_RPM:g} rpm are not spindle speeds, got {text!r}", field="--rpm")
    return lo, hi


def _load(path: str, flag: str, freq_hz=None):
    """An FRF from a file, or from an assembly TOML (``toolpoint.dynamics.model.frf_from_toml``)."""
    from ..io.table import check_regular_file

    p = Path(path)
    try:
        check_regular_file(p, what="FRF file")
    except InputError as err:
        raise InputError(err.message, file=p, field=flag) from None
    try:
        if p.suffix.lower() == ".toml":
            from ..dynamics.model import frf_from_toml

            frf = frf_from_toml(p, freq_hz=freq_hz)
        else:
            from ..io.frf_files import read_frf

            frf = read_frf(p, min_points=3)
        return frf.to_receptance()
    except InputError:
        raise
    except (ValueError, OSError) as err:  # the model's own checks, unreadable files
        raise InputError(str(err), file=p, field=flag) from None


# ----------------------------------------------------------------- command
def _cutting(args):
    """The cutting conditions from the flags, errors naming the flag given."""
    from ..stability import CuttingConditions

    values = {}
    for flag, what in (("--tangential-coeff", "cutting coefficient Kt, N/m²"),
                       ("--radial-ratio", "force ratio Kn/Kt, dimensionless")):
        given = getattr(args, flag[2:].replace("-", "_"))
        if given is None:
            raise InputError(f"required ({what})", field=flag)
        values[flag] = _number(given, flag)
    teeth = _number(args.teeth, "--teeth", int)
    immersion = _number(args.immersion, "--immersion")
    flags = {"teeth": "--teeth", "tangential_coeff": "--tangential-coeff", "radial_ratio": "--radial-ratio",
             "radial_immersion": "--immersion", "milling": "--down/--up"}
    try:
        cut = CuttingConditions(teeth=teeth, tangential_coeff=values["--tangential-coeff"],
                                radial_ratio=values["--radial-ratio"], radial_immersion=immersion,
                                milling=args.milling)
    except InputError as err:
        raise InputError(err.message, field=flags.get(err.field, err.field)) from None
    if cut.tangential_coeff > KT_MAX:  # finite but overflowing the lobe arithmetic (1e300 × depth × …)
        raise InputError(f"{cut.tangential_coeff:g} N/m² is beyond any material (typical 1e8–3e9 N/m², "
                         f"refused above {KT_MAX:g})", field="--tangential-coeff")
    return cut


#: Largest specific cutting force accepted, N/m² (1e6 N/mm²: 300 × the hardest alloys' ~3e9 N/m²).
KT_MAX = 1e12


def run(args) -> int:
    """Run ``toolpoint lobes``; returns the exit code (InputErrors are left to the caller: exit 2)."""
    cut = _cutting(args)
    lo, hi = _rpm_range(args.rpm)
    npts = _number(args.rpm_points, "--rpm-points", int)
    if not 2 <= npts <= MAX_RPM_POINTS:
        raise InputError(f"must be from 2 to {MAX_RPM_POINTS}, got {npts}", field="--rpm-points")
    method = args.method.strip().lower()
    if method not in ("zoa", "sdm"):
        raise InputError(f"must be 'zoa' or 'sdm', got {args.method!r}", field="--method")
    n_modes = None
    if args.modes is not None:
        n_modes = _number(args.modes, "--modes", int)
        if n_modes < 1:
            raise InputError(f"must be ≥ 1, got {n_modes}", field="--modes")
    accuracy = _number(args.accuracy, "--accuracy")
    if not 0.25 <= accuracy <= 16:
        raise InputError(f"must be from 0.25 to 16, got {args.accuracy}", field="--accuracy")

    band = parse_band(args.band)
    outs = _outputs(args)
    frfs = {"FRF": _load(args.frf, "FRF")}
    for flag in ("--frf-y", "--frf-xy", "--frf-yx"):
        path = getattr(args, flag[2:].replace("-", "_"))
        frfs[flag] = None if path is None else _load(path, flag, freq_hz=frfs["FRF"].freq_hz)
    files = {"FRF": args.frf, "--frf-y": args.frf_y, "--frf-xy": args.frf_xy, "--frf-yx": args.frf_yx}
    from ..progress import Progress
    from ..stability.measured import lobes_from_frf

    with warnings_to_stderr():
        rpm = np.linspace(lo, hi, npts)
        if cut.tangential_coeff < 1e6:
            warnings.warn(f"Kt {cut.tangential_coeff:g} N/m² is very small (typical 1e8–3e9 N/m²): "
                          "was it given in N/mm²?")
        if method == "zoa":
            for flag, given in (("--modes", n_modes is not None), ("--accuracy", args.accuracy != "1")):
                if given:
                    warnings.warn(f"{flag} is used by --method sdm only; ignored")
        with contextlib.ExitStack() as stack:
            bar = []  # opened when the SDM starts: a refused model prints its one line only

            def step(done, total):
                if not bar:
                    bar.append(stack.enter_context(Progress(total, "semi-discretisation", "speed")))
                bar[0].update(done - bar[0].n)

            found = lobes_from_frf(frfs["FRF"], cut, rpm, frf_y=frfs["--frf-y"], frf_xy=frfs["--frf-xy"],
                                   frf_yx=frfs["--frf-yx"], method=method, band=band, n_modes=n_modes,
                                   accuracy=accuracy, files=files, log=print, progress=step)
    res = found.lobes
    if method == "sdm":
        ms = np.unique(res.params["m"])
        print(f"semi-discretisation: {ms.min()}–{ms.max()} steps over the cut" if ms.size > 1 else
              f"semi-discretisation: {ms[0]} steps over the cut")
    fig = _figure(res) if outs["plot"] else None
    _write(outs, res, fig)
    for note in found.notes:
        print(note, file=sys.stderr)
    _summary(res, outs, found.edge, found.min_at_edge)
    return 0


def _outputs(args) -> dict:
    """The output paths, checked before any work (distinct, writable, not an input)."""
    outs = {"out": out_path(args.out, "--out"), "lobes": None, "plot": None}
    if args.lobes_out:
        outs["lobes"] = out_path(args.lobes_out, "--lobes-out")
    if args.plot:
        outs["plot"] = out_path(args.plot, "--plot")
        from matplotlib.figure import Figure

        fmt = outs["plot"].suffix.lstrip(".").lower()
        if fmt not in Figure().canvas.get_supported_filetypes():
            raise InputError(f"unsupported image format {fmt or '(none)'!r} (use .png, .pdf, .svg, …)", field="--plot")
    given = [p.resolve() for p in outs.values() if p is not None]
    if len(set(given)) != len(given):
        raise InputError("--out, --lobes-out and --plot must be different files", field="--out")
    inputs = {Path(p).resolve() for p in (args.frf, args.frf_y, args.frf_xy, args.frf_yx) if p}
    if inputs & set(given):
        raise InputError("an output would overwrite an input FRF", field="--out")
    return outs


def _figure(res):
    """The stability chart as a matplotlib Figure (not pyplot: no global state)."""
    use_agg()
    from matplotlib.figure import Figure

    fig = Figure(figsize=(8, 4.5), constrained_layout=True)
    ax = fig.subplots()
    res.plot(ax=ax)
    p = res.params
    ax.set_title(
        f"{res.method.upper()}: {p['teeth']} teeth, Kt = {p['tangential_coeff'] / 1e6:g} N/mm², "
        f"Kr = {p['radial_ratio']:g}, "
        f"a_e/D = {p['radial_immersion']:g}, {p['milling']}-milling",
        fontsize="medium",
    )
    return fig


def _write(outs, res, fig) -> None:
    """Write every output to a temporary file; rename them all only if all succeeded."""
    with contextlib.ExitStack() as stack:
        fh = stack.enter_context(atomic_open(outs["out"], "w", newline=""))
        fh.write("rpm,depth_mm,chatter_hz,lobe\n")
        np.savetxt(fh, np.column_stack([res.rpm, res.depth_mm, res.chatter_hz, res.lobe_number]),
                   fmt=["%.10g", "%.10g", "%.10g", "%d"], delimiter=",")
        if outs["lobes"]:
            fh = stack.enter_context(atomic_open(outs["lobes"], "w", newline=""))
            fh.write("lobe,rpm,depth_mm,chatter_hz,branch\n")
            for lobe in res.lobes:
                rows = np.column_stack([np.full(lobe.rpm.size, lobe.k), lobe.rpm, 1e3 * lobe.depth_m,
                                        lobe.chatter_hz, np.full(lobe.rpm.size, lobe.branch)])
                np.savetxt(fh, rows, fmt=["%d", "%.10g", "%.10g", "%.10g", "%d"], delimiter=",")
        if outs["plot"]:
            tmp = stack.enter_context(atomic_path(outs["plot"]))
            fig.savefig(tmp, format=outs["plot"].suffix.lstrip(".").lower(), dpi=130)


def _summary(res, outs, edge=None, at_edge=False) -> None:
    """Print the minimum, the best pocket and what was written.

    ``edge``: speeds whose limit is not trusted; ``at_edge``: the absolute minimum is not.
    """
    if np.isfinite(res.min_depth_m):
        print(f"absolute minimum depth: {1e3 * res.min_depth_m:.4g} mm at {res.min_rpm:.0f} rpm "
              f"(chatter {res.min_chatter_hz:.1f} Hz)" + (" — not trusted: chatter at the band edge" if at_edge
                                                          else ""))
        if at_edge and edge is not None and not edge.all():
            k = int(np.argmin(np.where(edge, np.inf, res.depth_m)))
            if np.isfinite(res.depth_m[k]):
                print(f"lowest trusted limit: {res.depth_mm[k]:.4g} mm at {res.rpm[k]:.0f} rpm "
                      f"(chatter {res.chatter_hz[k]:.1f} Hz)")
    else:
        print("no chatter found in the speed range (no lobe reaches it)")
    best = res.pocket()
    pr, pd = best.rpm, best.depth_m
    if np.isfinite(pd):
        print(f"best stable pocket: {1e3 * pd:.4g} mm at {pr:.0f} rpm")
    else:
        print("best stable pocket: none inside the speed range (the limit has no local maximum strictly inside it; "
              "widen --rpm)")
    n_inf = int(np.isinf(res.depth_m).sum())
    if n_inf:
        print(f"note: {n_inf} of {res.rpm.size} speeds have no limit found (written as inf)")
    written = [str(p) for p in outs.values() if p is not None]
    print("wrote " + ", ".join(written))
