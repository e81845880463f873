"""Every published model, one module each. Importing this package registers them all.

``brdfkit.models`` is both this package and the SPEC's ``bk.models()``: calling
the module returns the registry names, so ``import brdfkit.models.ward`` and
``bk.models()`` both work.
"""

import sys as _sys
import types as _types


class _CallableModule(_types.ModuleType):
    def __call__(self) -> list[str]:
        """Registry names of every analytic model, in registration order."""
        from ..registry import names

        return names()


_sys.modules[__name__].__class__ = _CallableModule

# The lecture's order: Lambert, the Phong family, microfacets, Oren-Nayar, the modern methods.
from . import lambert  # noqa: F401,E402
from . import phong  # noqa: F401,E402
from . import blinn_phong  # noqa: F401,E402
from . import cook_torrance  # noqa: F401,E402
from . import microfacet  # noqa: F401,E402
from . import oren_nayar  # noqa: F401,E402
from . import ward  # noqa: F401,E402
from . import schlick  # noqa: F401,E402
from . import htsg  # noqa: F401,E402
from . import ashikhmin_shirley  # noqa: F401,E402
from . import lafortune  # noqa: F401,E402
