"""Rendering speed: frames per second at 1024×1024, Phong shading, a ~100k-triangle mesh, every model.

    .venv/bin/python benchmarks/bench_render.py                  # table
    .venv/bin/python benchmarks/bench_render.py --json           # JSON list on stdout
    .venv/bin/python benchmarks/bench_render.py --size 512 --frames 3 --models ward,phong

The mesh is the Utah teapot tessellated to about 100k triangles (filling
roughly a third of the frame, the rest is background). Two lights (a point
light and a directional one), 4× MSAA into a float32 framebuffer. For every
material — OpenGL's fixed-function model, each registered BRDF with a GLSL
file, and a measured material (``--measured``: its MERL table looked up in a 3D
texture by ``shaders/measured.glsl``) — two figures:

``draw fps``   the GL draw alone (program, buffers and framebuffer made once;
               each frame: clear, draw, glFinish) — the shading throughput;
``frame fps``  the whole ``brdfkit.render.render`` call: buffers and framebuffer
               made, drawn, MSAA resolved, read back to numpy, tone-mapped.

Image-based lighting (``--ibl ENV``, default ``studio``; ``''`` to skip): for a few
materials (``--ibl-models``), the time per sample per pixel of the progressive IBL
path at the same size (``Renderer.time_ibl_pass``: passes of 8 samples, each one
BRDF-sampled and one environment-sampled direction with MIS, resolved and read back).

Best of ``--frames`` timed frames after a warm-up. The GL renderer string is
printed with the table (Mesa llvmpipe on a machine without a GPU). The load
average is printed too: figures taken on a busy machine are lower bounds.
"""

from __future__ import annotations

import argparse
import json
import os
import sys
import time



def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--size", type=int, default=1024)
    ap.add_argument("--frames", type=int, default=3)
    ap.add_argument("--subdivisions", type=int, default=40, help="teapot patch grid (40 -> ~100k triangles)")
    ap.add_argument("--models", default="", help="comma-separated registry names (default: all with GLSL)")
    ap.add_argument(
        "--measured",
        default="merl/gold-metallic-paint",
        help="comma-separated built-in measured materials, rendered through the MERL 3D-texture GLSL "
        "(default: merl/gold-metallic-paint; '' for none)",
    )
    ap.add_argument("--ibl", default="studio", help="environment for the IBL timing ('' to skip)")
    ap.add_argument("--ibl-models", default="lambert,microfacet,merl/chrome-steel",
                    help="comma-separated materials for the IBL timing")
    ap.add_argument("--json", action="store_true")
    args = ap.parse_args(argv)

    import brdfkit as bk
    from brdfkit import opengl
    from brdfkit.render import default_renderer, glsl, make_scene, meshes, render

    mesh = meshes.teapot(args.subdivisions)
    names = [n for n in (args.models.split(",") if args.models else bk.models()) if n]
    materials: list[tuple[str, object]] = []
    if not args.models:
        materials.append(("opengl (gold)", opengl.MATERIALS["gold"]))
    for n in names:
        if glsl.has_shader(n):
            materials.append((n, bk.model(n)))
    for n in (m for m in args.measured.split(",") if m):
        # the table is tabulated and uploaded once, before the timed frames
        materials.append((f"{n.split('/')[-1]} (MERL)", bk.material(n)))
    lights = [
        opengl.Light(position=(-2.5, 3.0, 3.0, 1.0), diffuse=(1, 1, 1)),
        opengl.Light(position=(1.0, 0.5, 1.0, 0.0), diffuse=(0.3, 0.3, 0.3)),
    ]
    r = default_renderer()
    rows = []
    for label, mat in materials:
        scene = make_scene(mesh=mesh, material=mat, shading="phong", size=(args.size, args.size), lights=lights)
        draw = r.time_draws(scene, args.frames)
        render(scene)  # warm-up
        best = float("inf")
        for _ in range(args.frames):
            t0 = time.perf_counter()
            render(scene)
            best = min(best, time.perf_counter() - t0)
        draw_best = min(draw, r.time_draws(scene, 1))
        rows.append(
            {
                "material": label,
                "triangles": mesh.n_triangles,
                "size": args.size,
                "draw_ms": draw_best * 1e3,
                "draw_fps": 1.0 / draw_best,
                "frame_ms": best * 1e3,
                "frame_fps": 1.0 / best,
            }
        )
        if not args.json:
            print(f"  {label:20s} draw {1/draw_best:8.2f} fps   frame {1/best:8.2f} fps", file=sys.stderr)
    ibl_rows = []
    if args.ibl:
        from brdfkit.render.environment import environment_from_spec

        env = environment_from_spec(args.ibl)[0]
        for n in (m for m in args.ibl_models.split(",") if m):
            mat = bk.material(n) if "/" in n else bk.model(n)
            scene = make_scene(mesh=mesh, material=mat, shading="phong", size=(args.size, args.size))
            scene.environment = env
            per = r.time_ibl_pass(scene, passes=max(1, args.frames))
            ibl_rows.append({"material": n, "environment": env.name, "size": args.size, "ms_per_sample": per * 1e3})
            if not args.json:
                print(f"  IBL {n:20s} {per * 1e3:8.1f} ms per sample per pixel", file=sys.stderr)
    info = r.info
    if args.json:
        print(json.dumps({"gl": info, "load": os.getloadavg(), "rows": rows, "ibl": ibl_rows}))
        return 0
    from rich.console import Console
    from rich.table import Table

    t = Table(title=f"Phong shading, {args.size}×{args.size}, teapot {mesh.n_triangles} triangles, 4× MSAA")
    for c in ("material", "draw ms", "draw fps", "frame ms", "frame fps"):
        t.add_column(c, justify="right" if c != "material" else "left")
    for row in rows:
        t.add_row(
            row["material"],
            f"{row['draw_ms']:.1f}",
            f"{row['draw_fps']:.2f}",
            f"{row['frame_ms']:.1f}",
            f"{row['frame_fps']:.2f}",
        )
    con = Console()
    con.print(t)
    if ibl_rows:
        ti = Table(title=f"Image-based lighting ({args.ibl}), {args.size}×{args.size}, 4× MSAA: time per sample")
        for c in ("material", "ms / sample", "s for 64 samples"):
            ti.add_column(c, justify="right" if c != "material" else "left")
        for row in ibl_rows:
            ti.add_row(row["material"], f"{row['ms_per_sample']:.1f}", f"{row['ms_per_sample'] * 64e-3:.1f}")
        con.print(ti)
    con.print(f"GL: {info['GL_RENDERER']} / {info['GL_VERSION']}; load average {os.getloadavg()[0]:.2f}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
