"""The HTTP server behind ``brdfkit serve``: a static single-page app and a small JSON API.

Standard library only (:mod:`http.server`, one thread per request). The page
(``static/index.html``, ``app.js``, ``style.css``: plain JavaScript and WebGL 2,
no build step, nothing fetched from outside) compiles every model's GLSL twin
(``render/shaders/<module>.glsl``) in the browser and renders with it.

API (every answer is JSON unless said otherwise; bad input gives status 400
and ``{"error": "<one line>"}``, an unknown path 404, the same shape):

``GET /api/models``
    ``{"models": [info, ...]}``: for every registered model its
    ``bk.model_info`` (name, title, reference, isotropic, params) where each
    parameter row also carries ``log_scale``, ``open_lo``, ``open_hi`` and
    ``uniform`` (its GLSL uniform name and type), plus ``glsl`` (whether the
    model has a GLSL twin).
``GET /api/shader/<model>``
    the model's GLSL ES 3.00 source as ``text/plain``: ``#version 300 es``,
    then :func:`brdfkit.render.glsl.shader_source` (common.glsl + the model's
    file), defining ``vec3 brdf(vec3 wi, vec3 wo)``; the page appends a ``main``.
``GET /api/eval?model=NAME&params=JSON&wi=X,Y,Z&wo=X,Y,Z``
    the numpy value ``bk.model(NAME, **params).eval(wi, wo)`` (float64) for
    cross-checking the browser. ``params`` is a JSON object (RGB as a list of
    3 numbers or one number, choices by name, booleans as true/false);
    ``wi``/``wo`` are ``x,y,z`` (normalised here; the zero vector is rejected)
    or JSON arrays ``[x,y,z]`` / ``[[x,y,z], ...]`` (broadcast against each
    other; :mod:`http.server` limits the request line to 64 KiB, about 1 500
    pairs per request). Answers ``{"model", "params" (the
    effective parameters), "wi", "wo", "value"}`` where ``value`` is ``[r,g,b]``
    or a list of them.
"""

from __future__ import annotations

import json
import math
import mimetypes
import threading
from http import HTTPStatus
from http.server import BaseHTTPRequestHandler, ThreadingHTTPServer
from pathlib import Path
from typing import Any
from urllib.parse import parse_qs, unquote, urlsplit

import numpy as np

STATIC_DIR = Path(__file__).resolve().with_name("static")
MAX_PAIRS = 100_000


class BadRequest(ValueError):
    """A client error: answered with status 400 and the one-line message."""


# ---------------------------------------------------------------------------
# the API, as plain functions (the handler only does HTTP)
# ---------------------------------------------------------------------------
def models_payload() -> dict[str, Any]:
    """The body of ``GET /api/models``."""
    import brdfkit as bk
    from brdfkit import registry
    from brdfkit.render import glsl

    out = []
    for name in bk.models():
        cls = registry.get(name)
        info = bk.model_info(name)
        by_name = {p.name: p for p in cls.spec}
        for row in info["params"]:
            p = by_name[row["name"]]
            row["log_scale"] = bool(p.log_scale)
            row["open_lo"] = bool(p.open_lo)
            row["open_hi"] = bool(p.open_hi)
            row["uniform"] = {"name": f"u_{p.name}", "type": glsl.GLSL_TYPES[p.kind]}
            if isinstance(row.get("min"), float) and not math.isfinite(row["min"]):
                row["min"] = None
        info["glsl"] = glsl.has_shader(cls)
        out.append(_jsonable(info))
    return {"models": out}


def shader_payload(name: str) -> str:
    """The body of ``GET /api/shader/<model>``: GLSL ES 3.00 source with its ``#version`` line."""
    from brdfkit import registry
    from brdfkit.render import glsl

    try:  # an unknown model, or one without a GLSL file
        return "#version 300 es\n" + glsl.shader_source(registry.get(name))
    except ValueError as e:
        raise BadRequest(str(e)) from None


