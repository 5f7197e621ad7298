"""``toolpoint simulate --mode-x FN:K:ZETA … --teeth N --tangential-coeff KT --radial-ratio KR --immersion A
--rpm RPM --depth-mm A [--out RESULT.json|csv] [--plot FIG.png] [--audio SIGNAL.wav|csv]``.

One milling cut simulated in the time domain (:func:`toolpoint.simulation.simulate_milling`): the verdict
(stable/chatter), Honeycutt & Schmitz metric, chatter frequency, surface location error and surface
peak-to-valley are printed. Modes are given on the command line (``--mode-x``/``--mode-y``, repeatable,
``f_n Hz:k N/m:ζ``) or in a modal file (``--modal``, TOML or JSON with lists ``modes_x``/``modes_y`` of
tables ``{fn_hz, k_n_per_m, zeta}``).

Outputs (written only when everything succeeded):

* ``--out``: ``.json`` — the scalar results and the once-per-revolution samples; ``.csv`` — header
  ``t_s,x_m,y_m,fx_n,fy_n``, the recorded time histories.
* ``--plot``: force, displacement, once-per-revolution samples (x–y) and the wall left by each tooth pass.
* ``--audio``: a synthetic microphone (or ``--sensor accelerometer``) signal, ``.wav`` or ``.csv``.
"""

from __future__ import annotations

import contextlib
import json
import math
from pathlib import Path

import numpy as np

from ..errors import InputError
from ..io.atomic import atomic_open, atomic_path
from .common import check_number, check_whole, out_path, use_agg, warnings_to_stderr


# ----------------------------------------------------------------- shared with ``map``
def add_model_options(p) -> None:
    """Options of the tool-point modes and the cut (shared by ``simulate`` and ``map``)."""
    p.add_argument("--mode-x", action="append", default=[], metavar="FN:K:ZETA",
                   help="a real mode in x: natural frequency Hz, modal stiffness N/m, damping ratio "
                   "(e.g. 922:1.34e6:0.011); repeat for several modes")
    p.add_argument("--mode-y", action="append", default=[], metavar="FN:K:ZETA",
                   help="a real mode in y (same form); none: y rigid")
    p.add_argument("--modal", help="modal file (.toml or .json) with lists modes_x and modes_y of "
                   "{fn_hz, k_n_per_m, zeta} (instead of --mode-x/--mode-y)")
    p.add_argument("--teeth", required=True, help="number of teeth N (integer ≥ 1)")
    p.add_argument("--tangential-coeff", required=True,
                   help="tangential cutting coefficient Kt, N/m² (e.g. 6e8 = 600 N/mm²)")
    p.add_argument("--radial-ratio", required=True, help="radial force ratio Kr = Kn/Kt, dimensionless (≥ 0)")
    p.add_argument("--immersion", required=True, help="radial immersion a_e/D in (0, 1] (1 = slotting)")
    g = p.add_mutually_exclusive_group()
    g.add_argument("--down", dest="milling", action="store_const", const="down", help="down-milling (default)")
    g.add_argument("--up", dest="milling", action="store_const", const="up", help="up-milling")
    p.set_defaults(milling="down")
    p.add_argument("--feed-mm", default="0.1", help="feed per tooth, mm (default 0.1)")
    p.add_argument("--edge-tangential", default="0", help="edge force coefficient Kte, N/m (default 0)")
    p.add_argument("--edge-normal", default="0", help="edge force coefficient Kne, N/m (default 0)")
    p.add_argument("--diameter-mm", default="0", help="tool diameter, mm (needed with --helix-deg)")
    p.add_argument("--helix-deg", default="0", help="helix angle, degrees (default 0: straight flutes)")
    p.add_argument("--slices", default="4", help="axial slices with a helix (default 4)")
    p.add_argument("--pitch-deg", help="tooth angles, degrees, comma separated, increasing from 0 (variable pitch)")
    p.add_argument("--runout-um", help="radial runout of each tooth, µm, comma separated")
    p.add_argument("--revolutions", default="40", help="revolutions simulated (default 40)")
    p.add_argument("--steps-per-tooth", default="64",
                   help="time steps per tooth period before substeps for the modes (default 64)")


def _mode(text: str, flag: str) -> tuple[float, float, float]:
    parts = text.split(":")
    try:
        vals = tuple(float(v) for v in parts)
    except ValueError:
        vals = ()
    if len(vals) != 3 or not all(math.isfinite(v) for v in vals):
        raise InputError(f"expected FN:K:ZETA (Hz, N/m, –), got {text!r}", file="command line", field=flag)
    return vals


