"""``bk.tabulate`` / ``brdfkit tabulate``: any model written as a measured-data file.

Formats (``format``, or told by the suffix of ``path``):

=======  ==========  =============================================================================
format   suffix      what is written
=======  ==========  =============================================================================
merl     ``.binary``  the model at the 90 x 90 x 180 bin centres of MERL's half/difference angles
                     (:func:`brdfkit.measured.merl.tabulate`); isotropic models only
rgl      ``.bsdf``    Dupuy & Jakob's adaptive parameterization built from the model
                     (:mod:`brdfkit.measured.rgl_writer`): isotropic or anisotropic, RGB; Mitsuba 3's
                     ``measured`` plugin and :mod:`brdfkit.measured.rgl` read it
=======  ==========  =============================================================================

RGL options (defaults in brackets): ``resolution`` [64] samples per side of each incident
direction's tables (``vndf``, ``rgb``, ``luminance``); ``n_theta`` [32] incident elevations;
``n_phi`` [1 for an isotropic model, else 10 per quarter turn of the wedge the model's symmetry
leaves, + 1] incident azimuths; ``ndf_resolution`` [64] nodes per side of ``ndf`` and ``sigma``;
``isotropic`` [the model's own attribute]; ``description`` [source and brdfkit version].

The output path is checked before any work (its folder, its suffix); the file is written
atomically (:mod:`brdfkit.fileio`). The result reports the **tabulation error**: the written file
is read back with brdfkit's reader and compared with the source on ``error_pairs`` [20000]
direction pairs uniform over the two hemispheres (fixed seed), as the relative RMS of
``f_r cos θi cos θo`` over the three channels,
``sqrt(Σ (file − model)² / Σ model²)`` (the cosines weight each pair by the light it carries).
"""

from __future__ import annotations

import contextlib
import os
import time
from dataclasses import asdict, dataclass, field
from typing import Any, Callable, Mapping

import numpy as np

FORMATS = {"merl": ".binary", "rgl": ".bsdf"}
_ARTICLE = {"merl": "a MERL", "rgl": "an RGL"}
#: accepted ranges of the RGL options
LIMITS = {"resolution": (4, 512), "n_theta": (2, 256), "n_phi": (3, 720), "ndf_resolution": (8, 128)}
ERROR_PAIRS = 20000
_ERROR_SEED = 20180


@dataclass
class TabulateResult:
    """What :func:`tabulate` wrote: ``path``, ``format``, ``bytes``, ``shape`` (the tables' sizes),
    ``error`` (the tabulation error, see the module docstring) on ``error_pairs`` pairs, ``seconds``."""

    path: str
    format: str
    source: str
    bytes: int
    shape: dict = field(default_factory=dict)
    error: float | None = None
    error_pairs: int = 0
    error_measure: str = "relative RMS of f_r cos(theta_i) cos(theta_o) over pairs uniform on the hemispheres"
    seconds: float = 0.0

    def to_json(self) -> dict[str, Any]:
        return asdict(self)


def random_pairs(n: int, seed: int = _ERROR_SEED) -> tuple[np.ndarray, np.ndarray]:
    """``n`` pairs of directions uniform (in solid angle) over the upper hemisphere."""
    rng = np.random.default_rng(seed)

    def dirs():
        z = rng.uniform(0.0, 1.0, n)
        p = rng.uniform(-np.pi, np.pi, n)
        s = np.sqrt(np.maximum(1 - z * z, 0.0))
        return np.stack([s * np.cos(p), s * np.sin(p), z], axis=1)

    return dirs(), dirs()


def tabulation_error(model, table, n: int = ERROR_PAIRS, seed: int = _ERROR_SEED) -> float:
    """Relative RMS of ``f_r cos θi cos θo`` of ``table`` against ``model`` (module docstring)."""
    wi, wo = random_pairs(n, seed)
    w = (wi[:, 2] * wo[:, 2])[:, None]
    a = np.asarray(model.eval(wi, wo), dtype=np.float64) * w
    b = np.asarray(table.eval(wi, wo), dtype=np.float64) * w
    den = float(np.sum(a * a))
    return float(np.sqrt(np.sum((a - b) ** 2) / den)) if den > 0 else float(np.sqrt(np.sum(b * b)))


