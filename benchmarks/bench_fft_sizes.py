"""FFT at awkward lengths: why the hot paths of ``cut`` use :mod:`scipy.fft` and trim to a fast length.

    OMP_NUM_THREADS=1 .venv/bin/python benchmarks/bench_fft_sizes.py

:func:`toolpoint.shop.growth.ring_decay` evaluates its Whittle likelihood about 1400 times per reading, one complex
FFT each, of the decimated record's length — any length, often one with a large prime factor, where pocketfft falls
back to Bluestein's algorithm. NumPy before 2.0 (CI's floor runs 1.26) has the older C pocketfft, slower still there;
:mod:`scipy.fft` has the C++ one in every SciPy toolpoint supports. Prints CPU µs per transform for a few lengths by
both, the largest share a length loses when trimmed to the next fast length below it (``scipy.fft.next_fast_len``),
and the CPU time of ``ring_decay`` on a noise-driven mode (its docstring's example, 4 s at 20 kHz).
"""
import datetime
import os
import platform
import time

import numpy as np
import scipy
import scipy.fft as sfft


def per_call(f, x, n, **kw):
    f(x, **kw)
    t = time.process_time()
    for _ in range(n):
        f(x, **kw)
    return (time.process_time() - t) / n * 1e6


def main():
    print(f"# {platform.node()} {platform.machine()}, {datetime.datetime.now(datetime.UTC):%Y-%m-%d %H:%M} UTC, load "
          f"average {os.getloadavg()[0]:.2f}; numpy {np.__version__}, scipy {scipy.__version__}; CPU µs per call")
    rng = np.random.default_rng(0)
    for m in (4799, 4800, 9601, 9600):
        x = rng.standard_normal(m) + 1j * rng.standard_normal(m)
        print(f"complex FFT of {m} ({'fast' if sfft.next_fast_len(m) == m else 'awkward'} length): numpy "
              f"{per_call(np.fft.fft, x, 1000):.0f}, scipy {per_call(sfft.fft, x, 1000):.0f}")
    from toolpoint.shop.growth import fast_len_at_most, ring_decay

    worst = max(1 - fast_len_at_most(m) / m for m in range(200, 20001))
    print(f"trimmed to a fast length (lengths 200-20000): at most {100 * worst:.2f} % shorter")
    from scipy.signal import lfilter

    rate, w, z = 20000.0, 2 * np.pi * 830.0, 0.005
    r, th = np.exp(-z * w / rate), w * np.sqrt(1 - z * z) / rate
    y = lfilter([1.0], [1.0, -2 * r * np.cos(th), r * r], rng.standard_normal(int(4 * rate)))
    t = np.arange(y.size) / rate
    y = y / y.std() + 20 * np.sin(2 * np.pi * 100 * t) + 10 * np.sin(2 * np.pi * 800 * t)
    c0 = time.process_time()
    for _ in range(5):
        d = ring_decay(y, rate, rpm=6000, teeth=2, line_hz=835.0, start_s=0.0, end_s=4.0)
    print(f"ring_decay, a 4 s record at 20 kHz: {(time.process_time() - c0) / 5:.3f} s CPU per reading "
          f"(σ {d.rate_per_s:.1f} /s, closed form -26.1 /s)")


if __name__ == "__main__":
    main()
