"""Re-export of :mod:`imucalib.models.earth` (the Earth model lives in ``models/``)."""

from imucalib.models.earth import *  # noqa: F403
from imucalib.models.earth import __all__ as __all__
