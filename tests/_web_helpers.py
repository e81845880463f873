"""Shared helpers for the tests that talk to a live explorer server (test_web_*.py).

The server itself is the ``server`` fixture of conftest.py; these speak to it with urllib.
"""

from __future__ import annotations

import json
import urllib.error
import urllib.request


def request(srv, path: str, body: bytes | None = None, timeout: float = 120):
    """(status, content type, body bytes) of GET path, or of POST path when ``body`` is given."""
    req = urllib.request.Request(srv.url.rstrip("/") + path, data=body, method="POST" if body is not None else "GET")
    try:
        with urllib.request.urlopen(req, timeout=timeout) as r:
            return r.status, r.headers.get("Content-Type", ""), r.read()
    except urllib.error.HTTPError as e:
        return e.code, e.headers.get("Content-Type", ""), e.read()


def get_json(srv, path: str, body: bytes | None = None, timeout: float = 120):
    """(status, decoded JSON) of ``request``; asserts the reply is JSON."""
    status, ctype, data = request(srv, path, body, timeout)
    assert ctype.startswith("application/json"), (path, ctype, data[:200])
    return status, json.loads(data)
