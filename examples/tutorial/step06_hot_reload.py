"""Tutorial step 6: hot reload, from the console or when you save.

Start the node, then edit ``GREETING`` in ``step06_greeter.py`` and save:

    python step06_hot_reload.py

A loop sends a ``tick`` event every second and the greeter prints a line.
The node runs for two minutes (``--seconds`` changes that); Ctrl-C stops it
sooner. The node reloads the greeter in two ways:

* When you save ``step06_greeter.py``, a watcher loop notices and schedules
  ``tasks.reload_component("greeter")`` (a task, like any other).
* From another terminal, a console talks to the node over TCP:

      snr-console 127.0.0.1:9123
      127.0.0.1:9123> reload greeter
      127.0.0.1:9123> list endpoints
      127.0.0.1:9123> exit

  ``exit`` stops the node (and closes the console); ``quit`` or Ctrl-D
  leaves the console and the node keeps running.

The greeting changes and the count goes on: the count is kept on the factory,
and a reload builds a new greeter from the same factory. ``--no-watch``
leaves only the console; ``--no-console`` only the watcher.
"""

import argparse
import os
import sys
from typing import List, Optional, Sequence, Tuple

import step06_greeter

import snr


class TickLoop(snr.ThreadLoop):
    """Schedules a ``tick`` event every ``period_s`` seconds."""

    def __init__(self, factory: "TickLoopFactory", parent: snr.AbstractNode) -> None:
        super().__init__(factory, parent, "ticker", max_tick_rate_hz=1 / factory.period_s)

    def loop(self) -> None:
        self.schedule(snr.tasks.event("tick"))


class TickLoopFactory(snr.LoopFactory):
    def __init__(self, period_s: float = 1.0) -> None:
        super().__init__()
        self.period_s = period_s

    def get(self, parent: snr.AbstractNode) -> TickLoop:
        return TickLoop(self, parent)


FileStamp = Tuple[int, int]  # (modification time in ns, size in bytes)


class ReloadWhenSavedLoop(snr.ThreadLoop):
    """Watches a source file; when it changes, asks the node to reload a component."""

    def __init__(self, factory: "ReloadWhenSavedFactory", parent: snr.AbstractNode) -> None:
        super().__init__(factory, parent, "reload_when_saved", max_tick_rate_hz=4)
        self.path = factory.path
        self.component = factory.component
        self.last_seen: Optional[FileStamp] = None

    def stamp(self) -> Optional[FileStamp]:
        try:
            info = os.stat(self.path)
        except OSError:
            return None  # being saved right now; look again next time
        return (info.st_mtime_ns, info.st_size)

    def setup(self) -> None:
        self.last_seen = self.stamp()

    def loop(self) -> None:
        now = self.stamp()
        if now is not None and now != self.last_seen:
            self.last_seen = now
            # The node logs "Reloaded 'greeter'" once it has rebuilt it.
            self.schedule(snr.tasks.reload_component(self.component))


class ReloadWhenSavedFactory(snr.LoopFactory):
    def __init__(self, path: str, component: str) -> None:
        super().__init__()
        self.path = path
        self.component = component

    def get(self, parent: snr.AbstractNode) -> ReloadWhenSavedLoop:
        return ReloadWhenSavedLoop(self, parent)


def make_config(
    console_port: Optional[int] = 9123,
    watch: bool = True,
    tick_s: float = 1.0,
    seconds: float = 120.0,
) -> snr.Config:
    """The greeter, a ticker, and the ways to reload; stops after ``seconds``."""
    factories: List[snr.AbstractFactory] = [
        step06_greeter.GreeterFactory(),
        TickLoopFactory(tick_s),
        snr.TimeoutLoopFactory(seconds=seconds),
    ]
    if watch:
        factories.append(ReloadWhenSavedFactory(step06_greeter.__file__, "greeter"))
    if console_port is not None:
        factories.append(snr.CommandReceiverFactory(port=console_port))
    return snr.Config({"greeter_node": factories})


def main(argv: Sequence[str]) -> None:
    parser = argparse.ArgumentParser(description="Hot reload: edit step06_greeter.py.")
    parser.add_argument("--port", type=int, default=9123, help="the console's TCP port")
    parser.add_argument("--no-console", action="store_true", help="no console over TCP")
    parser.add_argument("--no-watch", action="store_true", help="do not reload on save")
    parser.add_argument("--tick-s", type=float, default=1.0, help="seconds between greetings")
    parser.add_argument("--seconds", type=float, default=120.0, help="stop after this long")
    args = parser.parse_args(argv)
    port = None if args.no_console else args.port
    config = make_config(port, not args.no_watch, args.tick_s, args.seconds)
    snr.SynchronousRunner("greeter_node", config).run()


if __name__ == "__main__":
    main(sys.argv[1:])
