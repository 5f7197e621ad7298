"""Stability lobes from measured FRFs: trusted band → (modal model →) lobes, with every check and note.

The one pipeline behind ``toolpoint lobes`` and a notebook's call (:func:`lobes_from_frf`):

1. **Band.** Every FRF is cut to one band, :func:`toolpoint.trust.common_band` (given, or the intersection of
   the files' trusted bands: low-frequency noise ×1/ω², a receptance rising towards 0 Hz, low coherence). A chatter
   frequency is therefore only ever taken inside the band: a limit set by a low-frequency artefact cannot occur.
2. **Zero-order lobes** (:func:`~toolpoint.stability.zoa.zoa_lobes`) — always computed: the answer of
   ``method="zoa"`` and the cross-check of the semi-discretisation.
3. **Semi-discretisation** (``method="sdm"``) on a modal model fitted in the band
   (:func:`toolpoint.dynamics.modal.fit_frfs`, weighted as the band's noise is white). The SDM never declares
   stability on a failed model. The tool-point FRF is a driving point (a direct FRF at the tool tip; with cross
   FRFs, xx and yy): the fit enforces positive modal mass on it, and its notes (modes of negative mass dropped, or
   kept with a warning) join the result's. The model is refused (one line naming the file) when

   * the fit leaves ≥ 95 % of the FRF unexplained (noise only) or > 50 % (:data:`BAD_FIT`),
   * it holds no mode inside the band, or
   * a dominant peak of the FRF in the band (|H| ≥ :data:`PEAK_SHARE` × the largest) has no fitted mode within
     :data:`PEAK_TOL` of its frequency — the peak the lobes would hinge on is missing.

   Where the SDM finds no chatter at a speed the ZOA limits, or the two minima differ by more than
   :data:`AGREE_TOL`, a note says so: between the zero-order approximation and the SDM a few percent are
   expected at moderate immersion (the ZOA averages the directional factors over the tooth period), more at low
   radial immersion where the cut is strongly interrupted.

Speeds whose limiting chatter frequency sits on a trimmed band edge are flagged (:func:`toolpoint.trust.edge_hits`):
the resonance behind them may lie outside the band.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from ..errors import InputError
from ..frf import FRF
from ..trust import Band, common_band, edge_hits
from .cutting import CuttingConditions
from .milling import LobeResult

__all__ = ["MeasuredLobes", "lobes_from_frf", "BAD_FIT", "NO_RESONANCE", "PEAK_SHARE", "PEAK_TOL", "AGREE_TOL"]

NO_RESONANCE = 0.95
"""A modal fit leaving this relative RMS error explains < 10 % of the FRF's energy: no resonance (noise only)."""

BAD_FIT = 0.5
"""A fit worse than this explains < 75 % of the FRF: lobes from it would describe another structure."""

PEAK_SHARE = 0.5
"""A peak of |H| in the band at least this share of the largest is dominant: the model must hold a mode there."""

PEAK_TOL = 0.05
"""Relative distance within which a fitted natural frequency counts as the mode of a dominant peak (5 %: the |H|
peak of a mode with ζ ≤ 10 % and its neighbours' interference stay within it)."""

AGREE_TOL = 0.25
"""Relative difference of the ZOA and SDM minima beyond which a note reports the disagreement."""

_FLAGS = ("FRF", "--frf-y", "--frf-xy", "--frf-yx")


@dataclass(frozen=True)
class MeasuredLobes:
    """Stability lobes from measured FRFs and how they were obtained.

    Attributes
    ----------
    lobes : LobeResult
        The answer (depths in m, chatter frequencies in Hz) of the method asked for.
    method : str
        ``"zoa"`` or ``"sdm"``.
    band : toolpoint.trust.Band
        The band used (Hz), why, and the noise quantity the modal fit was weighted in.
    zoa : LobeResult
        The zero-order lobes on the same band (the answer itself when ``method="zoa"``).
    modal : tuple
        The modal fits behind the SDM (x and y, or one per force direction with cross FRFs); () for the ZOA.
    edge : numpy.ndarray
        (n,) bool: speeds whose limiting chatter frequency lies at a trimmed edge of the band (not trusted).
    min_at_edge : bool
        Whether the absolute minimum's chatter frequency lies at such an edge.
    notes : tuple of str
        One-line notes and warnings, in the order a user should read them (what the CLI prints on stderr).
    """

    lobes: LobeResult
    method: str
    band: Band
    zoa: LobeResult
    modal: tuple = ()
    edge: np.ndarray = field(default_factory=lambda: np.zeros(0, bool))
    min_at_edge: bool = False
    notes: tuple = ()


