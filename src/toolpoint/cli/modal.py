"""``toolpoint modal FRF... [--quantity Q] [--band LO:HI] [--modes N|auto] [--driving-point K|none] --out modes.csv
[--plot PNG]``.

A common-pole modal fit (:func:`toolpoint.dynamics.modal.fit_frfs`) of one or
several FRFs of one structure to one input, all on one frequency grid. The fit
is weighted in the quantity the files hold (a hammer test: accelerance, whose
noise is white), or by the files' coherence when every file has one.

``modes.csv`` has one row per mode, header
``freq_hz,damping_ratio,A1_real,A1_imag,…,Am_real,Am_imag``: the natural
frequency f_r = |λ_r|/2π (Hz), the damping ratio ζ_r = −Re λ_r/|λ_r| and, per
FRF k in the order given, the complex modal constant A_kr of the *receptance*
(whatever quantity the file holds), in m/N × rad/s = m/(N s), such that

    H_k(ω) = Σ_r [ A_kr / (iω − λ_r) + conj(A_kr) / (iω − conj λ_r) ] + residual terms      (m/N)

with λ_r = −ζ_r ω_r + iω_r √(1 − ζ_r²), ω_r = 2π f_r. (Mobility and
accelerance are iω H and −ω² H.)

``--driving-point K`` declares FRF K (0-based; default 0 for one FRF, none for several) a driving point: its
modes must have positive modal mass (:func:`~toolpoint.dynamics.modal.fit_modal`). The fit's notes — modes of
negative mass dropped, or kept and named with a warning — go to stderr after the band's.
"""

from __future__ import annotations

import sys
import warnings
from pathlib import Path

import numpy as np

from ..dynamics.modal import DrivingPointWarning, fit_frfs
from ..errors import InputError
from ..frf import FRF
from ..io.atomic import atomic_open
from ..io.frf_files import read_frf
from ..trust import common_band
from .common import out_path, parse_band, save_figure, use_agg, warnings_to_stderr

QUANTITIES = ("receptance", "mobility", "accelerance")


def register(sub) -> None:
    """Add the ``modal`` sub-command to the argparse sub-parsers ``sub``."""
    p = sub.add_parser("modal", help="common-pole modal fit of one or several FRFs → natural frequencies, damping, "
                                     "modal constants")
    p.add_argument("frf", nargs="+", metavar="FRF",
                   help="FRF files of one structure to one input, on one frequency grid (.csv, .uff, .frf, .txt)")
    p.add_argument("--quantity", choices=QUANTITIES,
                   help="what the files hold (default: as each file says; CSV means receptance); the fit is "
                   "weighted in it (noise white in the measured quantity)")
    p.add_argument("--band", metavar="LO:HI",
                   help="fit only from LO to HI Hz (default: the trusted band found in the data — low-frequency "
                   "noise ×1/ω² and low coherence left out, with a note — above 0 Hz)")
    p.add_argument("--modes", default="auto", metavar="N|auto",
                   help="number of modes, or auto (default: chosen by the Bayesian information criterion)")
    p.add_argument("--driving-point", metavar="K|none",
                   help="0-based index K of the FRF (in the order given) that is a driving point (response at the "
                   "input, e.g. the tool point's direct FRF): its modes must have positive modal mass — modes of "
                   "negative mass are dropped when the data cannot tell the models apart, else kept with a warning "
                   "naming them (default: 0 when one FRF is given, none when several; none: no such check)")
    p.add_argument("--out", required=True,
                   help="modes CSV: freq_hz,damping_ratio, then A{k}_real,A{k}_imag per FRF k (1, 2, …): modal "
                   "constants of the receptance, m/N × rad/s = m/(N s)")
    p.add_argument("--plot", help="figure: measured vs fitted magnitude and phase per FRF (PNG/PDF/SVG)")
    p.set_defaults(func=run)


def parse_modes(text: str) -> int | None:
    """``"auto"`` → None; a positive integer → that integer; otherwise an InputError."""
    if text == "auto":
        return None
    try:
        n = int(text)
    except ValueError:
        n = 0
    if n < 1:
        raise InputError(f"expected a positive integer or auto, got {text!r}", file="command line", field="--modes")
    return n


