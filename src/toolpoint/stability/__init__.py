"""Chatter stability of milling: stability lobes from tool-point FRFs.

* :func:`zoa_lobes` — zero-order approximation (Altintas & Budak 1995),
  straight from x/y receptances; fast, exact for time-invariant cutting.
* :func:`sdm_lobes` — semi-discretisation (Insperger & Stépán 2002/2004) of a
  state-space model of the tool point (:class:`StateSpaceModel`: real or
  complex modes, cross terms); needed at low radial immersion.
* :func:`sdm_limit_near` — the SDM limit near a guess per speed;
  :func:`sdm_limit_near_many` the same for many models (a prior's samples)
  at once; :func:`sdm_spectral_radius` — ρ at (speed, depth) points.
* :func:`from_modal_fit` builds the SDM's model from common-pole modal fits
  (:func:`toolpoint.dynamics.modal.fit_frfs`: complex modes, cross FRFs);
  :class:`ModalModel` holds real modes per direction given by hand.

The cut is described once by :class:`CuttingConditions` (teeth, tangential
cutting coefficient K_t in N/m², radial force ratio K_r = K_n/K_t, radial
immersion a_e/D, down/up milling). Units are SI inside (depth m, K_t N/m²,
receptance m/N); speeds in rpm.
Geometry and sign conventions: :mod:`toolpoint.stability.milling`.
"""

from .cutting import CuttingConditions
from .cutting import immersion_angles
from .milling import Lobe, LobeResult, Pocket, average_directional_matrix, directional_coefficients
from .sdm import sdm_limit_near, sdm_limit_near_many, sdm_lobes, sdm_spectral_radius
from .statespace import ModalModel, StateSpaceModel, from_modal_fit
from .zoa import zoa_lobes

__all__ = [
    "CuttingConditions",
    "Lobe",
    "LobeResult",
    "ModalModel",
    "Pocket",
    "StateSpaceModel",
    "average_directional_matrix",
    "directional_coefficients",
    "from_modal_fit",
    "immersion_angles",
    "sdm_limit_near",
    "sdm_limit_near_many",
    "sdm_lobes",
    "sdm_spectral_radius",
    "zoa_lobes",
]