def lobes_from_frf(frf_x: FRF, cutting: CuttingConditions, rpm, *, frf_y: FRF | None = None,
                   frf_xy: FRF | None = None, frf_yx: FRF | None = None, method: str = "zoa", band=None,
                   n_modes: int | None = None, accuracy: float = 1.0, files: dict | None = None,
                   progress=None, log=None) -> MeasuredLobes:
    """Stability lobes of a milling cut from measured tool-point receptances (module docstring).

    Parameters
    ----------
    frf_x : FRF
        x (feed) receptance, m/N, as measured.
    cutting : CuttingConditions
        Teeth, K_t (N/m²), K_r, a_e/D, down/up milling.
    rpm : array_like
        Increasing spindle speeds, rpm.
    frf_y, frf_xy, frf_yx : FRF, optional
        y receptance (default: the same as x), cross receptances (default 0), m/N.
    method : {"zoa", "sdm"}
        Zero-order approximation or semi-discretisation (any case).
    band : (float, float), optional
        The band to use, Hz (default: the trusted band found in the data).
    n_modes : int, optional
        Modes of the SDM's modal fit (default: chosen by the fit).
    accuracy : float
        Resolution factor of the SDM (see :func:`~toolpoint.stability.sdm.sdm_lobes`).
    files : dict, optional
        Where each FRF came from, keyed ``"FRF"``, ``"--frf-y"``, ``"--frf-xy"``, ``"--frf-yx"`` (for messages).
    progress : callable, optional
        ``progress(done, total)`` over the SDM's speeds.
    log : callable, optional
        ``log(text)`` receives the modal tables as they are fitted (the CLI prints them).

    Returns
    -------
    MeasuredLobes

    Raises
    ------
    InputError
        Bad FRFs, bands or settings, or a modal model the SDM must not use — one line naming file and field.

    Examples
    --------
    >>> import numpy as np
    >>> from toolpoint.stability import CuttingConditions
    >>> f = np.arange(1.0, 3001.0)
    >>> h = 1 / (1e7 * (1 - (f / 900) ** 2 + 0.04j * f / 900))
    >>> cut = CuttingConditions(teeth=2, tangential_coeff=6e8, radial_ratio=0.3, radial_immersion=0.5)
    >>> r = lobes_from_frf(FRF(f, h), cut, np.linspace(5000, 20000, 200))
    >>> r.method, (r.band.lo_hz, r.band.hi_hz), r.notes
    ('zoa', (1.0, 3000.0), ())
    >>> round(r.lobes.min_depth_m * 1e3, 2)
    1.72
    """
    from .zoa import zoa_lobes

    method = str(method).strip().lower()
    if method not in ("zoa", "sdm"):
        raise InputError(f"must be 'zoa' or 'sdm', got {method!r}", field="--method")
    files = {k: (files or {}).get(k) for k in _FLAGS}
    given = dict(zip(_FLAGS, (frf_x, frf_y, frf_xy, frf_yx)))
    present = {k: v for k, v in given.items() if v is not None}
    b = common_band(list(present.values()), band=band, files=[files[k] for k in present])
    cut = {k: b.cut(v) for k, v in present.items()}
    notes = list(b.notes)
    rpm = np.asarray(rpm, float)
    try:
        zoa = zoa_lobes(cut["FRF"], cut.get("--frf-y"), cutting, rpm=rpm, frf_xy=cut.get("--frf-xy"),
                        frf_yx=cut.get("--frf-yx"))
    except InputError as err:  # name the file the FRF came from
        flag = {"frf_x": "FRF", "frf_y": "--frf-y", "frf_xy": "--frf-xy", "frf_yx": "--frf-yx"}.get(err.field)
        if flag is None:
            raise
        raise InputError(err.message, file=files[flag], field=flag) from None
    modal: tuple = ()
    res = zoa
    if method == "sdm":
        res, modal = _sdm(cut, files, b, cutting, rpm, n_modes, accuracy, progress, log)
        for fit in modal:  # the driving-point rule's notes (modes of negative modal mass dropped or kept)
            notes += [n for n in fit.notes if n not in notes]
        notes += _agreement(res, zoa)
    for flag in ("FRF", "--frf-y"):  # a direct FRF whose largest |H| sits at the band's edge: its resonance is out
        if flag not in cut:
            continue
        mag = np.abs(cut[flag].values)
        k = int(np.argmax(mag))
        if mag.size > 4 and k in (0, 1, mag.size - 2, mag.size - 1):
            side, f_edge = ("upper", b.hi_hz) if k >= mag.size - 2 else ("lower", b.lo_hz)
            if not np.isfinite(res.depth_m).any():  # "no chatter" would rest on a band that lacks the resonance
                raise InputError(f"no lobe within the band {b.lo_hz:g}–{b.hi_hz:g} Hz reaches these speeds, and the "
                                 f"largest |H| sits at the band's {side} edge ({f_edge:g} Hz): the resonance that "
                                 "sets the lobes lies outside the band, so 'no chatter' is not in the data — measure "
                                 "there (a harder hammer tip for modes above) or set --band LO:HI",
                                 file=files[flag], field=flag)
            out_of_band = (f"warning: {files[flag] or flag}: the largest |H| sits at the band's {side} edge "
                           f"({f_edge:g} Hz): the resonance that sets the lobes may lie outside the band "
                           f"{b.lo_hz:g}–{b.hi_hz:g} Hz, and the limits where it would chatter are missing or too "
                           "high")
            break
    else:
        out_of_band = None
    data_hz = frf_x.freq_hz
    edge = edge_hits(res.chatter_hz, (b.lo_hz, b.hi_hz), data_hz) & np.isfinite(res.depth_m)
    min_at_edge = bool(edge_hits([res.min_chatter_hz], (b.lo_hz, b.hi_hz), data_hz)[0])
    if edge.any():
        r = res.rpm[edge]
        notes.append(f"warning: at {edge.sum()} of {res.rpm.size} speeds ({r.min():.0f}–{r.max():.0f} rpm) the "
                     f"limiting chatter frequency lies at the edge of the band {b.lo_hz:g}–{b.hi_hz:g} Hz: those "
                     "limits are not trusted (the resonance behind them may lie outside the band); check the FRF "
                     "there and set --band LO:HI")
    elif out_of_band is not None:  # no limit at the edge, yet the band's largest |H| is there: said once
        notes.append(out_of_band)
    return MeasuredLobes(res, method, b, zoa, modal, edge, min_at_edge, tuple(notes))


