"""The eval contract at the exact edges of every parameter range, on both engines, and a fuzz.

SPEC.md: ``eval`` never returns NaN, Inf or a negative value for any valid
parameters and any unit directions, and 0 below the horizon. ``test_contract.py``
draws parameters at least 1e-6 of the span inside an open bound; schlick's Z(t)
underflowed much closer than that (r = 1e-170 gave Inf, issue 14), so here every
numeric parameter of every registered model (and the measured materials) is set,
alone and all together, to

* its lower bound when the range includes it, else the next float above it;
  where the bound is 0, also the smallest positive float64 (5e-324) and float32
  (1.4e-45) — subnormals, the values that exposed the underflow;
* its upper bound when included, else the next float below it; for an unbounded
  range, the largest finite float64;

in every combination of the model's choice/bool parameters (each value alone when
there are more than 48 combinations), evaluated at special direction pairs
(normal incidence, grazing down to z = 5e-324, exactly at the horizon,
``wi == wo``, mirror pairs, ``wi == −wo``) and random ones, in float64 and
float32, on the compiled engine and on the reference engine.

The fuzz (``@pytest.mark.slow``; CI runs it): a million evaluations per model on
the compiled engine — 2000 random parameter sets (each parameter at an edge value
with probability 1/8, else uniform, or log-uniform over the whole range where it
spans decades) of 500 direction pairs each, half of them float32 — every value
finite and non-negative, zero below the horizon.
"""

from __future__ import annotations

import itertools
import math

import numpy as np
import pytest

import brdfkit as bk
from brdfkit import engine
from brdfkit.geometry import normalize, random_unit_vectors, spherical_to_vector

TINY64 = float(np.finfo(np.float64).smallest_subnormal)
TINY32 = float(np.finfo(np.float32).smallest_subnormal)
BIG64 = float(np.finfo(np.float64).max)
MAX_COMBOS = 48


# --------------------------------------------------------------------------- parameter edges
def edge_values(p) -> list[float]:
    """The exact range edges of a numeric parameter (see the module docstring)."""
    lo, hi = p.range
    out = []
    out.append(math.nextafter(lo, math.inf) if p.open_lo else lo)
    if lo == 0.0:
        out += [TINY64, TINY32]
    if math.isinf(hi):
        out.append(BIG64)
    else:
        out.append(math.nextafter(hi, -math.inf) if p.open_hi else hi)
    if p.kind == "int":
        out = sorted({int(math.ceil(v)) if v == out[0] else int(math.floor(v)) for v in out if abs(v) < 2**62})
    return list(dict.fromkeys(out))


def _numeric(cls):
    return [p for p in cls.spec if p.kind in ("scalar", "rgb", "int") and p.range is not None]


def _combos(cls) -> list[dict]:
    discrete = [p for p in cls.spec if p.kind in ("choice", "bool")]
    values = [list(p.choices) if p.kind == "choice" else [False, True] for p in discrete]
    combos = list(itertools.product(*values))
    if len(combos) <= MAX_COMBOS:
        return [dict(zip([p.name for p in discrete], c)) for c in combos] or [{}]
    return [{p.name: v} for p, vals in zip(discrete, values) for v in vals]


def _make(cls, params):
    """The model, or None where the model rejects the combination (a documented ValueError).

    A rejected set is tried once more without the numeric parameters the fitter never varies
    (shorthands such as microfacet's ``alpha``, which contradicts ``alpha_x``/``alpha_y``).
    """
    try:
        return cls(**params)
    except ValueError:
        pass
    shorthand = {p.name for p in _numeric(cls) if not p.fit}
    if not shorthand & set(params):
        return None
    try:
        return cls(**{k: v for k, v in params.items() if k not in shorthand})
    except ValueError:
        return None


def edge_param_sets(cls, singles_for_every_combo: bool = True) -> list[dict]:
    sets = []
    numeric = _numeric(cls)
    for ic, combo in enumerate(_combos(cls)):
        if singles_for_every_combo or ic == 0:
            for p in numeric:
                for v in edge_values(p):
                    sets.append({**combo, p.name: v})
        for pick in (0, -1):  # every numeric parameter at its low (high) edge at once
            sets.append({**combo, **{p.name: edge_values(p)[pick] for p in numeric}})
    return sets


