"""brdfkit.terms is the bottom layer of the models: its modules import no model, analysis, rendering or facade code.

Checked on the source (every import statement, function-level ones included), so that an import cycle through
``brdfkit.terms`` cannot come back unnoticed.
"""

from __future__ import annotations

import ast
from pathlib import Path

import pytest

import brdfkit.terms

TERMS = Path(brdfkit.terms.__file__).resolve().parent
PKG = TERMS.parent
#: what a term may import from brdfkit (the rest is numpy, numba and the standard library)
ALLOWED = ("brdfkit.engine", "brdfkit.geometry", "brdfkit.fileio", "brdfkit.terms")


def module_name(path: Path) -> str:
    return ".".join(path.relative_to(PKG.parent).with_suffix("").parts)


def brdfkit_imports(source: str, module: str) -> list[str]:
    """The brdfkit modules (or names) that the source of ``module`` imports, relative imports resolved, at any
    depth of its code."""
    package = module.rpartition(".")[0]
    out = []
    for node in ast.walk(ast.parse(source)):
        if isinstance(node, ast.Import):
            out += [a.name for a in node.names if a.name.split(".")[0] == "brdfkit"]
        elif isinstance(node, ast.ImportFrom):
            if node.level:
                base = package.split(".")
                base = base[: len(base) - (node.level - 1)]
                full = ".".join(base + ([node.module] if node.module else []))
            else:
                full = node.module or ""
            if full.split(".")[0] != "brdfkit":
                continue
            # ``from brdfkit import x`` / ``from .. import x``: the facade or a subpackage named x
            out += [f"{full}.{a.name}" for a in node.names] if full == "brdfkit" else [full]
    return out


TERM_FILES = sorted(TERMS.glob("*.py"))


@pytest.mark.parametrize("path", TERM_FILES, ids=[p.name for p in TERM_FILES])
def test_terms_import_only_the_layers_below(path):
    found = brdfkit_imports(path.read_text(encoding="utf-8"), module_name(path))
    bad = [m for m in found if not any(m == a or m.startswith(a + ".") for a in ALLOWED)]
    assert bad == [], f"{path.name} imports {bad}"


def test_the_checker_sees_facade_and_function_level_imports():
    src = "import brdfkit as bk\ndef f():\n    from ..analysis.albedo import albedo\n    from .. import registry\n"
    assert brdfkit_imports(src, "brdfkit.terms.probe") == ["brdfkit", "brdfkit.analysis.albedo", "brdfkit.registry"]


def test_htsg_model_and_series_avoid_the_facade():
    for path in (PKG / "models" / "htsg.py", TERMS / "htsg_series.py", TERMS / "special.py"):
        found = brdfkit_imports(path.read_text(encoding="utf-8"), module_name(path))
        assert "brdfkit" not in found and not [m for m in found if m.startswith("brdfkit.analysis")], path.name
