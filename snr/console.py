"""``python -m snr.console HOST:PORT``: the remote console (also ``snr-console``).

Example::

    $ python -m snr.console 127.0.0.1:9123 -c "list endpoints"
"""

from __future__ import annotations

import sys

from snr.std_mods.io.remote_console import main

__all__ = ["main"]

if __name__ == "__main__":
    sys.exit(main())
