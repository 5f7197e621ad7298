"""`toolpoint library`: tool library → joint distribution → FRF band → lobes with uncertainty → recommendations."""

import atexit
import csv
import functools
import math
import shutil
import tempfile
from pathlib import Path

import numpy as np
import pytest

from toolpoint.campaign.config import load_campaign
from toolpoint.campaign.learn import learn
from toolpoint.campaign.synth import synthesise, truth_joint
from toolpoint.cli.main import main
from toolpoint.dynamics.model import ToolPointModel
from toolpoint.errors import InputError
from toolpoint.frf import FRF
from toolpoint.identification.params import PARAMS
from toolpoint.stability.zoa_batch import zoa_limits
from toolpoint.recommend.engine import QUANTILES
from toolpoint.recommend.library import read_library
from toolpoint.recommend.run import run_library
from toolpoint.stability import CuttingConditions, zoa_lobes

HEADER = ("id,diameter_mm,overhang_mm,teeth,holder,tangential_coeff_n_mm2,radial_ratio,material,radial_immersion,"
          "milling,rpm_min,rpm_max")
N_TOOLS = 50
REL_SE = {"kt": 0.02, "ct": 0.1, "kr": 0.05, "cr": 0.3}  # relative standard error of the fake identifications


@functools.lru_cache(maxsize=1)
def small_campaign() -> Path:
    """A synthetic campaign (truth-law holder as a model: no inverse RCSA) and models learned from
    identifications simulated from the truth law (log-normal errors with the intervals they claim).

    A real ``campaign run`` of 50 tools takes ~40 s; the benchmark (benchmarks/bench_library.py) uses one.
    """
    root = Path(tempfile.mkdtemp(prefix="tp_library_"))
    atexit.register(shutil.rmtree, root, True)  # cached across tests: removed when the worker ends
    camp = root / "camp"
    synthesise(camp, n=4, seed=3)
    toml = (camp / "campaign.toml").read_text()
    head = toml.split("[holders.ER40]")[0]
    (camp / "campaign.toml").write_text(head + '[holders.ER40]\nmodel = "truth/spindle_holder.toml"\n')
    rng = np.random.default_rng(5)
    D = np.array([(9, 10, 12, 14, 16, 18, 20, 22, 25, 28, 30)[i % 11] for i in range(N_TOOLS)], float)
    L = np.round(rng.uniform(16, 83, N_TOOLS), 1)
    res = root / "results"
    res.mkdir()
    with open(res / "identified.csv", "w", newline="") as fh:
        w = csv.writer(fh)
        w.writerow(["id", "holder", "diameter_mm", "overhang_mm", *PARAMS, *[f"{p}_{s}" for p in PARAMS
                                                                             for s in ("lo", "hi")], "status"])
        for i in range(N_TOOLS):
            true = truth_joint(D[i], L[i])
            se = np.array([REL_SE[p] for p in PARAMS])
            v = true * np.exp(se * rng.standard_normal(4))
            ci = [x for k in range(4) for x in (v[k] * np.exp(-1.96 * se[k]), v[k] * np.exp(1.96 * se[k]))]
            cells = [repr(float(x)) for x in (*v, *ci)]
            w.writerow([f"T{i:03d}", "ER40", D[i], L[i], *cells, "ok"])
    learn(res, test_size=10, mfs=(2, 2), epochs=30, baselines=True, plots=False)  # baselines: the saved GP
    return root


def _library(path: Path, rows: list[str]) -> Path:
    path.write_text(HEADER + "\n" + "\n".join(rows) + "\n")
    return path


GOOD = ["A16,16,50,3,ER40,,,al7075,0.5,down,4000,20000",
        "B12,12,60,2,ER40,600,0.333,,1,up,4000,20000"]
BAD = ["C1,16,50,3,ER40,,,,0.5,down,4000,20000",          # no cutting data
       "D1,16,50,3,HSK63,,,al7075,0.5,down,4000,20000",   # holder not in the campaign
       "E1,16,5000,3,ER40,,,al7075,0.5,down,4000,20000"]  # far outside the learned range


@functools.lru_cache(maxsize=1)
def small_run() -> Path:
    """One library run (workers=1) shared by the tests here and in test_report.py."""
    root = small_campaign()
    lib = _library(root / "lib.csv", GOOD + BAD[:2])
    out = root / "run"
    run_library(lib, root / "camp", root / "results" / "models", out, workers=1, n_samples=40, rpm_points=150,
                progress=False)
    return out


