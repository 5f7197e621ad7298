"""``toolpoint cut RECORD --rpm N --teeth Z [--rate HZ] [--channel K] [--start S] [--end S] [--out cut.json]
[--plot cut.png] [--table cuts.csv]``.

Chatter detection from a record of a cut: microphone audio (WAV, FLAC, OGG, MP3), accelerometer or
displacement time histories (CSV/text columns, time first; one column with ``--rate``; UFF58). Spindle
and tooth-passing harmonics (all multiples of the spindle frequency: runout included) are removed, the
strongest remaining peak is tested (:func:`toolpoint.shop.analyse_cut` documents the criterion), per
segment (air cut, entry, cut windows, exit; talk near the microphone left out as ``talk``).

``cut.json``: ``verdict`` (stable|chatter), ``chatter_hz`` (null when stable), ``cuts`` (start_s, end_s, verdict,
chatter_hz of each cut between air cuts, and part_s: the part that holds it with its air), ``segments`` (kind,
start_s, end_s, verdict, chatter_hz, …), ``rpm_measured`` (from the spindle harmonics), ``recommended_rpm`` (a
tooth-passing harmonic on the chatter frequency), ``growth`` (how fast the chatter grew: ``rate_per_s``, the rise's
``start_s``/``end_s``, or the ``reason`` it was not read; null when stable: :mod:`toolpoint.shop.growth`), ``ring``
(how fast the line a stable cut, or a weak chatter line, rings at decays: ``rate_per_s`` ≤ 0, ``ln_sd``, ``freq_hz``,
``resolved``, or the ``reason`` it was not read; :func:`toolpoint.shop.growth.ring_decay`) and the criterion used.
A one-line summary goes to stdout (and a line of each cut's verdict where the record holds several). ``--table``: a
test-cut table for ``toolpoint update`` (``rpm, depth_mm, result, record, start_s, end_s``, one row per cut,
``depth_mm`` left for the user, ``result`` to the record). Bad input: one line naming file and field, exit 2.
"""

from __future__ import annotations

import json
import math
import os
import sys
from pathlib import Path

from ..errors import InputError
from .common import check_number, check_whole, out_path, save_figure, use_agg


def register(sub) -> None:
    """Add the ``cut`` sub-command to the CLI's sub-parsers."""
    p = sub.add_parser("cut", help="chatter detection from a record of a cut (audio, accelerometer, UFF58)",
                       description="Judge a test cut from its record: stable or chatter per segment, chatter "
                       "frequency, measured spindle speed and a Harmonizer-style speed.")
    p.add_argument("record", metavar="RECORD",
                   help="audio (.wav/.flac/.ogg/.mp3/.aiff/.caf, RF64, Wave64), text/CSV columns or UFF58")
    p.add_argument("--rpm", required=True, help="nominal spindle speed, rpm (refined from the record)")
    p.add_argument("--teeth", required=True, help="number of teeth")
    p.add_argument("--rate", help="sampling rate, Hz (needed for a one-column table)")
    p.add_argument("--channel", help="0-based channel / column (default: the mean of audio channels; the loudest "
                   "channel where the mean cancels in a band: microphones apart)")
    p.add_argument("--rpm-tolerance", default="0.03",
                   help="relative search range around --rpm for the spindle harmonics (default 0.03; 0 = exact)")
    p.add_argument("--window", default="1.0", help="length of the windows the cut is judged in, s (default 1)")
    p.add_argument("--dominance", default="0.05",
                   help="least power of a chatter line relative to the strongest spindle harmonic's (default 0.05, "
                        "-13 dB); lower finds weaker chatter and risks calling a noisy stable cut chatter")
    p.add_argument("--alias-dominance", default="0.002",
                   help="the same for a line whose tooth-passing alias (f +- f_t, f +- 2 f_t) is a new line too "
                        "(default 0.002, -27 dB; 0: never below --dominance)")
    p.add_argument("--growth-db", default="6",
                   help="a new line whose power rises steadily by this much over a judged part is chatter, however "
                        "weak (default 6 dB, with t >= 4; 0: no growth test)")
    p.add_argument("--hump-db", default="15",
                   help="a strong chatter line standing less than this over its neighbours is a hump: its ring is "
                        "read, and one that decays as a stable cut's (a mode the cutting noise drives) is not "
                        "chatter (default 15 dB; 0: not read)")
    p.add_argument("--start", help="judge the record from this time on, s (one cut of a record that holds cuts at "
                   "several speeds; times stay the record's)")
    p.add_argument("--end", help="judge the record up to this time, s")
    p.add_argument("--out", help="result JSON (default: print it)")
    p.add_argument("--table", help="also write a test-cut table for `toolpoint update`: one row per cut, with the "
                   "record and the part that holds the cut with its air (start_s, end_s); fill in depth_mm")
    p.add_argument("--plot", help="spectrogram with the harmonics and segments marked, and the chattering cut's "
                   "mean spectrum against the air cut's (.png/.pdf/.svg)")
    p.set_defaults(func=run)


