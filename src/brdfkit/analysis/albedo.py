"""Directional albedo (energy conservation) of any BRDF, by deterministic quadrature.

The directional albedo seen from the viewing direction ``wo`` is

    a(wo) = ∫_{H²} f_r(wi, wo) cos θi dωi,

the radiance a surface shows inside a white furnace (unit radiance from every
direction). For a reciprocal BRDF it equals the *directional-hemispherical
reflectance* of light arriving from ``wo``, ρ(wi) = ∫ f_r(wi, wo) cos θo dωo,
the fraction of the incident energy that is reflected; energy conservation
demands ρ ≤ 1 (Nicodemus et al. 1977, *Geometrical considerations and
nomenclature for reflectance*, NBS Monograph 160). :func:`albedo` computes
either integral (``over="wi"`` or ``over="wo"``).

Quadrature
----------
The model is a black box, so the integral is taken with two product rules
(*charts*) that both cover the whole hemisphere exactly, horizon included,
and both concentrate their nodes where glossy lobes live:

``H`` (half-vector chart)
    wi is parameterised by the half vector h = (θh, φh) around the normal:
    wi = 2 (wo·h) h − wo, dωi = 4 (wo·h) dωh (Walter et al. 2007, eq. 14).
    Half-vector lobes (Blinn-Phong, Cook-Torrance, microfacet, Ward,
    Ashikhmin-Shirley) are round in these coordinates. The set of h whose wi
    lies above the horizon is, with c = cos θo, s = sin θo, measuring φh from
    the azimuth of wo,

        cos φh > −(c/s) cot 2θh,   θh < π/4 + θo/2,

    so each ring θh is integrated over exactly the arc that is visible
    (a full circle for θh ≤ π/4 − θo/2). θh is split into panels whose
    widths double from 1e-5 rad (Gauss-Legendre on each), so a lobe of any
    width from 1e-4 rad up is resolved; in the clipped range a smoothstep
    substitution removes the square-root end-point behaviour of the arc
    length.

``R`` (mirror chart)
    wi in polar coordinates (ψ, β) around the mirror direction r = reflect(wo):
    wi = cos ψ r + sin ψ (cos β t1 + sin β t2), dωi = sin ψ dψ dβ. Mirror lobes
    (Phong) are round here. The horizon is at ψ = π/2 + atan2(s cos β, c), so
    every ray β is integrated up to the horizon exactly; ψ has the same
    doubling panels.

Each chart is evaluated at two resolutions; the difference is the chart's
error estimate, and the chart with the smaller estimate gives the answer
(the finer of its two results). The estimate is reported with the value:
:func:`albedo` with ``return_error=True``.
"""

from __future__ import annotations

import contextlib
import functools
import hashlib
import math
import threading
import zipfile
from dataclasses import dataclass
from typing import Any

import numpy as np

from ..geometry import normalize, reflect, rotate_z, spherical_to_vector

# panel boundaries shared by both charts: 0, 1e-5, 2e-5, 4e-5, ... (doubling)
_SMALLEST_PANEL = 1e-5
_BREAKS = np.concatenate([[0.0], _SMALLEST_PANEL * 2.0 ** np.arange(0, 40)])
_BREAKS = _BREAKS[_BREAKS < math.pi]
# the mirror chart also breaks at ψ = π/2, where clamped lobes max(0, r·wo)^s have their kink
_BREAKS_R = np.sort(np.concatenate([_BREAKS, [math.pi / 2]]))

#: (nodes per radial panel, angular nodes) of the coarse and fine rules
LEVELS = {
    "fast": ((5, 32), (8, 56)),
    "normal": ((6, 48), (10, 80)),
    "fine": ((10, 80), (16, 128)),
}
DEFAULT_LEVEL = "normal"


