"""The HTTP server behind ``brdfkit serve``: a static single-page app and a small JSON API.

Standard library only (:mod:`http.server`), hardened for a browser and for a
hostile page in it (see "HTTP" below). The page
(``static/index.html``, ``style.css`` and ``static/js/``: native ES modules and
WebGL 2, served as they are with no build step, nothing fetched from outside;
see ``js/main.js``) compiles every model's GLSL twin
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
    other; the request line is limited to 64 KiB, about 1 500 pairs per
    request). Answers ``{"model", "params" (the
    effective parameters), "wi", "wo", "value"}`` where ``value`` is ``[r,g,b]``
    or a list of them.

Then the table :data:`brdfkit.web.api.ROUTES` (``(method, path) -> handler``)
is consulted, so other modules can add endpoints without touching this file.

HTTP
----
* Every request body is read (``Content-Length``, at most :data:`MAX_BODY`
  bytes, or ``api.MAX_UPLOAD`` for the upload routes of ``api.ROUTES``) before the answer, so a body can never be taken for a second request
  on a kept-alive connection; a larger, malformed or chunked body is refused
  (413 / 400 / 411) with ``Connection: close``.
* Nagle's algorithm is off (``TCP_NODELAY``): a kept-alive answer is not held
  back 40 ms by delayed ACKs.
* Each connection has a read timeout (:attr:`Handler.timeout`, idle keep-alive
  included); connections are served by a bounded pool of
  :attr:`Server.workers` threads behind a listen backlog of
  :attr:`Server.request_queue_size`; when all are busy and the waiting line is
  full, a connection gets 503 and is closed.
* Malformed targets (NUL or control bytes, more than :data:`MAX_TARGET`
  characters, deeply nested JSON) answer 400 or 404, never 500, and no answer
  names a file-system path.
* The ``Host`` header must name the bound address, a localhost name
  (``localhost``, ``127.0.0.1``, ``[::1]``) or an IP literal, with the bound
  port, or one of the ``allowed_hosts`` given to :func:`make_server`: a page
  that reaches the server through DNS rebinding (``Host: evil.example``) gets
  403.
"""

from __future__ import annotations

import json
import mimetypes
import queue
import socket
import threading
from http import HTTPStatus
from http.server import BaseHTTPRequestHandler, HTTPServer
from pathlib import Path
from typing import Any, Iterable
from urllib.parse import parse_qs, unquote, urlsplit

import numpy as np

from .. import registry
from .jsonio import MAX_JSON_DEPTH, BadRequest, jsonable, loads, one_line, ui_model_info

STATIC_DIR = Path(__file__).resolve().with_name("static")
MAX_PAIRS = 100_000
MAX_BODY = 1 << 20  # bytes of a request body
MAX_TARGET = 65536  # characters of the request target (path and query), http.server's own line limit


# ---------------------------------------------------------------------------
# the API, as plain functions (the handler only does HTTP)
# ---------------------------------------------------------------------------
def models_payload() -> dict[str, Any]:
    """The body of ``GET /api/models``."""
    from ..render import glsl

    out = []
    for name in registry.names():
        cls = registry.get(name)
        info = ui_model_info(cls, glsl.GLSL_TYPES)  # what bk.model_info(name) answers, plus the UI's fields
        info["glsl"] = glsl.has_shader(cls)
        out.append(jsonable(info))
    return {"models": out}


def _web_model_class(name: str):
    """A registry model class by name; never a file path (see :func:`brdfkit.web.api.web_model`)."""
    from .api import web_model_class

    return web_model_class(name)


def shader_payload(name: str) -> str:
    """The body of ``GET /api/shader/<model>``: GLSL ES 3.00 source with its ``#version`` line."""
    from ..render import glsl

    try:  # an unknown model, or one without a GLSL file
        return "#version 300 es\n" + glsl.shader_source(_web_model_class(name))
    except ValueError as e:
        raise BadRequest(str(e)) from None