def _parse_dirs(text: str, what: str) -> np.ndarray:
    t = text.strip()
    if not t:
        raise BadRequest(f"{what}: missing; give x,y,z or a JSON array [x,y,z] / [[x,y,z], ...]")
    if t.startswith("["):
        try:
            obj = json.loads(t)
        except json.JSONDecodeError as e:
            raise BadRequest(f"{what}: not valid JSON ({e.msg})") from None
        try:
            arr = np.asarray(obj, dtype=np.float64)
        except (TypeError, ValueError):
            raise BadRequest(f"{what}: expected numbers in [x,y,z] or [[x,y,z], ...]") from None
    else:
        parts = t.split(",")
        try:
            arr = np.asarray([float(p) for p in parts], dtype=np.float64)
        except ValueError:
            raise BadRequest(f"{what}: expected x,y,z (three numbers), got {text!r}") from None
    if arr.ndim not in (1, 2) or arr.shape[-1] != 3:
        raise BadRequest(f"{what}: expected x,y,z or [[x,y,z], ...], got shape {list(arr.shape)}")
    if arr.ndim == 2 and arr.shape[0] > MAX_PAIRS:
        raise BadRequest(f"{what}: at most {MAX_PAIRS} directions per request, got {arr.shape[0]}")
    if not np.all(np.isfinite(arr)):
        raise BadRequest(f"{what}: components must be finite")
    n = np.linalg.norm(arr, axis=-1, keepdims=True)
    if np.any(n == 0):
        raise BadRequest(f"{what}: the zero vector is not a direction")
    return arr / n


def eval_payload(query: dict[str, list[str]]) -> dict[str, Any]:
    """The body of ``GET /api/eval`` for a parsed query string."""
    import brdfkit as bk

    allowed = {"model", "params", "wi", "wo"}
    for k in query:
        if k not in allowed:
            raise BadRequest(f"unknown query parameter '{k}'; allowed: model, params, wi, wo")
    for k, v in query.items():
        if len(v) > 1:
            raise BadRequest(f"query parameter '{k}' given {len(v)} times; give it once")
    name = query.get("model", [""])[0]
    if not name:
        raise BadRequest("missing query parameter 'model'; valid models: " + ", ".join(bk.models()))
    ptext = query.get("params", ["{}"])[0] or "{}"
    try:
        params = json.loads(ptext)
    except json.JSONDecodeError as e:
        raise BadRequest(f"params: not valid JSON ({e.msg}); give a JSON object like {{\"kd\": 0.5}}") from None
    if not isinstance(params, dict):
        raise BadRequest("params: must be a JSON object like {\"kd\": 0.5}")
    if "wi" not in query or "wo" not in query:
        raise BadRequest("missing query parameter 'wi' or 'wo' (each x,y,z or a JSON array of them)")
    wi = _parse_dirs(query["wi"][0], "wi")
    wo = _parse_dirs(query["wo"][0], "wo")
    try:
        wi_b, wo_b = np.broadcast_arrays(wi, wo)
    except ValueError:
        raise BadRequest(f"wi and wo do not broadcast: {len(wi)} and {len(wo)} directions") from None
    try:
        m = bk.model(name, **params)
        value = m.eval(wi_b, wo_b)
    except ValueError as e:
        raise BadRequest(_one_line(e)) from None
    from brdfkit.params import to_jsonable

    return {
        "model": name,
        "params": _jsonable(to_jsonable(m.params)),
        "wi": wi_b.tolist(),
        "wo": wo_b.tolist(),
        "value": np.asarray(value, dtype=np.float64).tolist(),
    }


def _one_line(e: BaseException) -> str:
    lines = str(e).strip().splitlines()
    return lines[0] if lines else type(e).__name__