# ----------------------------------------------------------------- checking the request
def _format_of(path: str, fmt: str | None) -> str:
    suffix = os.path.splitext(path)[1].lower()
    if fmt is None:
        for name, suf in FORMATS.items():
            if suffix == suf:
                return name
        raise ValueError(f"cannot tell the format from {path!r}: give format 'merl' (.binary) or 'rgl' (.bsdf)")
    if not isinstance(fmt, str) or fmt.lower() not in FORMATS:
        raise ValueError(f"unknown format {fmt!r}; valid formats: merl (.binary), rgl (.bsdf)")
    fmt = fmt.lower()
    if suffix != FORMATS[fmt]:
        raise ValueError(f"{_ARTICLE[fmt]} file must end in {FORMATS[fmt]} (so that it is read back as {fmt}), "
                         f"got {path!r}")
    return fmt


def _check_int(name: str, value) -> int:
    lo, hi = LIMITS[name]
    if isinstance(value, bool) or not isinstance(value, (int, np.integer)):
        raise ValueError(f"{name} must be a whole number in [{lo}, {hi}], got {value!r}")
    if not lo <= int(value) <= hi:
        raise ValueError(f"{name} must lie in [{lo}, {hi}], got {int(value)}")
    return int(value)


def _rgl_options(fmt: str, opts: Mapping[str, Any]) -> dict[str, Any]:
    """The RGL options, checked (one line each); for MERL, none may be given."""
    from .rgl_writer import DEFAULTS

    given = {k: v for k, v in opts.items() if v is not None}
    if fmt == "merl":
        if given:
            raise ValueError(f"{next(iter(given))} applies to format 'rgl' only (a MERL file has fixed bins)")
        return {}
    out = dict(DEFAULTS, isotropic=None, description=None)
    for k, v in given.items():
        if k in LIMITS:
            out[k] = _check_int(k, v)
        elif k == "isotropic":
            if not isinstance(v, (bool, np.bool_)):
                raise ValueError(f"isotropic must be true or false, got {v!r}")
            out[k] = bool(v)
        elif k == "description":
            if not isinstance(v, str):
                raise ValueError(f"description must be text, got {type(v).__name__}")
            out[k] = v
    return out


def _check_size(opts: dict[str, Any], isotropic: bool) -> None:
    """Refuse a file brdfkit's own reader would refuse (:data:`brdfkit.measured.rgl.MAX_TABLE_BYTES`)."""
    from .rgl import MAX_TABLE_BYTES
    from .rgl_writer import PHI_PER_QUARTER

    n_phi = opts.get("n_phi") or (1 if isotropic else 4 * PHI_PER_QUARTER + 1)
    per_slice = 4 * opts["resolution"] ** 2  # vndf + 3 rgb
    work = (n_phi * opts["n_theta"] * per_slice + 2 * opts["ndf_resolution"] ** 2) * 8 * 3
    if work > MAX_TABLE_BYTES:
        raise ValueError(f"tables of {work >> 20} MiB in memory, more than the reader's limit of "
                         f"{MAX_TABLE_BYTES >> 20} MiB: lower resolution, n_theta or n_phi")


# ----------------------------------------------------------------- the work
@contextlib.contextmanager
def _bar(progress, title: str):
    """``step(done, total)`` for :func:`rgl_tables`: a rich bar (``progress=True``, started at the
    first step, when the total is known), a callback, or nothing."""
    from .progress import fit_progress

    with contextlib.ExitStack() as stack:
        state: dict[str, Any] = {}

        def step(done: int, total: int) -> None:
            if "step" not in state:
                state["step"] = stack.enter_context(fit_progress(progress, title, total, "incident directions"))
            state["step"](done)

        yield step if progress else None