def _modal_file(path: str):
    p = Path(path)
    if not p.is_file():
        raise InputError("no such file", file=p, field="--modal")
    try:
        if p.suffix.lower() == ".json":
            data = json.loads(p.read_text())
        else:
            import tomllib

            data = tomllib.loads(p.read_text())
    except (ValueError, UnicodeDecodeError) as err:
        raise InputError(f"cannot read: {err}", file=p, field="--modal") from None
    if not isinstance(data, dict):
        raise InputError("expected a table with modes_x and modes_y", file=p, field="--modal")
    out = []
    for key in ("modes_x", "modes_y"):
        rows = data.get(key, [])
        if not isinstance(rows, list):
            raise InputError("must be a list of {fn_hz, k_n_per_m, zeta}", file=p, field=key)
        modes = []
        for i, row in enumerate(rows):
            try:
                modes.append((float(row["fn_hz"]), float(row["k_n_per_m"]), float(row["zeta"])))
            except (KeyError, TypeError, ValueError):
                raise InputError("needs numbers fn_hz, k_n_per_m, zeta", file=p, field=f"{key}[{i}]") from None
        out.append(modes)
    if not (out[0] or out[1]):
        raise InputError("no mode: give modes_x, modes_y or both", file=p, field="--modal")
    return out


def _list(text, flag, scale=1.0):
    if text is None:
        return None
    try:
        vals = [float(v) * scale for v in text.split(",")]
    except ValueError:
        raise InputError(f"expected numbers separated by commas, got {text!r}", field=flag) from None
    if not all(math.isfinite(v) for v in vals):
        raise InputError(f"must be finite, got {text!r}", field=flag)
    return vals


def model_and_cut(args):
    """(modes_x, modes_y, CuttingConditions, Tool, feed_m, options) from the shared flags, errors naming the flag."""
    from ..simulation import Tool
    from ..simulation.structure import modes_from_list
    from ..stability import CuttingConditions

    if args.modal and (args.mode_x or args.mode_y):
        raise InputError("give --modal or --mode-x/--mode-y, not both", field="--modal")
    if args.modal:
        mx, my = _modal_file(args.modal)
    else:
        mx = [_mode(t, "--mode-x") for t in args.mode_x]
        my = [_mode(t, "--mode-y") for t in args.mode_y]
        if not (mx or my):
            raise InputError("no mode: give --mode-x, --mode-y or --modal", field="--mode-x")
    for modes, flag in ((mx, "--mode-x"), (my, "--mode-y")):
        try:
            modes_from_list(modes, flag)
        except InputError as err:
            raise InputError(err.message, field=flag) from None
    flags = {"teeth": "--teeth", "tangential_coeff": "--tangential-coeff", "radial_ratio": "--radial-ratio",
             "radial_immersion": "--immersion", "milling": "--down/--up"}
    try:
        cut = CuttingConditions(teeth=check_whole(args.teeth, "--teeth", minimum=1),
                                tangential_coeff=check_number(args.tangential_coeff, "--tangential-coeff",
                                                              above=0, unit="N/m²"),
                                radial_ratio=check_number(args.radial_ratio, "--radial-ratio", minimum=0),
                                radial_immersion=check_number(args.immersion, "--immersion", above=0),
                                milling=args.milling)
    except ValueError as err:
        if isinstance(err, InputError):
            raise InputError(err.message, field=flags.get(err.field, err.field)) from None
        raise InputError(str(err), field="--tangential-coeff") from None
    tflags = {"diameter_m": "--diameter-mm", "helix_deg": "--helix-deg", "slices": "--slices",
              "tooth_angles_deg": "--pitch-deg", "runout_m": "--runout-um", "edge_tangential": "--edge-tangential",
              "edge_normal": "--edge-normal"}
    try:
        tool = Tool(diameter_m=check_number(args.diameter_mm, "--diameter-mm", minimum=0) * 1e-3,
                    helix_deg=check_number(args.helix_deg, "--helix-deg", minimum=0),
                    slices=check_whole(args.slices, "--slices", minimum=1),
                    tooth_angles_deg=_list(args.pitch_deg, "--pitch-deg"),
                    runout_m=_list(args.runout_um, "--runout-um", 1e-6),
                    edge_tangential=check_number(args.edge_tangential, "--edge-tangential", minimum=0),
                    edge_normal=check_number(args.edge_normal, "--edge-normal", minimum=0))
        tool.angles(cut.teeth), tool.runout(cut.teeth)
    except InputError as err:
        raise InputError(err.message, field=tflags.get(err.field, err.field)) from None
    feed = check_number(args.feed_mm, "--feed-mm", above=0, unit="mm") * 1e-3
    opts = dict(revolutions=check_whole(args.revolutions, "--revolutions", minimum=8),
                steps_per_tooth=check_whole(args.steps_per_tooth, "--steps-per-tooth", minimum=4))
    return mx, my, cut, tool, feed, opts


