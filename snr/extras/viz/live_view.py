"""A live view of a node's pages in Foxglove or Lichtblick, over the Foxglove WebSocket protocol.

Add `FoxgloveBridgeFactory` to a node, open the URL it logs, and every key it
forwards is a channel in the viewer (topic ``/<key>``): plot ``/depth_m.data``
for a number, ``/telemetry.data.depth_m`` for a dict of numbers. The pages are
sent as the node stores them, each exactly as the codec writes it.

The node never waits for a viewer: a viewer that reads slowly gets the newest
page of each key, and the pages it missed are counted and logged (see
``live_view_server.py``). The server listens on 127.0.0.1 only, unless told
otherwise: anyone who can connect sees every page.

It needs the ``websockets`` package: ``pip install 'snr-robotics[view]'``, which installs
without compiling on a Raspberry Pi too. Without it, creating the factory
raises a `ConfigError` that says so in one line.

Example::

    config = Config({"topside": [
        ...,
        FoxgloveBridgeFactory(["depth_m", "sensor_data"]),   # ws://127.0.0.1:8765
    ]})
"""

from __future__ import annotations

import importlib
import socket
import sys
from typing import TYPE_CHECKING, Any, List, Optional, Sequence, Union
from urllib.parse import quote

from snr.core import Endpoint, EndpointFactory
from snr.core.checks.os_errors import explain_os_error
from snr.prelude import (
    AbstractNode,
    CommsError,
    ConfigError,
    DataKey,
    SomeTasks,
    Task,
    TaskId,
    TaskType,
)
from snr.prelude.install import install_hint

if TYPE_CHECKING:
    from snr.extras.viz.live_view_server import LiveViewServer, LiveViewStats

__all__ = ["DEFAULT_LIVE_VIEW_PORT", "FoxgloveBridge", "FoxgloveBridgeFactory", "foxglove_app_url"]

DEFAULT_LIVE_VIEW_PORT = 8765
"""The port Foxglove and Lichtblick suggest for a WebSocket connection."""

_INSTALL = install_hint("view")
_STOP_S = 1.0  # how long stopping waits for the server's thread
_SEND_BUFFER = 1 << 18  # bytes the OS may hold for one viewer (Linux doubles it)


def foxglove_app_url(ws_url: str) -> str:
    """The Foxglove web app's address that opens the live view at ``ws_url``.

    Example::

        foxglove_app_url("ws://127.0.0.1:8765")
        # 'https://app.foxglove.dev/?ds=foxglove-websocket&ds.url=ws%3A%2F%2F127.0.0.1%3A8765'
    """
    return f"https://app.foxglove.dev/?ds=foxglove-websocket&ds.url={quote(ws_url, safe='')}"


def _server_module() -> Any:
    """``live_view_server``, imported now; a one-line ConfigError when websockets is missing."""
    try:
        import websockets.asyncio.server  # noqa: F401  (13.0 and later have it)
    except ImportError:
        raise ConfigError(
            "The live view needs the 'websockets' package (version 13 or later), which is "
            f"not installed: {_INSTALL}"
        ) from None
    return importlib.import_module("snr.extras.viz.live_view_server")


class FoxgloveBridge(Endpoint):
    """Serves the pages stored under its keys to Foxglove-protocol viewers.

    The server starts when the node starts and stops when it stops (a
    reload restarts it on the same port; viewers reconnect by themselves).

    Example::

        FoxgloveBridgeFactory(["depth_m"], port=8765)   # builds one of these
    """

    def __init__(self, factory: FoxgloveBridgeFactory, parent: AbstractNode) -> None:
        super().__init__(factory, parent, factory.name)
        self.bridge = factory
        self._server: Optional[LiveViewServer] = None
        self.task_handlers = {(TaskType.store_page, key): self.forward_page for key in factory.keys}

    def begin(self) -> None:
        """Listen now, so a port in use is reported when the node starts."""
        module = _server_module()
        bridge = self.bridge
        listener = _listen(bridge.host, bridge.port, self.parent.role, self.name)
        bridge.port = int(listener.getsockname()[1])  # the port chosen, when 0 was asked
        server: LiveViewServer = module.LiveViewServer(
            self.parent.role, listener, self.log, bridge.stats
        )
        server.start()
        self._server = server
        self.info(
            "Live view of %s at %s; in Foxglove or Lichtblick open a Foxglove WebSocket "
            "connection to it, or open %s",
            ", ".join(bridge.keys),
            bridge.url,
            bridge.app_url,
        )

    def forward_page(self, task: Task, key: TaskId) -> SomeTasks:
        """Hand the stored page to the server; never waits for a viewer."""
        page = task.page()
        server = self._server
        if page is not None and server is not None:
            server.publish(page)
        return None

    def halt(self) -> None:
        """Stop serving: close the viewers' connections and free the port."""
        server, self._server = self._server, None
        if server is not None:
            server.stop(_STOP_S)
            stats = self.bridge.stats
            if stats.pages_sent or stats.pages_dropped:
                self.info(
                    "Live view: %d pages sent, %d dropped for slow viewers",
                    stats.pages_sent,
                    stats.pages_dropped,
                )

    def terminate(self) -> None:
        """Stop serving, if not yet done."""
        self.halt()

    def is_alive(self) -> bool:
        """True while the server's thread runs."""
        server = self._server
        return server is not None and server.is_alive()


