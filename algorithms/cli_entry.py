"""Entry of the ``photodem`` console script.

The command's modules take a moment to load (numpy, rasterio), and its parser a moment to
build. A Ctrl-C in that moment would otherwise end in a Python traceback; here it ends like a
Ctrl-C during a run: one line, exit 130, and nothing written (nothing has started yet).
A ``PROJ_DATA`` from another PROJ installation is set aside here, before rasterio loads
(:mod:`.proj_env`).
"""

from __future__ import annotations

import sys

from .proj_env import use_own_proj_data  # standard library only: loads in no time


def main() -> int:
    """Load the command line and run it; a Ctrl-C before the run starts exits with 130.

    The command handles a Ctrl-C during a run itself; one that comes while its modules load or
    its parser is built escapes it and ends here, before anything was written.
    """
    note = use_own_proj_data()  # before rasterio is loaded: it reads PROJ_DATA on import
    if note:
        print(f"photodem: warning: {note}", file=sys.stderr)
    try:
        from .cli import main as run_command  # lazy: a Ctrl-C during the imports lands here

        return run_command()
    except KeyboardInterrupt:
        print("\nphotodem: cancelled (interrupted) before the command started; nothing was "
              "written.", file=sys.stderr)
        return 130


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
