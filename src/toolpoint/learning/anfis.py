r"""ANFIS: first-order (or zero-order) Sugeno fuzzy inference with hybrid learning.

A scikit-learn regressor that reproduces MATLAB's ``genfis`` (grid partition) +
``anfis`` (hybrid learning, Jang 1993), as used by Čiča et al. to predict the
holder–tool joint stiffness from tool diameter and overhang.

Model
-----
Inputs x = (x_1 … x_d). Input i has m_i membership functions (MFs) μ_ij, all of
one type:

* ``"gauss"``  μ(x) = exp(−(x − c)² / (2σ²))                 params [σ, c]
* ``"gbell"``  μ(x) = 1 / (1 + |(x − c)/a|^(2b))              params [a, b, c]
* ``"tri"``    μ(x) = max(min((x − a)/(b − a), (c − x)/(c − b)), 0)     params [a, b, c]
* ``"trap"``   μ(x) = max(min((x − a)/(b − a), 1, (d − x)/(d − c)), 0)  params [a, b, c, d]

(parameter order as in MATLAB's ``gaussmf``/``gbellmf``/``trimf``/``trapmf``;
σ, a, c, … carry the unit of the input).

Grid partition: one rule per combination of MFs, R = Π m_i rules, ordered with
the last input varying fastest (MATLAB ``genfis1``). Rule r with MF indices
(j_1 … j_d) fires with the product t-norm

    w_r = Π_i μ_{i,j_i}(x_i),          w̄_r = w_r / Σ_s w_s     (normalised firing)

and has the consequent (``order=1``: linear, ``order=0``: constant)

    y_r = p_{r,1} x_1 + … + p_{r,d} x_d + p_{r,0}      (stored as [p_1 … p_d, p_0])

The output is the weighted average  f(x) = Σ_r w̄_r y_r(x).

Because the rule base is the full grid, Σ_s w_s = Π_i Σ_j μ_ij(x_i), so the
normalised firing factorises into per-input normalised memberships
ν_ij = μ_ij / S_i with S_i = Σ_j μ_ij:   w̄_r = Π_i ν_{i,j_i}. That is how it is
computed here (outer products by broadcasting), which is also more robust to
underflow than forming w_r first.

Zero firing. Triangular and trapezoidal MFs are zero outside their support, so
an input value may lie outside every MF of its input (S_i = 0), e.g. when
predicting beyond the training range. Then that input is taken to belong fully
to the MF whose core (centre) is nearest: ν_ij = 1 for that j, 0 otherwise.
Beyond the outermost MF this continues the edge value (ν = 1 for the edge MF)
continuously; such samples contribute no premise gradient. The same rule
catches Gaussian/bell memberships that underflow to 0 far outside the range.

Hybrid learning (one epoch, batch; MATLAB ``anfis`` with method 1)
------------------------------------------------------------------
1. Forward pass with the premise (MF) parameters fixed: f is linear in the
   consequents, f = A θ with design rows A_n = [w̄_n1 x̃_n, …, w̄_nR x̃_n],
   x̃ = [x, 1] (order 1) or A_n = w̄_n (order 0); θ by least squares
   (``numpy.linalg.lstsq``; MATLAB uses a sequential Kalman filter with a 1e6
   initial covariance, which is the same solution up to a negligible ridge).
2. Training error E = Σ_n (t_n − f_n)², reported as RMSE = sqrt(E/N); checking
   RMSE likewise. Both are for the parameters *before* step 3, and the best
   parameters (lowest training RMSE, or lowest checking RMSE when checking data
   are given) are recorded here.
3. One gradient step on the premise parameters with θ fixed, normalised so the
   step size κ is the Euclidean distance moved in parameter space:
   α ← α − κ ∇_α E / ‖∇_α E‖. Chain rule (per sample, dropping n):

       ∂E/∂f      = −2 (t − f)
       ∂f/∂ν_ij   = G_ij = Σ_{r: j_r,i = j} y_r Π_{k≠i} ν_{k,j_r,k}
       ∂f/∂μ_ij   = (G_ij − f) / S_i           (since Σ_j ν_ij G_ij = f)
       ∂E/∂α_ijp  = Σ_n ∂E/∂f · ∂f/∂μ_ij · ∂μ_ij/∂α_ijp

   with the MF derivatives in :func:`membership`. Afterwards the MFs are made
   valid again (σ, a, b > 0; tri/trap corners sorted with positive gaps).
4. Step size κ (MATLAB rule, checked on the training RMSE sequence e):
   ×``step_decrease`` (0.9) after two up–down oscillations,
   e[k−4] < e[k−3] > e[k−2] < e[k−1] > e[k]; else ×``step_increase`` (1.1)
   after four consecutive reductions, e[k−4] > … > e[k]; each rule waits at
   least four epochs after it last fired.

Training stops after ``epochs`` epochs or when the training RMSE ≤ ``tol``.

References
----------
J.-S. R. Jang, "ANFIS: Adaptive-network-based fuzzy inference system",
IEEE Trans. SMC 23(3), 665–685, 1993.
"""

