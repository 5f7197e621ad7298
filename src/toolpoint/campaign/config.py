"""A campaign folder: ``campaign.toml`` + ``measurements.csv`` → typed objects.

``campaign.toml`` (lengths in mm at the boundary, all else SI)::

    [campaign]
    band_hz = [20.0, 4000.0]        # frequency band to fit (Hz); each measured FRF is further cut to its
                                    # trusted band (toolpoint.trust), noted in its row's warnings
    [materials.carbide]             # optional, as in an assembly file
    E = 580e9
    rho = 14500.0
    nu = 0.22
    [tool_family]
    material = "carbide"            # default "steel"
    flute_ratio = 0.8               # equivalent diameter of the fluted part / D
    flute_length_ratio = 2.0        # flute length = ratio × D, capped at the overhang
    [holders.ER40]                  # one entry per holder/collet; the subassembly comes from
    model = "spindle_holder.toml"   #   a model (spindle + holder + spindle–holder joint), or
    # joint = "sh_identified.json"  #   with the joint of `toolpoint identify --joint spindle_holder`, or
    # blank = { segments = [{ length_mm = 50, od_mm = 20 }], x2_mm = 40,
    #           G11 = "sh/G11.csv", G12 = "sh/G12.csv", G22 = "sh/G22.csv", smooth = "modal",
    #           band_hz = "auto" }      # or [lo, hi]: the blank FRFs' band (default all; "auto": trusted band)
    # files = { h = "h.csv", l = "l.csv", n = "n.csv", p = "p.csv" }
    # smooth = "modal": common-pole modal fit of the measured FRFs (noise out, peaks
    # kept; recommended); smooth_hz = 25: Savitzky–Golay window (rounds sharp peaks)
    [identify]
    method = "hybrid"
    bounds = { kt = [1e6, 1e9] }    # optional, the paper's by default

``measurements.csv``: columns ``id, diameter_mm, overhang_mm, frf`` (path
relative to the folder) and optionally ``holder`` (default: the only holder).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace
from pathlib import Path

import numpy as np

from ..dynamics.assembly import (
    MM,
    Component,
    Joint,
    Material,
    Segment,
    parse_materials,
    parse_segments,
    load_assembly,
)
from ..errors import InputError
from ..io.table import read_rows
from ..io.toml import TomlReader, load_toml
from ..io.frf_files import read_frf
from ..dynamics.inverse_rcsa import subassembly_from_blank, subassembly_from_files, subassembly_replicates
from ..identification.optim import check_method
from ..identification.params import Bounds
from ..dynamics.subassembly import Subassembly


@dataclass(frozen=True)
class ToolFamily:
    material: Material
    flute_ratio: float = 0.8
    flute_length_ratio: float = 2.0

    def tool(self, diameter_mm: float, overhang_mm: float) -> Component:
        """The overhang as a beam: plain shank, then flutes of equivalent diameter ratio·D."""
        D, L = diameter_mm * MM, overhang_mm * MM
        flutes = min(L, self.flute_length_ratio * D)
        segs = []
        if L - flutes > 1e-9:
            segs.append(Segment(L - flutes, D, 0.0, self.material))
        segs.append(Segment(flutes, self.flute_ratio * D, 0.0, self.material))
        return Component("tool", tuple(segs))


@dataclass(frozen=True)
class Measurement:
    id: str
    diameter_mm: float
    overhang_mm: float
    frf: Path
    holder: str
    line: int


@dataclass(frozen=True)
class HolderSource:
    name: str
    kind: str  # "model" | "blank" | "files"
    spec: dict


@dataclass(frozen=True)
class Campaign:
    folder: Path
    band_hz: tuple[float, float]
    family: ToolFamily
    holders: dict[str, HolderSource]
    measurements: tuple[Measurement, ...]
    method: str
    bounds: Bounds
    materials: dict  # by name, for blank segments

    @property
    def toml(self) -> Path:
        """Path of the campaign's ``campaign.toml``."""
        return self.folder / "campaign.toml"

    def subassembly(self, name: str, freq_hz=None) -> Subassembly:
        """The holder's subassembly on ``freq_hz`` (Hz, inside its measured band), or on
        its own measured grid when ``freq_hz`` is None (not for a model source)."""
        src = self.holders[name]
        where = f"holders.{name}.{src.kind}"
        if src.kind == "model":
            joint = src.spec.get("joint")
            a = load_assembly(self.folder / src.spec["path"], require_tool=False,
                              require_spindle_holder=joint is None)
            if joint is not None:
                a = replace(a, spindle_holder=_identified_joint(self.folder / joint, f"holders.{name}.joint"))
            return Subassembly.from_assembly(a, np.asarray(freq_hz, float))
        sub = self._measured_subassembly(name)
        if freq_hz is None:
            return sub
        try:
            return sub.at(np.asarray(freq_hz, float))
        except ValueError as e:
            raise InputError(str(e), file=self.toml, field=where) from None


    def subassembly_replicates(self, name: str, freq_hz, n: int, seed: int) -> list[Subassembly]:
        """Bootstrap replicates of a blank-measured holder's subassembly on ``freq_hz``
        (:func:`~toolpoint.dynamics.inverse_rcsa.subassembly_replicates`); [] for a model (exact) or FRF-file
        source (not sampled)."""
        src = self.holders[name]
        if src.kind != "blank" or n < 1:
            return []
        r = TomlReader(str(self.toml))
        blank = Component("blank", parse_segments(r, src.spec, f"holders.{name}.blank", self.materials))
        keys = [self.folder / src.spec[k] for k in ("G11", "G12", "G22")]
        reps = subassembly_replicates(blank, float(src.spec["x2_mm"]) * MM, *(read_frf(p) for p in keys), n=n,
                                      rng=np.random.default_rng(seed), band=src.spec.get("band_hz"))
        return [s.at(np.asarray(freq_hz, float)) for s in reps]

    def _measured_subassembly(self, name: str) -> Subassembly:
        src = self.holders[name]
        keys = [self.folder / src.spec[k] for k in (("G11", "G12", "G22") if src.kind == "blank" else tuple("hlnp"))]
        # a modal fit takes seconds: remember it while its input files are unchanged
        memo = (str(self.toml.resolve()), name, repr(sorted(src.spec.items())),
                tuple(_stamp(p) for p in keys + [self.toml]))
        if memo in _MEMO:
            return _MEMO[memo]
        smooth = src.spec.get("smooth")
        if src.kind == "files":
            sub = subassembly_from_files(*keys, smooth=smooth)
        else:
            r = TomlReader(str(self.toml))
            blank = Component("blank", parse_segments(r, src.spec, f"holders.{name}.blank", self.materials))
            try:
                sub = subassembly_from_blank(blank, float(src.spec["x2_mm"]) * MM, *(read_frf(p) for p in keys),
                                             smooth=smooth, band=src.spec.get("band_hz"))
            except InputError as e:
                if e.field != "band":
                    raise
                raise InputError(e.message, file=self.toml, field=f"holders.{name}.blank.band_hz") from None
        _MEMO.clear()  # one holder set at a time is enough
        _MEMO[memo] = sub
        return sub


