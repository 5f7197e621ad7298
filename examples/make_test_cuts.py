"""Regenerate examples/shop/: a SYNTHETIC session of test cuts (not a measurement) for ``toolpoint update``.

    python examples/make_test_cuts.py

A shop's first test cuts on the tool of ``examples/shop/cornelius_prior.toml``, made as the virtual campaign makes
them (``toolpoint.shop.campaign``): a true tool drawn from the prior (seed below), each cut the one ``update``
proposed after the cuts before it (``toolpoint update --forward sdm`` on the table so far), simulated in the time domain
(``toolpoint.simulation``, 250 revolutions, the modes kicked at entry; 0.74 s where ``update`` asks at least 1 s
of the first cut: on this well-damped tool, κ ≈ 450 /s, chatter 5 % past the limit grows by e^17 in 0.74 s, and
the label term G/(κt) is 0.7 % against 0.6 %) and heard by a microphone: the tool's velocity
(x + y) at 44.1 kHz over white room noise (5 % of the quietest cut's RMS, in air and in the cut alike), one gain for
the whole session (the chattering cut is the loudest), 16-bit FLAC. The cuts sit one after the other in one record,
``session.flac``, 1.5 s of air between them, as a shop records a session; ``test_cuts.csv`` names each cut's part
(``start_s``, ``end_s``) and leaves ``result`` to the record. ``truth.json`` holds the true tool and its
semi-discretisation (SDM) limit at each cut's speed, which the tests judge the record's verdicts against.
"""

import json
import tempfile
from pathlib import Path

import numpy as np
import soundfile as sf

from toolpoint.shop.campaign import microphone_record, simulated_shop
from toolpoint.shop.model import sdm_limits
from toolpoint.shop.prior import read_modal_prior
from toolpoint.shop.update import read_test_cuts, update
from toolpoint.simulation import sensor_signal

HERE = Path(__file__).resolve().parent / "shop"
SEED = 1  # the true tool and the shop's noise: two stable cuts, then one that chatters (seeds 1–8 tried)
CUTS = 3
RATE = 44100.0
AIR_S = 1.5


def main(out: Path = HERE) -> None:
    """Write ``session.flac``, ``test_cuts.csv`` and ``truth.json`` into ``out`` (the prior is read from HERE)."""
    out = Path(out)
    prior = read_modal_prior(HERE / "cornelius_prior.toml")
    rng = np.random.default_rng(SEED)
    theta = prior.theta((rng.standard_normal(prior.sigma.size) * (prior.sigma > 0))[None, :])[0]
    heard = []

    def keep(res, rpm, teeth, rng):  # the virtual campaign's microphone, the cut kept for the session record
        _, v = sensor_signal(res, 0, kind="microphone", rate=RATE, noise=0.0)
        heard.append(v - v.mean())
        return microphone_record(v, RATE, rng), RATE  # judged alone as the virtual campaign judges it

    shop = simulated_shop(prior, rate=RATE, record=keep)
    cuts = []
    with tempfile.TemporaryDirectory() as tmp:
        for _ in range(CUTS):
            # the cut `toolpoint update` proposes (its defaults: --forward sdm, --seed 0) from the table so far, read as
            # the command reads it: the session of the cuts so far, each part analysed by `cut` (its duration in the
            # record, not the simulation's: 0.751 against 0.743 s moved the third proposal a grid speed)
            made = read_test_cuts(_write(Path(tmp), cuts, heard), teeth=prior.cutting.teeth) if cuts else []
            nc = update(prior, made, rng=np.random.default_rng(0), forward="sdm").next_cut
            cuts.append(shop(theta, float(round(nc["rpm"])), round(nc["depth_m"], 6), rng))
    _write(out, cuts, heard)
    lim = [float(sdm_limits(prior, theta, np.array([round(c.rpm)]))[0][0]) for c in cuts]
    (out / "truth.json").write_text(json.dumps({
        "note": "synthetic: the true tool of examples/make_test_cuts.py (seed %d) and its SDM limit at each cut" % SEED,
        "theta": [float(v) for v in theta],
        "cuts": [{"rpm": round(c.rpm), "depth_mm": round(1e3 * c.depth_m, 3), "sdm_limit_mm": round(1e3 * a, 4),
                  "heard_alone": "stable" if c.stable else "chatter", "chatter_hz": c.chatter_hz}
                 for c, a in zip(cuts, lim)]}, indent=1) + "\n")
    for c, a in zip(cuts, lim):
        print(f"{c.rpm:.0f} rpm {1e3 * c.depth_m:.3f} mm: {'stable' if c.stable else 'chatter'} "
              f"(SDM limit {1e3 * a:.3f} mm, ratio {c.depth_m / a:.3f})")
    print(f"wrote {out / 'session.flac'} ({(out / 'session.flac').stat().st_size / 1e3:.0f} kB, "
          f"{sf.info(out / 'session.flac').duration:.1f} s), test_cuts.csv, truth.json")


def _write(out: Path, cuts, heard) -> Path:
    """``session.flac`` of the cuts (each between 1.5 s of air) and ``test_cuts.csv`` naming their parts; the room
    noise from its own seed, so that a session of the first cuts is the whole session's beginning but for the gain."""
    air = np.zeros(int(AIR_S * RATE))
    parts, rows, t = [air], [], AIR_S
    for c, v in zip(cuts, heard):
        rows.append((c, t - 0.5 * AIR_S, t + v.size / RATE + 0.5 * AIR_S))
        parts += [v, air]
        t += v.size / RATE + AIR_S
    x = np.concatenate(parts)
    x = x + 0.05 * min(float(np.std(v)) for v in heard[:len(cuts)]) * np.random.default_rng(
        SEED + 1000).standard_normal(x.size)
    sf.write(out / "session.flac", 0.8 * x / np.abs(x).max(), int(RATE), subtype="PCM_16")
    lines = ["rpm,depth_mm,result,record,start_s,end_s"]
    lines += [f"{c.rpm:.0f},{1e3 * c.depth_m:.3f},,session.flac,{a:.2f},{b:.2f}" for c, a, b in rows]
    (out / "test_cuts.csv").write_text("\n".join(lines) + "\n")
    return out / "test_cuts.csv"


if __name__ == "__main__":
    main()
