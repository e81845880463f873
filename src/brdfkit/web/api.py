"""Extra JSON/binary endpoints of the explorer, kept apart from the HTTP plumbing in :mod:`.server`.

``ROUTES`` maps ``(method, path)`` (e.g. ``("GET", "/api/nbrdf")``) to a handler
``handler(query: dict[str, list[str]], body: bytes) -> (status, content_type, payload_bytes)``.
The server dispatches to this table after its own routes; a handler raises
``ValueError`` for bad input, which the server answers with 400 and the
one-line message (never a traceback, never a file-system path).
"""

from __future__ import annotations

from typing import Callable

Handler = Callable[[dict, bytes], tuple[int, str, bytes]]

ROUTES: dict[tuple[str, str], Handler] = {}
