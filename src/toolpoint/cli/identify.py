"""``toolpoint identify ASSEMBLY.toml MEASURED… --method … [--seed N] [--out RESULT.json] [--plot FIT.png]``.

Without ``--joint``/``--params`` (and no ``joint``/``params`` in the file's ``[identify]``): the holder–tool
joint from a tool-point FRF. ``--joint spindle_holder`` (or any element): that element's four parameters,
by default from the holder-tip FRF of the spindle–holder subassembly (no tool). ``--params a.kt,bearings[0].k``
with one ``--at POINT`` per MEASURED file: any parameters from several FRFs
(:mod:`toolpoint.identification.problem`).
"""

from __future__ import annotations

import json
import sys
import warnings
from pathlib import Path

import numpy as np

from .. import __version__
from ..dynamics.assembly import load_assembly
from ..io.atomic import atomic_open
from ..errors import IdentifiabilityWarning, InputError
from ..io.frf_files import read_frf
from ..identification.identify import identify, make_algorithm, model_for
from ..identification.params import PARAMS, UNITS, Bounds
from ..identification.optim import METHODS, check_method
from .common import check_number, out_path, parse_band, save_figure, use_agg, warnings_to_stderr

MIN_POINTS = 10


def register(sub) -> None:
    """Add the ``identify`` subcommand to the argparse subparsers ``sub``."""
    p = sub.add_parser("identify", help="identify the holder–tool joint from a measured tool-point FRF")
    p.add_argument("assembly", help="assembly TOML (spindle, holder, tool, spindle–holder joint)")
    p.add_argument("measured", nargs="+",
                   help="measured receptance(s): .csv (freq_hz,real,imag), .uff/.unv or .frf (several with --at)")
    p.add_argument("--joint", help="identify this element's four parameters (spindle_holder, holder_tool, "
                   "bearings[i]); default point: holder_tip of the spindle–holder subassembly for spindle_holder")
    p.add_argument("--params", help="comma-separated parameters, e.g. spindle_holder.kt,bearings[0].k")
    p.add_argument("--at", action="append", default=[], metavar="POINT",
                   help="point of each MEASURED file, in order: tool_tip, holder_tip, spindle_nose, "
                   "tool:x_mm=40, or RESPONSE,FORCE for a cross FRF")
    p.add_argument("--weight", action="append", type=float, default=[], help="weight of each MEASURED file")
    p.add_argument("--no-tool", action="store_true", help="model the spindle–holder subassembly (no tool)")
    p.add_argument("--method", default="hybrid", help=f"one of {', '.join(METHODS)} (default hybrid)")
    p.add_argument("--seed", type=int, default=0, help="random seed (default 0)")
    p.add_argument("--out", help="result JSON file")
    p.add_argument("--plot", help="figure: measured vs identified FRF and convergence (PNG/PDF/SVG)")
    p.add_argument("--bounds", nargs="+", metavar="NAME=LO:HI", default=[],
                   help="override search bounds, e.g. kt=1e6:1e9 cr=0.1:300 (SI units)")
    p.add_argument("--band", metavar="LO:HI",
                   help="fit only from LO to HI Hz (default: [identify] band_hz = [LO, HI] of the assembly file, "
                   "else the trusted band found in each measured file — low-frequency noise ×1/ω² and low "
                   "coherence left out, with a note on stderr)")
    p.removed = {"--fmin": "--band LO:HI (fitted band, Hz)", "--fmax": "--band LO:HI (fitted band, Hz)"}
    p.add_argument("--quantity", choices=("receptance", "mobility", "accelerance"),
                   help="what the measured file holds (default: as the file says; CSV means receptance)")
    p.set_defaults(func=run)


