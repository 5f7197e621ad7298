r"""Bayesian update of the stability lobes from test cuts, and the next test cut.

Likelihood of a test cut at speed n and depth a (Karandikar et al. 2014 and Cornelius et al. 2024 use the
same kind of model; here with label noise and a chatter-frequency term):

    P(stable | θ, δ) = ε + (1 − 2ε) Φ( ln(a_lim(θ, n) e^δ / a) / w ),

δ the *label offset*: how far (ln) above the stability limit the shop first hears chatter — one for all the
cuts, a parameter of the posterior with prior N(μ, s²) (default μ = 0.01, s = 0.02). A detector hears chatter
only once it stands out of the forced vibration. Refitted on 2026-12-07 to the labels of ``cut`` as it is now: on
the whole loop's cuts of six tools (1 440 cuts of truths 450–489, probit fits with this module's w = 0.05,
``benchmarks/label_fit.py``) the labels' whole offset, δ and the growth term below together, was 0.010–0.032 (each
±0.007–0.011); the growth term takes 0.002–0.02 of it at those tools' growth rates and cut lengths. The default
until then, μ = s = 0.035, came from the detector of 2026-11-26, which heard chatter 7 % above the SDM limit at
EM28-80's pocket (now 1–2 %). The cuts cannot tell δ from the limit, so its prior carries to the band
(``docs/design/shop.md``, *The label offset refitted*). Labels by ear or by another detector may be heard later:
give their offset (``label_offset``; the old default is the cautious guess).
Chatter must also have *grown* to be heard, and just past the limit it grows slowly: e^{κ ln(a/a_lim) t} over a cut
of t seconds, κ = Re ∂s/∂ln a the growth rate of the sample's limiting lobe
(:func:`~toolpoint.shop.model.growth_rate`, ≈ ζω_n of the chattering mode). So each cut's boundary moves up by a
further min(G / (κ t), 0.5), G the ln of the growth the shop needs to hear chatter — a second parameter of the
posterior (column P + 1), with prior ln G ~ N(ln 2.5, 0.5²); it took EM12-60's recommended depth from above the true
limit for 24 % of 20 truths (1–6 cuts, mean) to 8 %, at the price of a wider band (``docs/design/shop.md``). On a
campaign tool whose chatter at the productive speeds is a 750 Hz mode with ζ ≈ 0.4 % (EM12-60: κ ≈ 25–40 /s) this is
7–12 % for a 0.9 s cut; on a well-damped mode (κ ≈ 500 /s) 0.5 %.
w (default 0.05) the relative width of the fuzzy boundary (a cut 5 % below the limit is stable with probability Φ(1) =
0.84: the limit of a real cut is not a sharp line). `cut`'s labels turn from stable to chatter more sharply, within w ≤
0.02 of their boundary on six tools (``benchmarks/label_fit.py``, w free): w = 0.03 converged within six cuts more often
(EM16-50 on 36 of 60 truths 490–549, against 24 of 60 with 0.05) and put the recommended depth above the
truth more often (EM12-60 after 20 of 240 updates, where it claims 5 %: in part a label `cut` missed far past the limit
weighing more, in part lobes over-confident away from the cuts), so it is an option, not the default
(``docs/design/shop.md``, *The boundary width from the labels*). ε (default 0.002) the probability that a label is
simply wrong, whatever the distance to the limit. ε sets how tight a bracket of cuts can make the band: the samples
outside a bracket [stable a_s, chatter a_c] keep a weight ε against ~1 inside, so with a bracket holding 15 % of the
prior's mass ε = 0.02 left ~10 % of the posterior outside it and the 5–95 % band could not close without more cuts
(measured: ``docs/design/shop.md``). Labels that are wrong *near* the limit (a detector, a forward model that is not the
shop's) belong in w, not in ε. A detector that misses chatter (a microphone at a pocket speed, where a resonant
tooth-passing harmonic hides it) is ``miss_rate`` m: P(label stable) = p_s + m p_c, P(label chatter) = (1 − m) p_c (off
by default: measured in ``docs/design/shop.md``).
A chattering cut with a measured
chatter frequency f adds

    p(f | θ) = (1 − ε_f) N(d; 0, (σ_f f)²) + ε_f / f,   d = min_j |f − (f_c(θ, n) + j N n/60)|, j = −2…2,

f_c the frequency of the limiting lobe at n (a detector may report an alias f_c + j f_t), σ_f = 2 %.
A chattering cut whose record shows how fast its chatter grew, σ_m (1/s, :mod:`toolpoint.shop.growth`), also says
how far past the limit it was: just past it σ = κ ln(a/a_lim), so x_m = σ_m / (b κ(θ)) is read against the sample's
x = ln(a/a_lim) (``growth_error``; :data:`GROWTH_ERROR`). Its error grows with x_m and adds to the boundary width w:
the label bounds the limit from above, the rate from below too.
A stable cut whose record shows its ring — how fast the line it rings at decays, σ_m < 0 (the cutting noise drives the
closed loop's least damped mode: :func:`toolpoint.shop.growth.ring_decay`) — says the cut was at least as close under
the limit as the x where the SDM's decay ln ρ(a_SDM e^x) / T first reaches σ_m: that mode decays no faster than any line
the record holds. A sample that puts the cut further below is penalised, one that puts it closer is not
(``ring_error``; :data:`RING_ERROR`; one ring per speed): the label bounds the limit from below, the ring from above.
In a noisy shop — one whose stable cuts' records ring at the tool's modes (:func:`noisy_shop`) — a stable cut near
its limit may be heard as chatter: its mode, driven by the cutting noise, rings at the chatter frequency. A chatter
label without a growth reading then has P(label chatter) = p_c + π Φ((u + r)/s) p_s (``precursor``;
:data:`PRECURSOR`), u = ln(a / a_lim): one-sided, the stable labels keep p_s, so the term acts through the chatter
labels only — it lets the band rise above them (its lower side rises too, by the mass it lets above). Such a shop also
hears chatter *late* at a pocket's top, where the tooth-passing harmonic rings the mode and its forced line hides a
chatter the noise spreads into a hump: there each cut's labels' boundary lies a further ν h above the limit,
h = ln(a_lim / a_min) the cut's height in its pocket over the lobes' floor (``noisy_pocket``; :data:`NOISY_POCKET`),
and the next cut takes no step above the stable cuts (below): their labels may be chatter unheard.

The posterior is sampled by sequential Monte Carlo (Chopin 2002; Del Moral, Doucet & Jasra 2006): prior
samples are tempered, L^β with β from 0 to 1 in steps that keep the effective sample size at half the
samples, resampled (systematic), and moved by random-walk Metropolis steps in the prior's standard-normal
coordinates with the particles' covariance (scale 2.38/√d, adapted to the acceptance). ``method="sir"``
is plain sampling–importance resampling from the prior, kept to measure against: see
``docs/design/shop.md``.

Lobes: the posterior samples' zero-order limits on a speed grid (:func:`~toolpoint.stability.zoa_batch.zoa_limits`),
corrected by the semi-discretisation (``forward="sdm"``, the default: a machine's cuts follow the SDM), their
5/50/95 % lines (the outer two read further out where the few references' SDM/ZOA ratios the lobes rest on
spread: :func:`_band_levels`) and P(stable): the share of samples whose limit exceeds a depth, moved toward 0.5
as those lines were (:func:`_p_chatter_map`).

Recommended point: the speed that maximises n · a₀₅(n) (removal rate at a fixed feed per tooth and width)
at the depth a₀₅ (P(stable) = 0.95); with ``forward="sdm"`` the depth is lowered to the own SDM 5 % limit, at
that speed, of posterior samples other than the lobe samples where that is lower (``update``) — each weighted by
the cuts within 0.4 % of that speed, with its own limit there (:func:`_recommended_own`). **Next test
cut**, two rules:

* ``"info"`` (default): the cut that most reduces the expected log width ln(a₉₅/a₀₅) of the limit at
  the recommended speed, among cuts at the most productive speeds (the 6 best by n · a₅₀ and the
  recommended one; ``next_speeds`` 0: the recommended one alone) and depths with P(chatter) ≤ ``risk``
  (default 0.3): for each candidate the posterior after "stable" and after "chatter" is the current samples
  reweighted by the cut's likelihood, and the expected
  width is P(stable) W_stable + P(chatter) W_chatter (+ ``chatter_cost`` × P(chatter), default 0). The
  log width, not (a₉₅ − a₀₅)/a₅₀: dividing by the median made a chatter outcome (lower median) look wider
  than it is and pushed the rule to creep up from below. Above a stable cut a_s the risk bound alone creeps
  too: the posterior piles up just above a_s (the prior's density falls there when the truth is above its
  median), its ``risk`` quantile is a few % higher, and each stable cut lifts the band by that much (measured:
  9 stable cuts from 2.50 to 3.39 mm before the chatter that closed the band). So until the first chatter, above
  the highest stable cut a_s within ±``creep_span`` (2 %) of a speed — each cut moved to it by the posterior
  median's ratio between the two speeds, since the rule wanders over neighbouring grid speeds — a step of
  e^min_step × a_s is also a candidate where the risk bound stops short of it, whatever its P(chatter) (the
  proposal says ``stepped``): the bracket has no upper side yet, cuts closer than the boundary's own width tell
  little, and a chatter one step of 2 w up is a bracket of ratio 1.105, which leaves a 5–95 % width of about 0.2.
  After the first chatter the risk bound alone narrows the bracket. ``min_step`` 0.1 by default (0: never). In the
  whole loop (``docs/design/shop.md``, 2026-11-29, 20 truths a case, 6 cuts) this rule took EM28-80 (one lightly damped
  mode) from 9 to 13 of 20 truths within 6 cuts (chattering median 1 both), EM12-60 from 5 to 6 and the Cornelius
  case from 14 to 15 (noise-free; 9 to 10 with 5 % cutting noise, chattering median 1.5 → 2), for 126 chattering
  cuts of 480 against 105 and the recommended depth above the truth after 0.031 of the updates against 0.021
  (claimed: 0.05); the rule before
  (``step_until_chatter=False``, ``creep_span=0.005``: a step only once the two highest stable cuts at a speed,
  ±0.5 %, crept closer than e^min_step) missed the creep over neighbouring speeds and lost a cut to each creep.
  A candidate whose heard outcome an earlier cut at its speed already gave (no deeper than a stable one, no
  shallower than a chattering one) is not proposed (``skip_repeats``);
* ``"risk"``: the most productive cut (max n · a) whose P(chatter) ≤ ``risk`` (default 0.1) — the depth
  a_risk(n), the ``risk`` quantile of the limit.

Either rule also says how long the cut should last (``next_cut["duration_s"]``, ``["revolutions"]``): as long as
the cuts so far (their median; ``cut_duration_s`` before the first), the duration its expected outcome assumes.
``audible_margin`` > 0 lengthens it where chatter grows slowly, so that chatter that far past the limit grows by
e^G̃ within the cut, t = G̃ / (margin · κ₂₅), κ₂₅ the lower quartile of the lobe samples' growth rates at its speed:
a lightly damped mode between its pockets (κ ≈ ζω_n ≈ 25 /s) asks for about 2 s at 0.05, a well-damped one or a
pocket's peak (κ ≈ 400–1000 /s) no more than the cuts already made; the time domain hears chatter 5 % past the
limit in such a cut and not in a 0.9 s one (``tests/shop/test_shop_update.py``). The default margin, 0.025, asks for
3–4 s on such a mode and leaves a well-damped tool's cuts as they are (``update``'s ``audible_margin``).
"""

from __future__ import annotations

import math
import os
import re
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from scipy.special import log_ndtr, logsumexp, ndtr, ndtri

from ..errors import InputError
from ..stability.zoa_batch import zoa_limits
from .model import ModalPrior, floor_limit, growth_rate, limit_at_speeds, receptance, sdm_limits

__all__ = ["DEFAULT_RISK", "GROWTH_ERROR", "NOISY_POCKET", "PRECURSOR", "RING_ERROR", "TestCut", "Posterior",
           "read_test_cuts", "check_consistent", "log_likelihood", "noisy_shop", "pocket_height", "update"]


_RPM_AGREE = 0.005
"""A record's spindle speed (``cut``'s, from its harmonics) further than this from its row's rpm moves the cut there:
a spindle at load runs within tenths of a percent of its command, an override or a slipping belt further."""

DEFAULT_RISK = {"info": 0.3, "risk": 0.1}
"""The default bound on the next cut's P(chatter) of each next-cut rule (module docstring)."""

GROWTH_ERROR = (1.0, 0.35, 0.7, 0.05)
"""A measured chatter growth against the zero-order κ ln(a / a_lim): (bias b, relative sd above, below, outlier share).
On simulated Cornelius-case cuts the readings were 0.89–0.91× the SDM's rate at the median (microphones and a
housing accelerometer; ln sd 0.2–0.3) and κ x 0.90× (ln sd 0.18): b = 1, s₊ ≈ √(0.25² + 0.18²). Fast rises read low
(0.52–0.80× at 60 % past the limit), so a reading below the prediction has the wider error (``docs/design/shop.md``, *A
chattering cut's growth rate*). With ``forward="sdm"`` the model's part of s₊ (κ x's 0.18) is the SDM growth curves'
instead, whose references' spread is added on top; s₊ is kept, on the side of a wider band."""


RING_ERROR = (0.4, 0.05)
"""A stable cut's ring (``TestCut.ring_per_s``) against the SDM's decay f_t ln ρ at its depth: (ln sd on the slow side,
outlier share). On pocket records of two tools with 5 % cutting-force noise (Cornelius truths 40–43, EM28-80 truths
40–43; 0.6–0.98 × the limit, resolved readings of stable verdicts, 138 records) ln(|σ_m| / |σ_SDM|) had its 5 %
quantile at −0.37 and its 10 % at −0.24: a reading can be slower than the SDM's decay by that much. Faster it often is
(a more damped line than the least damped mode, the reading's floor of 15–25 /s near the limit), and that side is not
used (:func:`log_likelihood`'s ``ring_x``). The reading's own ln sd is added in quadrature. 0.4, not the 0.25 the
records suggest: in the whole loop (Cornelius truths 20–29, 5 % noise) 0.25 with every stable cut's ring left the
band's coverage after 6 cuts at 0.73 against 0.86 without the rings — one wrong label near a band the rings had
narrowed broke it —, 0.4 with one ring per speed (``_sdm_ring_x``) at 0.86 (``docs/design/shop.md``, *A stable cut's
ring in update*)."""


@dataclass(frozen=True)
class TestCut:
    """One test cut: speed (rpm), depth (m), stable or not, measured chatter frequency (Hz) if any, how long
    the tool cut (s; None: not known, :func:`update`'s ``cut_duration_s``), what the analysis of its record
    could not rule out (``warnings``: :func:`toolpoint.shop.analyse_cut`'s, e.g. chatter on a mains harmonic) and
    the record (``record``: the table's file name, with its part ``(start–end s)`` where the row names one), and
    how fast a chattering cut's chatter grew (``growth_per_s``, σ in 1/s: :mod:`toolpoint.shop.growth`; None: not
    read); a stable cut's ring (``ring_per_s`` σ ≤ 0, 1/s, at ``ring_hz``, with ``ring_ln_sd`` the reading's own
    ln sd: :func:`toolpoint.shop.growth.ring_decay`; None: not read)."""

    __test__ = False  # a shop's test cut, not a pytest test class

    rpm: float
    depth_m: float
    stable: bool
    chatter_hz: float | None = None
    line: int | None = None
    source: str | None = None
    duration_s: float | None = None
    warnings: tuple = ()
    record: str | None = None
    growth_per_s: float | None = None
    ring_per_s: float | None = None
    ring_hz: float | None = None
    ring_ln_sd: float | None = None


# a spreadsheet's names for the test-cut table's columns (after ``_column_name``'s folding): name → the table's own
_COLUMN_ALIASES = {
    "rpm": tuple(f"{n}_{u}" for n in ("rpm", "speed", "spindle_speed", "spindle", "n", "s")
                 for u in ("rpm", "1/min", "min^_1", "min_1", "u/min")),
    "depth_mm": ("depth_mm_mm", "ap_mm", "a_p_mm", "axial_depth_mm", "depth_of_cut_mm", "doc_mm", "b_mm"),
    "result": ("verdict", "label", "outcome"),
    "chatter_hz": ("chatter_hz_hz", "chatter_frequency_hz", "chatter_freq_hz", "f_chatter_hz", "f_c_hz"),
    "duration_s": ("duration_s_s", "cut_duration_s", "cutting_time_s"),
}
_ALIAS = {a: name for name, aliases in _COLUMN_ALIASES.items() for a in aliases}
_DEPTH_NAMES = ("depth", "ap", "a_p", "axial_depth", "depth_of_cut", "doc")


def _column_name(header: str, path) -> str:
    """The test-cut table's name for a column header: lower case, blanks as ``_``, a unit in brackets or parentheses
    as a suffix (``"Depth [mm]"`` → ``"depth_mm"``, ``"Speed (rpm)"`` → ``"rpm"``); a depth in another unit than mm
    is refused (:class:`InputError` naming the column), not converted by guess.

    >>> _column_name("Depth [mm]", "t.csv"), _column_name("Spindle speed (rpm)", "t.csv"), _column_name("RESULT", "")
    ('depth_mm', 'rpm', 'result')
    """
    h = header.strip().lower().replace("µ", "u").replace("μ", "u")
    m = re.fullmatch(r"(.*?)\s*[\[(]\s*([^\])]*?)\s*[\])]", h)
    if m:
        h = f"{m.group(1)}_{m.group(2).replace(' ', '')}"
    h = re.sub(r"[\s\-]+", "_", h.strip())
    h = _ALIAS.get(h, h)
    base, _, unit = h.rpartition("_")
    if base in _DEPTH_NAMES and unit in ("um", "m", "in", "inch", "cm", "mil", "thou"):
        raise InputError(f"column {header.strip()!r} gives the depth in {unit}: give it in mm (depth_mm)", file=path,
                         field="depth_mm")
    return h


def _on_tooth_passing(f_hz: float, rpm: float, teeth: int) -> bool:
    """Whether ``f_hz`` lies on a tooth-passing harmonic k N rpm / 60 (k ≥ 1), within max(3 Hz, 0.3 %)."""
    f_t = teeth * rpm / 60.0
    k = round(f_hz / f_t)
    return k >= 1 and abs(f_hz - k * f_t) <= max(3.0, 0.003 * f_hz)


