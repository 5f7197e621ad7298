"""Tool-point dynamics for the time-domain simulation: complex modal coordinates and their exact step maps.

Every accepted description of the tool point (real modes per direction, a
:class:`~toolpoint.stability.statespace.StateSpaceModel`, common-pole fits
of :mod:`toolpoint.dynamics.modal`) is first made a state-space model
ż = A z + B F, r = C z (F = (F_x, F_y) in N, r = (x, y) in m) and then put in
complex modal coordinates η = V⁻¹ z, one per pole λ_k (1/s):

    η̇_k = λ_k η_k + w_kᵀ F,      r = Σ_k c_k η_k,                          (1)

block by block (A of every accepted model is block diagonal, one block per
mode or per fit), so repeated poles of two identical directions never meet in
one eigen-decomposition. Of each conjugate pair only the pole with Im λ > 0 is
kept, its output doubled and the real part taken (r is real).

For a force held constant over a step Δt (zero-order hold) (1) is solved
exactly, mode by mode:

    η_k(t + Δt) = e^{λ_k Δt} η_k(t) + (e^{λ_k Δt} − 1)/λ_k · w_kᵀ F.       (2)
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..errors import InputError
from ..stability.statespace import ModalModel, StateSpaceModel, from_modal_fit

__all__ = ["ModalDynamics", "as_modal_dynamics", "modes_from_list"]

# Largest condition number of a block's eigenvector matrix: above it the block is (nearly) defective and the
# modal coordinates would amplify round-off.
_MAX_COND = 1e8


@dataclass(frozen=True, eq=False)
class ModalDynamics:
    """Complex modal form (1) of a tool-point model.

    Attributes
    ----------
    poles : numpy.ndarray
        (m,) complex poles λ_k, rad/s (Im ≥ 0; one of each conjugate pair).
    inputs : numpy.ndarray
        (m, 2) complex w_k: modal input of F_x and F_y, 1/(N s) in modal units.
    outputs : numpy.ndarray
        (2, m) complex c_k (doubled for a pair), m per modal unit; r = Re(outputs @ η).
    model : StateSpaceModel
        The real model it came from (its ``frf`` is the receptance, m/N).
    """

    poles: np.ndarray
    inputs: np.ndarray
    outputs: np.ndarray
    model: StateSpaceModel

    @property
    def max_frequency_hz(self) -> float:
        """Highest |λ|/2π of the poles, Hz (what the time step must resolve)."""
        return float(np.abs(self.poles).max() / (2 * np.pi))

    def step_maps(self, dt) -> tuple[np.ndarray, np.ndarray]:
        """Exact zero-order-hold maps (2) for steps ``dt``.

        Parameters
        ----------
        dt : array_like
            (P,) time steps, s.

        Returns
        -------
        (E, G) : tuple of numpy.ndarray
            (m, P) complex e^{λΔt} (dimensionless) and (e^{λΔt} − 1)/λ (s).
        """
        lam = self.poles[:, None]
        x = lam * np.asarray(dt, float).reshape(1, -1)
        E = np.exp(x)
        # (e^x − 1)/λ = Δt · expm1(x)/x; expm1 keeps it accurate for slow poles (|x| ≪ 1)
        G = np.where(np.abs(x) > 0, np.expm1(x) / np.where(x == 0, 1, x), 1.0) * np.asarray(dt, float)
        return E, G


def modes_from_list(modes, field: str) -> ModalModel | None:
    """Real modes given as ``[(f_n Hz, k N/m, ζ), …]`` as a :class:`ModalModel` (modal mass k/ω²).

    Parameters
    ----------
    modes : sequence of (float, float, float) or None
        Natural frequency (Hz, > 0), modal stiffness (N/m, > 0), damping ratio (> 0).
        ``None`` or empty: a rigid direction.
    field : str
        Name for messages (``modes_x``, ``modes_y``).

    Returns
    -------
    ModalModel or None
    """
    if modes is None:
        return None
    try:
        arr = np.asarray(modes, dtype=float).reshape(-1, 3) if len(modes) else np.empty((0, 3))
    except (TypeError, ValueError):
        raise InputError("expected a list of (f_n Hz, k N/m, zeta) triples", field=field) from None
    if arr.shape[0] == 0:
        return None
    fn, k, ze = arr.T
    if np.any(~np.isfinite(arr)) or np.any(fn <= 0) or np.any(k <= 0) or np.any(ze <= 0) or np.any(ze >= 1):
        raise InputError("every mode needs f_n > 0 Hz, k > 0 N/m and 0 < zeta < 1", field=field)
    return ModalModel(fn, ze, k / (2 * np.pi * fn) ** 2)


def _to_state_space(modes_x, modes_y) -> StateSpaceModel:
    if isinstance(modes_x, StateSpaceModel):
        if modes_y is not None:
            raise InputError("give a StateSpaceModel alone (it holds both directions)", field="modes_y")
        return modes_x
    if hasattr(modes_x, "state_space") and hasattr(modes_x, "poles"):  # common-pole fit(s)
        return from_modal_fit(modes_x, modes_y)
    mm = []
    for value, field in ((modes_x, "modes_x"), (modes_y, "modes_y")):
        if isinstance(value, ModalModel):
            mm.append(value if value.n_modes else None)
        else:
            mm.append(modes_from_list(value, field))
    if mm[0] is None and mm[1] is None:
        raise InputError("the modal model has no mode (give modes in x, y or both)", field="modes")
    return StateSpaceModel.from_modes(mm[0], mm[1])


def _blocks(A: np.ndarray) -> list[np.ndarray]:
    """Index sets of the diagonal blocks of A (connected components of its non-zero pattern)."""
    from scipy.sparse.csgraph import connected_components

    n_comp, label = connected_components((A != 0) | (A.T != 0), directed=False)
    return [np.flatnonzero(label == c) for c in range(n_comp)]


def as_modal_dynamics(modes_x, modes_y=None) -> ModalDynamics:
    """The complex modal form (module docstring) of what the caller gave.

    Parameters
    ----------
    modes_x : StateSpaceModel, ModalFit, ModalModel, list of (f_n, k, ζ) or None
        A complete 2-input 2-output model (then ``modes_y`` is ``None``, or the y fit for a
        :class:`~toolpoint.dynamics.modal.ModalFit`), or the real modes in x (Hz, N/m, –);
        ``None``/empty: rigid in x.
    modes_y : ModalFit, ModalModel, list of (f_n, k, ζ) or None
        Real modes in y (or the fit of the responses to F_y); ``None``/empty: rigid in y.

    Returns
    -------
    ModalDynamics

    Raises
    ------
    InputError
        No mode at all (field ``modes``), bad modal values, a defective model.
    """
    ss = _to_state_space(modes_x, modes_y)
    A, B, C = ss.A, ss.B, ss.C
    poles, inputs, outputs = [], [], []
    for idx in _blocks(A):
        lam, V = np.linalg.eig(A[np.ix_(idx, idx)])
        if np.linalg.cond(V) > _MAX_COND:
            raise InputError("the model has a defective (repeated, coupled) pole; the simulation needs distinct "
                             "poles per block", field="modes")
        W = np.linalg.solve(V, B[idx].astype(complex))
        CV = C[:, idx] @ V
        for k in range(lam.size):
            if lam[k].imag < 0:
                continue  # the conjugate of a kept pole
            weight = 2.0 if lam[k].imag > 0 else 1.0
            poles.append(lam[k])
            inputs.append(W[k])
            outputs.append(weight * CV[:, k])
    return ModalDynamics(np.array(poles), np.array(inputs).reshape(-1, 2), np.array(outputs).T.reshape(2, -1), ss)