def _parse_dirs(text: str, what: str) -> np.ndarray:
    t = text.strip()
    if not t:
        raise BadRequest(f"{what}: missing; give x,y,z or a JSON array [x,y,z] / [[x,y,z], ...]")
    if t.startswith("["):
        obj = loads(t, what)
        try:
            arr = np.asarray(obj, dtype=np.float64)
        except (TypeError, ValueError, OverflowError):
            raise BadRequest(f"{what}: expected finite numbers in [x,y,z] or [[x,y,z], ...]") from None
    else:
        from ..params import to_float

        parts = t.split(",")
        if len(parts) != 3:
            raise BadRequest(f"{what}: expected x,y,z (three numbers), got {len(parts)} values")
        try:
            arr = np.asarray([to_float(p, what) for p in parts], dtype=np.float64)
        except ValueError as e:
            raise BadRequest(one_line(e)) from None
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
    allowed = {"model", "params", "wi", "wo"}
    for k in query:
        if k not in allowed:
            raise BadRequest(f"unknown query parameter '{k}'; allowed: model, params, wi, wo")
    for k, v in query.items():
        if len(v) > 1:
            raise BadRequest(f"query parameter '{k}' given {len(v)} times; give it once")
    name = query.get("model", [""])[0]
    if not name:
        raise BadRequest("missing query parameter 'model'; valid models: " + ", ".join(registry.names()))
    ptext = query.get("params", ["{}"])[0] or "{}"
    params = loads(ptext, "params", 'give a JSON object like {"kd": 0.5}')
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
        from .api import web_model

        m = web_model(name, params)
        value = m.eval(wi_b, wo_b)
    except (ValueError, TypeError, OverflowError) as e:
        raise BadRequest(one_line(e)) from None
    from ..params import to_jsonable

    return {
        "model": name,
        "params": jsonable(to_jsonable(m.params)),
        "wi": wi_b.tolist(),
        "wo": wo_b.tolist(),
        "value": np.asarray(value, dtype=np.float64).tolist(),
    }


# ---------------------------------------------------------------------------
# HTTP
# ---------------------------------------------------------------------------
class _Refuse(Exception):
    """Answer ``status`` with ``message`` and close the connection (the request could not be read whole)."""

    def __init__(self, status: int, message: str) -> None:
        super().__init__(message)
        self.status = status


LOCAL_NAMES = ("localhost", "127.0.0.1", "::1", "localhost.localdomain", "ip6-localhost")