def read_test_cuts(path: str | os.PathLike, *, teeth: int | None = None, cut_options: dict | None = None) -> list:
    """Read a test-cut table: CSV ``rpm, depth_mm, result`` (stable|chatter), optional ``chatter_hz``,
    ``duration_s`` (how long the tool cut, s), ``growth_per_s`` (how fast a chattering cut's chatter grew, 1/s:
    :mod:`toolpoint.shop.growth`), ``ring_per_s`` and ``ring_hz`` (a stable cut's ring: how fast its line at
    ``ring_hz`` decays, σ < 0 in 1/s, :func:`toolpoint.shop.growth.ring_decay`), ``record``, ``start_s`` and
    ``end_s``; column names in any case, a unit in brackets read as the name's suffix and a spreadsheet's usual names
    taken for the table's (``Spindle speed [rpm]`` is ``rpm``, ``Depth (mm)`` or ``ap [mm]`` is ``depth_mm``,
    ``Verdict`` is ``result``, ``Chatter [Hz]`` is ``chatter_hz``: ``_COLUMN_ALIASES``; a depth in another unit is
    refused),
    cells split at commas or (a spreadsheet's export with the decimal comma) semicolons
    (:func:`toolpoint.io.table.read_rows`).

    A ``record`` (path relative to the table) is analysed by :func:`toolpoint.shop.analyse_cut` (needs
    ``teeth``): it gives ``result``, ``chatter_hz``, ``growth_per_s`` and a stable cut's ring (where resolved) where
    the table leaves them empty, and
    ``duration_s`` (its longest run of entry, cut and exit); where both are given and disagree the table is refused (a
    contradiction is reported, not averaged). The record's spindle speed (from its harmonics) places the cut where it
    differs from the row's ``rpm`` by more than 0.5 % (said in the cut's warnings: an override, a slipping belt). A
    record whose tooth passing stands out at a speed beyond ``cut``'s search range (±3 %) and whose "chatter" is a
    tooth-passing harmonic of that speed, or whose spindle is not heard at the row's speed, is refused, naming both
    speeds, unless the row's ``result`` confirms the record's reading: judged at a speed it did not run at, its own
    tooth passing reads as chatter (simulated records given ±10 %: 398 of the 412 wrong verdicts on a microphone,
    308 of 325 on a housing accelerometer), and heavy chatter at the right speed makes such a comb on an
    accelerometer (48 of 576 records; 0 of 576 on a microphone). ``start_s`` and ``end_s`` (s from
    the record's start; either may be
    empty: its start, its end) name the part of the record that holds the row's cut, as ``toolpoint cut --start
    --end`` does: a shop that records a session of cuts in one file gives each cut its own row and part. What the
    analysis cannot rule out (chatter on a mains harmonic in a record without an air cut) stays with the cut
    (``TestCut.warnings``) and reaches the report.

    Raises
    ------
    InputError
        Naming the file, the line and the field.
    """
    from ..io.table import csv_unsafe, read_table

    p = Path(path)
    header, rows = read_table(p, what="the test-cut table")
    # "RPM", "Depth [mm]", "Result" as a spreadsheet writes them: the names are matched without case, a unit in
    # brackets is read as the name's suffix, and a depth in another unit is refused rather than guessed
    names = {h: _column_name(h, p) for h in header}
    seen: dict = {}
    for h in header:
        n = names[h]
        if n and n in seen:  # one value per cut: a second column of the same name would silently win
            raise InputError(f"columns {seen[n]!r} and {h!r} both give {n}", file=p, field=n)
        seen[n] = h
    header = [names[h] for h in header]
    rows = [(line, {(names[k] if isinstance(k, str) else k): v for k, v in row.items()}) for line, row in rows]
    for need in ("rpm", "depth_mm"):
        if need not in header:
            raise InputError(f"missing column {need!r} (columns: {', '.join(header) or 'none'})", file=p, field=need)
    if "result" not in header and "record" not in header:
        raise InputError("needs a column 'result' (stable|chatter) or 'record'", file=p, field="result")
    cuts, records = [], {}
    for line, row in rows:
        def num(name, *, required=True, lo=0.0, at_lo=False):
            v = (row.get(name) or "").strip()
            if not v:
                if required:
                    raise InputError(f"line {line}: empty", file=p, field=name)
                return None
            try:
                x = float(v)
            except ValueError:
                raise InputError(f"line {line}: {v!r} is not a number", file=p, field=name) from None
            if not (math.isfinite(x) and (x >= lo if at_lo else x > lo)):
                raise InputError(f"line {line}: must be a finite number {'≥' if at_lo else '>'} {lo:g}, got {v}",
                                 file=p, field=name)
            return x
        rpm, depth = num("rpm"), num("depth_mm")
        if rpm > 200_000:
            raise InputError(f"line {line}: {rpm:g} rpm is not a spindle speed", file=p, field="rpm")
        if depth > 1000:
            raise InputError(f"line {line}: {depth:g} mm is not a depth of cut", file=p, field="depth_mm")
        fc = num("chatter_hz", required=False)
        dur = num("duration_s", required=False)
        grow = num("growth_per_s", required=False)
        if grow is not None and grow > 1e4:
            raise InputError(f"line {line}: {grow:g} /s is not a chatter's growth rate (e^σt: σ ≲ 1000 /s)", file=p,
                             field="growth_per_s")
        if dur is not None and dur > 3600:
            raise InputError(f"line {line}: {dur:g} s is not a test cut's duration", file=p, field="duration_s")
        # a stable cut's ring: σ ≤ 0 (1/s) is how fast the line decays, so the table gives it as a negative number
        ring = num("ring_per_s", required=False, lo=-1e4)
        ring_hz = num("ring_hz", required=False)
        if ring is not None and ring >= 0:
            raise InputError(f"line {line}: a ring decays, so its rate σ is negative (1/s), got {ring:g}", file=p,
                             field="ring_per_s")
        if (ring is None) != (ring_hz is None):
            raise InputError(f"line {line}: a ring needs both its rate and its frequency", file=p,
                             field="ring_hz" if ring is not None else "ring_per_s")
        ring_sd = None
        res = (row.get("result") or "").strip().lower()
        if res and res not in ("stable", "chatter"):
            raise InputError(f"line {line}: must be 'stable' or 'chatter', got {res!r}", file=p, field="result")
        rec = csv_unsafe((row.get("record") or "").strip())  # "'-take1.wav" as `cut --table` writes it
        t0, t1 = num("start_s", required=False, at_lo=True), num("end_s", required=False)
        if (t0 is not None or t1 is not None) and not rec:
            raise InputError(f"line {line}: a part of a record needs the record", file=p,
                             field="start_s" if t0 is not None else "end_s")
        if t0 is not None and t1 is not None and t1 <= t0:
            raise InputError(f"line {line}: must be after start_s ({t0:g} s), got {t1:g} s", file=p, field="end_s")
        span = None if t0 is None and t1 is None else (t0 or 0.0, math.inf if t1 is None else t1)
        what = rec if span is None else (f"{rec} ({t0:g}–{t1:g} s)" if t0 is not None and t1 is not None
                                         else f"{rec} (from {t0:g} s)" if t0 is not None else f"{rec} (to {t1:g} s)")
        warns = ()
        if rec:
            if teeth is None:
                raise InputError(f"line {line}: a record needs the number of teeth", file=p, field="record")
            from ..io.records import read_cut_record
            from .detect import analyse_cut

            rp = (p.parent / rec) if not Path(rec).is_absolute() else Path(rec)
            if rp not in records:  # a session's record, one row per cut in it, is read once (and warned of once)
                records[rp] = read_cut_record(rp)
                warns += tuple(f"{rec}: {w}" for w in records[rp].warnings)
            r = records[rp]
            if span is not None and span[0] >= r.duration_s:
                raise InputError(f"line {line}: {span[0]:g} s is after the end of its record {rec} "
                                 f"({r.duration_s:.4g} s)", file=p, field="start_s")
            try:
                a = analyse_cut(r.samples, r.rate_hz, rpm=rpm, teeth=teeth, full_scale=r.full_scale, source=str(rp),
                                span_s=span, **(cut_options or {}))
            except InputError as e:  # a record `cut` will not judge (its spindle not heard, clipped, too short …)
                # `cut`'s advice in the table's words: a row's part of a record is its start_s and end_s
                why = (f"{e.field}: " if e.field else "") + re.sub(
                    r"its own --rpm and --start/--end \(that cut with its air: ([^)]*)\)",
                    r"its own row (rpm; start_s, end_s: that cut with its air is \1)", e.message)
                if not res:
                    raise InputError(f"line {line}: its record {what} was not judged: {why}", file=p,
                                     field="record") from None
                a = None  # the table's own label stands, and the user hears why the record did not count
                warns += (f"its record {what} was not judged ({why}); the table's '{res}' stands",)
        if rec and a is not None:
            ran = a.criterion.get("speed_elsewhere_rpm")
            on_ran = a.chatter_hz is not None and ran is not None and _on_tooth_passing(a.chatter_hz, ran, a.teeth)
            if ran is not None and not res and (on_ran or not a.criterion.get("spindle_heard", True)):
                # judged at a speed it did not run at, its own tooth passing is the "chatter" (a stable record at 6000
                # rpm given as 6600: "chatter at 400 Hz", 36 dB out) and the cut sits at the wrong speed in the lobes.
                # Heavy chatter at the right speed can look the same on a housing accelerometer (48 of 576 simulated
                # records; none of 576 on a microphone): the row's own result confirms the record's reading
                why = (f"its 'chatter' at {a.chatter_hz:.1f} Hz is a tooth-passing harmonic of {ran:.0f} rpm" if on_ran
                       else f"no spindle harmonics stand out at {rpm:g} rpm")
                raise InputError(f"line {line}: its record {what} ran at {ran:.0f} rpm by its tooth-passing harmonics "
                                 f"({100 * (ran / rpm - 1):+.1f} % from the table's {rpm:g} rpm), and {why}: put the "
                                 f"speed the spindle ran at in rpm (an override?); if it did run at {rpm:g} rpm (heavy "
                                 "chatter makes such a comb), confirm the record's reading in the row's result",
                                 file=p, field="rpm")
            if abs(a.rpm / rpm - 1) > _RPM_AGREE:
                # within cut's search range but not the speed typed: the cut happened at the speed the record ran at
                warns += (f"{what}: the spindle ran at {a.rpm:.0f} rpm, {100 * (a.rpm / rpm - 1):+.1f} % from the "
                          f"table's {rpm:g} rpm (by its harmonics): the cut is placed at {a.rpm:.0f} rpm",)
                rpm = float(a.rpm)
            if res and res != a.verdict:
                # what `cut` doubted of the record may be the contradiction's cause (a wrong tooth count makes the
                # cutter's own tooth harmonics "chatter"): the refusal says it, so `cut` need not be run to find it
                doubts = a.criterion.get("warnings", ())
                raise InputError(f"line {line}: the table says {res}, its record {what} says {a.verdict}"
                                 + (f" at {a.chatter_hz:.1f} Hz" if a.chatter_hz else "")
                                 + ("".join(f"; {what}: {w}" for w in doubts)), file=p, field="result")
            res = a.verdict
            if fc is None and a.chatter_hz is not None:
                fc = a.chatter_hz
            if grow is None and a.growth is not None and a.growth.rate_per_s is not None:
                grow = a.growth.rate_per_s
            if dur is None:
                dur = _cutting_s(a)
            if ring is None:
                ring, ring_hz, ring_sd = ring_fields(a).values()
            warns += tuple(f"{what}: {w}" for w in a.criterion.get("warnings", ()))
            if len({v for *_, v, _ in a.cuts}) > 1:  # a row is one cut; its record holds cuts that disagree
                warns += (f"{what}: the {'record' if span is None else 'part'} holds {len(a.cuts)} cuts ("
                          + "; ".join(f"{ta:.1f}–{tb:.1f} s {v}" for ta, tb, v, _ in a.cuts)
                          + f"): the row takes the record's verdict, {a.verdict}; give each cut its own row, and "
                          "its part of the record in start_s and end_s",)
        if not res:
            raise InputError(f"line {line}: empty (and no record)", file=p, field="result")
        if res == "stable" and fc is not None:
            raise InputError(f"line {line}: a stable cut has no chatter frequency", file=p, field="chatter_hz")
        if res == "stable" and grow is not None:
            raise InputError(f"line {line}: a stable cut has no chatter growth", file=p, field="growth_per_s")
        if res == "chatter" and ring is not None:
            raise InputError(f"line {line}: a ring is a stable cut's (a chatter's line does not decay)", file=p,
                             field="ring_per_s")
        cuts.append(TestCut(rpm, depth * 1e-3, res == "stable", fc, line, str(p), dur, warns, what if rec else None,
                            grow, ring, ring_hz, ring_sd))
    if not cuts:
        raise InputError("no test cuts", file=p, field="rpm")
    check_consistent(cuts, source=str(p))
    return cuts


def ring_fields(analysis) -> dict:
    """A stable verdict's ring as :class:`TestCut`'s ``ring_per_s``, ``ring_hz`` and ``ring_ln_sd`` (None each
    where :func:`toolpoint.shop.analyse_cut` read none; an unresolved line: as narrow as a steady tone, it says no
    rate; or a line that dies away over the cut — the entry's kick, not a ring the cutting noise sustains
    (:attr:`~toolpoint.shop.growth.RingDecay.sustained`): its rate, read as a stationary line's, is not its decay,
    and it says nothing of the shop's noise (:func:`noisy_shop`); or a "line" less than
    :data:`~toolpoint.shop.growth.RING_MIN_PEAK_DB` over its floor — a bump of the record's noise)."""
    from .growth import RING_MIN_PEAK_DB

    rg = analysis.ring
    ok = (analysis.verdict == "stable" and rg is not None and rg.rate_per_s is not None and rg.resolved
          and rg.freq_hz is not None and rg.sustained is not False
          and (rg.peak_to_floor is None or rg.peak_to_floor >= 10 ** (RING_MIN_PEAK_DB / 10)))
    return {"ring_per_s": rg.rate_per_s if ok else None, "ring_hz": rg.freq_hz if ok else None,
            "ring_ln_sd": rg.ln_sd if ok else None}


def _cutting_s(analysis) -> float | None:
    """The longest of a record's cuts (entry, cut, exit: chatter grows within one cut), s."""
    return max((b - a for a, b, *_ in analysis.cuts), default=None) or None


def check_consistent(cuts, *, rpm_rel: float = 0.005, depth_rel: float = 0.05, source: str | None = None) -> None:
    """Refuse labels that contradict each other: at one speed (±``rpm_rel``), a stable cut deeper than a
    chattering one by more than ``depth_rel`` (more than the fuzzy boundary explains), or the same cut both ways.

    Raises
    ------
    InputError
        Naming the two lines (field ``result``).
    """
    for i, a in enumerate(cuts):
        for b in cuts[i + 1:]:
            if abs(a.rpm / b.rpm - 1) > rpm_rel or a.stable == b.stable:
                continue
            s, c = (a, b) if a.stable else (b, a)
            if s.depth_m >= c.depth_m * (1 + depth_rel) or (s.depth_m == c.depth_m):
                raise InputError(f"lines {s.line} and {c.line} contradict each other: stable at "
                                 f"{1e3 * s.depth_m:g} mm but chatter at {1e3 * c.depth_m:g} mm "
                                 f"({s.rpm:g} / {c.rpm:g} rpm); check the labels", file=source, field="result")


BOUNDARY_WIDTH = 0.05
"""``update``'s default boundary width w (ln): how far from the limit a cut's label is uncertain (module docstring;
``docs/design/shop.md``, *The boundary width from the labels*)."""

LABEL_OFFSET = (0.01, 0.02)
"""``update``'s default prior of the label offset δ, (mean, sd) in ln: where ``cut``'s labels lie above the limit,
besides the growth term (module docstring; ``docs/design/shop.md``, *The label offset refitted*)."""

NOISY_POCKET = 0.025
"""A noisy shop's late chatter at a pocket's top, ν: where the cutting force's noise drives the tool's modes
(:func:`noisy_shop`), each cut's labels' boundary moves up by a further ν h, h = ln(a_lim / a_min) the cut's height in
its pocket over the lobes' floor (:func:`pocket_height`), and the ``"info"`` rule proposes no step above the stable
cuts. At a pocket's top the tooth-passing harmonic sits on the mode; its forced line stands 20–30 dB over chatter that
has just saturated, and the noise spreads that chatter into a hump that `cut` reads as a ring. With 5 % force noise
EM28-80 (its pocket 75× its floor, h ≈ 4.3) heard chatter 10–20 % past the limit there (28 of 97 stable labels more than
5 % past it, the chatter labels at a median 1.157 ×), the two-mode case (2.6×, h ≈ 1) within 2.3 %: ν ≈ 0.1 / 4.3. Set
from EM28-80's truths 390–409, checked on fresh truths and the other tools (``docs/design/shop.md``, *A noisy shop's
pocket*)."""

PRECURSOR = (0.5, 0.1, 0.08)
"""A noisy shop's false chatter (π, r, s): where the cutting force's noise drives the tool's modes, a stable cut near
its limit rings at the chatter frequency and may be heard as chatter — P(chatter heard | stable, u) = π Φ((u + r)/s),
u = ln(a / a_lim) ≤ 0 — unless the record shows the chatter grew (a ring does not). Read from the labels of `cut` on
pocket records with 5 % force noise (Cornelius truths 40–43 at each truth's pocket speeds, 24 records per depth):
chatter heard on 0 / 1 / 6 / 11 / 12 of 24 stable records at 0.6 / 0.8 / 0.9 / 0.95 / 0.98 × the SDM limit (a
maximum-likelihood fit gives π ≈ 0.7, r 0.08, s 0.09; −ln L 50.9 against 51.7 for these rounder values). Judged by
`cut` with its hump rule the same records are heard 0 / 1 / 2 / 7 / 7 times, four new truths' 0 / 0 / 1 / 7 / 14; a
refit to those (π 0.8, r 0.02, s 0.08) and a rate by the ring's decay were no better in the whole loop. Off the
pocket it over-states: 1 of 48 records heard at 0.85–0.975 × on two tools at 20276 rpm, where it expects 14
(``docs/design/shop.md``, *A noisy shop's false chatter*). :func:`update` applies it only where the stable cuts' own
records say the shop is noisy (:func:`noisy_shop`)."""

POCKET_SPEEDS = 5
"""Speeds over ±3 % of the recommended speed at which the lobe samples' own SDM limits replace the references' ratio
(``update``'s ``own_pocket``)."""

SDM_TRAIN = 200
"""Posterior samples whose own SDM limits at the cut speeds train ``update``'s per-sample SDM/ZOA ratio (its
``sdm_train``; :class:`_RatioFit`) before the third sampling."""

OWN_NEAR = dict(log_step=0.07, max_steps=15, bisections=0)
"""The search options of the samples' own SDM limits (:func:`~toolpoint.stability.sdm_limit_near_many`; the training
of the per-sample ratio, the lobe samples' own limits at the cuts and in the pocket, the recommended depth's and the
first cut's checks): steps of 0.07 in ln a from the guess until the verdict changes, then ρ interpolated linearly
across that bracket — no halvings. Why: the own limits enter a likelihood whose boundary is 0.05 wide in ln a, and
these searches were half of an update's CPU. Against the full upward search (``sdm_limits``) on 120 of EM16-50 truth
21's posterior samples at its three cut speeds, from guesses ln sd 0.12 (0.05) off: ln error sd 0.0020 (0.0022),
max 0.028, 1.02 s (0.78 s) CPU, where steps of 0.2 and two halvings gave sd 0.0015 (0.0101: one step over a thin
unstable band, 0.19), 1.30 s (1.28 s); 2026-12-02, ``docs/design/shop.md`` (*The own searches without halvings*)."""

OWN_MIN_ESS = 0.25
"""The least effective share of the lobe samples the own-SDM weights may leave (``update``'s ``own_sdm``): below it
the weights are tempered (:func:`_own_temper`), so the 5 % and 95 % quantiles of 400 samples rest on at least five
effective samples each (where that many samples have a non-zero weight)."""


def noisy_shop(cuts) -> int | None:
    """The first stable cut whose record rings (its ring read to an ln sd ≤ 0.5: :func:`toolpoint.shop.growth.
    ring_decay`), or None: the evidence that the cutting noise drives the tool's modes, so that a stable cut near its
    limit may be heard as chatter (:data:`PRECURSOR`). A quiet cut's record holds the entry's decaying kick at most,
    which reads loosely (ln sd 1.3–2.2 on noise-free Cornelius records, 0.14–0.32 with 5 % force noise) — but not
    always: 2 of 24 noise-free EM12-60 records at 0.8–0.95 × the limit had a kick read at ln sd 0.36 or with none,
    and an EM16-50 whole-loop cut a bump of the room noise read at 0.47. So a record's ring reaches the cuts only
    where it rings through the cut and stands 10 dB over the record's noise (:func:`ring_fields`): 44 of 45 rings of
    5 % force-noise two-mode case records did, none of those kicks nor that bump (5.4 dB over its floor;
    ``docs/design/shop.md``, *An entry's kick, or a bump of the noise, is no
    ring*)."""
    return next((r for r, c in enumerate(cuts) if _ring_readable(c)), None)