def _sdm(cut, files, band, cutting, rpm, n_modes, accuracy, progress, log):
    """Modal model of the cut FRFs (checked) and the semi-discretisation on it.

    The tool-point FRFs are driving points (direct FRFs at the tool tip): each fit enforces positive modal mass on
    its direct FRF (``driving_point=0`` of :func:`~toolpoint.dynamics.modal.fit_frfs`; with cross FRFs, xx for
    force x and yy for force y), and its notes join the result's."""
    from .sdm import sdm_lobes
    from .statespace import from_modal_fit

    say = log or (lambda text: None)
    noise = band.noise_quantity or None
    if "--frf-xy" in cut or "--frf-yx" in cut:
        fits = []
        for direct, cross in (("FRF", "--frf-yx"), ("--frf-y" if "--frf-y" in cut else "FRF", "--frf-xy")):
            flags = [direct] + ([cross] if cross in cut else [])
            try:  # the direct FRF (xx for force x, yy for force y) is the driving point
                fit = _quiet_fit([cut[f] for f in flags], n_modes=n_modes, noise=noise, driving_point=0)
            except InputError as err:
                raise InputError(f"common-pole fit of {' and '.join(flags)}: {err.message}",
                                 file=files[flags[-1]], field=flags[-1]) from None
            say(f"common-pole fit, force {'xy'[len(fits)]} ({', '.join(flags)}):\n{fit.table()}")
            _check_model(fit, cut[direct], direct, files[direct])
            fits.append(fit)
        model = from_modal_fit(fits[0], fits[1])
    else:
        fits = [_fit_one(cut["FRF"], "FRF", files["FRF"], n_modes, noise)]
        say(f"modal fit, x ({cut['FRF'].label or 'FRF'}):\n{fits[0].table()}")
        if "--frf-y" in cut:
            fits.append(_fit_one(cut["--frf-y"], "--frf-y", files["--frf-y"], n_modes, noise))
            say(f"modal fit, y ({cut['--frf-y'].label or 'FRF_Y'}):\n{fits[1].table()}")
        else:
            say("y: same modes as x (symmetric tool)")
        model = from_modal_fit(fits[0], fits[1] if len(fits) > 1 else None)
    res = sdm_lobes(model, None, cutting, rpm=rpm, accuracy=accuracy, progress=progress)
    return res, tuple(fits)


