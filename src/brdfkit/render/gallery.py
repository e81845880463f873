"""``brdfkit gallery``: the lecture's figures, rendered with real OpenGL and labelled.

Each figure is a grid of panels with a caption under every panel and a title:

``materials``              the lecture's 12-material OpenGL table, as spheres (fixed-function, Gouraud)
``gouraud-vs-phong``       flat / Gouraud / Phong shading on a coarse and a fine sphere: the
                           highlight that falls inside a big triangle is missed by Gouraud
``phong-vs-blinn-phong``   Phong's (r·v)^s and Blinn's (n·h)^s lobes, on a sphere and on a plane
                           seen at a grazing angle (Blinn's highlight stretches, Phong's stays round)
``lambert-vs-oren-nayar``  a matte sphere, lit from the viewer and from the side
``cook-torrance-metals``   Cook–Torrance 1982 metals (index of refraction from the normal-incidence
                           reflectance, as the paper does) and a roughness sweep, in the studio environment
``ward-anisotropic``       Ward's brushed (anisotropic) highlight against the isotropic one
``measured``               six measured MERL materials (built-in Neural-BRDF networks, tabulated
                           to the MERL grid and looked up in a 3D texture by ``shaders/measured.glsl``),
                           in the studio environment
``metals-ibl``             gold, copper, silver, aluminium (microfacet, complex index, multiple
                           scattering) and four measured metals, in the studio environment
``white-furnace``          microfacet spheres (F = 1) in a uniform white environment at increasing
                           roughness, single scattering vs the Kulla-Conty compensation: a sphere that
                           conserves energy disappears into the background
``microsurfaces``          the lecture's three microfacet pictures made by tracing light through
                           explicit surfaces (:mod:`brdfkit.microsurfaces.figures`): paths coloured by
                           bounce, traced G1 beside Smith's and the V-groove formula, traced albedo
                           split by bounce beside the Kulla-Conty compensation. Plots, not renders:
                           three PNGs, made where Mitsuba 3's llvm variant runs (``brdfkit[measure]``)
                           and skipped with a note elsewhere

The figures lit by an environment (``cook-torrance-metals``, ``measured``, ``metals-ibl``,
``white-furnace``) use image-based lighting (:mod:`brdfkit.render.environment`,
``shaders/ibl.glsl``) with ``IBL_SAMPLES`` samples per pixel.

Nothing is downloaded: meshes are built in, materials are the registered models.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Callable, Sequence

import numpy as np

from .. import opengl, sources
from ..measured.nbrdf import material
from ..geometry import normalize, reflect
from ..opengl import Light, LightModel
from .camera import DEFAULT_CAMERA, look_at

# --------------------------------------------------------------------------- panels


@dataclass
class Panel:
    caption: str
    mesh: Any
    material: Any
    shading: str = "phong"
    camera: dict | None = None
    lights: Sequence[Light] | None = None
    light_model: LightModel | None = None
    exposure: float = 1.0
    environment: Any = None  # a built-in name or an environment spec: image-based lighting
    samples: int = 64
    look: Any = None  # a scene.Look replacing the material's default look (exposure then ignored)


def _available_everywhere() -> str | None:
    """The default ``unavailable()``: no reason, the figure can be made anywhere."""
    return None


@dataclass
class Figure:
    """A grid of rendered panels; ``unavailable()`` gives the reason it cannot be made here, or None."""

    name: str
    title: str
    columns: int
    panels: Callable[[], list[Panel]] = field(repr=False)
    unavailable: Callable[[], str | None] = field(repr=False, default=_available_everywhere)


FRONT = {"eye": [0.0, 0.0, 3.6], "target": [0.0, 0.0, 0.0], "up": [0.0, 1.0, 0.0], "fov_deg": 36.0}
ABOVE = DEFAULT_CAMERA  # slightly above the equator
TEAPOT_CAM = {"eye": [0.0, 1.1, 3.4], "target": [0.0, -0.05, 0.0], "up": [0.0, 1.0, 0.0], "fov_deg": 33.0}

GL_LIGHT = [Light(position=(-1.0, 1.0, 1.0, 0.0), diffuse=(1, 1, 1), specular=(1, 1, 1))]

STUDIO = [  # key (point), fill (directional, dim), rim from behind-right
    Light(position=(-2.5, 3.0, 3.0, 1.0), diffuse=(1.0, 1.0, 1.0)),
    Light(position=(2.0, 0.5, 1.0, 0.0), diffuse=(0.25, 0.25, 0.28)),
    Light(position=(1.5, 2.0, -2.0, 0.0), diffuse=(0.35, 0.35, 0.35)),
]
STUDIO_AMBIENT = LightModel(ambient=(0.08, 0.08, 0.08))


def world_light(direction, camera: dict, **kw) -> Light:
    """A directional light shining from world ``direction``, expressed in the camera's eye space."""
    mv = look_at(camera["eye"], camera.get("target", (0, 0, 0)), camera.get("up", (0, 1, 0)))
    d = normalize(mv[:3, :3] @ np.asarray(direction, dtype=np.float64))
    return Light(position=tuple(d) + (0.0,), **kw)