def parse_driving_point(text: str | None, n_frfs: int) -> int | None:
    """``--driving-point``: None (not given) → 0 for one FRF, None for several; ``"none"`` → None; an index K with
    0 ≤ K < ``n_frfs`` → K; otherwise an InputError naming the flag."""
    if text is None:
        return 0 if n_frfs == 1 else None
    if text.strip().lower() == "none":
        return None
    try:
        k = int(text)
    except ValueError:
        k = -1
    if not 0 <= k < n_frfs:
        raise InputError(f"expected the 0-based index of one of the {n_frfs} FRF(s) (0–{n_frfs - 1}) or none, got "
                         f"{text!r}", file="command line", field="--driving-point")
    return k


def run(args) -> int:
    """Fit the FRF files, write ``--out`` (and ``--plot``); returns exit code 0.

    Bad input raises :class:`~toolpoint.errors.InputError` before anything is written
    (the CLI turns it into one line and exit code 2).
    """
    out = out_path(args.out, "--out", inputs=args.frf)
    plot = out_path(args.plot, "--plot", inputs=args.frf) if args.plot else None
    band = parse_band(args.band)
    n_modes = parse_modes(args.modes)
    driving = parse_driving_point(getattr(args, "driving_point", None), len(args.frf))
    with warnings_to_stderr():
        frfs = [read_frf(path, quantity=args.quantity) for path in args.frf]
        b = common_band(frfs, band=band, files=args.frf)
        notes = list(b.notes)
        f = frfs[0].freq_hz
        band = None if (b.lo_hz, b.hi_hz) == (f[0], f[-1]) else (b.lo_hz, b.hi_hz)
        _check(frfs, args.frf, band)
        try:
            with warnings.catch_warnings():  # the driving-point warning is in fit.notes, printed below
                warnings.simplefilter("ignore", DrivingPointWarning)
                fit = fit_frfs(frfs, band=band, n_modes=n_modes, noise=b.noise_quantity or None,
                               driving_point=driving)
        except InputError as e:
            flag = {"band": "--band", "n_modes": "--modes"}.get(e.field)
            if flag is None:
                raise
            if flag == "--band" and args.band is None:  # the data are short, not a band the user gave
                raise InputError(e.message.replace(" in the band 0–inf Hz", ""), file=args.frf[0],
                                 field="freq_hz") from None
            raise InputError(e.message, file="command line", field=flag) from None
    if plot:  # render first: a plotting failure must not leave a CSV without its figure
        fig = _figure(frfs, fit, args.frf)
    # all or none: the figure first (the likelier to fail), then the table; a failed table removes the figure
    if plot:
        save_figure(fig, plot)
    try:
        _write_modes(out, fit)
    except BaseException:
        if plot:
            plot.unlink(missing_ok=True)
        raise
    print(fit.table())
    print(f"{fit.n_modes} modes, {fit.band_hz[0]:g}–{fit.band_hz[1]:g} Hz, {len(frfs)} FRFs → {out}")
    for note in notes + list(fit.notes):
        print(note, file=sys.stderr)
    return 0


def _check(frfs, paths, band) -> None:
    """Name the file: another grid, or an FRF that is zero everywhere in the band."""
    f = frfs[0].freq_hz
    for g, path in zip(frfs, paths):
        if not np.array_equal(g.freq_hz, f):
            raise InputError(f"frequency grid ({g.freq_hz.size} points, {g.freq_hz[0]:g}–{g.freq_hz[-1]:g} Hz) "
                             f"differs from that of {paths[0]} ({f.size} points, {f[0]:g}–{f[-1]:g} Hz)",
                             file=path, field="freq_hz")
        lo, hi = band or (0.0, np.inf)
        sel = (f >= lo) & (f <= hi)
        if sel.any() and not np.any(g.values[sel]):
            raise InputError("the FRF is zero everywhere in the band: nothing to fit", file=path, field="values")


