"""``python -m asekit <command>``: see :mod:`asekit.cli.main`."""

import sys

from asekit.cli.main import main

if __name__ == "__main__":
    sys.exit(main())