def log_likelihood(prior: ModalPrior, theta, cuts, *, boundary_width: float = BOUNDARY_WIDTH,
                   label_noise: float = 0.002, freq_sigma: float = 0.02, freq_outlier: float = 0.05,
                   freq_hz=None, log_ratio=None, miss_rate: float = 0.0, label_offset=0.0, label_growth=0.0,
                   cut_duration_s: float = 1.0, growth_error=None, growth_x=None, ring_x=None,
                   ring_outlier: float = RING_ERROR[1], precursor=None, kappa=None,
                   kappa_log_ratio=None, noisy_pocket=None) -> np.ndarray:
    """ln p(cuts | θ) for each row of θ (see the module docstring); shape (S,).

    ``log_ratio`` (per cut, optional): ln of a factor on the zero-order limit at the cut's speed (the SDM
    correction of :func:`update`'s ``forward="sdm"``); ``boundary_width`` may be one value per cut.
    ``miss_rate``: probability that a chattering cut is labelled stable (a detector's missed chatter), on top
    of ε: P(label stable) = p_s + m p_c, P(label chatter) = (1 − m) p_c. ``label_offset`` δ (scalar or one per
    sample, (S,)): the labels' boundary is a_lim e^δ — chatter is heard only δ (ln) above the limit.
    ``label_growth`` G (scalar or (S,)): the boundary moves up by a further min(G / (κ t), 0.5) per cut, κ the
    sample's chatter growth rate at the cut (:func:`~toolpoint.shop.model.growth_rate`), t the cut's
    ``duration_s`` (else ``cut_duration_s``): chatter is heard once it has grown by e^G; ``kappa_log_ratio`` (C,)
    multiplies κ by e^r, or (Q, C) by each of Q references' e^r (:func:`update`'s ``growth_by="sdm"``: the SDM's
    growth at the references), the labels' likelihood then the mean over the references of each one's product over
    the cuts; ``kappa`` (S, C) replaces κ where finite (each sample's own SDM growth). ``growth_error`` (b, s₊,
    s₋, o), None to leave it out: each chattering cut's measured growth σ_m (``TestCut.growth_per_s``) as a distance
    past the limit, x_m = σ_m / (b κ) (κ the sample's :func:`~toolpoint.shop.model.growth_rate`), against the
    sample's x = ln(a / a_lim) (a_lim with ``log_ratio``'s correction): x_m − x split-normal with sd
    √((s₊ x_m)² + w²) above and √((s₋ x_m)² + w²) below (w the boundary width), a share o of readings anywhere in
    a 100× range of σ (:func:`update`'s ``growth_error``); not at a cut whose ``log_ratio`` exceeds 0.1 in size
    (the SDM's limiting lobe may be another than the zero-order's, whose κ this is). ``growth_x`` (x_m, sd), each
    (C,), nan where a cut's reading is not used: the distances past the limit the readings say by the SDM's own
    growth (``_sdm_growth_x``), used instead of σ_m / (b κ) and the 10 % rule; its sd (the references' spread)
    is added to the error in quadrature, and the outliers are uniform over x_m ∈ [0, 1.5]. ``ring_x`` (x_r, sd), each
    (C,), nan where a cut has none, in 1/s (κ x): how close under the limit a stable cut's ring says it was at least
    (``_sdm_ring_x``), x_r = S_r / κ for each sample (κ its :func:`~toolpoint.shop.model.growth_rate`): the least damped
    mode decays no faster than any line the record holds, so only a sample that puts the cut further below the limit
    than x_r is penalised, by a half-normal of sd √((sd / κ)² + w²); a share
    ``ring_outlier`` of readings says nothing (the penalty's floor). The ring lowers the band's upper side, never
    lifts it. ``precursor`` (π, r, s), None to leave it out: a stable cut u = ln(a / a_lim) from the limit is heard as
    chatter with a further probability π Φ((u + r)/s) (:data:`PRECURSOR`) — P(label chatter) = p_c + π h p_s —
    except a chattering cut whose growth was read (a ring does not grow). One-sided: P(label stable) stays p_s (not
    (1 − π h) p_s), so a stable label says no more than in a quiet shop; the band's lower side still rises by the
    mass the softened chatter labels let above them. ``noisy_pocket`` ν, None to leave it out: each cut's labels'
    boundary moves up by a further ν h, h = ln(a_lim / a_min) ≥ 0 the cut's height in its pocket over the sample's
    zero-order floor (:func:`~toolpoint.shop.model.floor_limit`; a_lim with ``log_ratio``'s correction): a noisy
    shop hears chatter late at a pocket's top (:data:`NOISY_POCKET`)."""
    rpm = np.array([c.rpm for c in cuts])
    depth = np.array([c.depth_m for c in cuts])
    stable = np.array([c.stable for c in cuts])
    a_lim, f_c, *floor = limit_at_speeds(prior, theta, rpm, freq_hz, floor=noisy_pocket is not None)
    # one factor per cut (C,), or per sample and cut (S, C): each sample's own SDM limit (update's own_sdm)
    lr = np.zeros((1, len(cuts))) if log_ratio is None else np.atleast_2d(np.asarray(log_ratio, float))
    # kappa_log_ratio (Q, C): the labels' likelihood a mixture over Q references' growth, one axis more (S, Q, C)
    g = np.reshape(np.asarray(label_growth, float), (-1, 1))
    mix = kappa_log_ratio is not None and np.ndim(kappa_log_ratio) == 2 and np.any(g > 0)
    ex = (lambda v: v[:, None, :]) if mix else (lambda v: v)  # noqa: E731
    offset = np.reshape(np.asarray(label_offset, float), (-1, 1, 1) if mix else (-1, 1))
    if np.any(g > 0):
        dur = np.array([cut_duration_s if c.duration_s is None else c.duration_s for c in cuts], float)
        offset = offset + growth_offset(prior, theta, rpm, f_c, g, dur, kappa, kappa_log_ratio)
    if noisy_pocket is not None:  # a noisy shop hears chatter late at a pocket's top: ν h further up
        offset = offset + ex(float(noisy_pocket) * pocket_height(prior, theta, a_lim * np.exp(lr), floor_m=floor[0]))
    with np.errstate(divide="ignore"):
        x = (ex(np.log(a_lim) + lr) + offset - np.log(depth)[None, :]) / np.asarray(boundary_width, float)
    x = np.where(np.isfinite(x), x, 50.0)  # no lobe reaches the speed: stable at any depth in the grid
    eps = label_noise
    ls = np.logaddexp(np.log(eps), np.log1p(-2 * eps) + log_ndtr(x))  # ln P(stable)
    lc = np.logaddexp(np.log(eps), np.log1p(-2 * eps) + log_ndtr(-x))  # ln P(chatter)
    if miss_rate > 0:  # a chattering cut heard as stable
        ls = np.logaddexp(ls, math.log(miss_rate) + lc)
        lc = lc + math.log1p(-miss_rate)
    if precursor is not None:  # a noisy shop: a stable cut near its limit heard as chatter (its mode's ring)
        pi, reach, spread = (float(v) for v in precursor)
        with np.errstate(divide="ignore", invalid="ignore"):
            u = np.log(depth)[None, :] - np.log(a_lim) - lr
        u = ex(np.where(np.isfinite(u), u, -np.inf))  # no lobe reaches the speed: stable, and no ring to hear
        lh = math.log(pi) + log_ndtr((u + reach) / spread)  # ln(π h)
        on = np.array([_rate(c) is None for c in cuts])[None, :]  # a growth read: chatter that grew, not a ring
        # one-sided: a chatter label says less, a stable label no more than in a quiet shop — with its factor
        # (1 − π h) a stable cut near the limit lifted the band's lower side over truth 25's limit (Cornelius, 5 %
        # noise, recommended depth above the truth after 4 and 6 cuts): π varies from shop to shop, and a wrong
        # one may not lift the recommended depth
        lc = np.where(on, np.logaddexp(lc, ls + lh), lc)
    ll = np.where(stable[None, :], ls, lc).sum(axis=-1)
    if mix:  # one reference's growth for all of a sample's cuts, the references equally likely
        ll = logsumexp(ll, axis=1) - math.log(ll.shape[1])
    N = prior.cutting.teeth
    for r, c in enumerate(cuts):
        if c.stable or c.chatter_hz is None:
            continue
        ft = N * c.rpm / 60.0
        alias = f_c[:, r, None] + ft * np.arange(-2, 3)[None, :]
        d = np.nanmin(np.abs(c.chatter_hz - alias), axis=1) if np.any(np.isfinite(f_c[:, r])) else \
            np.full(f_c.shape[0], np.inf)
        d = np.where(np.isfinite(d), d, np.inf)
        sd = freq_sigma * c.chatter_hz
        gauss = -0.5 * (d / sd) ** 2 - math.log(sd * math.sqrt(2 * math.pi))
        inlier = math.log(1 - freq_outlier) if freq_outlier < 1 else -math.inf  # 1: the frequency says nothing
        ll = ll + np.logaddexp(inlier + gauss, math.log(freq_outlier / c.chatter_hz))
    if ring_x is not None:
        xr, xrsd = (np.asarray(v, float) for v in ring_x)
        idx = [r for r, c in enumerate(cuts) if c.stable and np.isfinite(xr[r])]
        if idx:
            w = np.broadcast_to(np.asarray(boundary_width, float), (len(cuts),))[idx][None, :]
            # the references' curves are their own: scaled to each sample's by its κ (its own damping: the
            # references' mean put a ring 0.21 under the limit at 0.12 on a Cornelius campaign, their κ steeper)
            kap = growth_rate(prior, theta, rpm[idx], f_c[:, idx])
            with np.errstate(divide="ignore", invalid="ignore"):
                x_s = np.log(depth[idx])[None, :] - np.log(a_lim[:, idx]) - lr[:, idx]  # ≤ 0 below the limit
                x_r, sd_r = xr[idx][None, :] / kap, xrsd[idx][None, :] / kap
                d = np.maximum(x_r - x_s, 0.0) / np.sqrt(sd_r ** 2 + w ** 2)
            # no lobe reaches the speed, or no growth at the sample's lobe: the floor alone
            g = np.where(np.isfinite(d) & (kap > 0), -0.5 * d * d, -np.inf)
            ll = ll + np.logaddexp(math.log1p(-ring_outlier) + g, math.log(ring_outlier)).sum(axis=1)
    if growth_error is not None and growth_x is not None:
        # the readings as distances past the limit by the SDM's own growth curves (the references'): x_m the same for
        # every sample, so no Jacobian; the references' spread joins the reading's error
        xg, xsd = (np.asarray(v, float) for v in growth_x)
        idx = [r for r, c in enumerate(cuts) if _rate(c) and np.isfinite(xg[r])]
        if idx:
            _, s_hi, s_lo, out = (float(v) for v in growth_error)
            xm, ref_sd = xg[idx][None, :], xsd[idx][None, :]
            w = np.broadcast_to(np.asarray(boundary_width, float), (len(cuts),))[idx][None, :]
            r = xm - (np.log(depth[idx])[None, :] - np.log(a_lim[:, idx]) - lr[:, idx])
            sd_hi = np.sqrt((s_hi * xm) ** 2 + w ** 2 + ref_sd ** 2)
            sd_lo = np.sqrt((s_lo * xm) ** 2 + w ** 2 + ref_sd ** 2)
            with np.errstate(invalid="ignore"):
                sd = np.where(r > 0, sd_hi, sd_lo)
                g = -0.5 * (r / sd) ** 2 + np.log(2.0 / (math.sqrt(2 * math.pi) * (sd_hi + sd_lo)))
            g = np.where(np.isfinite(g), g, -np.inf)  # no lobe reaches the speed: the outliers' share alone
            # outliers: uniform over the x a 100× range of σ spans on the curve, taken as [0, 1.5] (ln)
            ll = ll + np.logaddexp(math.log1p(-out) + g, math.log(out / 1.5)).sum(axis=1)
        return ll
    # without the SDM's growth curves (forward="zoa", or a caller's log_ratio): where the SDM's limit lies more than
    # 10 % from the zero-order's, its limiting lobe may be another (a flip lobe, a pocket): the zero-order lobe's κ
    # does not describe the chatter heard, and the rate is left out (EM12-60: κ x against the SDM's rate 0.07–1.6
    # there, 0.89–1.07 within it but for one 1.96; docs/design/shop.md)
    idx = [r for r, c in enumerate(cuts) if _rate(c) and np.all(np.abs(lr[:, r]) <= _GROWTH_LR_MAX)] \
        if growth_error is not None else []
    if idx:
        # the reading as a distance past the limit, x_m = σ_m / (b κ), against the sample's x = ln(a / a_lim):
        # its error grows with x_m (the reading's, s₊ / s₋) on top of the boundary width w (the limit's own model
        # error: a reading cannot place the limit closer than the model knows where it is); b κ the Jacobian
        b, s_hi, s_lo, out = (float(v) for v in growth_error)
        sig = np.array([cuts[k].growth_per_s for k in idx], float)[None, :]
        kap = growth_rate(prior, theta, rpm[idx], f_c[:, idx])
        w = np.broadcast_to(np.asarray(boundary_width, float), (len(cuts),))[idx][None, :]
        with np.errstate(divide="ignore", invalid="ignore"):
            xm = sig / (b * kap)
            r = xm - (np.log(depth[idx])[None, :] - np.log(a_lim[:, idx]) - lr[:, idx])
            sd_hi, sd_lo = np.hypot(s_hi * xm, w), np.hypot(s_lo * xm, w)
            sd = np.where(r > 0, sd_hi, sd_lo)
            g = -0.5 * (r / sd) ** 2 + np.log(2.0 / (math.sqrt(2 * math.pi) * (sd_hi + sd_lo) * b * kap))
        # no growth at the sample's lobe (κ ≤ 0, no lobe reaching the speed): the outliers' share alone
        g = np.where((kap > 0) & np.isfinite(g), g, -np.inf)
        ll = ll + np.logaddexp(math.log1p(-out) + g, np.log(out / (math.log(100.0) * sig))).sum(axis=1)
    return ll


def _rate(cut) -> float | None:
    """A chattering cut's measured growth rate σ_m (1/s) where it can enter the likelihood: finite and > 0 (the
    table's reader refuses others; a :class:`TestCut` made in code is not checked)."""
    g = cut.growth_per_s
    return float(g) if not cut.stable and g is not None and math.isfinite(g) and g > 0 else None


_RING_HZ_REL = 0.1  # a ring more than 10 % from the references' chatter frequency (and its aliases) is not read
_RING_LN_SD_MAX = 0.5  # nor one read to worse than this ln sd (as `cut` calls a line a ring: detect._rings)

_GROWTH_HZ_REL = 0.03  # a reference's growing line more than this (relative) from the heard one does not read it
_GROWTH_LR_MAX = 0.1  # |ln(a_SDM / a_ZOA)| at a cut beyond which its growth rate is not read (log_likelihood)
_GROWTH_CAP = 0.5  # ln: a chatter that cannot grow audibly within the cut leaves the label uninformative, not wild


def pocket_height(prior: ModalPrior, theta, limit_m, freq_hz=None, *, floor_m=None) -> np.ndarray:
    """h = ln(a_lim / a_min) ≥ 0 of each sample's limits ``limit_m`` (S, ·), m, over its zero-order floor a_min
    (``floor_m`` (S,), else :func:`~toolpoint.shop.model.floor_limit` on ``freq_hz``): how high in its pocket a cut
    lies (0 on the lobes' floor; 4.3 at the top of EM28-80's pocket, 75× its floor). 0 where the limit is not finite
    (no lobe reaches the speed)."""
    a_min = floor_limit(prior, theta, freq_hz) if floor_m is None else np.asarray(floor_m, float)
    with np.errstate(divide="ignore", invalid="ignore"):
        h = np.log(np.asarray(limit_m, float)) - np.log(a_min)[:, None]
    return np.where(np.isfinite(h), np.maximum(h, 0.0), 0.0)


def growth_offset(prior: ModalPrior, theta, rpm, chatter_hz, growth, duration_s, kappa=None,
                  kappa_log_ratio=None) -> np.ndarray:
    """min(G / (κ t), 0.5): how far (ln) above the limit a chatter that must grow by e^G within t seconds is heard,
    κ the growth rate (:func:`~toolpoint.shop.model.growth_rate`) of each sample (S, R) times e^``kappa_log_ratio``
    where that is finite — (R,), or (Q, R) for Q references' SDM/ZOA growth ratios (:func:`_sdm_kappa_log_ratio`),
    then the result is (S, Q, R) — or ``kappa`` (S, R) where that is finite (the sample's own SDM growth); 0.5 where
    κ ≤ 0, 0 where no lobe reaches the speed (the sample is stable there anyway)."""
    kap = growth_rate(prior, theta, rpm, chatter_hz)
    fin = np.isfinite(np.asarray(chatter_hz, float))
    mix = kappa_log_ratio is not None and np.ndim(kappa_log_ratio) == 2
    if kappa_log_ratio is not None:
        klr = np.asarray(kappa_log_ratio, float)
        klr = np.exp(np.where(np.isfinite(klr), klr, 0.0))
        kap = kap[:, None, :] * klr[None] if mix else kap * klr[None, :]
    if kappa is not None:
        kappa = np.asarray(kappa, float)
        kappa = kappa[:, None, :] if mix else kappa
        kap = np.where(np.isfinite(kappa), kappa, kap)
    g_shape, t_shape = ((-1, 1, 1), (1, 1, -1)) if mix else ((-1, 1), (1, -1))
    with np.errstate(divide="ignore", invalid="ignore"):
        d = np.reshape(growth, g_shape) / (kap * np.reshape(duration_s, t_shape))
    d = np.where(kap > 0, np.minimum(d, _GROWTH_CAP), _GROWTH_CAP)
    return np.where(fin[:, None, :] if mix else fin, d, 0.0)


@dataclass(frozen=True)
class Posterior:
    """Result of :func:`update` (SI inside: depths m, frequencies Hz, K_t N/m²).

    Attributes
    ----------
    prior : ModalPrior
    cuts : tuple of TestCut
    method : str
        ``"smc"`` or ``"sir"``.
    z : ndarray, shape (S, P + 2)
        Equally weighted posterior samples in the prior's standard-normal coordinates; column P: the label
        offset's (δ = μ + s z, ``update``'s ``label_offset``), column P + 1: the label growth's
        (G = G̃ e^{s_G z}, ``label_growth``).
    ess : tuple of float
        Effective sample sizes at each tempering step (SIR: the one).
    acceptance : float
        Mean Metropolis acceptance (SMC; nan for SIR).
    rpm : ndarray, shape (G,)
    limit_q_m : ndarray, shape (3, G)
        5/50/95 % lines of the limit: the lobe samples' median, and their quantiles at ``band_levels``, so that a
        limit drawn from the posterior falls under the first (over the last) 5 % of the time although the band
        rests on a few references' SDM/ZOA ratios (:func:`_band_levels`; ``update``'s ``band_noise``).
    depth_m : ndarray, shape (D,)
    p_stable : ndarray, shape (D, G)
        P(stable) at each depth and speed: the lobe samples' share above the depth, moved toward 0.5 as the band's
        lines are widened (:func:`_p_chatter_claimed`, :func:`_p_chatter_map`), so that it is 0.95 on the band's 5 %
        line (the share itself where the levels are 0.05/0.95 and the depth lies among the samples).
    prior_limit_q_m : ndarray, shape (3, G)
        The prior's quantiles, for comparison.
    recommended : dict
        ``rpm``, ``depth_m`` (the 5 % limit), ``p_stable``.
    next_cut : dict
        ``rule``, ``risk``, ``rpm``, ``depth_m``, ``p_chatter``, ``duration_s`` and ``revolutions`` (how long it
        should last: :func:`update`'s ``audible_margin``), ``duration_by_growth`` (lengthened where chatter grows
        slowly), ``growth_rate_p25_per_s`` (κ₂₅ there, 1/s; None without the margin).
    cpu_s : float
        CPU time of the update.
    label_offset : (float, float)
        Prior mean and standard deviation of the label offset δ (ln; :func:`update`).
    label_growth : (float, float)
        Prior median and log standard deviation of the label growth G (ln of the amplitude; :func:`update`).
    forward : str
        The forward model, ``"sdm"`` or ``"zoa"``.
    growth_past_limit : tuple of (float or None)
        Per cut: how far past the limit (ln) its measured growth rate said it was, read from the SDM's growth curves
        (``forward="sdm"``); None where no rate entered that way (a stable cut, no rate, ``growth_error`` None,
        ``forward="zoa"`` — where κ x is per sample —, or a rate the references' curves do not bracket).
    ring_under_limit : tuple of (float or None)
        Per cut: how close under the limit (ln, ≤ 0) a stable cut's ring said it was at least, read from the SDM's
        decay curves (``forward="sdm"``, :func:`update`'s ``ring_error``); None where no ring entered.
    precursor : (float, float, float) or None
        The noisy shop's false chatter (π, r, s; ln) the likelihood used (:data:`PRECURSOR`); None where it
        was left out (``update``'s ``precursor`` None, or no stable cut's record rang: a quiet shop).
    noisy_evidence : int or None
        Index of the stable cut whose ring said the shop is noisy (:func:`noisy_shop`).
    own_sdm_ess : float or None
        Effective sample size of the lobe samples' weights by their own SDM limits at the cut speeds
        (:func:`update`'s ``own_sdm``), of ``lobe_samples``, as resampled (after tempering); None where they were
        not weighted, 0 where no weight was finite (the lobe samples left unweighted).
    own_sdm_power : float or None
        The power α ∈ (0, 1] those weights were raised to: 1 where they left at least :data:`OWN_MIN_ESS` of the
        lobe samples effective, else the largest α that does (the band then lies between the references' and the
        own limits'), or ~1e-9 where none does (fewer samples than that of non-zero weight); None where they were
        not weighted.
    lobe_z : ndarray, shape (m, P + 2), optional
        The lobe samples (rows of ``z``, as ``z``'s columns), resampled by those weights where they were weighted
        (rows repeat): the samples whose limits make ``limit_q_m``.
    own_pocket_rpm : tuple of float
        The speeds (rpm) at which the lobe samples' own SDM limits replaced the references' ratio near the most
        productive speed (:func:`update`'s ``own_pocket``); empty where none did.
    band_levels : ndarray, shape (2, G), optional
        The quantile levels of the lobe samples that ``limit_q_m``'s first and last lines are, per speed: 0.05 and
        0.95 where the references do not spread (or ``band_noise`` is off), further out where they do.
    lobe_limit_m : ndarray, shape (m, G), optional
        The lobe samples' limits at each speed, m: what ``limit_q_m`` and ``p_stable`` are read from
        (:meth:`p_chatter` reads the map at any depth).
    noisy_pocket : float or None
        The noisy shop's late chatter at a pocket's top (ν, :data:`NOISY_POCKET`) the likelihood used; None where it
        was left out (``update``'s ``noisy_pocket`` None or 0, or a quiet shop).
    """

    prior: ModalPrior
    cuts: tuple
    method: str
    z: np.ndarray
    ess: tuple
    acceptance: float
    rpm: np.ndarray
    limit_q_m: np.ndarray
    depth_m: np.ndarray
    p_stable: np.ndarray
    prior_limit_q_m: np.ndarray
    recommended: dict
    next_cut: dict
    cpu_s: float
    label_offset: tuple = (0.0, 0.0)
    label_growth: tuple = (0.0, 0.0)
    forward: str = "sdm"
    growth_past_limit: tuple = ()
    ring_under_limit: tuple = ()
    precursor: tuple | None = None
    noisy_evidence: int | None = None
    own_sdm_ess: float | None = None
    lobe_z: np.ndarray | None = None
    own_sdm_power: float | None = None
    own_pocket_rpm: tuple = ()
    band_levels: np.ndarray | None = None
    lobe_limit_m: np.ndarray | None = None
    noisy_pocket: float | None = None

    def p_chatter(self, depth_m) -> np.ndarray:
        """P(chatter) that the map claims at ``depth_m`` (m) at each of the speeds ``rpm``: 1 − ``p_stable`` read at
        any depth rather than the map's grid (:func:`_p_chatter_map`).

        Parameters
        ----------
        depth_m : float or array_like, shape (G,) or (D, G)
            One depth at every speed, a depth per speed, or D depths per speed, m.

        Returns
        -------
        ndarray, shape (G,) or (D, G)
            The probability that the limit at that speed lies at or under the depth.

        Examples
        --------
        >>> import numpy as np
        >>> from toolpoint.shop.model import cornelius_2024
        >>> from toolpoint.shop.update import update
        >>> prior = cornelius_2024()
        >>> post = update(prior, [], rng=np.random.default_rng(0), n_samples=200, lobe_samples=100,
        ...               forward="zoa")
        >>> p = post.p_chatter(post.limit_q_m[0])  # on the band's 5 % line
        >>> bool(np.all(np.abs(p - 0.05) < 0.02))
        True
        """
        if self.lobe_limit_m is None:
            raise ValueError("this posterior keeps no lobe samples' limits (lobe_limit_m)")
        d = np.asarray(depth_m, float)
        one = d.ndim <= 1
        d = np.broadcast_to(d, (1, self.rpm.size) if one else (d.shape[0], self.rpm.size))
        p = np.where(np.isfinite(d), _p_chatter_map(self.lobe_limit_m, d, self.levels), np.nan)  # no depth: no claim
        return p[0] if one else p

    @property
    def levels(self) -> np.ndarray:
        """The quantile levels (2, G) the band's 5 % and 95 % lines were read at: ``band_levels``, or 0.05 / 0.95 at
        every speed where there are none."""
        if self.band_levels is not None:
            return self.band_levels
        return np.array([[0.05], [0.95]]) * np.ones((1, self.rpm.size))

    @property
    def theta(self) -> np.ndarray:
        """Posterior samples of the parameters (S, P), SI."""
        return self.prior.theta(self.z[:, :self.prior.sigma.size])

    @property
    def parameter_samples(self) -> np.ndarray:
        """The posterior samples of the parameters (S, P), SI, that :meth:`parameter_quantiles` reads: the lobe
        samples where they were weighted by their own SDM limits (``own_sdm_ess``; the posterior the lobes are made
        of), else ``theta``."""
        return self.prior.theta(self._posterior_z[:, :self.prior.sigma.size])

    @property
    def _posterior_z(self) -> np.ndarray:
        """The samples' coordinates (S, P + 2) the parameters' and the label model's quantiles read: the lobe samples'
        where they were weighted by their own SDM limits, else ``z``."""
        return self.lobe_z if self.own_sdm_ess is not None else self.z

    def parameter_quantiles(self) -> dict:
        """name → (prior 5/50/95 %, posterior 5/50/95 %) of each parameter (SI), the posterior's of
        :attr:`parameter_samples`."""
        zq = np.array([-1.6448536269514729, 0.0, 1.6448536269514729])
        prior_q = np.exp(self.prior.log_median[None, :] + zq[:, None] * self.prior.sigma[None, :])
        P = self.prior.sigma.size
        z = self._posterior_z
        post_q = np.quantile(self.parameter_samples, [0.05, 0.5, 0.95], axis=0)
        out = {n: (tuple(prior_q[:, k]), tuple(post_q[:, k])) for k, n in enumerate(self.prior.names)}
        mu, sd = self.label_offset
        off = mu + sd * z[:, P]
        out["label_offset_ln"] = (tuple(mu + zq * sd), tuple(np.quantile(off, [0.05, 0.5, 0.95])))
        gm, gs = self.label_growth
        if gm > 0:
            g = gm * np.exp(gs * z[:, P + 1])
            out["label_growth_ln"] = (tuple(gm * np.exp(zq * gs)), tuple(np.quantile(g, [0.05, 0.5, 0.95])))
        return out


def _systematic(w, rng):
    n = w.size
    u = (rng.random() + np.arange(n)) / n
    return np.minimum(np.searchsorted(np.cumsum(w), u), n - 1)


def _ess(logw):
    w = np.exp(logw - logw.max())
    return float(w.sum() ** 2 / np.sum(w * w))


