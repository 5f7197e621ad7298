"""Recommended points against the truth a synthetic campaign hides from the pipeline (slow: a whole campaign).

A small campaign (40 tools, its own seed) is synthesised, identified and learned with the defaults a new user
takes; ``library`` then recommends points for tools it never measured. The truth: the campaign's true
spindle–holder model and joint law through the same zero-order lobes, with the library's cutting coefficients.
Independent of the pipeline's own models (it never reads ``truth/``).
"""

import json

import numpy as np
import pytest

from toolpoint.campaign.config import load_campaign
from toolpoint.campaign.synth import truth_joint
from toolpoint.cli.main import main
from toolpoint.dynamics.assembly import load_assembly
from toolpoint.dynamics.model import ToolPointModel
from toolpoint.dynamics.subassembly import Subassembly
from toolpoint.recommend.engine import robust_min
from toolpoint.recommend.library import read_library, tool_file_stem
from toolpoint.stability.zoa_batch import zoa_limits

pytestmark = pytest.mark.slow

TOOLS = ("id,diameter_mm,overhang_mm,teeth,holder,tangential_coeff_n_mm2,radial_ratio,material,radial_immersion,"
         "milling,rpm_min,rpm_max\n") + """S10-45,10,45,3,ER40,,,al7075,0.5,down,4000,24000
S12-60,12,60,3,ER40,,,al7075,0.5,down,4000,24000
S16-70,16,70,4,ER40,,,aluminium,0.3,up,3000,20000
S20-40,20,40,4,ER40,,,steel,0.2,down,1000,8000
S25-55,25,55,4,ER40,2000,0.3,steel,0.1,down,800,6000
S28-80,28,80,4,ER40,,,al7075,0.25,up,2000,12000
"""


@pytest.mark.first
def test_recommended_points_are_below_the_true_limit_on_a_small_campaign(tmp_path):
    camp, res, out = tmp_path / "camp", tmp_path / "camp" / "results", tmp_path / "lib"
    assert main(["campaign", "synth", str(camp), "--n", "40", "--seed", "11"]) == 0
    assert main(["campaign", "run", str(camp), "--out", str(res), "--workers", "1"]) == 0
    assert main(["campaign", "learn", str(res), "--no-plots", "--no-baselines"]) == 0  # defaults: 3×7 MFs
    lib = tmp_path / "tools.csv"
    lib.write_text(TOOLS)
    assert main(["library", str(lib), "--campaign", str(camp), "--models", str(res / "models"), "--out", str(out),
                 "--workers", "1", "--samples", "100", "--rpm-points", "300"]) == 0

    c = load_campaign(camp)
    tools, _ = read_library(lib)
    stable_at_high_p = []
    for t in tools:
        s = json.loads((out / "tools" / f"{tool_file_stem(t.id)}.json").read_text())
        a = np.load(out / "tools" / f"{tool_file_stem(t.id)}.npz")
        f, rpm = a["freq_hz"], a["rpm"]
        sub = Subassembly.from_assembly(load_assembly(camp / "truth" / "spindle_holder.toml",
                                                      require_tool=False), f)
        h = ToolPointModel(c.family.tool(t.diameter_mm, t.overhang_mm), sub, f).tool_point(
            truth_joint(t.diameter_mm, t.overhang_mm))
        true = 1e3 * zoa_limits(f, h, t.cutting, rpm)
        true_robust = robust_min(rpm, true, s["rpm_tolerance"])
        best = s["points"][0]
        j = int(np.argmin(np.abs(rpm - best["rpm"])))
        assert best["depth_mm"] <= true_robust[j], (t.id, best, true_robust[j])
        assert best["depth_mm"] >= 0.3 * true_robust[j], (t.id, best, true_robust[j])  # not uselessly cautious
        p = a["p_stable"] / 100.0
        d = a["depth_mm"][:, None] < s["cap_mm"]
        high = (p >= 0.95) & d
        stable_at_high_p.append((a["depth_mm"][:, None] < true[None, :])[high])
        assert s["dominant_source"] in ("joint", "cutting K_t", "cutting K_r", "subassembly")
    share = np.concatenate(stable_at_high_p).mean()
    assert share >= 0.95, share  # with the library's own K_t as truth, P ≥ 0.95 must hold at least as often
