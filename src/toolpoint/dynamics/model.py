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
from ..frf import FRF, check_freq_hz

__all__ = ["ToolPointModel", "AssemblyModel", "frf_from_toml"]


class ToolPointModel:
    """A tool on a given spindle–holder subassembly: tool-point receptance for many joints.

    Parameters
    ----------
    tool : Component
        The overhang, holder tip → tool tip.
    subassembly : Subassembly
        Holder-tip receptances (model or measured); interpolated onto ``freq_hz``
        inside its band only.
    freq_hz : array_like
        (F,) frequencies > 0 Hz, strictly increasing.
    max_beta_l : float, optional
        Mesh parameter of the tool (:func:`~toolpoint.dynamics.components.mesh`).

    Attributes
    ----------
    freq_hz, omega : numpy.ndarray
        (F,) Hz and rad/s.
    SH : numpy.ndarray
        (F, 2, 2) holder-tip receptance on ``freq_hz``.
    T : numpy.ndarray
        (F, 4, 4) free–free tool end receptances.
    coupler : ToolPointCoupler
        Eq. (3) for batches of holder–tool joints.
    """

    def __init__(self, tool, subassembly: Subassembly, freq_hz, *, max_beta_l: float | None = None):
        f = check_freq_hz(freq_hz, positive=True)
        self.tool = tool
        self.freq_hz = f
        self.omega = 2 * np.pi * f
        self.SH = subassembly.at(f).R
        self.T = end_receptances(tool, f, max_beta_l=max_beta_l)
        self.coupler = ToolPointCoupler(self.T, self.SH, self.omega)

    def tool_point(self, params) -> np.ndarray:
        """Tool-point receptance h, m/N: (N, F) for params (N, 4), (F,) for params (4,).

        params = [kt N/m, ct N s/m, kr N m/rad, cr N m s/rad] of the holder–tool joint.
        """
        return self.coupler(params)


