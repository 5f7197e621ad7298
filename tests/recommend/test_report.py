"""`toolpoint report`: one self-contained HTML page; rendered and sorted in a real headless Chromium."""

import re
import shutil
import subprocess

import pytest

from test_library import small_run
from toolpoint.cli.main import main

CHROMIUM = next((shutil.which(n) for n in ("chromium", "chromium-browser", "google-chrome") if shutil.which(n)), None)


@pytest.fixture(scope="module")
def report(tmp_path_factory):
    out = tmp_path_factory.mktemp("report") / "report.html"
    assert main(["report", str(small_run()), "--out", str(out)]) == 0
    return out


def test_self_contained(report):
    text = report.read_text()
    assert not re.search(r"""(src|href)\s*=\s*["']?(https?:|//)""", text)  # nothing fetched from the network
    assert "<script src" not in text and "<img" not in text
    # per ok tool: its figure data (drawn by the page's own script) with the probability map as a PNG
    assert text.count('<script type="application/json"') == 2
    assert text.count('"map":"data:image/png;base64,') == 2
    assert 'id="overview"' in text and 'id="filter"' in text
    for tid in ("A16", "B12", "C1", "D1"):
        assert f">{tid}<" in text
    assert "C1: no cutting data" in text


def test_report_errors(tmp_path, capsys):
    assert main(["report", str(tmp_path)]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "recommendations.csv" in err


def _dom(page, tmp_path, script: str) -> str:
    """The DOM after ``script`` ran on load, from headless Chromium."""
    probe = tmp_path / "probe.html"
    probe.write_text(page.read_text().replace("</body>", f"<script>{script}</script></body>"))
    run = subprocess.run([CHROMIUM, "--headless", "--no-sandbox", "--disable-gpu", "--virtual-time-budget=3000",
                          "--dump-dom", probe.as_uri()], capture_output=True, text=True, timeout=60)
    assert run.returncode == 0, run.stderr[-500:]
    return run.stdout


@pytest.mark.skipif(CHROMIUM is None, reason="Chromium is not installed (apt-get install chromium); CI installs it")
def test_renders_and_sorts_in_chromium(report, tmp_path):
    # click "D mm" (ascending), again (descending), then filter; D is 16 mm for A16, C1, D1 and 12 mm for B12
    script = ("const th=[...document.querySelectorAll('#overview th')].find(h=>h.textContent==='D mm');"
              "th.click();document.body.dataset.asc=[...document.querySelectorAll('#overview tbody tr')]"
              ".map(r=>r.cells[0].textContent).join(' ');th.click();"
              "document.body.dataset.desc=[...document.querySelectorAll('#overview tbody tr')]"
              ".map(r=>r.cells[0].textContent).join(' ');filterRows('B12');"
              "document.body.dataset.shown=[...document.querySelectorAll('#overview tbody tr')]"
              ".filter(r=>r.style.display!=='none').map(r=>r.cells[0].textContent).join(' ');")
    dom = _dom(report, tmp_path, script)
    assert "<h1>Recommended spindle speeds and depths</h1>" in dom
    asc = re.search(r'data-asc="([^"]*)"', dom).group(1).split()
    assert asc[0] == "B12"  # D 12 mm before the three 16 mm tools
    desc = re.search(r'data-desc="([^"]*)"', dom).group(1).split()
    assert desc[-1] == "B12" and sorted(desc) == sorted(asc) == ["A16", "B12", "C1", "D1"]  # 2nd click: descending
    assert re.search(r'data-shown="([^"]*)"', dom).group(1) == "B12"


@pytest.mark.skipif(CHROMIUM is None, reason="Chromium is not installed (apt-get install chromium); CI installs it")
def test_figures_drawn_when_a_tool_is_opened(report, tmp_path):
    """The first ok tool is open on load and drawn; the other is drawn only when opened (its link in the
    overview table opens its section)."""
    script = ("window.addEventListener('load',()=>{document.body.dataset.onload=document.querySelectorAll("
              "'.figs svg').length;location.hash='#tool-B12';openHash();});")
    dom = _dom(report, tmp_path, script)
    assert re.search(r'data-onload="(\d+)"', dom).group(1) == "2"  # the first tool's FRF and lobe figures only
    figs = re.findall(r'<div class="figs">(.*?)</div>', dom, re.S)
    assert len(figs) == 2 and all(f.count("<svg") == 2 for f in figs)  # B12 opened through its link
    for f in figs:
        assert f.count("<polygon") == 1  # the FRF band
        assert f.count("<polyline") == 4  # FRF median; 5, 50, 95 % limits
        assert f.count('<image href="data:image/png;base64,') == 1  # probability map
        assert "frequency, Hz" in f and "spindle speed, rpm" in f


@pytest.mark.skipif(CHROMIUM is None, reason="Chromium is not installed (apt-get install chromium); CI installs it")
def test_screenshot(report, tmp_path):
    shot = tmp_path / "shot.png"
    run = subprocess.run([CHROMIUM, "--headless", "--no-sandbox", "--disable-gpu", "--window-size=1200,1400",
                          f"--screenshot={shot}", report.as_uri()], capture_output=True, text=True, timeout=60)
    assert run.returncode == 0, run.stderr[-300:]
    from matplotlib.image import imread

    img = imread(shot)[..., :3]
    # a rendered page, not a blank one: dark text on white and the colour figures (cividis yellow and blue)
    assert img.std() > 0.1 and (img.mean(axis=2) < 0.3).mean() > 0.01
    yellow = (img[..., 0] > 0.8) & (img[..., 1] > 0.75) & (img[..., 2] < 0.4)  # cividis at P = 100 %
    blue = (img[..., 2] - img[..., 0] > 0.15) & (img.mean(axis=2) < 0.6)  # cividis towards P = 0
    assert yellow.sum() > 20 and blue.sum() > 500  # the open tool's probability map is drawn
