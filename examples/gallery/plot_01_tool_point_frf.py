"""
Tool-point FRF of an assembly
=============================

An assembly TOML (spindle on bearings, holder, tool, two joints; the paper's Table 1 holder–tool joint) to the
tool-point receptance by receptance coupling (RCSA). Each uniform segment is an exact Timoshenko transfer matrix,
so there is no mesh to converge.
"""

import matplotlib.pyplot as plt

from toolpoint import AssemblyModel, load_assembly

assembly = load_assembly("../numerical_case.toml")
model = AssemblyModel(assembly)
frf = model.tool_point_frf()  # 0–3000 Hz at 1 Hz, m/N
f_peak, h_peak = frf.peak()
print(f"dominant peak {f_peak:.0f} Hz, |h| = {h_peak:.2e} m/N")
frf.plot()
plt.show()
