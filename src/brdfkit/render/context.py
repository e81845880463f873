"""The headless OpenGL context shared by the renderer and the GLSL harness.

:func:`create_context` makes a moderngl context that needs no display: EGL
(Mesa llvmpipe on a machine without a GPU, the GPU's driver where there is
one), falling back to moderngl's default backend. It leaves whatever context
was current before it current again (see :class:`EGLCurrent`).
"""

from __future__ import annotations

from typing import Any


class EGLCurrent:
    """Save the calling thread's current EGL context on entry and make it current again on exit.

    moderngl/glcontext's EGL backend makes a context current on creation and on
    ``with ctx:`` but does not restore the previous one afterwards. Another
    moderngl context in the process (the renderer's) that relies on staying
    current would then silently issue its GL calls into ours, so every use of
    our context is wrapped in this guard. Without libEGL it does nothing.
    """

    _lib: Any = None
    _tried = False

    @classmethod
    def _egl(cls):
        if not cls._tried:
            cls._tried = True
            try:
                import ctypes

                lib = ctypes.CDLL("libEGL.so.1")
                for fn in ("eglGetCurrentContext", "eglGetCurrentDisplay", "eglGetCurrentSurface"):
                    getattr(lib, fn).restype = ctypes.c_void_p
                lib.eglGetCurrentSurface.argtypes = [ctypes.c_int]
                lib.eglMakeCurrent.argtypes = [ctypes.c_void_p] * 4
                lib.eglMakeCurrent.restype = ctypes.c_uint
                cls._lib = lib
            except (OSError, AttributeError):  # pragma: no cover - no EGL on this machine
                cls._lib = None
        return cls._lib

    def __enter__(self):
        lib = self._egl()
        self.saved = None
        if lib is not None:
            ctx = lib.eglGetCurrentContext()
            if ctx:
                self.saved = (lib.eglGetCurrentDisplay(), lib.eglGetCurrentSurface(0x3059),
                              lib.eglGetCurrentSurface(0x305A), ctx)  # EGL_DRAW, EGL_READ
        return self

    def __exit__(self, *exc):
        if self.saved is not None:
            self._lib.eglMakeCurrent(*self.saved)
        return False


def context_info(ctx: Any) -> dict[str, str]:
    """Vendor, renderer and version strings of a moderngl context (make it current first)."""
    info = ctx.info
    return {k: str(info.get(k)) for k in ("GL_VENDOR", "GL_RENDERER", "GL_VERSION")}


def create_context(require: int = 330) -> Any:
    """A standalone moderngl context of at least GL ``require`` (EGL first)."""
    import moderngl

    errors = []
    for kwargs in ({"backend": "egl"}, {}):
        try:
            # creating a context makes it current; keep whatever was current before
            with EGLCurrent():
                return moderngl.create_standalone_context(require=require, **kwargs)
        except Exception as e:  # pragma: no cover - depends on the machine
            errors.append(f"{kwargs or 'default'}: {str(e).splitlines()[0] if str(e) else e!r}")
    raise RuntimeError(  # pragma: no cover
        "no headless OpenGL 3.3 context (install Mesa EGL: libegl1 libegl-mesa0 libgl1-mesa-dri); "
        + "; ".join(errors)
    )