def _describe(source_text: str, params: Mapping[str, Any] | None) -> str:
    from .._version import __version__

    items = " ".join(f"{k}={v}" for k, v in (params or {}).items())
    return (f"{source_text}{' ' + items if items else ''}, tabulated by brdfkit {__version__} "
            "(Dupuy & Jakob 2018 parameterization)")


def tabulate(source, path, format: str | None = None, *, params: Mapping[str, Any] | None = None,
             resolution: int | None = None, n_theta: int | None = None, n_phi: int | None = None,
             ndf_resolution: int | None = None, isotropic: bool | None = None, description: str | None = None,
             error_pairs: int = ERROR_PAIRS, progress: bool | Callable[[int, int], None] = False,
             model=None) -> TabulateResult:
    """Write ``source`` (any model :mod:`brdfkit.sources` resolves, with ``params``) to ``path``
    as a MERL ``.binary`` or RGL ``.bsdf`` file; see the module docstring. Returns a
    :class:`TabulateResult`. Bad input: a one-line ``ValueError`` before any work.

    ``model``: the already-built model of ``source`` (the CLI resolves it with ``-p`` strings)."""
    from .. import sources
    from ..fileio import check_output_path

    t0 = time.perf_counter()
    path = os.fspath(path)
    if not isinstance(path, str) or path == "":
        raise ValueError("output path is empty")
    fmt = _format_of(path, format)
    opts = _rgl_options(fmt, dict(resolution=resolution, n_theta=n_theta, n_phi=n_phi,
                                  ndf_resolution=ndf_resolution, isotropic=isotropic, description=description))
    if isinstance(error_pairs, bool) or not isinstance(error_pairs, (int, np.integer)) or error_pairs < 0:
        raise ValueError(f"error_pairs must be a whole number >= 0, got {error_pairs!r}")
    check_output_path(path, what=f"{fmt.upper()} file", suffixes=(FORMATS[fmt],))
    if model is None:
        model = sources.resolve(source, params)
    label = getattr(model, "label", None) or getattr(model, "name", "") or type(model).__name__
    src_text = source if isinstance(source, str) else os.fspath(source) if isinstance(source, os.PathLike) else label
    if fmt == "merl":
        from .merl import tabulate as merl_table, write_merl_table

        write_merl_table(merl_table(model), path)
        shape = {"theta_h": 90, "theta_d": 90, "phi_d": 180}
    else:
        from .rgl_writer import rgl_tables
        from .tensor_file import write_tensor_file

        iso = bool(getattr(model, "isotropic", False)) if opts["isotropic"] is None else opts["isotropic"]
        _check_size(opts, iso)
        desc = opts["description"] if opts["description"] is not None else _describe(src_text, params)
        with _bar(progress, f"tabulate {label} → {os.path.basename(path)}") as step:
            tables = rgl_tables(model, resolution=opts["resolution"], n_theta=opts["n_theta"],
                                n_phi=opts["n_phi"], ndf_resolution=opts["ndf_resolution"],
                                isotropic=iso, description=desc, progress=step)
        write_tensor_file(path, tables.fields)
        f = tables.fields
        shape = {"n_phi": len(f["phi_i"]), "n_theta": len(f["theta_i"]), "resolution": int(f["rgb"].shape[-1]),
                 "ndf": list(f["ndf"].shape), "isotropic": tables.isotropic, "reduction": tables.reduction,
                 "ndf_power_steps": tables.ndf_steps}
    error = None
    if error_pairs:
        error = tabulation_error(model, sources.load_measured(path), int(error_pairs))
    return TabulateResult(path=path, format=fmt, source=str(src_text), bytes=os.path.getsize(path), shape=shape,
                          error=error, error_pairs=int(error_pairs), seconds=round(time.perf_counter() - t0, 3))


__all__ = ["tabulate", "TabulateResult", "tabulation_error", "random_pairs", "FORMATS"]
