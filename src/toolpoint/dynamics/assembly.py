"""Assembly description: the TOML file → typed, validated objects (SI units).

Schema (lengths in mm at the file boundary, keys ending in ``_mm``; all else SI)::

    [frequency]            start_hz, stop_hz, step_hz   (optional; default 0, 3000, 1)
    [materials.NAME]       E (Pa), rho (kg/m³), nu, loss_factor     ("steel" is built in)
    [spindle]              segments = [{length_mm, od_mm, id_mm = 0, material = "steel"}, …]
                           bearings = [{x_mm, k (N/m), c (N s/m), kr (N m/rad), cr (N m s/rad)}, …]
    [holder]  segments     spindle nose → holder tip
    [tool]    segments     holder tip → tool tip
    [joints.spindle_holder] kt (N/m), ct (N s/m), kr (N m/rad), cr (N m s/rad)
    [joints.holder_tool]    same (optional: identification finds it)
    [identify.bounds]      kt = [lo, hi], … (optional, used by ``toolpoint identify``)

Every problem raises :class:`~toolpoint.errors.InputError` naming the file and
the field (e.g. ``spindle.segments[1].od_mm``).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, replace
from pathlib import Path

import numpy as np

from .beam import Section
from ..io.toml import TomlReader, load_toml

__all__ = ["Material", "Segment", "Bearing", "Joint", "Component", "FrequencyGrid", "Assembly", "parse_joint",
           "parse_materials", "parse_segments", "parse_assembly", "load_toml", "load_assembly", "MM", "STEEL"]

MM = 1e-3
#: Largest frequency grid an assembly file may ask for (points): memory grows linearly with it, and a
#: typo such as ``step_hz = 0.0001`` (3e7 points over 0–3000 Hz) would otherwise ask for gigabytes.
MAX_FREQUENCIES = 1_000_000
#: Most segments per component: a beam of a few hundred pieces is already a modelling error.
MAX_SEGMENTS = 500
"""Metres per millimetre (file lengths are in mm)."""

STEEL = {"E": 210e9, "rho": 7800.0, "nu": 0.3, "loss_factor": 0.0}
"""The built-in material ``steel``: E Pa, ρ kg/m³, ν, loss factor η."""


@dataclass(frozen=True)
class Material:
    """An isotropic material.

    Attributes
    ----------
    name : str
    E : float
        Young's modulus, Pa.
    rho : float
        Density, kg/m³.
    nu : float
        Poisson's ratio (shear modulus G = E / (2(1 + ν))).
    loss_factor : float
        Structural damping η: the modulus is E(1 + iη).
    """

    name: str
    E: float  # Pa
    rho: float  # kg/m³
    nu: float
    loss_factor: float = 0.0


@dataclass(frozen=True)
class Segment:
    """Uniform hollow circular segment: length, outer and inner diameter in m (id 0: solid)."""

    length: float
    od: float
    id: float
    material: Material

    def section(self) -> Section:
        """The Timoshenko :class:`~toolpoint.dynamics.beam.Section` (A, I, κ, complex E) of this segment."""
        m = self.material
        return Section.tube(self.od, self.id, m.E, m.rho, m.nu, m.loss_factor)

    @property
    def mass(self) -> float:
        """Mass ρ π/4 (od² − id²) L, kg."""
        return self.material.rho * math.pi / 4 * (self.od**2 - self.id**2) * self.length


@dataclass(frozen=True)
class Bearing:
    """Radial spring-damper to ground at x (m from the component's start)."""

    x: float
    k: float  # N/m
    c: float = 0.0  # N s/m
    kr: float = 0.0  # N m/rad
    cr: float = 0.0  # N m s/rad


@dataclass(frozen=True)
class Joint:
    """Joint K = diag(kt + iω ct, kr + iω cr) between two components."""

    kt: float  # N/m
    ct: float  # N s/m
    kr: float  # N m/rad
    cr: float  # N m s/rad

    def as_array(self) -> np.ndarray:
        """[kt N/m, ct N s/m, kr N m/rad, cr N m s/rad] as a (4,) float array."""
        return np.array([self.kt, self.ct, self.kr, self.cr], float)


@dataclass(frozen=True)
class Component:
    """A multi-segment beam along the global x axis, with optional bearings."""

    name: str
    segments: tuple[Segment, ...]
    bearings: tuple[Bearing, ...] = ()

    @property
    def length(self) -> float:
        """Total length, m."""
        return sum(s.length for s in self.segments)

    @property
    def mass(self) -> float:
        """Total mass, kg."""
        return sum(s.mass for s in self.segments)


@dataclass(frozen=True)
class FrequencyGrid:
    """The ``[frequency]`` table: start, stop and step in Hz (stop included when on the grid)."""

    start_hz: float = 0.0
    stop_hz: float = 3000.0
    step_hz: float = 1.0

    def array(self) -> np.ndarray:
        """The grid start, start + step, … ≤ stop (Hz), as a float array.

        Examples
        --------
        >>> FrequencyGrid(0.0, 1.0, 0.25).array().tolist()
        [0.0, 0.25, 0.5, 0.75, 1.0]
        """
        n = int(math.floor((self.stop_hz - self.start_hz) / self.step_hz + 1e-9)) + 1
        return self.start_hz + self.step_hz * np.arange(n)


@dataclass(frozen=True)
class Assembly:
    """A spindle–holder–tool assembly, SI units.

    Attributes
    ----------
    spindle : Component
        With its bearings; from the rear to the spindle nose.
    holder : Component
        Spindle nose → holder tip.
    tool : Component or None
        Holder tip → tool tip (None for a spindle–holder description).
    spindle_holder, holder_tool : Joint or None
        The joints (None when the file leaves one out for identification to find).
    frequency : FrequencyGrid
    materials : dict
        Materials by name.
    identify : dict
        The raw ``[identify]`` table.
    source : str
        The file it came from (for error messages).
    """

    spindle: Component
    holder: Component
    tool: Component | None
    spindle_holder: Joint | None
    holder_tool: Joint | None = None
    frequency: FrequencyGrid = FrequencyGrid()
    materials: dict = field(default_factory=dict, compare=False)
    identify: dict = field(default_factory=dict, compare=False)
    source: str = "<memory>"

    def with_tool(self, tool: Component) -> "Assembly":
        """A copy with another tool."""
        return replace(self, tool=tool)

    def with_holder_tool(self, joint: Joint) -> "Assembly":
        """A copy with another holder–tool joint."""
        return replace(self, holder_tool=joint)


# --------------------------------------------------------------------------- parsing
def parse_materials(r: TomlReader, doc: dict) -> dict[str, Material]:
    """The ``[materials]`` tables of ``doc`` (plus the built-in ``steel``), by name."""
    mats = {"steel": Material("steel", **STEEL)}
    table = r.table(doc, "materials", "materials", required=False) or {}
    for name, spec in table.items():
        path = f"materials.{name}"
        if not isinstance(spec, dict):
            raise r.err(path, "must be a table")
        r.unknown_keys(spec, {"E", "rho", "nu", "loss_factor"}, path)
        base = STEEL if name == "steel" else {}
        E = r.number(spec, "E", path, default=base.get("E"), positive=True)
        rho = r.number(spec, "rho", path, default=base.get("rho"), positive=True)
        nu = r.number(spec, "nu", path, default=base.get("nu", 0.3))
        if not -1 < nu < 0.5:
            raise r.err(f"{path}.nu", f"must be in (-1, 0.5), got {nu:g}")
        eta = r.number(spec, "loss_factor", path, default=0.0, nonneg=True)
        mats[name] = Material(name, E, rho, nu, eta)
    return mats


def parse_segments(r: TomlReader, comp: dict, path: str, mats: dict) -> tuple[Segment, ...]:
    """``comp["segments"]`` ({length_mm, od_mm, id_mm, material}, mm) as segments in m; errors name ``path``."""
    segs = comp.get("segments")
    if segs is None:
        raise r.err(f"{path}.segments", "missing value")
    if not isinstance(segs, list) or not segs:
        raise r.err(f"{path}.segments", "must be a non-empty array of tables")
    if len(segs) > MAX_SEGMENTS:
        raise r.err(f"{path}.segments", f"{len(segs)} segments; at most {MAX_SEGMENTS} per component")
    out = []
    for i, s in enumerate(segs):
        p = f"{path}.segments[{i}]"
        if not isinstance(s, dict):
            raise r.err(p, "must be a table {length_mm, od_mm, id_mm, material}")
        r.unknown_keys(s, {"length_mm", "od_mm", "id_mm", "material"}, p)
        length = r.number(s, "length_mm", p, positive=True)
        od = r.number(s, "od_mm", p, positive=True)
        id_ = r.number(s, "id_mm", p, default=0.0, nonneg=True)
        if id_ >= od:
            raise r.err(f"{p}.id_mm", f"must be smaller than od_mm ({id_:g} ≥ {od:g})")
        mname = s.get("material", "steel")
        if mname not in mats:
            raise r.err(f"{p}.material", f"unknown material {mname!r} (known: {', '.join(sorted(mats))})")
        out.append(Segment(length * MM, od * MM, id_ * MM, mats[mname]))
    return tuple(out)


def _bearings(r: TomlReader, comp: dict, path: str, length_m: float) -> tuple[Bearing, ...]:
    bs = comp.get("bearings", [])
    if not isinstance(bs, list):
        raise r.err(f"{path}.bearings", "must be an array of tables")
    out = []
    for i, b in enumerate(bs):
        p = f"{path}.bearings[{i}]"
        if not isinstance(b, dict):
            raise r.err(p, "must be a table {x_mm, k, c, kr, cr}")
        r.unknown_keys(b, {"x_mm", "k", "c", "kr", "cr"}, p)
        x = r.number(b, "x_mm", p)
        if not 0 <= x * MM <= length_m * (1 + 1e-12):
            raise r.err(f"{p}.x_mm", f"bearing at {x:g} mm lies outside the spindle (0–{length_m / MM:g} mm)")
        out.append(
            Bearing(
                x * MM,
                r.number(b, "k", p, nonneg=True),
                r.number(b, "c", p, default=0.0, nonneg=True),
                r.number(b, "kr", p, default=0.0, nonneg=True),
                r.number(b, "cr", p, default=0.0, nonneg=True),
            )
        )
    return tuple(out)


def _component(r: TomlReader, doc: dict, name: str, mats: dict, with_bearings: bool) -> Component:
    comp = r.table(doc, name, name)
    allowed = {"segments", "bearings"} if with_bearings else {"segments"}
    r.unknown_keys(comp, allowed, name)
    segs = parse_segments(r, comp, name, mats)
    bearings = _bearings(r, comp, name, sum(s.length for s in segs)) if with_bearings else ()
    return Component(name, segs, bearings)


def parse_joint(r: TomlReader, d: dict, path: str) -> Joint:
    """A joint table {kt N/m > 0, ct N s/m ≥ 0, kr N m/rad > 0, cr N m s/rad ≥ 0}; errors name ``path``."""
    r.unknown_keys(d, {"kt", "ct", "kr", "cr"}, path)
    kt = r.number(d, "kt", path, positive=True)
    ct = r.number(d, "ct", path, nonneg=True)
    kr = r.number(d, "kr", path, positive=True)
    cr = r.number(d, "cr", path, nonneg=True)
    return Joint(kt, ct, kr, cr)


def _frequency(r: TomlReader, doc: dict) -> FrequencyGrid:
    t = r.table(doc, "frequency", "frequency", required=False)
    if t is None:
        return FrequencyGrid()
    r.unknown_keys(t, {"start_hz", "stop_hz", "step_hz"}, "frequency")
    start = r.number(t, "start_hz", "frequency", default=0.0, nonneg=True)
    stop = r.number(t, "stop_hz", "frequency", default=3000.0)
    step = r.number(t, "step_hz", "frequency", default=1.0)
    if step <= 0:
        raise r.err("frequency.step_hz", f"must be > 0, got {step:g}")
    if stop <= start:
        raise r.err("frequency.stop_hz", f"must be greater than start_hz ({stop:g} ≤ {start:g})")
    n = (stop - start) / step + 1
    if n > MAX_FREQUENCIES:
        raise r.err("frequency.step_hz", f"the grid {start:g}–{stop:g} Hz at {step:g} Hz has {n:.3g} points; "
                    f"at most {MAX_FREQUENCIES:,} (raise step_hz or narrow the band)")
    return FrequencyGrid(start, stop, step)


def parse_assembly(doc: dict, source: str = "<memory>", *, require_holder_tool: bool = False,
                   require_tool: bool = True, require_spindle_holder: bool = True) -> Assembly:
    """Build an :class:`Assembly` from a parsed TOML document (dict).

    Parameters
    ----------
    doc : dict
        The document (schema in the module docstring; lengths in mm).
    source : str
        Name used in error messages.
    require_holder_tool : bool
        Refuse a document without ``[joints.holder_tool]``.
    require_tool : bool
        ``False`` accepts a spindle–holder description without ``[tool]``
        (``Assembly.tool`` is then None), as a campaign's subassembly model.
    require_spindle_holder : bool
        ``False`` accepts a document without ``[joints.spindle_holder]`` (``Assembly.spindle_holder`` is then
        None), for identifying that joint.

    Raises
    ------
    InputError
        Naming ``source`` and the field.

    Examples
    --------
    >>> import tomllib
    >>> doc = tomllib.loads('''
    ... [spindle]
    ... segments = [{ length_mm = 300, od_mm = 70, id_mm = 20 }]
    ... bearings = [{ x_mm = 50, k = 2e8 }, { x_mm = 250, k = 3e8 }]
    ... [holder]
    ... segments = [{ length_mm = 60, od_mm = 40 }]
    ... [joints.spindle_holder]
    ... kt = 5e8
    ... ct = 300.0
    ... kr = 1.5e7
    ... cr = 50.0
    ... ''')
    >>> a = parse_assembly(doc, "sh.toml", require_tool=False)
    >>> a.tool is None, round(a.holder.length, 6), a.spindle.bearings[1].x
    (True, 0.06, 0.25)
    >>> parse_assembly(doc, "sh.toml")
    Traceback (most recent call last):
    ...
    toolpoint.errors.InputError: sh.toml: tool: missing section
    """
    r = TomlReader(source)
    r.unknown_keys(doc, {"frequency", "materials", "spindle", "holder", "tool", "joints", "identify"}, "file")
    mats = parse_materials(r, doc)
    spindle = _component(r, doc, "spindle", mats, with_bearings=True)
    holder = _component(r, doc, "holder", mats, with_bearings=False)
    tool = _component(r, doc, "tool", mats, with_bearings=False) if (require_tool or "tool" in doc) else None
    joints = r.table(doc, "joints", "joints", required=require_spindle_holder) or {}
    r.unknown_keys(joints, {"spindle_holder", "holder_tool"}, "joints")
    sh_t = r.table(joints, "spindle_holder", "joints.spindle_holder", required=require_spindle_holder)
    sh = parse_joint(r, sh_t, "joints.spindle_holder") if sh_t is not None else None
    ht_t = r.table(joints, "holder_tool", "joints.holder_tool", required=require_holder_tool)
    ht = parse_joint(r, ht_t, "joints.holder_tool") if ht_t is not None else None
    ident = r.table(doc, "identify", "identify", required=False) or {}
    return Assembly(spindle, holder, tool, sh, ht, _frequency(r, doc), mats, ident, source)


def load_assembly(path: str | Path, *, require_holder_tool: bool = False, require_tool: bool = True,
                  require_spindle_holder: bool = True) -> Assembly:
    """Load and validate an assembly TOML file (see :func:`parse_assembly` for the options).

    Examples
    --------
    The numerical case study shipped with toolpoint (``examples/numerical_case.toml``
    in the source tree):

    >>> from pathlib import Path
    >>> import toolpoint
    >>> path = Path(toolpoint.__file__).parents[2] / "examples" / "numerical_case.toml"
    >>> a = load_assembly(path, require_holder_tool=True)
    >>> [c.name for c in (a.spindle, a.holder, a.tool)], a.holder_tool.kt > 0
    (['spindle', 'holder', 'tool'], True)
    >>> round(a.tool.length * 1e3, 6), len(a.frequency.array())
    (60.0, 3001)
    """
    return parse_assembly(load_toml(path), str(path), require_holder_tool=require_holder_tool,
                          require_tool=require_tool, require_spindle_holder=require_spindle_holder)
