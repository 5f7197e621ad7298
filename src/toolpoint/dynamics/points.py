r"""Receptances at named points of an assembly, with joints and bearings as variable spring elements.

A *point* is a translational DOF on a component: ``tool_tip``, ``holder_tip``, ``spindle_nose`` (the
components' far ends) or ``COMPONENT:x_mm=X`` (X mm from the component's start, the end nearer the
spindle's rear; the spindle's own x as for its bearings). An FRF is a pair (response point, force point);
``"tool_tip"`` alone is the direct FRF, ``"tool_tip,holder_tip"`` the cross FRF (response at the tool tip,
force at the holder tip).

Every joint (spindle–holder, holder–tool) and every bearing is a 2-DOF spring element
K = diag(k + iωc, kr + iωcr) between DOF pairs a and b (a bearing: b to ground). With G₀ the receptance
of the structure without the *variable* elements (the components' exact receptances, block-diagonal,
joined through the fixed elements), adding the variable ones is, by the Woodbury identity,

    G = G₀ − U (K⁻¹ + P)⁻¹ V,   U = G₀ D,  V = Dᵀ G₀,  P = Dᵀ G₀ D,

with D (k, m) the incidence of the m variable element DOFs (+1 at b, −1 at a). Only the points' and the
elements' DOFs are kept, so a population of parameter sets costs one batch of (m × m) solves per
frequency. With a single variable element the entries of G are rational in its coefficients and
:meth:`ReceptanceModel.coupler` returns the fast :class:`~toolpoint.dynamics.coupling.ToolPointCoupler`.
"""

from __future__ import annotations

import re
from dataclasses import dataclass, replace

import numpy as np

from .assembly import MM, Assembly, Bearing, Component
from .components import assemble, mesh, receptance
from .coupling import ToolPointCoupler
from .fe import FEModel
from ..errors import InputError
from ..frf import check_freq_hz

__all__ = ["Point", "NAMED_POINTS", "parse_point", "parse_at", "element_names", "ReceptanceModel", "fe_frf"]

NAMED_POINTS = {"tool_tip": "tool", "holder_tip": "holder", "spindle_nose": "spindle"}
"""Named points → the component whose far end they are."""

_XPOINT = re.compile(r"^(spindle|holder|tool):x_mm=(.+)$")


@dataclass(frozen=True)
class Point:
    """A translational DOF on a component.

    Attributes
    ----------
    component : str
        ``spindle``, ``holder`` or ``tool``.
    x : float or None
        Distance from the component's start, m; None means its far end (the named tips).
    text : str
        As the user wrote it.
    """

    component: str
    x: float | None
    text: str

    def position(self, comp: Component) -> float:
        """x on ``comp``, m (its length for an end point)."""
        return comp.length if self.x is None else self.x


def parse_point(text: str, *, file=None, field: str = "at") -> Point:
    """``tool_tip``, ``holder_tip``, ``spindle_nose`` or ``COMPONENT:x_mm=X`` → :class:`Point`.

    Examples
    --------
    >>> parse_point("tool:x_mm=40").x
    0.04
    >>> parse_point("nose", file="command line", field="--at")
    Traceback (most recent call last):
    ...
    toolpoint.errors.InputError: command line: --at: unknown point 'nose' (tool_tip, holder_tip, \
spindle_nose or COMPONENT:x_mm=X with COMPONENT spindle, holder or tool)
    """
    t = str(text).strip()
    if t in NAMED_POINTS:
        return Point(NAMED_POINTS[t], None, t)
    m = _XPOINT.match(t)
    if m:
        try:
            x = float(m.group(2))
        except ValueError:
            x = float("nan")
        if not np.isfinite(x) or x < 0:
            raise InputError(f"x_mm must be a number ≥ 0, got {m.group(2)!r}", file=file, field=field)
        return Point(m.group(1), x * MM, t)
    raise InputError(f"unknown point {t!r} (tool_tip, holder_tip, spindle_nose or COMPONENT:x_mm=X with "
                     "COMPONENT spindle, holder or tool)", file=file, field=field)


