"""``Held``: the last few values built, by key — the one bounded cache of derived data in brdfkit.

Used where a value is large and derived from something the caller holds (a measured model's GLSL
table sets and texels, :mod:`brdfkit.render.tables` and :mod:`brdfkit.render.glsl`; the
microsurface tiles and their ray-tracing scenes, :mod:`brdfkit.microsurfaces`): unlike
``functools.lru_cache`` only the key is compared, and what the build needs travels in its closure.
"""

from __future__ import annotations

import threading
from collections import OrderedDict
from typing import Any, Callable, Hashable, TypeVar

_T = TypeVar("_T")


class Held:
    """The last ``size`` values built, by key (a small LRU whose builder is given per call).

    ``get(key, build)`` returns the value held under ``key``, or calls ``build()``, holds its
    value and returns it, dropping the least recently used beyond ``size``. Thread-safe; two
    threads missing the same key at once both build, and both get the value held first.
    """

    def __init__(self, size: int = 2) -> None:
        self.size = size
        self._values: OrderedDict[Hashable, Any] = OrderedDict()
        self._lock = threading.Lock()

    def get(self, key: Hashable, build: Callable[[], _T]) -> _T:
        with self._lock:
            if key in self._values:
                self._values.move_to_end(key)
                return self._values[key]
        value = build()
        with self._lock:
            value = self._values.setdefault(key, value)
            self._values.move_to_end(key)
            while len(self._values) > self.size:
                self._values.popitem(last=False)
        return value

    def clear(self) -> None:
        with self._lock:
            self._values.clear()

    def __len__(self) -> int:
        return len(self._values)


__all__ = ["Held"]
