"""A measurement's check: what a user reads before trusting lobes from a measured FRF (``toolpoint check``).

One call, :func:`check_measurement`, collects from the data alone:

* the band used and why (:func:`toolpoint.trust.common_band`: noise ×1/ω², a receptance rising towards 0 Hz,
  coherence, a given band) and the unit hint;
* the modes of the modal fit in that band (:func:`toolpoint.dynamics.modal.fit_frfs`, weighted as the noise is
  white), each with a confidence word — **clear**: its peak |A_r|/σ_r is ≥ 20 % of the largest |H| in the band;
  **weak**: 5–20 %; **doubtful**: below 5 %, or a negative modal mass on the driving point;
* the driving point (``driving_point``: by default FRF 0 when one FRF is given, none when several): the fit enforces
  positive modal mass on it (:func:`~toolpoint.dynamics.modal.fit_modal`'s rule: modes of negative mass dropped when
  the data cannot tell, else kept and named); the fit's notes are printed, its warnings are problems;
* the coherence (when the file has one): its median and the share of the band below 0.8;
* what looks wrong, one line each: no resonance in the band, a dominant peak at a band edge, a poor fit, low
  coherence, a large share of the data left out.
"""

from __future__ import annotations

import warnings
from dataclasses import dataclass

import numpy as np

from ..errors import InputError
from ..trust import COHERENCE_MIN, Band, common_band

__all__ = ["MeasurementCheck", "check_measurement"]


@dataclass(frozen=True)
class MeasurementCheck:
    """What :func:`check_measurement` found.

    Attributes
    ----------
    band : toolpoint.trust.Band
        The band used, why, and the noise quantity.
    fit : toolpoint.dynamics.modal.ModalFit or None
        The modal fit in the band (None when it failed; ``problems`` says why).
    confidence : tuple of str
        Per mode: ``"clear"``, ``"weak"`` or ``"doubtful"`` (module docstring).
    coherence : dict
        ``{"median": …, "below": share of the band with γ² < 0.8}`` per file that has a coherence; else {}.
    problems : tuple of str
        One line per thing that looks wrong.
    """

    band: Band
    fit: object
    confidence: tuple
    coherence: dict
    problems: tuple

    def report(self) -> str:
        """The one screen ``toolpoint check`` prints."""
        b = self.band
        lines = [f"band used: {b.lo_hz:g}–{b.hi_hz:g} Hz"
                 + (f" (noise white in {b.noise_quantity})" if b.noise_quantity else "")]
        lines += [f"  {n.replace('note: ', '')}" for n in b.notes if n.startswith("note")] or ["  (nothing left out)"]
        if self.fit is not None:
            lines.append(f"modes ({self.fit.n_modes}):  fn [Hz]   zeta [%]  confidence")
            lines += [f"  {r + 1:>3} {self.fit.fn_hz[r]:>10.1f} {100 * self.fit.zeta[r]:>9.2f}  {c}"
                      for r, c in enumerate(self.confidence)]
            lines.append("fit error in the band (relative RMS, " + self.fit.quantity + "): "
                         + ", ".join(f"{100 * e:.2g} %" for e in self.fit.fit_error))
        for name, c in self.coherence.items():
            lines.append(f"coherence {name}: median {c['median']:.3f}, {100 * c['below']:.0f} % of the band "
                         f"below {COHERENCE_MIN:g}")
        if self.fit is not None:
            lines += [f"  {n}" for n in self.fit.notes if n.startswith("note: ")]
        lines.append("looks wrong:" if self.problems else "looks wrong: nothing found")
        lines += [f"  - {p}" for p in self.problems]
        return "\n".join(lines)