_MEMO: dict = {}


def _stamp(path: Path):
    try:
        st = path.stat()
    except OSError:
        return None  # read_frf raises the one-line error
    return st.st_mtime_ns, st.st_size


def _identified_joint(path: Path, field: str, source=None) -> Joint:
    """The spindle–holder joint of a ``toolpoint identify --joint spindle_holder`` result JSON (SI)."""
    import json

    try:
        doc = json.loads(Path(path).read_text())
    except (OSError, ValueError) as e:
        raise InputError(f"cannot read identification result {path}: {e}", file=source, field=field) from None
    if not isinstance(doc, dict) or doc.get("joint", "spindle_holder") != "spindle_holder":
        raise InputError(f"{path} is not a spindle–holder joint identification (toolpoint identify --joint "
                         "spindle_holder)", file=source, field=field)
    vals = [doc.get(k) for k in ("kt", "ct", "kr", "cr")]
    if not all(isinstance(v, (int, float)) and not isinstance(v, bool) and 0 < v < math.inf for v in vals):
        raise InputError(f"{path} needs kt, ct, kr, cr > 0", file=source, field=field)
    return Joint(*map(float, vals))


def _smooth(r: TomlReader, spec: dict, path: str):
    """``smooth = "modal"`` or a Savitzky–Golay window ``smooth_hz`` (> 0); at most one."""
    if "smooth" in spec and "smooth_hz" in spec:
        raise r.err(path, "give smooth or smooth_hz, not both")
    if "smooth" in spec:
        if spec["smooth"] != "modal":
            raise r.err(f"{path}.smooth", f'must be "modal" (or use smooth_hz = window in Hz), got {spec["smooth"]!r}')
        return "modal"
    if "smooth_hz" in spec:
        v = spec["smooth_hz"]
        if isinstance(v, bool) or not isinstance(v, (int, float)) or not (0 < v < math.inf):
            raise r.err(f"{path}.smooth_hz", f"must be a window > 0 Hz, got {v!r}")
        return float(v)
    return None


