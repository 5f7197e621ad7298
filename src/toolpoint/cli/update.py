"""``toolpoint update (--prior PRIOR.toml | --library OUT --tool ID) --cuts CUTS.csv --out DIR [--seed N]``.

Bayesian update of the stability lobes from test cuts (:func:`toolpoint.shop.update`): the prior is a modal-prior
TOML file (:mod:`toolpoint.shop.prior`) or a tool of a ``library`` output; the test cuts a CSV ``rpm, depth_mm,
result`` (stable|chatter), optional ``chatter_hz``, ``duration_s`` (how long the tool cut), ``growth_per_s`` (how fast a
chattering cut's chatter grew, 1/s) and ``record`` (a record of the cut, analysed as ``toolpoint cut`` does; it also
gives the duration and the growth rate), with ``start_s``/``end_s`` where the
record holds several cuts (the row's part of it, as ``cut --start --end``). Writes ``lobes.csv``, ``p_stable.csv``,
``parameters.csv``, ``update.json`` (recommended point, the next test cut and its rule), ``lobes.png`` and
``report.html`` in ``--out``; prints the recommendation and the next cut. Contradictory labels are refused (exit 2),
not averaged.
"""

from __future__ import annotations

import math
import sys
import warnings

from ..errors import InputError
from .common import check_number, check_whole, out_folder, use_agg, warnings_to_stderr