def _rows(out: Path) -> dict:
    with open(out / "recommendations.csv", newline="") as fh:
        return {r["id"]: r for r in csv.DictReader(fh)}


# ------------------------------------------------------------- batch ZOA vs zoa_lobes
def test_batch_limits_match_zoa_lobes():
    """The vectorised limits against the per-FRF zero-order solver (exact crossings by Newton steps)."""
    c = load_campaign(small_campaign() / "camp")
    f = np.arange(20.0, 4000.0, 2.0)
    sub = c.subassembly("ER40", f)
    rng = np.random.default_rng(0)
    for D, L, ri, mill, rpm in [(16, 50, 0.5, "down", (3000, 20000)), (10, 70, 1.0, "down", (4000, 24000)),
                                (25, 30, 0.3, "up", (1000, 8000))]:
        model = ToolPointModel(c.family.tool(D, L), sub, f)
        H = model.tool_point(truth_joint(D, L) * np.exp(0.1 * rng.standard_normal((4, 4))))
        cut = CuttingConditions(teeth=3, tangential_coeff=7.96e8, radial_ratio=0.212, radial_immersion=ri,
                                milling=mill)
        grid = np.linspace(*rpm, 300)
        fast = zoa_limits(f, H, cut, grid)
        for h, lim in zip(H, fast):
            ref = zoa_lobes(FRF(f, h), None, cut, rpm=grid).depth_m
            assert np.all(np.isfinite(ref))
            assert np.max(np.abs(lim / ref - 1)) < 0.01  # measured ≤ 0.45 % (docs/design/recommend.md)


def test_batch_limits_cap_only_clips():
    c = load_campaign(small_campaign() / "camp")
    f = np.arange(20.0, 4000.0, 2.0)
    h = ToolPointModel(c.family.tool(16, 50), c.subassembly("ER40", f), f).tool_point(truth_joint(16, 50))
    cut = CuttingConditions(teeth=3, tangential_coeff=7.96e8, radial_ratio=0.212, radial_immersion=0.5)
    grid = np.linspace(3000, 20000, 200)
    full = zoa_limits(f, h, cut, grid)
    cap = 2 * full.min()
    assert np.allclose(zoa_limits(f, h, cut, grid, cap_m=cap), np.minimum(full, cap), rtol=1e-12)


def test_batch_limits_uneven_speed_grid():
    """An uneven speed grid (searched, not indexed arithmetically) against zoa_lobes on the same grid, and the
    evenly spaced grid's limits at the speeds both grids share."""
    c = load_campaign(small_campaign() / "camp")
    f = np.arange(20.0, 4000.0, 2.0)
    h = ToolPointModel(c.family.tool(12, 60), c.subassembly("ER40", f), f).tool_point(truth_joint(12, 60))
    cut = CuttingConditions(teeth=2, tangential_coeff=6e8, radial_ratio=1 / 3, radial_immersion=1.0)
    even = np.linspace(3000, 21000, 301)
    uneven = np.unique(np.r_[even[::3], np.geomspace(3100, 20900, 97)])
    lim = zoa_limits(f, h, cut, uneven)
    ref = zoa_lobes(FRF(f, h), None, cut, rpm=uneven).depth_m
    assert np.max(np.abs(lim / ref - 1)) < 0.01
    shared = np.isin(uneven, even[::3])
    assert np.allclose(lim[shared], zoa_limits(f, h, cut, even)[::3], rtol=1e-12)


# ------------------------------------------------------------------ library file
def test_library_rows_and_bad_rows(tmp_path):
    tools, bad = read_library(_library(tmp_path / "l.csv", GOOD + BAD[:1] + [
        ",16,50,3,ER40,,,al7075,0.5,down,4000,20000", "F1,16,x,3,ER40,,,al7075,0.5,down,4000,20000",
        "G1,16,50,3,ER40,600,,,0.5,down,4000,20000", "H1,16,50,3,ER40,,,al7075,0.5,down,9000,2000"]))
    assert [t.id for t in tools] == ["A16", "B12"]
    assert tools[1].cutting.tangential_coeff == 600e6 and tools[1].cutting.milling == "up"
    assert [b.id for b in bad] == ["C1", "line 5", "F1", "G1", "H1"]
    assert all("\n" not in b.error and b.error.startswith(b.id) for b in bad)
    assert "overhang_mm" in bad[2].error and "rpm_min" in bad[4].error