def update(prior: ModalPrior, cuts, *, rng: np.random.Generator, n_samples: int = 1000, method: str = "smc",
           rpm_grid=None, n_moves: int = 3, boundary_width: float = BOUNDARY_WIDTH, label_noise: float = 0.002,
           freq_sigma: float = 0.02, freq_outlier: float = 0.05, rule: str = "info", risk: float | None = None,
           lobe_samples: int = 400,
           n_depths: int = 60, chatter_cost: float = 0.0, forward: str = "sdm", sdm_refs: int = 4,
           min_step: float | None = None, sdm_train: int = SDM_TRAIN, sdm_train_model: str = "quadratic",
           miss_rate: float = 0.0,
           label_offset: tuple = LABEL_OFFSET, label_growth: tuple = (2.5, 0.5),
           cut_duration_s: float = 1.0, risk_after_chatter: float | None = None,
           skip_repeats: bool = True, step_until_chatter: bool | str = True, creep_span: float = 0.02,
           audible_margin: float = 0.025, max_cut_duration_s: float = 5.0,
           growth_error: tuple | None = GROWTH_ERROR, ring_error: tuple | None = RING_ERROR,
           precursor: tuple | None = PRECURSOR, own_sdm: bool = True, growth_by: str = "zoa",
           own_pocket: int = POCKET_SPEEDS, band_noise: bool = True,
           noisy_pocket: float | None = NOISY_POCKET, cut_speed_margin: float = 0.0,
           next_speeds: int = 6) -> Posterior:
    """Posterior of the tool's modal parameters and K_t from test cuts; lobes, P(stable), the next cut.

    Parameters
    ----------
    prior : ModalPrior
    cuts : sequence of TestCut
        May be empty (then the prior's lobes and first cut).
    rng : numpy.random.Generator
        Seeds everything stochastic.
    n_samples : int, default 1000
        Particles.
    method : {"smc", "sir"}
    rpm_grid : array_like, optional
        Speeds of the lobes, rpm (default: 200 speeds over the lobes k = 0…4 of the prior's modes).
    n_moves : int, default 3
        Metropolis moves per tempering step.
    boundary_width, label_noise, freq_sigma, freq_outlier
        The likelihood's w, ε, σ_f and ε_f (the share of chatter frequencies read anywhere; 1: the frequency says
        nothing). w (ln, default ``BOUNDARY_WIDTH`` = 0.05, in (0, 0.5]) is how sharply the labels turn at the limit
        (module docstring: 0.03 converges faster, and is less safe on EM12-60). Measured (2026-11-30;
        ``docs/design/shop.md``, *Tried, not adopted: a sharper chatter-frequency term*): 26 of 32 chattering cuts'
        frequencies on EM12-60 and on EM16-50 lay within 0.5 % of the zero-order limiting lobe's or an alias, 5 and 4
        more than 2 % off (the SDM's chatter on another mode; ``benchmarks/bench_shop.py --only heard``); in EM12-60's
        whole loop σ_f = 0.005 with ε_f = 0.25 converged no more often than the defaults.
    rule : {"info", "risk"}, default "info"
        How the next test cut is chosen (module docstring).
    risk : float, optional
        Largest P(chatter) of the next test cut (default 0.3 for ``"info"``, 0.1 for ``"risk"``).
    lobe_samples : int, default 400
        Posterior samples whose lobes are computed.
    n_depths : int, default 60
        Depths of the P(stable) map.
    chatter_cost : float, default 0
        ``"info"`` rule: added to the expected log width per unit P(chatter) (0: only the ``risk`` bound).
    forward : {"sdm", "zoa"}, default "sdm"
        ``"zoa"``: the zero-order limit alone — cheaper, and biased against a machine's cuts where the ZOA is
        (low radial immersion, the flip lobes at low speeds); the whole-loop figures of ``docs/design/shop.md``
        were all measured with ``"sdm"``, the default since 2026-11-28 (*The default forward model* there says
        what ``"zoa"`` gives in that loop). ``"sdm"``: after the zero-order posterior, the semi-discretisation
        limit of ``sdm_refs`` posterior samples at the cut speeds and on the lobe grid gives ln(a_SDM / a_ZOA);
        the posterior is sampled again
        with the zero-order limit times the references' mean ratio at each cut speed (their spread added to
        the boundary width), and each lobe sample is multiplied by one reference's ratio. For cuts that
        follow the SDM (time domain, a real machine) where the ZOA is biased (low radial immersion). Without
        cuts the prior's lobes are corrected by ``sdm_refs`` prior samples' ratios, and the first cut's
        P(chatter) is that of the lobe samples' own SDM limits at its speed (its depth lowered to the bound where
        they put it above: the references' estimate claimed 0.28 where 0.34–0.37 chattered). The recommended
        depth is the lower of the band's 5 % limit and the own SDM 5 % limit at its speed of up to
        ``lobe_samples`` posterior samples that are not the lobe samples, its P(stable) theirs
        (``recommended["limit_p05_m"]``, ``["own_sdm_p05_m"]``): the speed is where the lobe samples' estimate
        is most productive, so likely too high there (on the example tool's prior 0.138 of truths lay below the
        band's 5 % limit, 0.046 below the checked depth). Where fewer than 100 samples are left beyond the lobe
        samples (``n_samples`` < ``lobe_samples`` + 100) the lobe samples check it, which the choice did see
        (0.081 there); ``recommended["own_sdm_held_out"]`` says which. Limits: ``docs/design/shop.md``.
    sdm_refs : int, default 4
        Reference samples of ``forward="sdm"`` (each costs one SDM lobe computation on the grid).
    miss_rate : float, default 0
        Probability that a chattering cut is labelled stable (a detector's missed chatter; module docstring):
        a stable label then never rules out a limit below it by more than ε + m. The risk of the next cut stays
        the cut's own P(chatter).
    sdm_train : int, default :data:`SDM_TRAIN`
        ``forward="sdm"`` with cuts: samples of the corrected posterior whose own SDM limits at the cut speeds
        (:func:`~toolpoint.stability.sdm_limit_near`) replace the references' ratio there before a third
        sampling — each sample's own ratio from a fit to theirs, or their mean (``sdm_train_model``), with the
        fit's residual or their spread added to the boundary width; the lobe samples' ratio is moved to their
        mean within a few % of the cut speeds (0: the references only). The references come
        from the zero-order posterior, which moved its parameters to explain the cuts; their ratio at the
        cut speeds was measured 0.1–0.2 (ln) off the corrected samples' own. With their mean alone
        (``sdm_train_model="mean"``) 60 brought the median limit at the cut speeds closer to the SDM's but did not
        make campaigns converge more often, at 3–6 s more per update (``docs/design/shop.md``). With each sample's
        own ratio (the quadratic fit, the default since 2026-12-02) the recommended depth on EM12-60's fresh truths
        120–139 lay above the truth after 5 of 120 updates against 11 with ``sdm_train=0``, where it claims 5 %
        (*Each sample's own SDM ratio in the sampling* there), for about 1.5–4 s more CPU per update (one search of
        200 samples at the cut speeds, a third sampling; EM16-50 after 6 cuts: 21.1 s against 18.0 s with the
        searches of :data:`OWN_NEAR`, beside two other processes). 0: the references only (as before 2026-12-02).
    sdm_train_model : {"quadratic", "mean"}, default "quadratic"
        With ``sdm_train`` > 0, how the training samples' own ratios enter the third sampling. ``"mean"``: their
        mean at each cut speed, their spread added to the boundary width (as measured above, with the full
        search). ``"quadratic"``: each sample's own ratio from a least-squares fit quadratic in its prior
        coordinates (:class:`_RatioFit`; the searches as :data:`OWN_NEAR`), the fit's residual sd added to the
        width — the sampling then sees each sample's own limit at the cut speeds, not one mean for all.
    label_offset : (float, float), default :data:`LABEL_OFFSET` (0.01, 0.02)
        Mean and standard deviation of δ, ln of how far above the stability limit the shop first *hears* chatter:
        the labels' boundary is a_lim e^δ, one δ for all the cuts (a parameter of the posterior, column ``P`` of
        ``z``), while the lobes, P(stable), the recommended point and the next cut's P(chatter) are those of
        a_lim itself. The cuts cannot tell δ from the limit (both move the labels' boundary alike), so its
        prior carries to the band at the cut speeds. Measured on the whole loop's labels (``cut`` on the
        simulated shop's microphone) against each truth's SDM limit: the module docstring and
        ``benchmarks/label_fit.py``. (0, 0): the labels are the limit (a detector checked on this machine and
        tool); (0.035, 0.035), the default until 2026-12-07: labels heard later, by ear or another detector.
    label_growth : (float, float), default (2.5, 0.5)
        Median G̃ and log standard deviation s_G of G, the ln of how much chatter must grow within a cut to be heard (a
        parameter of the posterior, column ``P + 1`` of ``z``): each cut's labels' boundary moves up by a further min(G
        / (κ t), 0.5), κ the sample's chatter growth rate at the cut (:func:`~toolpoint.shop.model.growth_rate`, ≈ ζω_n
        of the chattering mode) and t the cut's duration. Just past the limit chatter grows slowly, e^{κ ln(a/a_lim) t}:
        on a lightly damped mode (κ ≈ 30 /s) a 1 s cut 10 % past the limit barely chatters, on a well-damped one (κ ≈
        500 /s) 1 % past it does. G̃ = 2.5 was fitted to the whole loop's labels on the campaign tool EM12-60 (60 cuts,
        truths 40–49: its cuts at the 750 Hz mode, κ ≈ 25–40 /s, were heard as chatter only 7–12 % above the SDM limit,
        those at its 2000 Hz mode, κ ≈ 900 /s, at 1–3 %; ``docs/design/shop.md``). (0, 0): off. κ is the zero-order
        lobe's: where the SDM's limiting lobe is another the offset is too small or too large there (a fifth of
        EM12-60's cuts grew less than 0.8× as fast as it says, one in twenty below 0.58×; a sixth more than 1.25×,
        one in twenty above 17×: ``benchmarks/bench_shop.py --only heard``).
    cut_duration_s : float, default 1.0
        Duration (s) of the cuts whose :class:`TestCut` does not state it, and of the next cut while no cut
        states one. Shorter is the safer guess (chatter had less time to grow, so a stable label says less).
    audible_margin : float, default 0.025
        The next cut's duration (``next_cut["duration_s"]``, what the rule's expected outcomes assume) is that of
        the cuts so far (their median, else ``cut_duration_s``). With ``audible_margin`` > 0 it is lengthened
        where chatter grows slowly: long enough that chatter ``audible_margin`` (ln) past the limit grows by e^G̃
        within it, t = G̃ / (κ₂₅ · audible_margin), κ₂₅ the lower quartile of the lobe samples' growth rates at
        its speed (:func:`~toolpoint.shop.model.growth_rate`), at most ``max_cut_duration_s``; the rule then
        weighs each candidate with the duration it would get. A short cut leaves chatter on a lightly damped mode
        unheard well past the limit, and its stable label says little (``label_growth``). Measured in the whole
        loop (EM12-60, truths 40–59, 6 cuts; ``docs/design/shop.md``, *The next cut's duration*): 0.05 narrowed
        the band at the recommended speed after 2–3 cuts (median 0.48 / 0.36 against 0.59 / 0.46) but not after
        6 (0.36 against 0.40; ≤ 0.25 for 2 truths against 6), heard more of the cuts past the limit as chatter
        (24 chattering cuts against 18) and converged for 0 truths against 3. Since the growth reading and the
        line-heard gate (2026-12-01, ``docs/design/shop.md``, *The lead measured on every case*), 0.025 converged
        within 6 cuts for 49 of 100 campaigns on EM12-60's truths 20–79 against 24 of 60 with 0, with a median of
        1 chattering cut (at most one in 59 of 100 against 46 of 60) and the recommended depth above the truth after
        4.2 % of the updates against 5.6 % (it claims 5 %); EM16-50's, EM28-80's and the two-mode case's cuts are
        not lengthened (the example tool's, three lightly damped modes, are). Those runs'
        shop cut a proposal as long as asked only where it was lengthened; cutting every proposal as long as asked
        (*The virtual shop cuts as long as proposed*; on the code before the ring's floor),
        37 of 60 converged within 6 cuts, 39 of 60 had at most one
        chattering cut, and the recommended depth lay above the truth after 2.2 % of the updates. 0 proposes the
        cuts' own length.
    max_cut_duration_s : float, default 5.0
        The longest next cut ``audible_margin`` proposes (s); it bounds the lengthening, not the length of the
        cuts already made.
    growth_error : (float, float, float, float) or None, default :data:`GROWTH_ERROR`
        How a chattering cut's measured growth rate σ_m (``TestCut.growth_per_s``, read from its record by
        :mod:`toolpoint.shop.growth`) enters: as a distance past the limit x_m = σ_m / (b κ) (κ the sample's
        :func:`~toolpoint.shop.model.growth_rate`) against the sample's ln(a / a_lim), split-normal with sd s₊ x_m
        above and s₋ x_m below, each with the boundary width added in quadrature (the limit's own model error), a
        share o of readings anywhere (:func:`log_likelihood`). The label bounds the limit from one side; the rate
        says how far past it the cut was. With ``forward="sdm"`` the rates enter once the SDM correction is known,
        and x_m is read from the SDM's own growth curves σ(x) = ln ρ(a_SDM e^x) / T at the references, not from
        the zero-order κ (``_sdm_growth_x``: at a pocket or a flip lobe another lobe limits and grows, and κ x
        was 0.04–2.2× the SDM's rate there); the references' spread joins the error. A reference whose growing line
        at the reading is not the cut's chatter frequency (folded by the tooth-passing frequency, 3 %) does not read
        it: its curve is another line's growth. None: the rates are not used.
    ring_error : (float, float) or None, default :data:`RING_ERROR`
        How a stable cut's ring (``TestCut.ring_per_s``: how fast the line it rings at decays,
        :func:`toolpoint.shop.growth.ring_decay`) enters, with ``forward="sdm"``: (ln sd of a reading slower than
        the SDM's decay, outlier share). The least damped mode decays no faster than the line read, so the SDM's
        decay curves at the references say how close under the limit the cut was at least, and a sample that puts
        it further below is penalised (``_sdm_ring_x``, :func:`log_likelihood`'s ``ring_x``): a stable cut near
        the limit then bounds the limit from above as well as from below. One-sided: a reading too fast (a more
        damped line, the reading's floor near the limit) says nothing, and the ring never lifts the band. None: not
        used.
    precursor : (float, float, float) or None, default :data:`PRECURSOR`
        A noisy shop's false chatter (π, r, s): once a stable cut's record rings (:func:`noisy_shop`: the cutting
        noise drives the tool's modes), each chatter label without a growth reading may be a stable cut up to
        about r under the limit, heard as chatter with probability π Φ((u + r)/s) (:func:`log_likelihood`): a
        chatter label then bounds the limit from above less tightly. In a quiet shop (no stable cut rings) it is
        left out. None: never (a shop whose chatter labels are checked, e.g. on the surface).
    noisy_pocket : float or None, default :data:`NOISY_POCKET`
        A noisy shop's late chatter at a pocket's top (ν): once a stable cut's record rings (as ``precursor``), each
        cut's labels' boundary lies a further ν h above the limit, h = ln(a_lim / a_min) its height in its pocket
        over the lobes' floor (:func:`pocket_height`): the tooth-passing harmonic that rings the mode there hides
        chatter that the noise spreads into a hump, which `cut` reads as a ring. The lobes, the recommended point and
        the next cut's P(chatter) stay those of a_lim, so a stable label high in a pocket lifts the band less; and the
        ``"info"`` rule proposes no step above the stable cuts (``min_step``), which rests on their labels whatever
        its P(chatter). In a quiet shop it is left out. None or 0: never (labels checked on the surface). Measured in
        the whole loop with 5 % cutting-force noise (``docs/design/shop.md``, *A noisy shop's pocket*).
    skip_repeats : bool, default True
        ``"info"`` rule: no candidate at the speed of an earlier cut (±0.5 %) that is no deeper than a stable cut there,
        or no shallower than a chattering one — the shop already knows how it ends. The likelihood takes each cut's
        fuzzy boundary (``boundary_width``) as independent of the others', so it counts such a repeat as news, and
        the rule used to propose it: in the whole loop 59 of 360 Cornelius cuts and 45 of 240 EM28-80 cuts
        (``update``'s defaults, truths 20–79 and 20–59) were such repeats (3 and 7 of them chattered: near the limit
        a label is not certain). Skipping them changed 7 of 60 Cornelius campaigns and 2 of 40 EM28-80 ones: within
        6 cuts 34 → 36 of 60 and 18 → 18 of 40, at most one chattering cut 30 → 30 and 37 → 38
        (``docs/design/shop.md``). Where every candidate repeats, the rule proposes as without it. False: as before
        2026-11-28. Counting the labels of cuts within 2 % of a speed once (their boundary's error shared) was
        tried twice and not kept: fewer campaigns converged (2026-12-01: EM16-50 10 → 8 of 20, EM12-60's held-out
        truths 11 → 6) for a band barely better calibrated (EM12-60's held out after 6 cuts: coverage 0.78 → 0.80,
        claims 0.90; ``docs/design/shop.md``, *Tried again and not kept: cuts near one speed share their boundary*).
    min_step : float, optional
        ``"info"`` rule: a cut e^min_step above the highest stable cut near a speed is a candidate even where it exceeds
        ``risk``, when the risk bound stops short of it — until the first chatter (``step_until_chatter``), or once two
        stable cuts crept closer than e^min_step (default 0.1 for ``"info"``, twice the default boundary width, 0.05;
        0: never; the ``"risk"`` rule has no step: module docstring).
    step_until_chatter : bool or "near", default True
        ``"info"`` rule: offer the step after any stable cut while no cut has chattered, and never after; False:
        only once the two highest stable cuts near a speed crept closer than e^min_step, chatter or not (the
        rule before 2026-11-29; ``docs/design/shop.md``). ``"near"``: while no cut within ±``creep_span`` of
        the speed has chattered — a chatter elsewhere gives that speed's bracket no upper side, and the stable
        cuts that follow it at a new recommended speed crept under the risk bound alone. It trades chattering
        cuts for convergence. In the whole loop (6 cuts) on the code of 2026-12-01, against the default:
        EM16-50 (truths 40–59) converged within 6 cuts for 12 of 20 against 10, a median of 1 chattering cut
        both; EM12-60's held-out truths 20–39 for 9 of 20 against 11, with a median of 2 chattering cuts against
        1 (at most one for 7 of 20 against 13); the two-mode case (10 truths) had at most one chattering cut
        for 6 of 10 (17 of 20 by default, on ``6e85d85``) and with 5 % force noise 1 of 10 (11 of 20)
        (``docs/design/shop.md``, *The step after a chatter elsewhere* and *`"near"` on EM12-60's held-out
        truths*). Not the default for that.
    creep_span : float, default 0.02
        ``"info"`` rule: the stable cuts within ±creep_span (relative speed) of a candidate speed count for its
        step, each depth moved to that speed by the posterior median's ratio between the two (0.005 before
        2026-11-29: a creep over neighbouring grid speeds, 0.5 % apart, went unseen).
    risk_after_chatter : float, optional
        The bound on P(chatter) of the next cut once any cut has chattered (≤ ``risk``; default: ``risk``
        throughout). The first chatter gives the bracket its upper side; a lower bound after it spends fewer
        tools on the rest, and buys that with a wider band: on EM16-50 in the whole loop (10 truths, 6 cuts) 0.1
        brought the chattering cuts from a median of 2 to 1 (0.10 of the cuts after the first chatter chattered,
        against 0.25–0.30), and the band at the recommended speed from 0.23–0.27 to 0.32–0.33 wide; 0 of 10 truths
        converged against 2–3 (``docs/design/shop.md``; measured with the step of ``step_until_chatter=False``,
        which is still proposed past it: the default proposes no step after a chatter).
    own_sdm : bool, default True
        ``forward="sdm"`` with cuts: each lobe sample's own SDM limit at the cut speeds replaces its reference's
        ratio there (:func:`~toolpoint.stability.sdm_limit_near` from the fit's ratio of ``sdm_train``, else from
        that one, as :data:`OWN_NEAR`: ln sd 0.002 from the full search). The lobe samples are weighted by the
        cuts' likelihood with their own limits (the boundary width ``boundary_width`` alone) over that of the
        sampling (the references' mean ratio, their spread added to the width), resampled (ESS:
        ``Posterior.own_sdm_ess``; the samples: ``Posterior.lobe_z``; where the weights leave fewer than
        :data:`OWN_MIN_ESS` of the samples effective they are tempered, ``Posterior.own_sdm_power`` < 1, so that
        the band is no heap of copies of a few samples), and each one's lobes moved to its own limit
        at the cut speeds, linearly between neighbouring cut speeds and fading over ±2 % beyond them. Without it
        the band at a cut speed is no narrower than the spread of the references' ratios there (ln sd 0.05–0.19 on
        EM16-50: one truth's band at a cut speed 0.33–0.57 wide over three seeds for the same cuts), and the
        samples agree with the cuts only through the references' mean. It costs one search per lobe sample over
        the cut speeds, all samples together (:func:`~toolpoint.stability.sdm_limit_near_many`: 1.2 s CPU for 120
        samples at three speeds on EM16-50, against 1.9–2.1 s one sample at a time). The recommended depth's
        check (held-out samples' own limits at its speed) is weighted by the cuts within 0.4 % of that speed alone,
        untempered (:func:`_recommended_own`; unweighted where no cut lies there).
        Measured in the whole loop: ``docs/design/shop.md`` (*Own SDM limits at the cut speeds*). False: as before
        2026-11-30.
    growth_by : {"zoa", "sdm"}, default "zoa"
        The κ of the label growth G / (κ t). ``"zoa"``: the zero-order lobe's
        (:func:`~toolpoint.shop.model.growth_rate`). ``"sdm"``: the SDM's growth, which the heard labels follow where
        the zero-order lobe is not the SDM's (``benchmarks/bench_shop.py --only heard``; ``docs/design/shop.md``,
        *Chatter past the limit is heard by the SDM's own growth*) — in the sampling after the SDM correction, each
        sample's zero-order κ times a reference's ratio κ_SDM / κ_ZOA at each cut, κ_SDM the secant to where its
        SDM growth ln ρ / T reaches G̃ / t (:func:`_sdm_kappa_log_ratio`), the labels' likelihood a mixture over
        the references; in the own reweighting each lobe sample's own secant ln ρ(a) / (T ln(a / a_SDM)) from its
        own limit to the cut's depth (the search's slope within 2 % of the limit). One SDM growth curve per
        reference and cut, one more spectral radius per lobe sample and cut. Needs ``forward="sdm"`` and
        ``own_sdm``. Measured in the whole loop (``docs/design/shop.md``, *The SDM's growth in the sampling too*):
        on EM12-60, truths 40–59, 6 of 20 converged within 6 cuts against 8, the recommended depth lay above the
        truth after 18 of 120 updates against 10 and the band held the truth at 0.871 of the speeds after 6 cuts
        against 0.933 (the references' mean ratio instead: 10–11 of 20, 15–22 of 120); on EM28-80 14 of 20
        against 13, 6 of 120 against 7. Not the default.

    own_pocket : int, default :data:`POCKET_SPEEDS`
        ``forward="sdm"``: the lobe samples' own SDM limits at this many speeds evenly over ±3 % of the speed where the
        band is most productive (the recommended speed as the references' ratios put it; one: that speed alone)
        replace the references' ratio there, linearly between those speeds and fading over ±2 % beyond them
        (:func:`_pocket_own`); the recommended point, the P(stable) map and the next cut then follow the corrected
        band. Each lobe sample
        carries one of ``sdm_refs`` references' SDM/ZOA ratio curves, and at a lobe's peak the ratio depends on
        where the sample's own peak lies: over 80 prior samples of EM16-50 a reference's ratio stood in for a
        sample's own to ln sd 0.032 over the grid but 0.107 within ±3 % of the recommended speed (0.285 of the
        samples off by more than 0.1), and the samples whose own peak is there are those whose SDM limit lies
        furthest above their zero-order one — the band's upper tail was too light (the prior's update with
        ``rng`` seed 0: 95 % line 3.60 mm at 14704 rpm, with the samples' own 3.96 mm; ``docs/design/shop.md``,
        *The band at the pocket from the samples' own SDM limits*). It costs one search per lobe sample at each
        speed, all together (6.4 s CPU for 400 samples at five speeds on EM16-50). 0: the references' ratios
        alone (as before 2026-12-01, night).
    band_noise : bool, default True
        ``forward="sdm"`` with at least two references: the band's 5 % and 95 % lines are read at per-speed levels
        that allow for the few references' ratio curves the lobes rest on away from the cut speeds and for the
        samples' own Monte Carlo noise — jackknives over the references and over samples dealt at random
        (:func:`_band_levels`; ``Posterior.band_levels``; one permutation drawn from ``rng``). False: at 0.05 and
        0.95 (as before 2026-12-05, night). Measured: ``docs/design/shop.md``, *The references' noise in the band*.
    cut_speed_margin : float, default 0
        Recommended speed: a speed within ±0.5 % of a cut already made is recommended instead of the most productive
        one where its n · a₀₅ is within this share of the best (``recommended["at_cut_speed"]``: the recommended speed
        lies within ±0.5 % of a cut, whatever the margin). After a
        stable cut the band's 5 % line rises at its speed and, fading over ±2 %, at the next grid speeds; on a lobe's
        rising side the best then moves one grid speed (0.5 %) up, to a speed with no cut, each update — and the
        ``"info"`` rule, which narrows the band at the recommended speed, follows it instead of bracketing the
        limit at one speed. With 0.03 (removal rate at most 3 % below the band's best) EM16-50 converged within 6
        cuts for 10 and 11 of 20 truths against 7 and 8 in the whole loop (490–529; the default's runs in an earlier
        Python environment, where a rerun moves up to 4 of 20), at the same safety, but for 8 of 20 fresh truths
        (530–549; the default 9, the same environment) (``docs/design/shop.md``, *The recommended speed held at a cut
        speed*). 0: the most productive speed, as before 2026-12-07.
    next_speeds : int, default 6
        The ``"info"`` rule's speeds: the next cut is at the recommended speed or at one of the ``next_speeds`` most
        productive by n · a₅₀; 0: at the recommended speed only. A cut at a neighbouring speed tells the limit at the
        recommended speed only through the lobes' slope between the two, and on a lobe's steep side that slope is
        what the posterior knows least: in EM16-50's whole loop a cut 18 % deeper than a stable one, at a speed 0.6 %
        away, chattered at 1.15 × the limit there, the truth's limit 11 % lower at that speed. With ``cut_speed_margin``
        0.03 as well, EM16-50 converged within 6 cuts for 11 of 20 truths 490–509 (default 7) but 9 of 20 fresh
        530–549 (default 9), EM12-60 for 15 of 20 (the default 15 and 11 in two Python environments), its
        recommended depth above the truth after 8 of 120 updates (the default 5 and 6): an option, not the default
        (``docs/design/shop.md``, *The next cut at the recommended speed*).

    Returns
    -------
    Posterior

    Examples
    --------
    >>> import numpy as np
    >>> from toolpoint.shop.model import cornelius_2024
    >>> pr = cornelius_2024(0.1)
    >>> post = update(pr, [TestCut(12000.0, 0.4e-3, False, 1280.0)], rng=np.random.default_rng(1), n_samples=300,
    ...               lobe_samples=100)
    >>> post.next_cut["rule"], 0 < post.next_cut["p_chatter"] <= 0.3
    ('info', True)
    """
    import time

    c0 = time.process_time()
    if method not in ("smc", "sir"):
        raise InputError(f"must be 'smc' or 'sir', got {method!r}", field="method")
    if forward not in ("zoa", "sdm"):
        raise InputError(f"must be 'zoa' or 'sdm', got {forward!r}", field="forward")
    if rule not in ("risk", "info"):
        raise InputError(f"must be 'risk' or 'info', got {rule!r}", field="rule")
    if growth_by not in ("zoa", "sdm"):
        raise InputError(f"must be 'zoa' or 'sdm', got {growth_by!r}", field="growth_by")
    if growth_by == "sdm" and (forward != "sdm" or not own_sdm):
        raise InputError("'sdm' needs forward='sdm' and own_sdm (the lobe samples' own SDM searches)",
                         field="growth_by")
    risk = DEFAULT_RISK[rule] if risk is None else risk
    if not 0 < risk <= 0.5:
        raise InputError(f"must be in (0, 0.5], got {risk}", field="risk")
    if risk_after_chatter is not None and not 0 < risk_after_chatter <= risk:
        raise InputError(f"must be in (0, risk = {risk:g}], got {risk_after_chatter}", field="risk_after_chatter")
    if int(sdm_train) != sdm_train or sdm_train < 0:
        raise InputError(f"must be a whole number ≥ 0, got {sdm_train}", field="sdm_train")
    if sdm_train_model not in ("mean", "quadratic"):
        raise InputError(f"must be 'mean' or 'quadratic', got {sdm_train_model!r}", field="sdm_train_model")
    if not 0 <= miss_rate < 1:
        raise InputError(f"must be in [0, 1), got {miss_rate}", field="miss_rate")
    if not (math.isfinite(boundary_width) and 0 < boundary_width <= 0.5):
        raise InputError(f"must be in (0, 0.5] (ln), got {boundary_width}", field="boundary_width")
    if not (math.isfinite(cut_speed_margin) and 0 <= cut_speed_margin <= 0.5):
        raise InputError(f"must be in [0, 0.5] (a share of the removal rate), got {cut_speed_margin}",
                         field="cut_speed_margin")
    if isinstance(next_speeds, bool) or not isinstance(next_speeds, (int, np.integer)) or not 0 <= next_speeds <= 50:
        raise InputError(f"must be a whole number in [0, 50], got {next_speeds!r}", field="next_speeds")
    if not (math.isfinite(freq_sigma) and 0 < freq_sigma <= 0.5):
        raise InputError(f"must be in (0, 0.5] (relative), got {freq_sigma}", field="freq_sigma")
    if not 0 < freq_outlier <= 1:
        raise InputError(f"must be in (0, 1], got {freq_outlier}", field="freq_outlier")
    if min_step is None:
        min_step = 0.1 if rule == "info" else 0.0
    if not 0 <= min_step <= 0.5:
        raise InputError(f"must be in [0, 0.5] (a log step), got {min_step}", field="min_step")
    if not 0 <= creep_span <= 0.1:
        raise InputError(f"must be in [0, 0.1] (relative speed), got {creep_span}", field="creep_span")
    try:
        off_mu, off_sd = (float(v) for v in label_offset)
    except (TypeError, ValueError):
        raise InputError(f"must be (mean, sd), got {label_offset!r}", field="label_offset") from None
    if not (-0.2 <= off_mu <= 0.5 and 0 <= off_sd <= 0.5):
        raise InputError(f"mean must be in [-0.2, 0.5] and sd in [0, 0.5] (ln), got {label_offset!r}",
                         field="label_offset")
    try:
        g_med, g_sd = (float(v) for v in label_growth)
    except (TypeError, ValueError):
        raise InputError(f"must be (median, sd), got {label_growth!r}", field="label_growth") from None
    if not (0 <= g_med <= 20 and 0 <= g_sd <= 1.5):
        raise InputError(f"median must be in [0, 20] and sd in [0, 1.5] (ln), got {label_growth!r}",
                         field="label_growth")
    if not (math.isfinite(cut_duration_s) and 0 < cut_duration_s <= 3600):
        raise InputError(f"must be in (0, 3600] s, got {cut_duration_s}", field="cut_duration_s")
    if not (math.isfinite(audible_margin) and 0 <= audible_margin <= 0.5):
        raise InputError(f"must be in [0, 0.5] (ln), got {audible_margin}", field="audible_margin")
    if not (math.isfinite(max_cut_duration_s) and 0 < max_cut_duration_s <= 3600):
        raise InputError(f"must be in (0, 3600] s, got {max_cut_duration_s}", field="max_cut_duration_s")
    if growth_error is not None:
        _option(growth_error, "growth_error", "(bias, sd above, sd below, outliers) or None",
                lambda v: len(v) == 4 and 0.2 <= v[0] <= 5 and 0.05 <= v[1] <= 2 and 0.05 <= v[2] <= 2
                and 0 < v[3] < 1, "needs bias in [0.2, 5], sds in [0.05, 2] (ln), outliers in (0, 1)")
    if ring_error is not None:
        _option(ring_error, "ring_error", "(ln sd, outliers) or None",
                lambda v: len(v) == 2 and 0.05 <= v[0] <= 2 and 0 < v[1] < 1,
                "needs an ln sd in [0.05, 2] and outliers in (0, 1)")
    if precursor is not None:
        _option(precursor, "precursor", "(share, reach, sd) or None",
                lambda v: len(v) == 3 and 0 < v[0] < 1 and 0 <= v[1] <= 0.5 and 0.01 <= v[2] <= 0.5,
                "needs a share in (0, 1), a reach in [0, 0.5] and an sd in [0.01, 0.5] (ln)")
    if min_step > 0 and rule != "info":
        raise InputError("the step above stable cuts belongs to the info rule; the risk rule has none",
                         field="min_step")
    if step_until_chatter not in (True, False, "near"):
        raise InputError(f"must be True, False or 'near', got {step_until_chatter!r}", field="step_until_chatter")
    if not (isinstance(own_pocket, (int, float, np.integer, np.floating)) and float(own_pocket).is_integer()
            and 0 <= own_pocket <= 50):
        raise InputError(f"must be a whole number in [0, 50], got {own_pocket!r}", field="own_pocket")
    if noisy_pocket is not None and not (isinstance(noisy_pocket, (int, float, np.integer, np.floating))
                                         and 0 <= noisy_pocket <= 0.2):
        raise InputError(f"must be in [0, 0.2] (ln per ln of pocket height) or None, got {noisy_pocket!r}",
                         field="noisy_pocket")
    if not isinstance(band_noise, (bool, np.bool_)):
        raise InputError(f"must be true or false, got {band_noise!r}", field="band_noise")
    cuts = tuple(cuts)
    f = prior.freq_grid()
    P = prior.sigma.size
    # z: the prior's standard-normal coordinates; column P the label offset's (δ = μ + s z), P + 1 the label
    # growth's (G = G̃ e^{s_G z})
    free = np.r_[prior.sigma > 0, off_sd > 0, g_med > 0 and g_sd > 0]
    # forward="sdm": the growth rates wait for the SDM correction (the zero-order pass only picks its references)
    kw = dict(boundary_width=boundary_width, label_noise=label_noise, freq_sigma=freq_sigma, freq_hz=f,
              freq_outlier=freq_outlier,
              miss_rate=miss_rate, label_offset=(off_mu, off_sd), label_growth=(g_med, g_sd),
              cut_duration_s=cut_duration_s, growth_error=growth_error if forward == "zoa" else None)
    # a noisy shop (a stable cut's record rings at a tool's mode): a chatter label may be a stable cut's ring
    noisy = None if precursor is None and not noisy_pocket else noisy_shop(cuts)
    if noisy is not None:
        if precursor is not None:
            kw["precursor"] = tuple(float(v) for v in precursor)
        if noisy_pocket:  # and chatter at a pocket's top is heard late (NOISY_POCKET)
            kw["noisy_pocket"] = float(noisy_pocket)
    z = _draw_z(rng, n_samples, free)
    ess_hist, acc = [], []
    log_ratio_grid = None
    kw_sdm = lr_at_cuts = None  # forward="sdm" with cuts: the last sampling's likelihood, the lobes' ratio at the cuts
    gx = None  # the SDM growth curves' reading of the rates (forward="sdm" with cuts)
    rx = None  # and of the stable cuts' rings
    grid = _default_grid(prior) if rpm_grid is None else np.asarray(rpm_grid, float)  # speeds of the lobes
    if cuts:
        z = _sample(prior, z, cuts, kw, method, n_moves, rng, ess_hist, acc)
        if forward == "sdm":
            # the SDM/ZOA ratio of the limit at reference posterior samples: at the cut speeds it corrects the
            # likelihood (its spread over the references widens the boundary), on the grid the lobes
            rpm_c = np.array([c.rpm for c in cuts])
            ref = z[rng.choice(n_samples, sdm_refs, replace=False), :P]
            lr_c, lr_g = _sdm_log_ratio(prior, prior.theta(ref), rpm_c, grid, f)
            spread = lr_c.std(axis=0) if sdm_refs > 1 else np.zeros(rpm_c.size)
            gx = None if growth_error is None else _sdm_growth_x(prior, prior.theta(ref), cuts, lr_c, f,
                                                                  float(growth_error[0]))
            if ring_error is not None:
                rx = _sdm_ring_x(prior, prior.theta(ref), cuts, lr_c, f, float(ring_error[0]))
            sdm_kw = {} if rx is None else dict(ring_x=rx[:2], ring_outlier=float(ring_error[1]))
            if growth_by == "sdm" and g_med > 0:
                # the label growth's κ: the references' SDM growth, their mixture (a sample's own is not known in
                # the sampling)
                sdm_kw["kappa_log_ratio"] = _sdm_kappa_log_ratio(prior, prior.theta(ref), cuts, lr_c, f, g_med,
                                                                 cut_duration_s)
            kw2 = dict(kw, boundary_width=np.sqrt(boundary_width ** 2 + spread ** 2),
                       log_ratio=lr_c.mean(axis=0), growth_error=growth_error, growth_x=gx, **sdm_kw)
            z = _sample(prior, _draw_z(rng, n_samples, free), cuts, kw2, method, n_moves, rng,
                        ess_hist, acc)
            log_ratio_grid = lr_g
            kw_sdm, lr_at_cuts = kw2, lr_c  # (R, C): what each reference's lobes carry at the cut speeds
            if sdm_train > 0:
                # the references' ratio is that of the zero-order posterior, not of the corrected one: the
                # corrected samples' own SDM limits at the cut speeds (sdm_train of them) give the ratio there,
                # its mean in the likelihood and its spread in the boundary width, and the posterior is sampled
                # a third time; each lobe sample keeps one reference's ratio, moved to that mean near the cuts
                u, inv, first = _cut_speeds(rpm_c)
                lr_ref_u = lr_c[:, first]  # (R, U)
                z_tr = z[rng.choice(n_samples, min(int(sdm_train), n_samples), replace=False), :P]
                if sdm_train_model == "mean":
                    lr_tr = _sdm_own_log_ratio(prior, z_tr, u, f, lr_ref_u.mean(axis=0))  # (T, U)
                    mean_u = lr_tr.mean(axis=0)
                    sd_u = lr_tr.std(axis=0, ddof=1) if lr_tr.shape[0] > 1 else np.zeros(u.size)
                    ratio = dict(log_ratio=mean_u[inv])
                else:  # each sample's own ratio from a quadratic fit in z (its residual sd in the width)
                    lr_tr = _sdm_own_log_ratio(prior, z_tr, u, f, lr_ref_u.mean(axis=0), near=OWN_NEAR)
                    fit = _RatioFit(z_tr, lr_tr, prior.sigma > 0, inv)
                    mean_u, sd_u = fit.mean, fit.resid_sd
                    ratio = dict(ratio_fit=fit)
                kw3 = dict(kw, boundary_width=np.sqrt(boundary_width ** 2 + sd_u[inv] ** 2),
                           growth_error=growth_error, growth_x=gx, **ratio, **sdm_kw)
                z = _sample(prior, _draw_z(rng, n_samples, free), cuts, kw3, method, n_moves,
                            rng, ess_hist, acc)
                log_ratio_grid = lr_g + _carry(mean_u[None, :] - lr_ref_u, grid, u)
                kw_sdm = kw3
                lr_at_cuts = (lr_ref_u + _carry(mean_u[None, :] - lr_ref_u, u, u))[:, inv]
    elif forward == "sdm":  # no cuts yet: the prior's lobes (and the first cut's risk) corrected the same way
        ref = z[rng.choice(n_samples, sdm_refs, replace=False), :P]
        log_ratio_grid = _sdm_log_ratio(prior, prior.theta(ref), np.zeros(0), grid, f)[1]
    # lobes of the posterior and of the prior
    m = min(lobe_samples, n_samples)
    pick = rng.choice(n_samples, m, replace=False)
    lim = _limits(prior, prior.theta(z[pick, :P]), f, grid)
    own_ess = own_power = None
    pocket_rpm = ()
    rows = None  # each lobe sample's reference (their noise in the band: _band_levels)
    if log_ratio_grid is not None:  # each lobe sample corrected by one reference's SDM/ZOA ratio
        rows = rng.integers(log_ratio_grid.shape[0], size=m)
        lim = lim * np.exp(log_ratio_grid[rows])
        if own_sdm and kw_sdm is not None:
            pick, lim, own_ess, own_power, idx = _own_reweight(prior, z, pick, lim, cuts, kw_sdm, lr_at_cuts[rows],
                                                               grid, f, boundary_width, rng, growth_by)
            rows = rows[idx]
        if own_pocket > 0:  # the band's upper tail at the productive speeds from the samples' own limits
            lim, pocket_rpm = _pocket_own(prior, z[pick, :P], f, grid, lim, int(own_pocket),
                                          cut_rpm=(np.array([c.rpm for c in cuts]) if own_sdm and kw_sdm is not None
                                                   else None))
    zp = rng.standard_normal((m, P)) * free[:P]
    lim_prior = _limits(prior, prior.theta(zp), f, grid)
    if band_noise and rows is not None and log_ratio_grid.shape[0] > 1:
        levels = _band_levels(lim, rows, log_ratio_grid.shape[0], pick, rng)
    else:
        levels = np.array([[0.05], [0.95]]) * np.ones((1, grid.size))
    q = _quantiles_at(lim, np.stack([levels[0], np.full(grid.size, 0.5), levels[1]]))
    qp = np.quantile(lim_prior, [0.05, 0.5, 0.95], axis=0)
    top = 1.5 * float(np.max(np.where(np.isfinite(q[2]), q[2], 0.0)))
    top = top if top > 0 else 1e-3
    depths = np.linspace(0, top, n_depths + 1)[1:]
    # P(stable) as the band claims it: the lobe samples' share above each depth, widened as the band's lines are
    p_st = 1.0 - _p_chatter_map(lim, depths, levels)
    q05 = np.where(np.isfinite(q[0]), q[0], np.nan)
    j = int(np.nanargmax(grid * q05))
    at_cut = (np.any(np.abs(grid[:, None] / np.array([c.rpm for c in cuts])[None, :] - 1) <= 0.005, axis=1)
              if cuts else np.zeros(grid.size, bool))  # the grid speeds within ±0.5 % of a cut made
    if cut_speed_margin > 0 and at_cut.any():
        # a speed already cut is recommended where it removes within the margin of the best: its band rests on the
        # cuts there, a neighbour's on the lobes' fade from them
        mrr = np.where(at_cut & np.isfinite(q05), grid * np.where(np.isfinite(q05), q05, 0.0), -np.inf)
        jc = int(np.argmax(mrr))
        if np.isfinite(mrr[jc]) and mrr[jc] >= (1 - cut_speed_margin) * grid[j] * q05[j]:
            j = jc
    p_rec = 1.0 - float(_p_chatter_map(lim[:, j:j + 1], [q05[j]], levels[:, j:j + 1])[0, 0])
    rec = {"rpm": float(grid[j]), "depth_m": float(q05[j]), "p_stable": p_rec,
           "limit_p05_m": float(q05[j]), "own_sdm_p05_m": None, "own_sdm_held_out": None,
           "at_cut_speed": bool(at_cut[j]),
           "limit_p50_m": float(q[1, j]), "limit_p95_m": float(q[2, j])}
    # once a cut has chattered the bracket has its upper side: the remaining cuts may be bounded lower
    bound = risk if risk_after_chatter is None or all(c.stable for c in cuts) else risk_after_chatter
    known = [c.duration_s for c in cuts if c.duration_s is not None]
    t_next = float(np.median(known)) if known else cut_duration_s  # the next cut lasts as the others did
    th_pick = prior.theta(z[pick, :P])
    g_pick = g_med * np.exp(g_sd * z[pick, P + 1])

    def duration(ks):
        """The next cut's duration at the speeds grid[ks] (len(ks),), s, and the lobe samples' κ₂₅ there."""
        if audible_margin <= 0 or g_med <= 0:
            return np.full(len(ks), t_next), np.full(len(ks), np.nan)
        _, fc = limit_at_speeds(prior, th_pick, grid[ks], f)
        kap = growth_rate(prior, th_pick, grid[ks], fc)
        kp = np.where(kap > 0, kap, np.nan)  # nan: no lobe reaches the speed (or no growth there)
        k25 = np.array([np.quantile(c[np.isfinite(c)], 0.25) if np.isfinite(c).any() else np.nan for c in kp.T])
        t = np.where(np.isfinite(k25), g_med / (np.where(np.isfinite(k25), k25, 1.0) * audible_margin), t_next)
        return np.clip(t, t_next, max(max_cut_duration_s, t_next)), k25
    if rule == "risk":
        # the deepest sample limit with at most bound × m samples at or below it (an interpolated quantile sat
        # up to 1/m above the bound: P(chatter) 0.053 for a bound of 0.05 with 150 samples)
        kq = int(math.floor(bound * m + 1e-9))
        srt = np.sort(lim, axis=0)
        qr = srt[kq - 1] if kq >= 1 else srt[0] * (1 - 1e-9)
        qr = np.where(np.isfinite(qr), qr, np.nan)
        k = int(np.nanargmax(grid * qr))
        nxt = {"rule": "risk", "risk": bound, "rpm": float(grid[k]), "depth_m": float(qr[k]),
               "p_chatter": float(np.mean(lim[:, k] <= qr[k])),
               "description": f"most productive cut (max rpm × depth) with P(chatter) ≤ {bound:g}"}
    else:
        off_pick = off_mu + off_sd * z[pick, P]

        floor_pick = floor_limit(prior, th_pick, f) if "noisy_pocket" in kw else None  # once, not per call

        def offset(ks):  # each lobe sample's label offset at the candidate speeds grid[ks], (m, len(ks))
            out = np.broadcast_to(off_pick[:, None], (m, len(ks)))
            if g_med > 0:
                _, fc = limit_at_speeds(prior, th_pick, grid[ks], f)
                out = out + growth_offset(prior, th_pick, grid[ks], fc, g_pick, duration(ks)[0])
            if floor_pick is not None:  # the outcome heard in a noisy shop at a pocket's top
                out = out + kw["noisy_pocket"] * pocket_height(prior, th_pick, lim[:, ks], floor_m=floor_pick)
            return out

        # a noisy shop: no step above the stable cuts — the step is proposed whatever its P(chatter), on stable labels
        # that at a pocket's top may be chatter unheard (noisy_pocket; EM25-55 climbed its pocket to 1.4 × the limit)
        step = 0.0 if "noisy_pocket" in kw else min_step
        nxt = _next_info(lim, grid, j, bound, boundary_width, label_noise, chatter_cost, cuts, step, miss_rate,
                         offset, skip_repeats, creep_span, step_until_chatter, next_speeds)
    if forward == "sdm":
        # the recommended depth checked by the own SDM limits of posterior samples that the choice of its speed did
        # not see: the lobe samples' tail is light at the speed where they look most productive (their own 5 %
        # limit 0.79–0.83 mm at the example tool's prior recommended speed, fresh prior samples' 0.68–0.72 mm)
        hold = np.setdiff1d(np.arange(n_samples), pick)[:m]
        held = hold.size >= min(m, 100)  # else (few samples beyond the lobes' ones) the lobe samples
        rec = _recommended_own(prior, z[hold if held else pick], f, grid, lim, rec, lobe_samples=not held,
                               cuts=cuts, kw=kw_sdm if own_sdm else None, boundary_width=boundary_width)
        if not cuts:  # measured calibrated with the lobe samples (docs/design/shop.md): kept on them
            nxt = _first_cut_own(prior, z[pick, :P], f, grid, lim, nxt, bound)
    k_next = int(np.argmin(np.abs(grid - nxt["rpm"])))
    t_cut, k25 = duration([k_next])
    nxt = dict(nxt, duration_s=float(t_cut[0]), revolutions=int(math.ceil(float(t_cut[0]) * nxt["rpm"] / 60.0)),
               growth_rate_p25_per_s=float(k25[0]) if np.isfinite(k25[0]) else None,
               duration_by_growth=bool(t_cut[0] > t_next * (1 + 1e-9)))
    return Posterior(prior, cuts, method, z, tuple(ess_hist), float(np.mean(acc)) if acc else float("nan"), grid, q,
                     depths, p_st, qp, rec, nxt, time.process_time() - c0, (off_mu, off_sd), (g_med, g_sd), forward,
                     tuple(float(v) if np.isfinite(v) else None for v in (gx[0] if gx is not None else
                                                                           np.full(len(cuts), np.nan))),
                     tuple(float(v) if np.isfinite(v) else None for v in (rx[2] if rx is not None else
                                                                           np.full(len(cuts), np.nan))),
                     kw.get("precursor"), noisy, own_ess, z[pick], own_power, pocket_rpm, levels, lim,
                     kw.get("noisy_pocket"))


