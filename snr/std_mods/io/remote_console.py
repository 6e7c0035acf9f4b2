"""The console's end: the client core `ConsoleClient`, its TCP transport, and `main`.

``snr-console HOST:PORT`` (or ``python -m snr console``) talks to a node's
`CommandReceiverFactory`; ``--zenoh`` loads another transport through the entry
point ``snr.console_transports`` (docs/console.md, "How the console is built").

Example::

    $ snr-console 127.0.0.1:9123
    Connected to node 'robot'. Type 'help' for the commands, 'exit' to stop the node.
    127.0.0.1:9123> task event beep
    Scheduled (event, 'beep'): []
"""

from __future__ import annotations

import socket
import sys
from abc import ABC, abstractmethod
from typing import IO, TYPE_CHECKING, Callable, Iterable, List, Optional, Sequence, Type, TypeVar

from snr.core import plugins
from snr.core.checks.os_errors import explain_os_error
from snr.prelude import SNRError, WireFormatError
from snr.std_mods.io.command_processor import COMMANDS, load_extra_commands
from snr.std_mods.io.console_protocol import (
    DEFAULT_CONSOLE_PORT,
    MAX_LINE_BYTES,
    TOKEN_ENV_VAR,
    ConsoleConnectionError,
    Reply,
    ReplyDecoder,
    Status,
    default_token,
    parse_address,
)

if TYPE_CHECKING:
    import argparse

__all__ = [
    "EXIT_CONNECTION",
    "EXIT_INTERRUPTED",
    "EXIT_OK",
    "EXIT_USAGE",
    "ConsoleClient",
    "RemoteConsole",
    "main",
    "say",
]

EXIT_OK = 0
"""Exit code: the session ended normally (``quit``, end of input, or ``exit``)."""

EXIT_CONNECTION = 1
"""Exit code: could not connect, was refused, lost the node, or a command failed."""

EXIT_USAGE = 2
"""Exit code: the command line was wrong."""

EXIT_INTERRUPTED = 130
"""Exit code: Ctrl-C while waiting for the node (the shell's convention)."""

_LEAVE_WORDS = ("quit", "q")
_Client = TypeVar("_Client", bound="ConsoleClient")


