"""Where the prior of ``update`` comes from: a modal-prior TOML file, or one tool of a ``library`` output.

Modal-prior TOML (mm and N/mm² at the boundary like the tool library; σ are log standard deviations)::

    name = "my tool"
    [cut]
    teeth = 4
    tangential_coeff_n_mm2 = 2003      # K_t
    radial_ratio = 0.404               # K_r = K_n / K_t
    radial_immersion = 0.5             # a_e / D
    milling = "down"
    sigma_kt = 0.1
    sigma_kr = 0.025
    rpm_min = 5000                     # the machine's speeds (optional)
    rpm_max = 25000
    [[mode]]
    freq_hz = 1243
    stiffness_n_m = 2.92e6
    damping = 0.0619
    sigma_freq = 0.025
    sigma_stiffness = 0.1
    sigma_damping = 0.1

A ``library`` output (``OUT/tools/<id>.npz`` and ``.json``, :mod:`toolpoint.recommend.run`) holds the
tool's nominal tool-point FRF, the 5/50/95 % quantiles of |Φ| over its sampled joints and its cutting
conditions. :func:`prior_from_library` is the one adapter from that output to a :class:`ModalPrior`
(a change of how ``library`` represents uncertainty touches only this function): modes picked on
−Im Φ of the nominal FRF (natural frequency at the peak, damping from the half-power band, stiffness
k = 1 / (2 ζ |Im Φ(f_n)|)), σ of the stiffness from the |Φ| quantiles at the peak
(ln(q95/q05) / 3.29), σ of frequency and damping given (defaults ``FREQ_SIGMA`` = 0.01, see there, and 0.2: the
band at the peak does not tell damping from stiffness); σ of K_t and K_r the library's own for that tool
(``cutting_sigma_ln`` of its JSON: the preset's or the library row's), unless given.
"""

from __future__ import annotations

import json
import math
import os
import tomllib
from pathlib import Path

import numpy as np

from ..errors import InputError
from ..stability.cutting import CuttingConditions
from .model import ModalPrior

__all__ = ["read_modal_prior", "prior_from_library", "modes_from_frf", "FREQ_SIGMA"]


def read_modal_prior(path: str | os.PathLike) -> ModalPrior:
    """Read a modal-prior TOML file (format in the module docstring).

    Raises
    ------
    InputError
        Naming the file and the field (``cut.teeth``, ``mode[1].damping``, …).
    """
    p = Path(path)
    try:
        doc = tomllib.loads(p.read_text(encoding="utf-8"))
    except FileNotFoundError:
        raise InputError("file not found", file=p) from None
    except (tomllib.TOMLDecodeError, UnicodeDecodeError) as err:
        raise InputError(f"not a TOML file: {err}", file=p) from None
    except OSError as err:
        raise InputError(f"cannot read: {err.strerror or err}", file=p) from None

    def get(table, key, where, *, default=None, kind=float):
        if key not in table:
            if default is not None:
                return default
            raise InputError("missing", file=p, field=f"{where}.{key}")
        v = table[key]
        if kind is float:
            if isinstance(v, bool) or not isinstance(v, (int, float)) or not math.isfinite(v):
                raise InputError(f"must be a number, got {v!r}", file=p, field=f"{where}.{key}")
            return float(v)
        if not isinstance(v, kind) or isinstance(v, bool):
            raise InputError(f"must be {kind.__name__}, got {v!r}", file=p, field=f"{where}.{key}")
        return v

    cut_t = doc.get("cut")
    if not isinstance(cut_t, dict):
        raise InputError("missing table [cut]", file=p, field="cut")
    modes = doc.get("mode")
    if not isinstance(modes, list) or not modes:
        raise InputError("needs at least one [[mode]]", file=p, field="mode")
    try:
        cut = CuttingConditions(get(cut_t, "teeth", "cut", kind=int),
                                get(cut_t, "tangential_coeff_n_mm2", "cut") * 1e6,
                                get(cut_t, "radial_ratio", "cut"), get(cut_t, "radial_immersion", "cut"),
                                get(cut_t, "milling", "cut", default="down", kind=str))
    except InputError as err:
        raise InputError(err.message, file=p, field=f"cut.{err.field}" if err.field else "cut") from None
    cols = {k: [] for k in ("freq_hz", "stiffness_n_m", "damping", "sigma_freq", "sigma_stiffness", "sigma_damping")}
    defaults = {"sigma_freq": 0.03, "sigma_stiffness": 0.15, "sigma_damping": 0.2}
    for i, m in enumerate(modes):
        if not isinstance(m, dict):
            raise InputError("must be a table", file=p, field=f"mode[{i}]")
        for k in cols:
            cols[k].append(get(m, k, f"mode[{i}]", default=defaults.get(k)))
    rng = None
    if "rpm_min" in cut_t or "rpm_max" in cut_t:
        rng = (get(cut_t, "rpm_min", "cut"), get(cut_t, "rpm_max", "cut"))
    try:
        return ModalPrior(**{k: tuple(v) for k, v in cols.items()}, cutting=cut,
                          sigma_kt=get(cut_t, "sigma_kt", "cut", default=0.1),
                          sigma_kr=get(cut_t, "sigma_kr", "cut", default=0.05),
                          name=str(doc.get("name", p.stem)), rpm_range=rng)
    except InputError as err:
        raise InputError(err.message, file=p, field=err.field) from None