def register(sub) -> None:
    """Add the ``update`` sub-command to the CLI's sub-parsers."""
    p = sub.add_parser("update", help="test cuts → posterior lobes (5/50/95 %%), P(stable) map, parameters, next cut",
                       description="Update the stability lobes of a tool from test cuts (sequential Monte Carlo "
                       "over modal parameters and K_t) and propose the next test cut.")
    src = p.add_mutually_exclusive_group(required=True)
    src.add_argument("--prior", help="modal-prior TOML (modes with σ, or a [measured] table naming a tap test's "
                     "FRF with the σ you state; cut with K_t in N/mm²)")
    src.add_argument("--library", help="a library output folder (with --tool)")
    p.add_argument("--tool", help="tool id in the library output")
    p.add_argument("--frf", help="with --prior: the measured tool-point FRF (a tap test: toolpoint tap's output, "
                   "CSV/UFF/CutPro) whose modes the prior takes, in place of the file's [[mode]] tables")
    p.add_argument("--sigma-freq", help="with --library: log standard deviation of the natural frequencies "
                   "(default 0.01: the running spindle's shift, which the library does not model)")
    p.add_argument("--cuts", help="test-cut table CSV (rpm, depth_mm, result[, chatter_hz][, duration_s]"
                   "[, growth_per_s][, ring_per_s, ring_hz][, record[, start_s, end_s]]); without it: the prior's"
                   " lobes and the first cut")
    p.add_argument("--no-growth", action="store_true",
                   help="leave the chattering cuts' growth rates out of the update (their labels and chatter "
                   "frequencies stay): docs/design/shop.md, *A chattering cut's growth rate*")
    p.add_argument("--no-ring", action="store_true",
                   help="leave the stable cuts' rings out of the update (their labels stay): docs/design/shop.md, "
                   "*A stable cut's ring in update*")
    p.add_argument("--no-precursor", action="store_true",
                   help="take every label at its word even where the stable cuts ring (a noisy shop's false "
                   "chatter, and its chatter heard late at a pocket's top: docs/design/shop.md, *A noisy shop's "
                   "false chatter*, *A noisy shop's pocket*), e.g. labels checked on the surface")
    p.add_argument("--out", required=True, help="output folder")
    p.add_argument("--seed", default="0", help="random seed (default 0)")
    p.add_argument("--samples", default="1000", help="posterior samples (default 1000)")
    p.add_argument("--method", choices=("smc", "sir"), default="smc", help="sampler (default smc)")
    p.add_argument("--rule", choices=("info", "risk"), default="info",
                   help="next-cut rule: info = most reduction of the limit's band at the recommended speed with "
                   "P(chatter) ≤ risk (default); risk = most productive cut with P(chatter) ≤ risk")
    p.add_argument("--risk", help="largest P(chatter) of the next cut (default 0.3 for info, 0.1 for risk)")
    p.add_argument("--risk-after-chatter",
                   help="largest P(chatter) of the next cut once a cut has chattered (≤ --risk; default: --risk): "
                   "fewer chattering cuts, a wider band (docs/design/shop.md)")
    p.add_argument("--min-step",
                   help="info rule: until the first chatter, a cut e^STEP above the highest stable cut near a speed "
                   "(±2 %%) may be proposed even past --risk, so stable cuts do not creep (default 0.1 = 2 × the "
                   "default boundary width; 0: never: docs/design/shop.md)")
    p.add_argument("--step-only-after-creep", action="store_true",
                   help="info rule: step only once the two highest stable cuts near a speed (±2 %%) crept closer "
                   "than e^--min-step, chatter or not (the trigger before 2026-11-29): fewer chattering cuts, a "
                   "slower climb (docs/design/shop.md, *The step until the first chatter*)")
    p.add_argument("--step-until-near-chatter", action="store_true",
                   help="info rule: keep the step above stable cuts near a speed until a cut within ±2 %% of it "
                   "chatters (not any cut): fewer cuts, more chattering ones (docs/design/shop.md, *The step after "
                   "a chatter elsewhere*)")
    p.add_argument("--label-offset", metavar="MEAN,SD",
                   help="ln of how far above the stability limit your cuts' chatter is first heard (mean, standard "
                   "deviation; default 0.01,0.02: where `cut`'s labels lie, fitted to 1 440 simulated cuts of six "
                   "tools, docs/design/shop.md); 0.035,0.035 for labels by ear or another detector, heard later; "
                   "0,0 if your labels are the limit itself")
    p.add_argument("--boundary-width", metavar="LN",
                   help="ln of how far from the limit your cuts' labels are uncertain (default 0.05; 0.03 converged in "
                   "fewer cuts on the campaign tools and put the recommended depth above the true limit more often "
                   "on one, docs/design/shop.md; benchmarks/label_fit.py fits w from logged cuts)")
    p.add_argument("--cut-speed-margin", metavar="SHARE",
                   help="recommend a speed already cut (±0.5 %%) where its removal rate at the 5 %% limit is within "
                   "SHARE of the best speed's (default 0: the best; 0.03 converged in fewer cuts on two of three "
                   "truth sets of one campaign tool, not on the third, docs/design/shop.md); update.json says "
                   "whether it is at a cut speed")
    p.add_argument("--next-speeds", metavar="N",
                   help="info rule: propose the next cut at the recommended speed or at one of the N most productive "
                   "speeds (default 6; 0: at the recommended speed only, where a cut tells its limit without the "
                   "lobes' slope between speeds; with --cut-speed-margin 0.03 it converged in fewer cuts on one "
                   "truth set of one campaign tool, not on fresh truths, docs/design/shop.md)")
    p.add_argument("--label-growth", metavar="MEDIAN,SD",
                   help="ln of how much chatter must grow within a cut to be heard (median, log standard deviation; "
                   "default 2.5,0.5: fitted to the chatter detector's labels, docs/design/shop.md); just past the "
                   "limit chatter grows slowly on a lightly damped mode, so a short cut there sounds stable; 0,0: off")
    p.add_argument("--cut-duration",
                   help="how long each test cut lasted, s, where the table has no duration_s and no record "
                   "(default 1; shorter is the safer guess)")
    p.add_argument("--audible-margin", metavar="LN",
                   help="propose the next cut longer than the cuts so far where chatter grows slowly, so that chatter "
                   "LN past the limit grows audibly within it (default 0.025: 3-4 s on a lightly damped mode, "
                   "a well-damped tool's cuts unchanged; 0: as long as the cuts so far; docs/design/shop.md)")
    p.add_argument("--max-cut-duration",
                   help="with --audible-margin: the longest next test cut proposed, s (default 5)")
    p.add_argument("--forward", choices=("sdm", "zoa"), default="sdm",
                   help="forward model: sdm = zero-order limit corrected by the semi-discretisation at posterior "
                   "samples, as a machine's cuts follow it (default; what the virtual campaigns were measured "
                   "with); zoa = zero-order limit alone (faster; biased at low radial immersion)")
    p.set_defaults(func=run)


