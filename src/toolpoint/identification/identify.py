"""Identify the holder–tool joint from a measured tool-point FRF (Python API).

    result = identify(model, measured, method="hybrid", seed=0)
    result.params        # {"kt": …, "ct": …, "kr": …, "cr": …}  (SI)
    result.ci95          # {"kt": [lo, hi], …}
    result.warnings      # identifiability and bound warnings

``model`` is a :class:`~toolpoint.dynamics.model.ToolPointModel` (tool on a
subassembly, any frequencies) or an :class:`~toolpoint.dynamics.model.AssemblyModel`;
the measured FRF is evaluated on the model's frequencies.
"""

from __future__ import annotations

import time

import numpy as np
from scipy.optimize import OptimizeResult

from ..dynamics.assembly import Assembly
from ..frf import FRF
from ..dynamics.model import ToolPointModel
from .objective import JointProblem
from .params import PARAMS, Bounds
from .optim import METHODS, Termination
from ..dynamics.subassembly import Subassembly
from .uncertainty import confidence_intervals, identifiability_warnings

__all__ = ["make_algorithm", "model_for", "identify", "relative_errors"]


def make_algorithm(method: str, options: dict | None = None):
    """An optimiser instance by name (``hybrid``, ``ga``, ``sa``, ``pso``, ``de``)."""
    if method not in METHODS:
        raise ValueError(f"unknown method {method!r} (one of {', '.join(METHODS)})")
    return METHODS[method](**(options or {}))


def model_for(assembly: Assembly, freq_hz, subassembly: Subassembly | None = None) -> ToolPointModel:
    """Tool-point model of ``assembly`` on ``freq_hz`` (Hz, > 0); the subassembly
    defaults to the assembly's own spindle + holder + spindle–holder joint."""
    sub = subassembly or Subassembly.from_assembly(assembly, freq_hz)
    return ToolPointModel(assembly.tool, sub, freq_hz)


def identify(
    model: ToolPointModel,
    measured: FRF,
    method: str = "hybrid",
    seed: int | None = 0,
    bounds: Bounds | None = None,
    options: dict | None = None,
    termination: Termination | None = None,
    callback=None,
) -> OptimizeResult:
    """Run one identification; returns a scipy-style ``OptimizeResult`` with

    x (SI [kt, ct, kr, cr]), x_log, fun (objective, m/N), nfev (points),
    nit, seconds, history (best objective per iteration), message, success,
    method, seed, params, ci95, se_log10, warnings.
    """
    if not np.array_equal(measured.freq_hz, model.freq_hz):
        raise ValueError("measured FRF and model frequencies differ: build the model on measured.freq_hz")
    problem = JointProblem(model.coupler, measured.to_receptance().values, bounds)
    algo = make_algorithm(method, options)
    rng = np.random.default_rng(seed)
    t0 = time.perf_counter()
    res = algo.minimize(problem, rng, termination, callback)
    x_log = np.asarray(res.x, float)
    ci, se = confidence_intervals(problem, x_log)
    res.seconds = time.perf_counter() - t0  # includes the uncertainty step
    res.x_log = x_log
    res.x = 10.0**x_log
    res.params = dict(zip(PARAMS, map(float, res.x)))
    res.ci95 = {k: [float(a), float(b)] for k, (a, b) in zip(PARAMS, ci)}
    res.se_log10 = dict(zip(PARAMS, map(float, se)))
    res.warnings = identifiability_warnings(x_log, ci, problem.bounds)
    res.seed = seed
    res.bounds = problem.bounds.as_dict()
    res.model_frf = FRF(model.freq_hz, problem.model(x_log), "receptance", f"identified ({method})")
    return res


def relative_errors(x, exact) -> dict:
    """|x − exact| / exact per parameter, as fractions."""
    return {k: float(abs(a - b) / abs(b)) for k, a, b in zip(PARAMS, np.asarray(x, float), np.asarray(exact, float))}