@pytest.mark.parametrize("text, match", [("", "empty file"), (HEADER + "\n", "no tools"),
                                         ("id,diameter_mm\nA,1\n", "overhang_mm")])
def test_library_file_errors(tmp_path, text, match):
    p = tmp_path / "l.csv"
    p.write_text(text)
    with pytest.raises(InputError, match=match):
        read_library(p)
    with pytest.raises(InputError, match="cannot read"):
        read_library(tmp_path / "missing.csv")


# ------------------------------------------------------------------ end to end
def test_run_rows_files_and_bad_rows():
    out = small_run()
    rows = _rows(out)
    assert set(rows) == {"A16", "B12", "C1", "D1"}
    assert rows["C1"]["status"] == rows["D1"]["status"] == "failed"
    assert rows["C1"]["error"].startswith("C1: no cutting data")
    assert rows["D1"]["error"].startswith("D1: holder 'HSK63' is not in the campaign")
    for tid in ("A16", "B12"):
        r = rows[tid]
        assert r["status"] == "ok" and (out / "tools" / f"{tid}.npz").exists()
        p05, p50, depth = float(r["limit_p05_mm"]), float(r["limit_p50_mm"]), float(r["depth_mm"])
        assert 0 < depth <= 0.9 * p05 * (1 + 1e-5) and p05 <= p50  # cells have 6 digits
        assert 4000 < float(r["rpm"]) < 20000 and float(r["p_stable"]) >= 0.95
        for p in PARAMS:
            assert float(r[f"{p}_p05"]) < float(r[f"{p}_p50"]) < float(r[f"{p}_p95"])
        with np.load(out / "tools" / f"{tid}.npz") as z:
            lq, ps, depth_grid = z["limit_q_mm"], z["p_stable"], z["depth_mm"]
        assert np.all(lq[0] <= lq[1]) and np.all(lq[1] <= lq[2])
        # P(stable) falls with depth, and is 0 above the 95 % limit / 100 below the 5 % limit (± one sample)
        assert np.all(np.diff(ps.astype(int), axis=0) <= 0)
        k = np.searchsorted(depth_grid, lq[2] * 1.0001)
        cols = np.flatnonzero(k < depth_grid.size)
        assert np.all(ps[k[cols], cols] <= 5)


def test_resume_after_a_kill_recomputes_only_what_is_missing(tmp_path):
    root = small_campaign()
    out = tmp_path / "run"
    shutil.copytree(small_run(), out)
    (out / "tools" / "B12.npz").unlink()  # killed before B12's row was complete
    before = _rows(out)["A16"]
    lib = _library(tmp_path / "lib.csv", GOOD + BAD[:2])
    counts = run_library(lib, root / "camp", root / "results" / "models", out, workers=1, n_samples=40,
                         rpm_points=150, progress=False)
    assert (counts.skipped, counts.ok, counts.failed) == (1, 1, 2)
    rows = _rows(out)
    assert rows["A16"] == before and rows["B12"]["status"] == "ok"
    assert len(rows) == 4


def test_outside_range_widens_or_refuses(tmp_path):
    root = small_campaign()
    lib = _library(tmp_path / "lib.csv", [BAD[2].replace("5000", "95")])
    lines = []
    run_library(lib, root / "camp", root / "results" / "models", tmp_path / "w", workers=1, n_samples=20,
                rpm_points=60, progress=False, on_bad=lines.append)
    r = _rows(tmp_path / "w")["E1"]
    assert r["status"] == "ok" and float(r["outside_range"]) > 0 and "widened" in r["notes"]
    assert len(lines) == 1 and lines[0].startswith("warning: E1: ")
    run_library(lib, root / "camp", root / "results" / "models", tmp_path / "r", workers=1, n_samples=20,
                rpm_points=60, progress=False, outside="refuse")
    r = _rows(tmp_path / "r")["E1"]
    assert r["status"] == "failed" and "refused" in r["error"] and r["error"].startswith("E1: ")


