"""``python -m snr.console HOST:PORT``: the remote console (also ``snr-console``).

The program is `snr.std_mods.io.remote_console.main`; this module lets
``python -m snr.console`` run it. With ``--zenoh SYSTEM [ROLE]`` it reaches a
node by its role over Zenoh instead (``snr/extras/zenoh/console.py``).

Example::

    $ python -m snr.console 127.0.0.1:9123 -c "list endpoints"
    $ python -m snr.console --zenoh team7 urov -c stats
"""

from __future__ import annotations

import sys

from snr.std_mods.io.remote_console import main

__all__ = ["main"]

if __name__ == "__main__":
    sys.exit(main())
