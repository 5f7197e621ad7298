"""A virtual test campaign: truth drawn from the prior, cuts made and judged, lobes updated, next cut proposed.

Loop (seeded by one ``numpy.random.Generator``):

1. θ* ~ prior (the "real" tool and K_t);
2. update the prior with the cuts so far (:func:`toolpoint.shop.update.update`), propose the next cut;
3. stop when the posterior 5–95 % band holds the true limit at ≥ ``coverage`` of the speeds and its relative
   width (a₉₅ − a₀₅)/a₅₀ at the recommended speed is ≤ ``width`` — or after ``max_cuts``;
4. make the proposed cut with ``shop(theta_true, rpm, depth_m, rng, duration_s) -> TestCut``, ``duration_s`` the
   proposal's (``next_cut["duration_s"]``: the cuts' own median, lengthened where ``update``'s ``audible_margin``
   asks), as a user who follows every proposal cuts (the CLI prints "for at least … s"), and go to 2. Until
   2026-12-01 the shop cut its usual length unless the proposal was lengthened, so a proposal after a lengthened
   cut (the cuts' median, itself long) was made short.

Shops: :func:`zoa_shop` labels a cut by the true zero-order limit (and gives the true chatter frequency) —
the update's own forward model, a check of the sampler and the rule; :func:`simulated_shop` makes the cut in
the time domain (:func:`toolpoint.simulation.simulate_milling`: the tool leaves the cut, chatter saturates),
records it with a microphone and judges the record with :func:`toolpoint.shop.analyse_cut` — the whole
loop; its truth is the semi-discretisation limit (:func:`sdm_limit`), not the zero-order one.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from .model import ModalPrior, limit_at_speeds, sdm_limits
from .update import TestCut, _limits, ring_fields, update

__all__ = ["CampaignResult", "virtual_campaign", "zoa_shop", "simulated_shop", "sdm_limit", "microphone_record"]


@dataclass(frozen=True)
class CampaignResult:
    """Outcome of :func:`virtual_campaign`.

    Attributes
    ----------
    theta_true : ndarray, shape (P,)
    cuts : tuple of TestCut
        The cuts made, in order.
    converged_after : int or None
        Number of cuts after which the stopping rule held (None: not within ``max_cuts``).
    chatter_cuts : int
        Chattering cuts among those made before convergence.
    coverage, width : tuple of float
        After each update (0, 1, … cuts): share of speeds whose true limit lies in the 5–95 % band, and the
        relative band width at the recommended speed.
    update_cpu_s : tuple of float
        CPU time of each update.
    below_recommended : tuple of bool
        After each update: the true limit at the recommended speed lies below the recommended depth (the 5 %
        limit: a calibrated band has this for 5 % of the truths).
    coverage_near, coverage_away : tuple of float
        After each update: the coverage over the speeds within ±3 % of a cut made so far (nan before the first
        cut) and over the others.
    miss_low, miss_high : tuple of float
        After each update: the share of speeds whose true limit lies below the band's 5 % limit (the band
        over-confident on the unsafe side) and above its 95 % limit.
    """

    theta_true: np.ndarray
    cuts: tuple
    converged_after: int | None
    chatter_cuts: int
    coverage: tuple
    width: tuple
    update_cpu_s: tuple
    below_recommended: tuple = ()
    coverage_near: tuple = ()
    coverage_away: tuple = ()
    miss_low: tuple = ()
    miss_high: tuple = ()
    p_chatter_at_truth: tuple = ()
    next_p_chatter: tuple = ()
    parameter_rank: tuple = ()


def zoa_shop(prior: ModalPrior):
    """A shop whose cuts chatter exactly above the true zero-order limit, at the true chatter frequency."""
    def shop(theta_true, rpm, depth_m, rng, duration_s=None):  # the labels need no time to grow here
        a, fc = limit_at_speeds(prior, theta_true[None, :], [rpm])
        stable = bool(depth_m < a[0, 0])
        return TestCut(float(rpm), float(depth_m), stable, None if stable else float(fc[0, 0]))
    return shop


def sdm_limit(prior: ModalPrior):
    """``true_limit`` for :func:`virtual_campaign` with a time-domain shop: the semi-discretisation limit of θ*
    (the same tool in x and y), m, searched as deep as the pockets go (:func:`~toolpoint.shop.model.sdm_limits`)."""
    def limit(theta, rpm):
        return sdm_limits(prior, theta, rpm)[0]
    return limit


def microphone_record(velocity, rate: float, rng: np.random.Generator, *, air_s: float = 1.0,
                      noise: float = 0.05) -> np.ndarray:
    """A microphone record of a simulated cut: ``air_s`` of air cut, the cut, ``air_s`` of air cut (the detector
    takes a quiet run shorter than 0.5 s for a pause in the cut, not an air cut).

    The microphone hears the tool's velocity (x + y) in the cut, over room noise — white, ``noise`` × the
    cut's RMS, the same in air and in the cut (what the detector's air-cut reference learns) — scaled to a
    peak of 0.8 full scale. No fans or spindle lines: a richer shop is passed to :func:`simulated_shop` as
    ``record`` (the tests' ``milling_sim.microphone``: fans, spindle runout, pink room noise).
    """
    v = np.asarray(velocity, float)
    v = v - v.mean()
    na = int(air_s * rate)
    x = np.concatenate([np.zeros(na), v, np.zeros(na)])
    x = x + noise * float(np.std(v)) * rng.standard_normal(x.size)
    peak = float(np.max(np.abs(x))) if x.size else 0.0
    return 0.8 * x / peak if peak > 0 else x  # a silent cut stays silent (the detector refuses it)


def simulated_shop(prior: ModalPrior, *, revolutions: int = 250, rate: float = 44100.0, record=None,
                   detector: dict | None = None, seed_level: float = 0.01, force_noise: float = 0.0):
    """A shop whose cuts are simulated in the time domain, recorded and judged by the chatter detector.

    Parameters
    ----------
    prior : ModalPrior
        The tool family (modes per θ, the cut).
    revolutions : int, default 250
        Revolutions simulated per cut from the steady cut (a seeded perturbation), all of them recorded:
        0.6–3 s at 5000–25000 rpm, long enough for the detector's windows.
    rate : float, default 44100
        Record sample rate, Hz.
    record : callable, optional
        ``record(result, rpm, teeth, rng) -> (samples, rate)`` from the
        :class:`~toolpoint.simulation.time_domain.SimulationResult` (one point); default
        :func:`microphone_record` of the tool's velocity.
    detector : dict, optional
        Options of :func:`toolpoint.shop.analyse_cut` (``full_scale`` 1.0 unless given: a sound file's; ``None``
        for a record in physical units, an accelerometer's m/s²).
    seed_level : float, default 0.01
        Kick of the modes at the start of the cut, relative to the forced response: a shop cut's modes are
        excited by the entry and the cutting noise (the simulation's own 1e-6 measures linear growth, and a cut
        barely past the limit would not chatter audibly within the record).
    force_noise : float, default 0
        Relative random fluctuation of the cutting force (``simulate_milling(force_noise=…)``: 4–9 % measured in
        turning): it drives the tool's modes in a stable cut, so that a cut near the limit sounds as a real one
        might (a noise-driven precursor at the chatter frequency). 0 keeps the cuts noise-free, as every whole-loop
        figure before 2026-11-29 was measured.

    Returns
    -------
    callable
        ``shop(theta, rpm, depth_m, rng, duration_s=None) -> TestCut`` with the detector's verdict, chatter
        frequency, growth rate and a stable cut's ring (:mod:`toolpoint.shop.growth`); a cut lasts ``revolutions``,
        or ``duration_s`` (s) when that is longer.
    """
    from ..simulation import sensor_signal, simulate_milling
    from .detect import analyse_cut

    opts = dict(detector or {})

    def default_record(res, rpm, teeth, rng):
        _, v = sensor_signal(res, 0, kind="microphone", rate=rate, noise=0.0)  # velocity x + y at the audio rate
        return microphone_record(v, rate, rng), rate

    make = default_record if record is None else record

    def shop(theta, rpm, depth_m, rng, duration_s=None):
        mm, cut = prior.tool(theta)
        revs = revolutions if duration_s is None else max(revolutions, math.ceil(duration_s * float(rpm) / 60.0))
        res = simulate_milling(mm, mm, cut, rpm=[float(rpm)], depth_m=[float(depth_m)], revolutions=revs,
                               seed=int(rng.integers(1 << 30)), seed_level=seed_level, force_noise=force_noise)
        x, fs = make(res, float(rpm), cut.teeth, rng)
        r = analyse_cut(x, fs, rpm=float(rpm), teeth=cut.teeth, **{"full_scale": 1.0, **opts})
        return TestCut(float(rpm), float(depth_m), r.verdict == "stable", r.chatter_hz,
                       duration_s=revs * 60.0 / float(rpm), warnings=tuple(r.criterion.get("warnings", ())),
                       growth_per_s=None if r.growth is None else r.growth.rate_per_s, **ring_fields(r))
    return shop


def virtual_campaign(prior: ModalPrior, *, rng: np.random.Generator, shop=None, max_cuts: int = 10,
                     coverage: float = 0.9, width: float = 0.2, theta_true=None, true_limit=None, stop: bool = True,
                     **update_kw) -> CampaignResult:
    """Run one virtual campaign (see the module docstring); ``update_kw`` go to :func:`update`.

    ``stop=False`` makes all ``max_cuts`` cuts (the same cuts, in the same random order, as a campaign that stops)
    and reports ``converged_after`` all the same: a campaign that stops when its band holds the truth selects the
    truths that go on, so the band's calibration after n cuts is read from campaigns that do not stop.

    ``true_limit(theta_true, rpm_grid) -> limit_m`` is the truth the coverage is judged against (default: the
    zero-order limit of θ*, the update's own model; a time-domain shop's truth is the SDM's).
    """
    shop = zoa_shop(prior) if shop is None else shop
    if theta_true is None:
        theta_true = prior.theta((rng.standard_normal(prior.sigma.size) * (prior.sigma > 0))[None, :])[0]
    cuts, cov_h, wid_h, cpu, below, near_h, away_h, low_h, high_h = [], [], [], [], [], [], [], [], []
    pit_h, p_next, rank_h = [], [], []
    converged = None
    true_lim = None
    for n in range(max_cuts + 1):
        post = update(prior, cuts, rng=rng, **update_kw)
        if true_lim is None:
            true_lim = (_limits(prior, theta_true[None, :], prior.freq_grid(), post.rpm)[0] if true_limit is None
                        else np.asarray(true_limit(theta_true, post.rpm), float))
        q = post.limit_q_m
        inside = (q[0] <= true_lim * 1.0000001) & (true_lim <= q[2] * 1.0000001)
        low, high = true_lim * 1.0000001 < q[0], q[2] * 1.0000001 < true_lim  # a NaN limit: neither, and not inside
        cov = float(inside.mean())
        low_h.append(float(low.mean()))
        pit_h.append(post.p_chatter(true_lim))
        rank = (post.parameter_samples < np.asarray(theta_true)[None, :]).mean(axis=0)
        rank_h.append(np.where(prior.sigma > 0, rank, np.nan))
        high_h.append(float(high.mean()))
        j = int(np.argmin(np.abs(post.rpm - post.recommended["rpm"])))
        wid = float((q[2, j] - q[0, j]) / q[1, j])
        cov_h.append(cov)
        wid_h.append(wid)
        cpu.append(post.cpu_s)
        below.append(bool(true_lim[j] < post.recommended["depth_m"]))
        near = (np.any(np.abs(post.rpm[:, None] / np.array([c.rpm for c in cuts])[None, :] - 1) <= 0.03, axis=1)
                if cuts else np.zeros(post.rpm.size, bool))
        near_h.append(float(inside[near].mean()) if near.any() else float("nan"))
        away_h.append(float(inside[~near].mean()) if (~near).any() else float("nan"))
        if converged is None and cov >= coverage and wid <= width:
            converged = n
            if stop:
                break
        if n == max_cuts:
            break
        nc = post.next_cut
        p_next.append(float(nc["p_chatter"]))
        # at least as long as proposed: the duration the rule's expected outcomes assumed
        cuts.append(shop(theta_true, nc["rpm"], nc["depth_m"], rng, nc["duration_s"]))
    chat = sum(not c.stable for c in (cuts if converged is None else cuts[:converged]))
    return CampaignResult(np.asarray(theta_true), tuple(cuts), converged, chat, tuple(cov_h), tuple(wid_h),
                          tuple(cpu), tuple(below), tuple(near_h), tuple(away_h), tuple(low_h), tuple(high_h),
                          tuple(pit_h), tuple(p_next), tuple(rank_h))
