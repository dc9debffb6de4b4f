"""``python -m inflo.tools.warm [-q]``: compile the canopy's numba kernels ahead (:mod:`inflo.tools.warm`)."""
import sys

from . import FLORETS, FRAMES, warm_canopy_kernels


def main(argv=None) -> int:
    argv = sys.argv[1:] if argv is None else argv
    if any(a not in ("-q", "--quiet") for a in argv):
        print("usage: python -m inflo.tools.warm [-q]", file=sys.stderr)
        return 2
    seconds = warm_canopy_kernels()
    if not argv:
        print(f"inflo: canopy kernels compiled or loaded ({FLORETS}-floret scene, {FRAMES} frames): "
              f"{seconds:.1f} s", file=sys.stderr)
    return 0


if __name__ == "__main__":
    sys.exit(main())
