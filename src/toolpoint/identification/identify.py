"""Identify the holder–tool joint from a measured tool-point FRF (Python API).

    result = identify(model, measured, method="hybrid", seed=0)
    result.params        # {"kt": …, "ct": …, "kr": …, "cr": …}  (SI)
    result.ci95          # {"kt": [lo, hi], …}
    result.warnings      # identifiability and bound warnings (also emitted as IdentifiabilityWarning)
    result.optimizer     # the optimiser's scipy OptimizeResult (x in log10 space)

``model`` is a :class:`~toolpoint.dynamics.model.ToolPointModel` (tool on a
subassembly, any frequencies); the measured FRF must be on the model's frequencies.
"""

from __future__ import annotations

import time
import warnings
from dataclasses import dataclass

import numpy as np
from scipy.optimize import OptimizeResult

from ..blas import single_thread_blas
from ..dynamics.assembly import Assembly
from ..dynamics.model import ToolPointModel
from ..dynamics.subassembly import Subassembly
from ..errors import IdentifiabilityWarning, InputError
from ..frf import FRF
from .objective import JointProblem
from .optim import METHODS, check_method
from .params import PARAMS, UNITS, Bounds
from .uncertainty import identifiability_warnings, intervals_and_correlation, open_end_warnings, profile_intervals

__all__ = ["IdentificationResult", "INTERVALS_DEFAULT", "make_algorithm", "model_for", "identify", "solve",
           "relative_errors"]

# 95 % intervals by default from the profile likelihood (measured: docs/design/identification.md)
INTERVALS_DEFAULT = "profile"


def make_algorithm(method: str, options: dict | None = None):
    """An optimiser instance by name.

    Parameters
    ----------
    method : str
        ``hybrid``, ``ga``, ``sa``, ``pso`` or ``de`` (checked by
        :func:`~toolpoint.identification.optim.check_method`: anything else is an InputError).
    options : dict, optional
        Keyword arguments of the optimiser's class (e.g. ``{"maxiter": 100, "maxfev": 20000}``).

    Returns
    -------
    GA, SA, PSO, DE or Hybrid

    Examples
    --------
    >>> make_algorithm("pso", {"maxiter": 50}).maxiter
    50
    """
    return METHODS[check_method(method, file=None, field="method")](**(options or {}))


def model_for(assembly: Assembly, freq_hz, subassembly: Subassembly | None = None) -> ToolPointModel:
    """Tool-point model of ``assembly`` on ``freq_hz``.

    Parameters
    ----------
    assembly : Assembly
    freq_hz : (F,) array
        Frequencies, Hz (> 0).
    subassembly : Subassembly, optional
        Default: the assembly's own spindle + holder + spindle–holder joint.

    Returns
    -------
    ToolPointModel
    """
    sub = subassembly or Subassembly.from_assembly(assembly, freq_hz)
    return ToolPointModel(assembly.tool, sub, freq_hz)


