"""Full-assembly finite-element model — an independent check of the RCSA result.

The equivalent of the paper's ANSYS model (BEAM188 + COMBIN14): spindle,
holder and tool meshed with two-node Timoshenko beam elements, bearings as
springs/dampers to ground, the spindle–holder and holder–tool joints as
zero-length spring–dampers between coincident nodes. One global matrix,
solved directly per frequency (banded LU) — nothing is shared with the exact
segment solution of :mod:`toolpoint.dynamics.beam` but the geometry.

Element (Przemieniecki 1968; Friedman & Kosmatka 1993): cubic deflection and
"interdependent" rotation interpolation, exact for static end loads, with
Φ = 12EI/(κGAL²):

    K = EI/((1+Φ)L³) [[12, 6L, −12, 6L], [6L, (4+Φ)L², −6L, (2−Φ)L²], …]

and the consistent mass (translational ρAL and rotary ρI/L parts, both over
(1+Φ)², polynomials in Φ given below). The natural-frequency error falls as h²
with the element length h (measured in ``tests/dynamics/test_beam.py``; the tool-point
FRF error likewise, ``tests/dynamics/test_coupling.py``), so Richardson extrapolation in
h² sharpens it. This is a check, not a hot path: it loops over frequencies.
"""

from __future__ import annotations

import numpy as np
from scipy.linalg import solve_banded

from .assembly import Assembly, Component, Segment
from .components import interior_cuts


def element_matrices(seg: Segment, L: float) -> tuple[np.ndarray, np.ndarray]:
    """Stiffness (complex, E with loss factor) and mass (real) 4×4 on [w1, ψ1, w2, ψ2]."""
    sec = seg.section()
    EI = sec.E * sec.Iz
    phi = (12 * sec.E * sec.Iz / (sec.kappa * sec.G * sec.A * L**2)).real  # E/G is real
    K = EI / ((1 + phi) * L**3) * np.array(
        [
            [12, 6 * L, -12, 6 * L],
            [6 * L, (4 + phi) * L**2, -6 * L, (2 - phi) * L**2],
            [-12, -6 * L, 12, -6 * L],
            [6 * L, (2 - phi) * L**2, -6 * L, (4 + phi) * L**2],
        ]
    )
    p, p2 = phi, phi**2
    m11 = 13 / 35 + 7 * p / 10 + p2 / 3
    m12 = (11 / 210 + 11 * p / 120 + p2 / 24) * L
    m13 = 9 / 70 + 3 * p / 10 + p2 / 6
    m14 = -(13 / 420 + 3 * p / 40 + p2 / 24) * L
    m22 = (1 / 105 + p / 60 + p2 / 120) * L**2
    m24 = -(1 / 140 + p / 60 + p2 / 120) * L**2
    Mt = np.array(
        [
            [m11, m12, m13, m14],
            [m12, m22, -m14, m24],
            [m13, -m14, m11, -m12],
            [m14, m24, -m12, m22],
        ]
    ) * (sec.rho * sec.A * L / (1 + p) ** 2)
    r11 = 6 / 5
    r12 = (1 / 10 - p / 2) * L
    r22 = (2 / 15 + p / 6 + p2 / 3) * L**2
    r24 = (-1 / 30 - p / 6 + p2 / 6) * L**2
    Mr = np.array(
        [
            [r11, r12, -r11, r12],
            [r12, r22, -r12, r24],
            [-r11, -r12, r11, -r12],
            [r12, r24, -r12, r22],
        ]
    ) * (sec.rho * sec.Iz / ((1 + p) ** 2 * L))
    return K, Mt + Mr