def run(args) -> int:
    """Run ``toolpoint update``; returns the exit code."""
    out = out_folder(args.out, "--out")
    seed = check_number(args.seed, "--seed", minimum=0)
    if seed != int(seed):
        raise InputError(f"must be a whole number, got {args.seed!r}", file="command line", field="--seed")
    n = check_number(args.samples, "--samples", minimum=50)
    risk = None if args.risk is None else check_number(args.risk, "--risk", above=0, maximum=0.5)
    rac = None if args.risk_after_chatter is None else check_number(args.risk_after_chatter, "--risk-after-chatter",
                                                                      above=0)
    from ..shop.update import DEFAULT_RISK

    if rac is not None and rac > (risk if risk is not None else DEFAULT_RISK[args.rule]):
        raise InputError(f"must be ≤ the bound before any chatter (--risk), got {args.risk_after_chatter}",
                         file="command line", field="--risk-after-chatter")
    min_step = None if args.min_step is None else check_number(args.min_step, "--min-step", minimum=0, maximum=0.5,
                                                               why="a log step: ×1.65")
    offset = {}
    if args.step_only_after_creep:
        if args.rule != "info":
            raise InputError("only with --rule info (the risk rule never steps)", file="command line",
                             field="--step-only-after-creep")
        offset["step_until_chatter"] = False
    if args.step_until_near_chatter:
        if args.rule != "info" or args.step_only_after_creep:
            raise InputError("only with --rule info and without --step-only-after-creep", file="command line",
                             field="--step-until-near-chatter")
        offset["step_until_chatter"] = "near"
    if args.label_offset is not None:
        offset["label_offset"] = _pair(args.label_offset, "--label-offset", "MEAN,SD", (-0.2, 0.5), (0, 0.5))
    if args.boundary_width is not None:
        offset["boundary_width"] = check_number(args.boundary_width, "--boundary-width", above=0, maximum=0.5,
                                                why="ln")
    if args.cut_speed_margin is not None:
        offset["cut_speed_margin"] = check_number(args.cut_speed_margin, "--cut-speed-margin", minimum=0,
                                                  maximum=0.5, why="a share of the removal rate")
    if args.next_speeds is not None:
        k = check_whole(args.next_speeds, "--next-speeds", minimum=0)
        if k > 50:
            raise InputError(f"must be ≤ 50, got {k}", file="command line", field="--next-speeds")
        offset["next_speeds"] = k
    if args.label_growth is not None:
        offset["label_growth"] = _pair(args.label_growth, "--label-growth", "MEDIAN,SD", (0, 20), (0, 1.5))
    if args.cut_duration is not None:
        offset["cut_duration_s"] = check_number(args.cut_duration, "--cut-duration", above=0, maximum=3600,
                                                unit="s", why="as a table's duration_s")
    if args.audible_margin is not None:
        offset["audible_margin"] = check_number(args.audible_margin, "--audible-margin", minimum=0, maximum=0.5,
                                                why="ln")
    if args.max_cut_duration is not None:
        offset["max_cut_duration_s"] = check_number(args.max_cut_duration, "--max-cut-duration", above=0,
                                                    maximum=3600, unit="s")
    if args.no_growth:
        offset["growth_error"] = None
    if args.no_ring:
        offset["ring_error"] = None
    if args.no_precursor:
        offset["precursor"] = offset["noisy_pocket"] = None
    if args.library and not args.tool:
        raise InputError("--library needs --tool ID", file="command line", field="--tool")
    if args.sigma_freq is not None and not args.library:
        raise InputError("only with --library (a prior file states its own σ)", file="command line",
                         field="--sigma-freq")
    sig_f = None if args.sigma_freq is None else check_number(args.sigma_freq, "--sigma-freq", minimum=0, maximum=0.5,
                                                              why="a log standard deviation")
    import numpy as np

    from ..shop.prior import prior_from_library, read_modal_prior
    from ..shop.report import (away_note, noisy_pocket_doc, noisy_pocket_note, pocket_note, precursor_doc,
                               precursor_note, write_update)
    from ..shop.update import read_test_cuts, update

    if args.frf is not None and not args.prior:
        raise InputError("only with --prior (its [cut] and the σ of the measured modes)", file="command line",
                         field="--frf")
    if args.prior:
        with warnings_to_stderr(), warnings.catch_warnings():  # the modal fit's notes on a measured FRF (modes of
            warnings.simplefilter("always")  # negative modal mass): on stderr, whatever the filters say
            prior = read_modal_prior(args.prior, frf=args.frf)
    else:
        prior = prior_from_library(args.library, args.tool, **({} if sig_f is None else {"sigma_freq": sig_f}))
    # the modes the prior rests on (a measured FRF's fit, a library tool's peaks, or the file's own), said in order
    # of frequency (a library tool lists them strongest first)
    print(f"prior {prior.name}: " + "; ".join(
        f"{f:.1f} Hz, k {k:.3g} N/m, ζ {100 * z:.2f} % (σ {sf:.3g}, {sk:.3g}, {sz:.3g})" for f, k, z, sf, sk, sz in
        sorted(zip(prior.freq_hz, prior.stiffness_n_m, prior.damping, prior.sigma_freq, prior.sigma_stiffness,
                   prior.sigma_damping))) + f"; K_t {prior.cutting.tangential_coeff / 1e6:.4g} N/mm² "
          f"(σ {prior.sigma_kt:.3g})")
    cuts = read_test_cuts(args.cuts, teeth=prior.cutting.teeth) if args.cuts else []
    use_agg()
    post = update(prior, cuts, rng=np.random.default_rng(int(seed)), n_samples=int(n), method=args.method,
                  rule=args.rule, risk=risk, forward=args.forward, min_step=min_step, risk_after_chatter=rac,
                  **offset)
    write_update(post, out)
    rc, nc = post.recommended, post.next_cut
    low = rc["limit_p05_m"] > rc["depth_m"]  # the samples' own SDM limits put it lower
    print(f"{len(cuts)} test cuts; recommended {rc['rpm']:.0f} rpm at {1e3 * rc['depth_m']:.3f} mm "
          f"(P(stable) {rc['p_stable']:.2f}"
          + (f"; the band's 5 % limit {1e3 * rc['limit_p05_m']:.3f} mm, lowered by posterior samples' own SDM limits"
             if low else "")
          + f"); next test cut ({nc['rule']}) {nc['rpm']:.0f} rpm at "
          f"{1e3 * nc['depth_m']:.3f} mm for at least {nc['duration_s']:.1f} s ({nc['revolutions']} rev"
          f"{': chatter grows slowly there' if nc['duration_by_growth'] else ''}), "
          f"P(chatter) {nc['p_chatter']:.2f}"
          f"{' (a step above the highest stable cut near this speed)' if nc.get('stepped') else ''}"
          f"{' (it repeats a cut already made there: none within the bound would be new)' if nc.get('repeat') else ''}"
          f"; wrote {out}/report.html")
    if rc["own_sdm_held_out"] is False:  # the check by samples the speed's choice saw: said, not hidden
        print(f"note: the recommended depth was checked by the lobe samples themselves ({int(n)} posterior "
              "samples leave fewer than 100 beyond them); --samples 1000 checks it by held-out samples")
    if cuts:
        print("note: " + away_note([{"rpm": c.rpm} for c in cuts]))
    rates = _growth_read(post, args.no_growth)
    if rates:
        print("growth rates: " + rates)
    rings = _ring_read(post, args.no_ring)
    if rings:
        print("rings: " + rings)
    if (pc := precursor_doc(post)) is not None and any(not c.stable and c.growth_per_s is None for c in cuts):
        print("noisy shop: " + precursor_note(pc))  # said where a chatter label is read differently
    if (npd := noisy_pocket_doc(post)) is not None:
        print("noisy shop: " + noisy_pocket_note(npd))
    pocket = pocket_note({"rpm": rc["rpm"], "limit_p05_mm": 1e3 * rc["limit_p05_m"],
                          "own_sdm_p05_mm": None if rc["own_sdm_p05_m"] is None else 1e3 * rc["own_sdm_p05_m"],
                          "lobes_own_sdm": post.own_sdm_ess is not None})
    if pocket is not None:
        print("note: " + pocket)
    for c in cuts:  # a label that rests on a doubtful record: said where the user looks
        for w in c.warnings:
            print(f"{args.cuts}: line {c.line}: warning: {w}", file=sys.stderr)
    for c, w in [*_depth_units(post), *_outside(post)]:
        print(f"{args.cuts}: line {c.line}: warning: {w}", file=sys.stderr)
    return 0