def parse_at(text: str, *, file=None, field: str = "at") -> tuple[Point, Point]:
    """``"P"`` (direct FRF at P) or ``"P,Q"`` (response at P, force at Q) → (response, force) points.

    Examples
    --------
    >>> [p.text for p in parse_at("tool_tip,holder_tip")]
    ['tool_tip', 'holder_tip']
    """
    parts = [s for s in str(text).split(",")]
    if len(parts) not in (1, 2):
        raise InputError(f"expected POINT or RESPONSE,FORCE, got {text!r}", file=file, field=field)
    pts = [parse_point(p, file=file, field=field) for p in parts]
    return (pts[0], pts[-1])


def element_names(assembly: Assembly, with_tool: bool) -> list[str]:
    """The spring elements of ``assembly``: ``spindle_holder``, ``holder_tool`` (with a tool), ``bearings[i]``."""
    names = ["spindle_holder"] + (["holder_tool"] if with_tool else [])
    return names + [f"bearings[{i}]" for i in range(len(assembly.spindle.bearings))]


@dataclass
class _Element:
    name: str
    a: int | None  # kept-DOF index of the w DOF on side a (None: ground)
    b: int
    rot: bool  # has a rotational spring
    value: np.ndarray  # (4,) k, c, kr, cr (SI)


