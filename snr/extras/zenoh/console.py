"""The console over Zenoh: reach any node of a system by its role (the ``zenoh`` extra).

Install it with ``pip install 'snr-robotics[zenoh]'``.

A node that adds `ZenohConsoleFactory` answers console commands asked as
Zenoh queries on ``snr/<system>/@console/<role>``; `ZenohConsole` asks them.
So a teacher's laptop on the robots' network reaches every node of every
team's system without knowing an address::

    python -m snr console --zenoh team7            # the roles that answer
    python -m snr console --zenoh team7 urov       # type commands into 'urov'

The commands, their replies and their limits are the TCP console's
(docs/console.md): the query's payload is the command line, the reply's
payload a reply frame of the console protocol (``snr-console/1 ok 4\\npong``).
A node given a token (or ``SNR_CONSOLE_TOKEN``) only answers queries that
carry it as their attachment.

Example::

    Config({"urov": [..., ZenohConsoleFactory("team7", connect=["tcp/10.0.0.2:7447"])]})
    with ZenohConsole("team7", "urov", connect=["tcp/10.0.0.2:7447"]) as console:
        print(console.send("list endpoints").text)
"""

from __future__ import annotations

import argparse
import sys
import threading
import time
from typing import IO, Any, Dict, List, Optional, Sequence, Set

from snr.core import LoopFactory
from snr.extras.zenoh.comms import (
    KEY_PREFIX,
    MEET_ENDPOINTS_S,
    _check_chunk_text,
    _zenoh_module,
    meet_endpoints,
    zenoh_config,
)
from snr.prelude import AbstractNode, CommsError
from snr.std_mods.comms.handshake import FROM_ENVIRONMENT, find_secret
from snr.std_mods.io.command_processor import COMMANDS
from snr.std_mods.io.command_receiver import ConsoleLoop
from snr.std_mods.io.console_protocol import (
    MAX_LINE_BYTES,
    TOKEN_ENV_VAR,
    ConsoleConnectionError,
    ConsoleSession,
    Reply,
    ReplyDecoder,
    Status,
    default_token,
    tokens_match,
)
from snr.std_mods.io.remote_console import EXIT_CONNECTION, EXIT_OK, ConsoleClient, say

__all__ = [
    "EVERY_NODE_COMMANDS",
    "ZenohConsole",
    "ZenohConsoleFactory",
    "ZenohConsoleLoop",
    "console_key",
]

MAX_WAITING_QUERIES = 16  # commands queued on one node and not answered yet; more are refused

EVERY_NODE_COMMANDS = ("help", "list", "stats", "dump", "graph")
"""The commands a console sends to every node its role pattern matches (``"*"``).

They only read. ``echo`` and ``hz`` read too, but watch one key on one
node over time, so they need one node's role; the others (``exit``,
``task``, ``reload``, ``pause``...) change a node: typed at ``"*"`` they
would stop or change every robot of the system at once.
"""

_MEET_QUIET_S = 0.25  # a new console waits this long after the last endpoint it met, if any
_ONE_NODE_STREAMS = ("echo", "hz")  # read-only, but a stream of replies from one node


def console_key(system: str, role: str) -> str:
    """The key expression a node's console answers on.

    Example::

        console_key("team7", "urov")   # 'snr/team7/@console/urov'
    """
    return f"{KEY_PREFIX}/{system}/@console/{role}"


class _QueryReply(ConsoleSession):
    """Where one command's reply goes: the query it came in (answered once, then finished)."""

    def __init__(self, owner: ZenohConsoleLoop, query: Any) -> None:
        self.owner = owner
        self.query: Any = query

    def send(self, reply: Reply) -> None:
        query, self.query = self.query, None
        if query is not None:
            self.owner.answer(query, reply)
            self.owner.answered()


