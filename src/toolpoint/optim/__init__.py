"""Optimisers for joint identification: GA, SA, PSO (ours), DE (scipy) and the hybrid."""

from .base import Termination
from .de import DE
from .ga import GA
from .hybrid import Hybrid
from .pso import PSO
from .sa import SA

METHODS = {"hybrid": Hybrid, "ga": GA, "sa": SA, "pso": PSO, "de": DE}

__all__ = ["DE", "GA", "METHODS", "PSO", "SA", "Hybrid", "Termination"]
