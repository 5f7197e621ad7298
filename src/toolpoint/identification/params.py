"""The holder–tool joint's parameters, their search bounds, and what "identified" means.

One home for these definitions: the identification, the campaign, the learning
and the CLI all import them from here.

p = [kt N/m, ct N s/m, kr N m/rad, cr N m s/rad] (the paper's Eq. 7): the
joint K = diag(kt + iω ct, kr + iω cr).

A parameter is *identified* when its 95 % interval [lo, hi] spans at most a
factor :data:`IDENTIFIED_RATIO` (hi/lo ≤ 2). Intervals are log-symmetric
(see :mod:`.uncertainty`), so the standard error of ln p follows from the
interval and the Student-t quantile used to make it:
σ_ln = ln(hi/lo) / (2 t₀.₉₇₅).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.stats import t as student_t

from ..errors import InputError

__all__ = [
    "PARAMS", "UNITS", "PAPER_BOUNDS", "IDENTIFIED_RATIO", "Bounds", "interval_ratio", "is_identified",
    "ci_quantile", "sigma_ln_from_interval", "ELEMENT_PARAMS", "ELEMENT_UNITS", "DEFAULT_BOUNDS", "CORRELATION_LIMIT",
]

PARAMS = ("kt", "ct", "kr", "cr")
UNITS = {"kt": "N/m", "ct": "N s/m", "kr": "N m/rad", "cr": "N m s/rad"}
# The paper's search ranges (section 4).
PAPER_BOUNDS = {"kt": (1e6, 1e9), "ct": (1.0, 300.0), "kr": (1e5, 1e7), "cr": (1.0, 300.0)}


BOUND_RANGE = (1e-12, 1e15)
"""Search bounds of joint and bearing parameters outside this range (SI) are refused: joints measure k ≈ 1e4–1e10
(N/m, N m/rad) and c ≈ 1e-3–1e4 (N s/m, N m s/rad); a bound of 1e300 is a typo, and would overflow the model."""


def check_bound_range(lo: float, hi: float, *, file=None, field=None) -> None:
    """One line naming ``field`` when a bound lies outside :data:`BOUND_RANGE`."""
    if lo < BOUND_RANGE[0] or hi > BOUND_RANGE[1]:
        raise InputError(f"bounds [{lo:g}, {hi:g}] lie outside any joint's range ({BOUND_RANGE[0]:g}–"
                         f"{BOUND_RANGE[1]:g} in SI units): a typo?", file=file, field=field)


@dataclass(frozen=True)
class Bounds:
    """Box bounds of the search, SI units, one (lo, hi) per parameter of :data:`PARAMS`.

    Parameters
    ----------
    lo, hi : (4,) ndarray
        Lower and upper bounds of [kt N/m, ct N s/m, kr N m/rad, cr N m s/rad], 0 < lo < hi.

    Examples
    --------
    >>> b = Bounds.from_dict({"kt": [1e6, 1e8]})
    >>> b.as_dict()["kt"], float(b.log_hi[0])
    ([1000000.0, 100000000.0], 8.0)
    >>> Bounds.from_dict({"kt": [1e8, 1e6]}, source="a.toml")
    Traceback (most recent call last):
    ...
    toolpoint.errors.InputError: a.toml: bounds.kt: lo must be < hi, got [1e+08, 1e+06]
    """

    lo: np.ndarray
    hi: np.ndarray

    @classmethod
    def from_dict(cls, d: dict | None = None, *, source: str | None = None, section: str = "bounds") -> "Bounds":
        """The paper's bounds (:data:`PAPER_BOUNDS`), overridden by ``d``.

        Parameters
        ----------
        d : dict, optional
            {"kt": [lo, hi], …}, SI units.
        source : str, optional
            File the values came from (for error messages).
        section : str, default "bounds"
            Table name used in error messages (``section.kt``).

        Returns
        -------
        Bounds

        Raises
        ------
        InputError
            Unknown name, not [lo, hi], not finite and > 0, or lo ≥ hi.
        """
        merged = dict(PAPER_BOUNDS)
        for key, val in (d or {}).items():
            field = f"{section}.{key}"
            if key not in PARAMS:
                raise InputError(f"unknown parameter (one of {', '.join(PARAMS)})", file=source, field=field)
            try:
                lo, hi = (float(v) for v in val)
            except (TypeError, ValueError):
                raise InputError(f"must be [lo, hi], got {val!r}", file=source, field=field) from None
            if not (np.isfinite(lo) and np.isfinite(hi)) or lo <= 0 or hi <= 0:
                raise InputError(f"bounds must be finite and > 0, got [{lo:g}, {hi:g}]", file=source, field=field)
            check_bound_range(lo, hi, file=source, field=field)
            if lo >= hi:
                raise InputError(f"lo must be < hi, got [{lo:g}, {hi:g}]", file=source, field=field)
            merged[key] = (lo, hi)
        return cls(np.array([merged[k][0] for k in PARAMS]), np.array([merged[k][1] for k in PARAMS]))

    @property
    def log_lo(self) -> np.ndarray:
        """log10 of ``lo`` (the optimisers' space)."""
        return np.log10(self.lo)

    @property
    def log_hi(self) -> np.ndarray:
        """log10 of ``hi`` (the optimisers' space)."""
        return np.log10(self.hi)

    def as_dict(self) -> dict:
        """{"kt": [lo, hi], …} with Python floats, SI units."""
        return {k: [float(a), float(b)] for k, a, b in zip(PARAMS, self.lo, self.hi)}


# Every spring element of an assembly (see toolpoint.dynamics.points): joints have kt, ct, kr, cr, bearings
# k, c, kr, cr, all in the slot order [k, c, kr, cr] of K = diag(k + iωc, kr + iωcr).
ELEMENT_PARAMS = {"joint": PARAMS, "bearing": ("k", "c", "kr", "cr")}
ELEMENT_UNITS = {"joint": UNITS, "bearing": {"k": "N/m", "c": "N s/m", "kr": "N m/rad", "cr": "N m s/rad"}}
# Default search bounds by element (SI): the holder–tool joint the paper's; the spindle–holder joint (an ISO 40 /
# HSK taper is 1e8–1e9 N/m, 1e6–1e8 N m/rad) and the bearings (preloaded angular-contact sets 1e7–1e9 N/m)
# two or more decades around the usual values.
DEFAULT_BOUNDS = {
    "holder_tool": PAPER_BOUNDS,
    "spindle_holder": {"kt": (1e6, 1e10), "ct": (1.0, 1e4), "kr": (1e4, 1e9), "cr": (0.01, 1e3)},
    "bearing": {"k": (1e6, 1e10), "c": (1.0, 1e5), "kr": (1e3, 1e8), "cr": (0.01, 1e3)},
}
# |correlation| of two identified log10 parameters above which they are reported as trading off.
CORRELATION_LIMIT = 0.95

# An interval wider than this factor says the data do not determine the parameter.
IDENTIFIED_RATIO = 2.0


def interval_ratio(lo, hi) -> np.ndarray:
    """hi / lo of 95 % intervals (inf where lo ≤ 0 or a bound is not finite)."""
    lo = np.asarray(lo, float)
    hi = np.asarray(hi, float)
    with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
        r = hi / lo
    return np.where((lo > 0) & np.isfinite(r), r, np.inf)


def is_identified(lo, hi, ratio: float = IDENTIFIED_RATIO) -> np.ndarray:
    """True where the 95 % interval [lo, hi] spans at most a factor ``ratio``.

    Examples
    --------
    >>> is_identified([1.0, 1.0], [1.5, 3.0]).tolist()
    [True, False]
    """
    return interval_ratio(lo, hi) <= ratio


def ci_quantile(dof: int | float = np.inf, level: float = 0.95) -> float:
    """Student-t quantile t_{(1+level)/2, dof} that makes a two-sided ``level`` interval."""
    return float(student_t.ppf(0.5 + level / 2, dof))


def sigma_ln_from_interval(lo, hi, dof: int | float = np.inf, level: float = 0.95) -> np.ndarray:
    """Standard error of ln p from its log-symmetric interval: ln(hi/lo) / (2 t).

    ``dof`` is the residual degrees of freedom of the fit (2F − 4 for F
    frequencies); for the thousands of frequencies of an FRF, t → 1.96.

    Examples
    --------
    >>> round(float(sigma_ln_from_interval(1.0, np.exp(2 * 1.959963984540054))), 6)
    1.0
    """
    return np.log(interval_ratio(lo, hi)) / (2.0 * ci_quantile(dof, level))