def _fit_one(frf, flag, path, n_modes, noise):
    """Complex modes of one direct receptance (a driving point), refused when they cannot carry the SDM."""
    try:
        fit = _quiet_fit([frf], n_modes=n_modes, noise=noise, driving_point=0)
    except InputError as err:
        raise InputError(err.message, file=path, field=flag) from None
    _check_model(fit, frf, flag, path)
    return fit


def _quiet_fit(frfs, **kw):
    """:func:`~toolpoint.dynamics.modal.fit_frfs` with its :class:`DrivingPointWarning` left to ``fit.notes``
    (carried into :attr:`MeasuredLobes.notes`, so the CLI prints it once)."""
    import warnings

    from ..dynamics.modal import DrivingPointWarning, fit_frfs

    with warnings.catch_warnings():
        warnings.simplefilter("ignore", DrivingPointWarning)
        return fit_frfs(frfs, **kw)


def _check_model(fit, frf: FRF, flag, path) -> None:
    """Refuse a modal model the SDM must not use (module docstring, step 3)."""
    err = float(np.max(fit.fit_error))
    if err >= NO_RESONANCE:
        raise InputError(f"no resonance found for --method sdm: the modal fit ({fit.n_modes} modes) leaves "
                         f"{100 * err:.0f} % (relative RMS) of the FRF unexplained (noise only?)", file=path,
                         field=flag)
    lo, hi = fit.band_hz
    if fit.n_modes == 0:
        raise InputError(f"no mode inside the FRF's band {lo:g}–{hi:g} Hz for --method sdm (the resonance lies "
                         "outside the measured band)", file=path, field=flag)
    if err > BAD_FIT:
        raise InputError(f"the modal fit leaves {100 * err:.0f} % (relative RMS) of the FRF unexplained; the "
                         "semi-discretisation needs a modal model (try --modes, or --method zoa)", file=path,
                         field=flag)
    missing = [p for p in dominant_peaks(frf) if not np.any(np.abs(fit.fn_hz - p) <= PEAK_TOL * p)]
    if missing:
        raise InputError(f"the modal model ({fit.n_modes} modes at {', '.join(f'{x:.0f}' for x in fit.fn_hz)} Hz) "
                         f"has no mode at the FRF's dominant peak{'s' if len(missing) > 1 else ''} "
                         f"{', '.join(f'{p:.0f}' for p in missing)} Hz: the semi-discretisation would miss the "
                         "chatter there; use --method zoa, or set --modes or --band LO:HI", file=path, field=flag)


def dominant_peaks(frf: FRF) -> np.ndarray:
    """Frequencies (Hz) of the local maxima of |H| (smoothed over 5 points) with |H| ≥ :data:`PEAK_SHARE` × max."""
    a = np.abs(np.asarray(frf.values).reshape(len(frf), -1)[:, 0])
    if a.size < 5:
        return np.zeros(0)
    s = np.convolve(a, np.ones(5) / 5, "same")
    s[:2], s[-2:] = a[:2], a[-2:]
    inner = (s[1:-1] >= s[:-2]) & (s[1:-1] > s[2:]) & (s[1:-1] >= PEAK_SHARE * s.max())
    return frf.freq_hz[1:-1][inner]


def _agreement(sdm: LobeResult, zoa: LobeResult) -> list[str]:
    """Notes where the SDM and the ZOA on the same band disagree (module docstring)."""
    out = []
    stable = ~np.isfinite(sdm.depth_m) & np.isfinite(zoa.depth_m)
    if stable.any():
        out.append(f"warning: the semi-discretisation found no chatter at {stable.sum()} of {sdm.rpm.size} speeds "
                   "where the zero-order method limits the depth: check the modal model (toolpoint check) before "
                   "trusting those speeds")
    a, b = sdm.min_depth_m, zoa.min_depth_m
    if np.isfinite(a) and np.isfinite(b) and abs(a - b) > AGREE_TOL * b:
        out.append(f"warning: the SDM minimum {a * 1e3:.3g} mm and the zero-order minimum {b * 1e3:.3g} mm differ "
                   f"by {100 * abs(a - b) / b:.0f} % (more than {100 * AGREE_TOL:.0f} %): a few percent are expected "
                   "at moderate immersion; check the modal model and the band")
    return out
