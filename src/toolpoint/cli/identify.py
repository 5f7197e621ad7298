"""``toolpoint identify ASSEMBLY.toml MEASURED --method … [--seed N] [--out RESULT.json] [--plot FIT.png]``."""

from __future__ import annotations

import json
import sys
import warnings
from pathlib import Path

import numpy as np

from .. import __version__
from ..dynamics.assembly import load_assembly
from ..io.atomic import atomic_open
from ..errors import InputError
from ..io.frf_files import read_frf
from ..identification.identify import identify, make_algorithm, model_for
from ..identification.params import PARAMS, UNITS, Bounds
from ..identification.optim import METHODS
from .common import out_path, save_figure, use_agg, warnings_to_stderr

MIN_POINTS = 10


def register(sub) -> None:
    p = sub.add_parser("identify", help="identify the holder–tool joint from a measured tool-point FRF")
    p.add_argument("assembly", help="assembly TOML (spindle, holder, tool, spindle–holder joint)")
    p.add_argument("measured", help="measured tool-point receptance: .csv (freq_hz,real,imag), .uff/.unv or .frf")
    p.add_argument("--method", default="hybrid", help=f"one of {', '.join(METHODS)} (default hybrid)")
    p.add_argument("--seed", type=int, default=0, help="random seed (default 0)")
    p.add_argument("--out", help="result JSON file")
    p.add_argument("--plot", help="figure: measured vs identified FRF and convergence (PNG/PDF/SVG)")
    p.add_argument("--bounds", nargs="+", metavar="NAME=LO:HI", default=[],
                   help="override search bounds, e.g. kt=1e6:1e9 cr=0.1:300 (SI units)")
    p.add_argument("--fmin", type=float, help="fit only from this frequency (Hz)")
    p.add_argument("--fmax", type=float, help="fit only up to this frequency (Hz)")
    p.add_argument("--quantity", choices=("receptance", "mobility", "accelerance"),
                   help="what the measured file holds (default: as the file says; CSV means receptance)")
    p.set_defaults(func=run)


def parse_bounds(items: list[str]) -> dict:
    out = {}
    for it in items:
        name, _, rng = it.partition("=")
        lo, _, hi = rng.partition(":")
        try:
            out[name.strip()] = [float(lo), float(hi)]
        except ValueError:
            raise InputError(f"expected NAME=LO:HI, got {it!r}", file="command line", field="--bounds") from None
    return out


def load_problem_inputs(args):
    """Assembly, bounds, measured FRF (validated); shared with ``reproduce``."""
    assembly = load_assembly(args.assembly)
    file_bounds = assembly.identify.get("bounds", {})
    if not isinstance(file_bounds, dict):
        raise InputError("must be a table like {kt = [1e6, 1e9]}", file=args.assembly, field="identify.bounds")
    b = Bounds.from_dict(file_bounds, source=args.assembly, section="identify.bounds")
    cli = parse_bounds(args.bounds)
    if cli:
        merged = {**b.as_dict(), **cli}
        b = Bounds.from_dict(merged, source="command line", section="--bounds")
    return assembly, b


def run(args) -> int:
    if args.method not in METHODS:
        raise InputError(f"unknown method {args.method!r} (one of {', '.join(METHODS)})", file="command line",
                         field="--method")
    out = out_path(args.out, "--out") if args.out else None
    plot = out_path(args.plot, "--plot") if args.plot else None
    with warnings_to_stderr():
        assembly, bounds = load_problem_inputs(args)
        meas = read_frf(args.measured, quantity=args.quantity, min_points=MIN_POINTS)
        if meas.freq_hz[0] == 0:
            warnings.warn(f"{args.measured}: the 0 Hz point is not used (free–free components are singular there)")
            meas = meas.band(fmin=np.nextafter(0.0, 1.0))
        meas = meas.band(args.fmin, args.fmax)
        if len(meas) < MIN_POINTS:
            raise InputError(f"only {len(meas)} points in the fitted band, need at least {MIN_POINTS}",
                             file=args.measured, field="freq_hz")
        if assembly.holder_tool is not None:
            print(f"note: [joints.holder_tool] in {args.assembly} is ignored — it is what we identify", file=sys.stderr)
        model = model_for(assembly, meas.freq_hz)
        algo = make_algorithm(args.method)
        res = _run_with_progress(model, meas, args.method, args.seed, bounds, algo)
    _report(res, args)
    doc = result_document(res, args.method, args.seed, assembly=args.assembly, measured=args.measured)
    fig = None
    if plot:
        use_agg()
        from ..identification.figures import fit_figure

        fig = fit_figure(meas, {f"identified ({args.method})": res.model_frf}, {args.method: res.history},
                         title=f"{Path(args.measured).name}: identified holder–tool joint")
    if out:
        with atomic_open(out) as fh:
            json.dump(doc, fh, indent=2)
    if fig is not None:
        save_figure(fig, plot)
    return 0


def _run_with_progress(model, meas, method, seed, bounds, algo):
    from tqdm import tqdm

    total = algo.termination().max_iter
    with tqdm(total=total, desc=f"identify ({method})", unit="it", disable=None, leave=False, file=sys.stderr) as bar:
        def cb(it, best, nfev):
            bar.update(1)
            bar.set_postfix_str(f"best {best:.3e} m/N, {nfev} evals", refresh=False)

        return identify(model, meas, method, seed, bounds, callback=cb)


def result_document(res, method, seed, **extra) -> dict:
    """The RESULT.json content (SI units)."""
    doc = {k: res.params[k] for k in PARAMS}
    doc.update(
        units=UNITS,
        ci95=res.ci95,
        method=method,
        seed=seed,
        evaluations=int(res.nfev),
        iterations=int(res.nit),
        seconds=float(res.seconds),
        objective=float(res.fun),
        objective_units="m/N",
        message=res.message,
        warnings=list(res.warnings),
        bounds=res.bounds,
        toolpoint=__version__,
        **extra,
    )
    return doc


def _report(res, args) -> None:
    print(f"method {args.method}, seed {args.seed}: objective {res.fun:.4g} m/N, {res.nfev} evaluations, "
          f"{res.seconds:.2f} s — {res.message}")
    for k in PARAMS:
        lo, hi = res.ci95[k]
        print(f"  {k} = {res.params[k]:.6g} {UNITS[k]:9s}  95 % CI [{lo:.4g}, {hi:.4g}]")
    for w in res.warnings:
        print(f"warning: {w}", file=sys.stderr)
