"""What a user names -> a model: the one place that decides.

Every command, the Python API (``bk.model``, ``bk.fit``, ``bk.load_measured``),
scenes, the fitter and the web API turn a *source* into a model here, so that
a new kind of source (a file format) is added once and works everywhere.

Kinds of source, in the order they are tried
--------------------------------------------
``instance``  a :class:`~brdfkit.models.base.BRDF` object, taken as it is
``model``     a registered model name (``brdfkit list``); takes parameters
``material``  a built-in measured material, ``merl/chrome`` or a unique bare ``chrome``
``brdf``      a Disney BRDF Explorer ``.brdf`` file (its GLSL); takes parameters
``fit``       a fit's JSON (``brdfkit fit ... --json > fit.json``); parameters override the fitted ones
``merl``      a MERL ``.binary`` file (Matusik et al. 2003); also any existing file of another suffix
``bin``       a ``.bin`` file, told by content: UTIA (Filip & Vávra 2014; headerless, exactly
              1 990 656 bytes) or else MERL (12-byte header)
``rgl``       an RGL ``.bsdf`` file (Dupuy & Jakob 2018, as Mitsuba 3's ``measured`` reads it)

File kinds are chosen by suffix (:data:`FILE_KINDS`, case-insensitive). Measured
data (``material``, ``merl``) takes no parameters. :func:`resolve` with
``files=False`` refuses every file kind: the web server must never read a file
of a request's choosing.

Errors are one-line ``ValueError``\\ s naming the source and what would work.
"""

from __future__ import annotations

import difflib
import json
import os
from dataclasses import dataclass
from typing import Any, Callable, Iterable, Mapping

import numpy as np

from . import registry
from .models.base import BRDF
from .params import parse_assignments

#: kinds that take parameters (a parameter table to parse ``-p`` against)
PARAMETRIC = ("model", "brdf", "fit")
#: kinds that are measured data (no parameters)
MEASURED = ("material", "merl", "bin", "rgl")
#: kinds read from a file
FILES = ("brdf", "fit", "merl", "bin", "rgl")


@dataclass(frozen=True)
class Source:
    """A resolved source: its ``kind`` (see the module docstring) and the text or object it came from."""

    kind: str
    text: str
    obj: Any = None  # the BRDF instance for ``instance``

    @property
    def is_measured(self) -> bool:
        return self.kind in MEASURED

    def model_class(self) -> type[BRDF]:
        """The class whose parameter table applies: registered model, ``.brdf`` shader or the fitted model."""
        if self.kind == "model":
            return registry.get(self.text)
        if self.kind == "brdf":
            from .interchange.brdf_explorer import load_brdf_class

            return load_brdf_class(self.text)
        if self.kind == "fit":
            return registry.get(_read_fit_json(self.text)[0])
        if self.kind == "instance":
            return type(self.obj)
        raise ValueError(f"{self.text}: measured data has no parameter table")

    def build(self, params: Mapping[str, Any] | None = None) -> BRDF:
        """The model, with ``params`` (already parsed values) set on parametric kinds."""
        params = dict(params or {})
        if self.kind == "instance":
            if params:
                raise ValueError(f"{_label(self.obj)}: a model object takes no further parameters ({next(iter(params))})")
            return self.obj
        if self.kind in MEASURED and params:
            raise ValueError(f"{self.text}: measured data takes no parameters; drop {next(iter(params))}")
        return _BUILDERS[self.kind](self.text, params)


def _label(model: Any) -> str:
    return getattr(model, "label", None) or getattr(model, "name", type(model).__name__)


# -- builders, one per kind --------------------------------------------------------------
def _build_model(name: str, params: dict) -> BRDF:
    return registry.get(name)(**params)


def _build_material(name: str, params: dict) -> BRDF:
    from .measured.nbrdf import material

    return material(name)


def _build_brdf(path: str, params: dict) -> BRDF:
    from .interchange.brdf_explorer import load_brdf

    return load_brdf(path, **params)


def _build_merl(path: str, params: dict) -> BRDF:
    from .measured.merl import load_merl

    return load_merl(path)