def parse_bounds(items: list[str]) -> dict:
    """``["kt=1e6:1e9", …]`` → ``{"kt": [1e6, 1e9], …}`` (SI); a malformed item is an InputError."""
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
    """Run ``toolpoint identify``; returns the exit code (0)."""
    args.method = check_method(args.method)
    check_number(args.seed, "--seed", minimum=0)  # NumPy's generator refuses a negative seed with a ValueError
    for flag in ("joint", "params"):  # given but empty is a mistake, not "absent"
        if getattr(args, flag, None) is not None and not str(getattr(args, flag)).strip(" ,"):
            raise InputError("is empty: name the joint (e.g. spindle_holder) or the parameters",
                             file="command line", field=f"--{flag}")
    if general_requested(args):
        return run_general(args)
    if len(args.measured) != 1:
        raise InputError(f"{len(args.measured)} measured files: several need --params (or --joint) and --at",
                         file="command line", field="measured")
    if args.at or args.weight or args.no_tool:
        raise InputError("--at, --weight and --no-tool need --params or --joint", file="command line",
                         field="--at")
    args.measured = args.measured[0]
    inputs = [args.assembly, args.measured]
    out = out_path(args.out, "--out", inputs=inputs) if args.out else None
    plot = out_path(args.plot, "--plot", inputs=inputs) if args.plot else None
    with warnings_to_stderr():
        assembly, bounds = load_problem_inputs(args)
        meas = read_frf(args.measured, quantity=args.quantity, min_points=MIN_POINTS)
        if meas.freq_hz[0] == 0:  # free–free components are singular there; the band note names what is fitted
            meas = meas.band(fmin=np.nextafter(0.0, 1.0))
        meas, note = fit_band(meas, args.measured, band_spec(args))
        if not np.any(meas.values):  # a joint fitted to zeros would be "identified" at the bounds
            raise InputError("the FRF is zero at every frequency of the band: nothing to identify", file=args.measured,
                             field="values")
        if len(meas) < MIN_POINTS:
            raise InputError(f"only {len(meas)} points in the fitted band, need at least {MIN_POINTS}",
                             file=args.measured, field="freq_hz")
        if assembly.holder_tool is not None:
            print(f"note: [joints.holder_tool] in {args.assembly} is ignored — it is what we identify", file=sys.stderr)
        model = model_for(assembly, meas.freq_hz)
        if note:
            print(note, file=sys.stderr)
        algo = make_algorithm(args.method)
        res = _run_with_progress(model, meas, args.method, args.seed, bounds, algo)
    _report(res, args, measured=[meas.to_receptance().values])
    doc = result_document(res, args.method, args.seed, assembly=args.assembly, measured=args.measured,
                          band_hz=[float(meas.freq_hz[0]), float(meas.freq_hz[-1])])
    _write(doc, out, plot, args.method, meas, res.model_frf, res.history,
           f"{Path(args.measured).name}: identified holder–tool joint")
    return 0


def _write(doc, out, plot, method, measured, fitted, history, title) -> None:
    """The result JSON and (if asked) the measured-vs-identified figure, each written atomically."""
    fig = None
    if plot:
        use_agg()
        from ..identification.figures import fit_figure

        fig = fit_figure(measured, {f"identified ({method})": fitted}, {method: history}, title=title)
    if out:
        with atomic_open(out) as fh:
            json.dump(doc, fh, indent=2)
    if fig is not None:
        save_figure(fig, plot)


def _run_with_progress(model, meas, method, seed, bounds, algo):
    """identify() with a progress bar on stderr; its IdentifiabilityWarnings are not shown here, because
    the caller prints each of ``result.warnings`` once."""
    from tqdm import tqdm

    total = algo.termination().maxiter
    with tqdm(total=total, desc=f"identify ({method})", unit="it", disable=None, leave=False, file=sys.stderr) as bar:
        def cb(it, best, nfev):
            bar.update(1)
            bar.set_postfix_str(f"best {best:.3e} m/N, {nfev} evals", refresh=False)

        with warnings.catch_warnings():
            warnings.simplefilter("ignore", IdentifiabilityWarning)
            return identify(model, meas, method, seed, bounds=bounds, callback=cb)