class Handler(BaseHTTPRequestHandler):
    server_version = "brdfkit"
    protocol_version = "HTTP/1.1"
    quiet = True  # set False to log requests to stderr
    timeout = 10.0  # seconds of silence after which a connection is closed (idle keep-alive included)
    disable_nagle_algorithm = True

    def log_message(self, format: str, *args: Any) -> None:  # noqa: A002 - stdlib signature
        if not self.quiet:
            super().log_message(format, *args)

    def send_error(self, code: int, message: str | None = None, explain: str | None = None) -> None:
        """The stdlib's own errors (bad request line, 414, 431...) as our JSON shape, always closing."""
        self.close_connection = True
        if getattr(self, "request_version", "HTTP/0.9") == "HTTP/0.9":  # answer with a status line anyway
            self.request_version = "HTTP/1.0"
        try:
            self._json(code, {"error": message or HTTPStatus(code).phrase},
                       head_only=getattr(self, "command", None) == "HEAD", close=True)
        except OSError:  # pragma: no cover - the client went away
            pass

    def parse_request(self) -> bool:
        """The stdlib's parsing, minus HTTP/0.9 (``GET /`` without a version: no status line, no headers)."""
        ok = super().parse_request()
        if ok and self.request_version == "HTTP/0.9":
            self.send_error(HTTPStatus.BAD_REQUEST, "HTTP/0.9 requests are not supported; send HTTP/1.0 or 1.1")
            return False
        return ok

    # -- responses ----------------------------------------------------------
    def _send(self, status: int, body: bytes, ctype: str, head_only: bool = False, close: bool = False) -> None:
        self.send_response(status)
        self.send_header("Content-Type", ctype)
        self.send_header("Content-Length", str(len(body)))
        self.send_header("Cache-Control", "no-store")
        self.send_header("X-Content-Type-Options", "nosniff")
        if close or self.close_connection:
            self.send_header("Connection", "close")
            self.close_connection = True
        self.end_headers()
        if not head_only:
            self.wfile.write(body)

    def _json(self, status: int, obj: Any, head_only: bool = False, close: bool = False) -> None:
        body = json.dumps(obj, separators=(",", ":"), allow_nan=False).encode("utf-8")
        self._send(status, body, "application/json; charset=utf-8", head_only, close)

    def _error(self, status: int, message: str, close: bool = False) -> None:
        # an answer to HEAD never has a body, errors included (else the next kept-alive answer is misread)
        self._json(status, {"error": message}, head_only=getattr(self, "command", None) == "HEAD", close=close)

    # -- request checks -------------------------------------------------------
    def _body_limit(self, method: str) -> int:
        """:data:`MAX_BODY`, or the upload limit ``api.MAX_UPLOAD`` for a route of :data:`api.ROUTES`."""
        from . import api

        try:
            path = unquote(urlsplit(self.path).path)
        except ValueError:
            return MAX_BODY
        if (method, path) in api.ROUTES:
            return max(MAX_BODY, int(getattr(api, "MAX_UPLOAD", MAX_BODY)))
        return MAX_BODY

    def _read_body(self, limit: int = MAX_BODY) -> bytes:
        """The whole request body (so that it cannot be read as the next request), or :class:`_Refuse`."""
        if self.headers.get("Transfer-Encoding"):
            raise _Refuse(HTTPStatus.LENGTH_REQUIRED, "chunked request bodies are not accepted; send Content-Length")
        lengths = self.headers.get_all("Content-Length") or []
        if not lengths:
            return b""
        if len(set(v.strip() for v in lengths)) != 1 or not lengths[0].strip().isdigit():
            raise _Refuse(HTTPStatus.BAD_REQUEST, "bad Content-Length header")
        n = int(lengths[0].strip())
        if n > limit:
            raise _Refuse(HTTPStatus.REQUEST_ENTITY_TOO_LARGE, f"request body of {n} bytes; at most {limit}")
        chunks, left = [], n
        while left > 0:
            chunk = self.rfile.read(min(left, 65536))
            if not chunk:
                raise _Refuse(HTTPStatus.BAD_REQUEST, "request body shorter than its Content-Length")
            chunks.append(chunk)
            left -= len(chunk)
        return b"".join(chunks)

    def _host_ok(self) -> bool:
        host = self.headers.get("Host")
        if host is None:  # HTTP/1.0 clients may omit it; HTTP/1.1 requires it
            return self.request_version == "HTTP/1.0"
        return self.server.host_allowed(host.strip())

    # -- routing --------------------------------------------------------------
    def do_HEAD(self) -> None:  # noqa: N802 - stdlib name
        self._handle("HEAD")

    def do_GET(self) -> None:  # noqa: N802
        self._handle("GET")

    def do_POST(self) -> None:  # noqa: N802
        self._handle("POST")

    def do_PUT(self) -> None:  # noqa: N802
        self._handle("PUT")

    def do_DELETE(self) -> None:  # noqa: N802
        self._handle("DELETE")

    def do_PATCH(self) -> None:  # noqa: N802
        self._handle("PATCH")

    def do_OPTIONS(self) -> None:  # noqa: N802
        self._handle("OPTIONS")

    def _handle(self, method: str) -> None:
        head_only = method == "HEAD"
        try:
            try:
                body = self._read_body(self._body_limit(method))
            except _Refuse as e:
                self._error(e.status, str(e), close=True)
                return
            except (TimeoutError, socket.timeout):
                self.close_connection = True
                return
            if not self._host_ok():
                self._error(HTTPStatus.FORBIDDEN, "Host header not allowed: this server answers only its own address")
                return
            self._route(method, body, head_only)
        except (BrokenPipeError, ConnectionResetError):  # pragma: no cover - the client went away
            self.close_connection = True

    def _route(self, method: str, body: bytes, head_only: bool) -> None:
        try:
            target = self.path
            if len(target) > MAX_TARGET:
                raise BadRequest(f"request target of {len(target)} characters; at most {MAX_TARGET}")
            url = urlsplit(target)
            path = unquote(url.path, errors="strict")
            if any(ord(c) < 32 or ord(c) == 127 for c in path):
                raise BadRequest("the path holds a NUL or control character")
            if method in ("GET", "HEAD") and self._builtin(path, url.query, head_only):
                return
            if self._extra(method, path, url.query, body, head_only):
                return
            if method not in ("GET", "HEAD") and self._exists(path):
                self._error(HTTPStatus.METHOD_NOT_ALLOWED, f"{method} is not supported on {_clip(path)}")
            elif path.startswith("/api/"):
                self._error(
                    HTTPStatus.NOT_FOUND,
                    f"no such API endpoint {_clip(path)!r}; see /api/models, /api/shader/<model>, /api/eval",
                )
            else:
                self._error(HTTPStatus.NOT_FOUND, f"not found: {_clip(path)}")
        except (BadRequest, UnicodeDecodeError) as e:
            msg = one_line(e) if isinstance(e, BadRequest) else "the path is not valid UTF-8"
            self._error(HTTPStatus.BAD_REQUEST, msg)
        except (BrokenPipeError, ConnectionResetError):  # pragma: no cover - the client went away
            self.close_connection = True
        except Exception as e:  # pragma: no cover - a bug: status 500, the exception's type only (no paths)
            self._error(HTTPStatus.INTERNAL_SERVER_ERROR, f"internal error ({type(e).__name__})")

    def _exists(self, path: str) -> bool:
        """Whether ``path`` is served for some method (then a wrong method is 405, else 404)."""
        from . import api

        if path in ("/api/models", "/api/eval") or path.startswith("/api/shader/"):
            return True
        if any(p == path for (_m, p) in api.ROUTES):
            return True
        if path.startswith("/api/"):
            return False
        return static_file(path) is not None

    def _builtin(self, path: str, query: str, head_only: bool) -> bool:
        """This module's own GET routes; False when ``path`` is none of them."""
        if path == "/api/models":
            self._json(HTTPStatus.OK, _cached_models(), head_only)
        elif path.startswith("/api/shader/"):
            name = path[len("/api/shader/"):]
            body = shader_payload(name).encode("utf-8")
            self._send(HTTPStatus.OK, body, "text/plain; charset=utf-8", head_only)
        elif path == "/api/eval":
            self._json(HTTPStatus.OK, eval_payload(_query(query)), head_only)
        elif not path.startswith("/api/"):
            return self._static(path, head_only)
        else:
            return False
        return True

    def _extra(self, method: str, path: str, query: str, body: bytes, head_only: bool) -> bool:
        """The endpoints of :data:`brdfkit.web.api.ROUTES`; False when none matches."""
        from . import api

        fn = api.ROUTES.get((method, path)) or (api.ROUTES.get(("GET", path)) if head_only else None)
        if fn is None:
            return False
        try:
            status, ctype, payload = fn(_query(query), body)
        except (ValueError, TypeError, OverflowError, RecursionError) as e:
            raise BadRequest(one_line(e)) from None
        self._send(int(status), bytes(payload), ctype, head_only)
        return True

    def _static(self, path: str, head_only: bool) -> bool:
        target = static_file(path)
        if target is None:
            return False
        try:
            data = target.read_bytes()
        except OSError:
            return False
        self._send(HTTPStatus.OK, data, static_type(target.name), head_only)
        return True


