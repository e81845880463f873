"""``brdfkit render`` and ``brdfkit gallery``."""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any, List, Optional

import typer


def _parse_size(text: str) -> list[int]:
    t = text.lower().replace("x", ",")
    parts = [p.strip() for p in t.split(",")]
    try:
        vals = [int(p) for p in parts]
    except ValueError:
        raise ValueError(f"--size: expected WIDTHxHEIGHT or a single number, got {text!r}") from None
    if len(vals) == 1:
        vals = vals * 2
    if len(vals) != 2 or min(vals) < 1 or max(vals) > 8192:
        raise ValueError(f"--size: expected WIDTHxHEIGHT with each in [1, 8192], got {text!r}")
    return vals


def _floats(text: str, n: tuple[int, ...], what: str) -> list[float]:
    try:
        vals = [float(p) for p in text.split(",")]
    except ValueError:
        raise ValueError(f"{what}: expected {' or '.join(map(str, n))} comma-separated numbers, got {text!r}") from None
    if len(vals) not in n:
        raise ValueError(f"{what}: expected {' or '.join(map(str, n))} comma-separated numbers, got {text!r}")
    return vals


def register(app: typer.Typer) -> None:
    @app.command("render")
    def render_cmd(
        output: Optional[Path] = typer.Option(None, "-o", "--output", help="output image: .png (display), .exr or .npy (linear float)"),
        scene: Optional[Path] = typer.Option(
            None, "--scene", help="JSON scene file ('example': the one shipped with brdfkit); the flags below override its fields"
        ),
        model: Optional[str] = typer.Option(None, "--model", "-m", help="a registered BRDF (see `brdfkit list`)"),
        param: Optional[List[str]] = typer.Option(None, "-p", "--param", help="model parameter name=value (repeatable)"),
        opengl_material: Optional[str] = typer.Option(
            None, "--opengl", help="an OpenGL fixed-function material from the lecture's table (e.g. gold)"
        ),
        measured: Optional[str] = typer.Option(
            None, "--measured", help="a built-in measured material (e.g. merl/gold-metallic-paint) or a measured file (.binary, .bin, .bsdf)"
        ),
        mesh: Optional[str] = typer.Option(None, "--mesh", help="sphere, torus, teapot, or an OBJ/PLY path"),
        shading: Optional[str] = typer.Option(None, "--shading", help="flat | gouraud | phong"),
        size: Optional[str] = typer.Option(None, "--size", help="WIDTHxHEIGHT (default 512x512)"),
        eye: Optional[str] = typer.Option(None, "--eye", help="camera position x,y,z (looks at the origin)"),
        fov: Optional[float] = typer.Option(None, "--fov", help="vertical field of view in degrees"),
        background: Optional[str] = typer.Option(None, "--background", help="r,g,b or r,g,b,a in [0, 1]"),
        antialias: Optional[bool] = typer.Option(None, "--antialias/--no-antialias", help="4x MSAA (default on)"),
        tonemap: Optional[str] = typer.Option(None, "--tonemap", help="clamp | reinhard | aces"),
        exposure: Optional[float] = typer.Option(None, "--exposure", help="linear exposure multiplier"),
        srgb: Optional[bool] = typer.Option(None, "--srgb/--no-srgb", help="sRGB-encode the picture"),
        backend: str = typer.Option("auto", "--backend", help="auto | glsl | numpy"),
        env: Optional[str] = typer.Option(
            None,
            "--env",
            help="image-based lighting: a built-in environment (see --list-envs) or an .exr/.hdr map; "
            "'none' for the point lights. Default for a BRDF or measured material with phong shading, "
            "the GLSL backend and no lights in the scene file: studio, not drawn behind the object",
        ),
        samples: Optional[int] = typer.Option(None, "--samples", help="samples per pixel of environment lighting (default 64)"),
        list_envs: bool = typer.Option(False, "--list-envs", help="list the built-in environments and exit"),
        as_json: bool = typer.Option(False, "--json", help="print what was rendered as JSON"),
    ) -> None:
        """Render a mesh with an OpenGL material or any BRDF (headless OpenGL)."""
        import time

        from .. import examples
        from ..cli_common import model_from_cli
        from . import scene as sc
        from ..fileio import check_output_path
        from .environment import BUILTINS, environment_from_spec
        from .image import IMAGE_SUFFIXES
        from .lighting import DEFAULT_ENVIRONMENT, uses_default_environment
        from .renderer import has_glsl

        if list_envs:
            if as_json:
                typer.echo(json.dumps([{"name": k, "description": v} for k, v in BUILTINS.items()]))
            else:
                for k, v in BUILTINS.items():
                    typer.echo(f"{k:10s} {v}")
            return
        if output is None:
            raise ValueError("render needs -o/--output (or --list-envs)")

        if scene is not None and str(scene) == examples.SCENE and not scene.exists():
            scene = examples.path("scene.json")
        obj: dict[str, Any] = sc.read_scene_file(scene) if scene is not None else {}
        base = scene.parent if scene is not None else None
        if sum(x is not None for x in (model, opengl_material, measured)) > 1:
            raise ValueError("give only one of --model, --opengl, --measured")
        if param and model is None:
            raise ValueError("-p/--param needs --model")
        if model is not None:
            material = model_from_cli(model, param or [])
        elif opengl_material is not None:
            from .. import opengl

            material = opengl.material_from_json(opengl_material)
        elif measured is not None:
            from ..sources import MEASURED, resolve

            material = resolve(measured, kinds=MEASURED)
        else:
            material = None
        if mesh is not None:
            obj["mesh"] = mesh
            base = None  # a --mesh path is relative to the working directory
        if shading is not None:
            obj["shading"] = shading
        if size is not None:
            obj["size"] = _parse_size(size)
        if eye is not None or fov is not None:
            cam = dict(obj.get("camera") or {})
            if "projection" in cam:
                raise ValueError("--eye/--fov cannot change a camera given as matrices")
            if eye is not None:
                cam["eye"] = _floats(eye, (3,), "--eye")
            if fov is not None:
                cam["fov_deg"] = fov
            obj["camera"] = cam
        if background is not None:
            obj["background"] = _floats(background, (3, 4), "--background")
        if antialias is not None:
            obj["antialias"] = antialias
        if tonemap is not None:
            obj["tonemap"] = tonemap
        if exposure is not None:
            obj["exposure"] = exposure
        if srgb is not None:
            obj["srgb"] = srgb
        if material is not None:
            obj["material"] = material  # an object: scene_from_json takes it as it is
        if env == "none":
            obj.pop("environment", None)
        elif env is not None:
            obj["environment"] = {"name": env} if env in BUILTINS else {"path": str(Path(env).absolute())}
        if samples is not None and isinstance(obj.get("environment"), dict):
            obj["environment"] = {**obj["environment"], "samples": samples}
        # the look: the material's defaults, then the scene file's fields, then the flags (already in obj)
        parsed, look = sc.scene_from_json(obj, base_dir=base)
        if env != "none" and uses_default_environment(
            parsed, lights_given=obj.get("lights") is not None,
            glsl=backend == "glsl" or (backend == "auto" and has_glsl(parsed.material)),
        ):
            default_env = {**DEFAULT_ENVIRONMENT, **({"samples": samples} if samples is not None else {})}
            parsed.environment, asked = environment_from_spec(default_env)
            parsed.samples = asked or parsed.samples
        if samples is not None and parsed.environment is None:
            raise ValueError("--samples needs environment lighting (--env, an environment in the scene file, or the default for a BRDF)")
        check_output_path(output, what="image", suffixes=IMAGE_SUFFIXES, notify=lambda m: typer.echo(f"brdfkit: {m}", err=True))
        t0 = time.perf_counter()
        frame = sc.render(parsed, look, backend=backend)
        dt = time.perf_counter() - t0
        frame.save(output)
        info = {
            "output": str(output),
            "size": list(parsed.size),
            "mesh": parsed.mesh.name,
            "triangles": parsed.mesh.n_triangles,
            "shading": parsed.shading,
            "material": getattr(parsed.material, "name", None) if not parsed.is_opengl else "opengl",
            "tonemap": look.tonemap,
            "srgb": look.srgb,
            "seconds": round(dt, 4),
        }
        if parsed.environment is not None:
            info["environment"] = parsed.environment.name
            info["samples"] = parsed.samples
        if as_json:
            typer.echo(json.dumps(info))
        else:
            lit = f", {parsed.environment.name} environment" if parsed.environment is not None else ""
            typer.echo(f"wrote {output} ({parsed.size[0]}x{parsed.size[1]}, {parsed.mesh.n_triangles} triangles{lit}, {dt:.2f} s)")

    @app.command("gallery")
    def gallery_cmd(
        out_dir: Path = typer.Option(Path("gallery"), "-o", "--output", help="folder for the images (created)"),
        size: int = typer.Option(256, "--size", help="pixels per panel (square)"),
        only: Optional[List[str]] = typer.Option(None, "--only", help="render only these figures (repeatable)"),
        as_json: bool = typer.Option(False, "--json", help="print the written files as JSON"),
    ) -> None:
        """The lecture's figures as labelled images (materials, Gouraud vs Phong, ...)."""
        from .gallery import gallery_names, run_gallery

        if size < 32 or size > 2048:
            raise ValueError(f"--size must be in [32, 2048], got {size}")
        names = gallery_names(only, notify=lambda m: typer.echo(f"brdfkit: {m}", err=True))
        from ..fileio import check_output_path

        check_output_path(out_dir, what="gallery", is_dir=True, notify=lambda m: typer.echo(f"brdfkit: {m}", err=True))
        written = run_gallery(out_dir, names, size=size, progress=not as_json)
        if as_json:
            typer.echo(json.dumps([str(p) for p in written]))
        else:
            typer.echo(f"wrote {len(written)} images to {out_dir}")
