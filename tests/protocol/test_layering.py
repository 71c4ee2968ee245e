"""protocol/ is the shared bottom layer: nothing in it imports the rig or the ground tools."""

import ast
import subprocess
import sys
from pathlib import Path

import protocol

ROOT = Path(protocol.__file__).resolve().parent
UPPER = ("rig_emulator", "gcs_tools")


def _imported_names(path: Path) -> set[str]:
    """Every module an ``import`` or ``from ... import`` names in the file, at any depth
    (lazy imports inside functions included)."""
    names = set()
    for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"), str(path))):
        if isinstance(node, ast.Import):
            names.update(alias.name for alias in node.names)
        elif isinstance(node, ast.ImportFrom) and node.level == 0 and node.module:
            names.add(node.module)
    return names


def test_no_protocol_module_imports_rig_emulator_or_gcs_tools():
    files = sorted(ROOT.rglob("*.py"))
    assert len(files) > 5
    offending = {
        str(path.relative_to(ROOT.parent)): sorted(n for n in _imported_names(path) if n.split(".")[0] in UPPER)
        for path in files
    }
    offending = {k: v for k, v in offending.items() if v}
    assert not offending, f"protocol/ must not import {UPPER}: {offending}"


def test_importing_every_protocol_module_loads_neither_package():
    modules = sorted(
        ".".join(p.relative_to(ROOT.parent).with_suffix("").parts).removesuffix(".__init__")
        for p in ROOT.rglob("*.py")
    )
    code = (
        "import importlib, sys\n"
        f"for m in {modules!r}: importlib.import_module(m)\n"
        f"print(sorted(m for m in sys.modules if m.split('.')[0] in {UPPER!r}))\n"
    )
    out = subprocess.run([sys.executable, "-c", code], cwd=ROOT.parent, capture_output=True, text=True, check=True)
    assert out.stdout.strip() == "[]"
