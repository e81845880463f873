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
already applied). The network is evaluated per pair in float64 by the scalar
kernel :func:`nbrdf_kernel` (weights stored as float32, as published; the
argument of exp is capped at 80, never reached by real data). The difference vector is the light direction ``wi`` seen from
the half-vector frame, as :func:`brdfkit.geometry.to_rusinkiewicz` computes it.
"""

from __future__ import annotations

import difflib
import functools
import math
import os

import numpy as np

from ..engine import jit
from .merl import MeasuredBRDF, symmetric_half_diff_c

_DATA = os.path.join(os.path.dirname(__file__), "data", "nbrdf_weights.npz")
SETS = ("merl", "rgl", "nielsen")


#: the six arrays of one network, in the order of the flat weight vector
LAYERS = ("fc1", "b1", "fc2", "b2", "fc3", "b3")


@functools.lru_cache(maxsize=1)
def _entries() -> tuple[str, ...]:
    """The array names in the weights file, read from its index alone (naming a material
    must not inflate 954 arrays: that was 0.1 s of every fresh ``brdfkit fit merl/…``)."""
    with np.load(_DATA) as z:
        return tuple(z.files)


@functools.lru_cache(maxsize=8)
def layers(full: str) -> tuple[np.ndarray, ...]:
    """The network of the material ``full`` (``set/name``): its :data:`LAYERS`, float32, shapes
    checked (``ValueError`` names the shape found)."""
    with np.load(_DATA) as z:
        out = tuple(z[f"{full}/{k}"].astype(np.float32) for k in LAYERS)
    shapes = ((N_IN, N_HID), (N_HID,), (N_HID, N_HID), (N_HID,), (N_HID, N_OUT), (N_OUT,))
    if tuple(a.shape for a in out) != shapes:
        raise ValueError(f"{full}: unexpected network shape {[a.shape for a in out]}")
    for a in out:
        a.flags.writeable = False
    return out


@functools.lru_cache(maxsize=1)
def materials() -> tuple[str, ...]:
    """Names of every built-in measured material (``set/name``), sorted by set then name."""
    names = {k.rsplit("/", 1)[0] for k in _entries()}
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


#: the layer sizes: 6 inputs, two hidden layers of 21, 3 outputs
N_IN, N_HID, N_OUT = 6, 21, 3
#: offsets of W1 (6×21, row-major), b1, W2 (21×21), b2, W3 (21×3), b3 in the flat weight vector
_O_W1 = 0
_O_B1 = _O_W1 + N_IN * N_HID
_O_W2 = _O_B1 + N_HID
_O_B2 = _O_W2 + N_HID * N_HID
_O_W3 = _O_B2 + N_HID
_O_B3 = _O_W3 + N_HID * N_OUT
N_WEIGHTS = _O_B3 + N_OUT


@jit
def nbrdf_network(w, theta_h, theta_d, phi_d):
    """The Neural-BRDF network at one configuration (φh = 0): RGB f_r in 1/sr.

    ``x = (sin θh, 0, cos θh, sin θd cos φd, sin θd sin φd, cos θd)``,
    ``a1 = relu(x·W1 + b1)``, ``a2 = relu(a1·W2 + b2)``, ``f = max(exp(a2·W3 + b3) − 1, 0)``.
    ``w`` is the flat weight vector (offsets ``_O_*``).
    """
    sd = math.sin(theta_d)
    x0 = math.sin(theta_h)
    x2 = math.cos(theta_h)
    x3 = sd * math.cos(phi_d)
    x4 = sd * math.sin(phi_d)
    x5 = math.cos(theta_d)
    a1 = np.empty(N_HID)
    for u in range(N_HID):  # x1 = 0 contributes nothing
        z = (w[_O_B1 + u] + x0 * w[_O_W1 + u] + x2 * w[_O_W1 + 2 * N_HID + u] + x3 * w[_O_W1 + 3 * N_HID + u]
             + x4 * w[_O_W1 + 4 * N_HID + u] + x5 * w[_O_W1 + 5 * N_HID + u])
        a1[u] = max(z, 0.0)
    o0 = w[_O_B3]
    o1 = w[_O_B3 + 1]
    o2 = w[_O_B3 + 2]
    for u in range(N_HID):
        z = w[_O_B2 + u]
        for t in range(N_HID):
            z += a1[t] * w[_O_W2 + t * N_HID + u]
        if z > 0.0:
            o0 += z * w[_O_W3 + u * N_OUT]
            o1 += z * w[_O_W3 + u * N_OUT + 1]
            o2 += z * w[_O_W3 + u * N_OUT + 2]
    return (max(math.expm1(min(o0, 80.0)), 0.0), max(math.expm1(min(o1, 80.0)), 0.0),
            max(math.expm1(min(o2, 80.0)), 0.0))


@jit
def nbrdf_kernel(wix, wiy, wiz, wox, woy, woz, p, c):
    """A Neural-BRDF material per pair (engine protocol, :mod:`brdfkit.engine`); φd folded into [0, π).

    ``p`` = the flat weights (:data:`N_WEIGHTS` floats, offsets ``_O_*``); ``c`` unused.
    """
    th, td, pd = symmetric_half_diff_c(wix, wiy, wiz, wox, woy, woz)
    return nbrdf_network(p, th, td, pd)


@jit
def _network_many(w, th, td, pd, out):
    for j in range(th.shape[0]):
        r, g, b = nbrdf_network(w, th[j], td[j], pd[j])
        out[j, 0] = r
        out[j, 1] = g
        out[j, 2] = b


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
        self.material = full
        self.label = full
        self._layers = layers(full)
        self._flat = np.ascontiguousarray(np.concatenate([a.astype(np.float64).ravel() for a in self._layers]))
        super().__init__()

    def __repr__(self) -> str:
        return f"bk.material({self.material!r})"

    kernel = staticmethod(nbrdf_kernel)

    def kernel_args(self):
        return self._flat, np.zeros(1, dtype=np.int64)

    def eval_rusinkiewicz(self, theta_h, theta_d, phi_d) -> np.ndarray:
        """The network at Rusinkiewicz angles (φd folded into [0, π)), ``(..., 3)`` float64."""
        from .merl import fold_phi_d

        th, td, pd = np.broadcast_arrays(
            np.asarray(theta_h, np.float64), np.asarray(theta_d, np.float64), np.asarray(phi_d, np.float64)
        )
        shape = th.shape
        out = np.empty((th.size, 3))
        _network_many(self._flat, th.ravel().copy(), td.ravel().copy(), fold_phi_d(pd.ravel()), out)
        return out.reshape(shape + (3,))


def material(name: str) -> NeuralBRDF:
    """A built-in measured material as a model, e.g. ``material("merl/gold-metallic-paint")``."""
    return NeuralBRDF(name)


__all__ = ["NeuralBRDF", "material", "materials", "resolve", "SETS"]