@functools.lru_cache(maxsize=None)
def _gl(n: int) -> tuple[np.ndarray, np.ndarray]:
    """Gauss-Legendre nodes and weights on [0, 1]."""
    x, w = np.polynomial.legendre.leggauss(n)
    return 0.5 * (x + 1.0), 0.5 * w


@functools.lru_cache(maxsize=None)
def _smoothstep(n: int) -> tuple[np.ndarray, np.ndarray]:
    """Gauss-Legendre on [0,1] pushed through t = 3u² − 2u³ (zero slope at both ends)."""
    u, w = _gl(n)
    return 3 * u**2 - 2 * u**3, w * 6 * u * (1 - u)


def _panels(lo: np.ndarray, hi: np.ndarray, b: np.ndarray = _BREAKS) -> tuple[np.ndarray, np.ndarray]:
    """Clip the panels ``b`` to [lo, hi] (arrays broadcast): (starts, ends) of shape (..., P)."""
    a = np.clip(b[:-1], lo[..., None], hi[..., None])
    e = np.clip(b[1:], lo[..., None], hi[..., None])
    # the last panel reaches hi whatever hi is
    tail_a = np.clip(b[-1], lo, hi)[..., None]
    tail_e = hi[..., None] + 0.0 * tail_a
    return np.concatenate([a, tail_a], -1), np.concatenate([e, tail_e], -1)


@functools.lru_cache(maxsize=128)
def _half_vector_rule0(theta_o: float, nr: int, na: int) -> tuple[np.ndarray, np.ndarray]:
    """Chart H for wo in the xz-plane (φo = 0); see :func:`half_vector_rule`."""
    c, s = math.cos(theta_o), math.sin(theta_o)
    wo = np.array([s, 0.0, c])
    th_b = math.pi / 4 - theta_o / 2  # rings below are full circles
    th_top = math.pi / 4 + theta_o / 2  # no visible h beyond
    nodes, weights = [], []
    # -- full rings: θh in [0, th_b], φh trapezoid on the circle
    a, e = _panels(np.asarray(0.0), np.asarray(th_b))
    keep = e > a
    a, e = a[keep], e[keep]
    x, w = _gl(nr)
    th = (a[:, None] + (e - a)[:, None] * x).ravel()
    wth = ((e - a)[:, None] * w).ravel()
    ph = 2 * math.pi * (np.arange(na) + 0.5) / na
    wph = np.full(na, 2 * math.pi / na)
    TH, PH = np.meshgrid(th, ph, indexing="ij")
    W = wth[:, None] * wph[None, :]
    nodes.append((TH.ravel(), PH.ravel()))
    weights.append(W.ravel())
    # -- clipped rings: θh in [th_b, th_top], φh in [−φmax, φmax]
    if th_top > th_b:
        a, e = _panels(np.asarray(th_b), np.asarray(th_top))
        keep = e > a
        a, e = a[keep], e[keep]
        x, w = _smoothstep(nr)
        th = (a[:, None] + (e - a)[:, None] * x).ravel()
        wth = ((e - a)[:, None] * w).ravel()
        ok = wth > 0
        th, wth = th[ok], wth[ok]
        with np.errstate(divide="ignore", invalid="ignore"):
            arg = -(c / s) / np.tan(2 * th) if s > 0 else np.full_like(th, -np.inf)
        arg = np.where(np.isfinite(arg), arg, np.where(2 * th > math.pi / 2, 1.0, -1.0))
        phmax = np.arccos(np.clip(arg, -1.0, 1.0))
        xg, wg = _gl(na)
        PH = -phmax[:, None] + 2 * phmax[:, None] * xg[None, :]
        W = wth[:, None] * (2 * phmax[:, None] * wg[None, :])
        TH = np.broadcast_to(th[:, None], PH.shape)
        nodes.append((TH.ravel(), PH.ravel()))
        weights.append(W.ravel())
    TH = np.concatenate([n[0] for n in nodes])
    PH = np.concatenate([n[1] for n in nodes])
    W = np.concatenate(weights)
    h = spherical_to_vector(TH, PH)
    oh = h @ wo
    wi = normalize(reflect(wo, h))
    W = W * np.sin(TH) * 4 * np.maximum(oh, 0.0)
    return _frozen(wi, W)