def static_file(path: str) -> Path | None:
    """The file of :data:`STATIC_DIR` a URL path names (``/`` is ``index.html``; a leading
    ``static/`` is dropped), or None: never a file outside that folder (no ``..``, no
    backslash, no empty part, no link that leads out)."""
    rel = "index.html" if path in ("", "/") else path.lstrip("/").removeprefix("static/")
    if "\\" in rel or any(part in ("..", "") for part in rel.split("/")) or len(rel) > 255:
        return None
    try:
        target = (STATIC_DIR / rel).resolve()
        return target if STATIC_DIR in target.parents and target.is_file() else None
    except (OSError, ValueError):
        return None


# The page's own types, whatever the system's MIME table says: the page is ES modules, which
# a browser runs only when served with a JavaScript type (and X-Content-Type-Options: nosniff).
STATIC_TYPES = {
    ".html": "text/html; charset=utf-8",
    ".js": "text/javascript; charset=utf-8",
    ".mjs": "text/javascript; charset=utf-8",
    ".css": "text/css; charset=utf-8",
    ".json": "application/json; charset=utf-8",
    ".svg": "image/svg+xml",
    ".png": "image/png",
}


def static_type(name: str) -> str:
    """The Content-Type of a static file by its name's suffix."""
    suffix = Path(name).suffix.lower()
    if suffix in STATIC_TYPES:
        return STATIC_TYPES[suffix]
    ctype = mimetypes.guess_type(name)[0] or "application/octet-stream"
    return ctype + "; charset=utf-8" if ctype.startswith("text/") else ctype


def _query(query: str) -> dict[str, list[str]]:
    try:
        return parse_qs(query, keep_blank_values=True, strict_parsing=False, max_num_fields=16)
    except ValueError as e:
        raise BadRequest(f"bad query string: {one_line(e)}") from None


def _clip(text: str, n: int = 80) -> str:
    return text if len(text) <= n else text[:n] + "..."


_MODELS_LOCK = threading.Lock()
_MODELS_CACHE: dict[str, Any] | None = None


def _cached_models() -> dict[str, Any]:
    global _MODELS_CACHE
    with _MODELS_LOCK:
        if _MODELS_CACHE is None:
            _MODELS_CACHE = models_payload()
        return _MODELS_CACHE