def renamed(err: InputError) -> InputError:
    """A library error on a simulation field, renamed to the command-line flag."""
    names = {"depth_m": "--depth-mm", "rpm": "--rpm", "feed_m": "--feed-mm", "revolutions": "--revolutions",
             "steps_per_tooth": "--steps-per-tooth", "substeps": "--substeps", "modes": "--mode-x",
             "tooth_angles_deg": "--pitch-deg", "runout_m": "--runout-um"}
    return InputError(err.message, file=err.file, field=names.get(err.field, err.field))


# ----------------------------------------------------------------- simulate
def register(sub) -> None:
    """Add the ``simulate`` sub-command to the CLI's sub-parsers."""
    p = sub.add_parser("simulate", help="time-domain simulation of one milling cut: forces, chatter, SLE, surface",
                       description="Time-domain simulation of one milling cut (regenerative chatter, tool leaving "
                       "the cut, helix, runout). Units: Kt in N/m², depth and feed in mm, speed in rpm.")
    add_model_options(p)
    p.add_argument("--rpm", required=True, help="spindle speed, rpm")
    p.add_argument("--depth-mm", required=True, help="axial depth of cut, mm")
    p.add_argument("--substeps", help="substeps per time step (default: enough for 20 steps per period of the "
                   "highest mode; fewer than 8 are refused)")
    p.add_argument("--start", default="steady", choices=("steady", "rest"),
                   help="start on the periodic cut plus a small seed (steady, default) or at rest (rest)")
    p.add_argument("--force-noise", default="0",
                   help="random fluctuation of the cutting force, relative standard deviation over 5 kHz (default "
                   "0; 0.04–0.09 measured in turning): it drives the tool's modes as a real cut's noise does; the "
                   "verdict stays the noise-free cut's")
    p.add_argument("--out", help="results: .json (scalars, once-per-rev samples) or .csv (time histories)")
    p.add_argument("--plot", help="figure file (.png, .pdf, .svg, …): force, displacement, once-per-rev, surface")
    p.add_argument("--audio", help="synthetic sensor signal: .wav or .csv")
    p.add_argument("--sensor", default="microphone", choices=("microphone", "accelerometer"),
                   help="sensor of --audio: microphone (velocity, default) or accelerometer (acceleration)")
    p.add_argument("--rate", default="44100", help="sample rate of --audio, Hz (default 44100)")
    p.add_argument("--noise", default="0.01", help="noise of --audio relative to the signal RMS (default 0.01)")
    p.set_defaults(func=run)


def _outputs(args) -> dict:
    outs = {}
    for flag, value in (("--out", args.out), ("--plot", args.plot), ("--audio", args.audio)):
        if value:
            outs[flag] = out_path(value, flag, inputs=[args.modal] if args.modal else ())
    if "--out" in outs and outs["--out"].suffix.lower() not in (".json", ".csv"):
        raise InputError("expected a .json or .csv file", file=outs["--out"], field="--out")
    if "--audio" in outs and outs["--audio"].suffix.lower() not in (".wav", ".csv"):
        raise InputError("expected a .wav or .csv file", file=outs["--audio"], field="--audio")
    given = [p.resolve() for p in outs.values()]
    if len(set(given)) != len(given):
        raise InputError("--out, --plot and --audio must be different files", field="--out")
    return outs


def run(args) -> int:
    """Run ``toolpoint simulate``; returns the exit code (InputErrors are left to the caller: exit 2)."""
    from ..simulation import sensor_signal, simulate_milling

    mx, my, cut, tool, feed, opts = model_and_cut(args)
    rpm = check_number(args.rpm, "--rpm", above=0, unit="rpm")
    depth = check_number(args.depth_mm, "--depth-mm", minimum=0, unit="mm") * 1e-3
    substeps = None if args.substeps is None else check_whole(args.substeps, "--substeps", minimum=1)
    rate = check_number(args.rate, "--rate", above=0, unit="Hz")
    noise = check_number(args.noise, "--noise", minimum=0)
    force_noise = check_number(args.force_noise, "--force-noise", minimum=0, maximum=0.3)
    outs = _outputs(args)
    with warnings_to_stderr():
        try:
            res = simulate_milling(mx or None, my or None, cut, rpm=rpm, depth_m=depth, feed_m=feed, tool=tool,
                                   substeps=substeps, start=args.start, force_noise=force_noise, **opts)
            signal = sensor_signal(res, 0, kind=args.sensor, rate=rate, noise=noise) if "--audio" in outs else None
        except InputError as err:
            raise renamed(err) from None
    fig = _figure(res) if "--plot" in outs else None
    _write(outs, res, fig, signal, rate)
    verdict = "stable" if res.stable[0] else "chatter"
    chatter = f", chatter {res.chatter_hz[0]:.1f} Hz" if np.isfinite(res.chatter_hz[0]) else ""
    print(f"{verdict} at {rpm:g} rpm, {1e3 * depth:g} mm{chatter}; metric {res.metric[0]:.3g}, "
          f"growth {res.growth_per_rev[0]:+.3g}/rev")
    print(f"surface location error {1e6 * res.sle_m[0]:+.3f} µm (> 0 undercut), wall peak-to-valley "
          f"{1e6 * res.surface_pv_m[0]:.3f} µm; mean force Fx {res.mean_force_n[0, 0]:.4g} N, "
          f"Fy {res.mean_force_n[0, 1]:.4g} N")
    if outs:
        print("wrote " + ", ".join(str(p) for p in outs.values()))
    return 0