@dataclass(frozen=True, eq=False)
class IdentificationResult:
    """The identified holder–tool joint (SI units) and how it was found.

    Attributes
    ----------
    params : dict
        {"kt": N/m, "ct": N s/m, "kr": N m/rad, "cr": N m s/rad}.
    x : (4,) ndarray
        The same values in ``PARAMS`` order, SI.
    ci95 : dict
        name → [lo, hi], 95 % interval, SI (see :mod:`.uncertainty`).
    se_log10 : dict
        name → standard error of log10 p.
    warnings : tuple of str
        Identifiability findings (wide interval, on a bound); each was also emitted as an
        :class:`~toolpoint.errors.IdentifiabilityWarning`.
    model_frf : FRF
        The model's tool-point receptance with the identified joint, m/N.
    method : str
    seed : int or None
    bounds : dict
        name → [lo, hi] search bounds, SI.
    seconds : float
        Wall time of the search and the uncertainty step, s.
    optimizer : scipy.optimize.OptimizeResult
        The optimiser's own result: ``x`` and ``fun`` in its space (log10 p; m/N), ``success``,
        ``status``, ``message``, ``nit``, ``nfev``, ``history``, …
    names : tuple of str
        Parameter names, in the order of ``x`` (``PARAMS`` for the holder–tool joint; full names such as
        ``spindle_holder.kt`` or ``bearings[0].k`` from :func:`~toolpoint.identification.problem.identify_frfs`).
    correlation : (n, n) ndarray or None
        Correlation of the log10 estimates (:func:`~toolpoint.identification.uncertainty.intervals_and_correlation`).
    model_frfs : tuple of FRF
        The model at every measured point (``model_frf`` is the first).
    intervals : str
        How ``ci95`` was made: ``"linear"`` (linearised at the optimum, :func:`identify`) or ``"profile"``
        (profile likelihood, the default of :func:`~toolpoint.identification.problem.identify_frfs`).
    """

    params: dict
    x: np.ndarray
    ci95: dict
    se_log10: dict
    warnings: tuple
    model_frf: FRF
    method: str
    seed: int | None
    bounds: dict
    seconds: float
    optimizer: OptimizeResult
    names: tuple = PARAMS
    correlation: np.ndarray | None = None
    model_frfs: tuple = ()
    intervals: str = "linear"

    @property
    def fun(self) -> float:
        """Objective at the optimum, ‖h − h_meas‖₂, m/N."""
        return float(self.optimizer.fun)

    @property
    def nfev(self) -> int:
        """Model evaluations of the search (the uncertainty step's 5 are not included)."""
        return int(self.optimizer.nfev)

    @property
    def nit(self) -> int:
        """Iterations of the optimiser (hybrid: of its global stage)."""
        return int(self.optimizer.nit)

    @property
    def success(self) -> bool:
        """True when the optimiser's convergence test held (not merely a cap reached)."""
        return bool(self.optimizer.success)

    @property
    def status(self) -> int:
        """The optimiser's status code (0 converged, 1 iteration limit, 2 evaluation limit, 3 other)."""
        return int(self.optimizer.status)

    @property
    def message(self) -> str:
        """Why the optimiser stopped."""
        return str(self.optimizer.message)

    @property
    def history(self) -> np.ndarray:
        """Best objective per iteration, m/N."""
        return self.optimizer.history

    @property
    def x_log(self) -> np.ndarray:
        """log10 of ``x`` (the optimiser's ``x``)."""
        return np.asarray(self.optimizer.x, float)


def identify(
    model: ToolPointModel,
    measured: FRF,
    method: str = "hybrid",
    seed: int | None = 0,
    *,
    bounds: Bounds | None = None,
    options: dict | None = None,
    callback=None,
    intervals: str = INTERVALS_DEFAULT,
) -> IdentificationResult:
    """Identify the holder–tool joint p = [kt, ct, kr, cr] from a measured tool-point FRF.

    Minimises the paper's Eq. (8), f(x) = ‖h(10^x) − h̄‖₂ (m/N), over x = log10 p within ``bounds``, then
    computes 95 % intervals and identifiability warnings (see :mod:`toolpoint.identification.uncertainty`).
    The same pipeline (:func:`solve`) serves the general problem of
    :func:`toolpoint.identification.problem.identify_frfs`.

    Parameters
    ----------
    model : ToolPointModel
        Tool on a subassembly, on the measured frequencies (:func:`model_for`).
    measured : FRF
        Measured tool-point FRF (converted to receptance, m/N).
    method : str, default "hybrid"
        ``hybrid``, ``ga``, ``sa``, ``pso`` or ``de`` (any case).
    seed : int or None, default 0
        Seed of the ``numpy.random.Generator`` that drives the search.
    bounds : Bounds, optional
        Search bounds, SI; default the paper's (:data:`~toolpoint.identification.params.PAPER_BOUNDS`).
    options : dict, optional
        Options of the optimiser (see its class, e.g. ``{"maxiter": 100}``).
    callback : callable, optional
        ``callback(nit, best_f, nfev)`` after every iteration.
    intervals : {"profile", "linear"}, default "profile"
        95 % intervals from the profile likelihood
        (:func:`~toolpoint.identification.uncertainty.profile_intervals`: follows the curved valleys along
        which parameters trade off; an end that reaches a search bound is also a warning) or linearised at the
        optimum (cheaper, too narrow where the fit is far from linear). The default is chosen by measurement
        (``docs/design/identification.md``): on FE data with 1 % noise the linearised intervals held c_r in
        too few trials, the profile ones close to 95 %.

    Returns
    -------
    IdentificationResult

    Warns
    -----
    IdentifiabilityWarning
        Once per entry of ``result.warnings``.

    Examples
    --------
    >>> from toolpoint.dynamics.assembly import load_assembly
    >>> a = load_assembly("examples/numerical_case.toml")
    >>> f = np.arange(100.0, 3001.0, 10.0)
    >>> model = model_for(a, f)
    >>> measured = FRF(f, model.tool_point(a.holder_tool.as_array()))
    >>> r = identify(model, measured, "hybrid", seed=0)
    >>> r.success, round(r.params["kt"] / 2.1e7, 6), r.warnings
    (True, 1.0, ())
    """
    if not np.array_equal(measured.freq_hz, model.freq_hz):
        raise ValueError("measured FRF and model frequencies differ: build the model on measured.freq_hz")
    problem = JointProblem(model.coupler, measured.to_receptance().values, bounds)
    return solve(problem, method, seed, options=options, callback=callback, intervals=intervals,
                 model_frfs=lambda x_log: (FRF(model.freq_hz, problem.model(x_log), "receptance",
                                               f"identified ({str(method).lower()})"),))


