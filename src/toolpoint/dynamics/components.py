"""Beam components → end-point receptances.

Two exact routes to the same receptances, chosen per frequency for round-off:

* **transfer chain** — T = Pₙ Tₙ ⋯ P₁ T₁ P₀ (pieces T, spring point matrices
  P = [[I, 0], [G, I]]); with end loads (F, M) at both ends the end receptance is
  R = [[T21⁻¹T22, T21⁻¹], [T11T21⁻¹T22 − T12, T11T21⁻¹]]. It keeps every entry's
  relative precision at low frequency, but the product grows like exp(Σ βL), so
  it is used only while Σ|β|L ≤ ``CHAIN_LIMIT``, only for free–free
  components (holder, tool, a suspended spindle), and only where its result is
  reciprocal to ``CHAIN_RECIPROCITY`` (a stiffness contrast costs digits too);
* **stiffness sweep** — condensation of the chain's dynamic stiffness onto
  its end nodes, well conditioned at high frequency.

A component (multi-segment beam, optional bearings to ground) is cut into
pieces at segment ends and bearing positions, and each piece into equal
sub-pieces so that its bending wavenumber times length stays ≤ ``max_beta_l``
at the top frequency (the piece stiffness is then far from its own
clamped–clamped poles). The piece matrices are exact
(:mod:`toolpoint.dynamics.beam`), so refining only re-expresses the same solution.

Global dynamic stiffness D(ω) (2 DOF per node: w, ψ) is assembled for all
frequencies at once and solved in one batched LAPACK call for the columns of
the requested end nodes: R = (D⁻¹)[ends, ends] is the receptance matrix,
[[h, l], [n, p]] per node pair (h = w/F, l = w/M, n = ψ/F, p = ψ/M).
Why the two routes and these limits: ``docs/design/dynamics.md``.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .assembly import Component
from .beam import inv2, mul2, stiffness_from_transfer, transfer_matrices

__all__ = ["MAX_BETA_L", "CHAIN_LIMIT", "CHAIN_RECIPROCITY", "Mesh", "interior_cuts", "mesh", "chain_growth",
           "assemble", "receptance", "end_receptances", "end_receptances_dense"]

MAX_BETA_L = 2.0
"""Default largest bending wavenumber × piece length at the top frequency (dimensionless)."""

# Above Σ βL ≈ 6 (past the first free–free mode, βL = 4.73) the stiffness
# sweep is well conditioned while the chain starts to lose digits (e^6 ≈ 400).
CHAIN_LIMIT = 6.0
"""Largest chain growth exponent Σ βL for which the transfer chain is used (dimensionless)."""

CHAIN_RECIPROCITY = 1e-10
"""Largest relative reciprocity defect max|R − Rᵀ| / max|R| of a chain result kept (dimensionless).