class AssemblyModel:
    """Receptances of an assembly's components on a frequency grid, coupled at the tool point.

    Parameters
    ----------
    assembly : Assembly
    freq_hz : array_like, optional
        (F,) frequencies ≥ 0 Hz, strictly increasing; defaults to the assembly's
        ``[frequency]`` grid. A 0 Hz point gets the static compliance.
    max_beta_l : float, optional
        Mesh parameter of every component (:func:`~toolpoint.dynamics.components.mesh`,
        default ``MAX_BETA_L``); smaller is finer. The pieces are exact, so this only
        matters for convergence checks.

    Attributes
    ----------
    freq_hz : numpy.ndarray
        (F,) the grid, Hz.
    freq_nonzero_hz, omega : numpy.ndarray
        (F',) the grid without 0 Hz, Hz and rad/s.
    subassembly : Subassembly
        Spindle + holder + spindle–holder joint on ``freq_nonzero_hz``.
    SH, T : numpy.ndarray
        (F', 2, 2) holder-tip and (F', 4, 4) free–free tool receptances.
    coupler : ToolPointCoupler
        Eq. (3) for batches of holder–tool joints.

    Examples
    --------
    >>> import numpy as np
    >>> from toolpoint.dynamics.assembly import parse_assembly
    >>> doc = {
    ...     "spindle": {"segments": [{"length_mm": 300, "od_mm": 70, "id_mm": 20}],
    ...                 "bearings": [{"x_mm": 50, "k": 2e8, "c": 1e3}, {"x_mm": 250, "k": 3e8, "c": 2e3}]},
    ...     "holder": {"segments": [{"length_mm": 60, "od_mm": 40}]},
    ...     "tool": {"segments": [{"length_mm": 50, "od_mm": 12}]},
    ...     "joints": {"spindle_holder": {"kt": 5e8, "ct": 300.0, "kr": 1.5e7, "cr": 50.0},
    ...                "holder_tool": {"kt": 2.1e7, "ct": 15.0, "kr": 1.4e6, "cr": 3.0}}}
    >>> model = AssemblyModel(parse_assembly(doc), np.arange(0.0, 3001.0, 100.0))
    >>> h = model.tool_point_frf()
    >>> len(h), h.unit, bool(h.values[0].imag == 0 and h.values[0].real > 0)
    (31, 'm/N', True)
    """

    def __init__(self, assembly: Assembly, freq_hz=None, *, max_beta_l: float | None = None):
        f = check_freq_hz(assembly.frequency.array() if freq_hz is None else freq_hz)
        self.assembly = assembly
        self.max_beta_l = max_beta_l
        self.freq_hz = f
        self.has_zero = bool(f[0] == 0)
        fz = f[1:] if self.has_zero else f
        self.freq_nonzero_hz = fz
        self.omega = 2 * np.pi * fz
        self.subassembly = Subassembly.from_assembly(assembly, fz, max_beta_l=max_beta_l)
        self.SH = self.subassembly.R
        self.T = end_receptances(assembly.tool, fz, max_beta_l=max_beta_l)
        self.coupler = ToolPointCoupler(self.T, self.SH, self.omega)

    @property
    def n_pieces(self) -> dict[str, int]:
        """Exact beam pieces per component (``spindle``, ``holder``, ``tool``) in this model's meshes."""
        fmax = self.freq_nonzero_hz.max() if self.freq_nonzero_hz.size else 1.0
        a = self.assembly
        return {c.name: len(mesh(c, fmax, self.max_beta_l).pieces) for c in (a.spindle, a.holder, a.tool)}

    # ----------------------------------------------------------------- batched
    def tool_point(self, params) -> np.ndarray:
        """Tool-point receptance h at the non-zero frequencies, m/N: (N, F') for params (N, 4), (F',) for (4,).

        params = [kt N/m, ct N s/m, kr N m/rad, cr N m s/rad] of the holder–tool joint.
        """
        return self.coupler(params)

    # ----------------------------------------------------------------- FRFs
    def _static(self, joint: Joint | None, point: str) -> complex | None:
        """Static compliance (m/N) at the tool tip or holder tip, or None if free in space."""
        a = self.assembly
        if not a.spindle.bearings:
            return None
        meshes = [mesh(a.spindle, 1.0, self.max_beta_l), mesh(a.holder, 1.0, self.max_beta_l)]
        links = [(0, meshes[0].n_nodes - 1, 1, 0, *a.spindle_holder.as_array())]
        if point == "tool":
            meshes.append(mesh(a.tool, 1.0, self.max_beta_l))
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
        """Tool-point direct receptance h = y/F (m/N) on ``freq_hz``, Eq. (3).

        Uses ``joint`` or, if None, the file's ``[joints.holder_tool]``
        (:class:`~toolpoint.errors.InputError` if neither). At 0 Hz: the static
        compliance of the grounded assembly (dropped with a warning if it has no bearings).
        """
        joint = joint or self.assembly.holder_tool
        if joint is None:
            raise InputError("missing section (needed for the tool-point FRF)", file=self.assembly.source,
                             field="joints.holder_tool")
        return self._with_static(self.coupler(joint.as_array()), joint, "tool", "tool point")

    def spindle_holder_frf(self) -> FRF:
        """Holder-tip direct receptance h (m/N) of the spindle–holder subassembly (Eq. 1) on ``freq_hz``."""
        return self._with_static(self.SH[:, 0, 0], None, "holder", "holder tip (spindle–holder)")


def frf_from_toml(path: str | Path, freq_hz=None, point: str = "tool") -> FRF:
    """Receptance FRF (m/N) of an assembly TOML file.

    Parameters
    ----------
    path : str or Path
        Assembly TOML file (:func:`~toolpoint.dynamics.assembly.load_assembly`).
    freq_hz : array_like, optional
        Frequencies, Hz; default the file's ``[frequency]`` grid.
    point : str
        ``"tool"`` (tool tip, needs ``[joints.holder_tool]``) or ``"spindle_holder"``
        (holder tip of the spindle–holder subassembly).
    """
    a = load_assembly(path, require_holder_tool=(point == "tool"))
    model = AssemblyModel(a, freq_hz)
    if point == "tool":
        return model.tool_point_frf()
    if point == "spindle_holder":
        return model.spindle_holder_frf()
    raise ValueError(f"point must be 'tool' or 'spindle_holder', not {point!r}")
