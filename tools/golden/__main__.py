"""``python -m inflo.tools.golden check|refresh|diff ...`` (see :mod:`inflo.tools.golden.cli`)."""
from .cli import main
from .species import COMMAND

if __name__ == "__main__":
    main(prog_name=COMMAND)