def _quantiles_at(lim, levels):
    """Quantiles of the lobes ``lim`` (m, G) at per-speed levels ``levels`` (L, G), (L, G): linear between order
    statistics as ``numpy.quantile``'s default; nan where a speed holds a nan."""
    m = lim.shape[0]
    srt = np.sort(lim, axis=0)
    pos = np.clip(levels, 0.0, 1.0) * (m - 1)
    lo = np.floor(pos).astype(int)
    hi = np.minimum(lo + 1, m - 1)
    a = np.take_along_axis(srt, lo, axis=0)
    b = np.take_along_axis(srt, hi, axis=0)
    with np.errstate(invalid="ignore"):
        out = np.where(b == a, np.where(np.isinf(a), np.nan, a), a + (pos - lo) * (b - a))  # as numpy's lerp
    return np.where(np.isnan(lim).any(axis=0)[None, :], np.nan, out)


def _band_levels(lim, rows, n_ref: int, sample, rng, p: float = 0.05):
    """Per-speed quantile levels (2, G) of the band's outer lines from the lobes ``lim`` (m, G), each row carrying
    reference ``rows`` (m,) of ``n_ref`` and being a copy of posterior sample ``sample`` (m,): such that a limit drawn
    from the posterior lies below the lower line (above the upper) with probability ``p`` although the band rests on
    only ``n_ref`` references' SDM/ZOA ratio curves and on finitely many samples.

    Away from the cut speeds a lobe sample's limit is its zero-order limit times one reference's ratio, and the
    error of a few references is shared by all samples: with the references' ratios spread by τ at a speed, the
    mixture of R of them lies off the population's by a variance τ²/R and is narrower than it by τ²/R (the mean
    square deviation of R draws from their mean is τ² (R − 1)/R). A jackknife over the references estimates the
    line's variance at each speed: with q_(−r) the ``p`` quantile of the rows not carrying reference r,
    σ²_ref = (R − 1)/R Σ_r (ln q_(−r) − mean)² (and so for 1 − ``p``). It also sees the samples' own Monte Carlo
    noise (few distinct samples in a tail; a resampled sample's copies share a reference), which makes the line
    scatter but not the band narrow: the same jackknife over R groups of samples dealt at random (``rng``; all
    copies of a sample in one group) estimates that part, σ²_smp, and the references' τ²/R is the excess
    e = max(σ²_ref − σ²_smp, 0). At the cut speeds, where the rows were moved to their own SDM limits, the references
    no longer matter and e is small. With s = |ln q_p − ln q₅₀| / z (z = Φ⁻¹(1 − p)) the band's spread on that
    side, a limit a ~ N(ln q₅₀, s² + e) falls under the line ln q₅₀ − z s + ε, ε ~ N(0, σ²_ref), with probability
    Φ(−z s / √(s² + σ²_ref + e)), not p; the level Φ(−z √(1 + (σ²_ref + e)/s²)) makes it p again (normal in ln a;
    R − 1 degrees of freedom make the true level a little lower still).

    Checked on lobes built that way (ln a = N(0, 0.2²) + one of four references' N(0, 0.1²) offsets, 400 rows; 3000
    draws, ``docs/design/shop.md``; 1500 in ``test_the_band_allows_for_its_few_references``): the plain 5 % and 95 %
    lines miss a fresh draw 0.061 and 0.064 of the time, these levels' 0.053 and 0.056.
    Why: over six `update` seeds on the same cuts the band's 5 % line scattered by ln sd 0.035–0.069 away from the
    cut speeds and 0.006–0.023 within 2 % of them (EM12-60, eight truths), and the band held the truth 0.04 less
    often than an exact posterior's (``docs/design/shop.md``, *The references' noise in the band*)."""
    z = float(-ndtri(p))
    G = lim.shape[1]
    levels = np.stack([np.full(G, p), np.full(G, 1 - p)])
    groups = [g for g in (rows != r for r in range(n_ref)) if g.sum() >= 2 and (~g).any()]
    if len(groups) < 2:
        return levels
    R = len(groups)
    uniq, inv = np.unique(sample, return_inverse=True)
    dealt = rng.permutation(uniq.size)[inv.ravel()] % R  # each distinct sample's group
    smp = [g for g in (dealt != r for r in range(R)) if g.sum() >= 2 and (~g).any()]

    def jackknife(gs):  # (2, G) variance of the ln p and 1 − p lines over leaving out each group
        k = len(gs)
        if k < 2:
            return np.zeros((2, G))
        jk = np.log(np.stack([np.quantile(lim[g], [p, 1 - p], axis=0) for g in gs]))  # (k, 2, G)
        return (k - 1) / k * np.sum((jk - jk.mean(axis=0)) ** 2, axis=0)

    with np.errstate(divide="ignore", invalid="ignore"):
        lu = np.log(np.quantile(lim, [p, 0.5, 1 - p], axis=0))
        var_ref = jackknife(groups)
        excess = np.maximum(var_ref - jackknife(smp), 0.0)
        s2 = ((lu[[0, 2]] - lu[1]) / z) ** 2
        ratio = (var_ref + excess) / s2
        ratio = np.where(np.isfinite(ratio) & (s2 > 0), ratio, 0.0)
    lev = ndtr(-z * np.sqrt(1 + ratio))
    return np.stack([lev[0], 1 - lev[1]])


