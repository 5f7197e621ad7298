"""``toolpoint map --mode-x FN:K:ZETA … --teeth N --tangential-coeff KT --radial-ratio KR --immersion A
--rpm LO:HI --depth-mm LO:HI --out MAP.csv [--plot MAP.png]``.

Stability and surface location error over a speed × depth grid, simulated in the time domain as one
vectorised batch (:func:`toolpoint.simulation.simulate_map`), with the semi-discretisation lobes of the same
modes for comparison. Modes on the command line or in a modal TOML/JSON file, as for ``simulate``.

Outputs (written only when everything succeeded):

* ``--out``: header ``rpm,depth_mm,stable,metric,growth_per_rev,sle_um,surface_pv_um,chatter_hz``, one row per
  grid point (``stable`` 1/0; ``chatter_hz`` nan where stable).
* ``--lobes-out``: header ``rpm,depth_mm,chatter_hz`` — the SDM limit at each speed of the grid.
* ``--plot``: the simulated verdicts (stable o, chatter x) over the SDM lobes, and the SLE map.
"""

from __future__ import annotations

import contextlib

import numpy as np

from ..errors import InputError
from ..io.atomic import atomic_open, atomic_path
from .common import check_whole, out_path, use_agg, warnings_to_stderr
from .simulate import add_model_options, model_and_cut, renamed

#: Most grid points one command simulates (time: ≈ 5 ms CPU per point at 40 revolutions).
MAX_POINTS = 200_000


def register(sub) -> None:
    """Add the ``map`` sub-command to the CLI's sub-parsers."""
    p = sub.add_parser("map", help="simulated stability and SLE over a speed × depth grid, beside the SDM lobes",
                       description="Time-domain stability and surface location error map of a milling cut. Units: "
                       "Kt in N/m², depths and feed in mm, speeds in rpm.")
    add_model_options(p)
    p.add_argument("--rpm", required=True, help="spindle speed range LO:HI in rpm, e.g. 4000:25000")
    p.add_argument("--rpm-points", default="100", help="number of speeds (default 100)")
    p.add_argument("--depth-mm", required=True, help="axial depth range LO:HI in mm, e.g. 0.05:4")
    p.add_argument("--depth-points", default="50", help="number of depths (default 50)")
    p.add_argument("--out", required=True,
                   help="CSV: rpm,depth_mm,stable,metric,growth_per_rev,sle_um,surface_pv_um,chatter_hz")
    p.add_argument("--lobes-out", help="CSV of the SDM limit: rpm,depth_mm,chatter_hz")
    p.add_argument("--plot", help="figure file (.png, .pdf, .svg, …): stability map over the lobes, SLE map")
    p.set_defaults(func=run)


def _range(text: str, flag: str) -> tuple[float, float]:
    parts = text.split(":")
    try:
        lo, hi = (float(v) for v in parts)
    except ValueError:
        raise InputError(f"expected LO:HI, got {text!r}", field=flag) from None
    if not (np.isfinite(lo) and np.isfinite(hi) and 0 < lo < hi):
        raise InputError(f"expected 0 < LO < HI, finite, got {text!r}", field=flag)
    return lo, hi