def result_document(res, method, seed, *, names=PARAMS, units=None, key=None, **extra) -> dict:
    """The RESULT.json content (SI units): value, unit, 95 % interval and bounds of each of ``names``
    (written under ``key(name)``), then how the optimiser ran and stopped."""
    key = key or (lambda n: n)
    units = UNITS if units is None else units
    doc = {key(n): res.params[n] for n in names}
    doc.update(
        units={key(n): units[n] for n in names},
        ci95={key(n): res.ci95[n] for n in names},
        method=method,
        seed=seed,
        evaluations=int(res.nfev),
        iterations=int(res.nit),
        seconds=float(res.seconds),
        objective=float(res.fun),
        objective_units="m/N",
        success=bool(res.success),
        status=int(res.status),
        message=res.message,
        warnings=list(res.warnings),
        bounds={key(n): res.bounds[n] for n in names},
        toolpoint=__version__,
        **extra,
    )
    return doc


def _report(res, args, names=PARAMS, units=UNITS, measured=None) -> None:
    """Print the identified parameters in aligned columns (stdout) and each identifiability warning once (stderr).

    The interval ends get the digits that tell them apart from the value; the objective is also given relative to
    the measured FRF's norm (the m/N figure alone says little).
    """
    rel = ""
    if measured is not None:
        norm = float(np.linalg.norm(np.concatenate([np.ravel(m) for m in measured])))
        if norm > 0:
            rel = f" ({res.fun / norm:.2g} of the measured FRF's norm)"
    state = "converged" if res.success else f"not converged: {res.message}"
    print(f"method {args.method}, seed {args.seed}: {state}; objective {res.fun:.3g} m/N{rel}, "
          f"{res.nfev:,} evaluations, {res.seconds:.2f} s")
    width = max(len(k) for k in names)
    uw = max(len(units[k]) for k in names)
    print(f"  {'':{width}s}  {'value':>12s}  {'unit':{uw}s}  95 % interval")
    for k in names:
        v, (lo, hi) = res.params[k], res.ci95[k]
        spread = max(abs(hi - v), abs(v - lo)) / abs(v) if v else 1.0
        digits = int(np.clip(np.ceil(-np.log10(max(spread, 1e-15))) + 2, 3, 15))
        print(f"  {k:{width}s}  {v:12.6g}  {units[k]:{uw}s}  [{lo:.{digits}g}, {hi:.{digits}g}]"
              f"  (−{100 * (v - lo) / v:.2g} %, +{100 * (hi - v) / v:.2g} %)" if v else "")
    for w in res.warnings:
        print(f"warning: {w}", file=sys.stderr)


def band_spec(args) -> tuple:
    """Where the fitted band comes from: ``("given", (lo, hi), field)`` or ``("auto",)``.

    ``--band`` first, then
    ``band_hz = [LO, HI]`` in the assembly file's ``[identify]`` table; otherwise the trusted
    band of each measured file (:func:`toolpoint.trust.trusted_band`).
    """
    from ..trust import check_band

    band = parse_band(getattr(args, "band", None))
    if band is not None:
        return ("given", band, "--band")
    t = _file_identify(args.assembly)
    if "band_hz" in t:
        return ("given", check_band(t["band_hz"], file=args.assembly, field="identify.band_hz"), "identify.band_hz")
    return ("auto",)


def fit_band(frf, path, spec):
    """``frf`` (read from ``path``) cut to the band of ``spec`` (:func:`band_spec`), and the note for stderr."""
    band, field = (spec[1], spec[2]) if spec[0] == "given" else (None, "--band")
    hint = "--band LO:HI or [identify] band_hz"
    from ..trust import common_band

    b = common_band([frf], band=band, files=[path], field=field, hint=hint)
    return b.cut(frf), "\n".join(b.notes)


# --------------------------------------------------------------------------- general form
_GENERAL_KEYS = {"joint", "params", "at", "weights", "start"}