class ReceptanceModel:
    """Receptances between named points for many values of the variable spring elements (module docstring).

    Parameters
    ----------
    assembly : Assembly
    freq_hz : array_like
        (F,) frequencies > 0 Hz (any order: several measurements' grids may be concatenated).
    points : sequence of Point
        Every point an FRF will be asked for.
    variable : sequence of str
        Elements whose values change (:func:`element_names`); the others keep the assembly's values.
    with_tool : bool, optional
        Include the tool (and the holder–tool joint). Default: when the assembly has a tool and either its
        holder–tool joint is given or ``holder_tool`` is variable.
    max_beta_l : float, optional
        Mesh parameter (:func:`~toolpoint.dynamics.components.mesh`); the pieces are exact.
    rot : dict, optional
        element name → whether a variable bearing gets a rotational spring (default: when its kr or cr ≠ 0).

    Raises
    ------
    InputError
        A point on a component the structure does not have, outside its component, an unknown element,
        or a fixed joint the assembly does not give.

    Examples
    --------
    >>> from toolpoint.dynamics.assembly import load_assembly
    >>> a = load_assembly("examples/numerical_case.toml")
    >>> f = np.array([500.0, 1500.0])
    >>> tip = parse_point("holder_tip")
    >>> m = ReceptanceModel(a, f, [tip], ["spindle_holder"], with_tool=False)
    >>> h = m.frf(a.spindle_holder.as_array()[None, None], tip, tip)[0]
    >>> from toolpoint.dynamics.subassembly import Subassembly
    >>> bool(np.allclose(h, Subassembly.from_assembly(a, f).R[:, 0, 0], rtol=1e-9))
    True
    """

    def __init__(self, assembly: Assembly, freq_hz, points, variable, *, with_tool: bool | None = None,
                 max_beta_l: float | None = None, rot: dict | None = None):
        f = check_freq_hz(np.unique(np.asarray(freq_hz, float)), positive=True)  # grids may repeat
        self.freq_hz = np.asarray(freq_hz, float)
        self.omega = w = 2 * np.pi * self.freq_hz
        self.assembly = a = assembly
        variable = list(dict.fromkeys(variable))
        if with_tool is None:
            with_tool = a.tool is not None and (a.holder_tool is not None or "holder_tool" in variable)
        if with_tool and a.tool is None:
            raise InputError("missing section (the model needs the tool)", file=a.source, field="tool")
        self.with_tool = with_tool
        known = element_names(a, with_tool)
        for name in variable:
            if name not in known:
                raise InputError(f"unknown element {name!r} (this structure has {', '.join(known)})",
                                 file=a.source, field="params")
        comps = [a.spindle, a.holder] + ([a.tool] if with_tool else [])
        by_name = {c.name: c for c in comps}
        self.points = list(dict.fromkeys(points))
        for p in self.points:
            if p.component not in by_name:
                raise InputError(f"point {p.text!r}: this structure has no {p.component} "
                                 f"(it has {', '.join(by_name)})", file=a.source, field="at")
            L = by_name[p.component].length
            if p.x is not None and not p.x <= L * (1 + 1e-12):
                raise InputError(f"point {p.text!r} lies outside the {p.component} (0–{L / MM:g} mm)",
                                 file=a.source, field="at")
        rot = rot or {}
        var_bearings = {int(n[9:-1]) for n in variable if n.startswith("bearings[")}
        # meshes: cut at points (zero springs) and bearings; variable bearings are taken out of the spindle
        kept: list[list[tuple[int, float]]] = []  # per component: (node, x)
        meshes = []
        for c in comps:
            bearings = tuple(Bearing(b.x, 0.0) if (c is a.spindle and i in var_bearings) else b
                             for i, b in enumerate(c.bearings))
            xs = [0.0, c.length] + [p.position(c) for p in self.points if p.component == c.name]
            xs += [b.x for b in c.bearings] if c is a.spindle else []
            cc = replace(c, bearings=bearings + tuple(Bearing(x, 0.0) for x in xs))
            m = mesh(cc, f.max(), max_beta_l)
            meshes.append(m)
            kept.append(sorted({int(np.argmin(abs(m.x - x))) for x in xs}))
        # kept DOFs: (w, ψ) of each kept node, component after component
        self._index: dict[tuple[str, int], int] = {}
        blocks = []
        k = 0
        for c, m, nodes in zip(comps, meshes, kept):
            D, _ = assemble([m], [], w)
            dofs = [d for n in nodes for d in (2 * n, 2 * n + 1)]
            blocks.append(receptance(D, dofs))
            for n in nodes:
                self._index[(c.name, n)] = k
                k += 2
        G = np.zeros((w.size, k, k), complex)
        s = 0
        for B in blocks:
            G[:, s : s + B.shape[1], s : s + B.shape[1]] = B
            s += B.shape[1]

        def dof(comp: Component, x: float) -> int:
            m = meshes[comps.index(comp)]
            return self._index[(comp.name, int(np.argmin(abs(m.x - x))))]

        self._point_dof = {p: dof(by_name[p.component], p.position(by_name[p.component])) for p in self.points}
        elements = []
        joints = [("spindle_holder", a.spindle, a.holder, a.spindle_holder)]
        if with_tool:
            joints.append(("holder_tool", a.holder, a.tool, a.holder_tool))
        for name, ca, cb, joint in joints:
            if joint is None and name not in variable:
                raise InputError("missing section (needed unless identified)", file=a.source, field=f"joints.{name}")
            value = joint.as_array() if joint is not None else np.full(4, np.nan)
            elements.append(_Element(name, dof(ca, ca.length), dof(cb, 0.0), True, value))
        for i, b in enumerate(a.spindle.bearings):
            name = f"bearings[{i}]"
            if name in variable:
                has_rot = rot.get(name, b.kr != 0 or b.cr != 0)
                elements.append(_Element(name, None, dof(a.spindle, b.x), has_rot, np.array([b.k, b.c, b.kr, b.cr])))
        fixed = [e for e in elements if e.name not in variable]
        self.elements = [next(e for e in elements if e.name == n) for n in variable]
        if fixed:
            G = self._woodbury(G, fixed, np.stack([e.value for e in fixed])[None])[0]
        self.G0 = G
        self._D = self._incidence(self.elements, k)
        self.P = np.einsum("km,fkl,ln->fmn", self._D, G, self._D)
        self._symmetric = bool(np.allclose(self.P, np.swapaxes(self.P, -1, -2), rtol=1e-10, atol=0.0))
        self._uv_cache: dict = {}

    # ------------------------------------------------------------------ internals
    @staticmethod
    def _incidence(elements, k: int) -> np.ndarray:
        cols = []
        for e in elements:
            for d in (0, 1) if e.rot else (0,):
                col = np.zeros(k)
                col[e.b + d] = 1.0
                if e.a is not None:
                    col[e.a + d] = -1.0
                cols.append(col)
        return np.stack(cols, 1) if cols else np.zeros((k, 0))

    def _kinv(self, elements, values) -> np.ndarray:
        """K⁻¹ diagonal (N, F, m) for values (N, n_el, 4)."""
        w = self.omega
        out = []
        for i, e in enumerate(elements):
            v = values[:, i]
            out.append(1.0 / (v[:, 0, None] + 1j * w * v[:, 1, None]))
            if e.rot:
                out.append(1.0 / (v[:, 2, None] + 1j * w * v[:, 3, None]))
        return np.stack(out, -1)

    def _woodbury(self, G, elements, values) -> np.ndarray:
        D = self._incidence(elements, G.shape[1])
        P = np.einsum("km,fkl,ln->fmn", D, G, D)
        U = G @ D
        M = P[None] + np.einsum("nfm,mq->nfmq", self._kinv(elements, values), np.eye(D.shape[1]))
        return G[None] - U[None] @ np.linalg.solve(M, (D.T @ G)[None])

    def _check(self, values) -> np.ndarray:
        v = np.asarray(values, float)
        if v.ndim != 3 or v.shape[1:] != (len(self.elements), 4):
            raise ValueError(f"values must be (N, {len(self.elements)}, 4), got {v.shape}")
        return v

    # ------------------------------------------------------------------ public
    def dof(self, point: Point) -> int:
        """Index of ``point``'s w DOF in :attr:`G0`."""
        return self._point_dof[point]

    def frf(self, values, i: Point, j: Point, sl: slice = slice(None)) -> np.ndarray:
        """Receptance (N, F) between response point ``i`` and force point ``j`` (m/N).

        Parameters
        ----------
        values : (N, n_elements, 4) array
            [k N/m, c N s/m, kr N m/rad, cr N m s/rad] of every variable element, in :attr:`elements` order.
        i, j : Point
        sl : slice
            Frequencies (a slice of ``freq_hz``).
        """
        return self.frf_jac(values, i, j, sl, jac=False)[0]

    def frf_jac(self, values, i: Point, j: Point, sl: slice = slice(None), jac: bool = True):
        """:meth:`frf` and its exact derivatives ∂h/∂value (N, n_elements, 4, F) (None when ``jac`` is False).

        ∂G_ij/∂θ = (U M⁻¹)_i,e (∂K⁻¹_e/∂θ) (M⁻¹ V)_e,j with M = K⁻¹ + P and ∂(1/k̃)/∂k = −1/k̃²,
        ∂(1/k̃)/∂c = −iω/k̃².
        """
        v = self._check(values)
        di, dj = self._point_dof[i], self._point_dof[j]
        G = self.G0[sl]
        w = self.omega[sl]
        kinv = self._kinv_sl(v, sl)  # (N, F, m)
        m = self._D.shape[1]
        M = self.P[sl][None] + kinv[..., None] * np.eye(m)
        Ui, Vj = self._uv(di, dj, sl)
        if jac and self._symmetric:  # reciprocity: Mᵀ = M, one solve for both right-hand sides
            ab = np.linalg.solve(M, np.broadcast_to(np.stack([Vj, Ui], -1)[None], M.shape[:-1] + (2,)))
            b, a = ab[..., 0], ab[..., 1]
        else:
            b = np.linalg.solve(M, np.broadcast_to(Vj[None, ..., None], M.shape[:-1] + (1,)))[..., 0]  # (N, F, m)
        h = G[None, :, di, dj] - np.einsum("fm,nfm->nf", Ui, b)
        if not jac:
            return h, None
        if not self._symmetric:
            a = np.linalg.solve(np.swapaxes(M, -1, -2),
                                np.broadcast_to(Ui[None, ..., None], M.shape[:-1] + (1,)))[..., 0]
        ab = a * b  # (N, F, m): ∂h/∂(K⁻¹_e) = a_e b_e
        out = np.zeros((v.shape[0], len(self.elements), 4, w.size), complex)
        col = 0
        for e_i, e in enumerate(self.elements):
            for slot in (0, 1) if e.rot else (0,):
                kt = v[:, e_i, 2 * slot, None] + 1j * w * v[:, e_i, 2 * slot + 1, None]
                dk = -ab[..., col] / kt**2  # ∂h/∂k
                out[:, e_i, 2 * slot] = dk
                out[:, e_i, 2 * slot + 1] = dk * 1j * w
                col += 1
        return h, out

    def minors(self, i: Point, j: Point, sl: slice = slice(None)) -> tuple[np.ndarray, np.ndarray]:
        r"""The receptance between ``i`` and ``j`` as a ratio of polynomials in the element stiffnesses.

        With k̃_d = k_d + iω c_d the complex stiffness of variable DOF d (the columns of the incidence D,
        element by element, translation before rotation) and K = diag(k̃), expanding the determinants of
        M = K⁻¹ + P and of the bordered matrix Q = [[P, V_j], [U_iᵀ, G₀,ij]] in the diagonal terms gives

            h_ij = Σ_T num_T Π_{d∈T} k̃_d / Σ_T den_T Π_{d∈T} k̃_d,
            den_T = det P[T, T],  num_T = det Q[T ∪ {m}, T ∪ {m}],

        summed over the 2^m subsets T of the m variable DOFs (den_∅ = 1, num_∅ = G₀,ij).

        Returns
        -------
        num, den : (F, 2^m) complex ndarray
            Coefficients, column ``mask`` for the subset T = {d : bit d of mask set}; m/N · (N/m)^|T| units.

        Examples
        --------
        >>> from toolpoint.dynamics.assembly import load_assembly
        >>> a = load_assembly("examples/numerical_case.toml")
        >>> f = np.array([500.0, 1500.0])
        >>> tip = parse_point("holder_tip")
        >>> m = ReceptanceModel(a, f, [tip], ["spindle_holder"], with_tool=False)
        >>> num, den = m.minors(tip, tip)
        >>> kt, ct, kr, cr = a.spindle_holder.as_array()
        >>> k = np.stack([kt + 1j * m.omega * ct, kr + 1j * m.omega * cr], -1)
        >>> mono = np.stack([np.ones(2), k[:, 0], k[:, 1], k[:, 0] * k[:, 1]], -1)
        >>> h = (num * mono).sum(1) / (den * mono).sum(1)
        >>> bool(np.allclose(h, m.frf(a.spindle_holder.as_array()[None, None], tip, tip)[0], rtol=1e-9))
        True
        """
        G, D = self.G0[sl], self._D
        di, dj = self._point_dof[i], self._point_dof[j]
        m = D.shape[1]
        Q = np.empty((G.shape[0], m + 1, m + 1), complex)
        Q[:, :m, :m] = self.P[sl]
        Q[:, :m, m] = np.einsum("km,fk->fm", D, G[:, :, dj])
        Q[:, m, :m] = np.einsum("fk,km->fm", G[:, di, :], D)
        Q[:, m, m] = G[:, di, dj]
        num = np.empty((G.shape[0], 2**m), complex)
        den = np.empty_like(num)
        for mask in range(2**m):
            idx = [d for d in range(m) if mask >> d & 1]
            den[:, mask] = np.linalg.det(Q[:, idx][:, :, idx]) if idx else 1.0
            idx.append(m)
            num[:, mask] = np.linalg.det(Q[:, idx][:, :, idx])
        return num, den

    def _uv(self, di: int, dj: int, sl: slice):
        """U_i = (G₀ D)_i and V_j = (Dᵀ G₀)_j on ``sl`` (F, m), cached per (i, j, slice)."""
        key = (di, dj, sl.start, sl.stop, sl.step)
        if key not in self._uv_cache:
            G, D = self.G0[sl], self._D
            self._uv_cache[key] = (np.einsum("fk,km->fm", G[:, di, :], D), np.einsum("km,fk->fm", D, G[:, :, dj]))
        return self._uv_cache[key]

    def _kinv_sl(self, v, sl):
        w_all = self.omega
        self.omega = w_all[sl]
        try:
            return self._kinv(self.elements, v)
        finally:
            self.omega = w_all

    def coupler(self, i: Point, j: Point, sl: slice = slice(None)) -> ToolPointCoupler:
        """The rational form h(k, c, kr, cr) of the single variable element between ``i`` and ``j``.

        Returns
        -------
        ToolPointCoupler
            ``coupler(params)`` with params (N, 4) = the element's [k, c, kr, cr]: as :meth:`frf`.
        """
        if len(self.elements) != 1:
            raise ValueError("the rational form needs exactly one variable element")
        e = self.elements[0]
        G = self.G0[sl]
        di, dj = self._point_dof[i], self._point_dof[j]
        rows = [e.b, e.b + 1]
        u = G[:, di, rows] - (G[:, di, [e.a, e.a + 1]] if e.a is not None else 0)
        v = G[:, rows, dj] - (G[:, [e.a, e.a + 1], dj] if e.a is not None else 0)
        Dfull = np.zeros((G.shape[1], 2))
        Dfull[rows, [0, 1]] = 1.0
        if e.a is not None:
            Dfull[[e.a, e.a + 1], [0, 1]] = -1.0
        P = np.einsum("km,fkl,ln->fmn", Dfull, G, Dfull)
        # no rotational spring (a bearing with kr = cr = 0): k̃r = 0 in the rational form does the same
        return ToolPointCoupler.from_parts(G[:, di, dj], u, v, P, self.omega[sl])