def _materials() -> list[Panel]:
    return [
        Panel(name, {"builtin": "sphere", "segments": 96, "rings": 48}, opengl.MATERIALS[name], "gouraud", FRONT, GL_LIGHT)
        for name in opengl.MATERIALS
    ]


def _highlight_light(theta_deg: float, phi_deg: float) -> Light:
    """A directional light whose highlight (infinite viewer, n = h) sits at the sphere point (θ from +y, φ)."""
    t, p = math.radians(theta_deg), math.radians(phi_deg)
    n = np.array([math.sin(t) * math.sin(p), math.cos(t), math.sin(t) * math.cos(p)])
    l = reflect(np.array([0.0, 0.0, 1.0]), n)  # the mirror of the view direction (0, 0, 1)
    return Light(position=tuple(l) + (0.0,), diffuse=(1, 1, 1), specular=(1, 1, 1))


def _gouraud_vs_phong() -> list[Panel]:
    # The coarse sphere's vertices sit every 30° in θ and φ; the highlight is put at the
    # centre of a face (θ = 75°, φ = 15°, 21° from the nearest vertices): chrome's lobe
    # ((n·h)^76.8) has fallen to ~0.5% there, so Gouraud shading loses it.
    light = [_highlight_light(75.0, -15.0), Light(position=(-1, 0.2, 0.6, 0), diffuse=0.15, specular=0.0)]
    coarse = {"builtin": "sphere", "segments": 12, "rings": 6}
    fine = {"builtin": "sphere", "segments": 96, "rings": 48}
    out = []
    for label, mesh in (("12×6 sphere", coarse), ("96×48 sphere", fine)):
        for shading in ("flat", "gouraud", "phong"):
            out.append(Panel(f"{shading}, {label}", mesh, opengl.MATERIALS["chrome"], shading, FRONT, light))
    return out


def _phong_vs_blinn() -> list[Panel]:

    sphere = {"builtin": "sphere", "segments": 96, "rings": 48}
    plane = {"builtin": "plane", "divisions": 64, "half_size": 4.0}
    graze_cam = {"eye": [0.0, 0.45, 3.0], "target": [0.0, 0.0, 0.0], "up": [0.0, 1.0, 0.0], "fov_deg": 40.0}
    # a light low over the far side of the plane, toward the camera: grazing incidence,
    # placed at the mirror image of the camera so that the highlight sits mid-picture
    graze_light = [world_light((0.0, 0.45, -3.0), graze_cam, diffuse=(1, 1, 1))]
    key = [Light(position=(-1.0, 1.0, 1.0, 0.0), diffuse=(1, 1, 1))]
    kw = dict(kd=(0.05, 0.12, 0.3), ks=0.6)
    mats = [
        ("Phong, s = 64", sources.model("phong", shininess=64, **kw)),
        ("Blinn-Phong, s = 64", sources.model("blinn-phong", shininess=64, **kw)),
        ("Blinn-Phong, s = 256", sources.model("blinn-phong", shininess=256, **kw)),
    ]
    out = [Panel(c, sphere, m, "phong", FRONT, key, LightModel(ambient=0.1)) for c, m in mats]
    out += [Panel(c + ", grazing", plane, m, "phong", graze_cam, graze_light, LightModel(ambient=0.1), 0.3) for c, m in mats]
    return out


