"""Forward-model speed on the numerical case (examples/numerical_case.toml).

Prints: component receptances at 3001 frequencies (target < 50 ms on one core)
and re-coupling one holder–tool joint over 3001 frequencies, amortised over a
batch of 400 (target < 50 µs). Run with OMP_NUM_THREADS=1 for one core.
"""

from __future__ import annotations

import time
from pathlib import Path

import numpy as np

from toolpoint.dynamics.assembly import load_assembly
from toolpoint.dynamics.components import end_receptances
from toolpoint.dynamics.model import AssemblyModel

EXAMPLE = Path(__file__).resolve().parents[1] / "examples" / "numerical_case.toml"


def best_of(fn, repeat=9, clock=time.perf_counter):
    """(best, median) seconds of ``repeat`` runs. On a busy machine pass
    ``clock=time.process_time`` (CPU time of this process) — see --cpu."""
    times = []
    for _ in range(repeat):
        t = clock()
        fn()
        times.append(clock() - t)
    return min(times), float(np.median(times))


def main() -> None:
    import sys

    clock = time.process_time if "--cpu" in sys.argv else time.perf_counter
    print(f"clock: {'CPU time of this process' if clock is time.process_time else 'wall time'}")
    a = load_assembly(EXAMPLE)
    f = np.arange(1.0, 3002.0)  # 3001 frequencies

    def components():
        end_receptances(a.spindle, f, "end")
        end_receptances(a.holder, f)
        end_receptances(a.tool, f)

    best, med = best_of(components, clock=clock)
    print(f"component receptances (spindle+holder+tool), 3001 frequencies: best {best * 1e3:.1f} ms, "
          f"median {med * 1e3:.1f} ms  (target < 50 ms)")

    model = AssemblyModel(a, f)
    rng = np.random.default_rng(0)
    batch = a.holder_tool.as_array() * rng.uniform(0.5, 2.0, (400, 4))
    best, med = best_of(lambda: model.tool_point(batch), clock=clock)
    print(f"re-coupling, batch of 400 joints × 3001 frequencies: best {best / 400 * 1e6:.1f} µs/joint, "
          f"median {med / 400 * 1e6:.1f} µs/joint  (target < 50 µs)")

    best, med = best_of(lambda: AssemblyModel(a, np.arange(0.0, 3001.0)).tool_point_frf(), repeat=5, clock=clock)
    print(f"whole tool-point FRF from the TOML model (0–3000 Hz, incl. static point): best {best * 1e3:.1f} ms")


if __name__ == "__main__":
    main()