Measured (2026-11-27) on 300 free–free beams with 8–10 mm necks between 20–90 mm segments, 20–5000 Hz: the chain's
defect tracked its error against the dense solve (both up to 5e-7), and no frequency with Σ βL < 2 crossed it.
"""


@dataclass(frozen=True)
class Mesh:
    """Nodes and exact pieces of one component.

    Attributes
    ----------
    x : numpy.ndarray
        (N,) node positions, m, from the component's start.
    pieces : tuple
        (Section, length m, left node index) per piece.
    ground : tuple
        (node, k N/m, c N s/m, kr N m/rad, cr N m s/rad) springs to ground.
    """

    x: np.ndarray
    pieces: tuple
    ground: tuple

    @property
    def n_nodes(self) -> int:
        """Number of nodes N."""
        return self.x.size


def interior_cuts(x0: float, x1: float, points, tol: float = 1e-9) -> list[float]:
    """[x0, points strictly inside (x0, x1), x1]; a point within ``tol`` m of an end is that end."""
    inside = sorted(p for p in points if x0 + tol < p < x1 - tol)
    return [x0] + [p for i, p in enumerate(inside) if i == 0 or p - inside[i - 1] > tol] + [x1]


def mesh(component: Component, fmax_hz: float, max_beta_l: float | None = None) -> Mesh:
    """Cut ``component`` at segment ends and bearings; sub-divide for conditioning at ``fmax_hz``.

    Every piece gets n = ⌈β(ω_max) L / max_beta_l⌉ equal sub-pieces, β the
    Euler–Bernoulli bending wavenumber (1/m) at ω_max = 2π max(fmax_hz, 1 Hz).

    Parameters
    ----------
    component : Component
    fmax_hz : float
        Highest frequency the mesh serves, Hz.
    max_beta_l : float, optional
        Largest βL per piece; None means :data:`MAX_BETA_L` (read at call time).
        Smaller values give more pieces (the same exact answer: a convergence check).

    Examples
    --------
    >>> from toolpoint.dynamics.assembly import Component, Material, Segment
    >>> bar = Component("bar", (Segment(0.3, 0.02, 0.0, Material("steel", 210e9, 7800.0, 0.3)),))
    >>> len(mesh(bar, 3000.0).pieces), len(mesh(bar, 3000.0, max_beta_l=0.25).pieces)
    (5, 33)
    """
    max_beta_l = MAX_BETA_L if max_beta_l is None else float(max_beta_l)
    if not max_beta_l > 0:
        raise ValueError(f"max_beta_l must be > 0, got {max_beta_l!r}")
    wmax = 2 * np.pi * max(float(fmax_hz), 1.0)
    edges = np.cumsum([0.0] + [s.length for s in component.segments])
    xs = [0.0]
    pieces = []
    for seg, x0, x1 in zip(component.segments, edges[:-1], edges[1:]):
        sec = seg.section()
        cuts = interior_cuts(x0, x1, [b.x for b in component.bearings])
        for a, b in zip(cuts[:-1], cuts[1:]):
            n = max(1, int(np.ceil(float(sec.wavenumber(wmax)) * (b - a) / max_beta_l)))
            for k in range(n):
                pieces.append((sec, (b - a) / n, len(xs) - 1))
                xs.append(a + (b - a) * (k + 1) / n)
    x = np.array(xs)
    x[-1] = edges[-1]
    ground = []
    for b in component.bearings:
        node = int(np.argmin(abs(x - b.x)))
        ground.append((node, b.k, b.c, b.kr, b.cr))
    return Mesh(x, tuple(pieces), tuple(ground))


def _piece_transfers(m: Mesh, omega: np.ndarray) -> list[np.ndarray]:
    """Transfer matrix of every piece; equal pieces share one evaluation, all in one pass."""
    keys = [(id(sec), round(length, 15)) for sec, length, _ in m.pieces]
    unique = list(dict.fromkeys(keys))
    first = {k: i for i, k in reversed(list(enumerate(keys)))}
    Ts = transfer_matrices([m.pieces[first[k]][:2] for k in unique], omega)
    at = {k: Ts[i] for i, k in enumerate(unique)}
    return [at[k] for k in keys]


def _piece_matrices(m: Mesh, omega: np.ndarray) -> list[np.ndarray]:
    """Dynamic stiffness of every piece (shared like the transfer matrices)."""
    done: dict[int, np.ndarray] = {}
    return [done.setdefault(id(T), stiffness_from_transfer(T)) for T in _piece_transfers(m, omega)]


def _ground(m: Mesh, omega: np.ndarray) -> np.ndarray:
    """Spring-to-ground 2×2 matrices G (n_nodes, F, 2, 2), diag(k + iωc, kr + iωcr)."""
    G = np.zeros((m.n_nodes, omega.size, 2, 2), complex)
    for node, k, c, kr, cr in m.ground:
        G[node, :, 0, 0] += k + 1j * omega * c
        G[node, :, 1, 1] += kr + 1j * omega * cr
    return G


def chain_growth(m: Mesh, omega: np.ndarray) -> np.ndarray:
    """Σ βL over the pieces (F,): the transfer chain's growth exponent."""
    return sum(sec.wavenumber(omega) * length for sec, length, _ in m.pieces)