class FEModel:
    """Global K (complex), C, M of components in series, with springs.

    Components are numbered one after the other, so every element and every
    joint couples DOFs at most 3 apart: a band of half-width 3.
    """

    BW = 3

    def __init__(self, components: list[Component], joints: list[np.ndarray], max_element_m: float = 2e-3):
        nodes_per = []
        self.elements = []  # (first dof, K, M)
        self.ground = []  # (dof, k, c) for both w and ψ springs
        self.node_x: list[np.ndarray] = []  # node positions per component, m from its start
        first = 0
        for comp in components:
            x = 0.0
            xs = [0.0]
            for seg in comp.segments:
                cuts = interior_cuts(x, x + seg.length, [b.x for b in comp.bearings])
                for a, b in zip(cuts[:-1], cuts[1:]):
                    n = max(1, int(np.ceil((b - a) / max_element_m)))
                    K, M = element_matrices(seg, (b - a) / n)
                    for _ in range(n):
                        self.elements.append((first + 2 * (len(xs) - 1), K, M))
                        xs.append(xs[-1] + (b - a) / n)
                x += seg.length
            xs = np.array(xs)
            self.node_x.append(xs)
            for b in comp.bearings:
                node = int(np.argmin(abs(xs - b.x)))
                self.ground += [(first + 2 * node, b.k, b.c), (first + 2 * node + 1, b.kr, b.cr)]
            nodes_per.append(xs.size)
            first += 2 * xs.size
        self.ndof = first
        self.first_dof = np.cumsum([0] + [2 * n for n in nodes_per])[:-1]
        self.last_dof = self.first_dof + 2 * (np.array(nodes_per) - 1)
        # joint i links the last node of component i with the first of component i + 1
        self.links = []
        for i, (kt, ct, kr, cr) in enumerate(joints):
            a, b = self.last_dof[i], self.first_dof[i + 1]
            self.links += [(a, b, kt, ct), (a + 1, b + 1, kr, cr)]

    def _bands(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """K (complex), C and M in LAPACK band storage (row bw + i − j, column j)."""
        bw = self.BW
        Kb = np.zeros((2 * bw + 1, self.ndof), complex)
        Cb = np.zeros((2 * bw + 1, self.ndof))
        Mb = np.zeros((2 * bw + 1, self.ndof))
        r, c = np.meshgrid(np.arange(4), np.arange(4), indexing="ij")
        for d0, K, M in self.elements:
            np.add.at(Kb, (bw + r - c, d0 + c), K)
            np.add.at(Mb, (bw + r - c, d0 + c), M)
        for d, k, cc in self.ground:
            Kb[bw, d] += k
            Cb[bw, d] += cc
        for a, b, k, cc in self.links:
            for i, j, sgn in ((a, a, 1), (b, b, 1), (a, b, -1), (b, a, -1)):
                Kb[bw + i - j, j] += sgn * k
                Cb[bw + i - j, j] += sgn * cc
        return Kb, Cb, Mb

    def matrices(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Dense global K (complex, N/m and N m/rad), C (real, N s/m …) and M (real, kg, kg m²), (ndof, ndof).

        For eigenvalue checks of small models; the solver itself uses band storage.
        """
        bw = self.BW
        bands = self._bands()
        i, j = np.meshgrid(np.arange(self.ndof), np.arange(self.ndof), indexing="ij")
        inside = np.abs(i - j) <= bw
        out = []
        for B in bands:
            A = np.zeros((self.ndof, self.ndof), B.dtype)
            A[inside] = B[bw + i[inside] - j[inside], j[inside]]
            out.append(A)
        return tuple(out)

    def node_dof(self, component: int, x: float) -> int:
        """The w DOF of the node of component number ``component`` nearest to ``x`` (m from its start)."""
        xs = self.node_x[component]
        return int(self.first_dof[component] + 2 * np.argmin(abs(xs - x)))

    def receptance(self, freq_hz, dof: int, force_dof: int | None = None) -> np.ndarray:
        """Receptance at ``dof`` for a unit load at ``force_dof`` (default ``dof``: direct), m/N for w DOFs,
        at each frequency (Hz)."""
        Kb, Cb, Mb = self._bands()
        out = np.empty(len(freq_hz), complex)
        e = np.zeros(self.ndof)
        e[dof if force_dof is None else force_dof] = 1.0
        for k, f in enumerate(np.asarray(freq_hz, float)):
            w = 2 * np.pi * f
            out[k] = solve_banded((self.BW, self.BW), Kb + 1j * w * Cb - w * w * Mb, e,
                                  overwrite_ab=True, check_finite=False)[dof]
        return out


def assembly_fe(assembly: Assembly, max_element_m: float = 2e-3) -> FEModel:
    """FE model of spindle + holder + tool with both joints."""
    return FEModel(
        [assembly.spindle, assembly.holder, assembly.tool],
        [assembly.spindle_holder.as_array(), assembly.holder_tool.as_array()],
        max_element_m,
    )


def tool_point_fe(assembly: Assembly, freq_hz, max_element_m: float = 2e-3) -> np.ndarray:
    """Tool-tip direct receptance h (m/N) of the full-assembly FE model."""
    fe = assembly_fe(assembly, max_element_m)
    return fe.receptance(freq_hz, int(fe.last_dof[-1]))