def _file_identify(path: str) -> dict:
    """The ``[identify]`` table of an assembly file, or {} (unreadable files fail later, with their own error)."""
    from ..io.toml import load_toml

    t = load_toml(path).get("identify", {})
    if not isinstance(t, dict):
        raise InputError("must be a table", file=path, field="identify")
    return t


def general_requested(args) -> bool:
    """True when ``--joint``/``--params`` or the file's ``[identify]`` asks for the general form."""
    if args.joint or args.params:
        return True
    return bool(_GENERAL_KEYS & set(_file_identify(args.assembly)))


def _general_setup(args):
    """Assembly, parameter names, measurements, bounds, start, with_tool, joint (or None), all validated."""
    from ..dynamics.assembly import load_assembly as _load
    from ..dynamics.points import parse_at
    from ..identification.problem import Measured, joint_names, param_bounds, parse_params

    src = args.assembly
    t = _file_identify(src)
    r_unknown = set(t) - (_GENERAL_KEYS | {"bounds", "method", "band_hz"})
    if r_unknown:
        raise InputError(f"unknown key {sorted(r_unknown)[0]!r}", file=src, field="identify")
    assembly = _load(src, require_tool=False, require_spindle_holder=False)
    joint = args.joint or (t.get("joint") if not args.params else None)
    where = ("command line", "--joint") if args.joint else (src, "identify.joint")
    if joint is not None:
        if args.params:
            raise InputError("give --joint or --params, not both", file="command line", field="--params")
        if joint not in ("spindle_holder", "holder_tool") and not str(joint).startswith("bearings["):
            raise InputError(f"unknown joint {joint!r} (spindle_holder, holder_tool or bearings[i])",
                             file=where[0], field=where[1])
        names = joint_names(joint)
    elif args.params:
        names = [n for n in args.params.split(",") if n.strip()]
        where = ("command line", "--params")
    else:
        names = t.get("params")
        where = (src, "identify.params")
        if not isinstance(names, list) or not all(isinstance(n, str) for n in names):
            raise InputError('must be a list of names like ["spindle_holder.kt"]', file=src, field="identify.params")
    params = parse_params(names, assembly, file=where[0], field=where[1])
    at = args.at or t.get("at") or []
    at_where = ("command line", "--at") if args.at else (src, "identify.at")
    if isinstance(at, str):
        at = [at]
    if not at and joint == "spindle_holder":
        at = ["holder_tip"] * len(args.measured)
    if not at and joint == "holder_tool":
        at = ["tool_tip"] * len(args.measured)
    if len(at) != len(args.measured):
        raise InputError(f"{len(at)} points for {len(args.measured)} measured files: give one --at per file",
                         file=at_where[0], field=at_where[1])
    weights = args.weight or t.get("weights") or [1.0] * len(args.measured)
    # > 0 and finite: the model of a measurement is divided by √w (a weight 0 or inf made it NaN)
    if len(weights) != len(args.measured) or not all(
            isinstance(w, (int, float)) and not isinstance(w, bool) and np.isfinite(w) and w > 0 for w in weights):
        raise InputError(f"need one finite weight > 0 per measured file, got {weights!r}",
                         file="command line" if args.weight else src,
                         field="--weight" if args.weight else "identify.weights")
    pts = [parse_at(a, file=at_where[0], field=at_where[1]) for a in at]
    with_tool = False if (args.no_tool or joint == "spindle_holder" or assembly.tool is None) else None
    on_tool = [p.text for pair in pts for p in pair if p.component == "tool"]
    if on_tool and with_tool is False:
        raise InputError(f"point {on_tool[0]!r}: the spindle–holder subassembly (no tool) has no tool",
                         file=at_where[0], field=at_where[1])
    tb = t.get("bounds", {})
    if not isinstance(tb, dict):
        raise InputError("must be a table like {kt = [1e6, 1e9]}", file=src, field="identify.bounds")
    bounds = param_bounds(params, tb, file=src, field="identify.bounds")
    cli = parse_bounds(args.bounds)
    if cli:
        over = {**dict(zip([p[2] for p in params], zip(bounds.lo, bounds.hi))), **cli}
        bounds = param_bounds(params, over, file="command line", field="--bounds")
    start = t.get("start", {})
    if not isinstance(start, dict):
        raise InputError("must be a table like {\"spindle_holder.kt\" = 5e8}", file=src, field="identify.start")
    meas, spec = [], band_spec(args)
    args.band_notes = []
    for path, (resp, force), w in zip(args.measured, pts, weights):
        frf = read_frf(path, quantity=args.quantity, min_points=MIN_POINTS)
        if frf.freq_hz[0] == 0:  # free–free components are singular there; the band note names what is fitted
            frf = frf.band(fmin=np.nextafter(0.0, 1.0))
        frf, note = fit_band(frf, path, spec)
        if not np.any(frf.values):  # a joint fitted to zeros would be "identified" at the bounds
            raise InputError("the FRF is zero at every frequency of the band: nothing to identify", file=path,
                             field="values")
        if note:
            args.band_notes.append(note)
        if len(frf) < MIN_POINTS:
            raise InputError(f"only {len(frf)} points in the fitted band, need at least {MIN_POINTS}", file=path,
                             field="freq_hz")
        meas.append(Measured(frf.to_receptance(), resp, force, float(w), path))
    return assembly, [p[2] for p in params], meas, bounds, start, with_tool, joint, at


