"""The demo of ``python -m snr demo``: both UROV roles on this machine, one process each.

By default the screen shows a one-line banner and the live telemetry; the
nodes log only warnings and errors. ``verbose=True`` (``--verbose``) shows
their whole log: listening, connecting, the simulated serial port.

``python -m snr demo --sim`` (`run_sim_demo`) runs lesson 1's wall follower
on the simulated rover instead: one node, in a window or as PNG frames.
"""

from __future__ import annotations

import logging
import socket
import sys
from typing import Optional

import snr
from snr.extras.demo.system import make_components
from snr.prelude import CommsError, ConfigError

__all__ = ["LogLevel", "LogLevelFactory", "free_port_pair", "run_demo", "run_sim_demo"]


def free_port_pair(host: str = "127.0.0.1") -> int:
    """A port P such that P and P+1 are both free on ``host`` right now.

    Raises:
        CommsError: no such pair was found in 50 tries.

    Example::

        port = free_port_pair()   # the demo's links listen on port and port + 1
    """
    for _ in range(50):
        with socket.socket() as probe:
            probe.bind((host, 0))
            port = int(probe.getsockname()[1])
        if port >= 65535:
            continue
        with socket.socket() as second:
            try:
                second.bind((host, port + 1))
            except OSError:
                continue
        return port
    raise CommsError(f"Could not find two free neighbouring ports on {host}.")


class LogLevel(snr.Endpoint):
    """Sets the log level of its node; it handles no tasks.

    The level is set when the node builds its components, in the node's own
    process: a process started with "spawn" (Windows, macOS) does not inherit
    the logging settings of the program that started it.

    Example::

        {"urov": [LogLevelFactory(logging.WARNING), ...]}
    """

    def __init__(self, factory: LogLevelFactory, parent: snr.AbstractNode) -> None:
        super().__init__(factory, parent, "log_level")
        parent.log.setLevel(factory.level)


class LogLevelFactory(snr.EndpointFactory):
    """Builds a `LogLevel`: list it first, so the node's log is quiet from its start.

    Example::

        LogLevelFactory(logging.WARNING)   # warnings and errors only
    """

    def __init__(self, level: int) -> None:
        super().__init__()
        self.level = level

    def get(self, parent: snr.AbstractNode) -> LogLevel:
        return LogLevel(self, parent)


VIEWED_KEYS = ["sensor_data", "controller_input"]
"""The topside keys ``--view`` shows: telemetry (a dict of numbers) and the pilot's command."""


def run_demo(seconds: float = 15.0, verbose: bool = False, view_port: Optional[int] = None) -> int:
    """Run the UROV system for ``seconds``: the exit code of ``python -m snr demo``.

    Each role runs in its own process, talking over TCP on 127.0.0.1 (ports
    chosen now, so the demo never collides with anything). The topside
    process shows the vehicle's live telemetry. Ctrl-C stops it early.
    With ``view_port`` (``--view``) the topside node also serves a live view
    of `VIEWED_KEYS` for Foxglove or Lichtblick on that port of 127.0.0.1,
    and the address to open is printed. Returns 0 when both nodes ended
    well, 1 if one did not, 2 if the live view cannot be offered (the
    ``view`` extra is not installed).

    Example::

        run_demo(seconds=2, verbose=True)   # with the nodes' whole log
        run_demo(seconds=120, view_port=8765)   # open the printed URL in a browser
    """
    components = make_components("127.0.0.1", free_port_pair(), seconds)
    level = logging.INFO if verbose else logging.WARNING
    for factories in components.values():
        assert isinstance(factories, list)
        factories.insert(0, LogLevelFactory(level))
    if view_port is not None:
        if view_port == 0:  # the URL is printed before the node starts: choose the port now
            with socket.socket() as probe:
                probe.bind(("127.0.0.1", 0))
                view_port = int(probe.getsockname()[1])
        try:
            bridge = snr.FoxgloveBridgeFactory(VIEWED_KEYS, port=view_port)
        except ConfigError as error:
            print(error, file=sys.stderr)
            return 2
        topside = components["topside"]
        assert isinstance(topside, list)
        topside.append(bridge)
        print(
            f"Live view: open {bridge.app_url}\n"
            f"  (or, in Foxglove or Lichtblick, open a Foxglove WebSocket connection to "
            f"{bridge.url}),\n"
            "  add a Plot panel and plot /sensor_data.data.depth_m",
            flush=True,
        )
    config = snr.Config(components, mode=snr.Mode.DEPLOYED)
    hint = "" if verbose else "; --verbose shows the log"
    print(
        f"SNR demo: a pilot steers a simulated underwater robot over TCP for {seconds:g} s "
        f"(Ctrl-C stops it{hint}).",
        flush=True,
    )
    runner = snr.MultiProcRunner(["urov", "topside"], config)
    runner.run()
    failed = [code for code in runner.exitcodes if code not in (0, None)]
    return 1 if failed else 0


def run_sim_demo(
    seconds: float = 15.0, verbose: bool = False, frames_dir: Optional[str] = None
) -> int:
    """Lesson 1's wall follower drives the simulated rover: ``python -m snr demo --sim``.

    One node in this process: the simulator, its view and the brain of
    ``examples/lessons/wall_follower.py``, lesson 1's solution (shipped as
    `snr.extras.lessons.l01_wall_follower.solution`).
    With a screen the rover drives in a window (closing it stops the demo);
    without one, or with ``frames_dir``, the pictures are PNG frames and the
    folder is printed. The default demo stays the UROV: it shows what SNR is
    for (two nodes in two processes, talking over TCP), where this one shows
    a student's first robot program. Returns 0 once the time is up.

    Example::

        run_sim_demo(seconds=5)                       # a window, or frames in sim_frames/
        run_sim_demo(seconds=5, frames_dir="frames")  # PNG frames in frames/
    """
    from snr.extras.lessons.l01_wall_follower import solution as wall_follower  # only --sim

    if not verbose:  # the node keeps a level set before it starts: warnings only
        logging.getLogger("snr.sim").setLevel(logging.WARNING)
    hint = "" if verbose else "; --verbose shows the log"
    print(
        f"SNR demo --sim: lesson 1's wall follower (docs/lessons.md) drives a simulated "
        f"rover round a room for {seconds:g} s (Ctrl-C stops it{hint}).",
        flush=True,
    )
    wall_follower.run(seconds, frames_dir)
    return 0