def modes_from_frf(freq_hz, frf, *, max_modes: int = 3, min_share: float = 0.1):
    """Peak-picked modes of a receptance: [(f_n Hz, k N/m, ζ)], strongest first.

    Peaks of −Im Φ holding ≥ ``min_share`` of the largest; ζ from the half-power frequencies of |Im Φ|
    (ζ = (f₂ − f₁) / 2 f_n), k = 1 / (2 ζ |Im Φ(f_n)|).

    Examples
    --------
    >>> import numpy as np
    >>> f = np.arange(100.0, 3000.0, 0.5)
    >>> r = f / 1200.0
    >>> h = 1 / (5e6 * (1 - r**2 + 2j * 0.03 * r))
    >>> [(round(a), round(b / 1e6, 2), round(c, 3)) for a, b, c in modes_from_frf(f, h)]
    [(1200, 5.0, 0.03)]
    """
    f = np.asarray(freq_hz, float)
    y = -np.asarray(frf).imag
    inner = (y[1:-1] > y[:-2]) & (y[1:-1] >= y[2:]) & (y[1:-1] > 0)
    idx = np.flatnonzero(inner) + 1
    if idx.size == 0:
        return []
    idx = idx[y[idx] >= min_share * y[idx].max()]
    idx = idx[np.argsort(-y[idx])][:max_modes]
    out = []
    for i in idx:
        half = y[i] / 2
        lo = i
        while lo > 0 and y[lo] > half:
            lo -= 1
        hi = i
        while hi < y.size - 1 and y[hi] > half:
            hi += 1
        # interpolate the half-power crossings
        f1 = np.interp(half, [y[lo], y[lo + 1]], [f[lo], f[lo + 1]]) if y[lo + 1] != y[lo] else f[lo]
        f2 = np.interp(half, [y[hi], y[hi - 1]], [f[hi], f[hi - 1]]) if y[hi - 1] != y[hi] else f[hi]
        zeta = max((f2 - f1) / (2 * f[i]), 1e-4)
        out.append((float(f[i]), float(1.0 / (2 * zeta * y[i])), float(zeta)))
    return out


FREQ_SIGMA = 0.01
"""Log σ of the natural frequencies of a prior made from a ``library`` output. The library's |Φ| band does not
say how the peaks move, but it bounds it: on the seed-3 campaign's EM12-60 its 5–95 % band is ±0.4–8 % of |Φ|
on the peaks' flanks, where a frequency shift σ_f would show as ±1.645 σ_f / (2ζ) (≈ ±70 % for σ_f 0.01, ζ
0.012): the joint and subassembly it samples move the peaks by about 0.1 %. What it never modelled is the
running spindle (speed and temperature move tool-point modes by about a percent): 0.01, not less."""


def prior_from_library(out_dir: str | os.PathLike, tool_id: str, *, sigma_freq: float = FREQ_SIGMA,
                       sigma_damping: float = 0.2, sigma_kt: float | None = None,
                       sigma_kr: float | None = None) -> ModalPrior:
    """A :class:`ModalPrior` of tool ``tool_id`` of a ``library`` output folder (see the module docstring).

    ``sigma_kt``, ``sigma_kr`` (log standard deviations of K_t and K_r): default the library's own for the tool,
    or 0.1 and 0.05 for an output that does not state them. ``sigma_freq``: log σ of every natural frequency
    (default ``FREQ_SIGMA``).

    Raises
    ------
    InputError
        A missing tool, or a FRF without a resonance.
    """
    from ..recommend.library import tool_file_stem

    tools = Path(out_dir) / "tools"
    stem = tool_file_stem(tool_id)  # the names library writes, never the id as a path
    npz, js = tools / f"{stem}.npz", tools / f"{stem}.json"
    if not npz.exists() or not js.exists():
        have = sorted(q.stem for q in tools.glob("*.json")) if tools.is_dir() else []
        raise InputError(f"no tool {tool_id!r} in this library output (tools: {', '.join(have[:10]) or 'none'})",
                         file=out_dir, field="tool")
    try:
        arr = np.load(npz)
        f, h, hq = arr["freq_hz"], arr["frf_nominal"], arr["frf_abs_q"]
        rpm = arr["rpm"] if "rpm" in arr.files else None  # the tool's speed range in the library
        doc = json.loads(js.read_text(encoding="utf-8"))
        c = doc["cutting"]
        cut = CuttingConditions(int(c["teeth"]), float(c["tangential_coeff"]), float(c["radial_ratio"]),
                                float(c["radial_immersion"]), str(c.get("milling", "down")))
        stated = doc.get("cutting_sigma_ln") or {}
        sigma_kt = float(stated.get("K_t", 0.1)) if sigma_kt is None else sigma_kt
        sigma_kr = float(stated.get("K_r", 0.05)) if sigma_kr is None else sigma_kr
    except (OSError, KeyError, ValueError, TypeError) as err:
        raise InputError(f"cannot read the tool's files ({err})", file=npz, field="tool") from None
    modes = modes_from_frf(f, h)
    if not modes:
        raise InputError("the tool's nominal FRF shows no resonance", file=npz, field="frf_nominal")
    sig_k = []
    for fn, _, _ in modes:
        i = int(np.argmin(np.abs(f - fn)))
        q05, q95 = float(hq[0, i]), float(hq[-1, i])
        sig_k.append(min(1.0, max(0.05, math.log(q95 / q05) / 3.29)) if q05 > 0 else 0.3)
    fn, k, z = zip(*modes)
    m = len(modes)
    return ModalPrior(tuple(fn), tuple(k), tuple(z), (sigma_freq,) * m, tuple(sig_k), (sigma_damping,) * m, cut,
                      sigma_kt=sigma_kt, sigma_kr=sigma_kr, name=f"library tool {tool_id}",
                      rpm_range=None if rpm is None or not rpm.size else (float(rpm.min()), float(rpm.max())))
