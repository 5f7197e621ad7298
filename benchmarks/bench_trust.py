"""The trusted band (toolpoint.trust): detected lower edge against the noise/signal crossing, false cuts, cost.

Synthetic tool-point receptances (tests/base/test_trust.py: modes 650, 1056, 2400 Hz, 0–5000 Hz at 1 Hz)
with complex white noise in accelerance (σ_A per part) divided by −ω². The reference f_c is where
the known noise level √2 σ_A/ω² meets the known clean |H| — independent of the detector, which
sees only the noisy data. Also: clean FRFs and noise white in the receptance must keep their band.

Run:  OMP_NUM_THREADS=1 python benchmarks/bench_trust.py [--seeds N]
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import numpy as np

from toolpoint.frf import FRF
from toolpoint.trust import trusted_band

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests"))
from test_trust import crossing_hz, noisy_toolpoint, toolpoint_receptance  # noqa: E402


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seeds", type=int, default=20)
    a = ap.parse_args(argv)
    print("sigma_A [m/(N s²)]  f_c [Hz]  detected lower edge / f_c over seeds: median (min–max)   expected √2")
    for sigma in (0.01, 0.04, 0.2, 1.0):
        ratios = []
        for seed in range(a.seeds):
            f, clean, noisy = noisy_toolpoint(seed, sigma)
            ratios.append(trusted_band(FRF(f, noisy)).lo_hz / crossing_hz(f, clean, sigma))
        fc = crossing_hz(f, clean, sigma)
        print(f"{sigma:18g}  {fc:8g}  {np.median(ratios):.2f} ({min(ratios):.2f}–{max(ratios):.2f})")

    f = np.arange(0.0, 5001.0)
    clean = toolpoint_receptance(f)
    cut = 0
    for seed in range(a.seeds):
        rng = np.random.default_rng(seed)
        for level in (0.01, 0.05):
            n = level * np.abs(clean).max() * (rng.standard_normal(f.size) + 1j * rng.standard_normal(f.size))
            cut += trusted_band(FRF(f, clean + n)).reason != ""
    print(f"noise white in the receptance (1 % and 5 % of the peak), {2 * a.seeds} FRFs: {cut} cut")

    _, _, noisy = noisy_toolpoint(0)
    frf = FRF(f, noisy)
    t0 = time.process_time()
    for _ in range(20):
        trusted_band(frf)
    print(f"cost: {1e3 * (time.process_time() - t0) / 20:.2f} ms CPU per 5001-point FRF")


if __name__ == "__main__":
    main()
