"""``python -m snr.console HOST:PORT``: the remote console (also ``snr-console``).

With ``--zenoh SYSTEM [ROLE]`` it reaches a node by its role over Zenoh
instead (``snr/extras/zenoh/console.py``).

Example::

    $ python -m snr.console 127.0.0.1:9123 -c "list endpoints"
    $ python -m snr.console --zenoh team7 urov -c stats
"""

from __future__ import annotations

import sys
from typing import IO, Optional, Sequence

from snr.core import plugins
from snr.prelude import SNRError
from snr.std_mods.io import remote_console

__all__ = ["main"]


def main(
    argv: Optional[Sequence[str]] = None,
    stdin: Optional[IO[str]] = None,
    stdout: Optional[IO[str]] = None,
    stderr: Optional[IO[str]] = None,
    prog: str = "snr-console",
) -> int:
    """Entry point of ``snr-console``: over TCP, or over Zenoh with ``--zenoh``.

    ``prog`` is the command's name in its usage and messages: ``python -m snr
    console`` passes ``"snr console"``, so its help shows what was typed.

    Example::

        main(["127.0.0.1:9123", "-c", "stats"])
    """
    words = list(sys.argv[1:] if argv is None else argv)
    if any(word == "--zenoh" or word.startswith("--zenoh=") for word in words):
        try:  # the Zenoh transport is an extra, found by its entry point
            zenoh_main = plugins.load("snr.console_transports", "zenoh", f"{prog} --zenoh")
        except SNRError as error:
            print(f"{prog}: {error}", file=sys.stderr if stderr is None else stderr)
            return 2
        return int(zenoh_main(words, stdin, stdout, stderr, prog))
    return remote_console.main(words, stdin, stdout, stderr, prog)


if __name__ == "__main__":
    sys.exit(main())