class ZenohConsoleLoop(ConsoleLoop):
    """Answers console commands that come as Zenoh queries (built by `ZenohConsoleFactory`).

    Example::

        loop = ZenohConsoleFactory("team7").get(node)
        loop.key     # 'snr/team7/@console/<the node's role>'
    """

    def __init__(self, factory: ZenohConsoleFactory, parent: AbstractNode) -> None:
        super().__init__(factory, parent, factory.name)
        self.spec = factory
        self.zenoh = _zenoh_module()
        self.key = console_key(factory.system, parent.role)
        self.session: Any = None
        self._queryable: Any = None
        self._alive: Any = None  # liveliness token: consoles tell "left" from "busy" by it
        self._waiting = 0
        self._lock = threading.Lock()

    def begin(self) -> None:
        """Add the command processor; open a Zenoh session, say it is alive and answer on `key`."""
        super().begin()
        spec = self.spec
        where = f"ZenohConsoleFactory of node {self.parent.role!r}"
        secret = find_secret(spec.secret, where)
        config = zenoh_config(spec.mode, spec.connect, spec.listen, spec.scouting, secret=secret)
        try:
            self.session = self.zenoh.open(config)
        except self.zenoh.ZError as error:
            raise CommsError(
                f"Node {self.parent.role!r} could not open the Zenoh session of its console "
                f"(listen={spec.listen}, connect={spec.connect}): {str(error).split(' at /')[0]}"
            ) from None
        # The token first: a console that got this node's greeting also sees it alive.
        self._alive = self.session.liveliness().declare_token(self.key)
        self._queryable = self.session.declare_queryable(self.key, self._on_query)
        self.info("Console answers over Zenoh on %s", self.key)

    def loop(self) -> None:
        """Nothing to do here: queries come on Zenoh's threads."""
        self.wait_s(1.0)

    def halt(self) -> None:
        """Stop answering, say this console is gone and close the session."""
        alive, self._alive = self._alive, None
        if alive is not None:
            alive.undeclare()
        queryable, self._queryable = self._queryable, None
        if queryable is not None:
            queryable.undeclare()
        session, self.session = self.session, None
        if session is not None:
            session.close()

    def terminate(self) -> None:
        """Close the session if it is still open."""
        self.halt()

    def answered(self) -> None:
        """A command's reply went out (any thread)."""
        with self._lock:
            self._waiting -= 1

    def _on_query(self, query: Any) -> None:
        """Zenoh's thread: check the query, then queue its command for the node's thread."""
        token = self.spec.token
        if token is not None:
            given = query.attachment
            if given is None or not tokens_match(
                given.to_bytes().decode("utf-8", "replace"), token
            ):
                self.answer(query, Reply(Status.ERROR, "This node needs its console token."))
                return
        payload = query.payload
        line = payload.to_bytes().decode("utf-8", "replace") if payload is not None else ""
        if not line.strip():
            self.answer(query, Reply(Status.HELLO, self.greeting(f" over Zenoh ({self.key})")))
            return
        if len(line.encode("utf-8")) > MAX_LINE_BYTES or "\n" in line:
            text = f"A command is one line of at most {MAX_LINE_BYTES} bytes."
            self.answer(query, Reply(Status.ERROR, text))
            return
        with self._lock:
            busy = self._waiting >= MAX_WAITING_QUERIES
            if not busy:
                self._waiting += 1
        if busy:
            text = "The node is busy with other consoles' commands; try again."
            self.answer(query, Reply(Status.ERROR, text))
            return
        self.submit(line, _QueryReply(self, query))

    def answer(self, query: Any, reply: Reply) -> None:
        """Reply to ``query`` and finish it (any thread); a console that gave up is let be."""
        try:
            query.reply(self.key, reply.encode())
            query.drop()  # finished: the console stops waiting for more replies
        except Exception:  # the console gave up waiting, or the session closed
            pass


class ZenohConsoleFactory(LoopFactory):
    """Lets consoles reach this node over Zenoh, by system and role.

    Args:
        system: the system's name, as in `ZenohCommsFactory`.
        mode, connect, listen, scouting: the Zenoh session's set-up, as in
            `ZenohCommsFactory` (peer mode with multicast scouting by default).
        token: a shared secret queries must carry (default: ``SNR_CONSOLE_TOKEN``
            if set, else a word made from the node's secret, ``SNR_SECRET`` or
            the secret file, else none: anyone on the Zenoh network can type
            commands).
        name: the component name (default ``"zenoh_console"``).
        secret: the system's secret (default: ``SNR_SECRET`` or the secret
            file; None: none), as in `ZenohCommsFactory`: with one, only
            Zenoh sessions with the same secret reach this console at all.

    Example::

        ZenohConsoleFactory("team7")
        ZenohConsoleFactory("team7", connect=["tcp/192.168.1.10:7447"], scouting=False)
    """

    def __init__(
        self,
        system: str,
        *,
        mode: str = "peer",
        connect: Sequence[str] = (),
        listen: Sequence[str] = (),
        scouting: bool = True,
        token: Optional[str] = None,
        name: Optional[str] = None,
        secret: Optional[str] = FROM_ENVIRONMENT,
    ) -> None:
        super().__init__()
        _check_chunk_text(system, "The system name", wildcards=False)
        self.system = system
        self.mode = mode
        self.connect = list(connect)
        self.listen = list(listen)
        self.scouting = scouting
        self.token = default_token(token, "ZenohConsoleFactory")
        self.secret = secret
        self.name = name or "zenoh_console"

    def get(self, parent: AbstractNode) -> ZenohConsoleLoop:
        return ZenohConsoleLoop(self, parent)