def _outside(post, far: float = 0.5):
    """(cut, warning) for a cut outside the speeds the lobes are drawn over (it counts, but the map, the recommended
    point and the next cut stay within them), and for a chatter frequency farther than ``far`` (relative) from every
    mode of the prior and its tooth-passing aliases f ± j f_t (|j| ≤ 2): a kHz value in a Hz column, or a machine's
    line taken for chatter. Only said: the likelihood's chatter-frequency term gives such a line 5 % outlier weight."""
    import numpy as np

    lo, hi = float(np.min(post.rpm)), float(np.max(post.rpm))
    f_modes = np.asarray(post.prior.freq_hz, float)
    teeth = post.prior.cutting.teeth
    for c in post.cuts:
        if not lo * 0.995 <= c.rpm <= hi * 1.005:
            yield c, (f"{c.rpm:g} rpm lies outside the speeds of the lobes ({lo:.0f}–{hi:.0f} rpm): the cut counts, "
                      "but the map, the recommended point and the next cut stay within them")
        if c.chatter_hz is not None:
            f_t = teeth * c.rpm / 60.0
            near = f_modes[:, None] + f_t * np.arange(-2, 3)[None, :]
            if np.min(np.abs(c.chatter_hz / near - 1)) > far:
                yield c, (f"chatter at {c.chatter_hz:.1f} Hz lies far from every mode of the prior "
                          f"({', '.join(f'{f:.0f}' for f in f_modes)} Hz) and their tooth-passing aliases: is the "
                          "chatter_hz column in Hz, and the line the cut's?")


