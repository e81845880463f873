"""Disney BRDF Explorer's ``.brdf`` files as brdfkit models.

BRDF Explorer (Walt Disney Animation Studios, 2012, github.com/wdas/brdf) keeps
an analytic BRDF in a small text file::

    analytic
    # comment lines start with '#'
    ::begin parameters
    float NAME MIN MAX DEFAULT
    bool NAME DEFAULT            (0 or 1)
    color NAME R G B
    ::end parameters
    ::begin shader
    ... GLSL defining  vec3 BRDF(vec3 L, vec3 V, vec3 N, vec3 X, vec3 Y) ...
    ::end shader
    ::begin isFunc               (optional: an importance-sampling function)
    ...
    ::end isFunc

The grammar, as BRDF Explorer's reader applies it: the first line names the
file's type (``analytic``); every line is trimmed; blank lines and lines whose
first character is ``#`` are skipped everywhere, inside the shader too;
``::begin NAME`` / ``::end NAME`` delimit sections, which do not nest. The
application declares one uniform per parameter, named as the parameter
(``uniform float NAME``, ``uniform bool NAME``, ``uniform vec3 NAME``), and
calls ``BRDF`` with ``L`` toward the light, ``V`` toward the viewer, the normal
``N`` and the tangent frame ``X``, ``Y``; the result is the BRDF without the
cosine.

This module turns such a file into

* ``Param``\\ s: ``float`` -> ``scalar`` with the file's range, ``bool`` ->
  ``bool``, ``color`` -> ``rgb`` in [0, 1] (BRDF Explorer's colour picker);
* a GLSL source in brdfkit's shader convention (:mod:`brdfkit.render.glsl`):
  ``uniform <type> u_<NAME>`` per parameter, the file's GLSL unchanged (with
  ``#line`` directives, so compiler messages name the file's own lines), and
  ``vec3 brdf(vec3 wi, vec3 wo)`` which returns 0 below the horizon and
  otherwise calls ``BRDF(wi, wo, +z, +x, +y)``. The parameters reach the
  file's code under their own names as global variables copied from the
  ``u_`` uniforms at the start of ``brdf``.

:func:`parse_brdf_text` does the parsing (no OpenGL); :func:`load_brdf` makes a
model whose ``eval`` runs that GLSL through the headless GL context of
:func:`brdfkit.render.glsl.eval_glsl` (float32 on the GPU/llvmpipe; the result
is returned in the dtype ``eval`` promises). The shader is compiled when the
file is loaded, so a GLSL error is reported then, in one line with the
compiler's message and the file's line number.

BRDF Explorer's shaders are desktop GLSL: they rely on implicit int -> float
conversions (``1 - x``, ``clamp(x, 0, 1)``) and may redefine built-ins
(``reflect``), which GLSL 3.30 core accepts and GLSL ES 3.00 (WebGL 2) does
not; :func:`load_brdf` compiles them as 3.30 core. For WebGL,
``BrdfShader.glsl_es`` carries the source with integer literals in float
context promoted and such functions renamed, and :func:`glsl_es_source`
accepts it only after it compiled as ES 3.00 and evaluated exactly as the
original (measured: all 40 files of BRDF Explorer's own ``src/brdfs/`` pass;
4 of them compile as ES unchanged).
"""

from __future__ import annotations

import math
import os
import re
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any, ClassVar

import numpy as np

from ..params import Param

__all__ = [
    "BrdfShader", "parse_brdf_text", "parse_brdf_file", "load_brdf", "load_brdf_class", "BrdfExplorerModel",
    "promote_int_literals", "rename_builtin_overloads", "glsl_es_source", "shader_json", "parse_bparam_text",
]

