"""toolpoint — tool-point FRF prediction for milling.

Data flow: geometry (TOML) → beam components → receptances → coupling →
objective → optimisers → result → campaign dataset → ANFIS → predicted joint →
predicted FRF → stability lobes.
"""

__version__ = "0.1.0"