def check_measurement(frfs, *, files=None, band=None, n_modes: int | None = None,
                      driving_point: int | None | str = "auto") -> MeasurementCheck:
    """Check measured FRFs before they are trusted (module docstring).

    Parameters
    ----------
    frfs : sequence of FRF
        Measured SISO FRFs on one grid (e.g. the tool point, a driving point).
    files : sequence of str, optional
        Their file names, for the lines.
    band : (float, float), optional
        A given band, Hz (no detection).
    n_modes : int, optional
        Modes of the fit (default: chosen by the fit).
    driving_point : int or None, optional
        Index of the FRF that is a driving point (its modes must have positive modal mass), None for none; default
        ``"auto"``: 0 when one FRF is given (a tool-point FRF is a driving point), none when several.

    Returns
    -------
    MeasurementCheck

    Examples
    --------
    >>> from toolpoint import FRF
    >>> f = np.arange(1.0, 3001.0)
    >>> h = 1 / (1e7 * (1 - (f / 900) ** 2 + 0.04j * f / 900))
    >>> c = check_measurement([FRF(f, h)])
    >>> [round(x) for x in c.fit.fn_hz], c.confidence, c.problems
    ([900], ('clear',), ())
    """
    from .modal import DrivingPointWarning, fit_frfs

    frfs = list(frfs)
    names = [str(n) for n in files] if files is not None else [g.label or f"FRF {k + 1}" for k, g in enumerate(frfs)]
    b = common_band(frfs, band=band, files=names)
    problems = [n.replace("warning: ", "") for n in b.notes if n.startswith("warning")]
    f0 = frfs[0].freq_hz
    kept = np.mean((f0 >= b.lo_hz) & (f0 <= b.hi_hz))
    if kept < 0.7:
        problems.append(f"only {100 * kept:.0f} % of the data lies in the trusted band")
    cut = [b.cut(g) for g in frfs]
    if isinstance(driving_point, str) and driving_point == "auto":
        driving_point = 0 if len(frfs) == 1 else None
    fit, conf = None, ()
    try:
        with warnings.catch_warnings():  # the driving-point warning is in fit.notes: one of the problems below
            warnings.simplefilter("ignore", DrivingPointWarning)
            fit = fit_frfs(cut, n_modes=n_modes, noise=b.noise_quantity or None, driving_point=driving_point)
    except InputError as err:
        if err.field == "driving_point":
            raise
        problems.append(f"modal fit failed: {err.message}")
    if fit is not None:
        if fit.n_modes == 0:
            problems.append("no resonance found in the band: lobes from this FRF would be limited by its edges")
        top = float(np.max(np.abs(cut[0].values)))
        sigma = -fit.poles.real
        size = np.abs(fit.residues[:, 0]) / np.maximum(sigma, 1e-300) / max(top, 1e-300)
        words = np.where(size >= 0.2, "clear", np.where(size >= 0.05, "weak", "doubtful"))
        if driving_point is not None and fit.n_modes:
            # a driving point's modes all have positive modal mass (a_r = −2 Re(A_r conj λ_r) > 0): a mode of
            # negative mass the fit kept is a fit artefact the data demand — or the FRF is no driving point
            wrong = ~(fit.real_modes()[0][:, driving_point] > 0)
            words = np.where(wrong, "doubtful", words)
        problems += [n[len("warning: "):] for n in fit.notes if n.startswith("warning: ")]
        conf = tuple(str(w) for w in words)
        if float(np.max(fit.fit_error)) > 0.2:
            problems.append(f"the modal fit leaves {100 * float(np.max(fit.fit_error)):.0f} % of the band "
                            "unexplained: check the band and the data")
    a = np.abs(cut[0].values)
    if a.size > 4 and int(np.argmax(a)) in (0, 1, a.size - 2, a.size - 1):
        problems.append(f"the largest |H| sits at the band edge ({cut[0].freq_hz[int(np.argmax(a))]:g} Hz): the "
                        "dominant resonance may lie outside the band")
    coh = {}
    for name, g in zip(names, cut):
        if g.meta.get("coherence") is not None:
            gam = np.asarray(g.meta["coherence"], float).reshape(-1)
            coh[name] = {"median": float(np.median(gam)), "below": float(np.mean(gam < COHERENCE_MIN))}
            if coh[name]["below"] > 0.1:
                problems.append(f"{name}: coherence below {COHERENCE_MIN:g} over {100 * coh[name]['below']:.0f} % "
                                "of the band (more hits, another hammer tip or a better point)")
    return MeasurementCheck(b, fit, conf, coh, tuple(problems))