def test_coverage_of_the_true_limit_on_held_out_tools():
    """The limit of the truth-law joint lies inside the 5–95 % band for most (tool, speed) pairs.

    Held-out tools of the models' split; the campaign's identifications are simulated (small_campaign), so
    this checks the propagation, not the identification (benchmarks/bench_library.py does the real thing).
    ANFIS σ (training residuals and identification intervals). The GP baseline's own σ gives 0.725 here
    (6 tools; it is over-confident on 40 training rows: RMS z of the truth 1.3–1.4) and 0.872 in the
    benchmark: docs/design/recommend.md.
    """
    from toolpoint.campaign.distribution import JointPredictor

    root = small_campaign()
    with open(root / "results" / "models" / "split.csv", newline="") as fh:
        test_ids = [r["id"] for r in csv.DictReader(fh) if r["set"] == "test"]
    with open(root / "results" / "identified.csv", newline="") as fh:
        geo = {r["id"]: (float(r["diameter_mm"]), float(r["overhang_mm"])) for r in csv.DictReader(fh)}
    c = load_campaign(root / "camp")
    f = np.arange(20.0, 4000.0, 2.0)
    sub = c.subassembly("ER40", f)
    pred = JointPredictor(root / "results" / "models")
    cut = CuttingConditions(teeth=3, tangential_coeff=7.96e8, radial_ratio=0.212, radial_immersion=0.5)
    grid = np.linspace(4000, 20000, 120)
    inside = []
    rng = np.random.default_rng(1)
    for tid in test_ids[:6]:
        D, L = geo[tid]
        dist = pred.predict(D, L)
        model = ToolPointModel(c.family.tool(D, L), sub, f)
        lims = zoa_limits(f, model.tool_point(dist.sample(0, 100, rng)), cut, grid, cap_m=0.02)
        lo, hi = np.quantile(lims, [QUANTILES[0], QUANTILES[-1]], axis=0)
        true = zoa_limits(f, model.tool_point(truth_joint(D, L)), cut, grid, cap_m=0.02)
        inside.append((true >= lo * (1 - 1e-9)) & (true <= hi * (1 + 1e-9)))
    coverage = float(np.mean(inside))
    print(f"coverage {coverage:.3f} over {len(inside)} tools × {grid.size} speeds")
    assert coverage >= 0.85


def test_gp_model_samples_the_gp_predictive_distribution(tmp_path):
    """--model gp: the joint's median and σ per tool are the saved GP's predictive mean and std of log10 p
    (not the ANFIS ones); a models folder without saved GPs is refused with a clear error."""
    import json

    from toolpoint.campaign.models import load_gp_models
    from toolpoint.campaign.distribution import JointPredictor

    root = small_campaign()
    models = root / "results" / "models"
    lib = _library(tmp_path / "lib.csv", GOOD[:1])
    run_library(lib, root / "camp", models, tmp_path / "g", workers=1, n_samples=20, rpm_points=60, progress=False,
                model="gp")
    assert _rows(tmp_path / "g")["A16"]["status"] == "ok"
    doc = json.loads((tmp_path / "g" / "tools" / "A16.json").read_text())
    gps = load_gp_models(models)
    anfis = JointPredictor(models).predict(16, 50)
    assert doc["model"] == "gp" and set(gps) == {"kt", "ct", "kr"}
    for k, p in enumerate(PARAMS):
        if p in gps:
            mean, sd = gps[p].predict([[16, 50]])
            assert doc["joint"][p]["sigma_log10"] == pytest.approx(sd[0], rel=1e-9)
            assert doc["joint"][p]["p50"] == pytest.approx(10 ** mean[0], rel=1e-9)
            assert abs(doc["joint"][p]["sigma_log10"] / anfis.sigma_log10[0, k] - 1) > 0.1
    bare = tmp_path / "bare" / "models"
    shutil.copytree(models, bare)
    shutil.copy(root / "results" / "identified.csv", bare.parent)
    manifest = json.loads((bare / "manifest.json").read_text())
    del manifest["gp"]
    (bare / "manifest.json").write_text(json.dumps(manifest))
    with pytest.raises(InputError, match="no GP baseline for kt saved"):
        JointPredictor(bare, "gp")
    with pytest.raises(InputError, match="must be one of anfis, gp"):
        JointPredictor(models, "gpr")


# ------------------------------------------------------------------ CLI
def test_cli_bad_library_is_one_line_exit_2(tmp_path, capsys):
    root = small_campaign()
    empty = tmp_path / "empty.csv"
    empty.write_text(HEADER + "\n")
    for lib in (empty, tmp_path / "missing.csv"):
        code = main(["library", str(lib), "--campaign", str(root / "camp"), "--models",
                     str(root / "results" / "models"), "--out", str(tmp_path / "o")])
        err = capsys.readouterr().err
        assert code == 2 and err.count("\n") == 1 and err.startswith("toolpoint library: error: ")
    assert not (tmp_path / "o").exists()


