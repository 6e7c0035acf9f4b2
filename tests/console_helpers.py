"""Run a node with a console receiver in a thread, for the console tests."""

from __future__ import annotations

import socket
import threading
from typing import Any, List, Optional, Sequence

from snr import AbstractFactory, CommandReceiverFactory, Config, Mode, Node
from snr.std_mods.io import RemoteConsole
from snr.std_mods.io.console_protocol import Reply, ReplyDecoder
from tests.quiet import SLOW_HANDLER_S

STOP_TIMEOUT_S = 5.0


class NodeInThread:
    """A node (with a CommandReceiverFactory on a free port) running in a thread.

    Use as a context manager: on exit the node is stopped (if still running),
    the thread joined, and any failure of the node re-raised.
    """

    def __init__(
        self,
        factories: Sequence[AbstractFactory],
        token: Optional[str] = None,
        mode: Mode = Mode.TEST,
        profile: Optional[bool] = None,
        **receiver_options: Any,
    ) -> None:
        self.receiver = CommandReceiverFactory(port=0, token=token, **receiver_options)
        config = Config({"robot": [*factories, self.receiver]}, mode=mode, profile=profile)
        self.node = Node("robot", config)
        self.node.slow_handler_s = SLOW_HANDLER_S  # quick handlers on a busy machine
        self.errors: List[BaseException] = []
        self.thread = threading.Thread(target=self._run, name="test-node", daemon=True)
        self.host = ""
        self.port = 0

    def _run(self) -> None:
        try:
            self.node.loop()
        except BaseException as error:  # reported by __exit__
            self.errors.append(error)

    def __enter__(self) -> NodeInThread:
        self.thread.start()
        self.host, self.port = self.receiver.wait_until_listening(STOP_TIMEOUT_S)
        return self

    def __exit__(self, *exc: object) -> None:
        self.node.set_terminate_flag("test finished")
        self.thread.join(STOP_TIMEOUT_S)
        assert not self.thread.is_alive(), "the node did not stop"
        if self.errors:
            raise self.errors[0]

    def console(self, token: Optional[str] = None, timeout_s: float = 5.0) -> RemoteConsole:
        """A connected RemoteConsole (close it, or use it in a with block)."""
        console = RemoteConsole(self.host, self.port, token=token, timeout_s=timeout_s)
        console.connect()
        return console

    def wait_stopped(self) -> None:
        self.thread.join(STOP_TIMEOUT_S)
        assert not self.thread.is_alive(), "the node did not stop"


def read_replies(sock: socket.socket, count: int, timeout_s: float = 5.0) -> List[Reply]:
    """Read ``count`` reply frames from a raw console socket (fewer if the node hangs up)."""
    decoder = ReplyDecoder()
    replies: List[Reply] = []
    sock.settimeout(timeout_s)
    while len(replies) < count:
        data = sock.recv(65536)
        if not data:
            break
        replies += decoder.feed(data)
    return replies