class ConsoleClient(ABC):
    """The console's core: sends command lines, prints replies, runs the program.

    It reaches nodes through a transport's methods (docs/console.md, "How the
    console is built"): `RemoteConsole` over TCP, ``ZenohConsole``
    (``snr.extras.zenoh.console``) over Zenoh.

    Example::

        with RemoteConsole("127.0.0.1", 9123) as console:   # a ConsoleClient over TCP
            print(console.send("list endpoints").text)

    Args:
        token: the shared token, if the node needs one (default: the
            ``SNR_CONSOLE_TOKEN`` environment variable, else a word made from
            the secret, ``SNR_SECRET`` or the secret file, as the node makes it).
        timeout_s: how long to wait to connect, and for each reply.
    """

    def __init__(self, token: Optional[str] = None, timeout_s: float = 10.0) -> None:
        self.token = default_token(token, "The console")
        load_extra_commands()  # COMMANDS names every command: for Tab and the Zenoh console
        self.timeout_s = timeout_s
        self.greeting: Optional[Reply] = None

    # -- what a transport provides ------------------------------------------------
    @property
    @abstractmethod
    def where(self) -> str:
        """What the prompt and the messages call the node(s), e.g. ``"127.0.0.1:9123"``."""

    @abstractmethod
    def connect(self) -> Reply:
        """Reach the node(s); returns the greeting.

        Raises:
            ConsoleConnectionError: no node answered, or it turned the console away.
        """

    @abstractmethod
    def ask(self, line: str, timeout_s: float) -> Reply:
        """Send one checked line, wait at most ``timeout_s``; its reply (several nodes': one).

        Raises:
            ConsoleConnectionError: the node went away, or no reply came in time.
        """

    @abstractmethod
    def close(self) -> None:
        """Hang up (the node keeps running). Safe to call twice."""

    @abstractmethod
    def is_connected(self) -> bool:
        """True until the console or the node closed the connection."""

    @classmethod
    @abstractmethod
    def add_arguments(cls, parser: argparse.ArgumentParser, prog: str) -> None:
        """Add the command-line options that say which node(s) to reach (for `main`)."""

    @classmethod
    @abstractmethod
    def from_arguments(cls, args: argparse.Namespace) -> ConsoleClient:
        """The client the parsed command line describes (not connected yet).

        Raises:
            ValueError: an option is malformed (a usage error).
            SNRError: the transport cannot be set up (e.g. its library is missing).
        """

    # -- the core -------------------------------------------------------------------
    def _accept(self, greeting: Reply, node: str) -> Reply:
        """``greeting`` if it says hello; else close and say why the node refused."""
        if greeting.status is not Status.HELLO:
            self.close()
            raise ConsoleConnectionError(f"{node} turned the console away: {greeting.text}")
        self.greeting = greeting
        return greeting

    def send(self, line: str) -> Reply:
        """Send one command line and wait for its reply.

        Raises:
            ConsoleConnectionError: not connected, or the node went away.
            ValueError: the line has a newline or is longer than the node accepts.
        """
        if "\n" in line or "\r" in line:
            raise ValueError("A console command is one line: remove the line breaks.")
        if len(line.encode("utf-8")) > MAX_LINE_BYTES:
            raise ValueError(f"A console command may be at most {MAX_LINE_BYTES} bytes long.")
        if not self.is_connected():
            raise self._not_connected()
        reply = self.ask(line, self.timeout_s + _reply_after_s(line))
        if reply.status is Status.BYE:
            self.close()
        return reply

    def _not_connected(self) -> ConsoleConnectionError:
        return ConsoleConnectionError(
            f"The console is not connected to {self.where}: call connect() first "
            "(a node that said bye has closed the connection)."
        )

    def stream(self, line: str, output: IO[str], replies: Optional[int] = None) -> int:
        """Send ``line`` (an ``echo KEY``) again and again, printing each reply, until Ctrl-C.

        Stops early after ``replies`` replies, on an error reply, or when the
        node says bye. Returns an exit code, like `run_command`.

        Example::

            console.stream("echo depth", sys.stdout)   # until Ctrl-C
        """
        sent = 0
        try:
            while replies is None or sent < replies:
                reply = self.send(line)
                sent += 1
                say(output, reply.text)
                if reply.status in (Status.ERROR, Status.BYE):
                    return EXIT_CONNECTION
        except ValueError as error:
            say(output, f"error: {error}")
            return EXIT_CONNECTION
        except KeyboardInterrupt:
            say(output, f"\n(Ctrl-C) Stopped `{line}`.")
        return EXIT_OK

    def __enter__(self: _Client) -> _Client:
        if not self.is_connected():
            self.connect()
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    # -- the interactive program ------------------------------------------------
    def interact(
        self,
        read_line: Optional[Callable[[str], str]] = None,
        output: Optional[IO[str]] = None,
    ) -> int:
        """Read commands until ``quit``, end of input, or the node says bye.

        ``read_line(prompt)`` defaults to ``input`` (with readline if there is
        one). Returns an exit code.
        """
        out = output if output is not None else sys.stdout
        if read_line is None:
            _enable_line_editing()
            read_line = input
        say(out, "Type 'quit' or Ctrl-D to leave (the node keeps running).")
        while self.is_connected():
            try:
                line = read_line(f"{self.where}> ").strip()
            except EOFError:
                out.write("\n")  # so the shell's prompt starts on a new line
                return EXIT_OK
            except KeyboardInterrupt:
                say(out, "\n(Ctrl-C) Type 'quit' to leave.")
                continue
            if line.lower() in _LEAVE_WORDS:
                return EXIT_OK
            if not line:
                continue
            code = self.run_command(line, out)
            if not self.is_connected():
                return code
        return EXIT_OK

    def run_command(self, line: str, output: IO[str]) -> int:
        """Send ``line``, print the reply; an exit code for this command.

        ``echo KEY`` (without a count) streams: it is sent again and again,
        each reply printed, until Ctrl-C (see `stream`).

        Raises:
            ConsoleConnectionError: the node went away.
        """
        words = line.split()
        if len(words) == 2 and words[0].lower() == "echo":
            return self.stream(line, output)
        try:
            reply = self.send(line)
        except ValueError as error:
            say(output, f"error: {error}")
            return EXIT_CONNECTION
        say(output, reply.text)
        if reply.status is Status.ERROR:
            return EXIT_CONNECTION
        if reply.status is Status.BYE and words[0].lower() != "exit":
            return EXIT_CONNECTION  # the node left without being asked
        return EXIT_OK

    def run(
        self,
        commands: Sequence[str] = (),
        stdin: Optional[IO[str]] = None,
        out: Optional[IO[str]] = None,
        err: Optional[IO[str]] = None,
        prog: str = "snr-console",
    ) -> int:
        """Connect, then run ``commands``, or what stdin gives (typed, or piped); the exit code.

        ``prog`` begins each error message: the name of the command that was typed.

        Example::

            RemoteConsole("127.0.0.1", 9123).run(["stats"])   # prints the stats, returns 0
        """
        out = out if out is not None else sys.stdout
        err = err if err is not None else sys.stderr
        try:
            greeting = self.connect()
            if commands:
                return self._run_lines(commands, out)
            say(out, greeting.text)
            source = stdin if stdin is not None else sys.stdin
            if source.isatty() and stdin is None:
                return self.interact(output=out)
            return self._run_lines((line.strip() for line in source), out)
        except ConsoleConnectionError as error:
            say(err, f"{prog}: {error}")
            return EXIT_CONNECTION
        except KeyboardInterrupt:  # while waiting for a reply: leave (the node keeps running)
            say(err, f"\n{prog}: interrupted.")
            return EXIT_INTERRUPTED
        finally:
            self.close()

    def _run_lines(self, lines: Iterable[str], out: IO[str]) -> int:
        """Run commands from ``-c`` or a pipe; the exit code of the worst one."""
        worst = EXIT_OK
        for line in lines:
            if not line:
                continue
            if line.lower() in _LEAVE_WORDS:
                break
            worst = max(worst, self.run_command(line, out))
            if not self.is_connected():
                break
        return worst