def test_cli_bad_rows_on_stderr_others_go_on(tmp_path, capsys):
    root = small_campaign()
    lib = _library(tmp_path / "lib.csv", GOOD[:1] + BAD[:2])
    code = main(["library", str(lib), "--campaign", str(root / "camp"), "--models", str(root / "results" / "models"),
                 "--out", str(tmp_path / "o"), "--workers", "1", "--samples", "10", "--rpm-points", "50"])
    cap = capsys.readouterr()
    assert code == 1 and "1 tools ok, 2 failed" in cap.out  # finished with failed items: exit 1, not 0
    assert "finished, 2 tools failed" in cap.err
    errs = [ln for ln in cap.err.splitlines() if ln.startswith("error: ")]
    assert [ln.split(":")[1].strip() for ln in errs] == ["C1", "D1"]
    assert math.isfinite(float(_rows(tmp_path / "o")["A16"]["depth_mm"]))


def test_resume_keeps_only_tools_computed_with_the_same_joint_model(tmp_path):
    import json

    from toolpoint.recommend.run import COLUMNS, _resume

    tools = tmp_path / "tools"
    tools.mkdir()
    table = tmp_path / "recommendations.csv"
    with open(table, "w", newline="") as fh:
        w = csv.DictWriter(fh, COLUMNS)
        w.writeheader()
        for tid, model in (("A", "anfis"), ("B", "gp"), ("C", None)):
            w.writerow({c: "" for c in COLUMNS} | {"id": tid, "status": "ok"})
            (tools / f"{tid}.npz").write_bytes(b"")
            (tools / f"{tid}.json").write_text(json.dumps({} if model is None else {"model": model}))
    assert _resume(table, tools, {"A", "B", "C"}, "gp") == {"B"}  # A and C (older runs: ANFIS) start again
    assert _resume(table, tools, {"A", "B", "C"}, "gp") == {"B"}  # and the rewritten table says so
    with open(table, newline="") as fh:
        assert [r["id"] for r in csv.DictReader(fh)] == ["B"]


def test_a_limit_at_the_depth_cap_is_shown_as_at_least_the_cap():
    """A limit equal to the internal depth cap was not computed: CSV '>=cap', never the cap as a number."""
    from types import SimpleNamespace

    from toolpoint.recommend.engine import _point
    from toolpoint.recommend.run import _ok_row

    cap = 9.68e-3
    rpm = np.array([1000.0, 2000.0])
    nominal = np.array([cap, 5e-3])
    lq = np.array([[cap, 4e-3], [cap, 5e-3], [cap, 6e-3]])
    samples = np.full((10, 2), cap)
    job = SimpleNamespace(rpm=rpm, margin=0.1)
    p = _point(job, nominal, lq, lq[0], samples, cap, 1.0, 0, "pocket", lq[0][0])
    assert p["capped"] == ["limit_nominal_mm", "limit_p05_mm", "limit_p50_mm", "limit_robust_p05_mm"]
    assert _point(job, nominal, lq, lq[0], samples, cap, 1.0, 1, "pocket", lq[0][1])["capped"] == []
    joint = {k: {"p05": 1.0, "p50": 1.0, "p95": 1.0} for k in ("kt", "ct", "kr", "cr")}
    summary = {"points": [p], "joint": joint, "min_limit_mm": {"p05": 4.0}, "cap_mm": 1e3 * cap}
    row = _ok_row(SimpleNamespace(id="EM28-80"), summary, 0.0, [])
    assert row["limit_p05_mm"] == row["limit_p50_mm"] == row["limit_nominal_mm"] == ">=9.68"
    assert row["rpm"] == "1000"


