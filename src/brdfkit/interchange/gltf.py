"""glTF 2.0 binaries: a UV sphere with the material as ``pbrMetallicRoughness`` and the
``KHR_materials_ior`` / ``_specular`` / ``_diffuse_roughness`` extensions (pygltflib).

Which source becomes which parameters, and when exactly: :mod:`brdfkit.interchange.export`.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from ..models.base import BRDF
from .approx import _rgb, _is, _is_eon, eon_roughness, _target_params, conductor_f0_f82


def _gltf_direct(model: BRDF) -> tuple[dict[str, Any] | None, bool, str]:
    p = model.params
    if _is(model, "lambert"):
        return {"base_color": _rgb(p["kd"]), "metallic": 0.0, "roughness": 1.0, "specular": 0.0}, True, (
            "lambert -> baseColor = kd, KHR_materials_specular.specularFactor = 0"
        )
    if _is_eon(model):
        return {"base_color": _rgb(p["kd"]), "metallic": 0.0, "roughness": 1.0, "specular": 0.0,
                "diffuse_roughness": eon_roughness(p)}, True, (
            "oren-nayar eon -> baseColor = kd, specularFactor = 0, "
            "KHR_materials_diffuse_roughness.diffuseRoughnessFactor = min(sigma, 1)"
        )
    if _is(model, "microfacet") and p["distribution"] == "ggx":
        ax, ay = float(p["alpha_x"]), float(p["alpha_y"])
        a = math.sqrt(ax * ay)
        kd = np.asarray(_rgb(p["kd"]))
        ks = np.asarray(_rgb(p["ks"]))
        rough = math.sqrt(a)
        if p["fresnel"] in ("schlick", "conductor"):
            if p["fresnel"] == "schlick":
                f0 = np.asarray(_rgb(p["f0"]))
            else:
                f0, _ = conductor_f0_f82(p["eta"], p["k"])
            exact = (p["fresnel"] == "schlick" and p["shadowing"] == "smith" and ax == ay and kd.max() == 0
                     and np.all(ks == 1) and not p.get("multiscatter", False))
            return {"base_color": np.clip(f0, 0, 1).tolist(), "metallic": 1.0, "roughness": rough}, exact, (
                "metal: baseColor = f0, roughness = sqrt(alpha)"
            )
        if p["fresnel"] == "dielectric":
            eta = float(np.mean(_rgb(p["eta"])))
            return {"base_color": kd.tolist(), "metallic": 0.0, "roughness": rough, "ior": min(max(eta, 1.0), 5.0),
                    "specular": float(min(ks.max(), 1.0))}, False, "dielectric: baseColor = kd, ior = eta"
    return None, False, ""


def gltf_params(model: BRDF, metric: str = "ngan", data=None) -> tuple[dict[str, Any], dict[str, Any]]:
    """glTF metallic-roughness (+ior, +specular) parameters for a model, and what went into them."""
    from .targets import GltfPBR

    return _target_params(GltfPBR, "the glTF BRDF", _gltf_direct, model, metric, data)


def uv_sphere(n_lat: int = 32, n_lon: int = 64) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """A closed unit UV sphere (+y up): positions, normals (= positions), float32, and uint32
    triangle indices, counter-clockwise seen from outside; the poles and the seam are shared vertices."""
    th = np.arange(1, n_lat) * (np.pi / n_lat)
    ph = np.arange(n_lon) * (2 * np.pi / n_lon)
    T, P = np.meshgrid(th, ph, indexing="ij")
    ring = np.stack([np.sin(T) * np.cos(P), np.cos(T), -np.sin(T) * np.sin(P)], axis=-1).reshape(-1, 3)
    pos = np.concatenate([[[0.0, 1.0, 0.0]], ring, [[0.0, -1.0, 0.0]]])
    south = len(pos) - 1

    def v(i, j):  # ring i (0-based), azimuth j
        return 1 + i * n_lon + (j % n_lon)

    idx = []
    for j in range(n_lon):
        idx.append((0, v(0, j), v(0, j + 1)))
        idx.append((south, v(n_lat - 2, j + 1), v(n_lat - 2, j)))
    for i in range(n_lat - 2):
        for j in range(n_lon):
            a, b, c, d = v(i, j), v(i + 1, j), v(i + 1, j + 1), v(i, j + 1)
            idx += [(a, b, c), (a, c, d)]
    pos = pos.astype(np.float32)
    nrm = pos / np.linalg.norm(pos, axis=1, keepdims=True)
    return pos, nrm.astype(np.float32), np.asarray(idx, dtype=np.uint32)


def gltf_bytes(params: dict[str, Any], name: str = "brdfkit") -> bytes:
    """A .glb (binary glTF 2.0) with a UV sphere and the material."""
    import pygltflib as g

    pos, nrm, idx = uv_sphere()
    blob = pos.tobytes() + nrm.tobytes() + idx.tobytes()
    n_pos, n_idx = len(pos), idx.size
    bc = [float(x) for x in params["base_color"]]
    material = g.Material(
        name=name,
        pbrMetallicRoughness=g.PbrMetallicRoughness(
            baseColorFactor=bc + [1.0], metallicFactor=float(params["metallic"]), roughnessFactor=float(params["roughness"])
        ),
        doubleSided=False,
    )
    ext: dict[str, Any] = {}
    if abs(float(params["ior"]) - 1.5) > 0:
        ext["KHR_materials_ior"] = {"ior": float(params["ior"])}
    sc = [float(x) for x in params["specular_color"]]
    if float(params["specular"]) != 1.0 or sc != [1.0, 1.0, 1.0]:
        ext["KHR_materials_specular"] = {"specularFactor": float(params["specular"]), "specularColorFactor": sc}
    if float(params.get("diffuse_roughness", 0.0)) > 0:
        ext["KHR_materials_diffuse_roughness"] = {"diffuseRoughnessFactor": float(params["diffuse_roughness"])}
    if ext:
        material.extensions = ext
    gl = g.GLTF2(
        asset=g.Asset(generator="brdfkit export", version="2.0"),
        scene=0,
        scenes=[g.Scene(nodes=[0])],
        nodes=[g.Node(mesh=0, name=name)],
        meshes=[g.Mesh(name="sphere", primitives=[g.Primitive(attributes=g.Attributes(POSITION=0, NORMAL=1), indices=2, material=0)])],
        materials=[material],
        accessors=[
            g.Accessor(bufferView=0, componentType=g.FLOAT, count=n_pos, type=g.VEC3,
                       max=pos.max(axis=0).tolist(), min=pos.min(axis=0).tolist()),
            g.Accessor(bufferView=1, componentType=g.FLOAT, count=n_pos, type=g.VEC3),
            g.Accessor(bufferView=2, componentType=g.UNSIGNED_INT, count=n_idx, type=g.SCALAR),
        ],
        bufferViews=[
            g.BufferView(buffer=0, byteOffset=0, byteLength=pos.nbytes, target=g.ARRAY_BUFFER),
            g.BufferView(buffer=0, byteOffset=pos.nbytes, byteLength=nrm.nbytes, target=g.ARRAY_BUFFER),
            g.BufferView(buffer=0, byteOffset=pos.nbytes + nrm.nbytes, byteLength=idx.nbytes, target=g.ELEMENT_ARRAY_BUFFER),
        ],
        buffers=[g.Buffer(byteLength=len(blob))],
        extensionsUsed=sorted(ext),
    )
    gl.set_binary_blob(blob)
    return b"".join(gl.save_to_bytes())


def _gltf_uses(params: dict[str, Any], ext: str) -> bool:
    if ext == "KHR_materials_ior":
        return float(params["ior"]) != 1.5
    if ext == "KHR_materials_diffuse_roughness":
        return float(params.get("diffuse_roughness", 0.0)) > 0
    return float(params["specular"]) != 1.0 or [float(x) for x in params["specular_color"]] != [1.0, 1.0, 1.0]
