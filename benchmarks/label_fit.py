"""Where the whole loop's shop hears chatter: probit fits of the labels against each truth's limit (prints; not a test).

    python benchmarks/label_fit.py LOG [LOG ...]

LOG is the output of ``bench_shop.py --only update --shops sim --verbose`` (one line per campaign). Each cut there is
printed as ``rpm/depth_mm`` + ``s`` or ``C`` (heard stable or chatter) + ``<a / a_lim>`` (the cut's depth over the
truth's SDM limit at its speed) + ``(duration)``. Per tool (the ``library prior`` line of its block, else the
Cornelius case) this prints the share of cuts heard as chatter in bins of a / a_lim, and two maximum-likelihood fits
of the label model of ``toolpoint.shop.update``, P(chatter) = ε + (1 − 2ε) Φ((ln(a / a_lim) − δ) / w), ε = ``update``'s
``label_noise`` (0.002):

* δ and w both free — where the labels' boundary lies and how sharp it is;
* w fixed at ``update``'s ``boundary_width`` (0.05 by default) — the δ that ``update``'s own likelihood would read from
  these labels (its mean and sd under a flat prior on a grid), the figure its ``label_offset`` prior stands for. This δ
  holds the growth term G / (κ t) too: the labels' whole offset.

A campaign printed in two logs (the same tool, seed and settings: a rerun with more cuts repeats the first ones) is
counted once.
"""

from __future__ import annotations

import re
import sys

import numpy as np
from scipy.optimize import minimize
from scipy.stats import norm


def _update_default(name):
    """``update``'s own default of one likelihood setting (one home: the fits use what ``update`` uses)."""
    import inspect

    from toolpoint.shop.update import update
    return inspect.signature(update).parameters[name].default


EPS = _update_default("label_noise")
W_UPDATE = _update_default("boundary_width")
BINS = (0.0, 0.9, 0.97, 1.0, 1.03, 1.06, 1.10, 1.20, np.inf)
_CUT = re.compile(r"(\d+)/([\d.]+)([sC])<([\d.]+)>\(([\d.]+)s\)")


def read(paths):
    """{tool: {(settings, seed, k): (a / a_lim, chatter)}} from the verbose lines of the logs (k the cut's place)."""
    out: dict = {}
    for p in paths:
        for block in open(p, encoding="utf-8").read().split("## update")[1:]:
            m = re.search(r"library prior (\S+?):", block)
            tool = m.group(1) if m else "Cornelius 2024 two-mode"
            # the run's settings (update options, force noise) from its header line: campaigns of other settings
            # on the same seeds are other campaigns
            setting = block.splitlines()[0].split(";", 1)[-1]
            for line in block.splitlines():
                s = re.match(r"\s+seed (\d+): .*?; cuts (.*?); width", line)
                if not s:
                    continue
                for k, (_, _, lab, r, _) in enumerate(_CUT.findall(s.group(2))):
                    out.setdefault(tool, {})[(setting, int(s.group(1)), k)] = (float(r), lab == "C")
    return out


def _nll(r, y, delta, w):
    """Negative log-likelihood of the labels y at depths r (a / a_lim); ``delta`` a number or an array of them."""
    d = np.asarray(delta, float)[..., None]
    p = np.clip(EPS + (1 - 2 * EPS) * norm.cdf((np.log(r) - d) / w), 1e-300, 1.0)
    return -(np.log(p[..., y]).sum(axis=-1) + np.log1p(-p[..., ~y]).sum(axis=-1))


def fit(r, y):
    """(δ, w) free by maximum likelihood; then δ's mean and sd with ``update``'s w (flat prior on a grid)."""
    res = minimize(lambda q: _nll(r, y, q[0], np.exp(q[1])), [0.02, np.log(0.03)], method="Nelder-Mead",
                   options={"xatol": 1e-5, "fatol": 1e-6})
    grid = np.linspace(-0.15, 0.2, 1401)
    ll = -_nll(r, y, grid, W_UPDATE)  # the whole grid at once
    p = np.exp(ll - ll.max())
    p /= p.sum()
    mean = float((grid * p).sum())
    return float(res.x[0]), float(np.exp(res.x[1])), mean, float(np.sqrt(((grid - mean) ** 2 * p).sum()))


def main(argv):
    if not argv:
        print(__doc__)
        return 2
    data = read(argv)
    print("tool | cuts (campaigns) | heard chatter at a/a_lim " + " / ".join(
        f"{lo:g}–{hi:g}" for lo, hi in zip(BINS[1:-2], BINS[2:-1])) + f" | δ, w free | δ with w = {W_UPDATE:g} (sd)")
    for tool, cuts in data.items():
        r = np.array([v[0] for v in cuts.values()])
        y = np.array([v[1] for v in cuts.values()])
        shares = []
        for lo, hi in zip(BINS[1:-2], BINS[2:-1]):
            sel = (r >= lo) & (r < hi)
            shares.append(f"{y[sel].mean():.2f} ({sel.sum()})" if sel.any() else "—")
        d, w, m, s = fit(r, y)
        n_camp = len({k[:2] for k in cuts})
        print(f"{tool} | {len(r)} ({n_camp}) | {' / '.join(shares)} | {d:.3f}, {w:.3f} | {m:.3f} ({s:.3f})")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