def test_a_depth_past_the_flutes_is_the_flute_length():
    """bench_calibration found 417 mm recommended for a D 8.7 / L 15.5 mm tool whose limit lies above the depth cap:
    no recommendation is deeper than the modelled flutes, and it says so."""
    from types import SimpleNamespace

    from toolpoint.recommend.engine import _point

    rpm = np.array([1000.0, 2000.0])
    lim = np.array([[0.4, 0.5], [0.45, 0.55], [0.5, 0.6]])  # m: far past any flute
    samples = np.full((10, 2), 0.5)
    job = SimpleNamespace(rpm=rpm, margin=0.1)
    p = _point(job, lim[1], lim, lim[0], samples, np.inf, 0.02, 1, "pocket", lim[0][1])
    assert p["depth_mm"] == pytest.approx(20.0) and p["flute_limited"] and p["p_stable"] == 1.0
    q = _point(job, lim[1], lim, lim[0], samples, np.inf, 1.0, 1, "pocket", lim[0][1])
    assert q["depth_mm"] == pytest.approx(450.0) and not q["flute_limited"]


def test_tool_ids_from_the_file_never_become_paths_and_csv_cells_never_formulas(tmp_path):
    """Issue: an id `../../x` wrote next to the output folder, an absolute id anywhere; `=cmd|…` went into the CSV
    as it was (a spreadsheet runs it); report followed ids out of `tools/`."""
    root = small_campaign()
    work = tmp_path / "a" / "b"
    work.mkdir(parents=True)
    evil = ["../../x", str(tmp_path / "abs"), "=cmd|' /C calc'!A0", "CON", "a" * 300]
    rows = [f'"{i}",16,50,3,ER40,,,al7075,0.5,down,4000,20000' if "," in i or "'" in i
            else f"{i},16,50,3,ER40,,,al7075,0.5,down,4000,20000" for i in evil]
    lib = _library(tmp_path / "lib.csv", rows)
    out = work / "out"
    before = {p for p in tmp_path.rglob("*")}
    run_library(lib, root / "camp", root / "results" / "models", out, workers=1, n_samples=20, rpm_points=60,
                progress=False)
    new = {p for p in tmp_path.rglob("*")} - before
    assert all(out in p.parents or p == out for p in new), sorted(map(str, new - {out}))
    written = sorted(p.name for p in (out / "tools").iterdir())
    assert all(len(n) < 80 and "/" not in n for n in written) and len(written) == 2 * len(evil)
    with open(out / "recommendations.csv", newline="", encoding="utf-8") as fh:
        cells = [c for r in csv.reader(fh) for c in r]
    assert not any(c.startswith(("=", "+", "@")) for c in cells)
    assert "'=cmd|' /C calc'!A0" in cells
    from toolpoint.recommend.report import write_report

    page = write_report(out).read_text(encoding="utf-8")
    assert page.count("files missing or unreadable") == 0  # every section read back from the names it wrote
    assert "=cmd|&#x27; /C calc&#x27;!A0" in page  # shown as the id it is (escaped), never as a formula cell


def test_report_does_not_follow_an_id_out_of_the_tools_folder(tmp_path):
    out = tmp_path / "run"
    shutil.copytree(small_run(), out)
    (tmp_path / "secret.json").write_text('{"id": "../../secret"}')
    with open(out / "recommendations.csv", "a", encoding="utf-8") as fh:
        fh.write("../../secret,ok" + "," * 33 + "\n")
    from toolpoint.recommend.report import write_report

    with pytest.warns(UserWarning, match="unreadable or incomplete"):
        page = write_report(out).read_text(encoding="utf-8")
    assert "files missing or unreadable" in page  # it looked only inside tools/, under the safe name


def test_a_second_library_run_into_the_same_folder_is_refused_and_stale_temporaries_go(tmp_path):
    from toolpoint.campaign.run import folder_lock
    from toolpoint.errors import InputError

    root = small_campaign()
    lib = _library(tmp_path / "lib.csv", GOOD[:1])
    out = tmp_path / "o"
    (out / "tools").mkdir(parents=True)
    stale = out / "tools" / ".A16.npz.x1y2.tmp.npz"  # what a SIGTERM during an atomic write leaves
    stale.write_bytes(b"half")
    args = (lib, root / "camp", root / "results" / "models", out)
    with folder_lock(out, "library run"):  # a run in progress
        with pytest.raises(InputError, match="another library run"):
            run_library(*args, workers=1, n_samples=10, rpm_points=30, progress=False)
    assert stale.exists()  # the refused run touched nothing
    run_library(*args, workers=1, n_samples=10, rpm_points=30, progress=False)
    assert not stale.exists()
    with open(out / "recommendations.csv") as fh:
        assert sum(1 for line in fh if line.startswith("A16,")) == 1
