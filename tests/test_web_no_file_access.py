"""A request from the page can never make the server read a file it names (a .brdf or MERL path)."""

from __future__ import annotations

import http.client
import json
import shutil
from pathlib import Path
from urllib.parse import quote

import pytest

from brdfkit.web import start_in_thread

DATA = Path(__file__).parent / "data"


@pytest.fixture()
def srv():
    server, thread = start_in_thread("127.0.0.1", 0)
    yield server
    server.shutdown()
    server.server_close()


def _get(server, path: str) -> tuple[int, bytes]:
    conn = http.client.HTTPConnection("127.0.0.1", server.server_address[1], timeout=30)
    conn.request("GET", path)
    r = conn.getresponse()
    body = r.read()
    conn.close()
    return r.status, body


@pytest.mark.parametrize(
    "route",
    [
        "/api/eval?model={}&wi=0,0,1&wo=0,0,1",
        "/api/shader/{}",
        "/api/validate?model={}",
        "/api/albedo?model={}",
    ],
)
def test_brdf_paths_are_refused(srv, tmp_path, route):
    # a valid .brdf file the server could read if it resolved paths; a broken one whose line it could quote
    good = tmp_path / "ward.brdf"
    shutil.copy(DATA / "ward.brdf", good)
    bad = tmp_path / "secret.brdf"
    bad.write_text("::begin parameters\nTOP-SECRET-LINE\n::end parameters\n")
    for f in (good, bad):
        status, body = _get(srv, route.format(quote(str(f), safe="")))
        text = body.decode("utf-8", "replace")
        assert "TOP-SECRET-LINE" not in text
        assert str(tmp_path) not in text
        if status == 200:  # /api/validate answers 200 with ok=false
            assert json.loads(text)["ok"] is False
        else:
            assert status in (400, 404)


def test_names_still_work(srv):
    status, body = _get(srv, "/api/eval?model=lambert&wi=0,0,1&wo=0,0,1")
    assert status == 200
    assert json.loads(body)["value"][0] == pytest.approx(0.5 / 3.141592653589793, rel=1e-12)
    status, body = _get(srv, "/api/eval?model=" + quote("merl/chrome", safe="") + "&wi=0,0,1&wo=0,0,1")
    assert status == 200 and min(json.loads(body)["value"]) > 0


@pytest.mark.parametrize("route", ["/api/validate", "/api/albedo", "/api/ibl/sampler", "/api/eval"])
def test_deeply_nested_params_are_a_client_error(srv, route):
    deep = quote("[" * 5000 + "]" * 5000, safe="")
    dirs = "&wi=0,0,1&wo=0,0,1" if route == "/api/eval" else ""
    status, body = _get(srv, f"{route}?model=lambert&params={deep}{dirs}")
    assert status in (200, 400)
    doc = json.loads(body)
    assert "nested deeper" in (doc.get("error") or "")
    if status == 200:
        assert doc["ok"] is False