from __future__ import annotations

import json
import math
import numbers
import os
import warnings

import numpy as np
from sklearn.base import BaseEstimator, RegressorMixin
from sklearn.utils.validation import check_array, check_X_y

from ..io.atomic import atomic_open
from ..errors import ExtrapolationWarning, InputError

__all__ = [
    "ANFIS", "MF_PARAMS", "membership", "genfis_params", "save_model", "load_model", "predict_quietly",
]

#: Parameter names per membership-function type (MATLAB order).
MF_PARAMS = {"gauss": ("sigma", "c"), "gbell": ("a", "b", "c"), "tri": ("a", "b", "c"), "trap": ("a", "b", "c", "d")}

_FORMAT = "toolpoint.anfis"  # stored in model files: kept for compatibility
_FORMAT_VERSION = 1
# Smallest MF width / corner gap, relative to the input's data range: keeps
# σ, a > 0 and tri/trap slopes finite after a gradient step.
_MIN_WIDTH = 1e-6
_MIN_BELL_B = 1e-6


# --------------------------------------------------------------------- MFs
def membership(kind: str, params, x, *, grad: bool = False):
    """Evaluate the m MFs of one input at the points x.

    Parameters
    ----------
    kind : one of :data:`MF_PARAMS`.
    params : (m, p) array, one row of MATLAB-ordered parameters per MF.
    x : (n,) array of input values.
    grad : also return the derivatives with respect to the parameters.

    Returns
    -------
    mu : (n, m) memberships in [0, 1].
    dmu : (n, m, p) ∂μ/∂param, only if ``grad``. Derivatives:

    * gauss: ∂μ/∂c = μ (x − c)/σ²,  ∂μ/∂σ = μ (x − c)²/σ³
    * gbell, with u = |x − c|/a, s = u^(2b), s μ² = μ(1 − μ):
      ∂μ/∂a = 2b μ(1 − μ)/a,  ∂μ/∂b = −2 ln(u) μ(1 − μ),  ∂μ/∂c = 2b μ(1 − μ)/(x − c)
    * trap, with L = (x − a)/(b − a), U = (d − x)/(d − c), on the rising side
      (0 < L < min(U, 1)): ∂μ/∂a = (L − 1)/(b − a), ∂μ/∂b = −L/(b − a); on the
      falling side (0 < U < min(L, 1)): ∂μ/∂c = U/(d − c), ∂μ/∂d = (1 − U)/(d − c);
      0 elsewhere (one-sided at the corners).
    * tri(a, b, c) = trap(a, b, b, c), so ∂/∂b sums the trap's ∂/∂b and ∂/∂c.
    """
    P = np.asarray(params, dtype=float)
    x = np.asarray(x, dtype=float)[:, None]  # (n, 1) against (m,) parameter rows
    if kind == "gauss":
        sig, c = P[:, 0], P[:, 1]
        dx = x - c
        mu = np.exp(-0.5 * (dx / sig) ** 2)
        if not grad:
            return mu
        return mu, np.stack([mu * dx**2 / sig**3, mu * dx / sig**2], axis=-1)
    if kind == "gbell":
        a, b, c = P[:, 0], P[:, 1], P[:, 2]
        dx = x - c
        u = np.abs(dx) / a
        s = u ** (2 * b)
        mu = 1.0 / (1.0 + s)
        if not grad:
            return mu
        g = mu * (1.0 - mu)  # = s μ², but finite even if s overflows
        pos = u > 0  # at x = c the derivatives w.r.t. b and c are taken as 0
        d_a = 2 * b * g / a
        d_b = np.where(pos, -2 * g * np.log(np.where(pos, u, 1.0)), 0.0)
        d_c = np.where(pos, 2 * b * g / np.where(pos, dx, 1.0), 0.0)
        return mu, np.stack([d_a, d_b, d_c], axis=-1)
    if kind == "tri":
        T = np.column_stack([P[:, 0], P[:, 1], P[:, 1], P[:, 2]])
        out = membership("trap", T, x[:, 0], grad=grad)
        if not grad:
            return out
        mu, d = out
        return mu, np.stack([d[..., 0], d[..., 1] + d[..., 2], d[..., 3]], axis=-1)
    if kind == "trap":
        a, b, c, d = P[:, 0], P[:, 1], P[:, 2], P[:, 3]
        lo = (x - a) / (b - a)
        hi = (d - x) / (d - c)
        mu = np.clip(np.minimum(lo, hi), 0.0, 1.0)
        if not grad:
            return mu
        inner = (mu > 0) & (mu < 1)
        rising = inner & (lo <= hi)
        falling = inner & ~rising
        z = np.zeros_like(mu)
        dmu = np.stack(
            [
                np.where(rising, (lo - 1) / (b - a), z),
                np.where(rising, -lo / (b - a), z),
                np.where(falling, hi / (d - c), z),
                np.where(falling, (1 - hi) / (d - c), z),
            ],
            axis=-1,
        )
        return mu, dmu
    raise ValueError(f"unknown membership function {kind!r} (one of {', '.join(MF_PARAMS)})")


