"""Every model's GLSL is valid GLSL ES 3.00 (WebGL 2, the browser explorer) and GLSL 3.30 core.

Two independent compilers check it:

* the GL driver's own (Mesa; ``#version 300 es`` is accepted by a desktop
  context through ``GL_ARB_ES3_compatibility``), as a vertex and a fragment
  shader, linked: :func:`brdfkit.render.glsl.compile_check`;
* the Khronos reference front end ``glslangValidator`` (Debian package
  ``glslang-tools``), skipped with the reason when it is not installed.

Negative controls show that the ES checks are not vacuous: code that GLSL 3.30
accepts but ES 3.00 forbids (an implicit int -> float conversion, ``double``)
is rejected in ES mode by both.
"""

from __future__ import annotations

import pytest

import brdfkit as bk
from brdfkit.render import glsl

WITH_GLSL = [n for n in bk.models() if glsl.has_shader(n)]

needs_glslang = pytest.mark.skipif(
    not glsl.glslang_available(), reason="glslangValidator not installed (Debian: apt-get install glslang-tools)"
)

_BAD_ES = {
    "implicit int->float": "vec3 brdf(vec3 wi, vec3 wo) { float x = 1; return vec3(x) * wi.z; }\n",
    "double": "vec3 brdf(vec3 wi, vec3 wo) { double x = 1.0; return vec3(float(x)) * wi.z; }\n",
}
_GOOD = "vec3 brdf(vec3 wi, vec3 wo) { return vec3(wi.z * wo.z); }\n"


@pytest.mark.parametrize("version", glsl.VERSIONS)
@pytest.mark.parametrize("name", WITH_GLSL)
def test_driver_compiles(name, version):
    glsl.compile_check(name, version)


@needs_glslang
@pytest.mark.parametrize("version", glsl.VERSIONS)
@pytest.mark.parametrize("name", WITH_GLSL)
def test_glslang_validates(name, version):
    glsl.glslang_validate(name, version)


@pytest.mark.parametrize("what", sorted(_BAD_ES))
def test_driver_rejects_what_es_forbids(what):
    src = glsl.common_source() + _BAD_ES[what]
    if what == "implicit int->float":
        glsl.compile_source(src, "330 core")  # legal desktop GLSL ...
    with pytest.raises(glsl.GLSLError):
        glsl.compile_source(src, "300 es")  # ... but not ES
    glsl.compile_source(glsl.common_source() + _GOOD, "300 es")


@needs_glslang
@pytest.mark.parametrize("what", sorted(_BAD_ES))
def test_glslang_rejects_what_es_forbids(what):
    with pytest.raises(glsl.GLSLError, match="300 es"):
        glsl.glslang_validate_source(glsl.common_source() + _BAD_ES[what], "300 es")
    glsl.glslang_validate_source(glsl.common_source() + _GOOD, "300 es")


def test_compile_errors_carry_the_log():
    with pytest.raises(glsl.GLSLError, match="(?i)error"):
        glsl.compile_source(glsl.common_source() + "vec3 brdf(vec3 wi, vec3 wo) { return undefined_thing; }\n")
    with pytest.raises(ValueError, match="version"):
        glsl.compile_source(_GOOD, "450 core")


def test_sources_keep_to_the_common_subset():
    """Textual rules the compilers cannot all see: no #version/#include, no double, one brdf()."""
    import re

    for name in WITH_GLSL:
        text = glsl.shader_path(name).read_text()
        code = re.sub(r"//[^\n]*", "", text)
        assert not re.search(r"^\s*#\s*(version|include|extension)", code, re.M), name
        assert not re.search(r"\bdouble\b|\bdvec[234]\b", code), name
        assert len(re.findall(r"\bvec3\s+brdf\s*\(\s*vec3\s+wi\s*,\s*vec3\s+wo\s*\)", code)) == 1, name
    common = re.sub(r"//[^\n]*", "", glsl.common_source())
    assert "brdf(" not in common
    assert not re.search(r"^\s*#\s*(version|include|extension)", common, re.M)