_IDENT = re.compile(r"[A-Za-z_][A-Za-z0-9_]*\Z")
_BRDF_DEF = re.compile(r"\b(vec3|float)\s+BRDF\s*\(")
_GLSL_TYPES = {"scalar": "float", "rgb": "vec3", "bool": "bool"}
_SECTIONS = ("parameters", "shader", "isFunc")
#: anisotropic pairs by their conventional names (Disney's ward.brdf: alpha_x/alpha_y, ashikhman_shirley.brdf:
#: n_u/n_v, ...): a file declares no ties, so the second float of a pair it has is tied to the first
#: (Param.tie), one value when the file's model is fitted to isotropic data, as brdfkit's own models declare
ISOTROPIC_PAIRS = (("alpha_x", "alpha_y"), ("nu", "nv"), ("n_u", "n_v"), ("alpha_u", "alpha_v"), ("m_x", "m_y"),
                   ("cx_1", "cy_1"), ("cx_2", "cy_2"), ("cx_3", "cy_3"))


def _tie_pairs(params: tuple[Param, ...]) -> tuple[Param, ...]:
    """``params`` with the second float of each of :data:`ISOTROPIC_PAIRS` present tied to the first."""
    floats = {p.name for p in params if p.kind == "scalar"}
    twin = {b: a for a, b in ISOTROPIC_PAIRS if a in floats and b in floats}
    return tuple(replace(p, tie=twin[p.name]) if p.name in twin else p for p in params)


@dataclass(frozen=True)
class BrdfShader:
    """A parsed ``.brdf`` file.

    ``name``      the file name given to the parser (used in messages)
    ``params``    one :class:`~brdfkit.params.Param` per parameter line, in file order
    ``glsl``      the wrapped source in brdfkit's convention (defines ``brdf(wi, wo)``,
                  declares ``u_<param>``); without ``common.glsl`` and without a
                  ``#version`` line
    ``raw_glsl``  the file's shader section as BRDF Explorer inserts it (comment
                  lines blanked, so line k of it is line ``shader_line + k`` of the file)
    ``shader_line`` the file's line number of the first line of ``raw_glsl``
    ``returns``   ``"vec3"`` or ``"float"`` (the declared type of ``BRDF``)
    ``is_func``   the optional ``isFunc`` section (kept, not used by brdfkit)
    ``glsl_es``   ``glsl`` with the two textual fixes GLSL ES 3.00 (WebGL 2) needs
                  (:func:`rename_builtin_overloads`, :func:`promote_int_literals`);
                  not compiled here -- :func:`glsl_es_source` validates it with OpenGL
    """

    name: str
    params: tuple[Param, ...]
    glsl: str
    raw_glsl: str
    shader_line: int = 1
    returns: str = "vec3"
    is_func: str = ""
    kind: str = "analytic"
    glsl_es: str = ""
    extra: dict = field(default_factory=dict, compare=False)


def _err(name: str, lineno: int, msg: str) -> ValueError:
    return ValueError(f"{name}:{lineno}: {msg}")


def _number(name: str, lineno: int, text: str, what: str) -> float:
    try:
        x = float(text)
    except ValueError:
        raise _err(name, lineno, f"{what} must be a number, got {text!r}") from None
    if not math.isfinite(x):
        raise _err(name, lineno, f"{what} must be finite, got {text!r}")
    return x