def _centres(kind: str, P: np.ndarray) -> np.ndarray:
    """Centre of each MF's core, used for the zero-firing fallback."""
    if kind == "gbell":
        return P[:, 2]
    if kind == "trap":
        return 0.5 * (P[:, 1] + P[:, 2])
    return P[:, 1]  # gauss c, tri peak b


def genfis_params(kind: str, lo: float, hi: float, m: int) -> np.ndarray:
    """Initial (m, p) MF parameters of one input, as MATLAB ``genfis1``/``genparam``.

    Centres c_j evenly spaced from ``lo`` to ``hi`` (the input's data range),
    spacing Δ = (hi − lo)/(m − 1), half spacing h = Δ/2:

    * gauss: σ = h / sqrt(2 ln 2)  (neighbours cross at μ = 0.5)
    * gbell: a = h, b = 2, c = c_j  (neighbours cross at μ = 0.5)
    * tri:   [c − Δ, c, c + Δ]  (each reaches its neighbours' centres)
    * trap:  [c − 1.4h, c − 0.6h, c + 0.6h, c + 1.4h]
    """
    if kind not in MF_PARAMS:
        raise ValueError(f"unknown membership function {kind!r} (one of {', '.join(MF_PARAMS)})")
    c = np.linspace(lo, hi, m)
    h = (hi - lo) / 2 / (m - 1)
    one = np.ones(m)
    if kind == "gauss":
        return np.column_stack([h / np.sqrt(2 * np.log(2)) * one, c])
    if kind == "gbell":
        return np.column_stack([h * one, 2 * one, c])
    if kind == "tri":
        return np.column_stack([c - 2 * h, c, c + 2 * h])
    return np.column_stack([c - 1.4 * h, c - 0.6 * h, c + 0.6 * h, c + 1.4 * h])


def _make_valid(kind: str, P: np.ndarray, span: float) -> np.ndarray:
    """Return MF parameters that define valid MFs (in place on a copy).

    σ and a at least 1e-6 × the input's data range, bell exponent b > 0,
    tri/trap corners sorted with gaps of at least 1e-6 × range (finite slopes).
    """
    P = P.copy()
    floor = _MIN_WIDTH * span
    if kind in ("gauss", "gbell"):
        P[:, 0] = np.maximum(P[:, 0], floor)
        if kind == "gbell":
            P[:, 1] = np.maximum(P[:, 1], _MIN_BELL_B)
    else:
        P.sort(axis=1)
        for k in range(1, P.shape[1]):
            P[:, k] = np.maximum(P[:, k], P[:, k - 1] + floor)
    return P


# ------------------------------------------------------------------ network
def _premise_layer(kind, premise, X, *, grad=False):
    """Per-input normalised memberships ν_i (n, m_i), 1/S_i (n,), ∂μ_i/∂α (n, m_i, p)."""
    nus, inv_s, dmus = [], [], []
    for i, P in enumerate(premise):
        x = X[:, i]
        out = membership(kind, P, x, grad=grad)
        mu, dmu = out if grad else (out, None)
        s = mu.sum(axis=1)
        dead = s <= np.finfo(float).tiny  # outside every MF's support (see module doc)
        nu = mu / np.where(dead, 1.0, s)[:, None]
        if dead.any():
            nearest = np.argmin(np.abs(x[dead, None] - _centres(kind, P)[None, :]), axis=1)
            nu[dead] = 0.0
            nu[np.flatnonzero(dead), nearest] = 1.0
        nus.append(nu)
        inv_s.append(np.where(dead, 0.0, 1.0 / np.where(dead, 1.0, s)))
        dmus.append(dmu)
    return nus, inv_s, dmus


def _firing(nus):
    """Normalised rule firing w̄ (n, R), last input varying fastest."""
    w = nus[0]
    for nu in nus[1:]:
        w = (w[:, :, None] * nu[:, None, :]).reshape(w.shape[0], -1)
    return w


def _extended(X, order):
    """x̃ = [x_1 … x_d, 1] (order 1) or [1] (order 0), shape (n, d+1) or (n, 1)."""
    one = np.ones((X.shape[0], 1))
    return np.hstack([X, one]) if order == 1 else one


def _design(wbar, Xe):
    """Least-squares design matrix A (n, R·q): A[n, r·q + k] = w̄_nr x̃_nk."""
    n = wbar.shape[0]
    return (wbar[:, :, None] * Xe[:, None, :]).reshape(n, -1)


def _premise_gradient(nus, inv_s, dmus, rule_out, f, t, sw):
    """∇E w.r.t. each input's MF parameters, E = Σ s_n (t − f)²; list of (m_i, p)."""
    n, d = f.shape[0], len(nus)
    dE_df = -2.0 * sw * (t - f)
    Y = rule_out.reshape((n,) + tuple(nu.shape[1] for nu in nus))
    grads = []
    for i in range(d):
        # G_i[n, j] = Σ over the other inputs' MF indices of Y · Π_{k≠i} ν_k
        ops = [Y, [0, *range(1, d + 1)]]
        for k in range(d):
            if k != i:
                ops += [nus[k], [0, k + 1]]
        G = np.einsum(*ops, [0, i + 1])
        dE_dmu = (dE_df * inv_s[i])[:, None] * (G - f[:, None])
        grads.append(np.einsum("nj,njp->jp", dE_dmu, dmus[i]))
    return grads