def assemble(meshes: list[Mesh], links: list[tuple], omega) -> tuple[np.ndarray, list[int]]:
    """Global dynamic stiffness (F, N, N) of several meshes joined by springs.

    ``links`` holds (mesh_a, node_a, mesh_b, node_b, kt, ct, kr, cr): a zero-length
    joint K = diag(kt + iωct, kr + iωcr) between two nodes. Returns D and the
    first DOF index of each mesh.
    """
    w = np.asarray(omega, float).reshape(-1)
    offsets = np.cumsum([0] + [2 * m.n_nodes for m in meshes])
    D = np.zeros((w.size, offsets[-1], offsets[-1]), complex)
    for m, off in zip(meshes, offsets[:-1]):
        for (sec, length, node), Dp in zip(m.pieces, _piece_matrices(m, w)):
            i = off + 2 * node
            D[:, i : i + 4, i : i + 4] += Dp
        for node, k, c, kr, cr in m.ground:
            i = off + 2 * node
            D[:, i, i] += k + 1j * w * c
            D[:, i + 1, i + 1] += kr + 1j * w * cr
    for ma, na, mb, nb, kt, ct, kr, cr in links:
        for d, kk in ((0, kt + 1j * w * ct), (1, kr + 1j * w * cr)):
            i, j = offsets[ma] + 2 * na + d, offsets[mb] + 2 * nb + d
            D[:, i, i] += kk
            D[:, j, j] += kk
            D[:, i, j] -= kk
            D[:, j, i] -= kk
    return D, list(offsets[:-1])


def receptance(D: np.ndarray, dofs: list[int]) -> np.ndarray:
    """(D⁻¹)[dofs, dofs] for every frequency: (F, k, k)."""
    E = np.zeros((D.shape[1], len(dofs)))
    E[dofs, np.arange(len(dofs))] = 1.0
    X = np.linalg.solve(D, np.broadcast_to(E, (D.shape[0],) + E.shape))
    return X[:, dofs, :]


def _chain_receptance(m: Mesh, omega: np.ndarray) -> np.ndarray:
    """End receptance (F, 4, 4) by the transfer chain (see module docstring)."""
    G = _ground(m, omega)
    grounded = {g[0] for g in m.ground}
    T = np.broadcast_to(np.eye(4, dtype=complex), (omega.size, 4, 4)).copy()
    for (_, _, node), Tp in zip(m.pieces, _piece_transfers(m, omega)):
        if node in grounded:  # point matrix [[I, 0], [G, I]] at the piece's left node
            T[:, 2:, :] += G[node] @ T[:, :2, :]
        T = Tp @ T
    if m.n_nodes - 1 in grounded:
        T[:, 2:, :] += G[-1] @ T[:, :2, :]
    T11, T12, T21, T22 = T[:, :2, :2], T[:, :2, 2:], T[:, 2:, :2], T[:, 2:, 2:]
    T21i = inv2(T21)
    R = np.empty_like(T)
    R[:, :2, :2] = mul2(T21i, T22)
    R[:, :2, 2:] = T21i
    R[:, 2:, :2] = mul2(T11, R[:, :2, :2]) - T12
    R[:, 2:, 2:] = mul2(T11, T21i)
    return R


def _chain_end_stiffness(m: Mesh, omega: np.ndarray) -> np.ndarray:
    """Dynamic stiffness (F, 4, 4) condensed onto the first and last node of a chain.

    Interior nodes are condensed one at a time (block Gaussian elimination along
    the chain, ``Z ← Z − Z_·k Π⁻¹ Z_k·`` with the 2×2 pivot Π at node k): a few
    2×2 operations per node instead of a dense solve. A pivot is singular only at
    a clamped–clamped natural frequency of the chain up to node k + 1.
    """
    G = _ground(m, omega)
    P = _piece_matrices(m, omega)
    Z = P[0].copy()
    Z[:, :2, :2] += G[0]
    Z[:, 2:, 2:] += G[1]
    for k, Pk in enumerate(P[1:], start=1):
        Pi = inv2(Z[:, 2:, 2:] + Pk[:, :2, :2])
        A = mul2(Z[:, :2, 2:], Pi)  # Z_0k Π⁻¹
        B = mul2(Pk[:, 2:, :2], Pi)  # P_ba Π⁻¹
        Zn = np.empty_like(Z)
        Zn[:, :2, :2] = Z[:, :2, :2] - mul2(A, Z[:, 2:, :2])
        Zn[:, :2, 2:] = -mul2(A, Pk[:, :2, 2:])
        Zn[:, 2:, :2] = -mul2(B, Z[:, 2:, :2])
        Zn[:, 2:, 2:] = Pk[:, 2:, 2:] - mul2(B, Pk[:, :2, 2:]) + G[k + 1]
        Z = Zn
    return Z