def _lambert_vs_oren_nayar() -> list[Panel]:

    sphere = {"builtin": "sphere", "segments": 96, "rings": 48}
    kd = (0.75, 0.6, 0.45)
    mats = [
        ("Lambert", sources.model("lambert", kd=kd)),
        ("Oren-Nayar, σ = 0.35", sources.model("oren-nayar", kd=kd, sigma=0.35)),
        ("Oren-Nayar, σ = 1.0", sources.model("oren-nayar", kd=kd, sigma=1.0)),
    ]
    head = [Light(position=(0.0, 0.0, 1.0, 0.0), diffuse=(1, 1, 1))]
    side = [Light(position=(-1.0, 0.3, 0.35, 0.0), diffuse=(1, 1, 1))]
    lm = LightModel(ambient=0.0)
    out = [Panel(c + ", light at the eye", sphere, m, "phong", FRONT, head, lm) for c, m in mats]
    out += [Panel(c + ", light at the side", sphere, m, "phong", FRONT, side, lm) for c, m in mats]
    return out


def _ior_from_f0(f0: Sequence[float]) -> tuple[float, ...]:
    """Cook & Torrance (1982): n = (1 + √F0) / (1 − √F0), the real index with that normal reflectance."""
    return tuple(min(999.0, (1 + math.sqrt(f)) / (1 - math.sqrt(f))) for f in f0)


METALS = {  # normal-incidence reflectance (linear RGB), commonly tabulated values
    "gold": (0.99, 0.71, 0.29),
    "copper": (0.95, 0.64, 0.54),
    "silver": (0.95, 0.93, 0.88),
    "aluminium": (0.91, 0.92, 0.92),
}


def _cook_torrance_metals() -> list[Panel]:

    teapot = {"builtin": "teapot", "subdivisions": 10}
    out = []
    # lit by the studio environment: under the former point lights the metals' colours were
    # unreadable (copper pale pink-grey, silver = aluminium, 6 % of the pixels clipped); the
    # exposure 0.6 makes up for the 1982 formula's 1/π, 4x the modern 1/4 (docs/physics.md)
    for name, f0 in METALS.items():
        m = sources.model("cook-torrance", kd=0.0, ks=1.0, m=0.2, ior=_ior_from_f0(f0))
        out.append(Panel(f"{name}, m = 0.2", teapot, m, "phong", TEAPOT_CAM, exposure=0.6, environment="studio",
                         samples=IBL_SAMPLES))
    for rough in (0.08, 0.15, 0.3, 0.5):
        m = sources.model("cook-torrance", kd=0.0, ks=1.0, m=rough, ior=_ior_from_f0(METALS["gold"]))
        out.append(Panel(f"gold, m = {rough:g}", teapot, m, "phong", TEAPOT_CAM, exposure=0.6, environment="studio",
                         samples=IBL_SAMPLES))
    return out


def _ward() -> list[Panel]:

    sphere = {"builtin": "sphere", "segments": 96, "rings": 48}
    torus = {"builtin": "torus"}
    kw = dict(kd=(0.1, 0.1, 0.12), ks=0.25)
    mats = [
        ("isotropic, α = 0.15", sources.model("ward", alpha_x=0.15, alpha_y=0.15, **kw)),
        ("brushed, αx = 0.04, αy = 0.4", sources.model("ward", alpha_x=0.04, alpha_y=0.4, **kw)),
        ("brushed, αx = 0.4, αy = 0.04", sources.model("ward", alpha_x=0.4, alpha_y=0.04, **kw)),
    ]
    lights = [Light(position=(-2.0, 2.5, 3.0, 1.0), diffuse=(1, 1, 1))]
    lm = LightModel(ambient=0.1)
    out = [Panel(f"sphere, {c}", sphere, m, "phong", FRONT, lights, lm) for c, m in mats]
    out += [Panel(f"torus, {c}", torus, m, "phong", ABOVE, lights, lm) for c, m in mats]
    return out