def fe_frf(assembly: Assembly, freq_hz, response: Point, force: Point | None = None, *, with_tool: bool = True,
           max_element_m: float = 2e-3) -> np.ndarray:
    """Receptance (F,) between two points of the full-assembly FE model (:mod:`toolpoint.dynamics.fe`), m/N.

    An independent check of :class:`ReceptanceModel`: Timoshenko beam elements, joints and bearings as
    springs, one banded solve per frequency. ``with_tool=False`` models the spindle–holder subassembly.

    Examples
    --------
    >>> from toolpoint.dynamics.assembly import load_assembly
    >>> a = load_assembly("examples/numerical_case.toml")
    >>> tip = parse_point("holder_tip")
    >>> h = fe_frf(a, [800.0], tip, with_tool=False)
    >>> m = ReceptanceModel(a, [800.0], [tip], [], with_tool=False)
    >>> bool(abs(h[0] / m.G0[0, m.dof(tip), m.dof(tip)] - 1) < 1e-3)
    True
    """
    force = force or response
    comps = [assembly.spindle, assembly.holder] + ([assembly.tool] if with_tool else [])
    joints = [assembly.spindle_holder.as_array()] + ([assembly.holder_tool.as_array()] if with_tool else [])
    cut = []
    for c in comps:
        xs = [p.position(c) for p in (response, force) if p.component == c.name]
        cut.append(replace(c, bearings=c.bearings + tuple(Bearing(x, 0.0) for x in xs)))
    fe = FEModel(cut, joints, max_element_m)
    names = [c.name for c in comps]
    dofs = []
    for p in (response, force):
        if p.component not in names:
            raise InputError(f"point {p.text!r}: this structure has no {p.component}", file=assembly.source,
                             field="at")
        ci = names.index(p.component)
        dofs.append(fe.node_dof(ci, p.position(comps[ci])))
    return fe.receptance(freq_hz, dofs[0], force_dof=dofs[1])