# --------------------------------------------------------------------------- directions
def special_pairs() -> tuple[np.ndarray, np.ndarray]:
    g = [np.array([1.0, 0.0, TINY64]), np.array([0.0, 1.0, TINY64]), np.array([-1.0, 0.0, 1e-300])]
    grazing = normalize(np.array([[math.cos(a), math.sin(a), 1e-12] for a in (0.3, 2.0, 4.0)]))
    horizon = np.array([[1.0, 0.0, 0.0], [0.0, -1.0, 0.0]])
    below = np.array([[0.6, 0.0, -0.8]])
    normal = np.array([[0.0, 0.0, 1.0]])
    near_normal = spherical_to_vector(np.array([1e-8, 1e-4]), np.array([0.0, 1.0]))
    moderate = spherical_to_vector(np.radians([30.0, 60.0, 85.0, 89.999]), np.radians([0.0, 120.0, 250.0, 10.0]))
    dirs = np.concatenate([np.array(g), grazing, horizon, below, normal, near_normal, moderate])
    n = len(dirs)
    wi, wo = [], []
    for a in range(n):
        for b in range(n):
            wi.append(dirs[a])
            wo.append(dirs[b])
    wi = np.array(wi)
    wo = np.array(wo)
    mirror = dirs * np.array([-1.0, -1.0, 1.0])  # reflect about +z
    wi = np.concatenate([wi, dirs, dirs])
    wo = np.concatenate([wo, mirror, -dirs])
    return wi, wo


def random_pairs(n: int, seed: int) -> tuple[np.ndarray, np.ndarray]:
    rng = np.random.default_rng(seed)
    return random_unit_vectors(n, rng), random_unit_vectors(n, rng, hemisphere=False)


SP_WI, SP_WO = special_pairs()
RD_WI, RD_WO = random_pairs(24, 7)
WI = np.concatenate([SP_WI, RD_WI])
WO = np.concatenate([SP_WO, RD_WO])


def check(m, wi, wo, what: str) -> None:
    for dt in (np.float64, np.float32):
        a, b = wi.astype(dt), wo.astype(dt)
        f = m.eval(a, b)
        assert f.dtype == dt, what
        bad = ~np.isfinite(f) | (f < 0)
        if bad.any():
            i = np.argwhere(bad)[0][0]
            raise AssertionError(f"{what} {np.dtype(dt).name}: f({a[i].tolist()}, {b[i].tolist()}) = {f[i].tolist()}")
        below = (a[:, 2] <= 0) | (b[:, 2] <= 0)
        assert np.all(f[below] == 0), f"{what} {np.dtype(dt).name}: nonzero below the horizon"


def _measured_models():
    from brdfkit.measured.merl import MERLBRDF, SHAPE

    rng = np.random.default_rng(11)
    table = rng.random((3,) + SHAPE) * 10.0
    table[:, :, :, ::7] = -1.0  # missing bins
    table[0, 40:50] = 1e300  # huge but finite measurements
    from brdfkit.measured.nbrdf import SETS, materials

    names = materials()
    out = [bk.material("merl/chrome")] + [bk.material(next(n for n in names if n.startswith(s + "/"))) for s in SETS]
    out += [MERLBRDF(table, interpolation=i) for i in ("nearest", "trilinear")]
    return out


MODELS = bk.models()


@pytest.mark.parametrize("eng", ["compiled", "reference"])
@pytest.mark.parametrize("name", MODELS)
def test_every_model_at_the_exact_range_edges(name, eng):
    cls = bk.registry.get(name)
    old = engine.engine()
    engine.set_engine(eng)
    tried = 0
    # the reference engine runs pair by pair in Python: every edge alone for the default
    # choices and all edges at once for every choice, at the special pairs only
    full = eng == "compiled"
    wi, wo = (WI, WO) if full else (SP_WI, SP_WO)
    try:
        for params in edge_param_sets(cls, singles_for_every_combo=full):
            m = _make(cls, params)
            if m is None:
                continue
            tried += 1
            check(m, wi, wo, f"{eng} {name} {params}")
    finally:
        engine.set_engine(old)
    assert tried > 0, f"{name}: no edge parameter set was accepted"


