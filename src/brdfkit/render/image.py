"""From the renderer's linear framebuffer to a picture: exposure, tone mapping, sRGB, background; PNG and EXR.

The renderer returns linear RGBA with premultiplied colour and coverage alpha.
:func:`to_display` un-premultiplies, multiplies by ``exposure``, applies the
tone curve, encodes (sRGB or not), and composites over the background — in
display space, as OpenGL's own antialiased framebuffer would:

``clamp``     ``min(x, 1)``
``reinhard``  ``x / (1 + x)`` (Reinhard et al. 2002, the global operator)
``aces``      Narkowicz's 2015 fit of the ACES filmic curve,
              ``x (2.51 x + 0.03) / (x (2.43 x + 0.59) + 0.14)``, clamped to [0, 1]

``srgb`` applies the IEC 61966-2-1 transfer function (linear below 0.0031308).

Defaults differ by material, on purpose:

* OpenGL fixed-function materials: ``clamp`` without sRGB encoding. OpenGL
  writes the clamped lit colour straight into the 8-bit framebuffer, so that
  is what brdfkit shows: the pictures are the ones OpenGL makes.
* BRDF materials produce radiance (scene-referred, unbounded): ``aces`` tone
  mapping and sRGB encoding.

:func:`save_image` writes 8-bit PNG (the display image) or EXR (the linear
float image, premultiplied RGBA, no tone mapping, no background), chosen by
the file's extension; ``.npy`` stores the linear float array. Every file is
written atomically (:mod:`brdfkit.fileio`: a temporary file beside it, then
``os.replace``), so an interrupted write leaves the previous file whole.
"""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np

from ..fileio import atomic_open, atomic_path

TONEMAPS = ("clamp", "reinhard", "aces")


def srgb_encode(x: np.ndarray) -> np.ndarray:
    """Linear [0, 1] -> sRGB-encoded [0, 1] (IEC 61966-2-1)."""
    x = np.clip(x, 0.0, 1.0)
    return np.where(x <= 0.0031308, 12.92 * x, 1.055 * np.power(x, 1 / 2.4) - 0.055)


def tonemap(x: np.ndarray, curve: str = "clamp") -> np.ndarray:
    """Apply a tone curve to linear, non-negative values; returns values in [0, 1]."""
    x = np.maximum(x, 0.0)
    if curve == "clamp":
        return np.minimum(x, 1.0)
    if curve == "reinhard":
        return x / (1.0 + x)
    if curve == "aces":
        return np.clip(x * (2.51 * x + 0.03) / (x * (2.43 * x + 0.59) + 0.14), 0.0, 1.0)
    raise ValueError(f"tonemap must be one of {', '.join(TONEMAPS)}; got {curve!r}")


def to_display(
    linear: np.ndarray,
    tonemap_curve: str = "clamp",
    exposure: float = 1.0,
    srgb: bool = False,
    background=(0.0, 0.0, 0.0, 1.0),
) -> np.ndarray:
    """Linear premultiplied RGBA (H, W, 4) -> display RGBA in [0, 1] (float64)."""
    if not np.isfinite(exposure) or exposure <= 0:
        raise ValueError(f"exposure must be a positive number, got {exposure}")
    lin = np.asarray(linear, dtype=np.float64)
    a = np.clip(lin[..., 3:4], 0.0, 1.0)
    rgb = lin[..., :3] / np.where(a > 0, a, 1.0)
    rgb = tonemap(rgb * exposure, tonemap_curve)
    if srgb:
        rgb = srgb_encode(rgb)
    bg = np.asarray(background, dtype=np.float64)
    out = np.empty(lin.shape[:2] + (4,))
    out[..., :3] = rgb * a + bg[:3] * (1 - a)
    out[..., 3:4] = a + bg[3] * (1 - a)
    return out


def to_uint8(display: np.ndarray) -> np.ndarray:
    """Display values in [0, 1] -> uint8, rounding to nearest (as OpenGL's unorm conversion)."""
    return np.clip(np.floor(np.asarray(display) * 255.0 + 0.5), 0, 255).astype(np.uint8)


def save_png(path: str | os.PathLike, display: np.ndarray) -> None:
    from PIL import Image

    img = to_uint8(display)
    mode = "RGBA" if img.shape[-1] == 4 else "RGB"
    if mode == "RGBA" and np.all(img[..., 3] == 255):
        img, mode = img[..., :3], "RGB"
    with atomic_open(path, "wb") as f:
        Image.fromarray(np.ascontiguousarray(img), mode).save(f, format="PNG")


def save_exr(path: str | os.PathLike, linear: np.ndarray) -> None:
    """Linear float RGBA (premultiplied) as a 32-bit float OpenEXR file."""
    lin = np.ascontiguousarray(np.asarray(linear, dtype=np.float32))
    try:
        import OpenEXR
    except ImportError:  # pragma: no cover
        OpenEXR = None
    if OpenEXR is not None and hasattr(OpenEXR, "File"):
        channels = {"RGBA": lin}
        header = {"compression": OpenEXR.ZIP_COMPRESSION, "type": OpenEXR.scanlineimage}
        with atomic_path(path) as tmp, OpenEXR.File(header, channels) as f:
            f.write(tmp)
        return
    try:  # pragma: no cover - fallback
        import imageio.v3 as iio

        with atomic_path(path) as tmp:
            iio.imwrite(tmp, lin, extension=".exr")
    except Exception as e:  # pragma: no cover
        raise OSError(f"cannot write EXR {path}: install the OpenEXR package ({e})") from None


def read_exr(path: str | os.PathLike) -> np.ndarray:
    """An EXR written by :func:`save_exr`, as (H, W, 4) float32."""
    import OpenEXR

    with OpenEXR.File(os.fspath(path)) as f:
        ch = f.channels()
        if "RGBA" in ch:
            return np.asarray(ch["RGBA"].pixels, dtype=np.float32)
        return np.stack([np.asarray(ch[c].pixels, dtype=np.float32) for c in "RGBA"], axis=-1)


IMAGE_SUFFIXES = (".png", ".exr", ".npy")


def save_image(path: str | os.PathLike, linear: np.ndarray, display: np.ndarray) -> None:
    """Write ``display`` (PNG) or ``linear`` (EXR, NPY) according to the file's extension."""
    suffix = Path(path).suffix.lower()
    if suffix not in IMAGE_SUFFIXES:
        raise ValueError(f"output must end in {', '.join(IMAGE_SUFFIXES)}; got {os.fspath(path)!r}")
    parent = Path(path).parent
    if not parent.exists():
        raise OSError(f"output directory does not exist: {parent}")
    if suffix == ".png":
        save_png(path, display)
    elif suffix == ".exr":
        save_exr(path, linear)
    else:
        save_npy(path, linear)


def save_npy(path: str | os.PathLike, linear: np.ndarray) -> None:
    """The linear float image as float32 ``.npy``, written atomically."""
    with atomic_open(path, "wb") as f:
        np.save(f, np.asarray(linear, dtype=np.float32))
