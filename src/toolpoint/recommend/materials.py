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
"""

from __future__ import annotations

__all__ = ["PRESETS", "preset"]

#: name → (K_t N/m², K_r dimensionless, source).
PRESETS: dict[str, tuple[float, float, str]] = {
    "al7075": (796e6, 0.212, "Altintas & Budak 1995, Al7075-T6 example"),
    "aluminium": (600e6, 1 / 3, "Insperger & Stépán 2004, milling example"),
    "steel": (2000e6, 0.3, "approximate medium-carbon steel value, not from one checked source"),
}


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
    key = "".join(ch for ch in name.lower() if ch not in "-_ ")
    return PRESETS.get(key)