def _step_change(e, k, last_dec, last_inc):
    """MATLAB's step-size rule after epoch k (0-based) of the training errors e.

    Returns "decrease" after two up-down oscillations
    (e[k−4] < e[k−3] > e[k−2] < e[k−1] > e[k]), else "increase" after four
    consecutive reductions, else None. Each rule fires at most once in four
    epochs: ``last_dec``/``last_inc`` are the epochs it last fired (start 0).
    """
    if k - last_dec >= 4 and e[k] < e[k - 1] > e[k - 2] < e[k - 3] > e[k - 4]:
        return "decrease"
    if k - last_inc >= 4 and e[k] < e[k - 1] < e[k - 2] < e[k - 3] < e[k - 4]:
        return "increase"
    return None


# ----------------------------------------------------------------- validation
def _is_int(v) -> bool:
    return isinstance(v, numbers.Integral) and not isinstance(v, bool)


def _is_real(v) -> bool:
    return isinstance(v, numbers.Real) and not isinstance(v, bool)


def _as_target(y, n, name):
    """1-D finite float target of length n (checking data)."""
    t = check_array(y, ensure_2d=False, dtype=float, input_name=name)
    if t.ndim == 2 and t.shape[1] == 1:
        t = t[:, 0]
    if t.ndim != 1:
        raise ValueError(f"{name} must be 1-D (single output), got shape {t.shape}")
    if t.shape[0] != n:
        raise ValueError(f"{name} has {t.shape[0]} values but X_val has {n} rows")
    return t


