"""Cutting conditions of a milling operation, validated once.

The cutting force model is the linear one of Altintas & Budak (1995): a tooth
removing a chip of thickness h (m) over an axial depth a (m) feels

    F_t = K_t a h,   F_n = K_r K_t a h,

with the tangential cutting coefficient K_t in N/m² (a specific cutting
pressure: 600 N/mm² = 6e8 N/m²) and the dimensionless radial force ratio
K_r = K_n/K_t. These are *not* the joint stiffnesses ``kt`` (N/m) and ``kr``
(N m/rad) of :mod:`toolpoint.identification.params`; the names here say so.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..errors import InputError

__all__ = ["CuttingConditions", "MILLING", "check_cutting", "immersion_angles"]

MILLING = ("down", "up")



@dataclass(frozen=True)
class CuttingConditions:
    """Tool and cut of a milling operation (immutable; checked on creation).

    Parameters
    ----------
    teeth : int
        Number of teeth N (≥ 1).
    tangential_coeff : float
        Tangential cutting coefficient K_t, N/m² (> 0; typically 1e8–3e9).
    radial_ratio : float
        Radial (normal) to tangential force ratio K_r = K_n/K_t, dimensionless (≥ 0).
    radial_immersion : float
        Radial depth over tool diameter a_e/D, dimensionless, in (0, 1] (1 = slotting).
    milling : {"down", "up"}
        Down-milling (climb) or up-milling (conventional).

    Raises
    ------
    InputError
        Naming the offending field, e.g. ``tangential_coeff: must be > 0 N/m², got -1``.

    Examples
    --------
    >>> from toolpoint.stability import CuttingConditions
    >>> cut = CuttingConditions(teeth=2, tangential_coeff=6e8, radial_ratio=1/3, radial_immersion=0.5)
    >>> cut.milling, cut.normal_coeff
    ('down', 200000000.0)
    >>> [round(a, 4) for a in cut.immersion_angles]
    [1.5708, 3.1416]
    >>> CuttingConditions(teeth=2, tangential_coeff=-6e8, radial_ratio=0.3, radial_immersion=1)
    Traceback (most recent call last):
    ...
    toolpoint.errors.InputError: tangential_coeff: must be finite and > 0 N/m², got -6e+08
    """

    teeth: int
    tangential_coeff: float
    radial_ratio: float
    radial_immersion: float
    milling: str = "down"

    def __post_init__(self):
        teeth = self.teeth
        try:
            n = int(teeth)
            ok = n == teeth and n >= 1 and not isinstance(teeth, bool)
        except (TypeError, ValueError, OverflowError):
            ok = False
        if not ok:
            raise InputError(f"must be a positive integer, got {teeth!r}", field="teeth")
        kt = _real(self.tangential_coeff, "tangential_coeff")
        if not (np.isfinite(kt) and kt > 0):
            raise InputError(f"must be finite and > 0 N/m², got {kt:g}", field="tangential_coeff")
        kr = _real(self.radial_ratio, "radial_ratio")
        if not (np.isfinite(kr) and kr >= 0):
            raise InputError(f"radial force ratio Kn/Kt must be finite and ≥ 0, got {kr:g}", field="radial_ratio")
        ri = _real(self.radial_immersion, "radial_immersion")
        if not (0.0 < ri <= 1.0):
            raise InputError(f"radial immersion a_e/D must be in (0, 1], got {ri:g}", field="radial_immersion")
        if self.milling not in MILLING:
            raise InputError(f"must be 'down' or 'up', got {self.milling!r}", field="milling")
        for name, value in (("teeth", n), ("tangential_coeff", kt), ("radial_ratio", kr), ("radial_immersion", ri)):
            object.__setattr__(self, name, value)

    @property
    def normal_coeff(self) -> float:
        """Normal cutting coefficient K_n = K_r K_t, N/m²."""
        return self.radial_ratio * self.tangential_coeff

    @property
    def immersion_angles(self) -> tuple[float, float]:
        """Entry and exit angles (φ_st, φ_ex), rad (see :func:`immersion_angles`)."""
        return immersion_angles(self.radial_immersion, self.milling)

    def as_dict(self) -> dict:
        """The five fields as a plain dict (for result metadata and reports)."""
        return dict(teeth=self.teeth, tangential_coeff=self.tangential_coeff, radial_ratio=self.radial_ratio,
                    radial_immersion=self.radial_immersion, milling=self.milling)


def immersion_angles(radial_immersion: float, milling: str = "down") -> tuple[float, float]:
    """Entry and exit angles of a tooth.

    Parameters
    ----------
    radial_immersion : float
        a_e/D ∈ (0, 1], dimensionless.
    milling : {"down", "up"}

    Returns
    -------
    (phi_st, phi_ex) : tuple of float
        rad; up-milling (0, arccos(1 − 2a_e/D)), down-milling (arccos(2a_e/D − 1), π).

    Examples
    --------
    >>> immersion_angles(1.0, "up") == (0.0, float(np.pi))
    True
    """
    ri = float(radial_immersion)
    if milling == "up":
        return 0.0, float(np.arccos(1.0 - 2.0 * ri))
    if milling == "down":
        return float(np.arccos(2.0 * ri - 1.0)), float(np.pi)
    raise InputError(f"must be 'down' or 'up', got {milling!r}", field="milling")


def _real(value, name: str) -> float:
    try:
        return float(value)
    except (TypeError, ValueError):
        raise InputError(f"must be a number, got {value!r}", field=name) from None


def check_cutting(cutting) -> CuttingConditions:
    """``cutting`` if it is a :class:`CuttingConditions`, else one line naming the field.

    Parameters
    ----------
    cutting : object
        What the caller passed as ``cutting``.

    Returns
    -------
    CuttingConditions
    """
    if not isinstance(cutting, CuttingConditions):
        raise InputError(f"expected CuttingConditions, got {type(cutting).__name__}", field="cutting")
    return cutting