def _blank_band(r: TomlReader, b: dict, path: str):
    """A blank's ``band_hz``: absent (None: all of the measured FRFs), ``[lo, hi]`` in Hz or ``"auto"``."""
    from ..trust import check_band

    v = b.get("band_hz")
    if v is None or v == "auto":
        return v
    return check_band(v, file=r.file, field=f"{path}.band_hz")


def _band(r: TomlReader, doc: dict) -> tuple[float, float]:
    c = r.table(doc, "campaign", "campaign")
    band = c.get("band_hz")
    try:
        lo, hi = (float(v) for v in band)
    except (TypeError, ValueError):
        raise r.err("campaign.band_hz", f"must be [lo, hi] in Hz, got {band!r}") from None
    if not (0 < lo < hi and math.isfinite(hi)):
        raise r.err("campaign.band_hz", f"need 0 < lo < hi, got [{lo:g}, {hi:g}]")
    return lo, hi


def _family(r: TomlReader, doc: dict, mats: dict) -> ToolFamily:
    t = r.table(doc, "tool_family", "tool_family", required=False) or {}
    r.unknown_keys(t, {"material", "flute_ratio", "flute_length_ratio"}, "tool_family")
    name = t.get("material", "steel")
    if name not in mats:
        raise r.err("tool_family.material", f"unknown material {name!r} (known: {', '.join(sorted(mats))})")
    ratio = r.number(t, "flute_ratio", "tool_family", default=0.8, positive=True)
    if ratio > 1:
        raise r.err("tool_family.flute_ratio", f"must be ≤ 1, got {ratio:g}")
    length = r.number(t, "flute_length_ratio", "tool_family", default=2.0, positive=True)
    return ToolFamily(mats[name], ratio, length)


def _file_key(r: TomlReader, spec: dict, key: str, path: str, folder: Path) -> None:
    """``spec[key]`` must name an existing file (relative to the campaign folder)."""
    v = spec[key]
    if not isinstance(v, str) or not v:
        raise r.err(f"{path}.{key}", f"must be a file name (text), got {v!r}")
    if not (folder / v).is_file():
        raise r.err(f"{path}.{key}", f"file not found: {folder / v}")


def _holders(r: TomlReader, doc: dict, folder: Path) -> dict[str, HolderSource]:
    hs = r.table(doc, "holders", "holders")
    if not hs:
        raise r.err("holders", "needs at least one holder entry")
    out = {}
    for name, spec in hs.items():
        path = f"holders.{name}"
        if not isinstance(spec, dict):
            raise r.err(path, "must be a table")
        kinds = [k for k in ("model", "blank", "files") if k in spec]
        if len(kinds) != 1:
            raise r.err(path, "give exactly one of model, blank, files")
        kind = kinds[0]
        if kind == "model":
            p = folder / str(spec["model"])
            if not p.is_file():
                raise r.err(f"{path}.model", f"file not found: {p}")
            r.unknown_keys(spec, {"model", "joint"}, path)
            js = spec.get("joint")
            if js is not None:
                _identified_joint(folder / str(js), f"{path}.joint", source=r.file)
            out[name] = HolderSource(name, kind, {"path": str(spec["model"]),
                                                  "joint": None if js is None else str(js)})
        elif kind == "files":
            f = spec["files"]
            if not isinstance(f, dict) or set(f) - {"smooth", "smooth_hz"} != set("hlnp"):
                raise r.err(f"{path}.files", 'must be {h = …, l = …, n = …, p = …} (optionally smooth = "modal")')
            for k in "hlnp":
                _file_key(r, f, k, f"{path}.files", folder)
            out[name] = HolderSource(name, kind, {**{k: f[k] for k in "hlnp"},
                                                  "smooth": _smooth(r, f, f"{path}.files")})
        else:
            b = spec["blank"]
            if not isinstance(b, dict):
                raise r.err(f"{path}.blank", "must be a table")
            for k in ("segments", "x2_mm", "G11", "G12", "G22"):
                if k not in b:
                    raise r.err(f"{path}.blank.{k}", "missing value")
            # checked here, once, so that a bad holder stops the run with its config field instead of
            # failing every tool that uses it
            r.number(b, "x2_mm", f"{path}.blank", positive=True)
            for k in ("G11", "G12", "G22"):
                _file_key(r, b, k, f"{path}.blank", folder)
            sm = _smooth(r, b, f"{path}.blank")
            out[name] = HolderSource(name, kind, {**{k: v for k, v in b.items() if k not in ("smooth", "smooth_hz")},
                                                  "smooth": sm, "band_hz": _blank_band(r, b, f"{path}.blank")})
    return out