def run(args) -> int:
    """Run ``toolpoint map``; returns the exit code (InputErrors are left to the caller: exit 2)."""
    from ..simulation import simulate_map
    from ..stability import sdm_lobes

    mx, my, cut, tool, feed, opts = model_and_cut(args)
    r_lo, r_hi = _range(args.rpm, "--rpm")
    a_lo, a_hi = _range(args.depth_mm, "--depth-mm")
    ns = check_whole(args.rpm_points, "--rpm-points", minimum=1)
    nd = check_whole(args.depth_points, "--depth-points", minimum=1)
    if ns * nd > MAX_POINTS:
        raise InputError(f"{ns} × {nd} points, at most {MAX_POINTS} in one map", field="--rpm-points")
    outs = {"out": out_path(args.out, "--out", inputs=[args.modal] if args.modal else ())}
    for key, flag in (("lobes", "--lobes-out"), ("plot", "--plot")):
        value = getattr(args, key if key == "plot" else "lobes_out")
        outs[key] = out_path(value, flag) if value else None
    given = [p.resolve() for p in outs.values() if p is not None]
    if len(set(given)) != len(given):
        raise InputError("--out, --lobes-out and --plot must be different files", field="--out")
    rpm = np.linspace(r_lo, r_hi, ns)
    depth = np.linspace(a_lo, a_hi, nd) * 1e-3
    with warnings_to_stderr():
        try:
            res = simulate_map(mx or None, my or None, cut, rpm=rpm, depth_m=depth, feed_m=feed, tool=tool, **opts)
        except InputError as err:
            raise renamed(err) from None
        from ..simulation.structure import as_modal_dynamics

        lobes = sdm_lobes(as_modal_dynamics(mx or None, my or None).model, None, cut, rpm=rpm) if ns > 1 else None
    fig = _figure(res, lobes) if outs["plot"] else None
    _write(outs, res, lobes, fig)
    n_st = int(res.stable.sum())
    print(f"{n_st} of {res.stable.size} points stable; largest stable depth at every depth below: "
          f"{1e3 * res.limit_m.min():.4g}–{1e3 * res.limit_m.max():.4g} mm over the speeds")
    print("wrote " + ", ".join(str(p) for p in outs.values() if p is not None))
    return 0


def _figure(res, lobes):
    use_agg()
    from matplotlib.figure import Figure

    fig = Figure(figsize=(11, 4.5), constrained_layout=True)
    ax = fig.subplots(1, 2)
    R, A = np.meshgrid(res.rpm, 1e3 * res.depth_m)
    ax[0].plot(R[res.stable], A[res.stable], "o", ms=2, color="#0072B2", label="simulated stable")
    ax[0].plot(R[~res.stable], A[~res.stable], "x", ms=2, color="#E69F00", label="simulated chatter")
    if lobes is not None:
        ax[0].plot(lobes.rpm, np.minimum(lobes.depth_mm, 1e3 * res.depth_m.max() * 1.1), "k-", lw=1, label="SDM")
    ax[0].set(xlabel="spindle speed (rpm)", ylabel="axial depth (mm)", title="stability")
    ax[0].legend(fontsize="small", loc="upper left")
    sle = np.where(res.stable, 1e6 * res.sle_m, np.nan)
    if res.rpm.size > 1 and res.depth_m.size > 1:
        im = ax[1].pcolormesh(res.rpm, 1e3 * res.depth_m, sle, shading="nearest", cmap="coolwarm")
        fig.colorbar(im, ax=ax[1], label="SLE (µm, > 0 undercut; stable points)")
    else:
        ax[1].plot(R.ravel(), sle.ravel(), "o")
    ax[1].set(xlabel="spindle speed (rpm)", ylabel="axial depth (mm)", title="surface location error")
    return fig


def _write(outs, res, lobes, fig) -> None:
    """Write every output to a temporary file; rename them all only if all succeeded."""
    R, A = np.meshgrid(res.rpm, res.depth_m)
    with contextlib.ExitStack() as stack:
        fh = stack.enter_context(atomic_open(outs["out"], "w", newline=""))
        fh.write("rpm,depth_mm,stable,metric,growth_per_rev,sle_um,surface_pv_um,chatter_hz\n")
        np.savetxt(fh, np.column_stack([R.ravel(), 1e3 * A.ravel(), res.stable.ravel().astype(int),
                                        res.metric.ravel(), res.growth_per_rev.ravel(), 1e6 * res.sle_m.ravel(),
                                        1e6 * res.surface_pv_m.ravel(), res.chatter_hz.ravel()]),
                   fmt=["%.10g", "%.10g", "%d", "%.6g", "%.6g", "%.6g", "%.6g", "%.6g"], delimiter=",")
        if outs["lobes"]:
            fh = stack.enter_context(atomic_open(outs["lobes"], "w", newline=""))
            fh.write("rpm,depth_mm,chatter_hz\n")
            if lobes is not None:
                np.savetxt(fh, np.column_stack([lobes.rpm, lobes.depth_mm, lobes.chatter_hz]), fmt="%.10g",
                           delimiter=",")
        if outs["plot"]:
            tmp = stack.enter_context(atomic_path(outs["plot"]))
            fig.savefig(tmp, format=outs["plot"].suffix.lstrip(".").lower(), dpi=130)
