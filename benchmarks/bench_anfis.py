"""Speed of ANFIS training at the size of Čiča et al.: 2 inputs, 3×7 Gaussian MFs
(21 rules, first order), 148 samples, 100 epochs. Target: < 1 s on one core.

Run:  python benchmarks/bench_anfis.py [--repeat N] [--profile]
(set OMP_NUM_THREADS=1 / OPENBLAS_NUM_THREADS=1 to pin the BLAS to one core).
"""

from __future__ import annotations

import argparse
import cProfile
import pstats
import time

import numpy as np

from toolpoint.learning.anfis import ANFIS


def make_data(n=148, seed=0):
    """Synthetic joint stiffness kt (N/m) vs tool diameter (mm) and overhang (mm)."""
    rng = np.random.default_rng(seed)
    d = rng.uniform(6.0, 25.0, n)
    L = rng.uniform(30.0, 120.0, n)
    kt = 1e7 * (d / 10.0) ** 2.5 * (60.0 / L) ** 1.5 * (1 + 0.02 * rng.standard_normal(n))
    return np.column_stack([d, L]), kt


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeat", type=int, default=5)
    ap.add_argument("--profile", action="store_true")
    args = ap.parse_args(argv)
    X, y = make_data()
    model = ANFIS(n_mfs=(3, 7), mf="gauss", order=1, epochs=100)
    model.fit(X, y)  # warm-up (imports, BLAS init)
    times = []
    for _ in range(args.repeat):
        t0 = time.perf_counter()
        model.fit(X, y)
        times.append(time.perf_counter() - t0)
    best = min(times)
    print(f"ANFIS fit: 2 inputs, 3x7 gauss MFs (21 rules, order 1), {X.shape[0]} samples, 100 epochs")
    print(f"  best of {args.repeat}: {best:.3f} s   median: {np.median(times):.3f} s   "
          f"({1e3 * best / 100:.2f} ms/epoch)")
    print(f"  final training RMSE {model.history_['train_rmse'].min():.4g} N/m (target std {y.std():.4g})")
    t0 = time.perf_counter()
    for _ in range(100):
        model.predict(X)
    print(f"  predict {X.shape[0]} samples: {1e3 * (time.perf_counter() - t0) / 100:.3f} ms")
    print("  requirement < 1 s:", "OK" if best < 1.0 else "NOT MET")
    if args.profile:
        cProfile.runctx("model.fit(X, y)", globals(), {"model": model, "X": X, "y": y}, "/tmp/anfis.prof")
        pstats.Stats("/tmp/anfis.prof").sort_stats("cumulative").print_stats(15)


if __name__ == "__main__":
    main()
