"""The explorer in a real browser: Debian's chromium, headless, WebGL 2 on SwiftShader, driven by playwright.

* every model's GLSL compiles and links in the browser's WebGL 2 (GLSL ES 3.00);
* the page's GPU evaluation of brdf() (RGBA32F render target, read back) equals
  numpy's ``model.eval`` for the shared parity vectors and several parameter sets;
* the lit sphere shows the shading an independent formula predicts (Lambert:
  sRGB(kd cos θi) at the centre) and changes when a slider moves;
* the polar plot is drawn; a screenshot is taken (set BRDFKIT_WRITE_DOCS=1 to
  write it to docs/img/web_explorer.png).

Skipped, with the reason, when /usr/bin/chromium (Debian package ``chromium``) or
the Python package ``playwright`` is missing. Never runs ``playwright install``.
"""

from __future__ import annotations

import base64
import io
import math
import os
import shutil
from pathlib import Path

import numpy as np
import pytest

import brdfkit as bk
from brdfkit.render import glsl

CHROMIUM = "/usr/bin/chromium"
if not os.path.exists(CHROMIUM):
    pytest.skip(f"{CHROMIUM} not found (Debian: apt-get install chromium)", allow_module_level=True)
playwright_api = pytest.importorskip("playwright.sync_api", reason="the Python package playwright is not installed")
from PIL import Image  # noqa: E402

from brdfkit.web import start_in_thread  # noqa: E402

CHROMIUM_ARGS = [
    "--headless=new", "--no-sandbox", "--disable-gpu",
    "--use-gl=angle", "--use-angle=swiftshader", "--enable-unsafe-swiftshader",
    "--disable-background-networking", "--disable-component-update", "--disable-sync",
    "--no-first-run", "--disable-quic",
]
ROOT = Path(__file__).resolve().parents[1]


@pytest.fixture(scope="module")
def page():
    srv, thread = start_in_thread("127.0.0.1", 0)
    pw = playwright_api.sync_playwright().start()
    browser = pw.chromium.launch(executable_path=CHROMIUM, args=CHROMIUM_ARGS)
    pg = browser.new_page(viewport={"width": 1640, "height": 1000})
    errors: list[str] = []
    pg.on("pageerror", lambda e: errors.append(str(e)))
    pg.on("console", lambda m: errors.append(m.text) if m.type == "error" else None)
    pg.goto(srv.url)
    pg.wait_for_function("window.brdfkitStatus && window.brdfkitStatus.ready", timeout=90_000)
    pg.errors = errors
    try:
        yield pg
    finally:
        browser.close()
        pw.stop()
        srv.shutdown()
        srv.server_close()
        thread.join(5)


def settle(pg):
    """Redraw synchronously with the current control values (the page's own rAF redraw may still be pending)."""
    n = pg.evaluate("window.brdfkitStatus.frames")
    pg.evaluate("window.brdfkit.redraw()")
    assert pg.evaluate("window.brdfkitStatus.frames") > n


def canvas_rgb(pg, selector: str) -> np.ndarray:
    """The canvas's own pixels (toDataURL: exactly its width x height), RGB float."""
    url = pg.evaluate(f"document.querySelector({selector!r}).toDataURL('image/png')")
    png = base64.b64decode(url.split(",", 1)[1])
    return np.asarray(Image.open(io.BytesIO(png)).convert("RGB"), dtype=np.float64)


def srgb(c: float) -> float:
    c = min(max(c, 0.0), 1.0)
    return 12.92 * c if c <= 0.0031308 else 1.055 * c ** (1 / 2.4) - 0.055


def test_webgl2_and_every_model_compiles(page):
    st = page.evaluate("window.brdfkitStatus")
    assert st["error"] is None, st["error"]
    assert st["webgl2"] is True
    assert st["floatTargets"] is True
    assert sorted(st["models"]) == sorted(bk.models())
    failed = {n: s["error"] for n, s in st["models"].items() if not (s["ok"] and s["sphere"] and s["eval"])}
    assert not failed, f"shaders that do not compile in WebGL 2: {failed}"
    assert "all shaders compiled" in page.locator("#status").inner_text()
    assert not page.errors, page.errors


def _param_sets(name: str) -> list[dict]:
    """Defaults, every alternative choice / bool value, and a mid-range set (30% up each slider)."""
    cls = bk.registry.get(name)
    sets: list[dict] = [{}]
    for p in cls.spec:
        if p.kind == "choice":
            sets += [{p.name: c} for c in p.choices if c != p.default]
        elif p.kind == "bool":
            sets.append({p.name: not p.default})
    mid = {}
    for p in cls.spec:
        if p.kind not in ("scalar", "rgb") or p.name == "alpha":
            continue
        lo, hi = p.range
        hi = min(hi, 1e3)
        if p.log_scale:
            a = max(lo, hi * 1e-5)
            v = math.exp(math.log(a) + 0.3 * (math.log(hi) - math.log(a)))
        else:
            v = lo + 0.3 * (hi - lo)
        mid[p.name] = v if p.kind == "scalar" else [v, 0.8 * v + 0.2 * lo, 0.6 * v + 0.4 * lo]
    sets.append(mid)
    if name == "microfacet":
        sets.append({"alpha_x": 0.05, "alpha_y": 0.3, "distribution": "beckmann"})
    return sets


