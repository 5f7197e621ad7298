"""A realistic synthetic campaign with a documented, fixed truth law.

What the lab would do, simulated: one ISO 40 spindle with an ER40 collet chuck;
its subassembly measured once with a Ø20 × 50 mm blank (inverse RCSA, three
impact FRFs with noise); then ``n`` carbide end mills of diameter D 9–30 mm at
overhang L 16–83 mm, each tool-point FRF measured with complex noise.

Truth law of the holder–tool joint (fixed before any training was looked at;
D, L in mm, D₀ = 16 mm, L₀ = 50 mm)::

    kt = 2.1e7 (D/D₀)^1.5 (L/L₀)^-0.15   N/m        contact stiffness grows with the
    kr = 1.4e6 (D/D₀)^2.5 (L/L₀)^-0.10   N m/rad    clamped shank (area ∝ D, bending
    ct = 15    (D/D₀)^1.0                N s/m       ∝ D³…D⁴); longer overhangs load the
    cr = 3     (D/D₀)^2.0                N m s/rad   contact harder (slightly softer)

At D₀ = 16 mm, L₀ = 50 mm this is the paper's Table 1 joint. Diameters are the
standard series 9, 10, 12, 14, 16, 18, 20, 22, 25, 28, 30 mm (cycled), overhangs
uniform in 16–83 mm (seeded). The truth (law, per-tool joints, the true
subassembly model) goes to ``truth/``, which the pipeline never reads.
"""

from __future__ import annotations

import csv
import json
from pathlib import Path

import numpy as np

from ..dynamics.assembly import MM, Component, Material, Segment, load_assembly
from ..io.atomic import atomic_open
from ..frf import FRF
from ..io.frf_files import write_frf
from ..dynamics.inverse_rcsa import blank_frfs
from ..dynamics.model import ToolPointModel
from ..dynamics.subassembly import Subassembly
from .config import ToolFamily

DIAMETERS_MM = (9, 10, 12, 14, 16, 18, 20, 22, 25, 28, 30)
OVERHANG_MM = (16.0, 83.0)
D0, L0 = 16.0, 50.0
BAND_HZ = (20.0, 4000.0)
STEP_HZ = 2.0
CARBIDE = {"E": 580e9, "rho": 14500.0, "nu": 0.22}

SPINDLE_HOLDER_TOML = """\
# True spindle–holder subassembly of the synthetic campaign (truth: the pipeline
# never reads this file; it sees only the blank measurements in sh/).
# Spindle as in examples/numerical_case.toml; ER40 collet chuck, 70 mm gauge length.
[spindle]
segments = [
  { length_mm = 60,  od_mm = 50, id_mm = 20 },
  { length_mm = 200, od_mm = 65, id_mm = 20 },
  { length_mm = 100, od_mm = 70, id_mm = 20 },
  { length_mm = 40,  od_mm = 90, id_mm = 20 },
  { length_mm = 65,  od_mm = 90 },
]
bearings = [
  { x_mm = 30,  k = 2.0e8, c = 1500 },
  { x_mm = 370, k = 3.0e8, c = 2500 },
  { x_mm = 395, k = 3.0e8, c = 2500 },
]
[holder]
segments = [
  { length_mm = 20, od_mm = 63 },
  { length_mm = 25, od_mm = 55 },
  { length_mm = 25, od_mm = 50 },
]
[joints.spindle_holder]
kt = 5.0e8
ct = 300.0
kr = 1.5e7
cr = 50.0
"""

# Second point 5 mm from the holder face: the best-conditioned choice (inverse_rcsa docs).
BLANK = {"od_mm": 20.0, "length_mm": 50.0, "x2_mm": 45.0}


def truth_joint(diameter_mm, overhang_mm) -> np.ndarray:
    """The joint of the truth law (module docstring); broadcasts over arrays.

    Parameters
    ----------
    diameter_mm, overhang_mm : array_like
        Tool diameter D and overhang L, mm.

    Returns
    -------
    ndarray, shape (..., 4)
        [kt N/m, ct N s/m, kr N m/rad, cr N m s/rad].

    Examples
    --------
    >>> truth_joint(16, 50).tolist()  # the paper's Table 1 joint
    [21000000.0, 15.0, 1400000.0, 3.0]
    """
    d = np.asarray(diameter_mm, float) / D0
    lr = np.asarray(overhang_mm, float) / L0
    return np.stack(
        np.broadcast_arrays(2.1e7 * d**1.5 * lr**-0.15, 15.0 * d**1.0, 1.4e6 * d**2.5 * lr**-0.10, 3.0 * d**2.0), -1
    )


def _noisy(frf: FRF, level: float, rng: np.random.Generator) -> FRF:
    if level <= 0:
        return frf
    sigma = level * np.abs(frf.values).max()
    n = (rng.standard_normal(len(frf)) + 1j * rng.standard_normal(len(frf))) * sigma / np.sqrt(2)
    return FRF(frf.freq_hz, frf.values + n, frf.quantity, frf.label)