def _build_bin(path: str, params: dict) -> BRDF:
    """A ``.bin`` file: UTIA (headerless, exactly 3·6·48·6·48 float64) or MERL (12-byte 90,90,180 header)."""
    from .measured.utia import FILE_BYTES, load_utia

    if os.path.isfile(path) and os.path.getsize(path) == FILE_BYTES:
        with open(path, "rb") as fh:
            head = fh.read(12)
        if head != b"Z\0\0\0Z\0\0\0\xb4\0\0\0":  # MERL's int32 header 90, 90, 180
            return load_utia(path)
    from .measured.merl import load_merl

    return load_merl(path)


def _build_rgl(path: str, params: dict) -> BRDF:
    from .measured.rgl import load_rgl

    return load_rgl(path)


def _read_fit_json(path: str) -> tuple[str, dict[str, Any], str | None]:
    """(model name, fitted parameters, source label) of a ``brdfkit fit ... --json`` file."""
    try:
        with open(path, encoding="utf-8") as fh:
            obj = json.load(fh)
    except OSError as e:
        raise ValueError(f"{path}: cannot read: {e.strerror or e}") from None
    except (json.JSONDecodeError, UnicodeDecodeError) as e:
        raise ValueError(f"{path}: not valid JSON ({e})") from None
    if isinstance(obj, list) and len(obj) == 1:
        obj = obj[0]
    if not isinstance(obj, dict) or not isinstance(obj.get("model"), str) or not isinstance(obj.get("params"), dict):
        raise ValueError(f"{path}: expected the JSON of 'brdfkit fit ... --json' (an object with 'model' and 'params')")
    params = {k: (np.asarray(v, dtype=np.float64) if isinstance(v, list) else v)
              for k, v in obj["params"].items() if v is not None}
    src = obj.get("source")
    return obj["model"], params, src if isinstance(src, str) else None


def _build_fit(path: str, params: dict) -> BRDF:
    name, fitted, src = _read_fit_json(path)
    model = registry.get(name)(**dict(fitted, **params))
    model.label = f"{name} fitted to {src}" if src else name
    return model


_BUILDERS: dict[str, Callable[[str, dict], BRDF]] = {
    "model": _build_model,
    "material": _build_material,
    "brdf": _build_brdf,
    "fit": _build_fit,
    "merl": _build_merl,
    "bin": _build_bin,
    "rgl": _build_rgl,
}

#: file suffix (lower case) -> kind. A reader of a new format adds its suffix here and its builder above.
FILE_KINDS: dict[str, str] = {".brdf": "brdf", ".json": "fit", ".binary": "merl", ".bin": "bin", ".bsdf": "rgl"}
#: what an existing file of no known suffix is read as (MERL's reader checks its header and size)
DEFAULT_FILE_KIND = "merl"


# -- deciding the kind ---------------------------------------------------------------------
def _material_name(text: str) -> str | None:
    """The full ``set/name`` when ``text`` names a built-in measured material, else None."""
    from .measured.nbrdf import materials

    names = materials()
    if text in names:
        return text
    bare = [n for n in names if n.split("/", 1)[1] == text]
    return bare[0] if len(bare) == 1 else None


def _suffix(text: str) -> str:
    return os.path.splitext(text)[1].lower()


def _looks_like_path(text: str) -> bool:
    from .measured.nbrdf import SETS

    head = text.split("/", 1)[0]
    return (text.startswith((".", os.sep, "~")) or _suffix(text) != ""
            or (os.sep in text and head not in SETS) or text.count("/") > 1)


def _unknown(text: str, files: bool = True) -> ValueError:
    from .measured.nbrdf import SETS, materials, resolve as resolve_material

    names = materials()
    if ("/" in text and text.split("/", 1)[0] in SETS) or sum(n.split("/", 1)[1] == text for n in names) > 1:
        try:
            resolve_material(text)  # raises with its "did you mean" hint
        except ValueError as e:
            return e
    shown = text if len(text) <= 80 and text.isprintable() else repr(text[:80]) + "..."
    near = difflib.get_close_matches(text, list(registry.names()) + [n.split("/", 1)[1] for n in names], n=3, cutoff=0.6)
    hint = f"; did you mean {', '.join(near)}?" if near else ""
    files_too = f"; or a file: {', '.join(sorted(FILE_KINDS))}" if files else ""
    return ValueError(f"unknown model {shown!r}{hint} (valid models: {', '.join(registry.names())}; "
                      f"or a built-in measured material, see `brdfkit list --measured`{files_too})")


