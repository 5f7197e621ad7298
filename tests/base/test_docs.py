"""Every public name has a docstring; the main entry points have a doctested Examples section."""

import importlib
import inspect
import pkgutil

import pytest

import toolpoint

MODULES = sorted(m.name for m in pkgutil.walk_packages(toolpoint.__path__, "toolpoint."))


def _public(module):
    for name, obj in vars(module).items():
        if name.startswith("_") or getattr(obj, "__module__", None) != module.__name__:
            continue
        if inspect.isclass(obj) or inspect.isfunction(obj):
            yield name, obj
            if inspect.isclass(obj):
                for attr, member in vars(obj).items():
                    if attr.startswith("_"):
                        continue
                    fn = member.fget if isinstance(member, property) else getattr(member, "__func__", member)
                    if inspect.isfunction(fn) or isinstance(member, property):
                        yield f"{name}.{attr}", fn


@pytest.mark.parametrize("modname", MODULES)
def test_public_names_have_docstrings(modname):
    module = importlib.import_module(modname)
    assert (module.__doc__ or "").strip(), f"{modname} has no module docstring"
    missing = [n for n, obj in _public(module) if not (inspect.getdoc(obj) or "").strip()]
    assert not missing, f"{modname}: no docstring for {', '.join(missing)}"


ENTRY_POINTS = [
    "toolpoint.frf.FRF",
    "toolpoint.dynamics.assembly.load_assembly",
    "toolpoint.dynamics.model.AssemblyModel",
    "toolpoint.io.frf_files.read_frf",
    "toolpoint.identification.identify.identify",
    "toolpoint.identification.params.Bounds",
    "toolpoint.learning.anfis.ANFIS",
    "toolpoint.stability.zoa.zoa_lobes",
    "toolpoint.stability.cutting.CuttingConditions",
]


@pytest.mark.parametrize("path", ENTRY_POINTS)
def test_entry_points_have_examples(path):
    modname, name = path.rsplit(".", 1)
    doc = inspect.getdoc(getattr(importlib.import_module(modname), name)) or ""
    assert "Examples\n--------" in doc and ">>> " in doc, f"{path}: no doctested Examples section"
