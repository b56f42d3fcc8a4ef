"""Entry of the ``photodem`` console script.

The command's modules take a moment to load (numpy, rasterio). A Ctrl-C in that moment would
otherwise end in a Python traceback; here it ends like a Ctrl-C during a run: one line, exit
130, and nothing written (nothing has started yet).
"""

from __future__ import annotations

import sys


def main() -> int:
    """Load the command line and run it; a Ctrl-C while loading exits with 130."""
    try:
        from .cli import main as run_command  # lazy: a Ctrl-C during the imports lands here
    except KeyboardInterrupt:
        print("\nphotodem: cancelled (interrupted) before the command started; nothing was "
              "written.", file=sys.stderr)
        return 130
    return run_command()


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
