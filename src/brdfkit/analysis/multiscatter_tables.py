"""Building the multiple-scattering tables of :mod:`brdfkit.terms.multiscatter` with this project's quadrature.

The energy compensation of Kulla & Conty (2017) needs the directional albedo ``E(μ)`` of the
single-scattering microfacet lobe (F = 1, kd = 0) on a grid of μ by α, per distribution and
shadowing term. They are tabulated once, offline, by :func:`brdfkit.analysis.albedo.albedo`
(``level="fine"``), and shipped as ``terms/data/multiscatter.npz``; the term only reads them.
Rebuilding takes about 4 minutes::

    python -m brdfkit.analysis.multiscatter_tables      # writes terms/data/multiscatter.npz
    python -m brdfkit.render.generate                   # then the GLSL twin's copy of them

(The tables are built here, in ``analysis``, so that ``terms`` never imports ``analysis``.)
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np

from ..fileio import atomic_open
from ..registry import get as model_class
from ..terms import multiscatter as ms
from .albedo import albedo


def albedo_table(distribution: str, shadowing: str, level: str = "fine") -> np.ndarray:
    """E(α_k, μ_j), shape (N_ALPHA, N_MU), of the single-scattering microfacet lobe (F = 1, kd = 0, ks = 1) on the
    grids of :func:`brdfkit.terms.multiscatter.alpha_grid` and :func:`~brdfkit.terms.multiscatter.mu_grid`;
    α = 0 is the mirror (E = 1)."""
    mu = ms.mu_grid()
    alphas = ms.alpha_grid()
    theta = np.arccos(mu)
    cls = model_class("microfacet")
    t = np.ones((len(alphas), len(mu)))
    for k, a in enumerate(alphas):
        if a == 0.0:
            continue  # the mirror: E = 1
        m = cls(distribution=distribution, shadowing=shadowing, alpha=float(a), fresnel="none", kd=0.0, ks=1.0)
        t[k] = albedo(m, theta, level=level)[:, 0]
    return t


def build_tables(path: Path = ms.DATA_PATH, level: str = "fine") -> dict[str, np.ndarray]:
    """Tabulate E(μ, α) for every distribution and shadowing term (:func:`albedo_table`) and write them, with
    the grids, to ``path`` (atomically); the term reads the new file from then on."""
    out: dict[str, np.ndarray] = {"mu": ms.mu_grid(), "alpha": ms.alpha_grid()}
    for d in ms.DISTRIBUTIONS:
        for s in ms.SHADOWINGS:
            out[ms.table_key(d, s)] = albedo_table(d, s, level)
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    with atomic_open(path, "wb") as fh:
        np.savez_compressed(fh, **out)
    ms.reload_tables()
    return out


def main(argv: list[str] | None = None) -> int:
    """``python -m brdfkit.analysis.multiscatter_tables``: rebuild ``terms/data/multiscatter.npz``."""
    argv = sys.argv[1:] if argv is None else argv
    if argv:
        print("usage: python -m brdfkit.analysis.multiscatter_tables  (no arguments)", file=sys.stderr)
        return 2
    build_tables()
    print(f"wrote {ms.DATA_PATH}; now run: python -m brdfkit.render.generate")
    return 0


__all__ = ["albedo_table", "build_tables"]

if __name__ == "__main__":
    raise SystemExit(main())
