"""One self-contained HTML page of a ``toolpoint library`` run (no network: figures are base64 PNG).

An overview table of all tools (click a header to sort, type in the box to
filter), then per tool: the tool-point FRF with its 5–95 % band, the lobe
diagram over the probability-of-stability map with the 5/50/95 % limits and
the recommended points, and the joint parameters with their 90 % intervals.
"""

from __future__ import annotations

import base64
import csv
import html
import io
import json
from pathlib import Path

import numpy as np

from ..errors import InputError
from ..identification.params import PARAMS, UNITS
from ..io.atomic import atomic_open
from .run import FILE_NAME

__all__ = ["write_report", "SHOWN"]

#: Columns of recommendations.csv shown in the overview table, with their headings.
SHOWN = {"id": "tool", "status": "status", "diameter_mm": "D mm", "overhang_mm": "L mm", "teeth": "N",
         "material": "material", "rpm": "rpm", "depth_mm": "depth mm (recommended)",
         "limit_p05_mm": "5 % limit mm", "limit_p50_mm": "50 % limit mm", "min_limit_p05_mm": "stable everywhere mm",
         "kind": "point", "outside_range": "outside range", "error": "error / notes"}

_SCRIPT = """
function sortBy(th){const t=th.closest('table'),i=[...th.parentNode.children].indexOf(th),
 b=t.tBodies[0],rows=[...b.rows],asc=th.dataset.dir!=='asc';
 [...th.parentNode.children].forEach(h=>delete h.dataset.dir);th.dataset.dir=asc?'asc':'desc';
 rows.sort((r,s)=>{const x=r.cells[i].textContent.trim(),y=s.cells[i].textContent.trim(),
  a=parseFloat(x),c=parseFloat(y);
  const v=(!isNaN(a)&&!isNaN(c))?a-c:(isNaN(a)&&!isNaN(c))?1:(!isNaN(a)&&isNaN(c))?-1:x.localeCompare(y);
  return asc?v:-v;});rows.forEach(r=>b.appendChild(r));}
function filterRows(q){q=q.toLowerCase();for(const r of document.querySelectorAll('#overview tbody tr'))
 r.style.display=r.textContent.toLowerCase().includes(q)?'':'none';}
"""
_STYLE = """
body{font-family:sans-serif;margin:1.5em;max-width:1400px}table{border-collapse:collapse;font-size:13px}
th,td{border:1px solid #ccc;padding:3px 6px;text-align:right}th{cursor:pointer;background:#eef}
th[data-dir=asc]::after{content:' \\25B2'}th[data-dir=desc]::after{content:' \\25BC'}
td:first-child,td.t{text-align:left}tr.failed{background:#fdd}img{max-width:32%;margin:0 0.5%}
section{border-top:2px solid #99c;margin-top:1.5em}
"""


def _png(fig) -> str:
    import matplotlib.pyplot as plt

    buf = io.BytesIO()
    fig.savefig(buf, format="png", dpi=80)
    plt.close(fig)
    return "data:image/png;base64," + base64.b64encode(buf.getvalue()).decode()


def _figures(a, s) -> list[str]:
    from matplotlib.figure import Figure

    figs = []
    fig = Figure(figsize=(5, 3.4))
    ax = fig.add_subplot()
    f = a["freq_hz"]
    ax.fill_between(f, a["frf_abs_q"][0], a["frf_abs_q"][2], color="C0", alpha=0.3, label="5–95 %")
    ax.semilogy(f, a["frf_abs_q"][1], "C0", lw=1, label="median")
    ax.set(xlabel="frequency, Hz", ylabel="|h|, m/N", title="tool-point FRF")
    ax.legend(fontsize=8)
    fig.tight_layout()
    figs.append(_png(fig))

    fig = Figure(figsize=(5, 3.4))
    ax = fig.add_subplot()
    rpm, depth = a["rpm"], a["depth_mm"]
    mesh = ax.pcolormesh(rpm, depth, a["p_stable"].astype(float), cmap="RdYlGn", vmin=0, vmax=100, shading="auto")
    fig.colorbar(mesh, ax=ax, label="P(stable), %")
    for k, (q, style) in enumerate(zip(("5 %", "50 %", "95 %"), ("k-", "k--", "k:"))):
        ax.plot(rpm, np.minimum(a["limit_q_mm"][k], depth[-1]), style, lw=1, label=f"{q} limit")
    for p in s["points"]:
        ax.plot(p["rpm"], p["depth_mm"], "b*", ms=10)
    ax.set(xlabel="spindle speed, rpm", ylabel="axial depth, mm", title="stability (stars: recommended)",
           ylim=(0, depth[-1]))
    ax.legend(fontsize=7, loc="upper left")
    fig.tight_layout()
    figs.append(_png(fig))

    fig = Figure(figsize=(5, 3.4))
    ax = fig.add_subplot()
    for k, p in enumerate(PARAMS):
        j = s["joint"][p]
        rel = np.array([j["p05"], j["p50"], j["p95"]]) / j["p50"]
        ax.errorbar([k], [1.0], yerr=[[1 - rel[0]], [rel[2] - 1]], fmt="o", capsize=6)
    ax.set_yscale("log")
    ax.set_xticks(range(len(PARAMS)),
                  [f"{p}\n{s['joint'][p]['p50']:.3g}\n{UNITS[p]}" for p in PARAMS], fontsize=8)
    ax.set(ylabel="value / median", title="joint: median and 90 % interval")
    fig.tight_layout()
    figs.append(_png(fig))
    return figs