class RemoteConsole(ConsoleClient):
    """The console over TCP: a client of a node's `CommandReceiverFactory`.

    Use it as a program (``snr-console``), or from Python, e.g. in a test.

    Example::

        with RemoteConsole("127.0.0.1", 9123) as console:
            print(console.send("list endpoints").text)

    Args:
        host: the node's address.
        port: the receiver's port.
        token, timeout_s: as for `ConsoleClient`.
    """

    def __init__(
        self,
        host: str = "127.0.0.1",
        port: int = DEFAULT_CONSOLE_PORT,
        token: Optional[str] = None,
        timeout_s: float = 10.0,
    ) -> None:
        super().__init__(token, timeout_s)
        self.host = host
        self.port = port
        self._sock: Optional[socket.socket] = None
        self._decoder = ReplyDecoder()
        self._ready: List[Reply] = []
        self._unanswered = 0  # requests sent whose replies were not read (Ctrl-C in a wait)

    @property
    def where(self) -> str:
        """``"host:port"``, for messages and the prompt."""
        return f"{self.host}:{self.port}"

    def connect(self) -> Reply:
        """Connect (and present the token if asked); returns the node's greeting.

        Raises:
            ConsoleConnectionError: refused, unreachable, wrong token, or not
                an SNR console at that address. The message says what to try.
        """
        try:
            self._sock = socket.create_connection((self.host, self.port), self.timeout_s)
        except OSError as error:
            raise ConsoleConnectionError(
                explain_os_error(
                    error,
                    action="connect",
                    target=self.where,
                    who="The console",
                    setting=f"the node's CommandReceiverFactory(port={self.port})",
                )
            ) from None
        greeting = self._receive(self.timeout_s)
        if greeting.status is Status.AUTH:
            if self.token is None:
                self.close()
                raise ConsoleConnectionError(
                    f"The node at {self.where} needs a console token. Give it with "
                    f"`--token TOKEN` or the {TOKEN_ENV_VAR} environment variable, or, if "
                    "the node has a secret, run the console with the same secret "
                    "($SNR_SECRET or the secret file; see docs/console.md)."
                )
            self._send_line(f"auth {self.token}")
            greeting = self._receive(self.timeout_s)
        return self._accept(greeting, f"The node at {self.where}")

    def ask(self, line: str, timeout_s: float) -> Reply:
        """Send ``line`` and read its reply (replies come in request order)."""
        while self._unanswered:  # a reply left unread by Ctrl-C: it is not this one's
            self._receive(timeout_s)
            self._unanswered -= 1
        self._send_line(line)
        self._unanswered += 1
        reply = self._receive(timeout_s)
        self._unanswered -= 1
        return reply

    def _send_line(self, line: str) -> None:
        sock = self._connected()
        try:
            sock.sendall(line.encode("utf-8") + b"\n")
        except OSError as error:
            raise self._lost(error) from None

    def _receive(self, wait_s: float) -> Reply:
        sock = self._connected()
        sock.settimeout(wait_s)
        while not self._ready:
            try:
                data = sock.recv(65536)
            except socket.timeout:
                raise ConsoleConnectionError(
                    f"No reply from the node at {self.where} within {wait_s:g} s. "
                    "It may be busy in a slow handler; try again, or use a longer "
                    "--timeout."
                ) from None
            except OSError as error:
                raise self._lost(error) from None
            if not data:
                raise self._lost(None)
            try:
                self._ready.extend(self._decoder.feed(data))
            except WireFormatError as error:
                self.close()
                raise ConsoleConnectionError(f"{self.where}: {error}") from None
        reply = self._ready.pop(0)
        if reply.status is Status.BYE:
            self.close()
        return reply

    def _connected(self) -> socket.socket:
        if self._sock is None:
            raise self._not_connected()
        return self._sock

    def _lost(self, error: Optional[OSError]) -> ConsoleConnectionError:
        self.close()
        why = f" ({error.strerror or error})" if error is not None else ""
        return ConsoleConnectionError(
            f"Lost the connection to the node at {self.where}{why}. The node may have "
            "stopped; its terminal says why."
        )

    def close(self) -> None:
        """Hang up (the node keeps running). Safe to call twice."""
        if self._sock is not None:
            self._sock.close()
            self._sock = None

    def is_connected(self) -> bool:
        """True until the console or the node closed the connection."""
        return self._sock is not None

    @classmethod
    def add_arguments(cls, parser: argparse.ArgumentParser, prog: str) -> None:
        """``[HOST:PORT]``, and the help's words on reaching a node over Zenoh instead."""
        parser.description = (
            "Send commands to a running SNR node (one with a CommandReceiverFactory)."
        )
        parser.epilog = (
            "Inside the console, type 'help' for the node's commands. To reach a node "
            f"by its role over Zenoh instead: {prog} --zenoh SYSTEM [ROLE] "
            f"(its options: {prog} --zenoh SYSTEM --help)."
        )
        parser.add_argument(
            "address",
            metavar="HOST:PORT",
            nargs="?",
            default=f"127.0.0.1:{DEFAULT_CONSOLE_PORT}",
            help=f"the node's console address (default 127.0.0.1:{DEFAULT_CONSOLE_PORT})",
        )

    @classmethod
    def from_arguments(cls, args: argparse.Namespace) -> RemoteConsole:
        """The console to ``args.address``.

        Raises:
            ValueError: the address is not ``HOST:PORT``.
        """
        host, port = parse_address(args.address)
        return cls(host, port, args.token, args.timeout)