@functools.lru_cache(maxsize=128)
def _mirror_rule0(theta_o: float, nr: int, na: int) -> tuple[np.ndarray, np.ndarray]:
    """Chart R for wo in the xz-plane (φo = 0); see :func:`mirror_rule`."""
    c, s = math.cos(theta_o), math.sin(theta_o)
    r = np.array([-s, 0.0, c])
    t1 = np.array([c, 0.0, s])
    t2 = np.array([0.0, 1.0, 0.0])
    # β panels: eighths of the circle, refined geometrically toward β = ±π/2, where the
    # horizon ψmax(β) turns fastest (over a width ~ c/s when wo is grazing)
    brk = list(np.arange(9) * (math.pi / 4))
    d = c / 4
    while d < math.pi / 8:
        brk += [math.pi / 2 - d, math.pi / 2 + d, 3 * math.pi / 2 - d, 3 * math.pi / 2 + d]
        d *= 4
    brk = np.unique(np.asarray(brk))
    nb = max(4, na // 8)
    xg, wg = _gl(nb)
    beta = (brk[:-1, None] + np.diff(brk)[:, None] * xg).ravel()
    wb = (np.diff(brk)[:, None] * wg).ravel()[:, None, None]
    psimax = math.pi / 2 + np.arctan2(s * np.cos(beta), c)  # (na,)
    a, e = _panels(np.zeros(beta.size), psimax, _BREAKS_R)  # (nβ, P)
    x, w = _gl(nr)
    PS = a[..., None] + (e - a)[..., None] * x  # (na, P, nr)
    WP = (e - a)[..., None] * w
    keep = WP > 0
    B = np.broadcast_to(beta[:, None, None], PS.shape)[keep]
    PS = PS[keep]
    W = (WP * wb)[keep] * np.sin(PS)
    sp = np.sin(PS)
    wi = (
        np.cos(PS)[:, None] * r
        + (sp * np.cos(B))[:, None] * t1
        + (sp * np.sin(B))[:, None] * t2
    )
    return _frozen(wi, W)


def _frozen(*arrays: np.ndarray) -> tuple[np.ndarray, ...]:
    for a in arrays:
        a.setflags(write=False)
    return arrays


@functools.lru_cache(maxsize=128)
def _polar_rule0(theta_o: float, nr: int, na: int) -> tuple[np.ndarray, np.ndarray]:
    """Chart D for wo in the xz-plane (φo = 0); see :func:`polar_rule`."""
    mo = math.cos(theta_o)
    mb = np.unique(np.concatenate([np.linspace(0.0, mo, 3), np.linspace(mo, 1.0, 3)]))
    mb = mb[np.concatenate([[True], np.diff(mb) > 1e-12])]
    x, w = _gl(nr)
    mu = (mb[:-1, None] + np.diff(mb)[:, None] * x).ravel()
    wmu = (np.diff(mb)[:, None] * w).ravel()
    pb = np.arange(9) * (math.pi / 4)
    xg, wg = _gl(max(4, na // 8))
    ph = (pb[:-1, None] + np.diff(pb)[:, None] * xg).ravel()
    wph = (np.diff(pb)[:, None] * wg).ravel()
    MU, PH = np.meshgrid(mu, ph, indexing="ij")
    st = np.sqrt(np.maximum(0.0, 1 - MU**2))
    wi = np.stack([st * np.cos(PH), st * np.sin(PH), MU], -1).reshape(-1, 3)
    W = (wmu[:, None] * wph[None, :]).ravel()
    return _frozen(wi, W)


def _at_azimuth(rule0, theta_o: float, phi_o: float, nr: int, na: int) -> tuple[np.ndarray, np.ndarray]:
    """The cached φo = 0 rule turned about the normal to φo (the rules depend on φo only so)."""
    wi, w = rule0(float(theta_o), int(nr), int(na))
    if phi_o != 0.0:
        (wi,) = _frozen(rotate_z(wi, float(phi_o)))
    return wi, w


def half_vector_rule(theta_o: float, phi_o: float, nr: int, na: int) -> tuple[np.ndarray, np.ndarray]:
    """Nodes (M,3) and solid-angle weights (M,) over the upper hemisphere of wi, chart H.

    ``theta_o``, ``phi_o``: the viewing direction (radians); ``nr`` Gauss-Legendre
    nodes per radial panel, ``na`` angular nodes (see :data:`LEVELS`). Read-only arrays.
    """
    return _at_azimuth(_half_vector_rule0, theta_o, phi_o, nr, na)


def mirror_rule(theta_o: float, phi_o: float, nr: int, na: int) -> tuple[np.ndarray, np.ndarray]:
    """Nodes (M,3) and solid-angle weights (M,) over the upper hemisphere of wi, chart R.

    Arguments as :func:`half_vector_rule`.
    """
    return _at_azimuth(_mirror_rule0, theta_o, phi_o, nr, na)


def polar_rule(theta_o: float, phi_o: float, nr: int, na: int) -> tuple[np.ndarray, np.ndarray]:
    """Nodes (M,3) and solid-angle weights (M,) over the upper hemisphere of wi, chart D.

    Gauss-Legendre in μ = cos θi and φi with breaks at θi = θo and at
    φi − φo ∈ {0, π/2, π, 3π/2}: the kinks of diffuse models written with
    max(θi, θo) and max(0, cos(φi − φo)) (Oren-Nayar) fall on panel edges.
    Arguments as :func:`half_vector_rule`.
    """
    return _at_azimuth(_polar_rule0, theta_o, phi_o, nr, na)


_CHARTS = {"H": half_vector_rule, "R": mirror_rule, "D": polar_rule}
_PRIMARY = ("H", "R")


class _Swapped:
    """``eval(wi, wo) = model.eval(wo, wi)``: integrates over the outgoing direction."""

    def __init__(self, model: Any) -> None:
        self.model = model

    def eval(self, wi, wo):
        return self.model.eval(wo, wi)


@dataclass
class AlbedoResult:
    """Albedo ``value`` (…, 3), its error estimate ``error`` (…), the ``chart`` used per angle."""

    value: np.ndarray
    error: np.ndarray
    chart: np.ndarray


def _check_angles(theta_o) -> np.ndarray:
    t = np.asarray(theta_o, dtype=np.float64)
    if not np.all(np.isfinite(t)) or np.any(t < 0) or np.any(t >= math.pi / 2):
        raise ValueError("albedo: theta_o must be finite angles in radians within [0, π/2)")
    return t


#: |y| below which a node lies on the mirror plane y = 0 (the plane of wo at φo = 0)
_ON_PLANE = 1e-12


#: the mirror (x, y, z) -> (x, −y, z) about the plane y = 0
_MIRROR = np.array([1.0, -1.0, 1.0])
#: the sort key of a node, ``x + √2·y + √3·z``: irrational weights, so distinct nodes of a rule do not
#: share a key by the rule's own structure (a tie could only make :func:`_fold`'s check fail, never pass)
_FOLD_KEY = np.array([1.0, math.sqrt(2.0), math.sqrt(3.0)])


def _fold(wi: np.ndarray, w: np.ndarray) -> tuple[np.ndarray, np.ndarray] | None:
    """The half y ≥ 0 of a rule symmetric about the plane y = 0, off-plane weights doubled; None if not symmetric.

    A rule for wo in the xz-plane (φo = 0) is symmetric when its nodes with y < 0 are the
    mirror images (x, −y, z) of those with y > 0, with equal weights (to rounding, 1e-12).
    Then, for an integrand with f(x, −y, z) = f(x, y, z), the half rule gives the same sum.
    The two halves are paired by sorting each on one linear key (:data:`_FOLD_KEY`) of the
    node, the lower half mirrored, and every pair is then compared: one sort of floats per
    half (a lexicographic sort of four rounded columns took 5x as long, and rounding to a
    grid split some mirror pairs that lie across a rounding boundary, leaving those rules
    unfolded).
    """
    y = wi[:, 1]
    up = np.flatnonzero(y > _ON_PLANE)
    down = np.flatnonzero(y < -_ON_PLANE)
    if up.size != down.size:
        return None
    a = up[np.argsort(wi[up] @ _FOLD_KEY)]
    b = down[np.argsort(wi[down] @ (_FOLD_KEY * _MIRROR))]
    if not (np.all(np.abs(wi[a] - wi[b] * _MIRROR) <= 1e-12)  # unit vectors: absolute is relative
            and np.all(np.abs(w[a] - w[b]) <= 1e-12 * np.maximum(1.0, np.abs(w[a])))):
        return None
    keep = np.ones(len(w), dtype=bool)
    keep[down] = False
    return wi[keep], np.where(y[keep] > _ON_PLANE, 2.0, 1.0) * w[keep]


_PLAN_LOCK = threading.Lock()


def _plan(*key):
    """:func:`_build_plan`, cached; threads asking for the same plan build it once (``check --all --jobs``)."""
    with _PLAN_LOCK:
        return _build_plan(*key)


#: a plan at φo = 0 (the one every check integrates over, at every angle of every model) is kept on disk
#: if it holds at most this many nodes (:func:`_build_plan`): 32 bytes a node (``wi`` and ``wc``), 12 MB for
#: ``check``'s angles at level ``fast``
PLAN_CACHE_MAX_NODES = 2_000_000


def _plan_file(key: tuple):
    """The disk-cache file of the plan ``key`` (``_build_plan``'s arguments): in the compiled kernels' folder,
    which is named by a hash of the package source (:func:`brdfkit.engine.cache.cache_dir`), so a change to
    the rules' code means a new file; the level's resolutions and numpy's version (its Gauss-Legendre nodes)
    are part of the name."""
    from ..engine.cache import cache_dir

    digest = hashlib.sha1(repr((key, LEVELS[key[2]], np.__version__)).encode()).hexdigest()[:20]
    return cache_dir() / "albedo-plans" / f"plan-{digest}.npz"


def _load_plan(path, key: tuple):
    """The plan ``key`` (``_build_plan``'s arguments) stored at ``path`` by :func:`_store_plan`, or None if the
    file is missing or not whole: every array of the right type and shape, the rules' rows in order within
    the nodes, each (chart, resolution, angle) of the key exactly once, the viewing directions the key's."""
    theta, phi_o, _level, charts, _max_nodes, _fold = key
    expected = sorted((c, r, k) for c in range(len(charts)) for r in (0, 1) for k in range(len(theta)))
    try:
        with np.load(path, allow_pickle=False) as z:
            wos = z["wos"]
            if not np.array_equal(wos, spherical_to_vector(np.asarray(theta, dtype=np.float64), phi_o)):
                return None
            batches, seen = [], []
            for b in range(int(z["batches"])):
                wi, wc, rows = z[f"wi{b}"], z[f"wc{b}"], z[f"rules{b}"]  # rows: start, chart, resolution, angle
                n = wc.shape[0]
                if (wi.dtype != np.float64 or wc.dtype != np.float64 or wc.ndim != 1 or wi.shape != (n, 3)
                        or rows.dtype != np.int64 or rows.ndim != 2 or rows.shape[1] != 4 or len(rows) == 0):
                    return None
                starts, ch, ri, k = rows[:, 0], rows[:, 1], rows[:, 2], rows[:, 3]
                seen += [(int(c), int(r), int(a)) for c, r, a in zip(ch, ri, k)]
                if starts[0] != 0 or np.any(np.diff(starts) < 0) or starts[-1] >= n:
                    return None
                wo = np.repeat(wos[k], np.diff(np.append(starts, n)), axis=0)  # each rule's viewing direction
                keys = tuple((charts[c], int(r), int(a)) for c, r, a in zip(ch, ri, k))
                batches.append((*_frozen(wi, wo, wc, starts.astype(np.intp)), keys))
    except (OSError, ValueError, KeyError, IndexError, EOFError, zipfile.BadZipFile):  # missing, truncated, foreign
        return None
    if sorted(seen) != expected:  # a rule missing, twice, or not the key's (an index out of range is caught above)
        return None
    (wos,) = _frozen(wos)
    return wos, tuple(batches)


def _store_plan(path, plan, charts: tuple) -> None:
    """Write ``plan`` to ``path`` atomically (the viewing directions of each row are not stored: they
    follow from its rule). A folder that cannot be written leaves the plan in memory only."""
    from ..fileio import atomic_open

    wos, batches = plan
    arrays = {"wos": wos, "batches": np.array(len(batches))}
    for b, (wi, _wo, wc, starts, keys) in enumerate(batches):
        arrays[f"wi{b}"] = wi
        arrays[f"wc{b}"] = wc
        arrays[f"rules{b}"] = np.array([(s, charts.index(c), r, k) for s, (c, r, k) in zip(starts, keys)],
                                       dtype=np.int64).reshape(-1, 4)
    with contextlib.suppress(OSError):
        path.parent.mkdir(parents=True, exist_ok=True)
        with atomic_open(path, "wb") as f:
            np.savez(f, **arrays)


@functools.lru_cache(maxsize=6)
def _build_plan(theta: tuple, phi_o: float, level: str, charts: tuple, max_nodes: int, fold: bool = False):
    """:func:`_make_plan`, from the disk cache where it is kept (φo = 0, at most
    :data:`PLAN_CACHE_MAX_NODES` nodes): a new process then reads the plan that every ``check`` of
    every model integrates over instead of building its rules (0.2 s at ``check``'s angles, level
    ``fast``). The stored plan is the built one, bit for bit."""
    key = (theta, phi_o, level, charts, max_nodes, fold)
    path = _plan_file(key) if phi_o == 0.0 else None
    if path is not None:
        plan = _load_plan(path, key)
        if plan is not None:
            return plan
    plan = _make_plan(*key)
    if path is not None and sum(b[2].shape[0] for b in plan[1]) <= PLAN_CACHE_MAX_NODES:
        _store_plan(path, plan, charts)
    return plan


def _make_plan(theta: tuple, phi_o: float, level: str, charts: tuple, max_nodes: int, fold: bool = False):
    """The evaluation plan of :func:`albedo_result`, built once per angle set, level and charts.

    Returns the viewing directions ``wos`` (n, 3) and batches of at most about ``max_nodes``
    nodes: ``(wi, wo, wc, starts, keys)`` with the concatenated nodes ``wi``, the matching
    ``wo`` rows, the weights ``wc`` = solid-angle weight × max(0, cos θi), the first row
    of each rule in the batch and its ``(chart, resolution, angle index)``. ``fold`` (only
    for φo = 0): each rule symmetric about the plane of wo is replaced by its half
    (:func:`_fold`), half the evaluations for integrands with that symmetry. ``check --all``
    integrates every model over the same angles, so caching this spares each call the
    concatenation (the arrays are read-only; ~40 MB per entry at level ``fast``, ~20 MB folded).
    """
    (n1r, n1a), (n2r, n2a) = LEVELS[level]
    flat = np.asarray(theta, dtype=np.float64)
    wos = spherical_to_vector(flat, phi_o)  # (n, 3): the viewing directions
    rules = []  # (chart, res index, angle index, wo, wi, w)
    for k, th in enumerate(theta):
        for ch in charts:
            for ri, (nr, na) in enumerate(((n1r, n1a), (n2r, n2a))):
                wi, w = _CHARTS[ch](th, phi_o, nr, na)
                half = _fold(wi, w) if fold and phi_o == 0.0 else None
                if half is not None:
                    wi, w = half
                rules.append((ch, ri, k, wos[k], wi, w))
    batches = []
    group: list = []
    count = 0
    for j in rules + [None]:
        if j is not None:
            group.append(j)
            count += j[4].shape[0]
            if count < max_nodes:
                continue
        if not group:
            break
        wi = np.concatenate([g[4] for g in group])
        wo = np.concatenate([np.broadcast_to(g[3], g[4].shape) for g in group])
        wc = np.maximum(wi[:, 2], 0.0) * np.concatenate([g[5] for g in group])
        sizes = [g[4].shape[0] for g in group]
        starts = np.concatenate([[0], np.cumsum(sizes)[:-1]]).astype(np.intp)
        batches.append((*_frozen(wi, wo, wc, starts), tuple(g[:3] for g in group)))
        group, count = [], 0
    (wos,) = _frozen(wos)
    return wos, tuple(batches)


def albedo_result(
    model: Any,
    theta_o,
    phi_o: float = 0.0,
    *,
    over: str = "wi",
    level: str = DEFAULT_LEVEL,
    charts: tuple[str, ...] = ("H", "R", "D"),
    max_nodes: int = 100_000,
    include_delta: bool = True,
    mirror_symmetric: bool = False,
) -> AlbedoResult:
    """Albedo with error estimate; see :func:`albedo`.

    ``mirror_symmetric``: the caller asserts f(Mwi, Mwo) = f(wi, wo) for the mirror
    M = diag(1, −1, 1) (every model here; :func:`brdfkit.analysis.verdict.mirror_symmetric`
    tests it). At φo = 0 only the half y ≥ 0 of each symmetric rule is then evaluated,
    which changes the sums by rounding only.
    """
    if over not in ("wi", "wo"):
        raise ValueError(f"albedo: over must be 'wi' or 'wo', got {over!r}")
    if level not in LEVELS:
        raise ValueError(f"albedo: level must be one of {', '.join(LEVELS)}, got {level!r}")
    for ch in charts:
        if ch not in _CHARTS:
            raise ValueError(f"albedo: unknown chart {ch!r}; valid charts: {', '.join(_CHARTS)}")
    if not math.isfinite(phi_o):
        raise ValueError("albedo: phi_o must be finite")
    t = _check_angles(theta_o)
    flat = t.ravel()
    target = _Swapped(model) if over == "wo" else model
    # results[chart][res] -> (n_angles, 3)
    results = {ch: [np.zeros((flat.size, 3)), np.zeros((flat.size, 3))] for ch in charts}
    fold = bool(mirror_symmetric) and phi_o == 0.0
    wos, batches = _plan(tuple(float(x) for x in flat), float(phi_o), level, tuple(charts), int(max_nodes), fold)
    for wi, wo, wc, starts, keys in batches:
        f = np.asarray(target.eval(wi, wo), dtype=np.float64)
        sums = np.add.reduceat(f * wc[:, None], starts, axis=0)
        for (ch, ri, k), sm in zip(keys, sums):
            results[ch][ri][k] = sm
    errs = np.stack([np.max(np.abs(results[ch][1] - results[ch][0]), axis=-1) for ch in charts])  # (C, n)
    fine = np.stack([results[ch][1] for ch in charts])  # (C, n, 3)
    idx = np.arange(flat.size)
    # Primary charts (H, R) put their densest nodes on the lobe centre (h = n, i.e.
    # wi = reflect(wo)), so they cannot miss a lobe; the smallest error estimate wins.
    # A secondary chart (D) can miss a narrow lobe at both resolutions (and then
    # reports a tiny error), so it is taken only where it agrees with the primary
    # answer within the two error estimates and improves on it.
    prim = np.array([ch in _PRIMARY for ch in charts])
    if prim.any():
        perr = np.where(prim[:, None], errs, np.inf)
        best = np.argmin(perr, axis=0)
        for k in np.flatnonzero(~prim):
            gap = np.max(np.abs(fine[k] - fine[best, idx]), axis=-1)
            ok = (errs[k] < errs[best, idx]) & (gap <= 2 * (errs[k] + errs[best, idx]))
            best = np.where(ok, k, best)
    else:
        best = np.argmin(errs, axis=0)
    value = fine[best, idx]
    err = errs[best, idx]
    if include_delta and hasattr(model, "delta_reflectance"):
        # the ideal-mirror part maps θ to θ (and is reciprocal): the same term for over="wi" and "wo"
        value = value + np.asarray(model.delta_reflectance(wos), dtype=np.float64)
    err = np.maximum(err, 1e-13 * np.max(np.abs(value), axis=-1))
    chart = np.asarray(charts)[best]
    return AlbedoResult(
        value.reshape(t.shape + (3,)), err.reshape(t.shape), chart.reshape(t.shape)
    )


def albedo(
    model: Any,
    theta_o,
    phi_o: float = 0.0,
    *,
    over: str = "wi",
    level: str = DEFAULT_LEVEL,
    return_error: bool = False,
    include_delta: bool = True,
):
    """Directional albedo of ``model`` at polar angles ``theta_o`` (radians, in [0, π/2)).

    ``over="wi"`` (default): a(wo) = ∫ f_r(wi, wo) cos θi dωi, the white-furnace
    radiance seen from wo = (theta_o, phi_o). ``over="wo"``: ρ(wi) = ∫ f_r(wi, wo)
    cos θo dωo, the fraction of light arriving from (theta_o, phi_o) that is
    reflected (the two agree for reciprocal models).

    Returns an array of shape ``theta_o.shape + (3,)`` (RGB); with
    ``return_error=True`` also the error estimate (difference between two
    quadrature resolutions, largest over channels), shape ``theta_o.shape``.
    ``level`` is ``"fast"``, ``"normal"`` or ``"fine"``. With ``include_delta`` (default)
    the model's ideal-mirror part (:meth:`BRDF.delta_reflectance`: HTSG's coherent
    specular, Schlick's mirror) is added, since ``eval`` cannot return a delta.
    """
    res = albedo_result(model, theta_o, phi_o, over=over, level=level, include_delta=include_delta)
    if return_error:
        return res.value, res.error
    return res.value


def brute_force_albedo(model: Any, theta_o: float, phi_o: float = 0.0, n: int = 2000) -> np.ndarray:
    """Reference a(wo) by a midpoint rule in (cos θi, φi) on an ``n × 2n`` grid.

    Independent of the charts above; slow and only accurate for smooth lobes
    (used by the tests as a cross-check).
    """
    mu = (np.arange(n) + 0.5) / n
    ph = 2 * math.pi * (np.arange(2 * n) + 0.5) / (2 * n)
    wo = spherical_to_vector(theta_o, phi_o)
    total = np.zeros(3)
    for m in mu.reshape(-1, 50) if n % 50 == 0 else [mu]:
        M, P = np.meshgrid(m, ph, indexing="ij")
        st = np.sqrt(1 - M**2)
        wi = np.stack([st * np.cos(P), st * np.sin(P), M], -1).reshape(-1, 3)
        f = model.eval(wi, wo)
        total += (f * wi[:, 2:3]).sum(0)
    return total * (1.0 / n) * (2 * math.pi / (2 * n))


__all__ = ["albedo", "albedo_result", "AlbedoResult", "brute_force_albedo", "half_vector_rule", "mirror_rule", "LEVELS"]