def write_report(out_dir, path=None) -> Path:
    """Write the HTML report of a library run.

    Parameters
    ----------
    out_dir : path-like
        The run's folder (``recommendations.csv``, ``tools/``).
    path : path-like, optional
        The HTML file (default ``out_dir/report.html``).

    Returns
    -------
    Path
        The file written.

    Raises
    ------
    InputError
        No ``recommendations.csv`` in ``out_dir``, or one without rows.
    """
    d = Path(out_dir)
    table = d / FILE_NAME
    try:
        with open(table, newline="", encoding="utf-8") as fh:
            rows = list(csv.DictReader(fh))
    except (OSError, UnicodeDecodeError, csv.Error) as e:
        raise InputError(f"cannot read ({getattr(e, 'strerror', None) or e}); run 'toolpoint library' first",
                         file=table) from None
    if not rows:
        raise InputError("no tools in the results", file=table)
    rows.sort(key=lambda r: r.get("id", ""))
    head = "".join(f'<th onclick="sortBy(this)">{html.escape(h)}</th>' for h in SHOWN.values())
    body, sections = [], []
    for r in rows:
        cells = []
        for k in SHOWN:
            v = r.get(k, "") or ""
            if k == "error" and not v:
                v = r.get("notes", "") or ""
            if k == "id" and r.get("status") == "ok":
                cells.append(f'<td><a href="#tool-{html.escape(v)}">{html.escape(v)}</a></td>')
            else:
                try:
                    v = f"{float(v):.4g}" if k not in ("id", "teeth") else v
                except ValueError:
                    pass
                cells.append(f'<td class="t">{html.escape(v)}</td>' if k in ("error", "material", "kind", "status")
                             else f"<td>{html.escape(v)}</td>")
        body.append(f'<tr class="{html.escape(r.get("status", ""))}">{"".join(cells)}</tr>')
        if r.get("status") != "ok":
            continue
        tid = r["id"]
        try:
            with np.load(d / "tools" / f"{tid}.npz") as z:
                a = {k: z[k] for k in z.files}
            s = json.loads((d / "tools" / f"{tid}.json").read_text(encoding="utf-8"))
        except (OSError, ValueError, KeyError) as e:
            sections.append(f'<section id="tool-{html.escape(tid)}"><h2>{html.escape(tid)}</h2>'
                            f"<p>files missing or unreadable: {html.escape(str(e))}</p></section>")
            continue
        pts = "".join(f"<tr><td class=t>{p['kind']}</td><td>{p['rpm']:.0f}</td><td>{p['depth_mm']:.3g}</td>"
                      f"<td>{p['limit_p05_mm']:.3g}</td><td>{p['limit_p50_mm']:.3g}</td><td>{p['p_stable']:.2f}</td>"
                      "</tr>" for p in s["points"])
        imgs = "".join(f'<img alt="figure" src="{src}">' for src in _figures(a, s))
        notes = "".join(f"<li>{html.escape(n)}</li>" for n in s.get("notes", []))
        cut = s.get("cutting", {})
        sections.append(
            f'<section id="tool-{html.escape(tid)}"><h2>{html.escape(tid)}</h2>'
            f"<p>D {s.get('diameter_mm', '')} mm, L {s.get('overhang_mm', '')} mm, holder "
            f"{html.escape(str(s.get('holder', '')))}; {cut.get('teeth', '')} teeth, K<sub>t</sub> "
            f"{cut.get('tangential_coeff', 0) / 1e6:.4g} N/mm², K<sub>r</sub> {cut.get('radial_ratio', 0):.3g} "
            f"({html.escape(str(cut.get('source', '')))}), a<sub>e</sub>/D {cut.get('radial_immersion', '')}, "
            f"{cut.get('milling', '')} milling; {s['n_samples']} joint samples</p>"
            f"<ul>{notes}</ul><table><thead><tr><th>point</th><th>rpm</th><th>depth mm (recommended)</th>"
            f"<th>5 % limit mm</th><th>50 % limit mm</th><th>P(stable)</th></tr></thead><tbody>{pts}</tbody></table>"
            f"<p>{imgs}</p></section>")
    page = (f"<!DOCTYPE html><html lang=en><head><meta charset=utf-8><title>toolpoint library report</title>"
            f"<style>{_STYLE}</style><script>{_SCRIPT}</script></head><body>"
            f"<h1>Recommended spindle speeds and depths</h1>"
            f"<p>{len(rows)} tools from <code>{html.escape(str(table))}</code>. Recommended depth: the 5 % limit "
            "(95 % of the sampled joints stable), minimum over the spindle-speed tolerance, less the margin. "
            "Click a header to sort; type to filter.</p>"
            f'<input id="filter" placeholder="filter tools…" oninput="filterRows(this.value)">'
            f'<table id="overview"><thead><tr>{head}</tr></thead><tbody>{"".join(body)}</tbody></table>'
            f'{"".join(sections)}</body></html>')
    out = Path(path) if path is not None else d / "report.html"
    with atomic_open(out, "w", encoding="utf-8") as fh:
        fh.write(page)
    return out