def _p_chatter_claimed(under, levels, p: float = 0.05, x=None):
    """The probability of chatter claimed at depths under which a share ``under`` (D, G) of the lobe samples' limits
    lie, consistent with the band read at ``levels`` (2, G; :func:`_band_levels`), (D, G).

    The band's 5 % line is the lobe samples' quantile at level ℓ = Φ(−z √(1 + r)) (z = Φ⁻¹(1 − ``p``)): the samples
    spread by s in ln a on that side, the truth by √(s² + v), r = v/s² the references' and the Monte Carlo noise
    the samples do not show. At a depth under which a share u of the samples lies, ln a = ln q₅₀ + s Φ⁻¹(u), the
    truth lies under it with probability Φ(s Φ⁻¹(u) / √(s² + v)) = Φ(Φ⁻¹(u) / √(1 + r)) — ``p`` at the band's
    line, u itself where the levels are ``p`` and 1 − ``p`` (r = 0); the lower side's r under the median, the upper
    side's over it. ``x`` (D, G): the normal scores Φ⁻¹(u) where the caller has them beyond the samples
    (:func:`_p_chatter_map`); else from ``under``, 0 and 1 staying 0 and 1."""
    z = float(-ndtri(p))
    k_lo = -ndtri(np.clip(levels[0], 1e-12, p)) / z  # √(1 + r) of each side, ≥ 1
    k_hi = ndtri(np.clip(levels[1], 1 - p, 1 - 1e-12)) / z
    if x is None:
        x = ndtri(np.clip(under, 0.0, 1.0))
    with np.errstate(invalid="ignore"):
        return ndtr(x / np.where(x < 0, k_lo, k_hi))


def _p_chatter_map(lim, depths, levels, p: float = 0.05):
    """P(chatter) claimed at ``depths`` ((D,) or (D, G), m) from the lobes ``lim`` (m, G) read at the band's
    ``levels`` (2, G), (D, G): :func:`_p_chatter_claimed` of the samples' share under each depth, and beyond the
    samples the normal model that reading rests on. Under the lowest sample the share says 0, yet where the lines
    were widened far (levels down to 0.001 where the references disagree) the band's own model gives a limit there
    a few per cent: the score runs on from Φ⁻¹(1/(2m)) at the lowest sample by ln(a_min / a) / s, s the samples'
    spread on that side ((ln q₅₀ − ln q_p) / z), and so above the highest — so that P(chatter) falls to 0 only as the
    depth does. Speeds whose lobes hold a nan keep the share alone (as ``update`` did before 2026-12-05)."""
    m = lim.shape[0]
    d = np.asarray(depths, float)
    d = d[:, None] if d.ndim == 1 else d
    under = 1.0 - (lim[None, :, :] > d[:, None, :]).mean(axis=1)
    z = float(-ndtri(p))
    with np.errstate(divide="ignore", invalid="ignore"):
        lq = np.log(np.quantile(lim, [p, 0.5, 1 - p], axis=0))
        s_lo, s_hi = (lq[1] - lq[0]) / z, (lq[2] - lq[1]) / z
        ld = np.log(d)
        x0 = ndtri(np.clip(under, 0.0, 1.0))  # the share's own score
        x_lo = ndtri(0.5 / m) - (np.log(lim.min(axis=0)) - ld) / s_lo
        x_hi = ndtri(1 - 0.5 / m) + (ld - np.log(lim.max(axis=0))) / s_hi
        ok_lo = np.isfinite(s_lo) & (s_lo > 0)
        ok_hi = np.isfinite(s_hi) & (s_hi > 0)
        x = np.where((under <= 0) & ok_lo & ~np.isnan(x_lo), np.minimum(x_lo, ndtri(0.5 / m)), x0)
        x = np.where((under >= 1) & ok_hi & ~np.isnan(x_hi), np.maximum(x_hi, ndtri(1 - 0.5 / m)), x)
    x = np.where(np.isnan(lim).any(axis=0)[None, :], x0, x)
    return _p_chatter_claimed(under, levels, p, x=x)


def _option(value, field: str, form: str, ok, need: str) -> tuple:
    """A tuple option of :func:`update` as floats, refused naming ``field`` where it is not numbers (``form``) or
    ``ok`` fails (``need``)."""
    try:
        v = tuple(float(x) for x in value)
    except (TypeError, ValueError):
        raise InputError(f"must be {form}, got {value!r}", field=field) from None
    if not ok(v):
        raise InputError(f"{need}; got {value!r}", field=field)
    return v


def _draw_z(rng, n, free):
    """Prior draws of z (n, P + 2): the model's P columns and δ's, then G's only when G is free — a run with G off
    draws exactly what it drew before G existed (same seed, same samples)."""
    z = np.zeros((n, free.size))
    z[:, :-1] = rng.standard_normal((n, free.size - 1)) * free[:-1]
    if free[-1]:
        z[:, -1] = rng.standard_normal(n)
    return z


class _RatioFit:
    """Each sample's ln(a_SDM / a_ZOA) at the cut speeds from its prior coordinates: a least-squares fit,
    quadratic in z (its free columns, no cross terms), to training samples' own ratios ``lr`` (T, U) at the U
    distinct cut speeds, one fit per speed (a speed with fewer than two training rows per coefficient: their mean
    alone). ``inv`` (C,): each cut's speed. Rows where the search found no limit (ratio 0) are left out of the
    fit. A prediction is held within the training ratios' range widened by one residual sd, since a quadratic
    far from its training cloud (the tempering starts from the prior) is no model of the ratio.

    Why: the sampling otherwise sees the cuts through one mean ratio per speed, while the samples' own ratios
    spread by ln sd 0.07–0.11 at EM12-60's productive speeds; a fit in z explained 0.41–0.89 of that spread on
    held-out posterior samples where linear, and 0.48 and 0.77 (linear 0.41, 0.42) at the two speeds where it did
    least (one truth, four speeds) — ``docs/design/shop.md``."""

    def __init__(self, z, lr, free, inv):
        self.free, self.inv = np.asarray(free, bool), np.asarray(inv, int)
        X = self._features(z)
        U = lr.shape[1]
        self.coef = np.zeros((X.shape[1], U))
        self.mean, self.resid_sd = np.zeros(U), np.zeros(U)
        self.lo, self.hi = np.zeros(U), np.zeros(U)
        for k in range(U):
            ok = lr[:, k] != 0
            y = lr[ok, k]
            if y.size == 0:
                continue
            self.mean[k] = y.mean()
            if y.size >= 2 * X.shape[1]:
                b, *_ = np.linalg.lstsq(X[ok], y, rcond=None)
                res = y - X[ok] @ b
                self.resid_sd[k] = math.sqrt(float(res @ res) / (y.size - X.shape[1]))
            else:
                b = np.r_[y.mean(), np.zeros(X.shape[1] - 1)]
                self.resid_sd[k] = float(y.std(ddof=1)) if y.size > 1 else 0.0
            self.coef[:, k] = b
            self.lo[k], self.hi[k] = y.min() - self.resid_sd[k], y.max() + self.resid_sd[k]

    def _features(self, z):
        zf = np.asarray(z, float)[:, :self.free.size][:, self.free]
        return np.c_[np.ones(zf.shape[0]), zf, zf ** 2]

    def __call__(self, z) -> np.ndarray:
        """The predicted ratios (S, C) of samples ``z`` (S, ≥ P) at each cut."""
        return np.clip(self._features(z) @ self.coef, self.lo, self.hi)[:, self.inv]


def _at(kw, z):
    """The likelihood's keywords ``kw`` for samples ``z``: a :class:`_RatioFit` (key ``ratio_fit``) evaluated at
    them as the per-sample ``log_ratio``; ``kw`` itself without one."""
    fit = kw.get("ratio_fit")
    if fit is None:
        return kw
    return dict({k: v for k, v in kw.items() if k != "ratio_fit"}, log_ratio=fit(z))


def _sample(prior, z, cuts, kw, method, n_moves, rng, ess_hist, acc):
    """Posterior samples (z) from prior samples ``z`` given the cuts: SIR or tempered SMC (module docstring)."""
    n_samples, P = z.shape[0], prior.sigma.size
    mu, sd = kw["label_offset"]
    g_med, g_sd = kw["label_growth"]
    free = np.r_[prior.sigma > 0, sd > 0, g_med > 0 and g_sd > 0]

    def loglik(z):
        return log_likelihood(prior, prior.theta(z[:, :P]), cuts, **dict(
            _at(kw, z), label_offset=mu + sd * z[:, P], label_growth=g_med * np.exp(g_sd * z[:, P + 1])))

    ll = loglik(z)
    if method == "sir":
        ess_hist.append(_ess(ll))
        w = np.exp(ll - ll.max())
        return z[_systematic(w / w.sum(), rng)]
    beta = 0.0
    while beta < 1.0:
        lo, hi = 0.0, 1.0 - beta
        if _ess(hi * ll) >= n_samples / 2:
            d = hi
        else:
            for _ in range(30):  # bisection on the tempering step
                mid = 0.5 * (lo + hi)
                lo, hi = (mid, hi) if _ess(mid * ll) >= n_samples / 2 else (lo, mid)
            d = max(lo, 1e-6)
        beta = min(1.0, beta + d)
        ess_hist.append(_ess(d * ll))
        w = np.exp(d * (ll - ll.max()))
        idx = _systematic(w / w.sum(), rng)
        z, ll = z[idx], ll[idx]
        cov = np.cov(z[:, free].T) if free.sum() > 1 else np.var(z[:, free]).reshape(1, 1)
        chol = np.linalg.cholesky(cov + 1e-9 * np.eye(int(free.sum())))
        scale = 2.38 / math.sqrt(free.sum())
        for _ in range(n_moves):
            prop = z.copy()
            prop[:, free] += scale * rng.standard_normal((n_samples, int(free.sum()))) @ chol.T
            llp = loglik(prop)
            log_a = -0.5 * (np.sum(prop ** 2, 1) - np.sum(z ** 2, 1)) + beta * (llp - ll)
            ok = np.log(rng.random(n_samples)) < log_a
            z[ok], ll[ok] = prop[ok], llp[ok]
            rate = float(ok.mean())
            acc.append(rate)
            scale *= 1.3 if rate > 0.3 else (0.7 if rate < 0.15 else 1.0)
    return z


def _sdm_log_ratio(prior, theta, rpm_cuts, grid, f):
    """ln(a_SDM / a_ZOA) of each sample (R, ·) at the cut speeds (may be none) and on the grid (both limits of
    the same θ).

    The first sample's SDM limits come from :func:`~toolpoint.shop.model.sdm_limits` (an upward search at every
    speed, as deep as the pockets go); the others' from :func:`~toolpoint.stability.sdm_limit_near`, started at
    their own zero-order limit times the first sample's ratio (a bracket of ±2 % in ln a, stepped out at most
    three times, halved once: the limit within about 0.5 %), and searched upwards like the first where that
    found no bracket. On EM16-50 (three modes) this halves the references' time at a ratio within 0.3 % of the
    full search (``docs/design/shop.md``). The others' searches run together (``sdm_limit_near_many``)."""
    from ..stability import sdm_limit_near_many

    zg = _limits(prior, theta, f, grid)
    zc = limit_at_speeds(prior, theta, rpm_cuts, f)[0] if rpm_cuts.size else np.zeros((theta.shape[0], 0))
    # one SDM call per sample over the grid and the cut speeds together
    speeds, inv = np.unique(np.r_[grid, rpm_cuts], return_inverse=True)
    inv_g, inv_c = inv[:grid.size], inv[grid.size:]
    z_u, fc_u = limit_at_speeds(prior, theta, speeds, f)  # the guesses' zero-order part
    out_c, out_g = np.zeros((theta.shape[0], rpm_cuts.size)), np.zeros((theta.shape[0], grid.size))

    def log_ratio(s, z):
        with np.errstate(divide="ignore", invalid="ignore"):
            return np.where(np.isfinite(s / z) & (s > 0), np.log(s / z), 0.0)

    # the first: as deep as the pockets go (with sdm_lobes' own range a pocket past 100 × the minimum limit was
    # inf, its ratio dropped to 0 and the correction lost exactly where the cuts are: EM28-80)
    s_all = np.full((theta.shape[0], speeds.size), np.nan)
    s_all[0] = sdm_limits(prior, theta[0], speeds, chatter=False)[0]
    lr_u = log_ratio(s_all[0], z_u[0])
    if theta.shape[0] > 1:  # the others together, from the first's ratio
        guess = z_u[1:] * np.exp(lr_u)[None, :]
        tools = [(mm, mm, cut) for mm, cut in map(prior.tool, theta[1:])]
        near, bracketed = sdm_limit_near_many(tools, rpm=speeds, depth_m=guess, log_step=0.02, max_steps=3,
                                              bisections=1, chatter_hz=fc_u[1:])
        s_all[1:][bracketed] = near[bracketed]
    for i in range(1, theta.shape[0]):
        redo = np.isnan(s_all[i])  # no guess, or no bracket within the steps: searched upwards
        if redo.any():
            s_all[i, redo] = sdm_limits(prior, theta[i], speeds[redo], chatter=False)[0]
    for i in range(theta.shape[0]):
        out_g[i] = log_ratio(s_all[i, inv_g], zg[i])
        out_c[i] = log_ratio(s_all[i, inv_c], zc[i])
    return out_c, out_g


_GROWTH_X = np.array([-0.06, -0.04, -0.02, -0.01, 0.0, 0.01, 0.02, 0.035, 0.05, 0.075, 0.1, 0.15, 0.2, 0.3, 0.4, 0.6,
                      0.8, 1.0])  # ln(a / a_SDM) of the growth curves (_sdm_growth_x)


