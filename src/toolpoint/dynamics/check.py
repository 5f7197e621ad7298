"""A measurement's check: what a user reads before trusting lobes from a measured FRF (``toolpoint check``).

One call, :func:`check_measurement`, collects from the data alone:

* the band used and why (:func:`toolpoint.trust.common_band`: noise ×1/ω², a receptance rising towards 0 Hz,
  coherence, a given band) and the unit hint;
* the modes of the modal fit in that band (:func:`toolpoint.dynamics.modal.fit_frfs`, weighted as the noise is
  white), each with a confidence word — **clear**: its peak |A_r|/σ_r is ≥ 20 % of the largest |H| in the band;
  **weak**: 5–20 %; **doubtful**: below 5 %, or, for a single FRF (a driving point), a modal constant on the other
  side from its largest mode's (a negative modal mass);
* the coherence (when the file has one): its median and the share of the band below 0.8;
* what looks wrong, one line each: no resonance in the band, a dominant peak at a band edge, a poor fit, low
  coherence, a large share of the data left out.
"""

from __future__ import annotations

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
        lines.append("looks wrong:" if self.problems else "looks wrong: nothing found")
        lines += [f"  - {p}" for p in self.problems]
        return "\n".join(lines)


def check_measurement(frfs, *, files=None, band=None, n_modes: int | None = None) -> MeasurementCheck:
    """Check measured FRFs before they are trusted (module docstring).

    Parameters
    ----------
    frfs : sequence of FRF
        Measured SISO FRFs on one grid (the first a driving point, e.g. the tool point).
    files : sequence of str, optional
        Their file names, for the lines.
    band : (float, float), optional
        A given band, Hz (no detection).
    n_modes : int, optional
        Modes of the fit (default: chosen by the fit).

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
    from .modal import fit_frfs

    frfs = list(frfs)
    names = [str(n) for n in files] if files is not None else [g.label or f"FRF {k + 1}" for k, g in enumerate(frfs)]
    b = common_band(frfs, band=band, files=names)
    problems = [n.replace("warning: ", "") for n in b.notes if n.startswith("warning")]
    f0 = frfs[0].freq_hz
    kept = np.mean((f0 >= b.lo_hz) & (f0 <= b.hi_hz))
    if kept < 0.7:
        problems.append(f"only {100 * kept:.0f} % of the data lies in the trusted band")
    cut = [b.cut(g) for g in frfs]
    fit, conf = None, ()
    try:
        fit = fit_frfs(cut, n_modes=n_modes, noise=b.noise_quantity or None)
    except InputError as err:
        problems.append(f"modal fit failed: {err.message}")
    if fit is not None:
        if fit.n_modes == 0:
            problems.append("no resonance found in the band: lobes from this FRF would be limited by its edges")
        top = float(np.max(np.abs(cut[0].values)))
        sigma = -fit.poles.real
        size = np.abs(fit.residues[:, 0]) / np.maximum(sigma, 1e-300) / max(top, 1e-300)
        words = np.where(size >= 0.2, "clear", np.where(size >= 0.05, "weak", "doubtful"))
        if len(cut) == 1 and fit.n_modes:
            # a driving point's modes all lie on the side of its largest one (Im A_r < 0 in our sign convention):
            # a mode on the other side is a negative modal mass — or the FRF is no driving point
            side = np.sign(fit.residues[int(np.argmax(size)), 0].imag)
            wrong = ~(side * fit.residues[:, 0].imag > 0.5 * np.abs(fit.residues[:, 0]))
            words = np.where(wrong, "doubtful", words)
            if wrong.any():
                problems.append(f"{int(wrong.sum())} mode(s) with a modal constant of the other sign (negative "
                                "modal mass at a driving point): a fit artefact, or the FRF is not a driving point")
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