def say(output: IO[str], text: str) -> None:
    """Write ``text`` and a newline to ``output`` and flush it; nothing for empty text.

    Example::

        say(sys.stdout, "Connected to node 'urov'.")
    """
    if text:
        output.write(text + "\n")
        output.flush()


def _reply_after_s(line: str) -> float:
    """How much longer than the timeout ``line``'s reply may take, as its command declares.

    Most commands declare nothing (0); ``hz`` its window. The node and the
    console read the same `COMMANDS`, so the wire carries no wait.
    """
    name, *words = line.split() or [""]
    entry = COMMANDS.get(name.lower())
    if entry is None or entry.reply_after_s is None:
        return 0.0
    return max(0.0, entry.reply_after_s(words))


def _enable_line_editing() -> None:
    """Line editing, history and Tab completion where readline exists."""
    try:
        import readline  # optional: absent on Windows
    except ImportError:
        return
    words = [*COMMANDS, *_LEAVE_WORDS]

    def complete(text: str, state: int) -> Optional[str]:
        matches = [w + " " for w in words if w.startswith(text)]
        return matches[state] if state < len(matches) else None

    readline.set_completer(complete)
    readline.parse_and_bind("tab: complete")


def main(
    argv: Optional[Sequence[str]] = None,
    stdin: Optional[IO[str]] = None,
    stdout: Optional[IO[str]] = None,
    stderr: Optional[IO[str]] = None,
    prog: str = "snr-console",
) -> int:
    """``snr-console``: over TCP, or over Zenoh with ``--zenoh``; returns the exit code.

    ``prog`` is the command's name in its usage and messages: ``python -m snr
    console`` passes ``"snr console"``, so its help shows what was typed.

    Example::

        main(["127.0.0.1:9123", "-c", "list endpoints"])   # prints the list, returns 0
        main(["--zenoh", "team7", "urov", "-c", "stats"])
    """
    import argparse  # here, not at the top: only the snr-console command parses arguments

    words = list(sys.argv[1:] if argv is None else argv)
    err = stderr if stderr is not None else sys.stderr
    client: Type[ConsoleClient] = RemoteConsole
    if any(word == "--zenoh" or word.startswith("--zenoh=") for word in words):
        try:  # the Zenoh transport is an extra, found by its entry point
            client = plugins.load("snr.console_transports", "zenoh", f"{prog} --zenoh")
        except SNRError as error:
            say(err, f"{prog}: {error}")
            return EXIT_USAGE
    parser = argparse.ArgumentParser(prog=prog)
    client.add_arguments(parser, prog)
    parser.add_argument(
        "--token", default=None, help=f"the node's console token (default: ${TOKEN_ENV_VAR})"
    )
    parser.add_argument(
        "-c",
        "--command",
        action="append",
        default=[],
        metavar="COMMAND",
        help="run this command and exit (may be repeated)",
    )
    parser.add_argument(
        "--timeout", type=float, default=10.0, help="seconds to wait for the node (default 10)"
    )
    args = parser.parse_args(words)
    try:
        console = client.from_arguments(args)
    except ValueError as error:  # e.g. an address that is not HOST:PORT
        parser.print_usage(err)
        say(err, f"{prog}: error: {error}")
        return EXIT_USAGE
    except SNRError as error:  # e.g. the transport's library is not installed
        say(err, f"{prog}: {error}")
        return EXIT_CONNECTION
    return console.run(args.command, stdin, stdout, err, prog)
