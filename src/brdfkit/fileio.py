"""Writing files without ever losing one: the single atomic writer every brdfkit output goes through.

Every file brdfkit writes (images, EXR, NPY, MERL tables, JSON, CSV, reports,
plots) is first written to a temporary file in the same folder, flushed to
disk, and then moved over the destination with :func:`os.replace`, which is
atomic on POSIX and Windows. A crash, ``kill -9`` or Ctrl-C mid-write leaves
the previous file whole (and at worst a stray ``.NAME.*.tmp`` beside it, which
the next successful write of any file in that folder does not touch).

Output paths are checked *before* long work starts (:func:`check_output_path`):
the folder must exist, except that its last level may be missing, in which
case it is created (and the caller is told); a whole missing tree is an error,
never created.

* :func:`atomic_open` -- ``with atomic_open(path, "w") as f: f.write(...)``
* :func:`atomic_path` -- for libraries that insist on a file name
  (matplotlib ``savefig``, OpenEXR, imageio): ``with atomic_path(path) as tmp:
  lib.save(tmp)``; the temporary name keeps the destination's suffix so
  format detection by extension still works.
* :func:`write_bytes`, :func:`write_text`, :func:`write_json` -- one-call forms.
"""

from __future__ import annotations

import contextlib
import json
import os
import tempfile
from pathlib import Path
from typing import IO, Any, Callable, Iterator

__all__ = [
    "atomic_open",
    "atomic_path",
    "write_bytes",
    "write_text",
    "write_json",
    "check_output_path",
]


def _tmp_name(path: Path) -> str:
    fd, tmp = tempfile.mkstemp(dir=path.parent, prefix=f".{path.name}.", suffix=f".tmp{path.suffix}")
    os.close(fd)
    return tmp


def _fsync_file(name: str) -> None:
    try:
        fd = os.open(name, os.O_RDONLY)
    except OSError:
        return
    try:
        os.fsync(fd)
    except OSError:
        pass
    finally:
        os.close(fd)


@contextlib.contextmanager
def atomic_path(path: str | os.PathLike) -> Iterator[str]:
    """Yield a temporary file name beside ``path``; on success move it over ``path`` atomically.

    On an exception the temporary file is removed and ``path`` is untouched.
    The temporary name ends with ``path``'s suffix (``.tmp.png``), so writers
    that pick the format from the extension keep working.
    """
    dest = Path(path)
    tmp = _tmp_name(dest)
    try:
        yield tmp
        _fsync_file(tmp)
        # mkstemp creates 0600 files; give the result the permissions a normal open() would.
        umask = os.umask(0)
        os.umask(umask)
        with contextlib.suppress(OSError):
            os.chmod(tmp, 0o666 & ~umask)
        os.replace(tmp, dest)
    except BaseException:
        with contextlib.suppress(OSError):
            os.unlink(tmp)
        raise


@contextlib.contextmanager
def atomic_open(path: str | os.PathLike, mode: str = "wb", **kwargs: Any) -> Iterator[IO]:
    """``open(path, mode)`` that only replaces ``path`` once the ``with`` block completes.

    ``mode`` must be a write mode (``"w"``, ``"wb"``, ``"wt"``); text modes
    default to UTF-8.
    """
    if not mode.startswith("w") or "+" in mode:
        raise ValueError(f"atomic_open: mode must be a plain write mode, got {mode!r}")
    if "b" not in mode:
        kwargs.setdefault("encoding", "utf-8")
    with atomic_path(path) as tmp:
        with open(tmp, mode, **kwargs) as f:
            yield f
            f.flush()
            os.fsync(f.fileno())


def write_bytes(path: str | os.PathLike, data: bytes) -> None:
    """Write ``data`` to ``path`` atomically."""
    with atomic_open(path, "wb") as f:
        f.write(data)


def write_text(path: str | os.PathLike, text: str) -> None:
    """Write ``text`` (UTF-8) to ``path`` atomically."""
    with atomic_open(path, "w") as f:
        f.write(text)


def write_json(path: str | os.PathLike, obj: Any, *, indent: int | None = 2) -> None:
    """Write ``obj`` as JSON (with a final newline) to ``path`` atomically."""
    write_text(path, json.dumps(obj, indent=indent) + "\n")


def check_output_path(
    path: str | os.PathLike,
    *,
    what: str = "output",
    suffixes: tuple[str, ...] | None = None,
    is_dir: bool = False,
    notify: Callable[[str], None] | None = None,
) -> Path:
    """Check, before any work starts, that ``path`` can be written; return it as a ``Path``.

    * ``path`` must not be an existing folder (unless ``is_dir``: then it is the
      folder to write into, and must not be an existing file);
    * its folder must exist -- except that the last missing level is created,
      and ``notify`` (e.g. ``print`` to stderr) is told so. Two or more missing
      levels are an error: a typo must not create a tree;
    * the folder must be writable;
    * with ``suffixes``, the file name must end in one of them.

    Raises ``ValueError`` with one line naming the path and what is wrong.
    """
    p = Path(path)
    if str(path) == "":
        raise ValueError(f"{what} path is empty")
    if suffixes is not None and not is_dir and p.suffix.lower() not in suffixes:
        raise ValueError(f"{what} file {str(path)!r} must end in {' or '.join(suffixes)}")
    target_dir = p if is_dir else p.parent
    if is_dir and p.exists() and not p.is_dir():
        raise ValueError(f"{what} folder {str(path)!r} exists and is not a folder")
    if not is_dir and p.is_dir():
        raise ValueError(f"{what} path {str(path)!r} is a folder, not a file")
    parent = target_dir if str(target_dir) else Path(".")
    if not parent.exists():
        grand = parent.parent
        if not grand.is_dir():
            raise ValueError(
                f"cannot write {what} {str(path)!r}: folder {str(grand)!r} does not exist (only one missing folder level is created)"
            )
        if not os.access(grand, os.W_OK):
            raise ValueError(f"cannot write {what} {str(path)!r}: folder {str(grand)!r} is not writable")
        try:
            parent.mkdir()
        except OSError as e:
            raise ValueError(f"cannot create folder {str(parent)!r} for {what}: {e.strerror}") from None
        if notify is not None:
            notify(f"created folder {str(parent)!r}")
    elif not parent.is_dir():
        raise ValueError(f"cannot write {what} {str(path)!r}: {str(parent)!r} is not a folder")
    if not os.access(parent, os.W_OK):
        raise ValueError(f"cannot write {what} {str(path)!r}: folder {str(parent)!r} is not writable")
    if not is_dir and p.exists() and not os.access(p, os.W_OK):
        raise ValueError(f"cannot write {what} {str(path)!r}: the file is not writable")
    return p
