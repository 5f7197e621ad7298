"""Forward model: assembly → component receptances → coupled tool-point FRF.

:class:`AssemblyModel` computes the spindle, holder and tool receptances once
for a frequency grid and couples them through the joints (Eqs. 1–4). Re-coupling
with new holder–tool joint values costs only the rational expression of
:class:`~toolpoint.dynamics.coupling.ToolPointCoupler`, vectorised over a batch of joint
parameter sets — what identification needs.

At 0 Hz the free–free holder and tool receptances are singular; there the
model returns the static compliance of the whole assembly, solved directly
from the exact static stiffness of all pieces, bearings and joints. An
assembly with no bearings is free in space and has no static compliance: the
0 Hz point is then dropped with a warning.
"""

from __future__ import annotations

import warnings
from pathlib import Path

import numpy as np

from .assembly import Assembly, Joint, load_assembly
from .components import assemble, end_receptances, mesh, receptance
from .coupling import ToolPointCoupler
from .subassembly import Subassembly
from ..errors import InputError
from ..frf import FRF

__all__ = ["ToolPointModel", "AssemblyModel", "frf_from_toml"]


class ToolPointModel:
    """A tool on a given spindle–holder subassembly: tool-point receptance for many joints.

    Parameters
    ----------
    tool : Component — the overhang, holder tip → tool tip.
    subassembly : Subassembly — holder-tip receptances (model or measured);
        interpolated onto ``freq_hz`` inside its band only.
    freq_hz : (F,) frequencies > 0, Hz.
    """

    def __init__(self, tool, subassembly: Subassembly, freq_hz):
        f = np.asarray(freq_hz, float).reshape(-1)
        if f.size == 0 or np.any(~np.isfinite(f)) or np.any(f <= 0) or np.any(np.diff(f) <= 0):
            raise ValueError("frequencies must be finite, > 0 and strictly increasing")
        self.tool = tool
        self.freq_hz = f
        self.omega = 2 * np.pi * f
        self.SH = subassembly.at(f).R
        self.T = end_receptances(tool, f)
        self.coupler = ToolPointCoupler(self.T, self.SH, self.omega)

    def tool_point(self, params) -> np.ndarray:
        """Tool-point receptance h (N, F) or (F,), m/N, for params (N, 4) or (4,) =
        [kt N/m, ct N s/m, kr N m/rad, cr N m s/rad]."""
        return self.coupler(params)


class AssemblyModel:
    """Receptances of an assembly's components on a frequency grid (Hz).

    Parameters
    ----------
    assembly : Assembly
    freq_hz : array or None — defaults to the assembly's ``[frequency]`` grid.
    """

    def __init__(self, assembly: Assembly, freq_hz=None):
        f = assembly.frequency.array() if freq_hz is None else np.asarray(freq_hz, float).reshape(-1)
        if f.size == 0 or np.any(~np.isfinite(f)) or np.any(f < 0) or np.any(np.diff(f) <= 0):
            raise ValueError("frequencies must be finite, ≥ 0 and strictly increasing")
        self.assembly = assembly
        self.freq_hz = f
        self.has_zero = bool(f[0] == 0)
        fz = f[1:] if self.has_zero else f
        self.freq_nonzero_hz = fz
        self.omega = 2 * np.pi * fz
        self.subassembly = Subassembly.from_assembly(assembly, fz)
        self.SH = self.subassembly.R
        self.T = end_receptances(assembly.tool, fz)
        self.coupler = ToolPointCoupler(self.T, self.SH, self.omega)

    # ----------------------------------------------------------------- batched
    def tool_point(self, params) -> np.ndarray:
        """Tool-point receptance h (N, F') or (F',) at the non-zero frequencies, m/N.

        params (N, 4) or (4,) = [kt N/m, ct N s/m, kr N m/rad, cr N m s/rad].
        """
        return self.coupler(params)

    # ----------------------------------------------------------------- FRFs
    def _static(self, joint: Joint | None, point: str) -> complex | None:
        """Static compliance (m/N) at the tool tip or holder tip, or None if free in space."""
        a = self.assembly
        if not a.spindle.bearings:
            return None
        meshes = [mesh(a.spindle, 1.0), mesh(a.holder, 1.0)]
        links = [(0, meshes[0].n_nodes - 1, 1, 0, *a.spindle_holder.as_array())]
        if point == "tool":
            meshes.append(mesh(a.tool, 1.0))
            links.append((1, meshes[1].n_nodes - 1, 2, 0, *joint.as_array()))
        D, offsets = assemble(meshes, links, np.zeros(1))
        dof = offsets[-1] + 2 * (meshes[-1].n_nodes - 1)
        return complex(receptance(D, [dof])[0, 0, 0])

    def _with_static(self, values: np.ndarray, joint, point: str, label: str) -> FRF:
        f = self.freq_nonzero_hz
        if self.has_zero:
            h0 = self._static(joint, point)
            if h0 is None:
                warnings.warn(
                    "0 Hz dropped: the assembly has no bearings, so it is free in space and has no static compliance",
                    stacklevel=3,
                )
            else:
                f = self.freq_hz
                values = np.concatenate([[h0], values])
        return FRF(f, values, "receptance", label)

    def tool_point_frf(self, joint: Joint | None = None) -> FRF:
        """Tool-point direct receptance h = y/F (m/N) with the given (or the file's) holder–tool joint."""
        joint = joint or self.assembly.holder_tool
        if joint is None:
            raise InputError("missing section (needed for the tool-point FRF)", file=self.assembly.source,
                             field="joints.holder_tool")
        return self._with_static(self.coupler(joint.as_array()), joint, "tool", "tool point")

    def spindle_holder_frf(self) -> FRF:
        """Holder-tip direct receptance of the spindle–holder subassembly (Eq. 1), m/N."""
        return self._with_static(self.SH[:, 0, 0], None, "holder", "holder tip (spindle–holder)")


def frf_from_toml(path: str | Path, freq_hz=None, point: str = "tool") -> FRF:
    """Receptance FRF of an assembly TOML file at the tool tip (``point="tool"``)
    or the spindle–holder holder tip (``point="spindle_holder"``)."""
    a = load_assembly(path, require_holder_tool=(point == "tool"))
    model = AssemblyModel(a, freq_hz)
    if point == "tool":
        return model.tool_point_frf()
    if point == "spindle_holder":
        return model.spindle_holder_frf()
    raise ValueError(f"point must be 'tool' or 'spindle_holder', not {point!r}")