def _sdm_growth_x(prior, theta, cuts, lr_c, f, bias: float = 1.0):
    """The distance past the limit, x_m (ln), that each chattering cut's measured growth σ_m says by the SDM's own
    growth: at each reference sample (rows of ``theta``) its σ(x) = ln ρ(a_SDM e^x) / T at the cut's speed (ρ the
    spectral radius per tooth period, a_SDM ≈ a_ZOA e^``lr_c`` the reference's limit there, as its search found it
    to ~0.5 %), made monotone (its running maximum), over x ∈ [−0.06, 1]; x_m = x(σ_m / ``bias``) − x(0), from the
    curve's own zero crossing (the limit exactly; the search's 0.5 % would be worth κ · 0.005 ≈ 2.5 /s on the
    Cornelius tool, a quarter of a reading 2 % past). A reference reads a cut that states its chatter frequency only
    where what grows on its curve at the reading is that line: the critical multiplier's ±arg μ f_t / 2π within 3 %
    of the heard frequency, both folded by the tooth-passing frequency f_t (:func:`_fold_hz`) — else its curve is
    another line's growth (EM12-60's truth 48 chattered at 1648 Hz, an alias of its 762 Hz mode, at 7.4 /s 0.46 past
    its limit; its four references grew a line 170–196 Hz off (folded) there and read 0.01, and the band after that
    cut missed the truth). (mean, sd) over the references, each (C,); nan where a cut has no reading, or fewer than two
    references bracket it (one, of one reference; the reading past x = 1, the curve not crossing zero within the
    grid: no SDM limit near the search's; or another line growing there).

    Why not κ x: the zero-order κ (:func:`~toolpoint.shop.model.growth_rate`) is the zero-order lobe's slope at its
    limit, and where the SDM's limit lies more than 10 % from it (a pocket, a flip lobe) another lobe limits and
    grows: there κ x was 0.04–2.2× the SDM's σ on four EM12-60 truths, and a cut 10 % past a pocket's limit can grow
    16× faster than the pocket's slope says, as the next lobe takes over (``docs/design/shop.md``)."""
    C = len(cuts)
    xm, xsd = np.full(C, np.nan), np.full(C, np.nan)
    use = [r for r, c in enumerate(cuts) if _rate(c)]
    if not use:
        return xm, xsd
    rpm = np.array([cuts[r].rpm for r in use])
    sig_m = np.array([cuts[r].growth_per_s for r in use], float) / bias
    a_z = limit_at_speeds(prior, theta, rpm, f)[0]  # (R, U)
    a_s = a_z * np.exp(np.asarray(lr_c, float)[:, use])
    ft = prior.cutting.teeth * rpm / 60.0
    hz = np.array([np.nan if cuts[r].chatter_hz is None else cuts[r].chatter_hz for r in use], float)
    heard = _fold_hz(hz, ft)  # nan where the cut states no chatter frequency: every reference reads it
    got = np.full((theta.shape[0], len(use)), np.nan)
    for i, t in enumerate(theta):
        ok = np.isfinite(a_s[i]) & (a_s[i] > 0)
        for j, q, phi in _sdm_curves(prior, t, rpm, a_s[i], ft, ok, _GROWTH_X, fold=True):
            if q[0] >= 0 or q[-1] < sig_m[j]:
                continue
            # what grows at the reading on this reference's curve must be the line heard: else it is another
            # line's growth, and the curve says nothing of how far past the limit the heard chatter was
            if abs(phi[int(np.argmax(q >= sig_m[j]))] - heard[j]) > _GROWTH_HZ_REL * hz[j]:
                continue
            got[i, j] = _cross(q, sig_m[j]) - _cross(q, 0.0)
    n = np.sum(np.isfinite(got), axis=0)
    need = min(2, theta.shape[0])  # one reference (update's sdm_refs=1) reads alone, with no spread
    for j, r in enumerate(use):
        if n[j] >= need:
            v = got[np.isfinite(got[:, j]), j]
            xm[r], xsd[r] = float(v.mean()), float(v.std(ddof=1)) if v.size > 1 else 0.0
    return xm, xsd


def _sdm_kappa_log_ratio(prior, theta, cuts, lr_c, f, growth: float, cut_duration_s: float):
    """ln(κ_SDM / κ_ZOA) of each reference sample (rows of ``theta``) at each cut, (R, C): κ_ZOA the
    reference's zero-order growth rate (:func:`~toolpoint.shop.model.growth_rate`), κ_SDM = (G / t) / x_b its SDM's
    secant to the depth where chatter is first heard, x_b the x at which the reference's SDM growth σ(x) = ln ρ(a_SDM
    e^x) / T (:func:`_sdm_curves`, over x ∈ [−0.06, 1], from its own zero crossing) reaches G / t, G ``growth`` (the
    label growth's prior median), t the cut's duration (else ``cut_duration_s``): with it, a sample like the
    reference hears chatter where the SDM says it has grown by e^G. Where σ does not reach G / t within x = 1, the
    secant to x = 1 (the offset's cap is reached anyway); nan where no reference reads the cut (no SDM limit near
    the search's, no zero-order growth), the zero-order κ is then used. :func:`log_likelihood` takes the labels'
    likelihood as a mixture over the references (one reference's ratios for all of a sample's cuts): at a speed where
    the samples fall into kinds that grow at e^−0.65…−0.2 and at e^2.1…2.8 × the zero-order κ (EM12-60 at 17769 and
    17970 rpm, two truths and 8 prior samples; ``docs/design/shop.md``), the references' mean fitted neither kind.

    Why: at EM12-60's pockets and flip lobes another lobe limits and grows than the zero-order one, whose κ was
    0.58–17× off the SDM's secant at a twentieth of the cuts each way; heard labels followed the SDM's growth
    (``benchmarks/bench_shop.py --only heard``)."""
    C = len(cuts)
    rpm = np.array([c.rpm for c in cuts])
    dur = np.array([cut_duration_s if c.duration_s is None else c.duration_s for c in cuts], float)
    a_z, f_c = limit_at_speeds(prior, theta, rpm, f)  # (R, C)
    a_s = a_z * np.exp(np.asarray(lr_c, float))
    kz = growth_rate(prior, theta, rpm, f_c)
    ft = prior.cutting.teeth * rpm / 60.0
    level = growth / dur
    got = np.full((theta.shape[0], C), np.nan)
    for i, t in enumerate(theta):
        ok = np.isfinite(a_s[i]) & (a_s[i] > 0) & np.isfinite(kz[i]) & (kz[i] > 0)
        for j, q in _sdm_curves(prior, t, rpm, a_s[i], ft, ok, _GROWTH_X):
            if q[0] >= 0 or q[-1] <= 0:  # no SDM limit within the curve's span
                continue
            x0 = _cross(q, 0.0)
            k_sdm = level[j] / (_cross(q, level[j]) - x0) if q[-1] >= level[j] else q[-1] / (_GROWTH_X[-1] - x0)
            got[i, j] = math.log(k_sdm / kz[i, j])
    return got


def _ring_readable(c) -> bool:
    return (c.stable and c.ring_per_s is not None and c.ring_hz is not None and math.isfinite(c.ring_per_s)
            and c.ring_per_s < 0 and (c.ring_ln_sd is None or c.ring_ln_sd <= _RING_LN_SD_MAX))


def ring_left_out(cuts, r: int) -> str | None:
    """Why cut ``r``'s ring does not enter :func:`update` before the SDM's curves are read, or None (it is read
    there): no ring (or not a stable cut's), one read to an ln sd over 0.5, or a deeper stable cut at its speed
    (±0.5 %) whose ring counts instead — rings read at one speed share their error against the SDM (the same modes,
    the same noise), so the likelihood may not multiply them as independent readings."""
    c = cuts[r]
    if not c.stable or c.ring_per_s is None:
        return "no ring"
    if not _ring_readable(c):
        return (f"read to an ln sd of {c.ring_ln_sd:.2f}, over {_RING_LN_SD_MAX:g}"
                if c.ring_ln_sd is not None and c.ring_ln_sd > _RING_LN_SD_MAX else "not a decaying line")
    deeper = [q for q, o in enumerate(cuts) if q != r and _ring_readable(o) and abs(o.rpm / c.rpm - 1) <= 0.005
              and (o.depth_m, q) > (c.depth_m, r)]
    if deeper:
        q = max(deeper, key=lambda q: (cuts[q].depth_m, q))
        where = f"line {cuts[q].line}" if cuts[q].line is not None else f"cut {q + 1}"
        return f"the deeper cut at its speed ({where}) counts instead"
    return None


def _sdm_curves(prior, theta, rpm, a_sdm, ft, ok, grid, fold: bool = False):
    """(j, σ(x)) for each speed rpm[j] where ``ok``: the sample's SDM σ(x) = ln ρ(a_sdm e^x) · f_t (1/s) over the
    ln offsets ``grid``, made monotone (its running maximum: the first x a level is reached). With ``fold``: (j, σ(x),
    φ(x)), φ the frequency of what grows there, folded into [0, f_t / 2] (Hz: ±arg μ f_t / 2π of the critical
    multiplier μ where the running maximum was reached; :func:`_fold_hz` folds a heard frequency alike)."""
    from ..stability.sdm import sdm_spectral_radius

    if not ok.any():
        return []
    mm, cut = prior.tool(theta)
    mu = sdm_spectral_radius(mm, mm, cut, rpm=rpm[ok][None, :], depth=a_sdm[ok][None, :] * np.exp(grid)[:, None],
                             multiplier=fold)  # (X, U')
    raw = np.log(np.maximum(np.abs(mu), 1e-300)) * ft[ok][None, :]
    sig = np.maximum.accumulate(raw, axis=0)
    if not fold:
        return list(zip(np.flatnonzero(ok), sig.T))
    # where each running maximum was reached: the last x at which the raw curve equals it
    at = np.maximum.accumulate(np.where(raw >= sig, np.arange(grid.size)[:, None], 0), axis=0)
    phi = np.abs(np.angle(np.take_along_axis(mu, at, axis=0))) / (2 * np.pi) * ft[ok][None, :]
    return list(zip(np.flatnonzero(ok), sig.T, phi.T))


def _fold_hz(f_hz, ft):
    """A frequency (Hz) folded into [0, f_t / 2] by the tooth-passing frequency f_t: f + k f_t and −f + k f_t (a line
    and its aliases, the mirror of a real signal) fold alike."""
    p = np.mod(np.asarray(f_hz, float) / ft, 1.0)
    return np.minimum(p, 1.0 - p) * ft


def _cross(q, level, grid=_GROWTH_X):
    """x where the non-decreasing curve q over ``grid`` first reaches ``level`` (q[0] < level ≤ q[-1]); linear
    between the grid's points."""
    k = int(np.argmax(q >= level))
    u = (level - q[k - 1]) / (q[k] - q[k - 1])
    return float(grid[k - 1] + u * (grid[k] - grid[k - 1]))


_RING_X = np.array([-1.0, -0.8, -0.6, -0.5, -0.4, -0.3, -0.25, -0.2, -0.15, -0.1, -0.07, -0.05, -0.03, -0.02, -0.01,
                    0.0, 0.01, 0.02, 0.035, 0.05])  # ln(a / a_SDM) of the decay curves (_sdm_ring_x)


def _sdm_ring_x(prior, theta, cuts, lr_c, f, ring_sd: float = RING_ERROR[0]):
    """How close under the limit, at least, each stable cut's ring says it was (x_r ≤ 0, ln), by the SDM's own decay:
    at each reference sample (rows of ``theta``) its σ(x) = ln ρ(a_SDM e^x) / T at the cut's speed (ρ the spectral
    radius per tooth period: the least damped mode's decay below the limit), made monotone (its running maximum),
    over x ∈ [−1, 0.05]. The least damped mode decays no faster than any line the record holds, so the cut was at
    least as close as the x where the curve first reaches the reading σ_m: x_r = x(σ_m) − x(0). Its sd on the side
    that matters (the truth further below) is x_r − x(σ_m e^s), s = √(``ring_sd``² + the reading's ln sd²),
    x(·) = −1 past the grid. Each reference's x_r and sd are multiplied by its κ at the cut
    (:func:`~toolpoint.shop.model.growth_rate`), so that the likelihood divides them by each sample's own: a curve's
    slope is its damping, and the references' is not the sample's. (mean of κ x_r over the references, sd: theirs in
    quadrature with the mean of the κ sds), each (C,), 1/s; and the references' mean x_r itself (C,), ln;
    nan where a stable cut has no ring (or one read to an ln sd over 0.5, or a deeper stable cut at its speed, ±0.5 %,
    has one of those: rings at one speed share their error), the ring lies more than 10 % from every reference's
    chatter frequency and its tooth-passing aliases (j = −2…2: another line than the tool's), decays faster than the
    curve at x = −1 (it says nothing), or fewer than two references read it."""
    C = len(cuts)
    xm, xsd, xp = np.full(C, np.nan), np.full(C, np.nan), np.full(C, np.nan)
    use = [r for r in range(C) if ring_left_out(cuts, r) is None]
    if not use:
        return xm, xsd, xp
    rpm = np.array([cuts[r].rpm for r in use])
    sig_m = np.array([cuts[r].ring_per_s for r in use], float)
    hz = np.array([cuts[r].ring_hz for r in use], float)
    s_tot = np.hypot(ring_sd, np.array([cuts[r].ring_ln_sd or 0.0 for r in use], float))
    a_z, f_c = limit_at_speeds(prior, theta, rpm, f)  # (R, U)
    a_s = a_z * np.exp(np.asarray(lr_c, float)[:, use])
    ft = prior.cutting.teeth * rpm / 60.0
    kap = growth_rate(prior, theta, rpm, f_c)  # (R, U)
    with np.errstate(invalid="ignore"):
        alias = f_c[:, :, None] + ft[None, :, None] * np.arange(-2, 3)[None, None, :]
        near = np.nanmin(np.abs(alias - hz[None, :, None]), axis=2) <= _RING_HZ_REL * hz[None, :]
    got, lo = (np.full((theta.shape[0], len(use)), np.nan) for _ in range(2))
    for i, t in enumerate(theta):
        ok = np.isfinite(a_s[i]) & (a_s[i] > 0) & near[i] & (kap[i] > 0)
        for j, q in _sdm_curves(prior, t, rpm, a_s[i], ft, ok, _RING_X):
            if q[0] >= sig_m[j] or q[-1] < 0:  # faster than far below the limit; no limit near the search's
                continue
            x0 = _cross(q, 0.0, _RING_X)
            got[i, j] = kap[i, j] * (_cross(q, sig_m[j], _RING_X) - x0)
            deeper = sig_m[j] * math.exp(s_tot[j])
            lo[i, j] = kap[i, j] * ((_cross(q, deeper, _RING_X) if q[0] < deeper else _RING_X[0]) - x0)
    n = np.sum(np.isfinite(got), axis=0)
    need = min(2, theta.shape[0])
    for j, r in enumerate(use):
        if n[j] >= need:
            k = np.isfinite(got[:, j])
            v, e = got[k, j], got[k, j] - lo[k, j]
            spread = float(v.std(ddof=1)) if v.size > 1 else 0.0
            xm[r], xsd[r] = float(v.mean()), float(math.sqrt(np.mean(e ** 2) + spread ** 2))
            xp[r] = float(np.mean(v / kap[k, j]))
    return xm, xsd, xp


def _sdm_own_log_ratio(prior, z, u, f, lr_guess, zoa=None, near: dict | None = None, cuts=None):
    """ln(a_SDM / a_ZOA) of each sample (S, U) at the speeds u: its own SDM limit
    (:func:`~toolpoint.stability.sdm_limit_near_many`: every sample's search in one call, from its zero-order limit
    times e^lr_guess); 0 where no lobe reaches the speed. ``zoa``: the samples' ``limit_at_speeds`` at u, when the
    caller has it. ``near``: search options of ``sdm_limit_near`` (its defaults otherwise).

    With ``cuts`` (their speeds among u) also each sample's SDM growth rate at each cut (S, C), 1/s: the secant
    ln ρ(a) / (T ln(a / a_SDM)) from its own limit to the cut's depth a (ρ per tooth period T) — how fast chatter
    grows there, on whichever lobe limits — or, within 2 % of the limit, the slope across the search's last
    bracket; nan where the search found no limit (the zero-order κ is used there)."""
    from ..stability import sdm_limit_near_many

    th = prior.theta(z)
    a_zoa, fc = limit_at_speeds(prior, th, u, f) if zoa is None else zoa  # (S, U)
    guess = a_zoa * np.exp(np.broadcast_to(lr_guess, a_zoa.shape))
    # Resampled samples repeat (the lobe samples: 15–20 % of the rows after the cuts' reweighting on EM12-60): each
    # distinct (θ, guesses) is searched once — every point's search is its own, so the same bits.
    one, back = _distinct_rows(th, guess, fc)
    tools = [(mm, mm, cut) for mm, cut in map(prior.tool, th[one])]
    # all samples' models together (the same search as one sdm_limit_near per sample; skipped guesses give NaN)
    if cuts is None:
        own, _ = sdm_limit_near_many(tools, rpm=u, depth_m=guess[one], chatter_hz=fc[one], **(near or {}))
        own = own[back]
    else:  # ρ at each cut's depth too: cut c is the j-th at its speed
        k = np.searchsorted(u, [c.rpm for c in cuts])
        j = np.array([sum(k[:i] == k[i]) for i in range(len(cuts))], int)
        depth = np.full((one.size, u.size, int(j.max()) + 1), np.nan)
        depth[:, k, j] = np.array([c.depth_m for c in cuts])[None, :]
        own, _, ex = sdm_limit_near_many(tools, rpm=u, depth_m=guess[one], chatter_hz=fc[one], rho_at=depth,
                                         extras=True, **(near or {}))
        period = 60.0 / (prior.cutting.teeth * u[k])  # (C,)
        with np.errstate(divide="ignore", invalid="ignore"):
            x = np.log(depth[:, k, j] / own[:, k])  # (S, C)
            sec = np.log(ex["rho_at"][:, k, j]) / (period[None, :] * x)
            kap = np.where(np.abs(x) >= 0.02, sec, ex["growth_per_s"][:, k])
        kap = np.where(np.isfinite(kap) & (kap > 0), kap, np.nan)[back]
        own = own[back]
    with np.errstate(divide="ignore", invalid="ignore"):
        lr = np.where(np.isfinite(own / a_zoa) & (own > 0), np.log(own / a_zoa), 0.0)
    return lr if cuts is None else (lr, kap)


def _distinct_rows(*arrays):
    """(first, back): the index of each distinct row of the arrays side by side (rows compared bit for bit, NaN
    included), in order of first appearance, and for every row the position of its own among them."""
    rows = np.ascontiguousarray(np.concatenate([np.asarray(a, float).reshape(len(a), -1) for a in arrays], axis=1))
    seen, first, back = {}, [], np.empty(rows.shape[0], int)
    for i, row in enumerate(rows):
        back[i] = seen.setdefault(row.tobytes(), len(first))
        if back[i] == len(first):
            first.append(i)
    return np.asarray(first, int), back


def _own_reweight(prior, z, pick, lim, cuts, kw, lr_now, grid, f, boundary_width, rng, growth_by="zoa"):
    """The lobe samples (rows ``pick`` of ``z``, lobes ``lim``) weighted by the cuts' likelihood with their own SDM
    limits at the cut speeds over that of the last sampling (``kw``: the references' mean ratio, their spread in the
    boundary width), resampled, and each one's lobes moved to its own limit at the cut speeds (the residual put on
    the grid by :func:`_interp_near`). ``lr_now`` (m, C): the ratio each lobe sample's lobes carry at the cuts.
    Returns the new ``pick`` and ``lim`` (rows repeat), the weights' effective sample size — 0 where no weight is
    finite (no sample can explain the cuts with its own limits; the likelihood's floors make that unreachable), the
    lobe samples then left as they were —, the power the weights were tempered to (:func:`_own_temper`; None
    where none was finite) and the rows of the old lobe samples the new ones are (m,).

    Why: each lobe sample carries one reference's SDM/ZOA ratio, and the references' ratios at a speed spread by
    ln sd 0.05–0.19 on EM16-50, so the band at a cut speed could not be narrower than that spread however the cuts
    fell — and the sampled posterior matched the cuts only through the references' mean (of one truth's
    posterior samples 37–62 % had their own limit below a stable cut; ``docs/design/shop.md``)."""
    P = prior.sigma.size
    u, inv, first = _cut_speeds(np.array([c.rpm for c in cuts]))
    zp = z[pick]
    # the search from each sample's ratio predicted by the fit where there is one (the references' ratios, the
    # guesses otherwise, lay ln sd 0.17 off on EM16-50): fewer steps to its bracket (OWN_NEAR)
    fit = kw.get("ratio_fit")
    guess = lr_now[:, first] if fit is None else fit(zp)[:, first]
    own = _sdm_own_log_ratio(prior, zp[:, :P], u, f, guess, near=OWN_NEAR,
                             cuts=cuts if growth_by == "sdm" else None)  # (m, U), and κ (m, C) with the cuts
    kap = None
    if growth_by == "sdm":
        own, kap = own
    mu, sd = kw["label_offset"]
    g_med, g_sd = kw["label_growth"]
    th = prior.theta(zp[:, :P])
    extra = dict(label_offset=mu + sd * zp[:, P], label_growth=g_med * np.exp(g_sd * zp[:, P + 1]))
    kw = _at(kw, zp)
    lw = (log_likelihood(prior, th, cuts, **dict(kw, **extra, boundary_width=boundary_width,
                                                 log_ratio=own[:, inv], kappa=kap))
          - log_likelihood(prior, th, cuts, **dict(kw, **extra)))
    lw = np.where(np.isfinite(lw), lw, -np.inf)
    if not np.isfinite(lw).any():
        return pick, lim, 0.0, None, np.arange(pick.size)
    alpha = _own_temper(lw, OWN_MIN_ESS * lw.size)
    lw = alpha * lw
    w = np.exp(lw - lw.max())
    idx = _systematic(w / w.sum(), rng)
    lim = lim[idx] * np.exp(_interp_near(own[idx] - lr_now[idx][:, first], grid, u))
    return pick[idx], lim, _ess(lw), alpha, idx


