"""One self-contained HTML page of a ``toolpoint library`` run (no network, no external script).

An overview table of all tools (click a header to sort, type in the box to
filter), then per tool a collapsed section: the recommended points, the joint
parameters with their 90 % intervals, and — drawn as SVG by the page's own
script when the section is opened — the tool-point FRF with its 5–95 % band
and the lobe diagram over the probability-of-stability map with the 5/50/95 %
limits and the recommended points.

Size: each tool carries only what its figures need, decimated — the FRF band
as a max/min envelope on :data:`FRF_BINS` frequency bins (peaks kept), the
limits as the minimum over bins of at most :data:`RPM_BINS` speeds (never
above the computed limit), the probability map as a small palette PNG — about
13 kB a tool instead of ~85 kB of matplotlib PNGs, and no plotting in Python
(measured figures: ``docs/design/recommend.md``).
"""

from __future__ import annotations

import base64
import html
import io
import json
import warnings
import zipfile
from pathlib import Path

import numpy as np

from ..errors import InputError
from .library import tool_file_stem
from ..identification.params import PARAMS, UNITS
from ..io.atomic import atomic_open
from ..io.table import check_regular_file, csv_unsafe, read_table
from .run import FILE_NAME

__all__ = ["write_report", "SHOWN", "FRF_BINS", "RPM_BINS", "MAP_SHAPE"]

#: Columns of recommendations.csv shown in the overview table, with their headings.
SHOWN = {"id": "tool", "status": "status", "diameter_mm": "D mm", "overhang_mm": "L mm", "teeth": "N",
         "material": "material", "rpm": "rpm", "depth_mm": "depth mm (recommended)",
         "p_stable": "P(stable)", "limit_p05_mm": "5 % limit mm", "limit_p50_mm": "50 % limit mm",
         "min_limit_p05_mm": "stable everywhere mm", "kind": "point", "dominant_uncertainty": "dominant uncertainty",
         "outside_range": "outside learned (D, L) range", "error": "error / notes"}

#: Frequency bins of the FRF band in the report (max of the 95 % and median, min of the 5 % curve per bin).
FRF_BINS = 240
#: At most this many speeds per tool in the report's lobe diagram (minimum of each limit over a bin).
RPM_BINS = 250
#: Probability-of-stability map in the report: at most this many (depths, speeds), in 5 % steps.
MAP_SHAPE = (50, 250)

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
function ticks(lo,hi,n){const raw=(hi-lo)/n,p=Math.pow(10,Math.floor(Math.log10(raw))),
 st=[1,2,5,10].map(m=>m*p).find(v=>v>=raw),out=[];
 for(let v=Math.ceil(lo/st)*st;v<=hi+st*1e-9;v+=st)out.push(+v.toPrecision(12));return out;}