def run_general(args) -> int:
    """``toolpoint identify`` in its general form (``--joint``/``--params``); returns the exit code (0)."""
    from ..identification.problem import FRFProblem, identify_frfs

    inputs = [args.assembly, *args.measured]
    out = out_path(args.out, "--out", inputs=inputs) if args.out else None
    plot = out_path(args.plot, "--plot", inputs=inputs) if args.plot else None
    with warnings_to_stderr():
        assembly, names, meas, bounds, start, with_tool, joint, at = _general_setup(args)
        try:
            problem = FRFProblem(assembly, names, meas, bounds, start=start, with_tool=with_tool)
        except InputError as e:
            if e.field == "at" and e.file == assembly.source:  # the point belongs to the command line / [identify]
                raise InputError(e.message, file="command line" if args.at else assembly.source,
                                 field="--at" if args.at else "identify.at") from None
            raise
        for note in args.band_notes:
            print(note, file=sys.stderr)
        algo = make_algorithm(args.method)
        from tqdm import tqdm

        with tqdm(total=algo.termination().maxiter, desc=f"identify ({args.method})", unit="it", disable=None,
                  leave=False, file=sys.stderr) as bar:
            def cb(it, best, nfev):
                bar.update(1)

            with warnings.catch_warnings():
                warnings.simplefilter("ignore", IdentifiabilityWarning)
                res = identify_frfs(problem, args.method, args.seed, callback=cb)
    short = joint is not None
    key = (lambda n: n.split(".")[-1]) if short else (lambda n: n)
    _report(res, args, names, problem.units)
    doc = result_document(
        res, args.method, args.seed, names=names, units=problem.units, key=key,
        assembly=args.assembly,
        measured=[{"file": m.source, "at": a, "weight": m.weight,
                   "band_hz": [float(m.frf.freq_hz[0]), float(m.frf.freq_hz[-1])]} for m, a in zip(meas, at)],
        correlation={"names": [key(n) for n in names], "matrix": np.nan_to_num(res.correlation).tolist()},
        ci95_method=res.intervals,
    )
    if joint is not None:
        doc["joint"] = joint
    else:
        doc["params"] = list(names)
    _write(doc, out, plot, args.method, meas[0].frf, res.model_frfs[0], res.history,
           f"{Path(meas[0].source).name}: identified {joint or ', '.join(names)}")
    return 0