def _write_modes(path: Path, fit) -> None:
    m = fit.residues.shape[1]
    head = ["freq_hz", "damping_ratio"] + [f"A{k + 1}_{part}" for k in range(m) for part in ("real", "imag")]
    cols = [fit.fn_hz[:, None], fit.zeta[:, None], np.stack([fit.residues.real, fit.residues.imag], -1).reshape(
        fit.n_modes, 2 * m)]
    with atomic_open(path, "w", newline="") as fh:
        np.savetxt(fh, np.hstack(cols).reshape(-1, 2 + 2 * m), fmt="%.17g", delimiter=",", header=",".join(head),
                   comments="")


def _figure(frfs, fit, paths):
    """Magnitude (top) and phase (bottom) per FRF, measured and fitted, in the quantity each file held."""
    use_agg()
    import matplotlib.pyplot as plt

    m = len(frfs)
    rows = 3 if fit.diagram else 2
    fig, ax = plt.subplots(rows, m, sharex=True, squeeze=False, figsize=(4.5 * m + 1, 2.75 * rows),
                           constrained_layout=True)
    lo, hi = fit.band_hz
    for k, (g, path) in enumerate(zip(frfs, paths)):
        q = g.meta.get("file_quantity", g.quantity)
        f = g.freq_hz[(g.freq_hz >= lo) & (g.freq_hz <= hi)]
        measured = g.band(lo, hi)
        factor = (2j * np.pi * f) ** {"receptance": 0, "mobility": 1, "accelerance": 2}[q]
        measured = FRF(f, measured.values * factor, q, measured.label)
        measured.plot(ax=ax[:2, k], label="measured", color="0.55", lw=1.0)
        fit.frf(f, k, q).plot(ax=ax[:2, k], label=f"modal fit ({fit.n_modes} modes)", color="C3", lw=1.2)
        for a in ax[:2, k]:
            for fn in fit.fn_hz:
                a.axvline(fn, color="C0", lw=0.5, alpha=0.4)
        ax[0, k].set_title(f"{Path(str(path)).name} (fit error {100 * fit.fit_error[k]:.3g} %)", fontsize="medium")
        if fit.diagram:  # the stabilisation diagram the order was chosen from, under each FRF
            _stabilisation(ax[2, k], fit, lo, hi)
    return fig


def _stabilisation(a, fit, lo, hi):
    """Poles of every LSCF order (f_n against order): a pole that recurs within 1 % in f_n and 20 % in ζ at the
    next order (the top order: the one below) is stable (filled); the fit's modes are the vertical lines."""
    orders = list(fit.diagram)
    # the top order has no next one: it is judged against the one below
    neighbours = [d for _, d in orders[1:]] + ([orders[-2][1]] if len(orders) > 1 else [np.empty(0, complex)])
    for (order, lam), nxt in zip(orders, neighbours):
        fn = np.abs(lam) / (2 * np.pi)
        ze = -lam.real / np.maximum(np.abs(lam), 1e-300)
        inside = (fn >= lo) & (fn <= hi)
        if nxt.size:
            fk, zk = np.abs(nxt) / (2 * np.pi), -nxt.real / np.maximum(np.abs(nxt), 1e-300)
            stable = np.array([np.any((abs(fk - f) < 0.01 * f) & (abs(zk - z) < 0.2 * max(z, 1e-9)))
                               for f, z in zip(fn, ze)], bool) if fn.size else np.zeros(0, bool)
        else:
            stable = np.zeros(fn.size, bool)
        a.plot(fn[inside & stable], np.full((inside & stable).sum(), order), "o", ms=3, color="C0")
        a.plot(fn[inside & ~stable], np.full((inside & ~stable).sum(), order), "x", ms=3, color="0.6")
    for f in fit.fn_hz:
        a.axvline(f, color="C3", lw=0.8, alpha=0.6)
    a.set_ylabel("model order")
    a.set_xlabel("frequency [Hz]")
    a.set_title("stabilisation diagram (● stable, × not; red: modes kept)", fontsize="small")