CONDUCTORS = {  # complex refractive index eta + i k at the sRGB primaries (Mitsuba 3's RGB values)
    "gold": ((0.143119, 0.374957, 1.442479), (3.983160, 2.385721, 1.603215)),
    "copper": ((0.200438, 0.924033, 1.102212), (3.912949, 2.452848, 2.142188)),
    "silver": ((0.155265, 0.116723, 0.138342), (4.828181, 3.122249, 2.146961)),
    "aluminium": ((1.657460, 0.880369, 0.521229), (9.223869, 6.269523, 4.837001)),
}
IBL_SAMPLES = 64
"""Samples per pixel of the gallery's image-based lighting (each: one BRDF and one environment sample)."""


def _metals_ibl() -> list[Panel]:

    teapot = {"builtin": "teapot", "subdivisions": 10}
    out = []
    for name, (eta, k) in CONDUCTORS.items():
        m = sources.model("microfacet", alpha=0.12, eta=eta, k=k, multiscatter=True)
        out.append(Panel(f"{name}, α = 0.12", teapot, m, "phong", TEAPOT_CAM, environment="studio", samples=IBL_SAMPLES))
    for name in ("merl/chrome", "merl/brass", "merl/aluminium", "merl/nickel"):
        out.append(Panel(name.split("/", 1)[1] + " (measured)", teapot, material(name), "phong", TEAPOT_CAM,
                         environment="studio", samples=IBL_SAMPLES))
    return out


FURNACE_ALPHAS = (0.25, 0.5, 0.75, 1.0)


def _white_furnace() -> list[Panel]:
    from .scene import Look

    sphere = {"builtin": "sphere", "segments": 96, "rings": 48}
    look = Look("clamp", 0.8, True)  # radiance 1 (the furnace) maps to the same grey as the background
    out = []
    for ms in (False, True):
        for a in FURNACE_ALPHAS:
            m = sources.model("microfacet", alpha=a, fresnel="none", multiscatter=ms)
            cap = f"α = {a:g}, " + ("multiple scattering" if ms else "single scattering")
            out.append(Panel(cap, sphere, m, "phong", FRONT, environment="furnace", samples=IBL_SAMPLES, look=look))
    return out


MEASURED = (
    "merl/gold-metallic-paint",
    "merl/blue-metallic-paint",
    "merl/chrome-steel",
    "merl/red-specular-plastic",
    "merl/alum-bronze",
    "merl/pink-fabric",
)
"""The built-in measured materials of the ``measured`` figure."""


def _measured() -> list[Panel]:

    sphere = {"builtin": "sphere", "segments": 96, "rings": 48}
    # lit by the studio environment: under the former two point lights chrome-steel (a near
    # mirror) was black but for one tiny highlight
    return [Panel(name.split("/", 1)[1], sphere, material(name), "phong", FRONT, environment="studio",
                  samples=IBL_SAMPLES) for name in MEASURED]


@dataclass
class PlotFigure:
    """A figure plotted from a simulation (matplotlib), not rendered: ``files()`` maps each PNG's name to
    the function that writes it; ``unavailable()`` gives the reason it cannot run here, or None."""

    name: str
    title: str
    files: Callable[[], dict[str, Callable[[Path], Path]]] = field(repr=False)
    unavailable: Callable[[], str | None] = field(repr=False, default=_available_everywhere)


def _microsurface_plots() -> dict[str, Callable[[Path], Path]]:
    from ..microsurfaces import figures as mf

    return {"microsurfaces-paths.png": mf.cross_section, "microsurfaces-masking.png": mf.masking_curves,
            "microsurfaces-albedo.png": mf.albedo_split}