function esc(s){return String(s).replace(/&/g,'&amp;').replace(/</g,'&lt;');}
// one SVG figure: o = {x:[lo,hi], y:[lo,hi], xlabel, ylabel, title, logy, image, lines, band, stars}
function plot(o){const W=440,H=300,L=62,R=10,T=24,B=42,pw=W-L-R,ph=H-T-B,n=plot.n=(plot.n||0)+1;
 const X=v=>L+(v-o.x[0])/(o.x[1]-o.x[0])*pw,Y=v=>T+ph-(v-o.y[0])/(o.y[1]-o.y[0])*ph;
 const pts=(xs,ys)=>xs.map((x,i)=>X(x).toFixed(1)+','+Y(ys[i]).toFixed(1)).join(' ');
 const box=`x="${L}" y="${T}" width="${pw}" height="${ph}"`;
 const dash=l=>l.dash?` stroke-dasharray="${l.dash}"`:'';
 let g=`<svg xmlns="http://www.w3.org/2000/svg" width="${W}" height="${H}" viewBox="0 0 ${W} ${H}">`+
  `<defs><clipPath id="c${n}"><rect ${box}/></clipPath></defs>`;
 if(o.image)g+=`<image href="${o.image}" ${box} preserveAspectRatio="none"/>`;
 g+=`<g clip-path="url(#c${n})" fill="none">`;
 if(o.band)g+=`<polygon points="${pts(o.band.x,o.band.lo)} ${pts(o.band.x.slice().reverse(),
  o.band.hi.slice().reverse())}" fill="#1f77b4" fill-opacity="0.3" stroke="none"/>`;
 for(const l of o.lines||[])
  g+=`<polyline points="${pts(l.x,l.y)}" stroke="${l.color||'#000'}" stroke-width="1.2"${dash(l)}/>`;
 for(const s of o.stars||[])g+=`<text x="${X(s[0])}" y="${Y(s[1])+6}" font-size="18" fill="#00c" `+
  `stroke="#fff" stroke-width="0.5" text-anchor="middle">&#9733;</text>`;
 g+=`</g><rect ${box} fill="none" stroke="#333"/>`;
 for(const v of ticks(o.x[0],o.x[1],6))
  g+=`<text x="${X(v)}" y="${T+ph+14}" font-size="11" text-anchor="middle">${v}</text>`;
 const yt=o.logy?ticks(Math.ceil(o.y[0]),Math.floor(o.y[1]),5).filter(Number.isInteger):ticks(o.y[0],o.y[1],5);
 for(const v of yt)g+=`<text x="${L-4}" y="${Y(v)+4}" font-size="11" text-anchor="end">${o.logy?'1e'+v:v}</text>`+
  `<line x1="${L}" x2="${L+4}" y1="${Y(v)}" y2="${Y(v)}" stroke="#333"/>`;
 g+=`<text x="${L+pw/2}" y="${H-6}" font-size="12" text-anchor="middle">${esc(o.xlabel)}</text>`+
  `<text transform="translate(14 ${T+ph/2}) rotate(-90)" font-size="12" text-anchor="middle">${esc(o.ylabel)}</text>`+
  `<text x="${L+pw/2}" y="16" font-size="13" text-anchor="middle">${esc(o.title)}</text>`;
 const leg=(o.lines||[]).filter(l=>l.label);
 if(leg.length)
  g+=`<rect x="${L+4}" y="${T+3}" width="96" height="${14*leg.length+4}" fill="#fff" fill-opacity="0.85"/>`;
 let ly=T+14;for(const l of leg){
  g+=`<line x1="${L+8}" x2="${L+30}" y1="${ly-4}" y2="${ly-4}" stroke="${l.color||'#000'}"${dash(l)}/>`+
  `<text x="${L+34}" y="${ly}" font-size="11">${esc(l.label)}</text>`;ly+=14;}
 return g+'</svg>';}
// (the toggle event of an open section can come while the parser has not reached its data yet, or has
// reached only part of it — a slow machine, a large report: JSON.parse failed and the section stayed blank;
// CI, 2026-12-02): nothing is drawn while the document is still being parsed, and the DOMContentLoaded
// handler draws the open sections)
function draw(d){const src=document.getElementById(d.dataset.src),figs=d.querySelector('.figs');
 if(document.readyState==='loading'||!d.open||d.dataset.drawn||!src||!figs)return;
 const a=JSON.parse(src.textContent);d.dataset.drawn=1;
 const h=a.h.map(r=>r.map(v=>v/100)),lo=Math.min(...h[0]),hi=Math.max(...h[2]);
 const limits=[['5 % limit',''],['50 % limit','6 3'],['95 % limit','2 2']];
 figs.innerHTML=plot({x:[a.f[0],a.f[a.f.length-1]],y:[lo-0.1,hi+0.1],logy:true,xlabel:'frequency, Hz',
  ylabel:'|h|, m/N',title:'tool-point FRF: median and 5–95 % band',band:{x:a.f,lo:h[0],hi:h[2]},
  lines:[{x:a.f,y:h[1],color:'#1f77b4',label:'median'}]})+
 plot({x:[a.rpm[0],a.rpm[a.rpm.length-1]],y:[0,a.top],xlabel:'spindle speed, rpm',ylabel:'axial depth, mm',
  title:'P(stable) (yellow 100 %, dark blue 0 %), limits; ★ recommended',image:a.map,stars:a.pts,
  lines:limits.map((l,k)=>({x:a.rpm,y:a.lim[k],label:l[0],dash:l[1]}))});}
