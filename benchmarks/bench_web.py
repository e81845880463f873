"""Frame rate of the explorer's lit sphere and lit object at 1024x768 in headless chromium.

Debian's chromium with WebGL 2 on SwiftShader (software, the CPU), as the browser tests
run it. Each figure is ``window.brdfkit.bench(view, 1024, 768, frames)``: the view drawn
into a 1024x768 canvas ``frames`` times by the page's own draw function, after one
warm-up frame; a case stops early (after at least 3 frames) past ``--budget`` seconds.
The sphere is one 750x750 tile (the canvas's height less the label line), every pixel
shaded. ``gl.finish()`` follows each frame, but in Chromium it returns before SwiftShader
has shaded (measured: 0.0 ms); the copy into the 2D canvas (``drawImage``) waits for the
work, so each frame's time is the shading plus the copy, as on the page.
Goal (issue 11): >= 30 fps for the sphere.

    python benchmarks/bench_web.py [--frames 20] [--budget 5]
"""

from __future__ import annotations

import argparse
import os
import sys
import time

CHROMIUM = "/usr/bin/chromium"
ARGS = [
    "--headless=new", "--no-sandbox", "--disable-gpu", "--use-gl=angle", "--use-angle=swiftshader",
    "--enable-unsafe-swiftshader", "--disable-background-networking", "--disable-component-update",
    "--disable-sync", "--no-first-run", "--disable-quic",
]

CASES = [
    ("sphere", {"model": "lambert", "params": {}}, {}),
    ("sphere", {"model": "microfacet", "params": {}}, {}),
    ("sphere", {"model": "merl/gold-metallic-paint", "params": {}}, {}),
    ("sphere", {"model": "htsg", "params": {}}, {}),
    ("object", {"model": "microfacet", "params": {}}, {"obj-mesh": "teapot", "obj-tess": 24, "obj-shading": "phong"}),
    ("object", {"model": "microfacet", "params": {}}, {"obj-mesh": "teapot", "obj-tess": 24, "obj-shading": "gouraud"}),
    ("object", {"model": "lambert", "params": {}},
     {"obj-mesh": "sphere", "obj-tess": 64, "obj-shading": "phong", "obj-material": "gl:gold"}),
]


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--frames", type=int, default=20)
    ap.add_argument("--budget", type=float, default=5.0, help="seconds per case: fewer frames (at least 3) past it")
    args = ap.parse_args()
    if not os.path.exists(CHROMIUM):
        print(f"brdfkit: error: {CHROMIUM} not found (Debian: apt-get install chromium)", file=sys.stderr)
        return 2
    from playwright.sync_api import sync_playwright

    from brdfkit.web import start_in_thread

    srv, thread = start_in_thread("127.0.0.1", 0)
    try:
        with sync_playwright() as pw:
            browser = pw.chromium.launch(executable_path=CHROMIUM, args=ARGS)
            page = browser.new_page(viewport={"width": 1024, "height": 768})
            page.goto(srv.url)
            page.wait_for_function("window.brdfkitStatus && window.brdfkitStatus.ready", timeout=120_000)
            print(f"renderer: {page.evaluate('window.brdfkitStatus.renderer')}; {os.cpu_count()} CPUs, "
                  f"load average {os.getloadavg()[0]:.1f} at the start; up to {args.frames} frames "
                  f"(or {args.budget:g} s) each at 1024x768")
            print(f"{'view':8s} {'material':28s} {'setting':34s} {'fps':>7s}")
            for view, brdf, settings in CASES:
                st = dict(brdf, compare=[], view=settings)
                page.evaluate("(s) => window.brdfkit.setState(s)", st)
                page.wait_for_function("window.brdfkit.meshReady()", timeout=60_000)
                t = time.time()
                r = page.evaluate("([v, n, b]) => window.brdfkit.bench(v, 1024, 768, n, b)", [view, args.frames, args.budget])
                label = settings.get("obj-material", brdf["model"]).replace("gl:", "OpenGL ")
                extra = ", ".join(f"{k[4:]}={v}" for k, v in settings.items() if k != "obj-material")
                print(f"{view:8s} {label:28s} {extra:34s} {r['fps']:7.1f}   ({r['frames']} frames, "
                      f"{time.time() - t:.1f} s, load {os.getloadavg()[0]:.1f})")
            browser.close()
    finally:
        srv.shutdown()
        srv.server_close()
        thread.join(5)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
