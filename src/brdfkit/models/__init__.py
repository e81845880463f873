"""Every published model, one module each. Importing this package registers them all."""

from . import lambert  # noqa: F401
from . import microfacet  # noqa: F401
from . import cook_torrance  # noqa: F401
from . import htsg  # noqa: F401
from . import phong  # noqa: F401
from . import blinn_phong  # noqa: F401
from . import oren_nayar  # noqa: F401
from . import ward  # noqa: F401
from . import schlick  # noqa: F401
from . import ashikhmin_shirley  # noqa: F401
