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

Instead of ``[[mode]]`` tables, a ``[measured]`` table takes the modes from a measured tool-point FRF (a tap
test: ``toolpoint tap``'s output, or any FRF file :func:`toolpoint.io.frf_files.read_frf` reads), with the
uncertainty the shop states (:func:`prior_from_frf`; path relative to the TOML file, or given to
:func:`read_modal_prior` as ``frf``)::

    [measured]
    frf = "tap_frf.csv"
    sigma_freq = 0.01                  # defaults: FREQ_SIGMA, MEASURED_SIGMA_STIFFNESS, 0.2
    sigma_stiffness = 0.1
    sigma_damping = 0.2
    band_hz = [300, 3000]              # optional: else the trusted band found in the data
    max_modes = 3                      # optional: the most flexible modes kept
    quantity = "receptance"            # optional: what a CSV or CutPro file holds (UFF says it itself)

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

__all__ = ["read_modal_prior", "prior_from_library", "prior_from_frf", "modes_from_frf", "FREQ_SIGMA",
           "MEASURED_SIGMA_STIFFNESS"]


def read_modal_prior(path: str | os.PathLike, *, frf: str | os.PathLike | None = None) -> ModalPrior:
    """Read a modal-prior TOML file (format in the module docstring).

    ``frf``: a measured tool-point FRF file whose modes the prior takes (:func:`prior_from_frf`), in place of
    the file's ``[[mode]]`` tables and of its ``[measured]`` table's ``frf`` (that table's σ stay).

    Raises
    ------
    InputError
        Naming the file and the field (``cut.teeth``, ``mode[1].damping``, ``measured.frf``, …).
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
    meas = doc.get("measured")
    if meas is not None and not isinstance(meas, dict):
        raise InputError("must be a table", file=p, field="measured")
    if frf is not None or meas is not None:
        if "mode" in doc:
            raise InputError("[[mode]] tables and measured modes ([measured] or an FRF given) both: keep one",
                             file=p, field="mode")
        meas = meas or {}
        if frf is None and "frf" not in meas:
            raise InputError("missing: the measured FRF file", file=p, field="measured.frf")
        src = Path(frf) if frf is not None else p.parent / get(meas, "frf", "measured", kind=str)
    else:
        modes = doc.get("mode")
        if not isinstance(modes, list) or not modes:
            raise InputError("needs at least one [[mode]] (or a [measured] table with the FRF of a tap test)",
                             file=p, field="mode")
    try:
        cut = CuttingConditions(get(cut_t, "teeth", "cut", kind=int),
                                get(cut_t, "tangential_coeff_n_mm2", "cut") * 1e6,
                                get(cut_t, "radial_ratio", "cut"), get(cut_t, "radial_immersion", "cut"),
                                get(cut_t, "milling", "cut", default="down", kind=str))
    except InputError as err:
        raise InputError(err.message, file=p, field=f"cut.{err.field}" if err.field else "cut") from None
    rng = None
    if "rpm_min" in cut_t or "rpm_max" in cut_t:
        rng = (get(cut_t, "rpm_min", "cut"), get(cut_t, "rpm_max", "cut"))
    sig_kt, sig_kr = get(cut_t, "sigma_kt", "cut", default=0.1), get(cut_t, "sigma_kr", "cut", default=0.05)
    if meas is not None:
        band = meas.get("band_hz")
        if band is not None and not (isinstance(band, list) and len(band) == 2
                                     and all(isinstance(v, (int, float)) and not isinstance(v, bool) for v in band)
                                     and 0 <= band[0] < band[1] and math.isfinite(band[1])):
            raise InputError(f"must be [LO, HI] in Hz, got {band!r}", file=p, field="measured.band_hz")
        sig = {k: get(meas, k, "measured", default=d) for k, d in
               (("sigma_freq", FREQ_SIGMA), ("sigma_stiffness", MEASURED_SIGMA_STIFFNESS), ("sigma_damping", 0.2))}
        for k, v in sig.items():
            if not 0 <= v <= 1:
                raise InputError(f"must be from 0 to 1 (a log standard deviation), got {v}", file=p,
                                 field=f"measured.{k}")
        q = get(meas, "quantity", "measured", default="receptance", kind=str)
        n = get(meas, "max_modes", "measured", default=3, kind=int)
        if n < 1:
            raise InputError(f"must be ≥ 1, got {n}", file=p, field="measured.max_modes")
        from ..io.frf_files import read_frf

        return prior_from_frf(read_frf(src, min_points=3, quantity=q), cut, **sig, sigma_kt=sig_kt, sigma_kr=sig_kr,
                              band=None if band is None else tuple(float(v) for v in band), max_modes=n,
                              name=str(doc.get("name", p.stem)), rpm_range=rng, source=str(src))
    cols = {k: [] for k in ("freq_hz", "stiffness_n_m", "damping", "sigma_freq", "sigma_stiffness", "sigma_damping")}
    defaults = {"sigma_freq": 0.03, "sigma_stiffness": 0.15, "sigma_damping": 0.2}
    for i, m in enumerate(modes):
        if not isinstance(m, dict):
            raise InputError("must be a table", file=p, field=f"mode[{i}]")
        for k in cols:
            cols[k].append(get(m, k, f"mode[{i}]", default=defaults.get(k)))
    try:
        return ModalPrior(**{k: tuple(v) for k, v in cols.items()}, cutting=cut, sigma_kt=sig_kt, sigma_kr=sig_kr,
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


MEASURED_SIGMA_STIFFNESS = 0.1
"""Log σ of the modal stiffnesses of a prior made from a measured FRF (stated; a shop that knows its own sets it).
What it covers: the hammer's and the accelerometer's calibration (a few % each, their certificates), the fit's own
scatter on a tap test's noise (on 8 virtual tap records of :func:`toolpoint.io.virtual_tap.lab_like_tap`: ln σ
0.6–1.5 %, within 3.1 % of the modes the records were made from; ``test_a_prior_from_a_measured_frf_holds_its_modes``)
and the tool as it is clamped for the cut rather than for the tap (a re-clamped tool moves its tool-point stiffness
by several %). Not measured here on a shop's repeated taps."""


