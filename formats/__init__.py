"""Readers and writers for every inflo file format; each has a spec page ``formats/<name>.md``."""
from .errors import FormatError, InputError

__all__ = ["FormatError", "InputError"]
