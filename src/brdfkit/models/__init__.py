"""Every published model, one module each. Importing this package registers them all."""

from . import lambert  # noqa: F401