_BUSY = (
    b"HTTP/1.1 503 Service Unavailable\r\nContent-Type: application/json; charset=utf-8\r\n"
    b"Content-Length: 37\r\nRetry-After: 1\r\nConnection: close\r\n\r\n"
    b'{"error":"server busy; retry later"}\n'
)


class Server(HTTPServer):
    """An HTTP server with a bounded pool of worker threads (not one thread per connection)."""

    allow_reuse_address = True
    request_queue_size = 128  # listen backlog
    workers = 32  # threads serving connections
    waiting = 256  # accepted connections waiting for a worker; beyond that: 503

    def __init__(self, address, handler, allowed_hosts: Iterable[str] = ()) -> None:
        self._extra_hosts = {h.strip().lower() for h in allowed_hosts if h and h.strip()}
        self._queue: queue.Queue = queue.Queue(maxsize=self.waiting)
        self._threads: list[threading.Thread] = []
        self._busy_lock = threading.Lock()
        self.busy = 0  # workers serving a connection now
        super().__init__(address, handler)
        for i in range(self.workers):
            t = threading.Thread(target=self._work, name=f"brdfkit-web-{i}", daemon=True)
            t.start()
            self._threads.append(t)

    @property
    def url(self) -> str:
        host, port = self.server_address[:2]
        if ":" in host:
            host = f"[{host}]"
        return f"http://{host}:{port}/"

    # -- Host check -------------------------------------------------------------
    def host_allowed(self, host: str) -> bool:
        """Whether a request's ``Host`` value names this server (see the module's docstring)."""
        import ipaddress

        bound, port = self.server_address[:2]
        h = host.lower()
        name, _, p = h.rpartition(":") if not h.endswith("]") else (h, "", "")
        if not name:  # no port given
            name, p = h, ""
        if p and p != str(port):
            return False
        if name in self._extra_hosts or h in self._extra_hosts:
            return True
        bare = name[1:-1] if name.startswith("[") and name.endswith("]") else name
        if bare in LOCAL_NAMES or bare == str(bound).lower():
            return True
        try:  # an IP literal cannot be rebound by DNS
            ipaddress.ip_address(bare)
            return True
        except ValueError:
            return False

    # -- the bounded pool ----------------------------------------------------------
    def process_request(self, request, client_address) -> None:
        try:
            self._queue.put_nowait((request, client_address))
        except queue.Full:
            try:
                request.settimeout(1.0)
                request.sendall(_BUSY)
            except OSError:
                pass
            self.shutdown_request(request)

    def _work(self) -> None:
        while True:
            item = self._queue.get()
            if item is None:
                return
            request, client_address = item
            with self._busy_lock:
                self.busy += 1
            try:
                self.finish_request(request, client_address)
            except Exception:  # pragma: no cover - a handler bug must not kill the worker
                pass
            finally:
                self.shutdown_request(request)
                with self._busy_lock:
                    self.busy -= 1

    def server_close(self) -> None:
        super().server_close()
        for _ in self._threads:
            try:
                self._queue.put_nowait(None)
            except queue.Full:  # pragma: no cover
                break


def make_server(host: str = "127.0.0.1", port: int = 0, *, allowed_hosts: Iterable[str] = ()) -> Server:
    """Bind the explorer's server (``port=0``: a free port; see ``server.url``); not yet serving.

    ``allowed_hosts`` adds names the ``Host`` header may carry (e.g. a name
    that resolves to this machine); localhost names and IP literals are always
    accepted. Raises a one-line ``ValueError`` for a bad port and ``OSError``
    (one line) when the address cannot be bound.
    """
    if isinstance(port, bool) or not isinstance(port, int) or not 0 <= port <= 65535:
        raise ValueError(f"--port must be an integer in [0, 65535] (0 = any free port), got {port!r}")
    if not isinstance(host, str) or not host.strip():
        raise ValueError("--host must be a host name or an IP address, e.g. 127.0.0.1")
    try:
        return Server((host, port), Handler, allowed_hosts=allowed_hosts)
    except OSError as e:
        reason = e.strerror or one_line(e)
        raise OSError(f"cannot listen on {host}:{port}: {reason}") from None


def start_in_thread(
    host: str = "127.0.0.1", port: int = 0, *, allowed_hosts: Iterable[str] = ()
) -> tuple[Server, threading.Thread]:
    """A running server in a daemon thread (for tests and notebooks); stop with ``server.shutdown()``."""
    srv = make_server(host, port, allowed_hosts=allowed_hosts)
    t = threading.Thread(target=srv.serve_forever, name="brdfkit-web", daemon=True)
    t.start()
    return srv, t
