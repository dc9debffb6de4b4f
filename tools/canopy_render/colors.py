"""The old import path of :mod:`inflo.formats.colors` (the same objects)."""
from inflo.formats.colors import *  # noqa: F403
from inflo.formats.colors import __all__  # noqa: F401
