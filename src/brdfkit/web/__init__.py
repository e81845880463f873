"""The browser explorer served by ``brdfkit serve``.

A standard-library HTTP server (:mod:`brdfkit.web.server`) serves a static
single-page app (``static/``: native ES modules and WebGL 2, no build step,
nothing fetched from outside) and a small JSON API. The page builds its
controls from each model's parameter spec, compiles the model's GLSL twin
(``render/shaders``) in the browser and shows a lit sphere and an in-plane
polar plot of f_r·cos θo that update as the sliders move.

>>> from brdfkit.web import start_in_thread
>>> srv, _ = start_in_thread(port=0)   # doctest: +SKIP
>>> print(srv.url)                      # doctest: +SKIP
"""

from __future__ import annotations

from .server import STATIC_DIR, BadRequest, make_server, start_in_thread

__all__ = ["STATIC_DIR", "BadRequest", "make_server", "start_in_thread"]