class ZenohConsole(ConsoleClient):
    """The console over Zenoh: reaches a node by system and role (``--zenoh``).

    A transport of the console's core, `ConsoleClient`: it talks like
    ``RemoteConsole`` (``send``, ``stream``, ``interact``); each command is one
    Zenoh query, its reply one reply frame.

    The role may be a pattern: ``"*"`` (the default) reaches every node of
    the system. Then only the read-only `EVERY_NODE_COMMANDS` are sent, and
    the reply holds every node's, each labelled with its role; a command
    that changes a node (``exit``, ``reload``...) is refused without being
    sent: name the node. A node that refuses the console (it needs its
    token) is named in each reply; the others are still reached. Which
    nodes are reached is asked again with each command: a node that joined
    since is reached too (or named as refusing), and one whose console has
    gone is named as having left, which does not fail the command; one
    still there that does not reply in time does.

    Its Zenoh session has the system's secret (``secret=``, by default
    ``SNR_SECRET`` or the secret file, as the nodes find it), so it reaches
    the nodes of a system that has one, and its console token is made from
    that secret unless a token is given.

    Example::

        with ZenohConsole("team7", "urov", connect=["tcp/127.0.0.1:7447"], scouting=False) as c:
            print(c.send("stats").text)
        ZenohConsole("team7").roles()   # ['camera', 'urov']
        with ZenohConsole("team7") as every:
            print(every.send("stats").text)   # "[camera] ...", then "[urov] ..."
    """

    def __init__(
        self,
        system: str,
        role: str = "*",
        *,
        mode: str = "peer",
        connect: Sequence[str] = (),
        listen: Sequence[str] = (),
        scouting: bool = True,
        token: Optional[str] = None,
        timeout_s: float = 10.0,
        secret: Optional[str] = FROM_ENVIRONMENT,
    ) -> None:
        super().__init__(token, timeout_s)
        self.system, self.role = system, role
        self.zenoh = _zenoh_module()
        self._config = zenoh_config(
            mode, connect, listen, scouting, secret=find_secret(secret, "ZenohConsole")
        )
        self._mode, self._connect = mode, list(connect)
        self.session: Any = None
        # With a pattern: the roles that greeted this console, so a command's
        # reply can say which of them did not answer it in time; the roles
        # that refused it (a token), named in every reply rather than dropped;
        # and the roles seen with a liveliness token: once it is gone, such a
        # node left (a node of an older SNR has none, so it may be just busy).
        self._greeted: List[str] = []
        self._refused: Dict[str, str] = {}
        self._tokened: Set[str] = set()
        self._lists_roles = False  # snr-console --zenoh SYSTEM, with no role and no -c

    @property
    def where(self) -> str:
        """``"system/role"``, for messages and the prompt."""
        return f"{self.system}/{self.role}"

    @property
    def every_node(self) -> bool:
        """True if the role is a pattern (``"*"``): commands reach every node it matches.

        Example::

            ZenohConsole("team7").every_node           # True: only read-only commands
            ZenohConsole("team7", "urov").every_node   # False
        """
        return "*" in self.role

    def connect(self) -> Reply:
        """Open the Zenoh session and greet the node; returns its greeting.

        With a pattern (``"*"``), the nodes that accept the console are used,
        and those that refuse it (say, for want of their token) are named.

        Raises:
            ConsoleConnectionError: no node of that role answered in time, or
                every one that answered refused the console.
        """
        self._open()
        by_role = self._greetings(self.timeout_s)
        if not by_role:
            raise self._nobody_answered(self.timeout_s)
        if self.every_node:
            greeting = self._greet_every_node(by_role)
        else:
            greeting = next(iter(by_role.values()))
        return self._accept(greeting, f"The node {self.where}")

    def _greet_every_node(self, by_role: Dict[str, Reply]) -> Reply:
        """Note the nodes that accept the console, refuse it, say they are alive; the greeting."""
        self._greeted = sorted(
            role for role, reply in by_role.items() if reply.status is Status.HELLO
        )
        self._refused = {
            role: _refusal(reply.text)
            for role, reply in by_role.items()
            if reply.status is not Status.HELLO
        }
        if not self._greeted:
            self.close()
            raise ConsoleConnectionError(
                f"Every node {self.where} turned the console away: "
                + _labelled({}, self._refused).text
            )
        self._tokened = self._alive_roles(self._ask_alive(self.timeout_s))
        hello = _labelled({role: by_role[role] for role in self._greeted}, self._refused)
        return Reply(
            Status.HELLO,
            f"{hello.text}\nRole {self.role!r} reaches the nodes that accepted it above: only "
            f"{', '.join(EVERY_NODE_COMMANDS)} are sent, and each node's reply is shown. "
            "Name a node for the other commands (exit, task, reload...).",
        )

    def roles(self, timeout_s: float = 2.0) -> List[str]:
        """The roles of the system's nodes that answer consoles now, sorted.

        Example::

            ZenohConsole("team7", scouting=False, connect=[...]).roles()   # ['urov']
        """
        self._open()
        return sorted(self._greetings(timeout_s, "*"))

    def _open(self) -> None:
        if self.session is None:
            self.session = self.zenoh.open(self._config)
            self._meet_endpoints()

    def _meet_endpoints(self) -> None:
        """Wait until the session has met a node at each ``connect`` endpoint.

        Zenoh opens a session at once and connects in the background: a first
        query reached only the nodes met by then, and a console to ``"*"``
        greeted one node of two now and then (a busy machine, 1 time in 40).
        The wait ends 0.25 s after the last node met if some endpoint has
        nobody listening, and after 2 s (or the console's timeout) at most.
        """
        # The node's comms wait the same way (in the background) to say which endpoint
        # they did not meet; here the wait only holds the first command back.
        meet_endpoints(
            self.session,
            self._connect,
            self._mode,
            min(self.timeout_s, MEET_ENDPOINTS_S),
            quiet_s=_MEET_QUIET_S,
        )

    def ask(self, line: str, timeout_s: float) -> Reply:
        """One query for ``line``: the node's reply, or every node's, labelled (``"*"``)."""
        if self.every_node:
            return self._ask_every_node(line, timeout_s)
        by_role = self._answers(line, timeout_s)
        if not by_role:
            raise self._nobody_answered(timeout_s)
        return next(iter(by_role.values()))

    def _ask_every_node(self, line: str, timeout_s: float) -> Reply:
        """Send a read-only command to every node the role matches; their replies, labelled."""
        command = line.split()[0].lower() if line.split() else ""
        if command not in EVERY_NODE_COMMANDS:
            return Reply(Status.ERROR, self._not_sent(command))
        pending = self._ask_alive(timeout_s)  # read after the replies: no extra wait
        answers = self._answers(line, timeout_s)
        self._meet(answers, timeout_s)
        alive = self._alive_roles(pending)
        self._tokened |= alive
        # Alive, yet neither known nor answering: it joined and is busy. Greet it
        # (Zenoh's thread answers greetings), so it is named below, not left out.
        for role in sorted(alive - answers.keys() - set(self._greeted) - self._refused.keys()):
            self._greet(role, timeout_s)
        by_role = {  # a node that refused the console refuses each command the same way
            role: reply for role, reply in answers.items() if role not in self._refused
        }
        notes = dict(self._refused)
        for role in [*self._greeted, *self._refused]:
            if role in answers:
                continue
            if role in self._tokened and role not in alive:  # stopped, or lost: not an error
                notes[role] = "left the system (its console is gone)"
            elif role in self._greeted:  # a node busy in a slow handler must not just vanish
                by_role[role] = Reply(Status.ERROR, self._no_reply(role, timeout_s, alive))
        if not by_role and not notes:
            raise self._nobody_answered(timeout_s)
        return _labelled(by_role, notes)

    def _meet(self, answers: Dict[str, Reply], timeout_s: float) -> None:
        """Roles that answered for the first time (they joined late): greeted, or refused.

        An error may be a refusal (the node needs its token): only a greeting
        tells, as it does at `connect`.
        """
        for role, reply in answers.items():
            if role in self._greeted or role in self._refused:
                continue
            if reply.status is Status.ERROR:
                self._greet(role, timeout_s)
            else:
                self._greeted = sorted([*self._greeted, role])

    def _greet(self, role: str, timeout_s: float) -> None:
        """Greet ``role`` alone: it is greeted, or refused (a token); if silent, asked next time."""
        greeting = self._answers("", timeout_s, role).get(role)
        if greeting is None:  # gone again: learn about it next time
            return
        if greeting.status is Status.HELLO:
            self._greeted = sorted([*self._greeted, role])
        else:
            self._refused[role] = _refusal(greeting.text)

    def _no_reply(self, role: str, timeout_s: float, alive: Set[str]) -> str:
        """Why a node that greeted this console has no reply, and what to do about it."""
        if role in alive:
            why = "the node may be busy in a slow handler"
        else:  # no liveliness token, ever: a node of an older SNR
            why = (
                "the node does not say whether it still runs (an older SNR), so it may "
                "have left the system or be busy"
            )
        return (
            f"no reply within {timeout_s:g} s: {why}. Ask it alone (`python -m snr console "
            f"--zenoh {self.system} {role}`) or give a longer --timeout."
        )

    def _ask_alive(self, timeout_s: float) -> Any:
        """Ask which consoles the role matches are alive now; read with `_alive_roles`."""
        key = console_key(self.system, self.role)
        return self.session.liveliness().get(key, timeout=timeout_s)

    @staticmethod
    def _alive_roles(pending: Any) -> Set[str]:
        """The roles whose console's liveliness token answered ``pending`` (a Zenoh get)."""
        samples = [answer.ok for answer in pending if answer.ok is not None]
        return {str(sample.key_expr).rsplit("/", 1)[-1] for sample in samples}

    def _not_sent(self, command: str) -> str:
        """Why ``command`` is not sent to every node, and what to type instead."""
        if command in _ONE_NODE_STREAMS:
            what, name = "streams from one node", "Name the node to stream from"
        elif command in COMMANDS:
            what, name = "changes a node", "Name the node"
        else:
            return f"Not sent: `{command}` is not a console command; `help` lists them."
        return (
            f"Not sent: `{command}` {what}, and role {self.role!r} reaches every node of "
            f"system {self.system!r}. {name}: `python -m snr console --zenoh {self.system} "
            f"ROLE` (or ZenohConsole({self.system!r}, ROLE)). To every node this console "
            f"sends only {', '.join(EVERY_NODE_COMMANDS)}."
        )

    def _greetings(self, timeout_s: float, role: str = "") -> Dict[str, Reply]:
        """Each node's greeting, by role; asked again until one answers or ``timeout_s`` ends.

        A query sent before the session has met the node's ends at once with
        no reply: a greeting (which changes nothing) may be asked again.
        """
        deadline = time.monotonic() + timeout_s
        while True:
            by_role = self._answers("", max(0.1, deadline - time.monotonic()), role)
            if by_role or time.monotonic() >= deadline:
                return by_role
            time.sleep(0.05)

    def _answers(self, line: str, timeout_s: float, role: str = "") -> Dict[str, Reply]:
        """One query for ``line`` (to ``role``, else the console's role): the replies, by role."""
        by_role = {}
        key = console_key(self.system, role or self.role)
        for answer in self._replies(key, line, timeout_s):
            replies = ReplyDecoder().feed(answer.payload.to_bytes())
            if replies:
                by_role[str(answer.key_expr).rsplit("/", 1)[-1]] = replies[0]
        return by_role

    def _nobody_answered(self, timeout_s: float) -> ConsoleConnectionError:
        return ConsoleConnectionError(
            f"No node {self.role!r} of system {self.system!r} answered within {timeout_s:g} s. "
            "Is it running with a ZenohConsoleFactory, on the same network (or the same "
            "connect endpoints)? `python -m snr console --zenoh SYSTEM` lists the roles "
            "that answer."
        )

    def _replies(self, key: str, line: str, timeout_s: float) -> List[Any]:
        token = self.token.encode("utf-8") if self.token else None
        answers = self.session.get(
            key, payload=line.encode("utf-8"), attachment=token, timeout=timeout_s
        )
        return [reply.ok for reply in answers if reply.ok is not None]

    def close(self) -> None:
        """Close the Zenoh session (the node keeps running). Safe to call twice."""
        session, self.session = self.session, None
        if session is not None:
            session.close()

    def is_connected(self) -> bool:
        """True until closed, or the node said bye."""
        return self.session is not None

    @classmethod
    def add_arguments(cls, parser: argparse.ArgumentParser, prog: str) -> None:
        """``--zenoh SYSTEM [ROLE]`` and the Zenoh session's options (for ``snr-console``)."""
        parser.description = "Type commands into a node of a system, found by its role over Zenoh."
        parser.add_argument("--zenoh", metavar="SYSTEM", required=True, help="the system's name")
        parser.add_argument(
            "role",
            nargs="?",
            help="the node's role (leave out to list the roles; with -c, read-only commands "
            "then go to every node)",
        )
        parser.add_argument(
            "--connect",
            action="append",
            default=[],
            metavar="ENDPOINT",
            help="a Zenoh endpoint to connect to, e.g. tcp/192.168.1.10:7447",
        )
        parser.add_argument(
            "--listen",
            action="append",
            default=[],
            metavar="ENDPOINT",
            help="a Zenoh endpoint to listen on, e.g. tcp/0.0.0.0:7447",
        )
        parser.add_argument(
            "--no-scouting",
            action="store_true",
            help="do not look for peers by multicast (give --connect instead)",
        )
        parser.add_argument(
            "--mode",
            default="peer",
            choices=["peer", "client"],
            help="peer (the default) or client, through a zenohd router given with --connect",
        )

    @classmethod
    def from_arguments(cls, args: argparse.Namespace) -> ZenohConsole:
        """The console ``--zenoh SYSTEM [ROLE]`` describes; with no role, every node.

        Raises:
            ConfigError: no zenoh library, or an endpoint Zenoh refuses.
        """
        console = cls(
            args.zenoh,
            args.role or "*",
            mode=args.mode,
            connect=args.connect,
            listen=args.listen,
            scouting=not args.no_scouting,
            token=args.token,
            timeout_s=args.timeout,
        )
        console._lists_roles = args.role is None
        return console

    def run(
        self,
        commands: Sequence[str] = (),
        stdin: Optional[IO[str]] = None,
        out: Optional[IO[str]] = None,
        err: Optional[IO[str]] = None,
        prog: str = "snr-console",
    ) -> int:
        """As `ConsoleClient.run`; from ``--zenoh SYSTEM`` alone, list the roles that answer."""
        if not self._lists_roles or commands:
            return super().run(commands, stdin, out, err, prog)
        try:
            roles = self.roles(min(self.timeout_s, 2.0))
        finally:
            self.close()
        found = ", ".join(roles) or "none"
        say(out or sys.stdout, f"Nodes of system {self.system!r} with a Zenoh console: {found}")
        return EXIT_OK if roles else EXIT_CONNECTION


