"""159 measured materials, shipped as Neural-BRDF networks.

Reference: A. Sztrajman, G. Rainer, T. Ritschel, T. Weyrich, "Neural BRDF
Representation and Importance Sampling", Computer Graphics Forum 40(6), 2021.
Networks from the public repository asztr/Neural-BRDF (MIT licence, see
``data/LICENSE``), converted from Keras to one numpy file ``data/nbrdf_weights.npz``.

Materials: ``merl/<name>`` (the 100 materials of the MERL database, Matusik et
al. 2003), ``rgl/<name>`` (51 isotropic materials of the EPFL RGL database),
``nielsen/<name>`` (8 materials of Nielsen, Jensen & Ramamoorthi 2015).

Each network maps the Rusinkiewicz half/difference vectors (φh = 0)

    x = (sin θh, 0, cos θh, sin θd cos φd, sin θd sin φd, cos θd)

through ``relu(x·W1 + b1)`` (21 units), ``relu(·W2 + b2)`` (21 units) and
``max(exp(·W3 + b3) − 1, 0)`` to RGB f_r in 1/sr (MERL's channel scales
already applied). The difference vector is the light direction ``wi`` seen from
the half-vector frame, as :func:`brdfkit.geometry.to_rusinkiewicz` computes it.
"""

from __future__ import annotations

import difflib
import functools
import os

import numpy as np

from .merl import MeasuredBRDF, fold_phi_d

_DATA = os.path.join(os.path.dirname(__file__), "data", "nbrdf_weights.npz")
SETS = ("merl", "rgl", "nielsen")


@functools.lru_cache(maxsize=1)
def _weights() -> dict[str, np.ndarray]:
    with np.load(_DATA) as z:
        return {k: z[k].astype(np.float32) for k in z.files}


@functools.lru_cache(maxsize=1)
def materials() -> tuple[str, ...]:
    """Names of every built-in measured material (``set/name``), sorted by set then name."""
    names = {k.rsplit("/", 1)[0] for k in _weights()}
    return tuple(sorted(names, key=lambda n: (SETS.index(n.split("/")[0]) if n.split("/")[0] in SETS else 9, n)))


def resolve(name: str) -> str:
    """Full ``set/name`` of a material; a bare name is accepted when unique. ``ValueError`` otherwise."""
    if not isinstance(name, str):
        raise ValueError(f"measured material name must be a string, got {name!r}")
    names = materials()
    if name in names:
        return name
    bare = [n for n in names if n.split("/", 1)[1] == name]
    if len(bare) == 1:
        return bare[0]
    if len(bare) > 1:
        raise ValueError(f"measured material {name!r} is ambiguous: {', '.join(bare)}")
    close = difflib.get_close_matches(name, names, n=3, cutoff=0.5)
    hint = f"; did you mean {', '.join(close)}?" if close else ""
    raise ValueError(
        f"unknown measured material {name!r}{hint} ({len(names)} available: "
        f"merl/…, rgl/…, nielsen/…; see `brdfkit list --measured`)"
    )


class NeuralBRDF(MeasuredBRDF):
    """One measured material as its Neural-BRDF network (a model with no parameters).

    The network is evaluated with φd folded into [0, π), the domain MERL stores
    (reciprocity maps φd to φd + π). The raw networks are not exactly reciprocal:
    over random angles the halves φd and φd + π differ by a median 3 % for the
    MERL networks and 30 % for the RGL ones (measured), so evaluating the raw
    network on [0, 2π) would make a measured material fail the reciprocity law
    for reasons of the fit, not of the material. Folding makes ``eval`` exactly
    reciprocal and equal to the MERL table that :func:`save_merl` writes.
    """

    name = "nbrdf"
    title = "measured material (Neural-BRDF network of Sztrajman et al. 2021)"
    reference = (
        "Sztrajman, Rainer, Ritschel, Weyrich, Neural BRDF Representation and Importance Sampling, "
        "CGF 40(6), 2021; data: Matusik et al. 2003 (MERL), EPFL RGL, Nielsen et al. 2015"
    )
    spec = ()

    def __init__(self, material: str) -> None:
        full = resolve(material)
        w = _weights()
        self.material = full
        self.label = full
        self._layers = tuple(w[f"{full}/{k}"] for k in ("fc1", "b1", "fc2", "b2", "fc3", "b3"))
        super().__init__()

    def __repr__(self) -> str:
        return f"bk.material({self.material!r})"

    def eval_rusinkiewicz(self, theta_h, theta_d, phi_d) -> np.ndarray:
        th, td, pd = np.broadcast_arrays(
            np.asarray(theta_h, np.float64), np.asarray(theta_d, np.float64), np.asarray(phi_d, np.float64)
        )
        shape = th.shape
        th, td, pd = th.ravel(), td.ravel(), fold_phi_d(pd.ravel())
        sd = np.sin(td)
        x = np.empty((th.size, 6), dtype=np.float32)
        x[:, 0] = np.sin(th)
        x[:, 1] = 0.0
        x[:, 2] = np.cos(th)
        x[:, 3] = sd * np.cos(pd)
        x[:, 4] = sd * np.sin(pd)
        x[:, 5] = np.cos(td)
        w1, b1, w2, b2, w3, b3 = self._layers
        out = np.empty((th.size, 3), dtype=np.float64)
        step = 1 << 16
        for s in range(0, th.size, step):
            a = np.maximum(x[s : s + step] @ w1 + b1, 0.0)
            a = np.maximum(a @ w2 + b2, 0.0)
            z = np.minimum(a @ w3 + b3, 80.0)  # exp overflow guard (never reached by real data)
            out[s : s + step] = np.maximum(np.expm1(z.astype(np.float64)), 0.0)
        return out.reshape(shape + (3,))


def material(name: str) -> NeuralBRDF:
    """A built-in measured material as a model, e.g. ``material("merl/gold-metallic-paint")``."""
    return NeuralBRDF(name)


__all__ = ["NeuralBRDF", "material", "materials", "resolve", "SETS"]