def _jsonable(obj: Any) -> Any:
    if isinstance(obj, dict):
        return {str(k): _jsonable(v) for k, v in obj.items()}
    if isinstance(obj, (list, tuple)):
        return [_jsonable(v) for v in obj]
    if isinstance(obj, np.ndarray):
        return _jsonable(obj.tolist())
    if isinstance(obj, (np.floating,)):
        obj = float(obj)
    if isinstance(obj, (np.integer,)):
        return int(obj)
    if isinstance(obj, (np.bool_,)):
        return bool(obj)
    if isinstance(obj, float) and not math.isfinite(obj):
        return None
    return obj


# ---------------------------------------------------------------------------
# HTTP
# ---------------------------------------------------------------------------
class Handler(BaseHTTPRequestHandler):
    server_version = "brdfkit"
    protocol_version = "HTTP/1.1"
    quiet = True  # set False to log requests to stderr

    def log_message(self, format: str, *args: Any) -> None:  # noqa: A002 - stdlib signature
        if not self.quiet:
            super().log_message(format, *args)

    # -- responses ----------------------------------------------------------
    def _send(self, status: int, body: bytes, ctype: str, head_only: bool = False) -> None:
        self.send_response(status)
        self.send_header("Content-Type", ctype)
        self.send_header("Content-Length", str(len(body)))
        self.send_header("Cache-Control", "no-store")
        self.send_header("X-Content-Type-Options", "nosniff")
        self.end_headers()
        if not head_only:
            self.wfile.write(body)

    def _json(self, status: int, obj: Any, head_only: bool = False) -> None:
        body = json.dumps(obj, separators=(",", ":"), allow_nan=False).encode("utf-8")
        self._send(status, body, "application/json; charset=utf-8", head_only)

    def _error(self, status: int, message: str) -> None:
        self._json(status, {"error": message})

    # -- routing --------------------------------------------------------------
    def do_HEAD(self) -> None:  # noqa: N802 - stdlib name
        self._route(head_only=True)

    def do_GET(self) -> None:  # noqa: N802
        self._route(head_only=False)

    def do_POST(self) -> None:  # noqa: N802
        # --- explorer (issue 11): POST routes of web/api.py ROUTES ---
        from . import api

        url = urlsplit(self.path)
        fn = api.ROUTES.get(("POST", unquote(url.path)))
        try:
            n = int(self.headers.get("Content-Length") or 0)
            if fn is None or n < 0 or n > api.MAX_UPLOAD:
                self.close_connection = True
                raise BadRequest("no such POST endpoint" if fn is None else f"body too large ({n} bytes)")
            self._api_route(fn, url.query, self.rfile.read(n), False)
        except BadRequest as e:
            self._error(HTTPStatus.BAD_REQUEST if fn is not None else HTTPStatus.NOT_FOUND, _one_line(e))
        except BrokenPipeError:  # pragma: no cover - the client went away
            pass
        except Exception as e:  # pragma: no cover - a bug: still one line, status 500
            self._error(HTTPStatus.INTERNAL_SERVER_ERROR, f"internal error: {type(e).__name__}: {_one_line(e)}")
        # --- end explorer ---

    def do_PUT(self) -> None:  # noqa: N802
        self._error(HTTPStatus.METHOD_NOT_ALLOWED, "only GET and POST are supported")

    do_DELETE = do_PATCH = do_PUT

    # --- explorer (issue 11): dispatch to web/api.py ROUTES ---
    def _api_route(self, fn, query: str, body: bytes, head_only: bool) -> None:
        try:
            q = parse_qs(query, keep_blank_values=True, max_num_fields=16)
            status, ctype, payload = fn(q, body)
        except ValueError as e:
            raise BadRequest(_one_line(e)) from None
        self._send(status, payload, ctype, head_only)
    # --- end explorer ---

    def _route(self, head_only: bool) -> None:
        try:
            url = urlsplit(self.path)
            path = unquote(url.path)
            if path.startswith("/api/"):
                self._api(path, url.query, head_only)
            else:
                self._static(path, head_only)
        except BadRequest as e:
            self._error(HTTPStatus.BAD_REQUEST, _one_line(e))
        except BrokenPipeError:  # pragma: no cover - the client went away
            pass
        except Exception as e:  # pragma: no cover - a bug: still one line, status 500
            self._error(HTTPStatus.INTERNAL_SERVER_ERROR, f"internal error: {type(e).__name__}: {_one_line(e)}")

    def _api(self, path: str, query: str, head_only: bool) -> None:
        if path == "/api/models":
            self._json(HTTPStatus.OK, _cached_models(), head_only)
        elif path.startswith("/api/shader/"):
            name = path[len("/api/shader/"):]
            body = shader_payload(name).encode("utf-8")
            self._send(HTTPStatus.OK, body, "text/plain; charset=utf-8", head_only)
        elif path == "/api/eval":
            try:
                q = parse_qs(query, keep_blank_values=True, strict_parsing=False, max_num_fields=16)
            except ValueError as e:
                raise BadRequest(f"bad query string: {_one_line(e)}") from None
            self._json(HTTPStatus.OK, eval_payload(q), head_only)
        elif ("GET", path) in _explorer_routes():  # explorer (issue 11): web/api.py ROUTES
            self._api_route(_explorer_routes()[("GET", path)], query, b"", head_only)
        else:
            self._error(HTTPStatus.NOT_FOUND, f"no such API endpoint {path!r}; see /api/models, /api/shader/<model>, /api/eval")

    def _static(self, path: str, head_only: bool) -> None:
        if path in ("", "/"):
            path = "/index.html"
        rel = path.lstrip("/")
        if rel.startswith("static/"):
            rel = rel[len("static/"):]
        target = (STATIC_DIR / rel).resolve()
        if STATIC_DIR not in target.parents or not target.is_file():
            self._error(HTTPStatus.NOT_FOUND, f"not found: {path}")
            return
        ctype = mimetypes.guess_type(target.name)[0] or "application/octet-stream"
        if ctype.startswith("text/") or ctype in ("application/javascript",):
            ctype += "; charset=utf-8"
        self._send(HTTPStatus.OK, target.read_bytes(), ctype, head_only)