def _param_line(name: str, lineno: int, line: str, seen: set[str]) -> Param:
    tokens = line.split()
    for i, t in enumerate(tokens):  # a trailing '# comment'
        if t.startswith("#"):
            tokens = tokens[:i]
            break
    kind = tokens[0]
    forms = {
        "float": "float NAME MIN MAX DEFAULT",
        "bool": "bool NAME DEFAULT",
        "color": "color NAME R G B",
    }
    if kind not in forms:
        raise _err(
            name, lineno, f"unknown parameter type {kind!r}; expected one of float, bool, color (e.g. '{forms['float']}')"
        )
    expected = len(forms[kind].split())
    if len(tokens) != expected:
        raise _err(name, lineno, f"expected '{forms[kind]}', got {line!r}")
    pname = tokens[1]
    if not _IDENT.match(pname) or pname.startswith("gl_") or "__" in pname:
        raise _err(name, lineno, f"parameter name {pname!r} is not a valid GLSL identifier")
    if pname in seen:
        raise _err(name, lineno, f"parameter {pname!r} is declared twice")
    seen.add(pname)
    if kind == "float":
        lo = _number(name, lineno, tokens[2], f"{pname}: MIN")
        hi = _number(name, lineno, tokens[3], f"{pname}: MAX")
        default = _number(name, lineno, tokens[4], f"{pname}: DEFAULT")
        if not lo <= hi:
            raise _err(name, lineno, f"{pname}: MIN {lo:g} is larger than MAX {hi:g}")
        if not lo <= default <= hi:
            raise _err(name, lineno, f"{pname}: DEFAULT {default:g} lies outside [{lo:g}, {hi:g}]")
        return Param(pname, "scalar", default, (lo, hi), doc=f"float parameter of the .brdf file (line {lineno})")
    if kind == "bool":
        text = tokens[2].lower()
        if text not in ("0", "1", "true", "false"):
            raise _err(name, lineno, f"{pname}: DEFAULT must be 0 or 1, got {tokens[2]!r}")
        return Param(pname, "bool", text in ("1", "true"), doc=f"bool parameter of the .brdf file (line {lineno})")
    rgb = tuple(_number(name, lineno, t, f"{pname}: {c}") for t, c in zip(tokens[2:], "RGB"))
    for c, x in zip("RGB", rgb):
        if not 0.0 <= x <= 1.0:
            raise _err(name, lineno, f"{pname}: {c} = {x:g} lies outside [0, 1]")
    return Param(pname, "rgb", rgb, (0.0, 1.0), doc=f"color parameter of the .brdf file (line {lineno})")


def _wrap(params: tuple[Param, ...], raw: str, shader_line: int, returns: str, name: str) -> str:
    """The file's GLSL in brdfkit's convention (see the module docstring)."""
    out = [f"// ---- {name}: a BRDF Explorer shader, wrapped by brdfkit.interchange.brdf_explorer ----"]
    for p in params:
        utype = "int" if p.kind == "bool" else _GLSL_TYPES[p.kind]
        out.append(f"uniform {utype} u_{p.name};")
    for p in params:
        out.append(f"{_GLSL_TYPES[p.kind]} {p.name};")
    out.append(f"#line {shader_line}")
    out.append(raw.rstrip("\n"))
    out.append("// ---- brdfkit's entry point: local frame N = +z, X = +x, Y = +y; L = wi, V = wo ----")
    out.append("vec3 brdf(vec3 bk_wi, vec3 bk_wo) {")  # prefixed: a parameter may be called wi
    out.append("    if (bk_wi.z <= 0.0 || bk_wo.z <= 0.0) return vec3(0.0);")
    for p in params:
        rhs = f"(u_{p.name} != 0)" if p.kind == "bool" else f"u_{p.name}"
        out.append(f"    {p.name} = {rhs};")
    call = "BRDF(bk_wi, bk_wo, vec3(0.0, 0.0, 1.0), vec3(1.0, 0.0, 0.0), vec3(0.0, 1.0, 0.0))"
    out.append(f"    return {'vec3(' + call + ')' if returns == 'float' else call};")
    out.append("}")
    return "\n".join(out) + "\n"


