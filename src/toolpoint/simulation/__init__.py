"""Time-domain milling simulation: regenerative chatter, forces, surface location error.

* :func:`simulate_milling` — regenerative milling in the time domain for many
  (speed, depth) points at once: multi-mode x/y dynamics (real modes, or a
  full model with cross terms), surface-history chip thickness with the
  tool leaving the cut, helix by axial slices, runout, variable pitch,
  up/down milling, linear + edge force model; outputs forces,
  displacements, once-per-revolution samples, a stability verdict and
  metric, chatter frequency, surface location error (SLE) and surface.
* :func:`simulate_map`, :func:`stability_boundary` — the same over a grid,
  and the limit per speed by bisection.
* :func:`sle_frequency_domain` — SLE of stable cuts from the FRF and the
  Fourier series of the force (Schmitz & Mann 2006), an independent check.
* :func:`sensor_signal`, :func:`write_signal` — synthetic microphone or
  accelerometer records (WAV/CSV); :func:`to_audio_rate` — a recorder's
  anti-aliased resampling.

Conventions (angles, force directions) are those of
:mod:`toolpoint.stability.milling`, so the results compare with the SDM and
zero-order lobes. SI units inside; speeds in rpm.
"""

from .frequency import sle_frequency_domain
from .maps import SimulationMap, simulate_map, stability_boundary
from .signals import sensor_signal, to_audio_rate, write_signal
from .structure import ModalDynamics, as_modal_dynamics
from .time_domain import SimulationResult, simulate_milling
from .tool import Tool

__all__ = [
    "ModalDynamics",
    "SimulationMap",
    "SimulationResult",
    "Tool",
    "as_modal_dynamics",
    "sensor_signal",
    "to_audio_rate",
    "simulate_map",
    "simulate_milling",
    "sle_frequency_domain",
    "stability_boundary",
    "write_signal",
]