def prior_from_frf(frf, cutting: CuttingConditions, *, sigma_freq: float = FREQ_SIGMA,
                   sigma_stiffness: float = MEASURED_SIGMA_STIFFNESS, sigma_damping: float = 0.2,
                   sigma_kt: float = 0.1, sigma_kr: float = 0.05, band=None, max_modes: int = 3,
                   min_share: float = 0.1, name: str = "measured tool", rpm_range=None,
                   source: str | None = None) -> ModalPrior:
    """A :class:`ModalPrior` from a measured tool-point FRF (a tap test) and the uncertainty the shop states.

    The FRF enters as every measured FRF does (:func:`toolpoint.trust.common_band`: the trusted band, or ``band``
    (Hz) given) and its modes are a driving point's modal fit there (:func:`toolpoint.dynamics.modal.fit_frfs`,
    weighted in the quantity whose noise is white, modes of positive modal mass): f_r, ζ_r and k_r = m_r ω_r² (m_r
    the real-mode modal mass, :meth:`~toolpoint.dynamics.modal.ModalFit.modal_mass`). Kept: up to ``max_modes``
    modes whose static flexibility at resonance 1 / (2 ζ_r k_r) is at least ``min_share`` of the largest (the modes
    that set the lobes). σ: ``sigma_freq`` (default :data:`FREQ_SIGMA`: the running spindle moves the modes a
    tap test of the stationary one measured), ``sigma_stiffness`` (:data:`MEASURED_SIGMA_STIFFNESS`),
    ``sigma_damping`` (0.2: damping is the least repeatable of the three and changes with speed), per mode.

    Parameters
    ----------
    frf : FRF
        The measured FRF (any quantity; converted to receptance, m/N).
    cutting : CuttingConditions
        The cut (K_t, K_r the medians).

    Returns
    -------
    ModalPrior

    Raises
    ------
    InputError
        No trusted band, a fit that fails, no mode of positive modal mass in the band, a mode just outside the band
        as flexible as those inside (the fit's residual pole: the prior would lack it), or a kept mode narrower than
        the line spacing (its damping is not in the data) — naming ``source``.

    Examples
    --------
    >>> import numpy as np
    >>> from toolpoint.frf import FRF
    >>> f = np.arange(10.0, 4000.0, 2.0)
    >>> h = sum(1 / (k * (1 - (f / fn) ** 2 + 2j * z * f / fn)) for fn, k, z in ((1243, 2.92e6, 0.0619),
    ...                                                                         (1747, 1.2e7, 0.0288)))
    >>> pr = prior_from_frf(FRF(f, h), CuttingConditions(4, 2003e6, 0.404, 0.5))
    >>> [(round(a), round(b / 1e6, 2), round(c, 4)) for a, b, c in zip(pr.freq_hz, pr.stiffness_n_m, pr.damping)]
    [(1243, 2.92, 0.0619), (1747, 12.0, 0.0288)]
    """
    import warnings

    from ..dynamics.modal import DrivingPointWarning, fit_frfs
    from ..trust import common_band

    from ..trust import RECEPTANCE_RANGE

    h = frf.to_receptance()
    b = common_band([h], band=band, files=[source], field="measured.band_hz", hint="band_hz = [LO, HI]")
    peak = float(np.max(np.abs(b.cut(h).values)))
    if not RECEPTANCE_RANGE[0] <= peak <= RECEPTANCE_RANGE[1]:  # a mode's stiffness would be off as far
        raise InputError(f"the largest |H| is {peak:.2g} m/N, orders of magnitude from a tool point's "
                         f"({RECEPTANCE_RANGE[0]:g}–{RECEPTANCE_RANGE[1]:g} m/N): the file holds another unit or "
                         "quantity (toolpoint tap --output-quantity measured writes an accelerance: say quantity = "
                         "\"accelerance\" in [measured])", file=source, field="measured.frf")
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        try:
            fit = fit_frfs([b.cut(h)], noise=b.noise_quantity or None, driving_point=0)
        except InputError as err:
            raise InputError(f"modal fit of the measured FRF: {err.message}", file=source,
                             field="measured.frf") from None
    for w in caught:  # the fit kept modes of negative modal mass: said, with what the prior does with them
        if issubclass(w.category, DrivingPointWarning):
            warnings.warn(f"{source or 'the measured FRF'}: {w.message}; the prior leaves those modes out",
                          DrivingPointWarning, stacklevel=2)
        else:
            warnings.warn(w.message, w.category, stacklevel=2)
    mass = fit.modal_mass(0)
    ok = np.isfinite(mass) & (mass > 0) & (fit.zeta > 0)
    if not ok.any():
        raise InputError(f"no mode of positive modal mass in the band {b.lo_hz:g}–{b.hi_hz:g} Hz (is it the tool "
                         "tip's direct FRF, a driving point?)", file=source, field="measured.frf")
    fn, z = fit.fn_hz[ok], fit.zeta[ok]
    k = mass[ok] * (2 * np.pi * fn) ** 2
    flex = 1 / (2 * z * k)
    keep = np.flatnonzero(flex >= min_share * flex.max())
    keep = keep[np.argsort(-flex[keep])][:max_modes]
    keep = np.sort(keep)  # by frequency
    # a mode just outside the band that the fit needed as a residual pole, as flexible as those inside: the prior
    # would lack it (a band cut at 1100 Hz left out the tap example's 1071 Hz mode, one cut at 1500 Hz its 1981 Hz
    # mode; the lobes they set would be missing)
    rp = np.asarray(fit.residual_poles)
    if rp.size:
        w_r = np.abs(rp)
        a_r = fit.residual_real_modes()[0][:, 0]  # 1 / modal mass
        z_r = -rp.real / w_r
        with np.errstate(divide="ignore", invalid="ignore"):
            flex_r = np.where((a_r > 0) & (z_r > 0), a_r / (2 * z_r * w_r ** 2), 0.0)
        if flex_r.max() >= min_share * flex.max():
            r = int(np.argmax(flex_r))
            raise InputError(f"a mode just outside the band {b.lo_hz:.0f}–{b.hi_hz:.0f} Hz, near "
                             f"{w_r[r] / (2 * np.pi):.0f} Hz, is {flex_r[r] / flex.max():.2g} × as flexible as the "
                             "strongest inside: the prior would "
                             "lack it — widen the band (band_hz) or measure there (a harder hammer tip for modes above "
                             "the band)", file=source, field="measured.frf")
    # a mode whose half-power band 2ζf is narrower than the line spacing is not resolved: its peak, and so its
    # damping and stiffness, fall between the lines (a real driving point at 1 Hz lines: "51.5 Hz, ζ 0.03 %")
    df = float(np.min(np.diff(frf.freq_hz)))
    thin = [int(r) for r in keep if 2 * z[r] * fn[r] < df]
    if thin:
        r = thin[0]
        raise InputError(f"the mode at {fn[r]:.1f} Hz (ζ {100 * z[r]:.3g} %) is narrower than the FRF's line spacing: "
                         f"its half-power band {2 * z[r] * fn[r]:.3g} Hz against {df:.3g} Hz, so its damping and "
                         "stiffness are not in the data — measure with finer lines (a longer record: Δf = 1/T) or "
                         "state the modes in [[mode]] tables", file=source, field="measured.frf")
    m = keep.size
    # the name says where the modes came from and over which band (a mode above a soft tip's band is not in it)
    where = f"modes of {Path(source).name if source else 'the FRF'}, {b.lo_hz:.0f}–{b.hi_hz:.0f} Hz"
    return ModalPrior(tuple(float(v) for v in fn[keep]), tuple(float(v) for v in k[keep]),
                      tuple(float(v) for v in z[keep]), (sigma_freq,) * m, (sigma_stiffness,) * m,
                      (sigma_damping,) * m, cutting, sigma_kt=sigma_kt, sigma_kr=sigma_kr, name=f"{name} ({where})",
                      rpm_range=rpm_range)


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
