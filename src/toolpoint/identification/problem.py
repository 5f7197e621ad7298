r"""General identification: any joints' and bearings' parameters from one or several FRFs (Eqs. 5–8).

Unknowns: any subset of ``spindle_holder.{kt,ct,kr,cr}`` (the paper's Eq. 5), ``holder_tool.{…}`` (Eq. 7)
and ``bearings[i].{k,c,kr,cr}``, searched as x = log10 p. Each measured FRF m (receptance at a response
and a force point, :mod:`toolpoint.dynamics.points`) has its own frequencies and weight w_m; the objective
generalises Eqs. (6) and (8),

    f(x) = sqrt(Σ_m w_m Σ_j |h_m(ω_j; 10^x) − h̄_m(ω_j)|²)   (m/N),

which is the paper's norm for one FRF with w = 1. When all unknowns belong to one element (one joint or
one bearing), every h_m is rational in that element's coefficients
(:meth:`~toolpoint.dynamics.points.ReceptanceModel.coupler`): the measurements are stacked, with √w_m, into
one :class:`~toolpoint.identification.objective.JointProblem` — the holder–tool joint's fast path. Otherwise
each evaluation solves the Woodbury system of the variable elements, in blocks of population members.
Both give exact Jacobians.
"""

from __future__ import annotations

import re
from dataclasses import dataclass

import numpy as np

from ..dynamics.assembly import Assembly
from ..dynamics.coupling import ToolPointCoupler
from ..dynamics.points import Point, ReceptanceModel, element_names
from ..errors import InputError
from ..frf import FRF
from .identify import INTERVALS_DEFAULT, IdentificationResult, solve
from .objective import JointProblem
from .params import DEFAULT_BOUNDS, ELEMENT_PARAMS, ELEMENT_UNITS, Bounds, check_bound_range

__all__ = ["Measured", "parse_params", "param_bounds", "FRFProblem", "identify_frfs"]

_NAME = re.compile(r"^(spindle_holder|holder_tool|bearings\[(\d+)\])\.(\w+)$")
BLOCK = 4
"""Population members per block of the general (Woodbury) path: (BLOCK, F, m, m) temporaries."""
POLY_MAX_DOF = 6
"""Variable spring DOFs up to which the general path evaluates populations in the polynomial form
(2^m + m 2^(m−1) coefficient rows: 48 for m = 4, 256 for m = 6); above, the Woodbury solves."""
POLY_BLOCK = 16
"""Population members per block of the polynomial form."""


@dataclass(frozen=True)
class _Poly:
    """Polynomial form of the general path (FRFProblem._polynomial)."""

    dofs: list  # (element index, 0 translation / 1 rotation) per variable spring DOF
    cols: list  # (subset mask, number of damping factors) per coefficient row
    E: np.ndarray  # (n_cols, 2ΣF) real view of √w (num − h̄ den)
    D: np.ndarray  # (n_cols, 2ΣF) real view of den
    N: np.ndarray  # (n_cols, ΣF) complex √w num
    Dc: np.ndarray  # (n_cols, ΣF) complex den


@dataclass(frozen=True)
class Measured:
    """One measured FRF: receptance (m/N) between a response and a force point, with a weight.

    Attributes
    ----------
    frf : FRF
        Receptance, frequencies > 0 Hz.
    response, force : Point
    weight : float
        w_m ≥ 0 in the objective (dimensionless).
    source : str
        File name, for messages.
    """

    frf: FRF
    response: Point
    force: Point
    weight: float = 1.0
    source: str = "<memory>"


def _kind(element: str) -> str:
    return "bearing" if element.startswith("bearings[") else "joint"


