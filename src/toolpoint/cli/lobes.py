"""``toolpoint lobes FRF [--frf-y FRF_Y] --teeth N --kt KT --kr KR --immersion A --rpm LO:HI --out LOBES.csv``.

Stability lobes of a milling cut from tool-point receptances: zero-order
approximation (default) or semi-discretisation of modal-fitted FRFs.

Outputs (written only when everything succeeded, all or none):

* ``--out``: header ``rpm,depth_mm,chatter_hz`` — the stability limit (minimum
  over lobes) at each speed in mm, and the chatter frequency (Hz) of the
  limiting lobe. ``inf`` means no chatter found at that speed (no lobe covers
  it with the FRF band given, or stable up to the SDM's search depth).
* ``--lobes-out``: header ``lobe,rpm,depth_mm,chatter_hz,branch`` — every lobe
  point in the range; ``lobe`` is k (whole chatter waves per tooth period),
  ``branch`` the eigenvalue branch (0/1) that two curves with the same k
  belong to (zero-order approximation; always 0 for SDM).
* ``--plot``: the chart (PNG/PDF/SVG…), unstable region shaded.
"""

from __future__ import annotations

import contextlib
import warnings
from pathlib import Path

import numpy as np

from ..io.atomic import atomic_open, atomic_path
from ..errors import InputError
from .common import out_path, use_agg, warnings_to_stderr


def register(sub) -> None:
    p = sub.add_parser(
        "lobes",
        help="chatter stability lobes from tool-point FRFs (zero-order or semi-discretisation)",
        description="Stability lobe diagram of a milling cut. Units: Kt in N/m² (600 N/mm² = 6e8), "
        "depths written in mm, speeds in rpm.",
    )
    # Numbers are parsed in run() so bad values give one error line, not argparse's usage block.
    p.add_argument("frf", help="x (feed) receptance: FRF file (.csv/.uff/.unv/.frf) or assembly .toml")
    p.add_argument("--frf-y", help="y receptance (default: the same as x, symmetric tool)")
    p.add_argument("--teeth", required=True, help="number of teeth N (integer ≥ 1)")
    p.add_argument("--kt", required=True, help="tangential cutting coefficient Kt, N/m² (e.g. 6e8)")
    p.add_argument("--kr", required=True, help="radial ratio Kr = Kn/Kt (≥ 0)")
    p.add_argument("--immersion", required=True, help="radial immersion a_e/D in (0, 1] (1 = slotting)")
    g = p.add_mutually_exclusive_group()
    g.add_argument("--down", dest="milling", action="store_const", const="down", help="down-milling (default)")
    g.add_argument("--up", dest="milling", action="store_const", const="up", help="up-milling")
    p.set_defaults(milling="down")
    p.add_argument("--rpm", required=True, help="spindle speed range LO:HI in rpm, e.g. 2000:20000")
    p.add_argument("--rpm-points", default="1000", help="number of speeds in the range (default 1000)")
    p.add_argument("--method", default="zoa", help="zoa (zero-order, default) or sdm (semi-discretisation)")
    p.add_argument("--modes", help="sdm: modes to fit per direction (default: chosen by the fit)")
    p.add_argument("--out", required=True, help="CSV of the limit: rpm,depth_mm,chatter_hz")
    p.add_argument("--lobes-out", help="CSV of every lobe: lobe,rpm,depth_mm,chatter_hz,branch")
    p.add_argument("--plot", help="chart file (.png, .pdf, .svg, …)")
    p.set_defaults(func=run)


# ----------------------------------------------------------------- parsing
def _number(text: str, flag: str, kind=float):
    try:
        v = kind(text)
    except (TypeError, ValueError):
        raise InputError(f"not a{'n integer' if kind is int else ' number'}: {text!r}", field=flag) from None
    if kind is float and not np.isfinite(v):
        raise InputError(f"must be finite, got {text!r}", field=flag)
    return v


def _rpm_range(text: str) -> tuple[float, float]:
    parts = text.split(":")
    if len(parts) != 2:
        raise InputError(f"expected LO:HI (e.g. 2000:20000), got {text!r}", field="--rpm")
    lo, hi = (_number(s, "--rpm") for s in parts)
    if lo <= 0:
        raise InputError(f"speeds must be > 0 rpm, got {text!r}", field="--rpm")
    if hi <= lo:
        raise InputError(f"range reversed or empty: {text!r} (LO must be below HI)", field="--rpm")
    return lo, hi