def run(args) -> int:
    """Run ``toolpoint cut``; returns the exit code."""
    rec_path = Path(args.record)
    out = out_path(args.out, "--out", inputs=[rec_path]) if args.out else None
    plot = out_path(args.plot, "--plot", inputs=[rec_path]) if args.plot else None
    table = out_path(args.table, "--table", inputs=[rec_path]) if args.table else None
    given = [(f, q.resolve()) for f, q in (("--out", out), ("--plot", plot), ("--table", table)) if q is not None]
    for k, (flag, q) in enumerate(given):  # one file for two outputs: the later write would replace the earlier
        if any(q == q0 for _, q0 in given[:k]):
            raise InputError("--out, --plot and --table must be different files", file="command line", field=flag)
    rpm = check_number(args.rpm, "--rpm", above=0, unit="rpm")
    teeth = check_whole(args.teeth, "--teeth")
    rate = check_number(args.rate, "--rate", above=0, unit="Hz") if args.rate is not None else None
    channel = check_whole(args.channel, "--channel") if args.channel is not None else None
    tol = check_number(args.rpm_tolerance, "--rpm-tolerance", minimum=0)
    if tol >= 0.5:
        raise InputError(f"must be < 0.5, got {args.rpm_tolerance}", file="command line", field="--rpm-tolerance")
    window = check_number(args.window, "--window", above=0, unit="s")
    start = check_number(args.start, "--start", minimum=0, unit="s") if args.start is not None else None
    end = check_number(args.end, "--end", above=0, unit="s") if args.end is not None else None
    if start is not None and end is not None and end <= start:
        raise InputError(f"must be after --start ({start:g} s), got {end:g} s", file="command line", field="--end")
    dominance = check_number(args.dominance, "--dominance", above=0)
    alias_dominance = check_number(args.alias_dominance, "--alias-dominance", minimum=0)
    growth_db = check_number(args.growth_db, "--growth-db", minimum=0, unit="dB")
    hump_db = check_number(args.hump_db, "--hump-db", minimum=0, unit="dB")
    from ..io.atomic import atomic_open
    from ..io.records import read_cut_record
    from ..shop import analyse_cut

    rec = read_cut_record(rec_path, rate_hz=rate, channel=channel)
    if start is not None and start >= rec.duration_s:
        raise InputError(f"{start:g} s is after the record's end ({rec.duration_s:.4g} s)", file=rec_path,
                         field="--start")
    res = analyse_cut(rec.samples, rec.rate_hz, rpm=rpm, teeth=teeth, rpm_tolerance=tol, window_s=window,
                      dominance=dominance, alias_dominance=alias_dominance, growth_db=growth_db,
                      hump_db=hump_db, full_scale=rec.full_scale, source=str(rec_path),
                      span_s=None if start is None and end is None else (start or 0.0, end or math.inf))
    doc = {"record": str(rec_path), "channel": rec.channel, "rate_hz": rec.rate_hz,
           "record_warnings": list(rec.warnings), **res.to_dict()}
    fig = None
    if plot is not None:
        use_agg()
        from ..shop.detect import plot_cut
        fig = plot_cut(res, name=rec_path.name)
    text = json.dumps(doc, indent=2)
    if out is not None:
        with atomic_open(out) as fh:
            fh.write(text + "\n")
    if table is not None:  # rows update reads: the record's path relative to the table, each cut's part
        rel = os.path.relpath(rec_path.resolve(), table.resolve().parent)
        import csv

        from ..io.table import csv_safe

        with atomic_open(table) as fh:  # csv quotes a record path that holds a comma; no cell runs as a formula
            w = csv.writer(fh, lineterminator="\n")
            w.writerow(["rpm", "depth_mm", "result", "record", "start_s", "end_s"])
            w.writerows([f"{res.rpm_nominal:g}", "", "", csv_safe(rel), f"{p0:.2f}", f"{p1:.2f}"]
                        for p0, p1 in res.parts)
    if fig is not None:
        save_figure(fig, plot)
    if out is None:
        print(text)
    msg = (f"{rec_path.name}: {res.verdict}"
           + (f" at {res.chatter_hz:.1f} Hz; Harmonizer speed {res.recommended_rpm:.0f} rpm" if res.chatter_hz else "")
           + ("" if res.growth is None else f"; its chatter grew at {res.growth.rate_per_s:.3g} /s"
              if res.growth.rate_per_s is not None else f"; its growth rate was not read ({res.growth.reason})")
           + (f"; its strongest line ({res.ring.freq_hz:.1f} Hz) decays at {-res.ring.rate_per_s:.3g} /s"
              if res.verdict == "stable" and res.ring is not None and res.ring.rate_per_s is not None
              and res.ring.resolved else "")
           + f"; spindle {res.rpm:.1f} rpm"
           + (f", its speed wandered ±{100 * res.criterion['speed_wander']:.2g} % (tracked)"
              if res.criterion.get("speed_tracked") else "")
           + ("; left out " + " and ".join(f"{a:.1f}–{b:.1f} s" for a, b in res.criterion["spindle_off_s"])
              + " (the spindle not at speed: starting, coasting or stopped)"
              if res.criterion.get("spindle_off_s") else ""))
    print(msg, file=sys.stderr if out is None else sys.stdout)
    if len(res.cuts) > 1:  # a session's record: each cut's verdict
        print(f"{rec_path.name}: {len(res.cuts)} cuts: " + "; ".join(
            f"{a:.1f}–{b:.1f} s {v}" + (f" at {hz:.1f} Hz" if hz else "") for a, b, v, hz in res.cuts)
            + " (each with its air, to judge alone with --start/--end: "
            + ", ".join(f"{p0:.1f}–{p1:.1f} s" for p0, p1 in res.parts) + ")",
            file=sys.stderr if out is None else sys.stdout)
    for w in (*rec.warnings, *res.criterion.get("warnings", ())):
        print(f"{rec_path.name}: warning: {w}", file=sys.stderr)
    return 0