def _listen(host: str, port: int, role: str, name: str) -> socket.socket:
    try:
        listener = socket.create_server((host, port))
        # Viewers' sockets inherit a small send buffer: what a slow viewer has not
        # read waits in SNR's newest-per-key buffer, not as stale pages in the OS.
        listener.setsockopt(socket.SOL_SOCKET, socket.SO_SNDBUF, _SEND_BUFFER)
    except OSError as error:
        raise CommsError(
            explain_os_error(
                error,
                action="listen",
                target=f"{host}:{port}",
                who=f"The live view {name!r} of node {role!r}",
                setting="FoxgloveBridgeFactory(port=...)",
            )
        ) from error
    return listener


class FoxgloveBridgeFactory(EndpointFactory):
    """Builds a `FoxgloveBridge`: a live view of ``keys`` for Foxglove and Lichtblick.

    Args:
        keys: the data keys to show (one key may be given as a string).
        port: the TCP port to listen on; 0 picks a free one (see ``port``
            after the node has started).
        host: the address to listen on. The default, 127.0.0.1, lets only
            this machine connect; ``"0.0.0.0"`` lets any machine on the
            network see every page of these keys.
        name: the endpoint's name (default ``"live_view"``).

    Raises:
        ConfigError: no keys, a port out of range, or the ``websockets``
            package is missing (``pip install 'snr-robotics[view]'``).

    Example::

        bridge = FoxgloveBridgeFactory(["depth_m", "sensor_data"])
        bridge.url       # 'ws://127.0.0.1:8765'
        bridge.app_url   # opens it in the Foxglove web app

    Attributes:
        stats: pages sent and dropped, over the whole run (a ``LiveViewStats``).
    """

    def __init__(
        self,
        keys: Union[DataKey, Sequence[DataKey]],
        port: int = DEFAULT_LIVE_VIEW_PORT,
        host: str = "127.0.0.1",
        name: Optional[str] = None,
    ) -> None:
        super().__init__(sys.modules[__name__])
        self.keys: List[DataKey] = [keys] if isinstance(keys, str) else list(keys)
        if not self.keys or not all(isinstance(k, str) and k for k in self.keys):
            raise ConfigError(
                f"FoxgloveBridgeFactory({keys!r}): keys must be a list of data keys to show, "
                "e.g. ['depth_m', 'heading_deg']."
            )
        if type(port) is not int or not 0 <= port <= 65535:
            raise ConfigError(
                f"FoxgloveBridgeFactory(port={port!r}): the port must be a whole number "
                f"from 1024 to 65535 (or 0 for any free port); the usual one is "
                f"{DEFAULT_LIVE_VIEW_PORT}."
            )
        module = _server_module()  # a missing package is reported now, not at start
        self.port = port
        self.host = host
        self.name = name or "live_view"
        self.stats: LiveViewStats = module.LiveViewStats()

    @property
    def url(self) -> str:
        """The WebSocket address viewers connect to, e.g. ``ws://127.0.0.1:8765``."""
        host = f"[{self.host}]" if ":" in self.host else self.host
        return f"ws://{host}:{self.port}"

    @property
    def app_url(self) -> str:
        """The Foxglove web app's address that opens this live view."""
        return foxglove_app_url(self.url)

    def get(self, parent: AbstractNode) -> FoxgloveBridge:
        return FoxgloveBridge(self, parent)

    def __repr__(self) -> str:
        return f"FoxgloveBridgeFactory({self.keys!r}, port={self.port})"
