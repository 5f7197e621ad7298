"""A virtual test campaign: truth drawn from the prior, cuts made and judged, lobes updated, next cut proposed.

Loop (seeded by one ``numpy.random.Generator``):

1. θ* ~ prior (the "real" tool and K_t);
2. update the prior with the cuts so far (:func:`toolpoint.shop.update.update`), propose the next cut;
3. stop when the posterior 5–95 % band holds the true limit at ≥ ``coverage`` of the speeds and its relative
   width (a₉₅ − a₀₅)/a₅₀ at the recommended speed is ≤ ``width`` — or after ``max_cuts``;
4. make the proposed cut with ``shop(theta_true, rpm, depth_m, rng) -> TestCut`` and go to 2.

Shops: :func:`zoa_shop` labels a cut by the true zero-order limit (and gives the true chatter frequency) —
the update's own forward model, a check of the sampler and the rule; a time-domain shop (simulation,
synthetic microphone record, :func:`toolpoint.shop.analyse_cut`) is :func:`simulated_shop` where the
simulation package exists.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .model import ModalPrior, limit_at_speeds
from .update import TestCut, _limits, update

__all__ = ["CampaignResult", "virtual_campaign", "zoa_shop"]


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
    """

    theta_true: np.ndarray
    cuts: tuple
    converged_after: int | None
    chatter_cuts: int
    coverage: tuple
    width: tuple
    update_cpu_s: tuple


def zoa_shop(prior: ModalPrior):
    """A shop whose cuts chatter exactly above the true zero-order limit, at the true chatter frequency."""
    def shop(theta_true, rpm, depth_m, rng):
        a, fc = limit_at_speeds(prior, theta_true[None, :], [rpm])
        stable = bool(depth_m < a[0, 0])
        return TestCut(float(rpm), float(depth_m), stable, None if stable else float(fc[0, 0]))
    return shop


def virtual_campaign(prior: ModalPrior, *, rng: np.random.Generator, shop=None, max_cuts: int = 10,
                     coverage: float = 0.9, width: float = 0.2, theta_true=None, true_limit=None,
                     **update_kw) -> CampaignResult:
    """Run one virtual campaign (see the module docstring); ``update_kw`` go to :func:`update`.

    ``true_limit(theta_true, rpm_grid) -> limit_m`` is the truth the coverage is judged against (default: the
    zero-order limit of θ*, the update's own model; a time-domain shop's truth is the SDM's).
    """
    shop = zoa_shop(prior) if shop is None else shop
    if theta_true is None:
        theta_true = prior.theta((rng.standard_normal(prior.sigma.size) * (prior.sigma > 0))[None, :])[0]
    cuts, cov_h, wid_h, cpu = [], [], [], []
    converged = None
    true_lim = None
    for n in range(max_cuts + 1):
        post = update(prior, cuts, rng=rng, **update_kw)
        if true_lim is None:
            true_lim = (_limits(prior, theta_true[None, :], prior.freq_grid(), post.rpm)[0] if true_limit is None
                        else np.asarray(true_limit(theta_true, post.rpm), float))
        q = post.limit_q_m
        inside = (q[0] <= true_lim * 1.0000001) & (true_lim <= q[2] * 1.0000001)
        cov = float(inside.mean())
        j = int(np.argmin(np.abs(post.rpm - post.recommended["rpm"])))
        wid = float((q[2, j] - q[0, j]) / q[1, j])
        cov_h.append(cov)
        wid_h.append(wid)
        cpu.append(post.cpu_s)
        if cov >= coverage and wid <= width:
            converged = n
            break
        if n == max_cuts:
            break
        nc = post.next_cut
        cuts.append(shop(theta_true, nc["rpm"], nc["depth_m"], rng))
    chat = sum(not c.stable for c in cuts)
    return CampaignResult(np.asarray(theta_true), tuple(cuts), converged, chat, tuple(cov_h), tuple(wid_h),
                          tuple(cpu))
