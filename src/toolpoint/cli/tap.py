"""``toolpoint tap RECORD... --out FRF``: impact-test records (time, force, response) → FRF with coherence.

Records are text tables (time s, force N, response; comma, tab or space
separated, header optional) or UFF files with force and response time
histories (dataset 58, function type 1). Each record may hold one hit or many
(cut at the force threshold). Output (by the extension of ``--out``):

* ``.csv``: ``freq_hz,real,imag,coherence``;
* ``.uff``/``.unv``/``.uf``: the FRF and the coherence as a second dataset 58;
* ``.frf``: CutPro (Hz, real, imaginary; no coherence).

Receptance (m/N) by default; ``--output-quantity measured`` keeps the
measured accelerance/mobility. The FRF is written only over the band the
hammer excited (up to where the force auto-spectrum has dropped by
``--force-drop`` dB, default 15), with a note on stderr; the acceleration's
offset and drift are removed per hit (``--detrend none`` keeps them). A single
hit is named as such and no coherence is written for it (one average has
coherence 1 by construction). ``--plot`` draws the records with the hits
marked, magnitude, phase (grey where the coherence is below 0.8) and
coherence. Outputs are checked before any work and written all or none: the
figure first, then the FRF; if the FRF cannot be written the figure is removed.
"""

from __future__ import annotations

import sys
import warnings
from pathlib import Path

from ..errors import InputError
from .common import check_whole, out_path, save_figure, use_agg, warnings_to_stderr


def register(sub) -> None:
    """Add the ``tap`` sub-command to the CLI's sub-parsers."""
    p = sub.add_parser("tap", help="impact-test records (time, force, response) → FRF with coherence",
                       description="FRF of an impact (hammer) test: hits found at a force threshold, force and "
                       "optional exponential windows, H1/H2 averaged over hits, coherence, double-hit and "
                       "overload checks. Units: s, N, m/s² (or m/s, m), or as a text header names them "
                       "(Accel (g), Time (ms), a units row); output m/N.")
    p.add_argument("records", nargs="+", metavar="RECORD", help="text (time s, force N, response) or UFF file")
    p.add_argument("--out", required=True, help="output FRF: .csv, .uff/.unv/.uf or .frf")
    p.add_argument("--response", choices=("acceleration", "velocity", "displacement"), default="acceleration",
                   help="what the text records' response column is (m/s², m/s or m; default acceleration)")
    p.add_argument("--channel", help="0-based response among several (the text columns after the force, a UFF "
                   "file's response time histories), e.g. one axis of a triaxial accelerometer")
    p.add_argument("--estimator", choices=("H1", "H2"), default="H1", help="FRF estimator (default H1)")
    p.add_argument("--output-quantity", choices=("receptance", "measured"), default="receptance",
                   help="write receptance m/N (default) or the measured quantity")
    p.add_argument("--threshold", default="0.1", help="hit trigger, fraction of the peak force (default 0.1)")
    p.add_argument("--min-gap", default="0.05", help="shortest time between hits, s; closer force pulses are "
                   "one double hit (default 0.05)")
    p.add_argument("--pretrigger", help="time kept before each trigger, s (default 20 samples)")
    p.add_argument("--force-window", help="force window length from the block start, s (default: the pulse "
                   "plus one pulse width)")
    p.add_argument("--exp-window", help="exponential window time constant τ, s, or 'auto' (1 %% at the block "
                   "end); adds damping 1/(2π f τ), reported (default: none)")
    p.add_argument("--fmax", help="highest frequency written, Hz (default: the end of the force band)")
    p.add_argument("--force-drop", default="15", metavar="DB",
                   help="the band ends where the hammer's force auto-spectrum has dropped this many dB below its "
                   "low-frequency level (default 15; test practice 10–20; 'off' for none)")
    p.add_argument("--detrend", choices=("auto", "none"), default="auto",
                   help="remove the response's offset and drift per hit (auto: acceleration line, velocity mean, "
                   "displacement pre-trigger mean; default) or not (none)")
    p.add_argument("--drop-bad", action="store_true", help="leave out double hits and overloads")
    p.add_argument("--plot", help="figure file (.png/.pdf/.svg): records with hits, magnitude, phase, coherence")
    p.set_defaults(func=run)