def parse_brdf_text(text: str, name: str = "<file>") -> BrdfShader:
    """Parse the text of a ``.brdf`` file; ``ValueError`` ``"NAME:LINE: what is wrong"`` if malformed."""
    if not isinstance(text, str):
        raise ValueError(f"{name}: expected the text of a .brdf file, got {type(text).__name__}")
    lines = text.splitlines()
    kind = None
    section = None
    section_line = 0
    params: list[Param] = []
    seen: set[str] = set()
    shader: list[str] | None = None
    shader_line = 0
    is_func: list[str] = []
    done: set[str] = set()
    for lineno, line in enumerate(lines, start=1):
        stripped = line.strip()
        if section == "shader":
            if stripped.split()[:1] not in (["::end"], ["::begin"]):
                # BRDF Explorer drops blank and '#' lines; blank them to keep the numbering
                shader.append("" if stripped.startswith("#") else line)
                continue
        if not stripped or stripped.startswith("#"):
            continue
        tokens = stripped.split()
        if kind is None:
            kind = tokens[0]
            if kind == "bparam":
                raise _err(name, lineno, "this is a BRDF Explorer parameter file ('bparam'), not a BRDF; "
                           "bk.load_brdf reads it together with the .brdf it names")
            if kind != "analytic":
                raise _err(name, lineno, f"the first line must be 'analytic' (the file's type), got {stripped!r}")
            continue
        if tokens[0] in ("::begin", "::end"):  # words after the section name are ignored, as BRDF Explorer does
            tokens = tokens[:2]
        if tokens[0] == "::begin":
            if len(tokens) != 2:
                raise _err(name, lineno, f"expected '::begin SECTION', got {stripped!r}")
            if section is not None:
                raise _err(name, lineno, f"'::begin {tokens[1]}' inside section '{section}' (opened on line {section_line}); sections do not nest")
            section, section_line = tokens[1], lineno
            if section in done and section in _SECTIONS:
                raise _err(name, lineno, f"section '{section}' appears twice")
            if section == "shader":
                shader, shader_line = [], lineno + 1
            continue
        if tokens[0] == "::end":
            if len(tokens) != 2 or section is None or tokens[1] != section:
                opened = f"'{section}' opened on line {section_line}" if section else "no open section"
                raise _err(name, lineno, f"'{stripped}' does not close a section ({opened})")
            done.add(section)
            section = None
            continue
        if section == "parameters":
            params.append(_param_line(name, lineno, stripped, seen))
        elif section == "isFunc":
            is_func.append(line)
        elif section is None:
            raise _err(name, lineno, f"text outside any section: {stripped!r}")
        # other sections (unknown to BRDF Explorer too) are ignored, as BRDF Explorer does
    if kind is None:
        raise ValueError(f"{name}: empty file, expected 'analytic' and a '::begin shader' section")
    if section is not None:
        raise _err(name, section_line, f"section '{section}' is never closed ('::end {section}' missing)")
    if shader is None:
        raise ValueError(f"{name}: no '::begin shader' section")
    raw = "\n".join(shader) + "\n"
    code = re.sub(r"/\*.*?\*/", lambda m: re.sub(r"[^\n]", " ", m.group(0)), raw, flags=re.S)
    code = re.sub(r"//[^\n]*", "", code)
    m = _BRDF_DEF.search(code)
    if m is None:
        raise _err(name, shader_line, "the shader section defines no 'vec3 BRDF(vec3 L, vec3 V, vec3 N, vec3 X, vec3 Y)'")
    returns = m.group(1)
    ptuple = _tie_pairs(tuple(params))
    return BrdfShader(
        name=name,
        params=ptuple,
        glsl=_wrap(ptuple, raw, shader_line, returns, name),
        raw_glsl=raw,
        shader_line=shader_line,
        returns=returns,
        is_func="\n".join(is_func) + ("\n" if is_func else ""),
        kind=kind,
        glsl_es=_wrap(ptuple, promote_int_literals(rename_builtin_overloads(raw)), shader_line, returns, name),
    )


def shader_json(shader: BrdfShader) -> dict[str, Any]:
    """A parsed file as plain JSON values (for the explorer's page): name, the parameter rows
    (as ``brdfkit info`` shows them), the wrapped GLSL, its ES 3.00 dialect and the raw shader."""
    return {
        "name": shader.name,
        "params": [p.as_row() for p in shader.params],
        "glsl": shader.glsl,
        "glsl_es": shader.glsl_es,
        "raw_glsl": shader.raw_glsl,
        "shader_line": shader.shader_line,
        "returns": shader.returns,
        "has_is_func": bool(shader.is_func),
    }


def parse_brdf_file(path: str | os.PathLike) -> BrdfShader:
    """Read and parse a ``.brdf`` file (``ValueError`` for a missing, unreadable or malformed file)."""
    p = Path(path)
    if not p.is_file():
        raise ValueError(f"{path}: no such .brdf file")
    try:
        text = p.read_text(encoding="utf-8")
    except UnicodeDecodeError:
        raise ValueError(f"{path}: not a text file (a .brdf file is UTF-8/ASCII text)") from None
    except OSError as e:
        raise ValueError(f"{path}: cannot read: {e.strerror or e}") from None
    return parse_brdf_text(text, name=str(path))