def identify(source: Any, *, files: bool = True) -> Source:
    """The :class:`Source` that ``source`` names, without building it (a file is checked to exist, not read)."""
    if isinstance(source, BRDF):
        return Source("instance", _label(source), source)
    if isinstance(source, os.PathLike):
        source = os.fspath(source)
    if not isinstance(source, str):
        raise ValueError(f"a model must be a name, a file path or a model object, got {type(source).__name__}")
    if source in registry.names():
        return Source("model", source)
    material = _material_name(source)
    if material is not None:
        return Source("material", material)
    kind = FILE_KINDS.get(_suffix(source))
    path_like = kind is not None or _looks_like_path(source)
    if not files:  # decided on the text alone: nothing on disk is looked at
        raise _no_files() if path_like else _unknown(source, files=False)
    if not path_like and not os.path.exists(source):
        raise _unknown(source)
    if not os.path.isfile(source):
        raise ValueError(f"{source}: " + _MISSING.get(kind, _MISSING[None]))
    return Source(kind or DEFAULT_FILE_KIND, source)


def _no_files() -> ValueError:
    return ValueError("model: a name is expected; file paths are not accepted over HTTP (drop the file on the page)")


def resolve(source: Any, params: Mapping[str, Any] | None = None, *, files: bool = True,
            kinds: Iterable[str] | None = None) -> BRDF:
    """The model ``source`` names, with ``params`` set (parametric kinds only).

    ``files=False`` refuses file paths; ``kinds`` restricts the accepted kinds
    (e.g. :data:`MEASURED`), with a one-line error naming what was expected.
    """
    src = identify(source, files=files)
    if kinds is not None:
        kinds = tuple(kinds)
        if src.kind not in kinds:
            raise ValueError(f"{src.text}: expected {' or '.join(_KIND_WORDS[k] for k in kinds)}, "
                             f"got {_KIND_WORDS[src.kind]}")
    return src.build(params)


def model(name: Any, **params: Any) -> BRDF:
    """``resolve(name, params)``: what ``bk.model`` is (the facade re-exports it)."""
    return resolve(name, params)


def from_cli(source: Any, items: Iterable[str] | None = None, *, files: bool = True) -> BRDF:
    """:func:`resolve` with ``-p name=value`` strings parsed against the source's parameter table."""
    items = list(items or ())
    src = identify(source, files=files)
    if src.kind in MEASURED:
        if items:
            raise ValueError(f"{src.text}: measured data takes no parameters; drop -p {items[0]}")
        return src.build()
    cls = src.model_class()
    return src.build(parse_assignments(getattr(cls, "name", src.text), cls.spec, items))


def model_class(source: Any, *, files: bool = True) -> type[BRDF]:
    """The class (parameter table, ``info()``) of a parametric source."""
    return identify(source, files=files).model_class()


def load_measured(path: str | os.PathLike) -> BRDF:
    """A measured-data file as a model (its format by suffix: :data:`FILE_KINDS`)."""
    text = os.fspath(path)
    kind = FILE_KINDS.get(_suffix(text), DEFAULT_FILE_KIND)
    if kind not in MEASURED:
        raise ValueError(f"{text}: not a measured-data file (a {_KIND_WORDS[kind]})")
    if not os.path.isfile(text):
        raise ValueError(f"{text}: no such file")
    return Source(kind, text).build()


_MISSING = {
    "brdf": "no such .brdf file",
    "merl": "no such MERL file",
    "bin": "no such .bin file (MERL or UTIA)",
    "rgl": "no such RGL .bsdf file",
    "fit": "no such file (a fit's JSON: brdfkit fit ... --json > FILE)",
    None: "no such file (nor a model or a built-in measured material: see `brdfkit list`, `brdfkit list --measured`)",
}

_KIND_WORDS = {
    "instance": "a model object",
    "model": "a registered model",
    "material": "a built-in measured material",
    "brdf": "a BRDF Explorer .brdf file",
    "fit": "a fit's JSON",
    "merl": "a MERL .binary file",
    "bin": "a MERL or UTIA .bin file",
    "rgl": "an RGL .bsdf file",
}

__all__ = ["Source", "identify", "resolve", "model", "from_cli", "model_class", "load_measured",
           "FILE_KINDS", "PARAMETRIC", "MEASURED", "FILES"]