@pytest.mark.parametrize("name", bk.models())
def test_browser_gpu_eval_equals_numpy(page, name):
    v = glsl.parity_vectors(64)
    wi, wo = v["wi"], v["wo"]
    for params in _param_sets(name):
        got = np.asarray(page.evaluate("([n, p, a, b]) => window.brdfkit.evaluate(n, p, a, b)",
                                       [name, params, wi.tolist(), wo.tolist()])).reshape(-1, 3)
        ref = bk.model(name, **params).eval(wi.astype(np.float64), wo.astype(np.float64))
        assert np.all(np.isfinite(got)) and np.all(got >= 0), (name, params)
        tol = 1e-4 * np.abs(ref) + 1e-6 * np.abs(ref).max() + 1e-30
        bad = np.abs(got - ref) > tol
        assert not bad.any(), (
            f"{name} {params}: {bad.any(axis=1).sum()} of {len(ref)} pairs differ, e.g. kind "
            f"{v['kind'][bad.any(axis=1)][0]} browser {got[bad.any(axis=1)][0]} numpy {ref[bad.any(axis=1)][0]}")


def test_every_model_and_control_works_in_the_ui(page):
    """Select each model, operate each of its controls once; the sphere shows lit pixels, no script errors."""
    for name in bk.models():
        _set_model(page, "main", name)
        rows = page.locator("#panel-main .param")
        names = [rows.nth(i).get_attribute("data-param") for i in range(rows.count())]
        assert names == [p.name for p in bk.registry.get(name).spec]
        for pname in names:
            row = page.locator(f"#panel-main [data-param={pname}]")
            if row.locator("select").count():
                sel = row.locator("select")
                opts = sel.locator("option").all_inner_texts()
                sel.select_option(opts[-1])
            elif row.locator("input[type=checkbox]").count():
                row.locator("input[type=checkbox]").click()
            else:
                row.locator("input[type=range]").press("PageUp")
        settle(page)
        img = canvas_rgb(page, "#sphere")
        assert img.max() > 100, f"{name}: the sphere shows no lit pixel (background is 69)"
        page.locator("#panel-main .reset").click()
        settle(page)
    assert not page.errors, page.errors


def _set_model(pg, key: str, name: str):
    pg.select_option(f"#model-{key}", name)
    settle(pg)