def parse_params(names, assembly: Assembly, *, file=None, field: str = "params") -> list[tuple[str, int, str]]:
    """``["spindle_holder.kt", "bearings[0].k", …]`` → [(element, slot 0–3, name), …].

    Raises
    ------
    InputError
        Unknown name, a bearing the spindle does not have, or a name given twice.

    Examples
    --------
    >>> from toolpoint.dynamics.assembly import load_assembly
    >>> a = load_assembly("examples/numerical_case.toml")
    >>> parse_params(["spindle_holder.kr", "bearings[2].c"], a)
    [('spindle_holder', 2, 'spindle_holder.kr'), ('bearings[2]', 1, 'bearings[2].c')]
    >>> parse_params(["spindle_holder.k"], a, file="command line", field="--params")
    Traceback (most recent call last):
    ...
    toolpoint.errors.InputError: command line: --params: unknown parameter 'spindle_holder.k' \
(spindle_holder.NAME or holder_tool.NAME with NAME kt, ct, kr, cr; bearings[i].NAME with NAME k, c, kr, cr)
    """
    out = []
    for raw in names:
        n = str(raw).strip()
        m = _NAME.match(n)
        kind = None if m is None else _kind(m.group(1))
        if m is None or m.group(3) not in ELEMENT_PARAMS[kind]:
            raise InputError(f"unknown parameter {n!r} (spindle_holder.NAME or holder_tool.NAME with NAME kt, ct, "
                             "kr, cr; bearings[i].NAME with NAME k, c, kr, cr)", file=file, field=field)
        if m.group(2) is not None and int(m.group(2)) >= len(assembly.spindle.bearings):
            raise InputError(f"unknown parameter {n!r}: the spindle has {len(assembly.spindle.bearings)} bearings "
                             f"(bearings[0] … bearings[{len(assembly.spindle.bearings) - 1}])", file=file, field=field)
        if any(o[2] == n for o in out):
            raise InputError(f"parameter {n!r} given twice", file=file, field=field)
        out.append((m.group(1), ELEMENT_PARAMS[kind].index(m.group(3)), n))
    if not out:
        raise InputError("no parameters to identify", file=file, field=field)
    return out


def param_bounds(params, overrides: dict | None = None, *, file=None, field: str = "bounds") -> Bounds:
    """Search bounds (SI) of ``params`` (from :func:`parse_params`): :data:`~.params.DEFAULT_BOUNDS`, overridden.

    ``overrides`` maps a full name (``"bearings[0].k"``) or, for a single element, the short name (``"kt"``)
    to [lo, hi].

    Examples
    --------
    >>> param_bounds([("bearings[0]", 0, "bearings[0].k")], {"k": [1e7, 1e9]}).as_dict()["kt"]
    [10000000.0, 1000000000.0]
    """
    short = {p[2].split(".")[-1]: p[2] for p in params} if len({p[0] for p in params}) == 1 else {}
    full = {p[2] for p in params}
    over = {}
    for key, val in (overrides or {}).items():
        name = short.get(key, key)
        if name not in full:
            raise InputError(f"no such parameter being identified (identifying {', '.join(sorted(full))})",
                             file=file, field=f"{field}.{key}")
        try:
            lo, hi = (float(v) for v in val)
        except (TypeError, ValueError):
            raise InputError(f"must be [lo, hi], got {val!r}", file=file, field=f"{field}.{key}") from None
        if not (np.isfinite(lo) and np.isfinite(hi)) or lo <= 0 or hi <= 0:
            raise InputError(f"bounds must be finite and > 0, got [{lo:g}, {hi:g}]", file=file, field=f"{field}.{key}")
        check_bound_range(lo, hi, file=file, field=f"{field}.{key}")
        if lo >= hi:
            raise InputError(f"lo must be < hi, got [{lo:g}, {hi:g}]", file=file, field=f"{field}.{key}")
        over[name] = (lo, hi)
    lo, hi = [], []
    for element, slot, name in params:
        table = DEFAULT_BOUNDS[element] if _kind(element) == "joint" else DEFAULT_BOUNDS["bearing"]
        b = over.get(name, table[ELEMENT_PARAMS[_kind(element)][slot]])
        lo.append(b[0])
        hi.append(b[1])
    return Bounds(np.array(lo, float), np.array(hi, float))