def _microsurfaces_unavailable() -> str | None:
    from ..microsurfaces.engines import available

    if available("mitsuba-llvm"):
        return None
    return "it traces with Mitsuba 3's llvm_ad_rgb variant, not available here (pip install 'brdfkit[measure]'; LLVM)"


FIGURES: dict[str, Figure | PlotFigure] = {
    f.name: f
    for f in (
        Figure("materials", "The lecture's OpenGL materials (fixed-function lighting, Gouraud shading)", 6, _materials),
        Figure("gouraud-vs-phong", "Flat, Gouraud and Phong shading of chrome: the highlight inside a big triangle", 3, _gouraud_vs_phong),
        Figure("phong-vs-blinn-phong", "Phong (r·v)^s vs Blinn-Phong (n·h)^s: round vs stretched highlights", 3, _phong_vs_blinn),
        Figure("lambert-vs-oren-nayar", "Lambert vs Oren-Nayar on a matte sphere: rough surfaces look flat", 3, _lambert_vs_oren_nayar),
        Figure("cook-torrance-metals", "Cook-Torrance (1982) metals, and gold from smooth to rough (studio environment)", 4, _cook_torrance_metals),
        Figure("ward-anisotropic", "Ward's anisotropic (brushed) highlight vs the isotropic one", 3, _ward),
        Figure("measured", "Measured materials (MERL, as Neural-BRDF networks) in the studio environment", 6, _measured),
        Figure("metals-ibl", "Metals (microfacet, complex index) and measured materials in the studio environment", 4, _metals_ibl),
        Figure("white-furnace", "White furnace (F = 1): single scattering loses energy, Kulla-Conty compensation restores it", 4, _white_furnace),
        PlotFigure("microsurfaces", "Shadowing, masking and inter-reflection, traced through explicit microsurfaces",
                   _microsurface_plots, _microsurfaces_unavailable),
    )
}


def gallery_names(only: Sequence[str] | None, notify: Callable[[str], None] = lambda m: None) -> list[str]:
    """The figures to make: ``only`` (each must exist and be able to run here: a ValueError otherwise),
    or every figure that can run here (the others named through ``notify``)."""
    if only:
        for n in only:
            if n not in FIGURES:
                raise ValueError(f"unknown figure {n!r}; valid figures: {', '.join(FIGURES)}")
            why = FIGURES[n].unavailable()
            if why:
                raise ValueError(f"figure {n!r} cannot be made here: {why}")
        return list(only)
    names = []
    for n, f in FIGURES.items():
        why = f.unavailable()
        if why:
            notify(f"skipped figure {n!r}: {why}")
        else:
            names.append(n)
    return names


# --------------------------------------------------------------------------- drawing


def _font(px: int):
    from PIL import ImageFont

    try:
        from matplotlib import font_manager

        return ImageFont.truetype(font_manager.findfont("DejaVu Sans"), px)
    except Exception:  # pragma: no cover - matplotlib is a dependency, but be safe
        try:
            return ImageFont.load_default(size=px)
        except TypeError:
            return ImageFont.load_default()


def _fitting_font(draw, text: str, px: int, width: int):
    """The largest font of at most ``px`` pixels (and at least 7) in which ``text`` fits ``width``."""
    size = px
    while True:
        f = _font(size)
        if size <= 7 or draw.textlength(text, font=f) <= width:
            return f
        size -= 1


def render_panel(panel: Panel, size: int, mesh_cache: dict) -> np.ndarray:
    """One panel as uint8 RGB (size × size)."""
    from .meshes import mesh_from_spec
    from .scene import Look, default_look, make_scene, render

    key = repr(panel.mesh)
    if key not in mesh_cache:
        mesh_cache[key] = mesh_from_spec(panel.mesh)
    scene = make_scene(
        mesh=mesh_cache[key],
        material=panel.material,
        shading=panel.shading,
        size=(size, size),
        camera=panel.camera,
        lights=list(panel.lights) if panel.lights is not None else None,
        light_model=panel.light_model,
        background=(0.0, 0.0, 0.0, 1.0),
        antialias=True,
    )
    if panel.environment is not None:
        from .environment import environment_from_spec

        scene.environment = environment_from_spec(panel.environment)[0]
        scene.samples = panel.samples
        scene.__post_init__()  # validate the combination
    d = default_look(scene.material)
    frame = render(scene, panel.look or Look(d.tonemap, panel.exposure, d.srgb))
    return frame.uint8[..., :3]