def _labelled(by_role: Dict[str, Reply], notes: Optional[Dict[str, str]] = None) -> Reply:
    """One reply from several nodes' replies: each under its role; an error if any was one.

    ``notes`` are lines about nodes with no reply of their own (they refused
    the console, or left the system): shown under their roles, but they do
    not make the reply an error, as no command failed on them. With no reply
    at all, only notes, the reply is an error: the command reached no node.

    Example::

        _labelled({"urov": Reply(Status.OK, "pong")}).text   # '[urov] pong'
    """
    texts = {role: reply.text for role, reply in by_role.items()}
    texts.update(notes or {})
    parts = []
    for role, text in sorted(texts.items()):
        parts.append(f"[{role}]" + ("\n" if "\n" in text else " ") + text)
    statuses = {reply.status for reply in by_role.values()}
    status = next(iter(statuses)) if len(statuses) == 1 else Status.ERROR
    return Reply(status, "\n".join(parts))


def _refusal(text: str) -> str:
    """How a node's refusal of the console reads under its role, with what to do about it.

    Example::

        _refusal("This node needs its console token.")
        # 'refused: this node needs its console token (give it: --token,
        #  SNR_CONSOLE_TOKEN, or the node's $SNR_SECRET)'
    """
    why = text.rstrip(".")
    hint = f" (give it: --token, {TOKEN_ENV_VAR}, or the node's $SNR_SECRET)"
    hint = hint if "token" in why else ""
    return f"refused: {why[:1].lower()}{why[1:]}{hint}"