# ---------------------------------------------------------------------------
# GLSL ES 3.00 (WebGL 2): integer literals in float context
# ---------------------------------------------------------------------------
_INT_LITERAL = re.compile(r"(?<![\w.])(\d+)(?![\w.])")
_INT_CONTEXT = re.compile(r"\b(int|uint|ivec[234]|uvec[234])\b|%|<<|>>|\+\+|--|(?<!&)&(?!&)|(?<!\|)\|(?!\|)|(?<!\^)\^(?!\^)")
_BUILTINS = frozenset(
    "radians degrees sin cos tan asin acos atan sinh cosh tanh asinh acosh atanh pow exp log exp2 log2 sqrt "
    "inversesqrt abs sign floor trunc round roundEven ceil fract mod min max clamp mix step smoothstep isnan isinf "
    "length distance dot cross normalize faceforward reflect refract matrixCompMult outerProduct transpose "
    "determinant inverse lessThan lessThanEqual greaterThan greaterThanEqual equal notEqual any all not".split()
)
_FUNC_DEF = re.compile(r"\b(?:float|vec[234]|int|bool|void|mat[234]|ivec[234]|bvec[234])\s+(\w+)\s*\([^;{}]*\)\s*\{")


def rename_builtin_overloads(code: str) -> str:
    """Functions the file defines under a built-in's name (``reflect``, ``smoothstep``) renamed
    ``bk_user_<name>``, calls included: GLSL ES 3.00 forbids redefining or overloading built-ins."""
    clean = _blank_comments(code)
    names = {m.group(1) for m in _FUNC_DEF.finditer(clean)} & _BUILTINS
    for name in sorted(names):
        code = re.sub(rf"\b{name}\b(?=\s*\()", f"bk_user_{name}", code)
    return code


def _blank_comments(code: str) -> str:
    code = re.sub(r"/\*.*?\*/", lambda m: re.sub(r"[^\n]", " ", m.group(0)), code, flags=re.S)
    return re.sub(r"//[^\n]*", lambda m: " " * len(m.group(0)), code)


def promote_int_literals(code: str) -> str:
    """``1 - x`` -> ``1.0 - x``: decimal integer literals outside integer contexts become floats.

    BRDF Explorer's shaders lean on desktop GLSL's implicit int -> float
    conversion, which GLSL ES 3.00 lacks. Left alone: literals inside ``[...]``
    (indices, array sizes), in ``for (...)`` headers, and every literal of a
    statement that mentions an integer type or an integer-only operator (int
    variables). A heuristic: :func:`glsl_es_source` accepts the result only if it
    compiles as GLSL ES 3.00 and evaluates exactly as the original does.
    """
    clean = _blank_comments(code)
    out = []
    last = 0
    depth = 0  # [...] nesting
    stmt_start = 0
    i = 0
    n = len(clean)
    while i < n:
        ch = clean[i]
        if ch == "[":
            depth += 1
        elif ch == "]":
            depth = max(0, depth - 1)
        elif ch in ";{}":
            stmt_start = i + 1
        elif ch == "f" and re.match(r"for\s*\(", clean[i:]) and (i == 0 or not (clean[i - 1].isalnum() or clean[i - 1] == "_")):
            # a loop header is integer context as a whole (its three parts are split by ';')
            k, level = clean.index("(", i), 0
            while k < n:
                level += {"(": 1, ")": -1}.get(clean[k], 0)
                if level == 0:
                    break
                k += 1
            i = k + 1
            stmt_start = i
            continue
        elif ch.isdigit() and (i == 0 or not (clean[i - 1].isalnum() or clean[i - 1] in "_.")):
            m = _INT_LITERAL.match(clean, i)
            if m:
                j = m.end()
                if depth == 0:
                    stmt_end = min([k for k in (clean.find(";", j), clean.find("{", j), clean.find("}", j)) if k >= 0] or [n])
                    stmt = clean[stmt_start:stmt_end]
                    if not _INT_CONTEXT.search(stmt):
                        out.append(code[last:j] + ".0")
                        last = j
                i = j
                continue
            # a float literal such as 1e5 or 2.: skip over it
        i += 1
    out.append(code[last:])
    return "".join(out)


