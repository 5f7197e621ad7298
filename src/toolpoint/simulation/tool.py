"""Geometry of the cutter for the time-domain simulation: tooth angles, runout, helix, edge forces.

Conventions are those of :mod:`toolpoint.stability.milling` (tooth j at
φ_j = Ω t + θ_j, measured clockwise from +y); a point at height z above the
tool tip of a helical flute lags behind the tip by ψ(z) = 2 z tan β / D
(β the helix angle, D the diameter), so its angle is φ_j − ψ(z).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..errors import InputError

__all__ = ["Tool"]


def _num(value, field) -> float:
    try:
        v = float(value)
    except (TypeError, ValueError):
        raise InputError(f"must be a number, got {value!r}", field=field) from None
    if not np.isfinite(v):
        raise InputError(f"must be finite, got {value!r}", field=field)
    return v


@dataclass(frozen=True)
class Tool:
    """Cutter geometry and edge forces beyond :class:`~toolpoint.stability.CuttingConditions` (immutable).

    Parameters
    ----------
    diameter_m : float
        Tool diameter D, m (> 0; only used with a helix).
    helix_deg : float
        Helix angle β, degrees, in [0, 80).
    slices : int
        Axial slices (≥ 1, ≤ 64) the depth is cut into; with β = 0 every slice is the same and one is used.
    tooth_angles_deg : sequence of float, optional
        Angle θ_j of each tooth, degrees, strictly increasing in [0, 360) (variable pitch); default equal
        pitch 360 j/N. Rounded to the simulation's angular step (the delay must be a whole number of steps).
    runout_m : sequence of float, optional
        Radial offset ρ_j of each tooth, m (> 0: the tooth reaches further out and cuts deeper); default 0.
    edge_tangential, edge_normal : float
        Edge (rubbing) force coefficients K_te, K_ne, N/m (≥ 0): a tooth in the cut feels an extra
        F_t = K_te a, F_n = K_ne a per axial depth a.

    Raises
    ------
    InputError
        Naming the field.
    """

    diameter_m: float = 0.0
    helix_deg: float = 0.0
    slices: int = 1
    tooth_angles_deg: tuple | None = None
    runout_m: tuple | None = None
    edge_tangential: float = 0.0
    edge_normal: float = 0.0

    def __post_init__(self):
        d = _num(self.diameter_m, "diameter_m")
        helix = _num(self.helix_deg, "helix_deg")
        if not 0 <= helix < 80:
            raise InputError(f"must be in [0, 80) degrees, got {helix:g}", field="helix_deg")
        if helix > 0 and d <= 0:
            raise InputError(f"must be > 0 m with a helix, got {d:g}", field="diameter_m")
        if d < 0:
            raise InputError(f"must be ≥ 0 m, got {d:g}", field="diameter_m")
        try:
            sl = int(self.slices)
            ok = sl == self.slices and 1 <= sl <= 64 and not isinstance(self.slices, bool)
        except (TypeError, ValueError):
            ok = False
        if not ok:
            raise InputError(f"must be an integer from 1 to 64, got {self.slices!r}", field="slices")
        for name in ("edge_tangential", "edge_normal"):
            if _num(getattr(self, name), name) < 0:
                raise InputError(f"must be ≥ 0 N/m, got {getattr(self, name)!r}", field=name)
            object.__setattr__(self, name, float(getattr(self, name)))
        for name in ("tooth_angles_deg", "runout_m"):
            v = getattr(self, name)
            if v is not None:
                try:
                    arr = np.asarray(v, dtype=float).reshape(-1)
                except (TypeError, ValueError):
                    raise InputError("must be a list of numbers", field=name) from None
                if not np.all(np.isfinite(arr)):
                    raise InputError("must be finite", field=name)
                object.__setattr__(self, name, tuple(float(a) for a in arr))
        if self.tooth_angles_deg is not None:
            a = np.asarray(self.tooth_angles_deg)
            if a.size < 1 or a[0] < 0 or a[-1] >= 360 or np.any(np.diff(a) <= 0):
                raise InputError("tooth angles must increase strictly within [0, 360) degrees",
                                 field="tooth_angles_deg")
        object.__setattr__(self, "diameter_m", d)
        object.__setattr__(self, "helix_deg", helix)
        object.__setattr__(self, "slices", sl)

    def angles(self, teeth: int) -> np.ndarray:
        """Tooth angles θ_j, rad, for ``teeth`` teeth (checked against the count)."""
        if self.tooth_angles_deg is None:
            return 2 * np.pi * np.arange(teeth) / teeth
        if len(self.tooth_angles_deg) != teeth:
            raise InputError(f"{len(self.tooth_angles_deg)} angles for {teeth} teeth", field="tooth_angles_deg")
        return np.deg2rad(np.asarray(self.tooth_angles_deg))

    def runout(self, teeth: int) -> np.ndarray:
        """Radial offsets ρ_j, m, for ``teeth`` teeth (zeros by default)."""
        if self.runout_m is None:
            return np.zeros(teeth)
        if len(self.runout_m) != teeth:
            raise InputError(f"{len(self.runout_m)} offsets for {teeth} teeth", field="runout_m")
        return np.asarray(self.runout_m, dtype=float)

    def lag(self, depth_m: np.ndarray) -> tuple[np.ndarray, int]:
        """Lag angles ψ of the slice centres, rad, shape (L, P), and the slice count L used."""
        depth_m = np.asarray(depth_m, float).reshape(-1)
        n = self.slices if self.helix_deg > 0 else 1  # straight flutes: all slices alike
        z = (np.arange(n)[:, None] + 0.5) * depth_m[None, :] / n
        if self.helix_deg == 0:
            return np.zeros_like(z), n
        return 2 * z * np.tan(np.deg2rad(self.helix_deg)) / self.diameter_m, n
