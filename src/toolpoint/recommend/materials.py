"""Named work-material presets of the linear cutting-force model (K_t N/m², K_r = K_n/K_t).

A tool library row may name one of these in its ``material`` column instead of
giving ``tangential_coeff_n_mm2`` and ``radial_ratio``. The values are
textbook examples, not calibrations of the user's tools and inserts: where the
recommended depths matter, measure the coefficients (cutting-force tests).

=========  ===========  ======  ==================================================================
name       K_t N/mm²    K_r     source
=========  ===========  ======  ==================================================================
al7075     796          0.212   Altintas & Budak (1995), CIRP Annals 44(1) 357–362, the Al7075-T6
                                example (also Altintas, *Manufacturing Automation*, ch. 4)
aluminium  600          1/3     Insperger & Stépán (2004), Int. J. Numer. Meth. Eng. 61, 117–141,
                                their milling example (K_t = 6e8, K_n = 2e8 N/m²)
steel      2000         0.3     approximate: the order of published values for medium-carbon
                                steels (AISI 1045 ≈ 1800–2200 N/mm²); not from one checked source
=========  ===========  ======  ==================================================================

Each coefficient is uncertain, and ``library`` samples it (log-normal, one standard deviation σ_ln of ln K):
a shop rarely knows K_t better than ±15–25 % (tool wear, edge preparation, feed, coolant; Altintas,
*Manufacturing Automation* 2nd ed., ch. 2, reports mechanistic calibrations differing by this much across
feeds and edges), read here as the 95 % range ±20 %, σ_ln = 0.10, for the published examples;
the ``steel`` preset is not from one checked source: σ_ln 0.15. K_r = K_n/K_t varies more with the
feed and the edge radius: σ_ln 0.15 (0.2 for steel). Coefficients given in the library row: σ_ln 0.10 and
0.15 unless its ``tangential_coeff_sigma_pct`` / ``radial_ratio_sigma_pct`` columns say otherwise (e.g. 3 %
after a cutting-force test).
"""

from __future__ import annotations

__all__ = ["PRESETS", "preset", "UNCERTAINTY", "LIBRARY_UNCERTAINTY", "uncertainty"]

#: name → (K_t N/m², K_r dimensionless, source).
PRESETS: dict[str, tuple[float, float, str]] = {
    "al7075": (796e6, 0.212, "Altintas & Budak 1995, Al7075-T6 example"),
    "aluminium": (600e6, 1 / 3, "Insperger & Stépán 2004, milling example"),
    "steel": (2000e6, 0.3, "approximate medium-carbon steel value, not from one checked source"),
}


#: name → (σ_ln K_t, σ_ln K_r): one standard deviation of the log of each coefficient (module docstring).
UNCERTAINTY: dict[str, tuple[float, float]] = {
    "al7075": (0.10, 0.15),
    "aluminium": (0.10, 0.15),
    "steel": (0.15, 0.20),
}
#: (σ_ln K_t, σ_ln K_r) of coefficients given in a library row without their own uncertainty columns.
LIBRARY_UNCERTAINTY = (0.10, 0.15)


def preset(name: str) -> tuple[float, float, str] | None:
    """The preset of a material name (case and ``-``/``_``/space insensitive), or None.

    Parameters
    ----------
    name : str
        Material name, e.g. ``"Al7075"`` or ``"al-7075"``.

    Returns
    -------
    (K_t N/m², K_r, source) or None

    Examples
    --------
    >>> preset("Al-7075")[:2]
    (796000000.0, 0.212)
    >>> preset("titanium") is None
    True
    """
    return PRESETS.get(_key(name))


def _key(name: str) -> str:
    return "".join(ch for ch in name.lower() if ch not in "-_ ")


def uncertainty(name: str) -> tuple[float, float]:
    """(σ_ln K_t, σ_ln K_r) of a preset name (:data:`UNCERTAINTY`); KeyError for an unknown name.

    Examples
    --------
    >>> uncertainty("Al-7075")
    (0.1, 0.15)
    """
    return UNCERTAINTY[_key(name)]