def solve(problem, method: str = "hybrid", seed: int | None = 0, *, options: dict | None = None, callback=None,
          intervals: str = INTERVALS_DEFAULT, model_frfs=None) -> IdentificationResult:
    """The one identification pipeline: search, 95 % intervals, identifiability and trade-off warnings.

    Parameters
    ----------
    problem : JointProblem or FRFProblem
        Objective in log10 space with ``bounds`` (and, for the general problem, ``names``, ``units`` and
        ``model_frfs(x_log)``).
    method, seed, options, callback, intervals
        As in :func:`identify`.
    model_frfs : callable, optional
        ``model_frfs(x_log)`` → tuple of the model's FRFs at the optimum (default ``problem.model_frfs``).

    Returns
    -------
    IdentificationResult
    """
    if intervals not in ("profile", "linear"):
        raise InputError(f"unknown interval method {intervals!r} (profile or linear)", field="intervals")
    method = str(method).lower()
    names = tuple(getattr(problem, "names", PARAMS))
    units = getattr(problem, "units", UNITS)
    general = hasattr(problem, "names")
    algo = make_algorithm(method, options)
    rng = np.random.default_rng(seed)
    t0 = time.perf_counter()
    # One BLAS thread: the SVDs and least-squares steps here are 4–12 columns wide. On the paper's case (2 cores,
    # GA seeds 0 and 3) two threads took 7.8 s wall / 15.5 s CPU against 5.4 s / 5.5 s with one; with two such
    # processes side by side (pytest's two workers) GA seed 0 took 151 s against 2.5 s, the threads spinning.
    with single_thread_blas():
        opt = algo.minimize(problem, rng, callback=callback)
        x_log = np.asarray(opt.x, float)
        ci, se, corr = intervals_and_correlation(problem, x_log)
        extra: tuple = ()
        if intervals == "profile":
            prof = profile_intervals(problem, x_log, se)
            ci = prof.ci
            extra = tuple(open_end_warnings(prof, names, units))
    seconds = time.perf_counter() - t0  # includes the uncertainty step
    kw = dict(names=names, units=units, pairs=True) if general else {}
    found = tuple(identifiability_warnings(x_log, ci, problem.bounds, corr=corr, **kw)) + extra
    for w in found:
        warnings.warn(w, IdentifiabilityWarning, stacklevel=3)
    x = 10.0**x_log
    frfs = tuple((model_frfs or problem.model_frfs)(x_log))
    bounds = ({k: [float(a), float(b)] for k, a, b in zip(names, problem.bounds.lo, problem.bounds.hi)} if general
              else problem.bounds.as_dict())
    return IdentificationResult(
        params=dict(zip(names, map(float, x))),
        x=x,
        ci95={k: [float(a), float(b)] for k, (a, b) in zip(names, ci)},
        se_log10=dict(zip(names, map(float, se))),
        warnings=found,
        model_frf=frfs[0],
        method=method,
        seed=seed,
        bounds=bounds,
        seconds=seconds,
        optimizer=opt,
        correlation=corr,
        model_frfs=frfs if general else (),
        intervals=intervals,
        names=names,
    )


def relative_errors(x, exact) -> dict:
    """|x − exact| / |exact| per parameter, as fractions.

    Parameters
    ----------
    x, exact : (4,) array
        [kt, ct, kr, cr], same units.

    Returns
    -------
    dict
        name → relative error.

    Examples
    --------
    >>> relative_errors([2.2e7, 15, 1.4e6, 3], [2e7, 15, 1.4e6, 3])["kt"]
    0.1
    """
    return {k: float(abs(a - b) / abs(b)) for k, a, b in zip(PARAMS, np.asarray(x, float), np.asarray(exact, float))}
