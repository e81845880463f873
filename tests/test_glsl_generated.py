"""Generated GLSL (brdfkit.render.generate) and the ``// @include`` lines that bring it into the shaders."""

from __future__ import annotations

import re

import pytest

from brdfkit.render import generate, glsl
from brdfkit.terms import multiscatter as ms


def test_committed_files_are_what_the_generator_writes():
    """Regenerating gives exactly the committed files (else: run ``python -m brdfkit.render.generate``)."""
    assert generate.stale() == []
    for name, text in generate.GENERATED.items():
        assert (glsl.SHADER_DIR / name).read_text(encoding="utf-8") == text(), name
    assert generate.main(["--check"]) == 0


def test_generator_writes_every_file_and_only_changed_ones(tmp_path):
    assert generate.stale(tmp_path) == sorted(generate.GENERATED)
    assert generate.write(tmp_path) == sorted(generate.GENERATED)
    for name in generate.GENERATED:
        assert (tmp_path / name).read_bytes() == (glsl.SHADER_DIR / name).read_bytes()
    assert generate.write(tmp_path) == [] and generate.stale(tmp_path) == []
    (tmp_path / "multiscatter_tables.glsl").write_text("// edited by hand\n", encoding="utf-8")
    assert generate.stale(tmp_path) == ["multiscatter_tables.glsl"]
    assert not list(tmp_path.glob("*.tmp*"))  # atomic writes leave no temporary files


def test_command_line():
    assert generate.main(["--bogus"]) == 2


def test_generated_files_say_so_and_only_they():
    """Each generated file opens with the header naming the command; no other shader file carries it."""
    for path in sorted(glsl.SHADER_DIR.glob("*.glsl")):
        text = path.read_text(encoding="utf-8")
        assert text.startswith(generate.header("")[:40]) == (path.name in generate.GENERATED), path.name
    for name in generate.GENERATED:
        assert generate.COMMAND in (glsl.SHADER_DIR / name).read_text(encoding="utf-8").splitlines()[0]


def test_multiscatter_tables_are_the_shipped_tables():
    text = (glsl.SHADER_DIR / "multiscatter_tables.glsl").read_text(encoding="utf-8")
    assert text.endswith(ms.glsl_tables())
    assert "const vec4 BK_MS_MISSING4[1634]" in text


def test_microfacet_source_includes_the_tables_once():
    """The hand-written file holds no table; every assembled source (eval_glsl, renderer, explorer) has them."""
    raw = glsl.shader_path("microfacet").read_text(encoding="utf-8")
    assert "// @include multiscatter_tables.glsl" in raw
    assert "BK_MS_MISSING4[1634]" not in raw and len(raw.splitlines()) < 200
    tables = (glsl.SHADER_DIR / "multiscatter_tables.glsl").read_text(encoding="utf-8").rstrip("\n")
    for src in (glsl.shader_source("microfacet"), glsl.shader_file("microfacet.glsl")):
        assert src.count(tables) == 1
        assert not glsl.INCLUDE.search(src)
    from brdfkit.web.server import shader_payload

    assert shader_payload("microfacet").count("const vec4 BK_MS_MISSING4[1634]") == 1


def test_no_assembled_source_keeps_an_include_line():
    for path in sorted(glsl.SHADER_DIR.glob("*.glsl")):
        assert not glsl.INCLUDE.search(glsl.shader_file(path.name)), path.name


def test_include_errors_are_value_errors(tmp_path, monkeypatch):
    monkeypatch.setattr(glsl, "SHADER_DIR", tmp_path)
    (tmp_path / "a.glsl").write_text("float a;\n// @include b.glsl\n", encoding="utf-8")
    (tmp_path / "b.glsl").write_text("// @include a.glsl\n", encoding="utf-8")
    (tmp_path / "c.glsl").write_text("x\n// @include nowhere.glsl\ny\n", encoding="utf-8")
    (tmp_path / "d.glsl").write_text("head\n// @include e.glsl\ntail\n", encoding="utf-8")
    (tmp_path / "e.glsl").write_text("const float E = 1.0;\n", encoding="utf-8")
    with pytest.raises(ValueError, match="cycle: a.glsl -> b.glsl -> a.glsl"):
        glsl.shader_file("a.glsl")
    with pytest.raises(ValueError, match="c.glsl: included shader file nowhere.glsl not found"):
        glsl.shader_file("c.glsl")
    assert glsl.shader_file("d.glsl") == "head\nconst float E = 1.0;\ntail\n"
    # only a whole comment line of that form includes: not code, not an indented or trailing mention
    text = "  // @include e.glsl\nint x; // @include e.glsl\n// @include e.glsl extra\n"
    assert glsl.expand_includes(text) == text
    assert re.fullmatch(glsl.INCLUDE, "// @include e.glsl")
