"""Deprecated name of :mod:`inflo.tools.golden` (the golden-file tooling moved out of ``common``):
``python -m inflo.tools.common.golden check|refresh|diff ...`` still runs, forwarded to
``python -m inflo.tools.golden``, so that old notes (and the header of the committed
``tests/golden/*/listing.toml`` files) keep working. Use the new name in anything new.
"""
from inflo.tools.golden import *  # noqa: F403 - the old import path, same objects
from inflo.tools.golden import __all__  # noqa: F401

if __name__ == "__main__":
    import sys

    from inflo.tools.golden.cli import main
    from inflo.tools.golden.species import COMMAND

    print(f"golden: note: python -m inflo.tools.common.golden is now {COMMAND}", file=sys.stderr)
    main(prog_name=COMMAND)