def _number(value, flag, positive=True):
    if value is None:
        return None
    try:
        x = float(value)
    except ValueError:
        raise InputError(f"{value!r} is not a number", field=flag) from None
    if not (x > 0 if positive else x >= 0) or x != x or x == float("inf"):
        raise InputError(f"must be a finite number {'> 0' if positive else '≥ 0'}, got {value}", field=flag)
    return x


def _write(path: Path, flag: str, writer, *args, **kw) -> None:
    """Call a writer; an operating-system error (full disk, permission) becomes one line naming the file."""
    try:
        writer(*args, **kw)
    except OSError as exc:
        raise InputError(f"cannot write ({exc.strerror or exc}); nothing written", file=path, field=flag) from None


def run(args) -> int:
    """Run ``toolpoint tap``; returns the exit code."""
    inputs = [Path(r) for r in args.records]
    out = out_path(args.out, "--out", inputs=inputs)
    if out.suffix.lower() not in (".csv", ".uff", ".unv", ".uf", ".frf"):
        raise InputError(f"unknown FRF file extension {out.suffix!r} (use .csv, .uff, .unv, .uf or .frf)",
                         file=out, field="--out")
    plot = out_path(args.plot, "--plot", inputs=inputs) if args.plot else None
    threshold = _number(args.threshold, "--threshold")
    if threshold >= 1:
        raise InputError(f"must be in (0, 1), got {args.threshold}", field="--threshold")
    if args.pretrigger is not None and _number(args.pretrigger, "--pretrigger", positive=False) >= \
            _number(args.min_gap, "--min-gap"):
        raise InputError(f"must be shorter than --min-gap ({args.min_gap} s), got {args.pretrigger}",
                         field="--pretrigger")
    exp = args.exp_window if args.exp_window in (None, "auto") else _number(args.exp_window, "--exp-window")
    opts = dict(estimator=args.estimator, output=args.output_quantity, threshold=threshold,
                min_gap_s=_number(args.min_gap, "--min-gap"), pretrigger_s=_number(args.pretrigger, "--pretrigger",
                                                                                   positive=False),
                force_window_s=_number(args.force_window, "--force-window"), exp_window_s=exp,
                drop_bad=args.drop_bad, fmax_hz=_number(args.fmax, "--fmax"),
                force_drop_db=None if args.force_drop == "off" else _number(args.force_drop, "--force-drop"),
                detrend=args.detrend)
    channel = None if args.channel is None else check_whole(args.channel, "--channel")
    from ..io.frf_files import write_frf
    from ..io.impact import impact_frf, plot_tap, read_record

    with warnings_to_stderr(), warnings.catch_warnings():
        warnings.simplefilter("always")  # the CLI reports every warning on stderr, whatever the filters say
        records = [read_record(r, response=args.response, channel=channel) for r in inputs]
        res = impact_frf(records, label=out.stem, **opts)
        # all or none: the figure first (the likelier to fail), then the FRF; a failed FRF removes the figure
        if plot is not None:
            use_agg()
            _write(plot, "--plot", save_figure, plot_tap(res), plot)
        try:
            _write(out, "--out", write_frf, out, res.frf, as_measured=args.output_quantity == "measured")
        except BaseException:
            if plot is not None:
                plot.unlink(missing_ok=True)
            raise
    f = res.frf.freq_hz
    coh = ("one hit: no coherence (1 by construction)" if res.single_hit
           else f"min coherence {res.coherence.min():.3f}")
    for note in res.notes:
        print(f"note: {note}", file=sys.stderr)
    print(f"{len(res.used)} of {len(res.hits)} hits averaged ({args.estimator}); {len(f)} lines "
          f"{f[0]:g}–{f[-1]:g} Hz; {coh}; wrote {out}", file=sys.stderr)
    if res.tau_s is not None:
        print(f"exponential window τ = {res.tau_s:.6g} s adds damping Δζ = 1/(2π f τ) "
              f"(e.g. {float(res.added_damping(f[-1] / 2)):.3g} at {f[-1] / 2:g} Hz): subtract it from modal "
              "damping fitted to this FRF (toolpoint.io.impact.corrected_damping)", file=sys.stderr)
    return 0