def _summary(res) -> dict:
    return dict(rpm=float(res.rpm[0]), depth_mm=1e3 * float(res.depth_m[0]), feed_mm=1e3 * res.feed_m,
                stable=bool(res.stable[0]), metric=float(res.metric[0]), growth_per_rev=float(res.growth_per_rev[0]),
                chatter_hz=None if not np.isfinite(res.chatter_hz[0]) else float(res.chatter_hz[0]),
                sle_um=1e6 * float(res.sle_m[0]), surface_pv_um=1e6 * float(res.surface_pv_m[0]),
                mean_force_n=[float(v) for v in res.mean_force_n[0]], dt_s=float(res.dt_s[0]),
                steps_per_rev=int(res.steps_per_rev), revolutions=int(res.revolutions),
                once_per_rev_m=res.once_per_rev_m[0].tolist(), surface_um=(1e6 * res.surface_m[0]).tolist())


def _figure(res):
    use_agg()
    from matplotlib.figure import Figure

    fig = Figure(figsize=(10, 7), constrained_layout=True)
    ax = fig.subplots(2, 2)
    t = 1e3 * res.time_s[0]
    ax[0, 0].plot(t, res.force_n[0, :, 0], lw=0.6, label="Fx")
    ax[0, 0].plot(t, res.force_n[0, :, 1], lw=0.6, label="Fy")
    ax[0, 0].set(xlabel="time (ms)", ylabel="force (N)", title="cutting force")
    ax[0, 0].legend(fontsize="small")
    ax[0, 1].plot(t, 1e6 * res.displacement_m[0, :, 0], lw=0.6, label="x")
    ax[0, 1].plot(t, 1e6 * res.displacement_m[0, :, 1], lw=0.6, label="y")
    ax[0, 1].set(xlabel="time (ms)", ylabel="displacement (µm)", title="tool displacement")
    ax[0, 1].legend(fontsize="small")
    opr = 1e6 * res.once_per_rev_m[0]
    ax[1, 0].plot(1e6 * res.displacement_m[0, :, 0], 1e6 * res.displacement_m[0, :, 1], lw=0.4, color="0.7")
    ax[1, 0].plot(opr[:, 0], opr[:, 1], "o", ms=3, color="C3")
    ax[1, 0].set(xlabel="x (µm)", ylabel="y (µm)", title="once-per-revolution samples")
    ax[1, 1].plot(1e6 * res.surface_m[0], ".-", lw=0.6)
    ax[1, 1].set(xlabel="tooth pass", ylabel="wall location (µm, > 0 undercut)", title="surface")
    fig.suptitle(f"{res.rpm[0]:g} rpm, {1e3 * res.depth_m[0]:g} mm: {'stable' if res.stable[0] else 'chatter'}",
                 fontsize="medium")
    return fig


def _write(outs, res, fig, signal, rate) -> None:
    """Write every output to a temporary file; rename them all only if all succeeded."""
    import soundfile

    with contextlib.ExitStack() as stack:
        if "--out" in outs:
            p = outs["--out"]
            fh = stack.enter_context(atomic_open(p, "w", newline=""))
            if p.suffix.lower() == ".json":
                json.dump(_summary(res), fh, indent=1)
            else:
                fh.write("t_s,x_m,y_m,fx_n,fy_n\n")
                np.savetxt(fh, np.column_stack([res.time_s[0], res.displacement_m[0], res.force_n[0]]),
                           fmt="%.10g", delimiter=",")
        if "--plot" in outs:
            tmp = stack.enter_context(atomic_path(outs["--plot"]))
            fig.savefig(tmp, format=outs["--plot"].suffix.lstrip(".").lower(), dpi=130)
        if "--audio" in outs:
            p = outs["--audio"]
            t, x = signal
            if p.suffix.lower() == ".wav":
                tmp = stack.enter_context(atomic_path(p))
                peak = float(np.max(np.abs(x))) if x.size else 0.0
                soundfile.write(tmp, 0.9 * x / peak if peak > 0 else x, int(round(rate)), subtype="PCM_24",
                                format="WAV")
            else:
                fh = stack.enter_context(atomic_open(p, "w", newline=""))
                fh.write("t_s,value\n")
                np.savetxt(fh, np.column_stack([t, x]), fmt="%.10g", delimiter=",")
