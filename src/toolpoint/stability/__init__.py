"""Chatter stability of milling: stability lobes from tool-point FRFs.

* :func:`zoa_lobes` — zero-order approximation (Altintas & Budak 1995),
  straight from x/y receptances; fast, exact for time-invariant cutting.
* :func:`sdm_lobes` — first-order semi-discretisation (Insperger & Stépán
  2002/2004) for modal models; needed at low radial immersion.
* :func:`fit_modes` — modal fit of an FRF (:class:`ModalModel`) to feed the SDM.

Units are SI inside (depth m, K_t N/m², receptance m/N); speeds in rpm.
Geometry and sign conventions: :mod:`toolpoint.stability.milling`.
"""

from .milling import Lobe, LobeResult, average_directional_matrix, directional_coefficients, immersion_angles
from .modalfit import ModalModel, fit_modes
from .sdm import sdm_lobes, sdm_spectral_radius
from .zoa import zoa_lobes

__all__ = [
    "Lobe",
    "LobeResult",
    "ModalModel",
    "average_directional_matrix",
    "directional_coefficients",
    "fit_modes",
    "immersion_angles",
    "sdm_lobes",
    "sdm_spectral_radius",
    "zoa_lobes",
]
