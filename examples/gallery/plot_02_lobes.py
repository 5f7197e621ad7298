"""
Stability lobes from the predicted FRF
======================================

Zero-order (Altintas–Budak) stability lobes of the numerical case's tool: 2 teeth, K_t = 600 N/mm²,
K_r = 0.3, half immersion, down-milling.
"""

import matplotlib.pyplot as plt
import numpy as np

from toolpoint import AssemblyModel, load_assembly
from toolpoint.stability import CuttingConditions, zoa_lobes
from toolpoint.stability.plot import plot_lobes

frf = AssemblyModel(load_assembly("../numerical_case.toml")).tool_point_frf()
cut = CuttingConditions(teeth=2, tangential_coeff=6e8, radial_ratio=0.3, radial_immersion=0.5)
res = zoa_lobes(frf, cutting=cut, rpm=np.linspace(5000, 30000, 1000))
print(f"minimum {res.min_depth_m * 1e3:.3f} mm at {res.min_rpm:.0f} rpm, chatter {res.min_chatter_hz:.0f} Hz")
plot_lobes(res)
plt.show()
