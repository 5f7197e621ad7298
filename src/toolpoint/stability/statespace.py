"""Tool-point dynamics as a first-order state-space model, the input of the semi-discretisation.

The tool point is a linear system with two inputs, the cutting forces
F = (F_x, F_y) (N), and two outputs, the displacements r = (x, y) (m):

    ż = A z + B F,     r = C z,                                            (1)

so its receptance matrix is Φ(iω) = C (iωI − A)⁻¹ B (m/N), cross terms
Φ_xy, Φ_yx included. Every modal description enters the same way:

* real modes per direction (:class:`ModalModel`):
  per mode the states (q_r, q̇_r) with q̈_r + 2ζ_rω_r q̇_r + ω_r² q_r = F_d/m_r,
  output d = Σ q_r (:meth:`StateSpaceModel.from_modes`);
* complex poles λ_r = σ_r + iω_dr with complex 2×2 residue matrices R_r,
  Φ(s) = Σ_r R_r/(s − λ_r) + conj(R_r)/(s − conj λ_r) (non-proportional
  damping and cross FRFs): each rank-one term c bᵀ of R_r (from its SVD) is a
  real 2×2 block, the real and imaginary parts p, q of the complex modal
  coordinate ζ̇ = λζ + bᵀF (:meth:`StateSpaceModel.from_poles`),

      d/dt [p, q] = [[σ, −ω_d], [ω_d, σ]] [p, q] + [Re bᵀ; Im bᵀ] F,   r = 2 Re c p − 2 Im c q;

* a common-pole fit of :mod:`toolpoint.dynamics.modal` (:func:`from_modal_fit`).

A force direction whose column of B is zero does not excite the model, a
direction whose row of C is zero does not move (rigid); the
semi-discretisation leaves both out. Units SI: A in 1/s (and 1/s² in
second-order blocks), B·F in state units per second, C·z in m.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..errors import InputError
from ..frf import FRF

__all__ = ["ModalModel", "StateSpaceModel", "from_modal_fit"]


@dataclass(frozen=True)
class ModalModel:
    """Real modes of one direction (x or y) of the tool point (no fitting here: fits are
    :func:`toolpoint.dynamics.modal.fit_frfs`, entering the SDM through :func:`from_modal_fit`).

    Attributes
    ----------
    fn_hz, zeta, mass_kg : (n,) natural frequencies (Hz), damping ratios, modal masses (kg).
    upper_residual : constant compliance R_u for modes above the band, m/N.
    lower_residual : R_l in −R_l/ω² for modes below the band, 1/kg.
    fit_error : relative RMS error of the fit (nan if not fitted).
    """

    fn_hz: np.ndarray
    zeta: np.ndarray
    mass_kg: np.ndarray
    upper_residual: float = 0.0
    lower_residual: float = 0.0
    fit_error: float = float("nan")
    label: str = ""

    def __post_init__(self):
        f, z, m = (np.atleast_1d(np.asarray(v, dtype=float)).reshape(-1) for v in (self.fn_hz, self.zeta, self.mass_kg))
        if not (f.size == z.size == m.size):
            raise InputError(f"{f.size} frequencies, {z.size} damping ratios, {m.size} masses", field="modes")
        if np.any(~np.isfinite(f) | (f <= 0)):
            raise InputError("natural frequencies must be finite and > 0 Hz", field="fn_hz")
        if np.any(~np.isfinite(z) | (z < 0)):
            raise InputError("damping ratios must be finite and ≥ 0", field="zeta")
        if np.any(~np.isfinite(m) | (m == 0)):
            raise InputError("modal masses must be finite and non-zero", field="mass_kg")
        for name, v in (("fn_hz", f), ("zeta", z), ("mass_kg", m)):
            object.__setattr__(self, name, v)

    @property
    def n_modes(self) -> int:
        """Number of modes."""
        return self.fn_hz.size

    @property
    def omega_n(self) -> np.ndarray:
        """Natural angular frequencies ω_r = 2π f_r, rad/s."""
        return 2 * np.pi * self.fn_hz

    @property
    def stiffness(self) -> np.ndarray:
        """Modal stiffness k_r = m_r ω_r², N/m."""
        return self.mass_kg * self.omega_n**2

    @property
    def damping(self) -> np.ndarray:
        """Modal viscous damping c_r = 2 ζ_r m_r ω_r, N·s/m."""
        return 2 * self.zeta * self.mass_kg * self.omega_n

    def frf(self, freq_hz, *, residuals: bool = True) -> FRF:
        """Re-synthesised receptance at ``freq_hz``.

        Parameters
        ----------
        freq_hz : array_like
            Increasing frequencies, Hz.
        residuals : bool
            Include the residual terms R_u − R_l/ω².

        Returns
        -------
        FRF
            Receptance, m/N.

        Examples
        --------
        >>> m = ModalModel([100.0], [0.05], [2.0])
        >>> k = m.stiffness[0]                         # N/m
        >>> bool(np.isclose(m.frf([0.0]).values[0], 1 / k))   # static compliance 1/k, m/N
        True
        """
        f = np.asarray(freq_hz, dtype=float).reshape(-1)
        w = 2 * np.pi * f
        basis = _mode_basis(w, self.omega_n, self.zeta)
        v = basis @ (1.0 / self.mass_kg)
        if residuals:
            v = v + self.upper_residual
            if self.lower_residual:
                with np.errstate(divide="ignore"):
                    v = v - self.lower_residual / w**2
        return FRF(f, v, "receptance", self.label or "modal fit")

    def table(self) -> str:
        """Human-readable table of the modes (one line per mode)."""
        lines = [f"{'mode':>4} {'fn [Hz]':>10} {'zeta [%]':>9} {'mass [kg]':>11} {'k [N/m]':>11}"]
        for r in range(self.n_modes):
            lines.append(
                f"{r + 1:>4} {self.fn_hz[r]:>10.2f} {100 * self.zeta[r]:>9.3f} "
                f"{self.mass_kg[r]:>11.4g} {self.stiffness[r]:>11.4g}"
            )
        if np.isfinite(self.fit_error):
            lines.append(f"fit error (relative RMS): {100 * self.fit_error:.2f} %")
        return "\n".join(lines)


def _mode_basis(w, wn, zeta):
    """Columns 1/(ω_r² − ω² + 2iζ_r ω_r ω), shape (n_freq, n_modes), s²."""
    w = w[:, None]
    return 1.0 / (wn**2 - w**2 + 2j * zeta * wn * w)




def _matrix(value, shape, name):
    try:
        a = np.array(value, dtype=float)
    except (TypeError, ValueError):
        raise InputError("must be a real matrix", field=name) from None
    if a.ndim != 2 or any(s is not None and a.shape[i] != s for i, s in enumerate(shape)):
        want = " × ".join("n" if s is None else str(s) for s in shape)
        raise InputError(f"expected shape {want}, got {a.shape}", field=name)
    if not np.all(np.isfinite(a)):
        raise InputError("must be finite", field=name)
    a.setflags(write=False)
    return a


@dataclass(frozen=True, eq=False)
class StateSpaceModel:
    """Two-input (F_x, F_y), two-output (x, y) state-space model ż = Az + BF, r = Cz of the tool point.

    Parameters
    ----------
    A : array_like
        (n, n) real state matrix, 1/s; every eigenvalue must have Re < 0 (damped modes).
    B : array_like
        (n, 2) real input matrix: columns for F_x and F_y (N).
    C : array_like
        (2, n) real output matrix: rows for x and y (m).
    label : str
        Name for messages and reports.

    Raises
    ------
    InputError
        Wrong shapes, non-finite entries, an undamped or unstable pole, no flexible direction.

    Examples
    --------
    One mode in x (922 Hz, ζ = 0.011, modal mass 0.03993 kg), y rigid; the static
    compliance is 1/k:

    >>> from toolpoint.stability import ModalModel, StateSpaceModel
    >>> ss = StateSpaceModel.from_modes(ModalModel([922.0], [0.011], [0.03993]), None)
    >>> k = 0.03993 * (2 * np.pi * 922.0) ** 2
    >>> phi = ss.frf([0.0])[0]                     # 2×2 receptance, m/N
    >>> bool(np.isclose(phi[0, 0].real, 1 / k)), float(abs(phi[1, 1]))
    (True, 0.0)
    """

    A: np.ndarray
    B: np.ndarray
    C: np.ndarray
    label: str = ""

    def __post_init__(self):
        A = _matrix(self.A, (None, None), "A")
        n = A.shape[0]
        if n < 1 or A.shape[1] != n:
            raise InputError(f"must be square and non-empty, got {A.shape}", field="A")
        B = _matrix(self.B, (n, 2), "B")
        C = _matrix(self.C, (2, n), "C")
        ev = np.linalg.eigvals(A)
        if np.any(ev.real >= 0):
            raise InputError(f"every pole must be damped (Re λ < 0); got Re λ = {ev.real.max():.3g} 1/s",
                             field="A")
        if not (np.any(B) and np.any(C)):
            raise InputError("no flexible direction (B or C is zero)", field="B/C")
        for name, v in (("A", A), ("B", B), ("C", C)):
            object.__setattr__(self, name, v)

    # ------------------------------------------------------------ properties
    @property
    def n_states(self) -> int:
        """Number of states n."""
        return self.A.shape[0]

    @property
    def poles(self) -> np.ndarray:
        """Eigenvalues of A, rad/s (complex, those with Im ≥ 0 first by frequency)."""
        ev = np.linalg.eigvals(self.A)
        return ev[np.lexsort((np.abs(ev), ev.imag < 0))]

    @property
    def max_frequency_hz(self) -> float:
        """Highest natural frequency |λ|/2π of the poles, Hz."""
        return float(np.abs(self.poles).max() / (2 * np.pi))

    @property
    def inputs(self) -> np.ndarray:
        """Indices (0 = x, 1 = y) of the force directions that excite the model (non-zero columns of B)."""
        return np.flatnonzero(np.any(self.B != 0, axis=0))

    @property
    def outputs(self) -> np.ndarray:
        """Indices (0 = x, 1 = y) of the directions that move (non-zero rows of C)."""
        return np.flatnonzero(np.any(self.C != 0, axis=1))

    # ------------------------------------------------------------ evaluation
    def frf(self, freq_hz) -> np.ndarray:
        """Receptance matrix Φ(iω) = C (iωI − A)⁻¹ B at ``freq_hz``.

        Parameters
        ----------
        freq_hz : array_like
            Frequencies, Hz.

        Returns
        -------
        numpy.ndarray
            (F, 2, 2) complex, m/N; ``[:, i, j]`` is the response in direction i to a force in j.
        """
        w = 2 * np.pi * np.asarray(freq_hz, float).reshape(-1)
        # Diagonalise once: Φ = (C V) diag(1/(iω − λ)) (V⁻¹ B); A has distinct poles for any fitted model.
        lam, V = np.linalg.eig(self.A)
        if np.linalg.cond(V) < 1e10:
            CV, VB = self.C @ V, np.linalg.solve(V, self.B.astype(complex))
            return np.einsum("ik,fk,kj->fij", CV, 1.0 / (1j * w[:, None] - lam[None, :]), VB)
        eye = np.eye(self.n_states)
        return np.stack([self.C @ np.linalg.solve(1j * wk * eye - self.A, self.B) for wk in w])  # defective A

    def rotated(self, angle_rad: float) -> "StateSpaceModel":
        """The structure turned by ``angle_rad`` in the same x, y axes.

        With Q the 2×2 rotation by the angle, Φ' = Q Φ Qᵀ: B' = B Qᵀ, C' = Q C
        (principal axes u, v of an orthotropic tool turned by θ: Φ'_xy = cs(Φ_u − Φ_v)).

        Parameters
        ----------
        angle_rad : float
            Rotation, rad, from x towards y.

        Returns
        -------
        StateSpaceModel
            Same A, turned B and C, same label.
        """
        c, s = np.cos(angle_rad), np.sin(angle_rad)
        R = np.array([[c, -s], [s, c]])
        return StateSpaceModel(self.A, self.B @ R.T, R @ self.C, self.label)

    # ------------------------------------------------------------ constructors
    @classmethod
    def from_modes(cls, modes_x, modes_y, label: str = "") -> "StateSpaceModel":
        """Real modes per direction (no cross terms); ``None`` for a rigid direction.

        Parameters
        ----------
        modes_x, modes_y : ModalModel or None
            Modes in x and y (positive modal masses, kg; residual terms are not used).
        label : str
            Name of the model.

        Returns
        -------
        StateSpaceModel
            States (q_r, q̇_r) per mode: A block [[0, 1], [−ω_r², −2ζ_rω_r]], B (0, 1/m_r) on the
            mode's direction, C (1, 0).
        """
        if modes_x is None and modes_y is None:
            raise InputError("need modes in x, y or both", field="modes")
        blocks = []
        for d, mm in ((0, modes_x), (1, modes_y)):
            if mm is None:
                continue
            field = "modes_" + "xy"[d]
            if not isinstance(mm, ModalModel):
                raise InputError(f"expected a ModalModel, got {type(mm).__name__}", field=field)
            if np.any(mm.mass_kg <= 0):
                raise InputError("modal masses must be > 0 for the semi-discretisation (negative: not a "
                                 "driving-point FRF?)", field=field)
            if np.any(mm.zeta <= 0):
                raise InputError("damping ratios must be > 0 for the semi-discretisation", field=field)
            for wn, ze, m in zip(mm.omega_n, mm.zeta, mm.mass_kg):
                blocks.append((d, np.array([[0.0, 1.0], [-wn**2, -2 * ze * wn]]), 1.0 / m))
        n = 2 * len(blocks)
        A, B, C = np.zeros((n, n)), np.zeros((n, 2)), np.zeros((2, n))
        for r, (d, a, binv) in enumerate(blocks):  # one block per mode
            A[2 * r: 2 * r + 2, 2 * r: 2 * r + 2] = a
            B[2 * r + 1, d] = binv
            C[d, 2 * r] = 1.0
        return cls(A, B, C, label)

    @classmethod
    def from_poles(cls, poles, residues, label: str = "", rtol: float = 1e-10) -> "StateSpaceModel":
        """Complex poles and 2×2 residue matrices: Φ(s) = Σ_r R_r/(s − λ_r) + conj(R_r)/(s − conj λ_r).

        Parameters
        ----------
        poles : array_like
            (n,) complex λ_r, rad/s, Re < 0, Im > 0.
        residues : array_like
            (n, 2, 2) complex R_r, m/(N s): ``[r, i, j]`` for the response in i to a force in j
            (a direction's row and column zero when it is rigid).
        label : str
            Name of the model.
        rtol : float
            Singular values of R_r below ``rtol`` × the largest of all are dropped.

        Returns
        -------
        StateSpaceModel
            Two real states per rank-one term of each R_r (module docstring).

        Examples
        --------
        A real mode written as a complex pole: λ = −ζω_n + iω_d, R = 1/(2iω_d m) on x.

        >>> wn, ze, m = 2 * np.pi * 922.0, 0.011, 0.03993
        >>> lam = complex(-ze * wn, wn * np.sqrt(1 - ze**2))
        >>> R = np.zeros((1, 2, 2), complex); R[0, 0, 0] = 1 / (2j * lam.imag * m)
        >>> ss = StateSpaceModel.from_poles([lam], R)
        >>> w = 2 * np.pi * 900.0
        >>> bool(np.isclose(ss.frf([900.0])[0, 0, 0], 1 / (m * (wn**2 - w**2 + 2j * ze * wn * w))))
        True
        """
        lam = np.asarray(poles, dtype=complex).reshape(-1)
        R = np.asarray(residues, dtype=complex)
        if R.shape != (lam.size, 2, 2):
            raise InputError(f"expected shape ({lam.size}, 2, 2), got {R.shape}", field="residues")
        if not (np.all(np.isfinite(lam)) and np.all(np.isfinite(R))):
            raise InputError("poles and residues must be finite", field="poles")
        if np.any(lam.real >= 0) or np.any(lam.imag <= 0):
            raise InputError("poles must have Re λ < 0 (damped) and Im λ > 0 (one of each conjugate pair)",
                             field="poles")
        U, S, Vh = np.linalg.svd(R)
        tol = rtol * max(S.max(initial=0.0), 1e-300)
        A, B, C = [], [], []
        for r in range(lam.size):  # a handful of poles
            for k in np.flatnonzero(S[r] > tol):
                c, b = U[r, :, k] * np.sqrt(S[r, k]), Vh[r, k, :] * np.sqrt(S[r, k])  # R ⊇ c bᵀ
                A.append(np.array([[lam[r].real, -lam[r].imag], [lam[r].imag, lam[r].real]]))
                B.append(np.vstack([b.real, b.imag]))
                C.append(np.column_stack([2 * c.real, -2 * c.imag]))
        if not A:
            raise InputError("all residues are zero", field="residues")
        n = 2 * len(A)
        Am = np.zeros((n, n))
        for r, a in enumerate(A):
            Am[2 * r: 2 * r + 2, 2 * r: 2 * r + 2] = a
        return cls(Am, np.vstack(B), np.hstack(C), label)


def from_modal_fit(fit_x, fit_y=None, *, label: str = "") -> StateSpaceModel:
    """State-space model from common-pole fits of :mod:`toolpoint.dynamics.modal` (residual terms left out).

    Parameters
    ----------
    fit_x : toolpoint.dynamics.modal.ModalFit
        Fit of the responses to a force in x: FRF 0 is Φ_xx; an FRF 1, if
        fitted, is the cross receptance Φ_yx (y response).
    fit_y : ModalFit, optional
        Fit of the responses to a force in y: FRF 0 is Φ_yy, an FRF 1 Φ_xy.
        ``None``: a symmetric tool, Φ_yy = Φ_xx (and Φ_xy = Φ_yx from FRF 1 of ``fit_x``).
    label : str
        Name of the model.

    Returns
    -------
    StateSpaceModel
        The two fits' realisations (``ModalFit.state_space``) side by side, driven by F_x and F_y.
    """
    blocks = []
    for d, fit in ((0, fit_x), (1, fit_x if fit_y is None else fit_y)):
        try:
            A, B, C = fit.state_space()
        except AttributeError:
            raise InputError(f"expected a ModalFit, got {type(fit).__name__}", field="fit_" + "xy"[d]) from None
        if A.shape[0] == 0:
            raise InputError("the fit has no mode", field="fit_" + "xy"[d])
        if C.shape[0] > 2:
            raise InputError(f"expected 1 or 2 FRFs (direct, cross), got {C.shape[0]}", field="fit_" + "xy"[d])
        Cd = np.zeros((2, A.shape[0]))
        Cd[d] = C[0]  # direct receptance
        if C.shape[0] == 2:
            Cd[1 - d] = C[1]  # cross receptance: the other direction's response
        blocks.append((d, A, B[:, 0], Cd))
    n = sum(b[1].shape[0] for b in blocks)
    A, B, C = np.zeros((n, n)), np.zeros((n, 2)), np.zeros((2, n))
    s = 0
    for d, a, b, c in blocks:
        k = a.shape[0]
        A[s: s + k, s: s + k], B[s: s + k, d], C[:, s: s + k] = a, b, c
        s += k
    return StateSpaceModel(A, B, C, label)
