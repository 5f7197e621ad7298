"""Accuracy and speed of ``toolpoint tap`` on a synthetic impact record (prints; not a test).

    .venv/bin/python benchmarks/bench_tap.py

A known 3-mode system (tests/tap_synth.py: response in closed form, not from an
FRF), half-sine force pulses, white noise on both channels, five hits of which
hit 4 is a double hit. Targets: FRF within 1 % of the exact receptance at the
peaks, coherence ≥ 0.99 there, the double hit flagged.
"""

from __future__ import annotations

import sys
import time
import warnings
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests"))
import tap_synth as S  # noqa: E402

from toolpoint.io.impact import Record, impact_frf  # noqa: E402


def at_peaks(frf, exact):
    rows = []
    for fn in S.FN:
        k = int(np.argmin(abs(frf.freq_hz - fn)))
        k = k - 5 + int(np.argmax(abs(exact[k - 5:k + 6])))
        rows.append((frf.freq_hz[k], abs(frf.values[k] / exact[k] - 1), k))
    return rows


def main():
    print("case                         est  hits used   f_peak Hz  |H/H_exact - 1|  coherence")
    for fs, noise in ((51200.0, (0.002, 0.002)), (51200.0, (0.0, 0.0)), (25600.0, (0.002, 0.002))):
        t, f, a = S.record(fs=fs, noise=noise)
        for drop in (True, False):
            for est in ("H1", "H2"):
                with warnings.catch_warnings(record=True) as w:
                    warnings.simplefilter("always")
                    t0 = time.perf_counter()
                    res = impact_frf(Record(t, f, a, source="synth"), estimator=est, drop_bad=drop)
                    sec = time.perf_counter() - t0
                flagged = [h.number for h in res.hits if h.double_at_s is not None]
                for fp, err, k in at_peaks(res.frf, S.exact_receptance(res.frf.freq_hz)):
                    print(f"fs={fs:7.0f} noise={noise[0]:.3f} {'drop' if drop else 'keep'}  {est}  "
                          f"{len(res.hits)}  {res.used!s:14} {fp:9.2f}  {err:10.2e}  {res.coherence[k]:.6f}")
                print(f"    double hit flagged: {flagged}; warnings: {len(w)}; {sec * 1e3:.0f} ms for {t.size} samples")
    # exponential window: estimate vs the exact FRF with poles moved by -1/tau
    t, f, a = S.record(fs=51200.0, hits=((0.05, 100.0),), double=None, duration=0.3, noise=(0.0, 0.0))
    lam, amp = S.poles()
    for tau in (0.1, 0.02):
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            res = impact_frf(Record(t, f, a), exp_window_s=tau)
        s = 2j * np.pi * res.frf.freq_hz[:, None]
        lam2 = lam - 1 / tau
        exact = np.sum(amp / (s - lam2) + np.conj(amp) / (s - np.conj(lam2)), axis=1)
        errs = [f"{e:.1e}" for _, e, _ in at_peaks(res.frf, exact)]
        print(f"exp window tau={tau} s: |H/H_exact(poles - 1/tau) - 1| at peaks {errs}; added zeta "
              f"{[round(float(z), 5) for z in res.added_damping(S.FN)]}")


if __name__ == "__main__":
    main()