def _explorer_routes() -> dict:  # explorer (issue 11)
    from . import api

    return api.ROUTES


_MODELS_LOCK = threading.Lock()
_MODELS_CACHE: dict[str, Any] | None = None


def _cached_models() -> dict[str, Any]:
    global _MODELS_CACHE
    with _MODELS_LOCK:
        if _MODELS_CACHE is None:
            _MODELS_CACHE = models_payload()
        return _MODELS_CACHE


class Server(ThreadingHTTPServer):
    daemon_threads = True
    allow_reuse_address = True

    @property
    def url(self) -> str:
        host, port = self.server_address[:2]
        if ":" in host:
            host = f"[{host}]"
        return f"http://{host}:{port}/"


def make_server(host: str = "127.0.0.1", port: int = 0) -> Server:
    """Bind the explorer's server (``port=0``: a free port; see ``server.url``); not yet serving.

    Raises a one-line ``ValueError`` for a bad port and ``OSError`` (one line)
    when the address cannot be bound.
    """
    if isinstance(port, bool) or not isinstance(port, int) or not 0 <= port <= 65535:
        raise ValueError(f"--port must be an integer in [0, 65535] (0 = any free port), got {port!r}")
    if not isinstance(host, str) or not host.strip():
        raise ValueError("--host must be a host name or an IP address, e.g. 127.0.0.1")
    mimetypes.add_type("application/javascript", ".js")
    mimetypes.add_type("text/css", ".css")
    try:
        return Server((host, port), Handler)
    except OSError as e:
        reason = e.strerror or _one_line(e)
        raise OSError(f"cannot listen on {host}:{port}: {reason}") from None


def start_in_thread(host: str = "127.0.0.1", port: int = 0) -> tuple[Server, threading.Thread]:
    """A running server in a daemon thread (for tests and notebooks); stop with ``server.shutdown()``."""
    srv = make_server(host, port)
    t = threading.Thread(target=srv.serve_forever, name="brdfkit-web", daemon=True)
    t.start()
    return srv, t