def compose(title: str, images: list[np.ndarray], captions: list[str], columns: int) -> Any:
    """A labelled grid (PIL image): title on top, a caption under each panel."""
    from PIL import Image, ImageDraw

    s = images[0].shape[0]
    rows = math.ceil(len(images) / columns)
    cap_px = max(11, s // 16)
    title_px = max(13, s // 12)
    pad = max(4, s // 40)
    cap_h = int(cap_px * 1.6)
    title_h = int(title_px * 2.0)
    W = columns * s + (columns + 1) * pad
    H = title_h + rows * (s + cap_h) + (rows + 1) * pad
    canvas = Image.new("RGB", (W, H), (24, 24, 24))
    draw = ImageDraw.Draw(canvas)
    tf = _fitting_font(draw, title, title_px, W - 2 * pad)
    draw.text((W / 2, title_h / 2 + pad / 2), title, fill=(235, 235, 235), font=tf, anchor="mm")
    for i, (img, cap) in enumerate(zip(images, captions)):
        r, c = divmod(i, columns)
        x = pad + c * (s + pad)
        y = title_h + pad + r * (s + cap_h + pad)
        canvas.paste(Image.fromarray(img), (x, y))
        cf = _fitting_font(draw, cap, cap_px, s - 4)
        draw.text((x + s / 2, y + s + cap_h / 2), cap, fill=(210, 210, 210), font=cf, anchor="mm")
    return canvas


def render_figure(
    fig: Figure,
    size: int = 256,
    advance: Callable[[], None] | None = None,
    mesh_cache=None,
    panels: list[Panel] | None = None,
):
    """The figure as a labelled PIL image; ``panels`` defaults to ``fig.panels()`` (pass them if already built)."""
    mesh_cache = {} if mesh_cache is None else mesh_cache
    panels = fig.panels() if panels is None else panels
    images = []
    for p in panels:
        images.append(render_panel(p, size, mesh_cache))
        if advance:
            advance()
    return compose(fig.title, images, [p.caption for p in panels], fig.columns)


def run_gallery(out_dir: str | Path, names: Sequence[str] | None = None, size: int = 256, progress: bool = True) -> list[Path]:
    """Render the figures ``names`` (all by default) into ``out_dir`` as PNG; returns the paths."""
    from rich.progress import BarColumn, MofNCompleteColumn, Progress, TextColumn, TimeElapsedColumn

    from ..fileio import atomic_open

    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    names = list(names) if names else list(FIGURES)
    figs = [FIGURES[n] for n in names]
    # built once: measured panels load networks; a plot figure's steps are its files
    panel_lists = [list(f.files().items()) if isinstance(f, PlotFigure) else f.panels() for f in figs]
    written: list[Path] = []
    mesh_cache: dict = {}
    with Progress(
        TextColumn("[bold]{task.description}"),
        BarColumn(),
        MofNCompleteColumn(),
        TimeElapsedColumn(),
        disable=not progress,
        transient=False,
    ) as bar:
        task = bar.add_task("gallery", total=sum(len(p) for p in panel_lists))
        for fig, panels in zip(figs, panel_lists):
            bar.update(task, description=fig.name)
            if isinstance(fig, PlotFigure):
                for fname, make in panels:
                    written.append(make(out / fname))  # each writes atomically
                    bar.advance(task)
                continue
            img = render_figure(fig, size, lambda: bar.advance(task), mesh_cache, panels)
            path = out / f"{fig.name}.png"
            with atomic_open(path, "wb") as fh:
                img.save(fh, format="PNG", optimize=True)
            written.append(path)
    return written