@pytest.mark.parametrize("eng", ["compiled", "reference"])
def test_measured_materials_contract(eng):
    old = engine.engine()
    engine.set_engine(eng)
    try:
        for m in _measured_models():
            check(m, WI, WO, f"{eng} {m!r}")
    finally:
        engine.set_engine(old)


def test_edge_values_are_accepted_and_exact():
    """The edges used above are the bounds themselves (or their next float): the model accepts each."""
    s = bk.registry.get("schlick")
    r = next(p for p in s.spec if p.name == "r")
    assert edge_values(r) == [TINY64, TINY32, 1.0]  # the next float above 0 is the smallest subnormal
    assert bk.model("schlick", r=TINY64).params["r"] == TINY64
    with pytest.raises(ValueError):
        bk.model("schlick", r=0.0)


# --------------------------------------------------------------------------- the fuzz
N_SETS = 2000
N_PAIRS = 500


def _fuzz_value(p, rng):
    if rng.random() < 0.125:
        return float(rng.choice(edge_values(p)))
    lo, hi = p.range
    if math.isinf(hi):
        hi = max(1e6, lo * 1e6)
    lo_eff = lo if not p.open_lo else math.nextafter(lo, math.inf)
    if p.kind == "int":
        return int(rng.integers(math.ceil(lo), math.floor(min(hi, lo + 1000)) + 1))
    n = 3 if p.kind == "rgb" else 1
    if (p.log_scale or (lo == 0 and hi / max(lo_eff, 1e-300) > 1e3)) and rng.random() < 0.5:
        a = max(lo_eff, 1e-300)
        v = np.exp(rng.uniform(math.log(a), math.log(hi), n))
    else:
        v = rng.uniform(lo_eff, hi, n)
    v = np.clip(v, lo_eff, hi if not p.open_hi else math.nextafter(hi, -math.inf))
    return [float(x) for x in v] if n == 3 else float(v[0])


def _fuzz_dirs(rng, n):
    wi = random_unit_vectors(n, rng)
    wo = random_unit_vectors(n, rng, hemisphere=False)
    k = n // 10  # a tenth near the horizon, down to z = 1e-300
    z = 10.0 ** rng.uniform(-300, -1, k)
    phi = rng.uniform(0, 2 * np.pi, k)
    wi[:k] = np.stack([np.cos(phi) * np.sqrt(1 - z * z), np.sin(phi) * np.sqrt(1 - z * z), z], axis=-1)
    wo[k : 2 * k] = wi[:k] * np.array([-1.0, -1.0, 1.0])  # mirror pairs at grazing
    wi[k : 2 * k] = wi[:k]
    return wi, wo


@pytest.mark.slow
@pytest.mark.parametrize("name", MODELS)
def test_million_case_fuzz(name):
    cls = bk.registry.get(name)
    rng = np.random.default_rng(sum(map(ord, name)) + 14)
    numeric = _numeric(cls)
    combos = _combos(cls)
    old = engine.engine()
    engine.set_engine("compiled")
    done = 0
    try:
        for s in range(N_SETS):
            params = dict(combos[int(rng.integers(len(combos)))])
            for p in numeric:
                params[p.name] = _fuzz_value(p, rng)
            m = _make(cls, params)
            if m is None:
                continue
            wi, wo = _fuzz_dirs(rng, N_PAIRS)
            dt = np.float32 if s % 2 else np.float64
            a, b = wi.astype(dt), wo.astype(dt)
            f = m.eval(a, b)
            bad = ~np.isfinite(f) | (f < 0)
            if bad.any():
                i = np.argwhere(bad)[0][0]
                raise AssertionError(f"{name} {params} {np.dtype(dt).name}: f({a[i].tolist()}, {b[i].tolist()}) = {f[i].tolist()}")
            below = (a[:, 2] <= 0) | (b[:, 2] <= 0)
            assert np.all(f[below] == 0)
            done += f.shape[0]
    finally:
        engine.set_engine(old)
    assert done >= 0.9 * N_SETS * N_PAIRS, f"{name}: only {done} evaluations (too many rejected parameter sets)"