class FRFProblem:
    """Minimise f(x) (module docstring) over x = log10 of ``params`` within ``bounds``.

    Parameters
    ----------
    assembly : Assembly
        The structure; parameters not identified keep its values.
    params : sequence of str
        Full names (:func:`parse_params`).
    measurements : sequence of Measured
    bounds : Bounds, optional
        One (lo, hi) per parameter, SI (default :func:`param_bounds`).
    start : dict, optional
        name → starting value, SI; must lie inside the bounds. Default: the assembly's value where it
        gives one (checked likewise).
    with_tool : bool, optional
        See :class:`~toolpoint.dynamics.points.ReceptanceModel`.

    Attributes
    ----------
    n_var : int
    xl, xu : (n_var,) ndarray
        log10 of the bounds.
    residual_scale : float
        RMS of the weighted measurements, m/N.
    nfev : int
        Model evaluations (points), a Jacobian counted as ``n_var``.
    fast : bool
        True when the rational single-element path is used.

    Examples
    --------
    >>> from toolpoint.dynamics.assembly import load_assembly
    >>> from toolpoint.dynamics.points import parse_point
    >>> a = load_assembly("examples/numerical_case.toml")
    >>> f = np.arange(100.0, 3001.0, 20.0)
    >>> tip = parse_point("holder_tip")
    >>> m = ReceptanceModel(a, f, [tip], [], with_tool=False)
    >>> meas = Measured(FRF(f, m.G0[:, m.dof(tip), m.dof(tip)]), tip, tip)
    >>> names = ["spindle_holder." + k for k in ("kt", "ct", "kr", "cr")]
    >>> prob = FRFProblem(a, names, [meas], with_tool=False)
    >>> prob.fast, float(prob.evaluate(np.log10(a.spindle_holder.as_array()))) < 1e-14
    (True, True)
    """

    def __init__(self, assembly: Assembly, params, measurements, bounds: Bounds | None = None, *,
                 start: dict | None = None, with_tool: bool | None = None):
        self.assembly = assembly
        self.params = parse_params(params, assembly)
        self.names = tuple(p[2] for p in self.params)
        self.n_var = len(self.params)
        self.bounds = bounds or param_bounds(self.params)
        self.xl, self.xu = self.bounds.log_lo, self.bounds.log_hi
        self.units = {p[2]: ELEMENT_UNITS[_kind(p[0])][ELEMENT_PARAMS[_kind(p[0])][p[1]]] for p in self.params}
        self.measurements = list(measurements)
        if not self.measurements:
            raise InputError("no measured FRF", file=assembly.source, field="measured")
        variable = list(dict.fromkeys(p[0] for p in self.params))
        points = [pt for m in self.measurements for pt in (m.response, m.force)]
        freqs = np.concatenate([m.frf.freq_hz for m in self.measurements])
        rot = {e: True for e, slot, _ in self.params if slot >= 2}
        self.model = ReceptanceModel(assembly, freqs, points, variable, with_tool=with_tool, rot=rot)
        self._base = np.stack([e.value for e in self.model.elements])  # (n_el, 4), NaN where unknown
        self._el = np.array([variable.index(p[0]) for p in self.params])
        self._slot = np.array([p[1] for p in self.params])
        for i, (e, slot, name) in enumerate(self.params):
            self._base[self._el[i], slot] = np.nan  # identified: never the file's value
        self._check_unknowns(variable)
        self.x_start = self._start(start)
        edges = np.cumsum([0] + [len(m.frf) for m in self.measurements])
        self._slices = [slice(a, b) for a, b in zip(edges[:-1], edges[1:])]
        sw = np.concatenate([np.full(len(m.frf), np.sqrt(m.weight)) for m in self.measurements])
        self._sw = sw
        self._meas = np.concatenate([m.frf.to_receptance().values for m in self.measurements]) * sw
        self.residual_scale = float(np.sqrt(np.mean(np.abs(self._meas) ** 2))) or 1.0
        self.fast = len(variable) == 1
        self._nfev = 0
        self._poly = None
        if not self.fast and self.model._D.shape[1] <= POLY_MAX_DOF:
            self._poly = self._polynomial()
        if self.fast:
            parts = [self.model.coupler(m.response, m.force, sl) for m, sl in zip(self.measurements, self._slices)]
            c = ToolPointCoupler.from_parts(
                np.concatenate([p.t00 for p in parts]) * sw,
                np.concatenate([p._u for p in parts]) * sw[:, None],
                np.concatenate([p._v for p in parts]),
                np.concatenate([p._P for p in parts]),
                np.concatenate([p.omega for p in parts]))
            full_lo = np.ones(4)  # slots not identified: placeholders, the inner problem's bounds are not used
            full_hi = np.full(4, 10.0)
            full_lo[self._slot], full_hi[self._slot] = self.bounds.lo, self.bounds.hi
            self._inner = JointProblem(c, self._meas, Bounds(full_lo, full_hi))
            with np.errstate(divide="ignore"):
                self._base_log = np.log10(np.nan_to_num(self._base[0], nan=1.0))

    def _polynomial(self):
        """Real matrices of the polynomial form of every measurement (see :meth:`_evaluate_poly`)."""
        dofs = [(e_i, s) for e_i, e in enumerate(self.model.elements) for s in ((0, 1) if e.rot else (0,))]
        m = len(dofs)
        cols = []  # (mask, q): coefficient of (iω)^q times the sum of the products with q damping factors
        for mask in range(2**m):
            cols += [(mask, q) for q in range(bin(mask).count("1") + 1)]
        E = np.empty((len(cols), self._meas.size), complex)
        Dn = np.empty_like(E)
        for meas, sl in zip(self.measurements, self._slices):
            num, den = self.model.minors(meas.response, meas.force, sl)
            iw = 1j * self.model.omega[sl]
            for r, (mask, q) in enumerate(cols):
                Dn[r, sl] = den[:, mask] * iw**q
                E[r, sl] = num[:, mask] * iw**q
        Nw = E * self._sw  # weighted numerator: √w h = Nw·μ / Dn·μ
        E = Nw - self._meas * Dn  # e = √w (num − h̄ den), f² = Σ |e|² / |den|²
        return _Poly(dofs, cols, np.ascontiguousarray(E.view(float)), np.ascontiguousarray(Dn.view(float)), Nw, Dn)

    def _monomials(self, v) -> np.ndarray:
        """(N, n_cols) products Σ Π k or c over each subset's DOFs, grouped by the number of c's."""
        dofs = self._poly.dofs
        N = v.shape[0]
        polys = {0: np.ones((N, 1))}
        for mask in range(1, 2 ** len(dofs)):
            d = mask.bit_length() - 1
            prev = polys[mask ^ (1 << d)]
            e_i, s = dofs[d]
            k, c = v[:, e_i, 2 * s, None], v[:, e_i, 2 * s + 1, None]
            new = np.zeros((N, prev.shape[1] + 1))
            new[:, :-1] += prev * k
            new[:, 1:] += prev * c
            polys[mask] = new
        return np.concatenate([polys[mask] for mask in range(2 ** len(dofs))], axis=1)

    def _evaluate_poly(self, X) -> np.ndarray:
        r"""f for X (N, n_var) from the polynomial form (:meth:`~toolpoint.dynamics.points.ReceptanceModel.minors`).

        h = num(k̃)/den(k̃) with num, den polynomials in the DOFs' k̃ = k + iωc; expanded, both are real
        linear combinations μ(p) of products of the parameters with complex, frequency-dependent
        coefficients, so a block of members costs two real matrix products, as in the holder–tool joint's
        :class:`~toolpoint.identification.objective.JointProblem`.
        """
        E, Dn = self._poly.E, self._poly.D
        v = self.values(X)
        out = np.empty(v.shape[0])
        for s in range(0, v.shape[0], POLY_BLOCK):
            mu = self._monomials(v[s : s + POLY_BLOCK])
            e = mu @ E
            d = mu @ Dn
            e *= e
            d *= d
            num = e[:, ::2] + e[:, 1::2]  # |e|²
            out[s : s + POLY_BLOCK] = np.sqrt(np.einsum("ij,ij->i", num, 1.0 / (d[:, ::2] + d[:, 1::2])))
        return out

    def _poly_model(self, x) -> np.ndarray:
        """Weighted model √w h (ΣF,) at one x from the polynomial form (residuals; the Jacobian is taken
        from the Woodbury form, whose derivative does not suffer the ~1e-7 cancellation of ∂(N/D))."""
        mu = self._monomials(self.values(x))
        return (mu @ self._poly.N)[0] / (mu @ self._poly.Dc)[0]

    # ------------------------------------------------------------------ set-up checks
    def _check_unknowns(self, variable):
        for i, e in enumerate(self.model.elements):
            missing = [ELEMENT_PARAMS[_kind(e.name)][s] for s in range(4)
                       if np.isnan(self._base[i, s]) and s not in self._slot[self._el == i]]
            if missing:
                raise InputError(f"{e.name} has no value in the file for {', '.join(missing)}: identify all four "
                                 "or give the joint", file=self.assembly.source, field=f"joints.{e.name}")

    def _start(self, start: dict | None) -> np.ndarray | None:
        a = self.assembly
        given = dict(start or {})
        x = np.full(self.n_var, np.nan)
        for i, (e, slot, name) in enumerate(self.params):
            v = given.pop(name, None)
            src = "start"
            if v is None:
                el = a.spindle_holder if e == "spindle_holder" else a.holder_tool if e == "holder_tool" else None
                if el is not None:
                    v = el.as_array()[slot]
                elif e.startswith("bearings["):
                    b = a.spindle.bearings[int(e[9:-1])]
                    v = (b.k, b.c, b.kr, b.cr)[slot]
                src = e if e.startswith("bearings") else f"joints.{e}"
                src = f"spindle.{src}" if e.startswith("bearings") else src
            if v is None or v == 0:  # no value, or a bearing's unmodelled kr/cr: no start
                continue
            lo, hi = self.bounds.lo[i], self.bounds.hi[i]
            if not lo <= v <= hi:
                raise InputError(f"{name} = {v:g} {self.units[name]} lies outside its search bounds [{lo:g}, {hi:g}]",
                                 file=a.source, field=f"{src}.{name.split('.')[-1]}" if src != "start" else
                                 f"identify.start.{name}")
            x[i] = np.log10(v)
        if given:
            raise InputError(f"unknown parameter {next(iter(given))!r} (identifying {', '.join(self.names)})",
                             file=a.source, field="identify.start")
        return x if np.all(np.isfinite(x)) else None

    # ------------------------------------------------------------------ values
    def values(self, X) -> np.ndarray:
        """Element values (N, n_elements, 4), SI, for X (N, n_var) in log10 space."""
        X = np.atleast_2d(np.asarray(X, float))
        v = np.broadcast_to(self._base, (X.shape[0],) + self._base.shape).copy()
        v[:, self._el, self._slot] = 10.0**X
        return v

    def _full_log(self, X) -> np.ndarray:
        X = np.atleast_2d(np.asarray(X, float))
        out = np.broadcast_to(self._base_log, (X.shape[0], 4)).copy()
        out[:, self._slot] = X
        return out

    @property
    def nfev(self) -> int:
        """Model evaluations so far (points; a Jacobian counts ``n_var``)."""
        return self._inner.nfev if self.fast else self._nfev

    def _model_stacked(self, X, jac: bool = False):
        """Weighted model (N, ΣF) (and ∂/∂x (N, n_var, ΣF)) on the general path."""
        v = self.values(X)
        N = v.shape[0]
        h = np.empty((N, self._meas.size), complex)
        J = np.empty((N, self.n_var, self._meas.size), complex) if jac else None
        for s in range(0, N, BLOCK):
            vb = v[s : s + BLOCK]
            for m, sl in zip(self.measurements, self._slices):
                hm, dm = self.model.frf_jac(vb, m.response, m.force, sl, jac=jac)
                h[s : s + BLOCK, sl] = hm * self._sw[sl]
                if jac:
                    d = dm[:, self._el, self._slot] * self._sw[sl]  # (n, n_var, F)
                    J[s : s + BLOCK, :, sl] = d * (np.log(10.0) * vb[:, self._el, self._slot])[..., None]
        return h, J

    # ------------------------------------------------------------------ optimiser interface
    def evaluate(self, X) -> np.ndarray:
        """Objective f (N,) for X (N, n_var), or a float for (n_var,); m/N."""
        X = np.asarray(X, float)
        single = X.ndim == 1
        if self.fast:
            out = self._inner.evaluate(self._full_log(X))
        elif self._poly is not None:
            out = self._evaluate_poly(X)
            self._nfev += out.size
        else:
            h, _ = self._model_stacked(X)
            out = np.linalg.norm(h - self._meas, axis=1)
            self._nfev += out.size
        return out[0] if single else out

    __call__ = evaluate

    def residuals(self, x) -> np.ndarray:
        """Stacked real and imaginary weighted residuals (2 ΣF,) at one x, in units of ``residual_scale``."""
        if self.fast:
            return self._inner.residuals(self._full_log(x)[0])
        h = self._poly_model(x) if self._poly is not None else self._model_stacked(x)[0][0]
        self._nfev += 1
        r = (h - self._meas) / self.residual_scale
        return np.concatenate([r.real, r.imag])

    def jacobian(self, x) -> np.ndarray:
        """∂residuals/∂x (2 ΣF, n_var), exact (counted as ``n_var`` evaluations)."""
        if self.fast:
            J = self._inner.jacobian(self._full_log(x)[0])
            self._inner.nfev += self.n_var - 4
            return J[:, self._slot]
        # the Woodbury form: the polynomial form's derivative loses ~1e-7 (relative) to cancellation
        J = self._model_stacked(x, jac=True)[1][0]
        self._nfev += self.n_var
        J = J / self.residual_scale
        return np.concatenate([J.real, J.imag], axis=1).T

    def model_frfs(self, x) -> list[FRF]:
        """The model's receptance at every measurement (unweighted, m/N) at one x; not counted."""
        if self.fast:
            h = self._inner.model(self._full_log(x)[0]) / self._sw
        else:  # the Woodbury solves (also where the polynomial form is used for the search)
            n = self._nfev
            h = self._model_stacked(x)[0][0] / self._sw
            self._nfev = n
        return [FRF(m.frf.freq_hz, h[sl], "receptance", f"identified at {m.response.text}")
                for m, sl in zip(self.measurements, self._slices)]