def test_sphere_matches_lambert_and_reacts_to_sliders(page):
    _set_model(page, "compare", "")
    _set_model(page, "main", "lambert")
    # scene: light 45° from the view direction, exposure 0
    page.evaluate("""() => { for (const [id, v] of [['light-theta', 45], ['light-phi', 45], ['exposure', 0]]) {
        const e = document.getElementById(id); e.value = v; e.dispatchEvent(new Event('input')); } }""")
    settle(page)
    img0 = canvas_rgb(page, "#sphere")
    h, w, _ = img0.shape
    centre = img0[h // 2 - 2:h // 2 + 3, w // 2 - 2:w // 2 + 3].mean(axis=(0, 1))
    # Lambert, kd = 0.5, a light of radiance 1 (E = π) at 45° from the normal at the centre:
    # L_o = kd/π · cos 45° · π = 0.5 · 0.7071
    expected = 255 * srgb(0.5 * math.cos(math.radians(45)))
    assert np.all(np.abs(centre - expected) < 3), (centre, expected)
    # move the kd slider to its end (keyboard, as a user would): kd = 1
    page.locator("#panel-main [data-param=kd] input[type=range]").press("End")
    settle(page)
    assert page.locator("#panel-main [data-param=kd] input[type=number]").first.input_value() == "1"
    img1 = canvas_rgb(page, "#sphere")
    centre1 = img1[h // 2 - 2:h // 2 + 3, w // 2 - 2:w // 2 + 3].mean(axis=(0, 1))
    expected1 = 255 * srgb(1.0 * math.cos(math.radians(45)))
    assert np.all(np.abs(centre1 - expected1) < 3), (centre1, expected1)
    assert np.abs(img1 - img0).max() > 50
    # the light direction slider moves the lit side
    page.locator("#light-phi").press("PageUp")
    settle(page)
    img2 = canvas_rgb(page, "#sphere")
    assert np.abs(img2 - img1).mean() > 1.0


@pytest.mark.parametrize("phi_deg", [0, 90, 210])
def test_sphere_highlight_where_the_half_vector_is_the_normal(page, phi_deg):
    """A sharp Blinn-Phong lobe peaks where n = normalize(L + V): 22.5° from the view axis for a light at 45°."""
    _set_model(page, "compare", "")
    _set_model(page, "main", "blinn-phong")
    page.evaluate("""(phi) => {
        const p = window.brdfkit.panels.main;
        p.values.kd = [0, 0, 0]; p.values.shininess = 2000; p.refreshAll();
        for (const [id, v] of [['light-theta', 45], ['light-phi', phi], ['exposure', -7]]) {
            const e = document.getElementById(id); e.value = v; e.dispatchEvent(new Event('input')); } }""", phi_deg)
    settle(page)
    img = canvas_rgb(page, "#sphere").sum(axis=2)
    h, w = img.shape
    # the peak: ks (s+8)/(8π) · cos θi · π 2^-7 with θi = 22.5° (n is the half vector), ks = 0.3
    peak = 0.3 * 2008 / (8 * math.pi) * math.cos(math.radians(22.5)) * math.pi * 2.0 ** -7
    lo, hi = 3 * 255 * srgb(0.95 * peak), 3 * 255 * srgb(1.01 * peak) + 1.5  # the pixel grid may miss the top
    assert lo <= img.max() <= hi, (img.max(), lo, hi)
    ys, xs = np.nonzero(img >= img.max() - 3)
    y, x = ys.mean() + 0.5, xs.mean() + 0.5
    # pixel -> sphere: p = ((px / size) * 2 - 1) * 1.06, GL's y up; n.xy = sin(22.5°) (cos φ, sin φ)
    r = math.sin(math.radians(22.5)) / 1.06 * (w / 2)
    ex = w / 2 + r * math.cos(math.radians(phi_deg))
    ey = h / 2 - r * math.sin(math.radians(phi_deg))
    assert abs(x - ex) < 2.5 and abs(y - ey) < 2.5, ((x, y), (ex, ey))


def test_roughness_slider_changes_highlight_and_polar_plot(page):
    _set_model(page, "main", "microfacet")
    sphere0, polar0 = canvas_rgb(page, "#sphere"), canvas_rgb(page, "#polar")
    slider = page.locator("#panel-main [data-param=alpha] input[type=range]")
    for _ in range(3):
        slider.press("PageDown")
    settle(page)
    a = float(page.locator("#panel-main [data-param=alpha] input[type=number]").input_value())
    ax = float(page.locator("#panel-main [data-param=alpha_x] input[type=number]").input_value())
    assert a < 0.2 and ax == pytest.approx(a, rel=1e-3)  # alpha drives alpha_x = alpha_y
    sphere1, polar1 = canvas_rgb(page, "#sphere"), canvas_rgb(page, "#polar")
    assert np.abs(sphere1 - sphere0).max() > 30
    assert np.abs(polar1 - polar0).max() > 30
    # the lobe is drawn in the main colour (#d9480f)
    main = np.array([0xD9, 0x48, 0x0F], dtype=np.float64)
    assert (np.abs(polar1 - main).max(axis=2) < 40).sum() > 50
    # anisotropic: alpha becomes undefined, the note says so
    ay = page.locator("#panel-main [data-param=alpha_y] input[type=number]")
    ay.fill("0.5")
    ay.dispatch_event("change")
    settle(page)
    assert page.locator("#panel-main [data-param=alpha] input[type=number]").input_value() == ""
    assert "anisotropic" in page.locator("#panel-main [data-param=alpha] .note").inner_text()
    p = page.evaluate("window.brdfkit.panels.main.params()")
    assert "alpha" not in p and p["alpha_y"] == 0.5


def test_crosscheck_button_and_screenshot(page, tmp_path):
    _set_model(page, "main", "microfacet")
    _set_model(page, "compare", "cook-torrance")
    page.evaluate("""() => { for (const [id, v] of [['light-theta', 50], ['light-phi', 35], ['exposure', 0],
        ['theta-i', 40]]) { const e = document.getElementById(id); e.value = v; e.dispatchEvent(new Event('input')); } }""")
    settle(page)
    page.click("#crosscheck")
    page.wait_for_function("document.getElementById('crosscheck-out').textContent.includes('max rel')", timeout=30_000)
    text = page.locator("#crosscheck-out").inner_text()
    diffs = [float(part.rsplit(" ", 1)[1]) for part in text.split("; ")]
    assert len(diffs) == 2 and max(diffs) < 1e-4, text
    out = tmp_path / "web_explorer.png"
    page.screenshot(path=str(out), full_page=True)
    img = Image.open(out)
    assert img.size[0] >= 1200 and img.size[1] >= 600
    if os.environ.get("BRDFKIT_WRITE_DOCS") == "1":
        dest = ROOT / "docs" / "img" / "web_explorer.png"
        dest.parent.mkdir(parents=True, exist_ok=True)
        shutil.copyfile(out, dest)
    assert not page.errors, page.errors