function openHash(){const t=document.getElementById(decodeURIComponent(location.hash.slice(1)));
 if(t&&t.tagName==='DETAILS'){t.open=true;draw(t);}}
window.addEventListener('hashchange',openHash);
window.addEventListener('DOMContentLoaded',()=>{document.querySelectorAll('details[open]').forEach(draw);openHash();});
"""
_STYLE = """
body{font-family:sans-serif;margin:1.5em;max-width:1400px}table{border-collapse:collapse;font-size:13px}
th,td{border:1px solid #ccc;padding:3px 6px;text-align:right}th{cursor:pointer;background:#eef}
th[data-dir=asc]::after{content:' \\25B2'}th[data-dir=desc]::after{content:' \\25BC'}
td:first-child,td.t{text-align:left}tr.failed{background:#fdd}
details{border-top:2px solid #99c;margin-top:0.8em;padding-top:0.3em}summary{cursor:pointer;font-size:1.1em}
.figs svg{margin:0.5em 1em 0 0;font-family:sans-serif}
"""


def _sig(v, digits=4):
    """Floats rounded to ``digits`` significant digits (short JSON)."""
    return [float(f"{x:.{digits}g}") for x in np.asarray(v, float).ravel()]


def _bins(n: int, most: int) -> np.ndarray:
    """Start indices of at most ``most`` contiguous bins covering range(n)."""
    return np.unique(np.linspace(0, n, min(n, most) + 1).astype(int))[:-1]


def _map_png(p_stable: np.ndarray) -> str:
    """The probability map (depths × speeds, %) as a small PNG data URL (cividis: perceptually uniform and
    colour-blind safe; 5 % steps, lowest depth at the bottom); block means over at most :data:`MAP_SHAPE`."""
    from matplotlib import colormaps
    from PIL import Image

    p = p_stable.astype(float)
    for axis, most in enumerate(MAP_SHAPE):
        p = np.add.reduceat(p, _bins(p.shape[axis], most), axis=axis) / np.diff(
            np.r_[_bins(p.shape[axis], most), p.shape[axis]]).reshape((-1, 1) if axis == 0 else (1, -1))
    level = np.round(p / 5).astype(np.uint8)[::-1]  # 0..20, top row = deepest
    palette = (255 * colormaps["cividis"](np.arange(21) / 20)[:, :3]).astype(np.uint8)
    img = Image.fromarray(level, "P")
    img.putpalette(palette.ravel().tolist())
    buf = io.BytesIO()
    img.save(buf, format="png", optimize=True)
    return "data:image/png;base64," + base64.b64encode(buf.getvalue()).decode()


def _plot_data(a, s) -> dict:
    """What the page's script needs to draw one tool's two figures (decimated; module docstring)."""
    f, q = a["freq_hz"], np.log10(a["frf_abs_q"])  # (F,), (3, F)
    b = _bins(f.size, FRF_BINS)
    env = [np.minimum.reduceat(q[0], b), np.maximum.reduceat(q[1], b), np.maximum.reduceat(q[2], b)]
    rpm, depth = a["rpm"], a["depth_mm"]
    top = float(depth[-1])
    r = _bins(rpm.size, RPM_BINS)
    lim = [np.minimum.reduceat(np.minimum(a["limit_q_mm"][k], top), r) for k in range(3)]
    centre = np.add.reduceat(f, b) / np.diff(np.r_[b, f.size])
    return {"f": np.round(centre).astype(int).tolist(),  # Hz
            "h": [np.round(100 * e).astype(int).tolist() for e in env],  # 100 log10 |h|, |h| in m/N
            "rpm": np.round(rpm[r]).astype(int).tolist(), "lim": [_sig(v, 3) for v in lim], "top": _sig([top])[0],
            "map": _map_png(a["p_stable"]), "pts": [_sig([p["rpm"], p["depth_mm"]]) for p in s["points"]]}


def _joint_table(s) -> str:
    rows = "".join(f"<tr><td class=t>{p}</td><td>{s['joint'][p]['p05']:.4g}</td><td>{s['joint'][p]['p50']:.4g}</td>"
                   f"<td>{s['joint'][p]['p95']:.4g}</td><td>{s['joint'][p]['sigma_log10']:.3g}</td>"
                   f"<td class=t>{html.escape(UNITS[p])}</td></tr>" for p in PARAMS)
    return ("<table><thead><tr><th>joint</th><th>5 %</th><th>50 %</th><th>95 %</th><th>σ decades</th><th>unit</th>"
            f"</tr></thead><tbody>{rows}</tbody></table>")


#: What a damaged tool file raises while its section is built (missing or cut file, bad JSON, missing keys,
#: wrong types or shapes, numbers that do not format).
_DAMAGED = (OSError, ValueError, KeyError, IndexError, TypeError, AttributeError, OverflowError,
            zipfile.BadZipFile)


def _section(d: Path, tid: str, n_data: int) -> str:
    """One tool's collapsible section (its data read from ``d/tools/<stem>.npz`` and ``.json``: only the names
    ``library`` writes, :func:`~toolpoint.recommend.library.tool_file_stem`, inside ``d/tools``)."""
    stem = d / "tools" / tool_file_stem(tid)
    for ext in (".npz", ".json"):  # a FIFO in place of a tool file would block the page for ever
        check_regular_file(f"{stem}{ext}", what="tool file")
    with np.load(f"{stem}.npz", allow_pickle=False) as z:
        a = {k: z[k] for k in z.files}
    s = json.loads(Path(f"{stem}.json").read_text(encoding="utf-8"))
    if s.get("id") != tid:
        raise ValueError(f"the files hold tool {s.get('id')!r}, not {tid!r}")
    data = json.dumps(_plot_data(a, s), separators=(",", ":"), allow_nan=False)
    def lim(p, k):  # a limit at the depth cap is no computed limit: it lies above the cap
        return f"≥ {s['cap_mm']:.3g}" if k in p.get("capped", ()) else f"{p[k]:.3g}"

    pts = "".join(f"<tr><td class=t>{html.escape(str(p['kind']))}</td><td>{p['rpm']:.0f}</td><td>{p['depth_mm']:.3g}"
                  f"</td><td>{lim(p, 'limit_p05_mm')}</td><td>{lim(p, 'limit_p50_mm')}</td><td>{p['p_stable']:.2f}</td>"
                  "</tr>" for p in s["points"])
    best = s["points"][0]
    notes = "".join(f"<li>{html.escape(str(n))}</li>" for n in s.get("notes", []))
    src = s.get("sources") or {}
    if src:  # which uncertain input makes the band at the recommended point (share of the variance of ln a)
        parts = ", ".join(f"{html.escape(k)} {100 * v:.0f} %" for k, v in sorted(src.items(), key=lambda kv: -kv[1]))
        notes += (f"<li>uncertainty at the recommended point: <b>{html.escape(str(s.get('dominant_source')))}</b> "
                  f"dominates ({parts} of the variance of ln a<sub>lim</sub>)</li>")
    cut = s.get("cutting", {})
    return (f'<details id="tool-{html.escape(tid)}" data-src="d{n_data}" ontoggle="draw(this)"'
            f'{" open" if n_data == 1 else ""}><summary><b>{html.escape(tid)}</b>: {best["rpm"]:.0f} rpm, '
            f'{best["depth_mm"]:.3g} mm ({html.escape(str(best["kind"]))})</summary>'
            f"<p>D {s.get('diameter_mm', '')} mm, L {s.get('overhang_mm', '')} mm, holder "
            f"{html.escape(str(s.get('holder', '')))}; {cut.get('teeth', '')} teeth, K<sub>t</sub> "
            f"{cut.get('tangential_coeff', 0) / 1e6:.4g} N/mm², K<sub>r</sub> {cut.get('radial_ratio', 0):.3g} "
            f"({html.escape(str(cut.get('source', '')))}), a<sub>e</sub>/D {cut.get('radial_immersion', '')}, "
            f"{cut.get('milling', '')} milling; {s['n_samples']} samples of the joint, K<sub>t</sub>, K<sub>r</sub>"
            f"{' and the subassembly' if s.get('subassembly_replicates') else ''}; P(stable) holds over the speed "
            f"tolerance ±{100 * s.get('rpm_tolerance', 0):.3g} %</p>"
            f"<ul>{notes}</ul><table><thead><tr><th>point</th><th>rpm</th><th>depth mm (recommended)</th>"
            f"<th>5 % limit mm</th><th>50 % limit mm</th><th>P(stable)</th></tr></thead><tbody>{pts}</tbody></table>"
            f'{_joint_table(s)}<div class="figs"></div>'
            f'<script type="application/json" id="d{n_data}">{data}</script></details>')


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
        No ``recommendations.csv`` in ``out_dir``, one without rows or without its ``id``/``status``
        columns. (A tool whose own files are damaged gets a section saying so, and a warning.)
    """
    d = Path(out_dir)
    table = d / FILE_NAME
    if not table.is_file():
        raise InputError("not found: run 'toolpoint library' first", file=table)
    header, rows = read_table(table, what="the library's results")
    rows = [(n, {k: csv_unsafe(v) if isinstance(v, str) else v for k, v in r.items()}) for n, r in rows]
    for name in ("id", "status"):
        if name not in header:
            raise InputError(f"no column {name!r}: not a 'toolpoint library' results table", file=table, field=name)
    rows = [r for _, r in rows]
    if not rows:
        raise InputError("no tools in the results", file=table)
    rows.sort(key=lambda r: r.get("id") or "")
    head = "".join(f'<th onclick="sortBy(this)">{html.escape(h)}</th>' for h in SHOWN.values())
    body, sections, n_data = [], [], 0
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
                    v = v if k in ("id", "teeth") else (f"{float(v):.0f}" if k == "rpm" else f"{float(v):.4g}")
                except ValueError:
                    v = v.replace(">=", "≥ ")
                cells.append(f'<td class="t">{html.escape(v)}</td>' if k in ("error", "material", "kind", "status",
                                                                                 "dominant_uncertainty")
                             else f"<td>{html.escape(v)}</td>")
        body.append(f'<tr class="{html.escape(r.get("status", ""))}">{"".join(cells)}</tr>')
        if r.get("status") != "ok":
            continue
        tid = r.get("id") or ""
        try:
            sections.append(_section(d, tid, n_data + 1))
            n_data += 1
        except _DAMAGED as e:  # a damaged tool is named on the page and on stderr; the others go on
            where = d / "tools" / tool_file_stem(tid)
            warnings.warn(f"{where}.json/.npz: unreadable or incomplete ({type(e).__name__}: {e}); "
                          "its section of the report says so (run 'toolpoint library' again to redo it)")
            sections.append(f'<details id="tool-{html.escape(tid)}"><summary>{html.escape(tid)}</summary>'
                            f"<p>files missing or unreadable: {html.escape(str(e))}</p></details>")
    page = (f"<!DOCTYPE html><html lang=en><head><meta charset=utf-8><title>toolpoint library report</title>"
            f"<style>{_STYLE}</style><script>{_SCRIPT}</script></head><body>"
            f"<h1>Recommended spindle speeds and depths</h1>"
            f"<p>{len(rows)} tools from <code>{html.escape(str(table))}</code>. Recommended depth: the depth 95 % "
            "of the samples (joint, cutting coefficients, subassembly) keep stable at every speed within the "
            "spindle-speed tolerance, less the margin; where no pocket is worth its uncertainty, the depth stable at "
            "every speed (point 'minimum'). P(stable) is calibrated out of sample (docs/design/recommend.md). "
            "Click a header to sort; type to filter; click a tool to open its figures.</p>"
            f'<input id="filter" placeholder="filter tools…" oninput="filterRows(this.value)">'
            f'<table id="overview"><thead><tr>{head}</tr></thead><tbody>{"".join(body)}</tbody></table>'
            f'{"".join(sections)}</body></html>')
    out = Path(path) if path is not None else d / "report.html"
    with atomic_open(out, "w", encoding="utf-8") as fh:
        fh.write(page)
    return out