def identify_frfs(problem: FRFProblem, method: str = "hybrid", seed: int | None = 0, *, options: dict | None = None,
                  callback=None, intervals: str = INTERVALS_DEFAULT) -> IdentificationResult:
    r"""Identify ``problem``'s parameters with the one pipeline (:func:`toolpoint.identification.identify.solve`).

    Parameters
    ----------
    problem : FRFProblem
    method : str, default "hybrid"
        ``hybrid``, ``ga``, ``sa``, ``pso`` or ``de``.
    seed : int or None, default 0
    options : dict, optional
        Options of the optimiser.
    callback : callable, optional
        ``callback(nit, best_f, nfev)``.
    intervals : {"profile", "linear"}, default "profile"
        As in :func:`toolpoint.identification.identify.identify`.

    Returns
    -------
    IdentificationResult
        ``params``, ``ci95``, ``se_log10`` (linearised) keyed by the full names (``result.names``);
        ``correlation`` (linearised); ``model_frfs`` (one per measurement); ``warnings`` include one per
        pair of parameters whose log10 estimates correlate with \|ρ\| > 0.95, and one per interval that
        runs into a search bound.

    Warns
    -----
    IdentifiabilityWarning
        Once per entry of ``result.warnings``.
    """
    return solve(problem, method, seed, options=options, callback=callback, intervals=intervals)


def joint_names(element: str) -> list[str]:
    """The four full parameter names of a joint or bearing, e.g. ``spindle_holder.kt`` …"""
    return [f"{element}.{k}" for k in ELEMENT_PARAMS[_kind(element)]]


__all__ += ["joint_names", "element_names"]