def glsl_es_source(cls_or_shader) -> str | None:
    """The wrapped source made valid GLSL ES 3.00 for WebGL 2, or None if that fails.

    The file's own source when it already compiles as ES 3.00; otherwise
    :func:`rename_builtin_overloads` and :func:`promote_int_literals` applied to its
    shader section, accepted only if
    (a) it compiles and links as GLSL ES 3.00 and (b) compiled as 3.30 core it
    returns the same values as the original at the parity vectors, with the
    parameters at their defaults (bit-for-bit up to 1e-6 relative). Needs the GL context.
    """
    from ..render.glsl import GLSLError, common_source, compile_source, eval_glsl, parity_vectors

    shader = cls_or_shader if isinstance(cls_or_shader, BrdfShader) else cls_or_shader.brdf_shader
    try:
        compile_source(common_source() + shader.glsl, version="300 es")
        return shader.glsl
    except GLSLError:
        pass
    glsl = shader.glsl_es
    try:
        compile_source(common_source() + glsl, version="300 es")
    except GLSLError:
        return None
    cls = model_class(shader)
    m = cls()
    v = parity_vectors(256)
    a = eval_glsl(m, v["wi"], v["wo"])
    b = eval_glsl(m, v["wi"], v["wo"], source=common_source() + glsl)
    same = np.isclose(a, b, rtol=1e-6, atol=0) | (np.isnan(a) & np.isnan(b))
    return glsl if bool(same.all()) else None


# ---------------------------------------------------------------------------
# the model
# ---------------------------------------------------------------------------
from ..models.base import BRDF  # noqa: E402  (after the parser, which needs no models)


def _compiler_line(log: str) -> str:
    """The first error line of a GL compiler log (Mesa: ``0:LINE(COL): error: ...``)."""
    lines = [ln.strip() for ln in str(log).splitlines() if ln.strip()]
    for ln in lines:
        if "error" in ln.lower() and re.match(r"^\d+:\d+", ln):
            return ln
    for ln in lines:
        if "error" in ln.lower():
            return ln
    return lines[0] if lines else "unknown GLSL error"


class BrdfExplorerModel(BRDF):
    """Base class of the models made from ``.brdf`` files (one subclass per file)."""

    name: ClassVar[str] = "brdf-explorer"
    title: ClassVar[str] = "a Disney BRDF Explorer shader"
    reference: ClassVar[str] = "B. Burley, BRDF Explorer (Walt Disney Animation Studios, 2012), .brdf file"
    isotropic: ClassVar[bool] = False  # unknown for a foreign shader: assume not
    spec: ClassVar[tuple[Param, ...]] = ()
    glsl_source: ClassVar[str] = ""  # brdfkit.render.glsl uses this instead of a shaders/ file
    #: the finite-difference step a gradient-based fitter needs: the GLSL sees the parameters as
    #: float32 uniforms, so a relative step below ~6e-8 (scipy's default 1.5e-8) changes nothing
    #: (measured: with 1e-3, fitting ggx.brdf to the microfacet it spells recovers the parameters
    #: to 1e-7; with the default step it stops at the start values' neighbourhood)
    fit_diff_step: ClassVar[float] = 1e-3
    brdf_shader: ClassVar[BrdfShader | None] = None
    source_path: ClassVar[str] = ""

    def _eval(self, wi, wo, p):
        from ..render.glsl import eval_glsl

        f = eval_glsl(self, wi, wo).astype(wi.dtype, copy=False)
        # the contract (no NaN/Inf/negative values) holds for brdfkit's own shaders by
        # construction; a foreign shader may break it at singular pairs: those become 0
        bad = ~np.isfinite(f) | (f < 0)
        if bad.any():
            f = np.where(bad, f.dtype.type(0), f)
        return f