def _growth_read(post, left_out: bool) -> str:
    """What each chattering cut's measured growth rate was read as (the report's table says the same), or ''."""
    parts = []
    for i, (c, x) in enumerate(zip(post.cuts, post.growth_past_limit or (None,) * len(post.cuts))):
        if c.stable or c.growth_per_s is None:
            continue
        where = f"cut {i + 1}" if c.line is None else f"line {c.line}"  # a cut made in code has no line
        said = (f"{where}: {c.growth_per_s:.3g} /s"
                + (" (left out: --no-growth)" if left_out else
                   f" = {100 * (math.exp(x) - 1):.1f} % past the limit by the SDM's growth" if x is not None else
                   " (per sample, the zero-order growth)" if post.forward == "zoa" else
                   " (not read: the references' growth curves do not reach it)"))
        parts.append(said)
    return "; ".join(parts)


def _ring_read(post, left_out: bool) -> str:
    """What each stable cut's ring was read as (the report's table says the same), or ''."""
    from ..shop.update import ring_left_out

    parts = []
    for i, (c, x) in enumerate(zip(post.cuts, post.ring_under_limit or (None,) * len(post.cuts))):
        if not c.stable or c.ring_per_s is None:
            continue
        where = f"cut {i + 1}" if c.line is None else f"line {c.line}"
        why_off = ("more than 10 % from the tool's chatter frequency and its tooth-passing aliases, or faster than "
                   "the SDM's decay curves reach")
        parts.append(f"{where}: {c.ring_per_s:.3g} /s at {c.ring_hz:.1f} Hz"
                     + (" (left out: --no-ring)" if left_out else
                        f" = at most {100 * (1 - math.exp(x)):.1f} % under the limit by the SDM's decay"
                        if x is not None else
                        " (not read: the zero-order forward model)" if post.forward == "zoa" else
                        f" (not read: {ring_left_out(post.cuts, i) or why_off})"))
    return "; ".join(parts)


def _depth_units(post, factor: float = 30.0):
    """(cut, warning) for depths more than ``factor`` × outside the prior's lobes (below its smallest 5 % limit,
    above its largest 95 %): a depth typed in m or µm into ``depth_mm``, or a column mixed up. Only said: a label
    that far from every lobe tells the posterior next to nothing, so a slip would otherwise pass unseen."""
    import numpy as np

    q = np.where(np.isfinite(post.prior_limit_q_m) & (post.prior_limit_q_m > 0), post.prior_limit_q_m, np.nan)
    if np.isnan(q[0]).all() or np.isnan(q[2]).all():  # no lobe on the grid: nothing to compare with
        return
    lo, hi = np.nanmin(q[0]), np.nanmax(q[2])
    for c in post.cuts:
        if c.depth_m < lo / factor or c.depth_m > hi * factor:
            low = c.depth_m < lo / factor
            yield c, (f"depth {1e3 * c.depth_m:g} mm is {f'under 1/{factor:g} of' if low else f'over {factor:g} ×'} "
                      f"the prior's {'smallest 5 %' if low else 'largest 95 %'} limit "
                      f"({1e3 * (lo if low else hi):.3g} mm): is the depth_mm column in mm?")


def _pair(value: str, flag: str, form: str, first: tuple, second: tuple) -> tuple:
    """``A,B`` of a prior (ln), A in ``first`` and B in ``second`` (closed ranges), else one line naming ``flag``."""
    parts = value.split(",")
    if len(parts) != 2:
        raise InputError(f"must be {form}, got {value!r}", file="command line", field=flag)
    a = check_number(parts[0], flag, minimum=first[0])
    b = check_number(parts[1], flag, minimum=second[0])
    if a > first[1] or b > second[1]:
        raise InputError(f"{form} must be ≤ {first[1]:g},{second[1]:g} (ln), got {value!r}", file="command line",
                         field=flag)
    return a, b