def end_receptances(component: Component, freq_hz, ends: str = "both", *,
                    max_beta_l: float | None = None) -> np.ndarray:
    """Receptance matrix at the component's ends, one global x axis.

    Parameters
    ----------
    component : Component
    freq_hz : array_like
        (F,) frequencies, Hz. A free–free component is singular at 0 Hz: ask for ω > 0 only.
    ends : str
        ``"both"`` → (F, 4, 4) on [w_start, ψ_start, w_end, ψ_end];
        ``"end"`` → (F, 2, 2) at the end (x = L) only; ``"start"`` likewise.
    max_beta_l : float, optional
        Mesh parameter (see :func:`mesh`).

    Returns
    -------
    numpy.ndarray
        Complex receptances, blocks [[h, l], [n, p]] in m/N, 1/N, rad/N, rad/(N m).

    Examples
    --------
    Slender free–free bar far below its first mode: the rigid-body mass line
    h ≈ −4/(m ω²) at either end.

    >>> import numpy as np
    >>> from toolpoint.dynamics.assembly import Component, Material, Segment
    >>> bar = Component("bar", (Segment(0.3, 0.02, 0.0, Material("steel", 210e9, 7800.0, 0.3)),))
    >>> h = end_receptances(bar, [1.0], "end")[0, 0, 0]
    >>> bool(abs(h.real * bar.mass * (2 * np.pi) ** 2 / -4 - 1) < 0.01)
    True
    """
    f = np.asarray(freq_hz, float).reshape(-1)
    if not component.bearings and np.any(f == 0):
        raise ValueError(f"{component.name}: free–free receptance is singular at 0 Hz")
    m = mesh(component, f.max() if f.size else 1.0, max_beta_l)
    w = 2 * np.pi * f
    R = np.empty((f.size, 4, 4), complex)
    # The chain is for free–free parts only: stiff springs in a chain mix scales
    # and cost digits, while a grounded stiffness matrix is regular at low ω.
    low = chain_growth(m, w) <= CHAIN_LIMIT if not component.bearings else np.zeros(f.size, bool)
    if np.any(low):
        idx = np.flatnonzero(low)
        Rc = _chain_receptance(m, w[idx])
        # The chain reaches the cross receptances by two routes (T21⁻¹ and T11T21⁻¹T22 − T12): they agree as far as
        # the chain kept its digits. A stiffness contrast (a thin neck between thick segments) costs digits that
        # Σ βL does not see: 8 mm between 90 mm lost 1e-7 at Σ βL 5.5, where the sweep kept 6e-15. Where
        # reciprocity fails by more than CHAIN_RECIPROCITY, the sweep takes the frequency.
        asym = np.abs(Rc - np.swapaxes(Rc, 1, 2)).max(axis=(1, 2)) / np.abs(Rc).max(axis=(1, 2))
        ok = asym <= CHAIN_RECIPROCITY
        R[idx[ok]] = Rc[ok]
        low[idx[~ok]] = False
    if not np.all(low):
        R[~low] = np.linalg.inv(_chain_end_stiffness(m, w[~low]))
    sel = {"both": slice(0, 4), "end": slice(2, 4), "start": slice(0, 2)}[ends]
    return R[:, sel, sel]


def end_receptances_dense(component: Component, freq_hz, ends: str = "both", *,
                          max_beta_l: float | None = None) -> np.ndarray:
    """Same as :func:`end_receptances` by a dense LAPACK solve of the whole chain (a check)."""
    f = np.asarray(freq_hz, float).reshape(-1)
    m = mesh(component, f.max() if f.size else 1.0, max_beta_l)
    D, _ = assemble([m], [], 2 * np.pi * f)
    last = 2 * (m.n_nodes - 1)
    dofs = {"both": [0, 1, last, last + 1], "end": [last, last + 1], "start": [0, 1]}[ends]
    return receptance(D, dofs)