_CLASS_CACHE: dict[tuple[str, int, int], type[BrdfExplorerModel]] = {}


def model_class(shader: BrdfShader, source_path: str = "") -> type[BrdfExplorerModel]:
    """A model class for a parsed file, with its GLSL compiled once (``ValueError`` naming the compiler's message)."""
    from ..render.glsl import GLSLError, compile_source, common_source

    cls = type(
        "BrdfFile_" + re.sub(r"\W", "_", Path(shader.name).stem),
        (BrdfExplorerModel,),
        {
            "name": shader.name,
            "title": f"BRDF Explorer shader {Path(shader.name).name}",
            "spec": shader.params,
            "glsl_source": shader.glsl,
            "brdf_shader": shader,
            "source_path": source_path,
            "__module__": __name__,
        },
    )
    try:
        compile_source(common_source() + shader.glsl, version="330 core")
    except GLSLError as e:
        raise ValueError(f"{shader.name}: GLSL error: {_compiler_line(e)}") from None
    return cls


def load_brdf_class(path: str | os.PathLike) -> type[BrdfExplorerModel]:
    """The model class of a ``.brdf`` file (cached while the file is unchanged)."""
    p = Path(path)
    try:
        st = p.stat()
    except OSError:
        raise ValueError(f"{path}: no such .brdf file") from None
    key = (str(path), st.st_mtime_ns, st.st_size)
    cls = _CLASS_CACHE.get(key)
    if cls is None:
        cls = model_class(parse_brdf_file(path), source_path=str(p.resolve()))
        _CLASS_CACHE[key] = cls
    return cls


def parse_bparam_text(text: str, name: str = "<file>") -> tuple[str, dict[str, Any]]:
    """A BRDF Explorer parameter file (``bparam BRDF_PATH`` and a ``parameters`` section of
    saved current values, as its "Save parameters" writes it) -> (BRDF path, {name: value})."""
    lines = text.splitlines()
    target = None
    section = None
    values: dict[str, Any] = {}
    for lineno, line in enumerate(lines, start=1):
        stripped = line.strip()
        if not stripped or stripped.startswith("#"):
            continue
        tokens = stripped.split()
        if target is None:
            if tokens[0] != "bparam" or len(tokens) < 2:
                raise _err(name, lineno, f"the first line must be 'bparam PATH_OF_THE_BRDF', got {stripped!r}")
            target = stripped.split(None, 1)[1]
            continue
        if tokens[0] == "::begin" and len(tokens) >= 2:
            section = tokens[1]
            continue
        if tokens[0] == "::end":
            section = None
            continue
        if section == "parameters":
            p = _param_line(name, lineno, stripped, set(values))
            values[p.name] = p.default
    if target is None:
        raise ValueError(f"{name}: empty file, expected 'bparam PATH_OF_THE_BRDF'")
    return target, values


def load_brdf(path: str | os.PathLike, **params: Any) -> BrdfExplorerModel:
    """A ``.brdf`` file as a model (parameters validated against the file's ranges).

    A BRDF Explorer parameter file (first line ``bparam PATH``) works too: the ``.brdf`` it
    names (as written, else beside the parameter file) with the saved values; ``params``
    override them.
    """
    p = Path(path)
    try:
        head = p.read_text(encoding="utf-8", errors="replace").lstrip()[:7] if p.is_file() else ""
    except OSError:
        head = ""
    if head.startswith("bparam"):
        target, saved = parse_bparam_text(p.read_text(encoding="utf-8"), name=str(path))
        brdf = Path(target)
        if not brdf.is_file():
            brdf = p.parent / Path(target).name
        if not brdf.is_file():
            raise ValueError(f"{path}: the BRDF it names, {target!r}, is not found (nor beside the parameter file)")
        cls = load_brdf_class(brdf)
        known = {q.name for q in cls.spec}
        saved = {k: v for k, v in saved.items() if k in known}  # as BRDF Explorer syncs them: by name
        saved.update(params)
        return cls(**saved)
    return load_brdf_class(path)(**params)