def _load(path: str, flag: str, freq_hz=None):
    """An FRF from a file, or from an assembly TOML (``toolpoint.dynamics.model.frf_from_toml``)."""
    p = Path(path)
    if not p.is_file():
        raise InputError("no such file", file=p, field=flag)
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
def run(args) -> int:
    teeth = _number(args.teeth, "--teeth", int)
    if teeth < 1:
        raise InputError(f"must be ≥ 1, got {teeth}", field="--teeth")
    kt = _number(args.kt, "--kt")
    if kt <= 0:
        raise InputError(f"must be > 0 N/m², got {args.kt}", field="--kt")
    kr = _number(args.kr, "--kr")
    if kr < 0:
        raise InputError(f"must be ≥ 0, got {args.kr}", field="--kr")
    immersion = _number(args.immersion, "--immersion")
    if not 0 < immersion <= 1:
        raise InputError(f"radial immersion a_e/D must be in (0, 1], got {args.immersion}", field="--immersion")
    lo, hi = _rpm_range(args.rpm)
    npts = _number(args.rpm_points, "--rpm-points", int)
    if npts < 2:
        raise InputError(f"must be ≥ 2, got {npts}", field="--rpm-points")
    method = args.method.strip().lower()
    if method not in ("zoa", "sdm"):
        raise InputError(f"must be 'zoa' or 'sdm', got {args.method!r}", field="--method")
    n_modes = None
    if args.modes is not None:
        n_modes = _number(args.modes, "--modes", int)
        if n_modes < 1:
            raise InputError(f"must be ≥ 1, got {n_modes}", field="--modes")

    outs = _outputs(args)
    with warnings_to_stderr():
        frf_x = _load(args.frf, "FRF")
        frf_y = None
        if args.frf_y is not None:
            frf_y = _load(args.frf_y, "--frf-y", freq_hz=frf_x.freq_hz)
        rpm = np.linspace(lo, hi, npts)
        cut = dict(teeth=teeth, kt=kt, kr=kr, radial_immersion=immersion, milling=args.milling, rpm=rpm)
        if kt < 1e6:
            warnings.warn(f"--kt {kt:g} N/m² is very small (typical 1e8–3e9 N/m²): was it given in N/mm²?")
        if method == "zoa":
            from ..stability import zoa_lobes

            if n_modes is not None:
                warnings.warn("--modes is used by --method sdm only; ignored")

            res = zoa_lobes(frf_x, frf_y, **cut)
        else:
            res = _sdm(frf_x, frf_y, n_modes, cut)
    fig = _figure(res) if outs["plot"] else None
    _write(outs, res, fig)
    _summary(res, outs)
    return 0


def _outputs(args) -> dict:
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
    inputs = {Path(p).resolve() for p in (args.frf, args.frf_y) if p}
    if inputs & set(given):
        raise InputError("an output would overwrite an input FRF", field="--out")
    return outs


def _sdm(frf_x, frf_y, n_modes, cut):
    from ..stability import fit_modes, sdm_lobes

    mx = fit_modes(frf_x, n_modes)
    print(f"modal fit, x ({frf_x.label or 'FRF'}):\n{mx.table()}")
    if frf_y is None:
        my = mx
        print("y: same modes as x (symmetric tool)")
    else:
        my = fit_modes(frf_y, n_modes)
        print(f"modal fit, y ({frf_y.label or 'FRF_Y'}):\n{my.table()}")
    res = sdm_lobes(mx, my, **cut)
    ms = np.unique(res.params["m"])
    print(f"semi-discretisation: {ms.min()}–{ms.max()} steps over the cut" if ms.size > 1 else
          f"semi-discretisation: {ms[0]} steps over the cut")
    return res


def _figure(res):
    use_agg()
    from matplotlib.figure import Figure

    fig = Figure(figsize=(8, 4.5), constrained_layout=True)
    ax = fig.subplots()
    res.plot(ax=ax)
    p = res.params
    ax.set_title(
        f"{res.method.upper()}: {p['teeth']} teeth, Kt = {p['kt'] / 1e6:g} N/mm², Kr = {p['kr']:g}, "
        f"a_e/D = {p['radial_immersion']:g}, {p['milling']}-milling",
        fontsize="medium",
    )
    return fig


def _write(outs, res, fig) -> None:
    """Write every output to a temporary file; rename them all only if all succeeded."""
    with contextlib.ExitStack() as stack:
        fh = stack.enter_context(atomic_open(outs["out"], "w", newline=""))
        fh.write("rpm,depth_mm,chatter_hz\n")
        np.savetxt(fh, np.column_stack([res.rpm, res.depth_mm, res.chatter_hz]), fmt="%.10g", delimiter=",")
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


def _summary(res, outs) -> None:
    if np.isfinite(res.min_depth_m):
        print(f"absolute minimum depth: {1e3 * res.min_depth_m:.4g} mm at {res.min_rpm:.0f} rpm "
              f"(chatter {res.min_chatter_hz:.1f} Hz)")
    else:
        print("no chatter found in the speed range (no lobe reaches it)")
    pr, pd = res.pocket()
    if np.isfinite(pd):
        print(f"best stable pocket: {1e3 * pd:.4g} mm at {pr:.0f} rpm")
    elif np.isinf(pd):
        print(f"best stable pocket: no limit found at {pr:.0f} rpm (beyond the lobes / search depth)")
    n_inf = int(np.isinf(res.depth_m).sum())
    if n_inf:
        print(f"note: {n_inf} of {res.rpm.size} speeds have no limit found (written as inf)")
    written = [str(p) for p in outs.values() if p is not None]
    print("wrote " + ", ".join(written))