class ANFIS(RegressorMixin, BaseEstimator):
    """Adaptive neuro-fuzzy inference system (Sugeno type, grid partition, hybrid learning).

    Parameters
    ----------
    n_mfs : int or sequence of int, default 2
        MFs per input (≥ 2); a sequence gives one number per input, e.g.
        ``(3, 7)`` → 21 rules.
    mf : {"gbell", "gauss", "tri", "trap"}, default "gbell" (MATLAB's default)
    order : {0, 1}, default 1 — constant or linear rule consequents.
    epochs : int, default 100 — maximum number of training epochs.
    step_size : float, default 0.01 — initial step size κ (distance moved in
        premise-parameter space per epoch, in input units).
    step_decrease, step_increase : float, default 0.9 and 1.1.
    tol : float, default 0.0 — error goal: stop once the training RMSE ≤ tol.
    validation_data : (X_val, y_val) or None — checking data. When given, the
        parameters with the lowest checking RMSE are kept (else lowest training
        RMSE). ``fit(X, y, X_val=..., y_val=...)`` overrides it.
    log_target : bool, default False — fit log10(y) (y > 0) and return
        10**f from :meth:`predict`; ``history_`` RMSEs are then in decades.
        Useful for stiffnesses spanning decades (relative errors even out).
    input_names, target_name : optional labels stored with the model and used
        by plots and the CLI (taken from DataFrame columns / Series name if not given).
    random_state : ignored — training is deterministic (grid initialisation,
        batch least squares and gradient steps); accepted for API symmetry.
    verbose : int, default 0 — print one line per epoch if > 0.

    Attributes
    ----------
    premise_ : list of (m_i, p) arrays, MF parameters per input (MATLAB order).
    consequents_ : (R, d+1) array [p_1 … p_d, p_0] per rule (order 1) or (R, 1).
    rules_ : (R, d) int array, MF index of each input in each rule.
    input_range_ : (d, 2) training data range per input.
    history_ : dict of arrays ``train_rmse``, ``val_rmse`` (NaN without
        checking data) and ``step_size`` (κ used for each epoch's update).
    best_epoch_ : 1-based epoch whose parameters were kept.
    n_features_in_, n_mfs_, input_names_, target_name_.

    Examples
    --------
    A straight line is reproduced exactly by linear consequents:

    >>> import numpy as np
    >>> X = np.linspace(0.0, 1.0, 11)[:, None]
    >>> model = ANFIS(n_mfs=2, mf="gauss", epochs=5).fit(X, 3.0 * X[:, 0] + 1.0)
    >>> np.round(model.predict([[0.25], [0.5]]), 6).tolist()
    [1.75, 2.5]
    """

    def __init__(
        self,
        n_mfs=2,
        mf="gbell",
        order=1,
        epochs=100,
        step_size=0.01,
        step_decrease=0.9,
        step_increase=1.1,
        tol=0.0,
        validation_data=None,
        log_target=False,
        input_names=None,
        target_name=None,
        random_state=None,
        verbose=0,
    ):
        self.n_mfs = n_mfs
        self.mf = mf
        self.order = order
        self.epochs = epochs
        self.step_size = step_size
        self.step_decrease = step_decrease
        self.step_increase = step_increase
        self.tol = tol
        self.validation_data = validation_data
        self.log_target = log_target
        self.input_names = input_names
        self.target_name = target_name
        self.random_state = random_state
        self.verbose = verbose

    # ------------------------------------------------------------ helpers
    def check_params(self, n_inputs: int) -> tuple[int, ...]:
        """Validate the settings for a model of ``n_inputs`` inputs (the one place they are checked).

        Parameters
        ----------
        n_inputs : int
            Number of input columns d.

        Returns
        -------
        tuple of int
            MFs per input (``n_mfs`` broadcast to d entries).

        Raises
        ------
        InputError
            A bad setting; ``err.field`` is the parameter's name (``n_mfs``, ``mf``,
            ``order``, ``epochs``, ``step_size``, ``step_decrease``, ``step_increase``, ``tol``).

        Examples
        --------
        >>> ANFIS(n_mfs=(3, 7)).check_params(2)
        (3, 7)
        >>> ANFIS(n_mfs=1).check_params(2)
        Traceback (most recent call last):
        ...
        toolpoint.errors.InputError: n_mfs: must be at least 2 for every input, got 1
        """
        d = int(n_inputs)
        if self.mf not in MF_PARAMS:
            raise InputError(f"must be one of {', '.join(MF_PARAMS)}, got {self.mf!r}", field="mf")
        if isinstance(self.order, bool) or self.order not in (0, 1):
            raise InputError(f"must be 0 (constant) or 1 (linear), got {self.order!r}", field="order")
        m = np.atleast_1d(np.asarray(self.n_mfs, dtype=object))
        if m.ndim != 1 or not all(_is_int(v) for v in m.tolist()):
            raise InputError(f"must be an int or a sequence of ints, got {self.n_mfs!r}", field="n_mfs")
        m = m.astype(int)
        if m.size == 1:
            m = np.repeat(m, d)
        if m.size != d:
            raise InputError(f"has {m.size} entries but X has {d} input columns", field="n_mfs")
        if np.any(m < 2):
            raise InputError(f"must be at least 2 for every input, got {self.n_mfs!r}", field="n_mfs")
        if not (_is_int(self.epochs) and self.epochs >= 1):
            raise InputError(f"must be a positive integer, got {self.epochs!r}", field="epochs")
        for name in ("step_size", "step_decrease", "step_increase"):
            v = getattr(self, name)
            if not (_is_real(v) and np.isfinite(v) and v > 0):
                raise InputError(f"must be a positive number, got {v!r}", field=name)
        if not (_is_real(self.tol) and self.tol >= 0):
            raise InputError(f"must be a non-negative number, got {self.tol!r}", field="tol")
        return tuple(int(v) for v in m)

    def _transform_target(self, t, name="y"):
        if not self.log_target:
            return t
        if np.any(t <= 0):
            raise ValueError(f"log_target=True needs {name} > 0")
        return np.log10(t)

    def _rule_outputs(self, X):
        return _extended(X, self.order) @ self.consequents_.T

    def _raw_predict(self, X):
        nus, _, _ = _premise_layer(self.mf, self.premise_, X)
        return np.sum(_firing(nus) * self._rule_outputs(X), axis=1)

    # ---------------------------------------------------------------- API
    def fit(self, X, y, *, sample_weight=None, X_val=None, y_val=None):
        """Train by hybrid learning; see the module docstring for the algorithm.

        ``sample_weight`` (n,) ≥ 0, optional: weighted least squares, E = Σ s_n (t_n − f_n)²
        in both the consequent solve and the premise gradient, and the training
        RMSE is the weighted one, sqrt(Σ s e² / Σ s) — e.g. s_n = 1/σ_n² for targets
        known to different precision (identified joints with their intervals).
        Not in MATLAB's anfis; None (default) is exactly the unweighted algorithm.
        """
        cols = getattr(X, "columns", None)
        y_name = getattr(y, "name", None)
        # numeric, finite, 2-D X and 1-D y (a column vector y is ravelled with a warning)
        X, t_raw = check_X_y(X, y, dtype=float, y_numeric=True)
        n, d = X.shape
        if n < 2:
            raise ValueError(f"ANFIS needs at least 2 samples, got n_samples = {n}")
        if sample_weight is None:
            sw = np.ones(n)
        else:
            sw = np.asarray(sample_weight, dtype=float).reshape(-1)
            if sw.size != n or np.any(~np.isfinite(sw)) or np.any(sw < 0):
                raise ValueError(f"sample_weight must be {n} finite values ≥ 0, got shape {sw.shape}")
            if np.count_nonzero(sw) < 2:
                raise ValueError("sample_weight: fewer than 2 weights are non-zero")
            sw = sw / sw.mean()
        rw = np.sqrt(sw)
        n_mfs = self.check_params(d)
        t = self._transform_target(t_raw)

        if X_val is None and y_val is None and self.validation_data is not None:
            try:
                X_val, y_val = self.validation_data
            except (TypeError, ValueError):
                raise ValueError("validation_data must be a tuple (X_val, y_val)") from None
        if (X_val is None) != (y_val is None):
            raise ValueError("give both X_val and y_val, or neither")
        has_val = X_val is not None
        if has_val:
            Xv = check_array(X_val, dtype=float, input_name="X_val")
            if Xv.shape[1] != d:
                raise ValueError(f"X_val has {Xv.shape[1]} columns but X has {d}")
            tv = self._transform_target(_as_target(y_val, Xv.shape[0], "y_val"), "y_val")

        used = X[sw > 0]  # a zero-weight sample is as if absent, also for the MF layout
        lo, hi = used.min(axis=0), used.max(axis=0)
        names = self.input_names if self.input_names is not None else cols
        names = None if names is None else [str(s) for s in names]
        if names is not None and len(names) != d:
            raise ValueError(f"input_names has {len(names)} names but X has {d} columns")
        for i in range(d):
            if hi[i] == lo[i]:
                label = names[i] if names else f"column {i}"
                raise ValueError(f"input {label} is constant ({lo[i]!r}); a grid partition needs a data range")
        span = hi - lo

        kind, order = self.mf, self.order
        premise = [genfis_params(kind, lo[i], hi[i], n_mfs[i]) for i in range(d)]
        Xe = _extended(X, order)
        Xve = _extended(Xv, order) if has_val else None
        q = Xe.shape[1]

        kappa = float(self.step_size)
        train_rmse, val_rmse, steps = [], [], []
        last_dec = last_inc = 0
        best = (np.inf, None, None, 0)
        for k in range(int(self.epochs)):
            # 1. consequents by least squares, premise fixed
            nus, inv_s, dmus = _premise_layer(kind, premise, X, grad=True)
            wbar = _firing(nus)
            theta = np.linalg.lstsq(_design(wbar, Xe) * rw[:, None], t * rw, rcond=None)[0]
            C = theta.reshape(-1, q)
            rule_out = Xe @ C.T
            f = np.sum(wbar * rule_out, axis=1)
            # 2. errors for these parameters; remember the best
            e_trn = float(np.sqrt(np.mean(sw * (t - f) ** 2)))
            train_rmse.append(e_trn)
            if has_val:
                nv, _, _ = _premise_layer(kind, premise, Xv)
                e_val = float(np.sqrt(np.mean((tv - np.sum(_firing(nv) * (Xve @ C.T), axis=1)) ** 2)))
            else:
                e_val = np.nan
            val_rmse.append(e_val)
            score = e_val if has_val else e_trn
            if score < best[0]:
                best = (score, [P.copy() for P in premise], C.copy(), k + 1)
            if self.verbose:
                print(f"ANFIS epoch {k + 1:4d}  train RMSE {e_trn:.6g}  check RMSE {e_val:.6g}  step {kappa:.4g}")
            if min(train_rmse) <= self.tol:  # MATLAB's error goal
                break
            # 3. one normalised gradient step on the premise, consequents fixed
            grads = _premise_gradient(nus, inv_s, dmus, rule_out, f, t, sw)
            norm = float(np.sqrt(sum(np.sum(g**2) for g in grads)))
            if norm > 0:
                premise = [_make_valid(kind, P - kappa * g / norm, span[i])
                           for i, (P, g) in enumerate(zip(premise, grads))]
            steps.append(kappa)
            # 4. step-size heuristic on the training-error sequence
            change = _step_change(train_rmse, k, last_dec, last_inc)
            if change == "decrease":
                kappa *= self.step_decrease
                last_dec = k
            elif change == "increase":
                kappa *= self.step_increase
                last_inc = k

        _, self.premise_, self.consequents_, self.best_epoch_ = best
        self.n_features_in_ = d
        self.n_mfs_ = n_mfs
        self.rules_ = np.array(np.unravel_index(np.arange(int(np.prod(n_mfs))), n_mfs)).T
        self.input_range_ = np.column_stack([lo, hi])
        self.input_names_ = names
        self.target_name_ = None if self.target_name is None else str(self.target_name)
        if self.target_name_ is None and y_name is not None:
            self.target_name_ = str(y_name)
        self.history_ = {
            "train_rmse": np.array(train_rmse),
            "val_rmse": np.array(val_rmse),
            "step_size": np.array(steps),
        }
        return self

    def outside_training_range(self, X) -> np.ndarray:
        """Which samples lie outside the training input range (any input).

        Parameters
        ----------
        X : array_like, shape (n, d)
            Inputs, in the units the model was trained in.

        Returns
        -------
        ndarray of bool, shape (n,)
            True where some input is below or above its training range
            (:attr:`input_range_`, with a tolerance of 1e-9 of the range).
        """
        self._check_fitted()
        X = check_array(X, dtype=float)
        if X.shape[1] != self.n_features_in_:
            raise ValueError(f"X has {X.shape[1]} features, but ANFIS is expecting {self.n_features_in_} features "
                             "as input")
        lo, hi = self.input_range_[:, 0], self.input_range_[:, 1]
        tol = 1e-9 * (hi - lo)
        return np.any((X < lo - tol) | (X > hi + tol), axis=1)

    def predict(self, X):
        """Model output f(x) (10**f with ``log_target``).

        Parameters
        ----------
        X : array_like, shape (n, d)
            Inputs, in the units the model was trained in.

        Returns
        -------
        ndarray, shape (n,)
            Predictions, in the unit of the target.

        Warns
        -----
        ExtrapolationWarning
            If a sample lies outside the training input range (see :func:`predict_quietly`).
        """
        if self.outside_training_range(X).any():  # also checks the model is fitted and X valid
            warnings.warn("ANFIS prediction outside the training input range", ExtrapolationWarning, stacklevel=2)
        f = self._raw_predict(check_array(X, dtype=float))
        return 10.0**f if self.log_target else f

    def _check_fitted(self):
        if not hasattr(self, "premise_"):
            from sklearn.exceptions import NotFittedError

            raise NotFittedError("this ANFIS instance is not fitted yet; call fit first")

    # ------------------------------------------------------------ save/load
    def to_dict(self) -> dict:
        """JSON-ready description of the fitted model (parameters, not code)."""
        self._check_fitted()
        params = self.get_params()
        params.pop("validation_data")  # data, not a setting
        params["n_mfs"] = np.asarray(params["n_mfs"]).tolist()
        if not isinstance(params["random_state"], (int, type(None))):
            params["random_state"] = None
        if params["input_names"] is not None:
            params["input_names"] = [str(s) for s in params["input_names"]]
        if params["target_name"] is not None:
            params["target_name"] = str(params["target_name"])
        return {
            "format": _FORMAT,
            "version": _FORMAT_VERSION,
            "params": params,
            "input_names": self.input_names_,
            "target_name": self.target_name_,
            "n_mfs": list(self.n_mfs_),
            "input_range": self.input_range_.tolist(),
            "premise": [P.tolist() for P in self.premise_],
            "consequents": self.consequents_.tolist(),
            "best_epoch": int(self.best_epoch_),
            "history": {k: [None if not np.isfinite(v) else float(v) for v in a] for k, a in self.history_.items()},
        }

    @classmethod
    def from_dict(cls, doc: dict) -> "ANFIS":
        """Inverse of :meth:`to_dict`.

        Raises
        ------
        InputError
            A malformed description (a ``ValueError``), naming the field: ``format``, ``version``,
            ``params`` (or the parameter, e.g. ``n_mfs``), ``premise``, ``consequents``,
            ``input_range``, ``input_names``, ``target_name``, ``best_epoch``, ``history``.
        """
        def bad(field, msg):
            return InputError(msg, field=field)

        def array(key, shape):
            try:
                a = np.array(doc[key], dtype=float)
            except KeyError:
                raise bad(key, "missing") from None
            except (TypeError, ValueError, OverflowError):
                raise bad(key, "must be an array of numbers") from None
            if a.shape != shape:
                raise bad(key, f"shape {a.shape} does not match the rule base (expected {shape})")
            if not np.all(np.isfinite(a)):
                raise bad(key, "non-finite model parameters")
            return a

        if not isinstance(doc, dict):
            raise bad(None, "not an ANFIS model (top level is not an object)")
        if doc.get("format") != _FORMAT:
            raise bad("format", f"not a {_FORMAT} model (format = {doc.get('format')!r})")
        if doc.get("version") != _FORMAT_VERSION:
            raise bad("version", f"unsupported model version {doc.get('version')!r}")
        params = doc.get("params")
        if not isinstance(params, dict):
            raise bad("params", "must be an object of ANFIS settings")
        params = dict(params)
        if isinstance(params.get("n_mfs"), list):  # JSON has no tuples
            params["n_mfs"] = tuple(params["n_mfs"])
        try:
            model = cls(**params)
        except TypeError as err:
            raise bad("params", f"unknown setting ({err})") from None
        try:
            n_mfs = tuple(int(v) for v in doc["n_mfs"])
        except KeyError:
            raise bad("n_mfs", "missing") from None
        except (TypeError, ValueError, OverflowError):
            raise bad("n_mfs", f"must be a list of integers, got {doc['n_mfs']!r}"[:200]) from None
        d = len(n_mfs)
        try:
            model.check_params(d)
        except InputError as err:
            raise bad(f"params.{err.field}" if err.field else "params", err.message) from None
        except (TypeError, ValueError, OverflowError) as err:
            raise bad("params", f"bad setting ({err})") from None
        if any(m < 2 for m in n_mfs) or math.prod(n_mfs) > 10**6:
            raise bad("n_mfs", f"must be integers ≥ 2 (at most 1e6 rules), got {list(n_mfs)}"[:200])
        p = len(MF_PARAMS[model.mf])
        prem = doc.get("premise")
        if not isinstance(prem, list) or len(prem) != d:
            raise bad("premise", f"must be a list of {d} arrays (one per input)")
        premise = []
        for i, m in enumerate(n_mfs):
            try:
                P = np.array(prem[i], dtype=float)
            except (TypeError, ValueError, OverflowError):
                raise bad(f"premise[{i}]", "must be an array of numbers") from None
            if P.shape != (m, p):
                raise bad(f"premise[{i}]", f"shape {P.shape} does not match n_mfs and mf (expected {(m, p)})")
            if not np.all(np.isfinite(P)):
                raise bad(f"premise[{i}]", "non-finite model parameters")
            premise.append(P)
        C = array("consequents", (int(np.prod(n_mfs)), d + 1 if model.order == 1 else 1))
        rng = array("input_range", (d, 2))
        for i, P in enumerate(premise):  # the MFs training keeps valid (_make_valid): σ, a, b > 0, sorted corners
            span = float(rng[i, 1] - rng[i, 0])
            if not np.array_equal(_make_valid(model.mf, P, span if span > 0 else 0.0), P) or (
                    model.mf in ("gauss", "gbell") and np.any(P[:, 0] <= 0)):
                raise bad(f"premise[{i}]", f"invalid {model.mf} membership functions (widths must be > 0, "
                                           "corners sorted with gaps)")
        names = doc.get("input_names")
        if names is not None and (not isinstance(names, list) or len(names) != d):
            raise bad("input_names", f"must be a list of {d} names (one per input)")
        tn = doc.get("target_name")
        if tn is not None and not isinstance(tn, str):
            raise bad("target_name", f"must be a string, got {tn!r}"[:200])
        best = doc.get("best_epoch", 0)
        if not isinstance(best, int) or isinstance(best, bool) or best < 0:
            raise bad("best_epoch", f"must be a non-negative integer, got {best!r}"[:200])
        hist = doc.get("history") or {}
        if not isinstance(hist, dict):
            raise bad("history", f"must be an object of RMSE lists (train_rmse, val_rmse), got {hist!r}"[:200])
        history = {}
        for k, a in hist.items():
            try:
                history[k] = np.array([np.nan if v is None else v for v in a], dtype=float).reshape(-1)
            except (TypeError, ValueError, OverflowError):
                raise bad(f"history.{k}", "must be a list of numbers or nulls") from None
        model.premise_, model.consequents_ = premise, C
        model.n_features_in_, model.n_mfs_ = d, n_mfs
        model.rules_ = np.array(np.unravel_index(np.arange(int(np.prod(n_mfs))), n_mfs)).T
        model.input_range_ = rng
        model.input_names_ = None if names is None else [str(s) for s in names]
        model.target_name_ = None if tn is None else str(tn)
        model.best_epoch_ = best
        model.history_ = history
        return model

    def save(self, path: str | os.PathLike) -> None:
        """Write the fitted model as JSON (atomically). Floats round-trip exactly."""
        doc = self.to_dict()
        with atomic_open(path, "w", encoding="utf-8") as fh:
            json.dump(doc, fh, indent=1, allow_nan=False, default=_json_scalar)
            fh.write("\n")

    @classmethod
    def load(cls, path: str | os.PathLike) -> "ANFIS":
        """Read a model written by :meth:`save`.

        Raises
        ------
        InputError
            Not a model file (a ``ValueError``): one line naming ``path`` and the field.
        OSError
            The file cannot be opened.
        """
        from ..io.table import check_regular_file

        if os.path.exists(path):
            check_regular_file(path, what="model file")  # a FIFO would block the open for ever
        with open(path, encoding="utf-8") as fh:
            try:
                doc = json.load(fh)
            except json.JSONDecodeError as err:
                raise InputError(f"not valid JSON: {err}", file=path) from None
            except (UnicodeDecodeError, ValueError, RecursionError) as err:  # bad bytes, a 5000-digit integer
                raise InputError(f"not a readable JSON file ({type(err).__name__})", file=path) from None
        try:
            return cls.from_dict(doc)
        except InputError as err:
            raise InputError(err.message, file=path, field=err.field) from None


def _json_scalar(v):
    """NumPy scalars given as parameters (e.g. ``epochs=np.int64(50)``) → Python."""
    if isinstance(v, np.generic):
        return v.item()
    raise TypeError(f"cannot store {type(v).__name__} in the model file")


def save_model(model: ANFIS, path: str | os.PathLike) -> None:
    """Same as ``model.save(path)``."""
    model.save(path)


def load_model(path: str | os.PathLike) -> ANFIS:
    """Same as ``ANFIS.load(path)``."""
    return ANFIS.load(path)


def predict_quietly(model: ANFIS, X) -> tuple[np.ndarray, bool]:
    """Predict without the :class:`~toolpoint.errors.ExtrapolationWarning`, and say whether it applied.

    For callers that report extrapolation themselves (once, in their own words).

    Parameters
    ----------
    model : ANFIS
        A fitted model.
    X : array_like, shape (n, d)
        Inputs, in the units the model was trained in.

    Returns
    -------
    prediction : ndarray, shape (n,)
        As :meth:`ANFIS.predict`, in the unit of the target.
    outside : bool
        Whether any sample lay outside the training input range.
    """
    outside = bool(model.outside_training_range(X).any())
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", ExtrapolationWarning)
        return model.predict(X), outside