def _measurements(path: Path, holders: dict) -> tuple[Measurement, ...]:
    rows = read_rows(path, what="the measurements table")
    if not rows:
        raise InputError("empty file", file=path, field="header")
    head = [h.strip() for h in rows[0][1]]
    need = ["id", "diameter_mm", "overhang_mm", "frf"]
    for col in need:
        if col not in head:
            raise InputError(f"missing column {col!r} (have {', '.join(head)})", file=path, field=col)
    idx = {c: head.index(c) for c in head}
    default_holder = next(iter(holders)) if len(holders) == 1 else None
    seen: dict[str, int] = {}
    out = []
    for n, row in rows[1:]:
        if len(row) != len(head):
            raise InputError(f"line {n}: {len(row)} cells, header has {len(head)}", file=path, field="row")
        get = lambda c: row[idx[c]].strip()  # noqa: E731
        mid = get("id")
        if not mid:
            raise InputError(f"line {n}: empty id", file=path, field="id")
        if mid in seen:
            raise InputError(f"duplicate id {mid!r} on lines {seen[mid]} and {n}", file=path, field="id")
        seen[mid] = n
        vals = {}
        for c in ("diameter_mm", "overhang_mm"):
            try:
                vals[c] = float(get(c))
            except ValueError:
                raise InputError(f"line {n}: {get(c)!r} is not a number", file=path, field=c) from None
            if not (vals[c] > 0 and math.isfinite(vals[c])):
                raise InputError(f"line {n}: must be > 0, got {get(c)}", file=path, field=c)
        holder = get("holder") if "holder" in idx and get("holder") else default_holder
        if holder is None:
            raise InputError(f"line {n}: several holders defined, name one in the 'holder' column", file=path,
                             field="holder")
        if holder not in holders:
            raise InputError(f"line {n}: unknown holder {holder!r} (campaign.toml has {', '.join(holders)})",
                             file=path, field="holder")
        out.append(Measurement(mid, vals["diameter_mm"], vals["overhang_mm"], path.parent / get("frf"), holder, n))
    if not out:
        raise InputError("no measurements", file=path, field="rows")
    return tuple(out)


def load_campaign(folder: str | Path) -> Campaign:
    """Read and validate a campaign folder."""
    folder = Path(folder)
    if not folder.is_dir():
        raise InputError("not a folder", file=folder)
    toml = folder / "campaign.toml"
    doc = load_toml(toml)
    r = TomlReader(str(toml))
    r.unknown_keys(doc, {"campaign", "materials", "tool_family", "holders", "identify"}, "file")
    mats = parse_materials(r, doc)
    band = _band(r, doc)
    family = _family(r, doc, mats)
    holders = _holders(r, doc, folder)
    ident = r.table(doc, "identify", "identify", required=False) or {}
    method = check_method(ident.get("method", "hybrid"), file=r.file, field="identify.method")
    bounds = Bounds.from_dict(ident.get("bounds"), source=str(toml), section="identify.bounds")
    return Campaign(folder, band, family, holders, _measurements(folder / "measurements.csv", holders), method,
                    bounds, mats)