def _pocket_own(prior, zp, f, grid, lim, n: int, span: float = 0.03, cut_rpm=None):
    """The lobes ``lim`` (m, G) of the lobe samples ``zp`` (m, P; rows may repeat) moved to each sample's own SDM limit
    at ``n`` grid speeds evenly over ±``span`` of the speed where the band's 5 % limit times the speed is largest —
    linearly in ln a between those speeds, fading over ±2 % beyond them (:func:`_interp_near`). Each search starts
    from what the sample's lobes carry there (:func:`_sdm_own_log_ratio` as :data:`OWN_NEAR`: ln sd 0.002 from the
    full search); a speed no lobe reaches, or a search that found no limit, leaves the sample's lobes as they were. A
    speed within 0.4 % of one of ``cut_rpm`` is not searched: the lobes already carry the samples' own limits there
    (:func:`_own_reweight`), and it keeps them. One pass: where the corrected band is most productive outside the
    speeds searched (the recommended speed moved more than ``span``), the band there is the references' — the
    recommended depth is checked there by held-out samples' own limits all the same (:func:`_recommended_own`).

    Why: the references' ratio is one of a few samples' own, and at a lobe's peak the ratio depends on where the
    sample's own peak lies — a random reference's stood in there to ln sd 0.107 on EM16-50 (0.032 over the whole
    grid), and the samples whose peak lies at the speed, whose SDM limit is furthest above their zero-order one, got
    another's: the band's upper tail was too light where the first cuts go (:func:`update`'s ``own_pocket``).

    Returns the new lobes and the speeds searched (a tuple of rpm, increasing)."""
    with np.errstate(invalid="ignore"):
        q05 = np.quantile(lim, 0.05, axis=0)
    q05 = np.where(np.isfinite(q05), q05, np.nan)
    if not np.isfinite(q05).any():
        return lim, ()
    j = int(np.nanargmax(grid * q05))
    offsets = np.linspace(-span, span, n) if n > 1 else np.zeros(1)  # one speed: the most productive itself
    ks = np.unique([int(np.argmin(np.abs(grid - grid[j] * (1 + d)))) for d in offsets])
    u = grid[ks]
    done = (np.zeros(u.size, bool) if cut_rpm is None or len(cut_rpm) == 0 else
            np.min(np.abs(u[:, None] / np.asarray(cut_rpm)[None, :] - 1), axis=1) <= 0.004)
    if done.all():
        return lim, ()
    # resampled rows repeat: one search per distinct sample (``first``: its first row)
    uz, first, inv = np.unique(zp, axis=0, return_index=True, return_inverse=True)
    inv = inv.ravel()
    s = ~done
    a, fc = limit_at_speeds(prior, prior.theta(uz), u[s], f)  # (S, U')
    carried = lim[first][:, ks[s]]
    resid = np.zeros((uz.shape[0], u.size))
    with np.errstate(divide="ignore", invalid="ignore"):
        guess = np.where(np.isfinite(carried / a) & (carried > 0), np.log(carried / a), 0.0)
        lr = _sdm_own_log_ratio(prior, uz, u[s], f, guess, zoa=(a, fc), near=OWN_NEAR)
        # _sdm_own_log_ratio gives 0 where its search found no limit: such a sample keeps its lobes
        own = np.where(lr != 0.0, a * np.exp(lr), np.nan)
        r = np.log(own / carried)
    resid[:, s] = np.where(np.isfinite(r), r, 0.0)
    return lim * np.exp(_interp_near(resid[inv], grid, u)), tuple(float(v) for v in u[s])


def _own_temper(lw, ess_min: float) -> float:
    """The power α ∈ (0, 1] of the own-SDM weights e^{α lw}: 1 where their ESS is at least ``ess_min``, else the
    largest α that keeps it there (bisection; the ESS falls as α grows). Where no power does — fewer than
    ``ess_min`` weights are non-zero — the smallest tried (2⁻³⁰): the non-zero weights all but equal.

    Why: with the full weights the ESS was 5–67 of 400 lobe samples for one EM12-60 truth's six cuts over eight
    seeds of the update, and a band of five distinct samples is a heap of copies — 0.016 wide (5–95 % over the
    median) with the truth outside it at a fifth of the speeds. Part of the way the band stays between the
    references' (wider at the cut speeds) and the own limits': wider than the exact posterior, never narrower
    than its samples can show (``docs/design/shop.md``, *The own-SDM weights tempered*)."""
    if _ess(lw) >= ess_min:
        return 1.0
    lo, hi = 0.0, 1.0
    for _ in range(30):
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if _ess(mid * lw) >= ess_min else (lo, mid)
    # α > 0 always: a sample of weight 0 (lw = −∞) keeps it, and as α → 0 the ESS tends to the count of the others,
    # which may lie under the floor (0 · −∞ would make the weights NaN)
    return lo if lo > 0 else hi


def _cut_speeds(rpm_c):
    """The distinct cut speeds u (sorted), each cut's index into u, and the first cut at each speed."""
    u, first, inv = np.unique(rpm_c, return_index=True, return_inverse=True)
    return u, inv, first


def _interp_near(resid, grid, u, kernel=0.02):
    """Residuals at the sorted speeds u (·, U) on the grid (·, G): linear in speed between neighbouring speeds of u
    (held at the end values beyond them, as ``np.interp``), faded by exp(−½ (d / ``kernel``)²), d the relative
    distance to the nearest of u — each residual itself at its own speed (where :func:`_carry` averages speeds
    closer than its kernel), 0 a few ``kernel`` away. One interpolation for all rows."""
    resid = np.atleast_2d(resid)
    d = np.min(np.abs(grid[:, None] / u[None, :] - 1), axis=1)
    fade = np.exp(-0.5 * (d / kernel) ** 2)
    if u.size == 1:
        return resid[:, :1] * fade[None, :]
    k = np.clip(np.searchsorted(u, grid) - 1, 0, u.size - 2)
    t = np.clip((grid - u[k]) / (u[k + 1] - u[k]), 0.0, 1.0)
    return (resid[:, k] * (1 - t) + resid[:, k + 1] * t) * fade[None, :]


def _own_limits(prior, z, f, grid, lim, k, lobe_samples=True):
    """Posterior samples' ``z`` own SDM limits at grid[k] (S,), searched from their zero-order limit times the
    median SDM/ZOA ratio of the lobes there (:func:`_sdm_own_log_ratio`): each lobe sample's own ratio when ``z``
    are the lobe samples (rows of ``lim``), else the ratio of the medians. inf where no lobe reaches the speed."""
    z = z[:, :prior.sigma.size]  # the modal parameters' columns (not the label offset's and growth's)
    u = grid[k:k + 1]
    zoa = limit_at_speeds(prior, prior.theta(z), u, f)
    a_zoa = zoa[0][:, 0]
    with np.errstate(divide="ignore", invalid="ignore"):
        guess = (np.nanmedian(np.log(lim[:, k] / a_zoa)) if lobe_samples else
                 np.log(np.nanmedian(np.where(lim[:, k] > 0, lim[:, k], np.nan)) / np.nanmedian(a_zoa)))
    lr = _sdm_own_log_ratio(prior, z, u, f, np.array([guess if np.isfinite(guess) else 0.0]), zoa=zoa,
                            near=OWN_NEAR)[:, 0]
    own = a_zoa * np.exp(lr)
    return np.where(np.isfinite(own), own, np.inf)


def _recommended_own(prior, z, f, grid, lim, rec, lobe_samples=False, cuts=(), kw=None,
                     boundary_width=BOUNDARY_WIDTH):
    """The recommended depth checked against the own SDM limits of posterior samples ``z`` that are not the lobe
    samples: the lower of the band's 5 % limit and theirs, P(stable) from theirs.

    The band rests on four references' SDM/ZOA ratio curves and on the lobe samples, and the recommended speed is
    the one where that estimate of n · a₀₅ is largest — where it is likely too high, as for the first cut
    (:func:`_first_cut_own`). Other samples' own limits at that one speed are an estimate the choice did not see.
    Measured: ``docs/design/shop.md`` (*The recommended depth checked*).

    Held-out samples (``lobe_samples`` False) with cuts within 0.4 % of the recommended speed and ``kw`` (the
    likelihood's arguments of the sampling): each sample is weighted by those cuts' likelihood with its own limit
    there (the boundary width ``boundary_width`` alone) over the sampling's (the references' mean ratio, their
    spread in the width), and the 5 % limit and P(stable) are the weighted ones — untempered. Why: the sampling
    sees a cut through the references' mean ratio, and at a speed where the samples' own ratios spread (EM12-60
    truth 93 at 17769 rpm: ln sd 0.07, their mean 0.09 above the references') most of its samples put their own
    limit above a cut heard chattering there; the lobe samples' weights are tempered (:func:`_own_temper`), and
    the depth recommended after its 5th cut was 2.54 mm, 8 % under that cut (2.76 mm). With the weights 2.46 mm
    (``rng`` seed 1) — still above the truth's limit there, 2.30 mm: the weights make the check agree with the
    cuts at its speed; they cannot move a posterior that is wrong elsewhere. On EM12-60's truths 80–99 the
    whole loop's cuts and the updates whose recommended depth lay above the truth were the same with and without
    them (``docs/design/shop.md``)."""
    k = int(np.argmin(np.abs(grid - rec["rpm"])))
    own = _own_limits(prior, z, f, grid, lim, k, lobe_samples)
    w = _own_weights_at(prior, z, f, grid[k], own, cuts, kw, boundary_width) if not lobe_samples else None
    srt_i = np.argsort(own, kind="stable")
    srt = own[srt_i]
    if w is None:
        # the deepest own limit with at most 5 % of the samples at or below it, as the risk rule's: an interpolated
        # quantile sat up to one sample above it (P(stable) 0.947 claimed as 0.95 with 150 samples)
        kq = int(math.floor(0.05 * own.size + 1e-9))
    else:  # the same with the weights: the deepest own limit with at most 5 % of the weight at or below it
        kq = int(np.searchsorted(np.cumsum(w[srt_i]) / w.sum(), 0.05 + 1e-9, side="right"))
    q = float(srt[kq - 1]) if kq >= 1 else float(srt[0] * (1 - 1e-9))
    out = dict(rec, own_sdm_p05_m=q if np.isfinite(q) else None, own_sdm_held_out=not lobe_samples)
    if np.isfinite(q) and q < rec["depth_m"]:
        out["depth_m"] = q
    above = own > out["depth_m"]
    out["p_stable"] = float(np.mean(above) if w is None else np.sum(w[above]) / w.sum())
    return out


def _own_weights_at(prior, z, f, rpm, own, cuts, kw, boundary_width):
    """Weights (S,) of posterior samples ``z`` by the cuts within 0.4 % of ``rpm`` with their own SDM limits ``own``
    (S,) at ``rpm`` over the sampling's likelihood (``kw``: its log_ratio and boundary width per cut); None where no
    cut lies there (or no weight is finite: the likelihood's floors make that unreachable)."""
    near = [i for i, c in enumerate(cuts) if abs(c.rpm / rpm - 1.0) <= 0.004] if kw is not None else []
    if not near:
        return None
    P = prior.sigma.size
    C = len(cuts)
    th = prior.theta(z[:, :P])
    kw = _at(kw, z)
    mu, sd = kw["label_offset"]
    g_med, g_sd = kw["label_growth"]
    extra = dict(label_offset=mu + sd * z[:, P], label_growth=g_med * np.exp(g_sd * z[:, P + 1]))
    lr0 = np.broadcast_to(np.asarray(kw.get("log_ratio", 0.0), float), (z.shape[0], C)).copy()
    bw0 = np.broadcast_to(np.asarray(kw["boundary_width"], float), (C,)).copy()
    a_c = limit_at_speeds(prior, th, np.array([cuts[i].rpm for i in near]), f)[0]  # zero-order, (S, n)
    lr1, bw1 = lr0.copy(), bw0.copy()
    with np.errstate(divide="ignore", invalid="ignore"):
        lr1[:, near] = np.log(own)[:, None] - np.log(a_c)  # the own limit at rpm stands for the cuts' speeds
    bw1[near] = boundary_width
    lw = (log_likelihood(prior, th, cuts, **dict(kw, **extra, log_ratio=lr1, boundary_width=bw1))
          - log_likelihood(prior, th, cuts, **dict(kw, **extra, log_ratio=lr0, boundary_width=bw0)))
    lw = np.where(np.isfinite(lw), lw, -np.inf)
    if not np.isfinite(lw).any():
        return None
    return np.exp(lw - lw.max())


def _first_cut_own(prior, z, f, grid, lim, nxt, bound):
    """The first cut's P(chatter) from the lobe samples' own SDM limits at its speed (prior samples: their own
    limits are the model's answer), the depth lowered to the bound where they put it above.

    The prior's lobes carry one of ``sdm_refs`` references' SDM/ZOA ratios per sample: four ratios estimate the
    correction at a speed to a few %, and the rule picks the speed and depth where that estimate is most
    productive — where it is likely too high. Measured (2026-11-27; 8–10 seeds, 100 truths from the prior each):
    first cuts that claimed P(chatter) 0.28 chattered for 0.37 of the truths on the example tool and 0.34 on
    EM16-50 (0.29 on the Cornelius case); with this check 0.28–0.30 claimed, 0.27–0.28 realised (``docs/design/
    shop.md``). It costs one search per lobe sample at one speed, all samples together
    (:func:`~toolpoint.stability.sdm_limit_near_many`): on EM16-50 1.9–2.3 s CPU of an 11.3–11.8 s prior update,
    against 3.4–3.6 s of 14.8–15.1 s one sample at a time (2026-11-30, two ``rng`` seeds, the same proposals)."""
    own = _own_limits(prior, z, f, grid, lim, int(np.argmin(np.abs(grid - nxt["rpm"]))))
    d = nxt["depth_m"]
    p = float(np.mean(own <= d))
    out = dict(nxt)
    if p > bound + 1e-9:
        kq = int(math.floor(bound * own.size + 1e-9))
        srt = np.sort(own)
        d = float(srt[kq - 1]) if kq >= 1 else float(srt[0] * (1 - 1e-9))
        p = float(np.mean(own <= d))
    out.update(depth_m=d, p_chatter=p)
    return out


def _carry(resid, grid, u, kernel=0.02):
    """Residuals at the speeds u (·, U) carried to the grid (·, G): Gaussian weights in the relative speed
    difference (width ``kernel``), normalised where they add up to more than one — the residual itself at a
    lone cut speed, fading to 0 a few ``kernel`` away."""
    k = np.exp(-0.5 * ((grid[:, None] / u[None, :] - 1) / kernel) ** 2)  # (G, U)
    return resid @ k.T / np.maximum(1.0, k.sum(axis=1))[None, :]


def _default_grid(prior: ModalPrior) -> np.ndarray:
    """200 speeds over the prior's ``rpm_range``, else from the 5th to beyond the 0th lobe of its modes."""
    if prior.rpm_range is not None:
        return np.linspace(*prior.rpm_range, 200)
    N = prior.cutting.teeth
    f = np.asarray(prior.freq_hz)
    lo = 60 * f.min() / (N * 5.5)
    hi = 60 * f.max() / (N * 0.7)
    return np.linspace(lo, hi, 200)


def _limits(prior, theta, f, grid):
    """Zero-order limits (S, G) of the samples: the limit scales as 1/K_t at fixed K_r (H scaled by K_t / K_t0),
    and K_r (small spread) is taken per quartile bin at the bin's median."""
    from dataclasses import replace

    H = receptance(prior, theta, f)
    out = np.empty((theta.shape[0], grid.size))
    m = prior.modes
    kt0 = prior.cutting.tangential_coeff
    kt, kr = theta[:, 3 * m], theta[:, 3 * m + 1]
    edges = np.quantile(kr, np.linspace(0, 1, 5))
    which = np.clip(np.searchsorted(edges, kr, "right") - 1, 0, 3)
    for b in range(4):  # four bins, not a loop over samples
        sel = which == b
        if sel.any():
            cut = replace(prior.cutting, radial_ratio=float(np.median(kr[sel])))
            out[sel] = zoa_limits(f, H[sel] * (kt[sel, None] / kt0), cut, grid)
    return out


def _wquantile_width(vals_sorted, w):
    """Log 5–95 % width ln(a₉₅/a₀₅) of the weighted samples: rows of ``w`` (C, S) in the order of ``vals_sorted``."""
    c = np.cumsum(w, axis=1)
    c /= c[:, -1:]
    lo = vals_sorted[np.minimum((c < 0.05).sum(axis=1), vals_sorted.size - 1)]
    hi = vals_sorted[np.minimum((c < 0.95).sum(axis=1), vals_sorted.size - 1)]
    return np.log(hi / lo)


def _median_ratio(q50, grid, k, rpm) -> float:
    """q50 at grid[k] over q50 at ``rpm`` (interpolated): moves a cut's depth to a neighbouring speed (1 where either
    median is not finite)."""
    r = q50[k] / np.interp(rpm, grid, q50)
    return float(r) if np.isfinite(r) and r > 0 else 1.0


def _next_info(lim, grid, j_rec, risk, width, eps, chatter_cost=0.0, cuts=(), min_step=0.0, miss_rate=0.0,
               offset=None, skip_repeats=False, creep_span=0.005, step_until_chatter=False, n_speeds=6):
    """The ``"info"`` rule: min expected relative band width at the recommended speed, P(chatter) ≤ risk —
    or a step of ``min_step`` (log) above the highest stable cut near that speed (±``creep_span``, depths moved
    by the posterior median's ratio), where the risk bound stops short of it: while no cut has chattered
    (``step_until_chatter``; ``"near"``: no cut near that speed), else once the two highest there crept closer
    than the step (module docstring).
    ``skip_repeats``: no candidate whose outcome an earlier cut at its speed already gave.
    ``offset(ks) -> (S, len(ks))``: each sample's label offset at the speeds grid[ks] (the outcome heard is that of
    a_lim e^δ; the risk is the cut's own, at a_lim)."""
    from scipy.special import ndtr

    if offset is None:
        def offset(ks):
            return np.zeros((lim.shape[0], len(ks)))

    q50 = np.quantile(lim, 0.5, axis=0)
    score = np.where(np.isfinite(q50), grid * q50, -np.inf)
    speeds = np.unique(np.r_[np.argsort(-score)[:n_speeds], j_rec]).astype(int)
    off = offset(speeds)  # (S, len(speeds)): one call for all the candidate speeds
    levels = np.linspace(0.02, risk, 12)
    target = lim[:, j_rec]
    order = np.argsort(target)
    ts = np.where(np.isfinite(target[order]), target[order], 1e9)
    cand = []
    for ki, k in enumerate(speeds):  # a few speeds; vectorised over depths and samples
        depths = np.quantile(lim[:, k], levels)
        ok = np.isfinite(depths) & (depths > 0)
        if not ok.any():
            continue
        depths = depths[ok]
        near = [c for c in cuts if abs(c.rpm / grid[k] - 1) <= 0.005]
        if skip_repeats and near:
            a_lo = max((c.depth_m for c in near if c.stable), default=0.0)
            a_hi = min((c.depth_m for c in near if not c.stable), default=np.inf)
            depths = depths[(depths > a_lo) & (depths < a_hi)]
        n_capped = depths.size
        # the cuts within ±creep_span of this speed, each moved to it by the posterior median's ratio between the two
        # speeds: the rule wanders over neighbouring grid speeds (0.5 % apart), and a creep there went unseen
        around = [(c, c.depth_m * _median_ratio(q50, grid, k, c.rpm)) for c in cuts
                  if abs(c.rpm / grid[k] - 1) <= creep_span]
        st = sorted(a for c, a in around if c.stable)
        a_s = st[-1] if st else None
        if step_until_chatter == "near":  # no chatter near this speed: its bracket has no upper side yet
            crept = bool(st) and all(c.stable for c, _ in around)
        elif step_until_chatter:  # no upper side to the bracket yet: climb at least a step a cut
            crept = bool(st) and all(c.stable for c in cuts)
        else:
            crept = len(st) >= 2 and st[-1] < st[-2] * math.exp(min_step)
        if min_step > 0 and a_s is not None and crept and (not depths.size or depths[-1] < a_s * math.exp(min_step)):
            step = a_s * math.exp(min_step)
            if not any(not c.stable and a <= step for c, a in around):  # not past a chatter already heard
                depths = np.r_[depths, step]
        if not depths.size:
            continue
        with np.errstate(divide="ignore"):
            x = (np.log(lim[None, :, k]) - np.log(depths[:, None])) / width  # (C, S)
        ps = eps + (1 - 2 * eps) * ndtr(np.where(np.isfinite(x), x, 50.0))
        p_stable = ps.mean(axis=1)  # the risk is the cut's, not the label's
        xh = x + off[None, :, ki] / width
        ph = eps + (1 - 2 * eps) * ndtr(np.where(np.isfinite(xh), xh, 50.0))
        ph = ph + miss_rate * (1 - ph)  # P(heard stable): the outcomes the posterior will see
        p_heard = ph.mean(axis=1)
        ws, wc = ph[:, order], (1 - ph)[:, order]
        exp_w = p_heard * _wquantile_width(ts, ws) + (1 - p_heard) * _wquantile_width(ts, wc)
        for i, (d, pst, e) in enumerate(zip(depths, p_stable, exp_w)):
            cand.append((float(e + chatter_cost * (1 - pst)), -float(grid[k] * d), int(k), float(d), float(1 - pst),
                         i >= n_capped))
    if not cand:  # every candidate repeats a known outcome (skip_repeats): as without the skip, and said
        out = _next_info(lim, grid, j_rec, risk, width, eps, chatter_cost, cuts, min_step, miss_rate, offset,
                         creep_span=creep_span, step_until_chatter=step_until_chatter, n_speeds=n_speeds)
        out["description"] += " (every such cut repeats one already made at its speed: this one too)"
        return dict(out, repeat=True)
    cand = [c for c in cand if c[4] <= risk + 1e-9 or c[5]] or cand
    e, _, k, d, pc, stepped = min(cand)
    now = float(_wquantile_width(ts, np.ones((1, ts.size)))[0])
    return {"rule": "info", "risk": risk, "rpm": float(grid[k]), "depth_m": d, "p_chatter": pc,
            "expected_log_width": e, "log_width_now": now, "stepped": bool(stepped), "repeat": False,
            "description": "the cut that most reduces the expected relative 5–95 % width of the limit at the "
                           "recommended speed, " + ("at that speed" if n_speeds == 0 else "among productive speeds")
                           + f", with P(chatter) ≤ {risk:g}"
                           + ((f" or, until a cut chatters near its speed, a step of ×{math.exp(min_step):.3f} "
                               "above the highest stable cut there" if step_until_chatter == "near" else
                               f" or, until the first chatter, a step of ×{math.exp(min_step):.3f} above the "
                               "highest stable cut near its speed" if step_until_chatter else
                               f" or, where two stable cuts crept, a step of ×{math.exp(min_step):.3f} above the "
                               "highest") if min_step > 0 else "")
                           + (" (this one: the step)" if stepped else "")}
