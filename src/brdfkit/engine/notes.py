"""One-time notes about what the engine could not use here (a numba internal, an LLVM option).

The engine leans on a few things numba and llvmlite do not promise to keep (:mod:`.vecmath`'s hook,
:mod:`.llvm_options`); where one is missing or refused the engine runs without it — the same values,
only slower — and says so once per process with a :class:`RuntimeWarning`, never again.
"""

from __future__ import annotations

import threading
import warnings

_SAID: set[str] = set()
_LOCK = threading.Lock()


def note_once(key: str, message: str) -> bool:
    """Warn ``message`` (a :class:`RuntimeWarning`) unless a note of ``key`` was given already; True if given now."""
    with _LOCK:
        if key in _SAID:
            return False
        _SAID.add(key)
    warnings.warn(f"brdfkit.engine: {message}", RuntimeWarning, stacklevel=3)
    return True


__all__ = ["note_once"]