def synthesise(out: str | Path, n: int = 178, seed: int = 0, noise: float = 0.01, blank_noise: float = 5e-5,
               smooth: str | float = "modal", fmt: str = "csv") -> dict:
    """Write a synthetic campaign folder (the truth law of the module docstring).

    Parameters
    ----------
    out : path-like
        Folder to write (``campaign.toml``, ``measurements.csv``, ``frf/``, ``sh/``, ``truth/``).
    n : int, default 178
        Number of tool assemblies.
    seed : int, default 0
        Seed of the overhangs and the noise.
    noise, blank_noise : float
        Complex Gaussian noise of the tool-point and the blank FRFs, standard
        deviation relative to each FRF's peak. The blank's is lower by default
        because inverse RCSA amplifies it ~100–400× into the subassembly
        (measurements: ``docs/design/campaign.md``).
    smooth : "modal" or float, default "modal"
        Written to campaign.toml: common-pole fit of the blank FRFs, or a
        Savitzky–Golay window in Hz.
    fmt : {"csv", "uff"}, default "csv"
        FRF file format.

    Returns
    -------
    dict
        ``n``, ``seed``, ``noise``, ``blank_noise``, ``band_hz`` (Hz), ``step_hz`` (Hz), ``law`` (text).
    """
    out = Path(out)
    rng = np.random.default_rng(seed)
    f = np.arange(BAND_HZ[0], BAND_HZ[1] + STEP_HZ / 2, STEP_HZ)
    (out / "truth").mkdir(parents=True, exist_ok=True)
    (out / "sh").mkdir(exist_ok=True)
    (out / "frf").mkdir(exist_ok=True)
    with atomic_open(out / "truth" / "spindle_holder.toml") as fh:
        fh.write(SPINDLE_HOLDER_TOML)
    sub = Subassembly.from_assembly(load_assembly(out / "truth" / "spindle_holder.toml", require_tool=False), f)

    carbide = Material("carbide", **CARBIDE)
    family = ToolFamily(carbide, 0.8, 2.0)
    blank = Component("blank", (Segment(BLANK["length_mm"] * MM, BLANK["od_mm"] * MM, 0.0,
                                        Material("steel", 210e9, 7800.0, 0.3)),))
    for G in blank_frfs(blank, BLANK["x2_mm"] * MM, sub):
        write_frf(out / "sh" / f"{G.label}.csv", _noisy(G, blank_noise, rng))

    D = np.array([DIAMETERS_MM[i % len(DIAMETERS_MM)] for i in range(n)], float)
    L = np.round(rng.uniform(*OVERHANG_MM, n), 1)
    joints = truth_joint(D, L)
    rows, truth_rows = [], []
    for i in range(n):
        mid = f"T{i + 1:03d}"
        tool = family.tool(D[i], L[i])
        h = ToolPointModel(tool, sub, f).tool_point(joints[i])
        name = f"frf/{mid}.{ 'uff' if fmt == 'uff' else 'csv'}"
        write_frf(out / name, _noisy(FRF(f, h, "receptance", mid), noise, rng))
        rows.append({"id": mid, "diameter_mm": D[i], "overhang_mm": L[i], "frf": name, "holder": "ER40"})
        truth_rows.append({"id": mid, "diameter_mm": D[i], "overhang_mm": L[i],
                           **dict(zip(("kt", "ct", "kr", "cr"), joints[i]))})

    with atomic_open(out / "campaign.toml") as fh:
        smooth_line = f'smooth = "{smooth}"' if isinstance(smooth, str) else f"smooth_hz = {smooth:g}"
        fh.write(CAMPAIGN_TOML.format(lo=BAND_HZ[0], hi=BAND_HZ[1], smooth=smooth_line, **BLANK, **CARBIDE))
    _write_csv(out / "measurements.csv", rows)
    _write_csv(out / "truth" / "truth.csv", truth_rows)
    summary = {"n": n, "seed": seed, "noise": noise, "blank_noise": blank_noise, "band_hz": list(BAND_HZ),
               "step_hz": STEP_HZ, "law": __doc__.split("Truth law")[1].split("At D₀")[0].strip()}
    with atomic_open(out / "truth" / "law.json") as fh:
        json.dump(summary, fh, indent=2)
    return summary


def _write_csv(path: Path, rows: list[dict]) -> None:
    with atomic_open(path, newline="") as fh:
        w = csv.DictWriter(fh, fieldnames=list(rows[0]))
        w.writeheader()
        w.writerows(rows)


CAMPAIGN_TOML = """\
# Synthetic campaign written by `toolpoint campaign synth` (see truth/law.json).
[campaign]
band_hz = [{lo}, {hi}]

[materials.carbide]
E = {E}
rho = {rho}
nu = {nu}

[tool_family]
material = "carbide"
flute_ratio = 0.8          # equivalent diameter of the flutes / D
flute_length_ratio = 2.0   # flute length = 2 D, capped at the overhang

[holders.ER40]             # subassembly measured with a blank (inverse RCSA, Park et al.)
blank = {{ segments = [{{ length_mm = {length_mm}, od_mm = {od_mm} }}], x2_mm = {x2_mm}, \
G11 = "sh/G11.csv", G12 = "sh/G12.csv", G22 = "sh/G22.csv", {smooth} }}

[identify]
method = "hybrid"
"""
