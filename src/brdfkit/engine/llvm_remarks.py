"""Holding back LLVM's "remark: ... loop not vectorized" lines while a driver compiles (C-level stderr).

With ``-force-vector-width`` (:mod:`.llvm_options`) LLVM reports every loop it could not vectorise
(those calling libm) on the process's stderr, which a user of ``brdfkit eval`` would see once per
driver. :func:`without_llvm_remarks` sends file descriptor 2 to a temporary file for the compile and
afterwards writes every line that is not such a remark back to stderr, so nothing else is lost.
"""

from __future__ import annotations

import contextlib
import os
import sys
import tempfile


@contextlib.contextmanager
def without_llvm_remarks():
    """Hold back LLVM's "remark: ... loop not vectorized" lines while a forced-width driver compiles.

    The C-level stderr goes to a temporary file for the compile; afterwards every line that is not
    such a remark (anything another thread wrote meanwhile) is written to stderr."""
    try:
        fd = sys.__stderr__.fileno()
    except (AttributeError, OSError, ValueError):  # pragma: no cover - no real stderr (embedded)
        yield
        return
    sys.__stderr__.flush()
    saved = os.dup(fd)
    with tempfile.TemporaryFile() as tmp:
        os.dup2(tmp.fileno(), fd)
        try:
            yield
        finally:
            os.dup2(saved, fd)
            os.close(saved)
            tmp.seek(0)
            rest = [ln for ln in tmp.read().decode("utf-8", "replace").splitlines(True) if not ln.startswith("remark: ")]
            if rest:
                sys.__stderr__.write("".join(rest))
                sys.__stderr__.flush()


__all__ = ["without_llvm_remarks"]
