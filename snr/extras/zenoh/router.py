"""``python -m snr router``: a Zenoh router for a classroom, set up from the secret.

Where multicast is blocked (most school Wi-Fi), Zenoh nodes meet through a
router: every node runs in ``mode="client"`` and connects to it. This runs one
in Python, with the same Zenoh as the nodes, so a teacher needs no ``zenohd``
download. With a secret (``$SNR_SECRET`` or the file of ``python -m snr secret
new``), the router links only to sessions that prove the same secret, the way
the nodes do (docs/comms.md, "Who may connect"). ``--zenohd`` prints instead
what ``zenohd`` needs for the same: its user, password and dictionary line.

The kernel never imports this module: ``python -m snr router`` loads it through
the ``snr.commands`` entry point ``router`` (``pyproject.toml``).

Example::

    python -m snr router --listen tcp/0.0.0.0:7447
"""

from __future__ import annotations

import argparse
import sys
import time
from typing import IO, Any, Optional

from snr.extras.zenoh.comms import zenoh_config, zenoh_credentials
from snr.prelude import ConfigError
from snr.prelude.install import install_hint
from snr.std_mods.comms.handshake import FROM_ENVIRONMENT, find_secret

__all__ = ["add_arguments", "run"]

DEFAULT_LISTEN = "tcp/0.0.0.0:7447"


def add_arguments(parser: argparse.ArgumentParser) -> None:
    """The router command's options (``python -m snr router --help``).

    Example::

        add_arguments(argparse.ArgumentParser())
    """
    parser.description = (
        "A Zenoh router that nodes in mode='client' connect to where multicast "
        "is blocked; with a secret, only nodes with the same secret link to it. --zenohd "
        f"prints what zenohd needs instead (needs {install_hint('zenoh')})."
    )
    parser.add_argument(
        "--listen",
        action="append",
        metavar="ENDPOINT",
        help=f"a Zenoh endpoint to listen on (default {DEFAULT_LISTEN}; may be repeated)",
    )
    parser.add_argument(
        "--seconds", type=float, default=None, help="stop after this long (default: Ctrl-C)"
    )
    parser.add_argument(
        "--zenohd",
        action="store_true",
        help="print what a zenohd router needs to accept nodes with this secret, and exit",
    )


def run(args: argparse.Namespace, out: Optional[IO[str]] = None) -> int:
    """Run the router (or print zenohd's settings); the command's exit status.

    Example::

        run(argparse.Namespace(listen=["tcp/127.0.0.1:7447"], seconds=5.0, zenohd=False))
    """
    out = out or sys.stdout
    try:
        secret = find_secret(FROM_ENVIRONMENT, "python -m snr router")
    except ConfigError as error:  # an empty secret, an unreadable secret file
        print(f"snr router: {error}", file=sys.stderr)
        return 1
    if args.zenohd:
        return _print_zenohd_settings(secret, out)
    try:
        import zenoh
    except ImportError:
        print(
            f"snr router: a router needs the Zenoh library: {install_hint('zenoh')}",
            file=sys.stderr,
        )
        return 1
    listen = list(args.listen or [DEFAULT_LISTEN])
    try:
        # No multicast scouting: the nodes connect to it by its address.
        config = zenoh_config(mode="router", listen=listen, scouting=False, secret=secret)
        router = zenoh.open(config)
    except zenoh.ZError as error:
        print(
            f"snr router: could not listen on {listen}: {str(error).split(' at /')[0]}. "
            "If a port is in use, stop the other program or pick another port.",
            file=sys.stderr,
        )
        return 1
    who = (
        "only nodes with this computer's secret link to it"
        if secret is not None
        else "no secret: any node on the network links to it"
    )
    print(
        f"Zenoh router listening on {', '.join(listen)} ({who}). Nodes connect with "
        "ZenohCommsFactory(system, mode='client', connect=['tcp/<this computer>:<port>'], "
        "scouting=False). Ctrl-C stops it.",
        file=out,
        flush=True,
    )
    try:
        _serve(router, args.seconds, out)
    except KeyboardInterrupt:
        pass
    finally:
        router.close()
    print("Zenoh router stopped.", file=out, flush=True)
    return 0


def _serve(router: Any, seconds: Optional[float], out: IO[str]) -> None:
    """Say how many sessions are linked each time it changes, until ``seconds`` pass."""
    deadline = None if seconds is None else time.monotonic() + seconds
    linked = 0
    while deadline is None or time.monotonic() < deadline:
        now = len(list(router.info.transports()))  # clients, peers and routers alike
        if now != linked:
            linked = now
            print(f"{linked} session(s) linked", file=out, flush=True)
        time.sleep(0.5 if deadline is None else min(0.5, max(0.0, deadline - time.monotonic())))


def _print_zenohd_settings(secret: Optional[bytes], out: IO[str]) -> int:
    """What zenohd needs to link to nodes with this secret (docs/comms.md, "Who may connect")."""
    if secret is None:
        print(
            "snr router --zenohd: this computer has no secret ($SNR_SECRET, or `python -m snr "
            "secret new`), so zenohd needs no settings: nodes without a secret link to any router.",
            file=out,
        )
        return 0
    user, password = zenoh_credentials(secret)
    print(
        "To let nodes with this secret link to zenohd, write this line to a file only you "
        f"can read (say users.txt):\n\n{user}:{password}\n\n"
        "and give zenohd these settings (in its JSON5 configuration file):\n\n"
        "transport: { auth: { usrpwd: {\n"
        f'  user: "{user}", password: "{password}", dictionary_file: "users.txt",\n'
        "} } }\n\n"
        "The password is made from the secret; the secret itself is not in it.",
        file=out,
    )
    return 0
