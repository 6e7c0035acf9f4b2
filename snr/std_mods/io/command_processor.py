"""The console's commands: their registry, `COMMANDS`, and `CommandProcessorEndpoint`.

A console (remote over TCP, local on stdin, or over Zenoh) never touches the
node itself: it turns each line the user typed into a command task, and this
endpoint runs the command in a task handler, on the node's thread, then hands
the reply to the console's `ConsoleSession` (thesis 6.4.3).

A command is a name, a help line and a function: `command` registers one in
`COMMANDS`. The kernel's commands are registered here; extras register theirs
the same way, in the modules the entry point group ``snr.console_commands``
names (step mode's, ``echo``, ``hz``, ``graph``), which `load_extra_commands`
loads when a console starts.

Example::

    COMMANDS["dump"].usage                 # 'dump profiler|datastore [KEY|PREFIX*]'
    processor.execute("task event beep")   # Reply(Status.OK, "Scheduled ...")
"""

from __future__ import annotations

import logging
import reprlib
import time
from dataclasses import dataclass
from typing import Any, Callable, Dict, List, Mapping, Optional, Sequence, Tuple, Union

from snr.core import Endpoint, EndpointFactory, Node, ThreadLoop, plugins, tasks
from snr.core.checks.error_text import closest_match, did_you_mean
from snr.core.components import NODE_CORE_NAME
from snr.core.logs import RepeatFilter
from snr.prelude import (
    AbstractComponent,
    AbstractNode,
    ComponentName,
    ConfigError,
    DataKey,
    Page,
    SomeTasks,
    Task,
    TaskId,
    TaskName,
    TaskType,
)
from snr.prelude.task import format_task
from snr.std_mods.comms.comms_loop import CommsLoop
from snr.std_mods.io.console_protocol import ConsoleSession, Reply, Status, parse_values

__all__ = [
    "COMMANDS",
    "REPLY_BUDGET_CHARS",
    "REPLY_BUDGET_S",
    "Answer",
    "CommandFailed",
    "CommandHelp",
    "CommandProcessorEndpoint",
    "CommandProcessorFactory",
    "command",
    "commands_table",
    "load_extra_commands",
    "no_arguments",
    "number_argument",
    "one_choice",
    "preview",
]

REPLY_BUDGET_CHARS = 64 * 1024
"""Longest reply a console command builds; a longer one is cut with a note.

Example::

    len(processor.execute("dump datastore").text) <= REPLY_BUDGET_CHARS + 400   # True
"""

REPLY_BUDGET_S = 0.01
"""Node-thread time a listing (``dump datastore``) may take, after its first 50 keys.

Example::

    REPLY_BUDGET_S * 1000   # 10.0 ms
"""

_MIN_LINES = 50  # a listing shows this many keys however slow the node is (each is cheap)
_PREVIEW_CHARS = 120


class _ValueRepr(reprlib.Repr):
    """`reprlib.Repr` that shortens read-only page data (DEBUG, TEST) as the list or dict it is."""

    def __init__(self, chars: int, levels: int, items: int) -> None:
        super().__init__()
        self.maxstring = self.maxother = chars
        self.maxlevel = levels
        self.maxlist = self.maxtuple = self.maxdict = self.maxset = items

    def repr_ReadOnlyList(self, value: List[Any], level: int) -> str:  # reprlib names it so
        return self.repr_list(value, level)

    def repr_ReadOnlyDict(self, value: Dict[Any, Any], level: int) -> str:
        return self.repr_dict(value, level)


_previews = _ValueRepr(_PREVIEW_CHARS, 3, 12)  # a short preview, cheap even for a huge value
_whole_values = _ValueRepr(REPLY_BUDGET_CHARS, 8, 2000)  # one value in full, up to a reply

Answer = Union[str, Reply, None]
"""What a command returns: the text of an OK reply, a reply, or None: it replies later."""
_Run = Callable[["CommandProcessorEndpoint", str], Answer]  # a command's function
_ReplyAfter = Callable[[List[str]], float]  # the words after its name -> seconds its reply may take


@dataclass(frozen=True)
class CommandHelp:
    """One console command: how to type it, what it does (for ``help``), and what runs it.

    ``run(processor, args)`` runs on the node's thread with the words typed
    after the command's name, and returns an `Answer`. ``reply_after_s(words)``,
    if given, is how many seconds the reply to those words may take on top of
    a console's timeout (``hz``'s window): consoles, which share this
    registry, wait that much longer for it.

    Example::

        CommandHelp("exit", "Stop the node and close this console.")
    """

    usage: str
    summary: str
    details: str = ""
    run: Optional[_Run] = None
    reply_after_s: Optional[_ReplyAfter] = None


COMMANDS: Dict[str, CommandHelp] = {}
"""Every console command by name, in the order ``help`` lists them (see `command`)."""


def command(
    usage: str, summary: str, details: str = "", reply_after_s: Optional[_ReplyAfter] = None
) -> Callable[[_Run], _Run]:
    """Register the decorated function as the console command named by ``usage``'s first word.

    The one way to add a command, for the kernel's and for an extra's: raise
    `CommandFailed` for a reply that says what is wrong; set
    ``processor.follow_up`` to the tasks the command asks for. A command that
    replies after a while gives ``reply_after_s``: from the words typed after
    its name, the seconds its reply may take beyond a console's timeout.

    Example::

        @command("ping", "Answer pong.")
        def ping(processor: CommandProcessorEndpoint, args: str) -> Answer:
            return "pong"

        @command("hz KEY", "Count KEY's pages for 2 s.", reply_after_s=lambda words: 2.0)
        def hz(processor: CommandProcessorEndpoint, args: str) -> Answer:
            ...   # the reply is sent 2 s later; a console waits its timeout + 2 s
    """

    def register(run: _Run) -> _Run:
        COMMANDS[usage.split()[0]] = CommandHelp(usage, summary, details, run, reply_after_s)
        if "help" in COMMANDS:  # `help` stays last
            COMMANDS["help"] = COMMANDS.pop("help")
        return run

    return register


_extras_loaded = False


def load_extra_commands() -> None:
    """Register the commands of every extra named in the entry point group ``snr.console_commands``.

    Safe to call again; an extra that cannot be imported is skipped (its
    commands stay unknown). Consoles call it when they start.

    Example::

        load_extra_commands()
        "echo" in COMMANDS   # True
    """
    global _extras_loaded
    if _extras_loaded:
        return
    _extras_loaded = True
    for name in plugins.names("snr.console_commands"):
        try:
            plugins.load("snr.console_commands", name, "The console")
        except ConfigError as error:
            logging.getLogger("snr").warning("Console commands %r not loaded: %s", name, error)


def commands_table() -> str:
    """Every command's usage and summary, one aligned line each (``help``, ``list commands``).

    Example::

        print(commands_table())   #   exit    Stop the node and close this console. ...
    """
    width = max(len(entry.usage) for entry in COMMANDS.values())
    return "\n".join(f"  {e.usage:<{width}}  {e.summary}" for e in COMMANDS.values())


class CommandFailed(Exception):
    """A command cannot run as typed; the message is the (error) reply.

    Example::

        raise CommandFailed("'pause' takes no arguments; got 'now'.")
    """


# Why `check_protected` refuses, by (what the component is, the action).
_REFUSALS = {
    ("core", "remove"): "Refused: {} is the node's own core. It stores every page, adds, "
    "removes and reloads components, and stops the node on `exit`; without it the node "
    "would run on deaf. To stop the node, type `exit`.",
    ("core", "reload"): "Refused: {} is the node's own core and runs every reload itself; "
    "SNR's own code is not reloaded while the node runs. Restart the node to load a new SNR.",
    ("console", "remove"): "Refused: {} is part of a console; removing it would cut off the "
    "consoles that use it, maybe this one. Type `quit` to leave this console, or `exit` to "
    "stop the node.",
    ("console", "reload"): "{} is part of the console, which cannot reload itself while it "
    "carries this command. Restart the node to load new console code.",
}


class CommandProcessorEndpoint(Endpoint):
    """Runs console command lines in a task handler and replies to the console.

    Its consoles schedule ``Task(TaskType.event, <its task name>, [line,
    session])``; you do not build it yourself: `CommandReceiverFactory` and
    `LocalConsoleFactory` add one to the node. A failing command is reported
    to the console and logged; it never stops the node.

    Attributes:
        session: the console of the command being run (None in `execute`).
        follow_up: the tasks the command being run asks for.
        state: what commands keep between lines, by name; a value with a
            ``close()`` is closed when the node stops.

    Example::

        processor.execute("task event beep")   # Reply(Status.OK, "Scheduled ...")
    """

    # For the graph: a console stores only what its user types (`task store_page ...`).
    produces: Sequence[DataKey] = ()
    reads: Sequence[DataKey] = ()

    def __init__(
        self, factory: CommandProcessorFactory, parent: AbstractNode, task_name: TaskName
    ) -> None:
        super().__init__(factory, parent, factory.name)
        load_extra_commands()
        self.console_name = factory.console
        self.task_name = task_name
        self.task_handlers = {(TaskType.event, task_name): self.on_command}
        self.session: Optional[ConsoleSession] = None
        self.follow_up: SomeTasks = None
        self.state: Dict[str, Any] = {}
        self._refusals = RepeatFilter(self.log)

    def on_command(self, task: Task, key: TaskId) -> SomeTasks:
        """Run the command line in the task and send the reply to its session."""
        if len(task.val_list) != 2 or not isinstance(task.val_list[1], ConsoleSession):
            self.warn(
                "Dropped a console command task with values %r: expected [line, session]. "
                "Consoles build these tasks; to run a command yourself, type it in "
                "snr-console.",
                task.val_list,
            )
            return None
        line, session = task.val_list
        self.session = session
        try:
            reply, follow_up = self._run(str(line))
        finally:
            self.session = None
        if reply is not None:
            session.send(reply)
        return follow_up

    def terminate(self) -> None:
        """Close what the commands keep (e.g. the timer of open ``echo``/``hz`` watches)."""
        for kept in self.state.values():
            if callable(getattr(kept, "close", None)):
                kept.close()

    def execute(self, line: str) -> Reply:
        """Run one command line now and return the reply (on the node's thread).

        Tasks the command asks for (e.g. ``task event go``) are scheduled.
        """
        reply, follow_up = self._run(line)
        self.schedule(follow_up)
        return reply or Reply(Status.OK, "")

    def _run(self, line: str) -> Tuple[Optional[Reply], SomeTasks]:
        """The reply to ``line`` (None: it comes later), and the tasks it asks for."""
        word, *args = line.split(None, 1) or [""]
        word = word.lower()
        if not word:
            return Reply(Status.OK, ""), None
        entry = COMMANDS.get(word)
        if entry is None or entry.run is None:
            hint = did_you_mean(word, COMMANDS)
            text = f"Unknown command {word!r}.{hint} Type 'help' to see the commands."
            return Reply(Status.ERROR, text), None
        self.follow_up = None
        try:
            answer = entry.run(self, "".join(args).strip())
        except CommandFailed as refused:
            answer = Reply(Status.ERROR, str(refused))
        except Exception as error:  # a broken command must not stop the robot
            self.log.exception("Console command %r failed", line)
            answer = Reply(
                Status.ERROR,
                f"{word!r} failed inside the node: {type(error).__name__}: {error}. "
                "The node keeps running; its log has the details.",
            )
        if isinstance(answer, str):
            answer = Reply(Status.OK, answer)
        if answer is not None and len(answer.text) > REPLY_BUDGET_CHARS:
            cut = len(answer.text) - REPLY_BUDGET_CHARS
            answer = Reply(
                answer.status,
                answer.text[:REPLY_BUDGET_CHARS]
                + f"\n... (reply cut: {cut:,} more characters; ask for "
                "less, e.g. `dump datastore KEY` for one key)",
            )
        return answer, self.follow_up

    def full_node(self, command: str) -> Node:
        """The node, if it is a running `snr.Node` (a command needs its queue or datastore).

        Raises:
            CommandFailed: the parent is another kind of node (e.g. a mock).

        Example::

            processor.full_node("stats").queue
        """
        if not isinstance(self.parent, Node):
            raise CommandFailed(
                f"{command!r} needs a running snr.Node; this component's parent is a "
                f"{type(self.parent).__name__}."
            )
        return self.parent

    def check_protected(self, node: AbstractNode, name: ComponentName, action: str) -> None:
        """Refuse to ``action`` ("remove" or "reload") the node's core or a console part.

        The refusal is the reply, and it is logged (repeats are counted, not repeated).
        """
        component = node.components.get(name)
        if name == NODE_CORE_NAME:
            kind = "core"
        elif component is None and action == "reload":
            hint = did_you_mean(name, node.components)
            raise CommandFailed(
                f"No component named {name!r} in node {node.role!r}.{hint} "
                f"Components: {', '.join(self.parent.components)}."
            )
        elif component is not None and _is_console_part(component, self.parent):
            kind = "console"
        else:
            return
        reason = _REFUSALS[kind, action].format(repr(name))
        self._refusals.report(
            ("refused", reason[:60]),
            "Refused console commands",
            logging.WARNING,
            "Console %s: %s",
            self.session or "console",
            reason,
        )
        raise CommandFailed(reason)


class CommandProcessorFactory(EndpointFactory):
    """Builds a `CommandProcessorEndpoint` (consoles add one for themselves).

    Args:
        name: the endpoint's name.
        task_name: the name of the command tasks it handles.
        console: the name of the console loop it serves, if any; the
            console refuses to remove or reload that loop (or itself).

    Example::

        tasks.add_component(CommandProcessorFactory("console_commands", "console:console"))
    """

    def __init__(
        self, name: ComponentName, task_name: TaskName, console: Optional[ComponentName] = None
    ) -> None:
        super().__init__()
        self.name = name
        self.task_name = task_name
        self.console = console

    def get(self, parent: AbstractNode) -> CommandProcessorEndpoint:
        return CommandProcessorEndpoint(self, parent, self.task_name)


# -- the kernel's commands, in the order `help` lists them -------------------------
@command("exit", "Stop the node and close this console.")
def _exit(p: CommandProcessorEndpoint, args: str) -> Answer:
    no_arguments("exit", args)
    p.follow_up = tasks.terminate(f"exit command from {p.session or 'console'}")
    return Reply(Status.BYE, f"Stopping node {p.parent.role!r}. Bye.")


@command(
    "task <type> <name> [values...]",
    "Schedule a task on the node.",
    "Types: event, store_page (alias store_data), process_data, reload, terminate.\n"
    'Values are JSON where they parse (1, 2.5, true, null, "two words", [1, 2],\n'
    '{"k": 1}), otherwise plain words (A, hello). Examples:\n'
    "  task event button_pressed A\n"
    "  task store_page depth_m 3.2\n"
    "  task terminate done",
)
def _task(p: CommandProcessorEndpoint, args: str) -> Answer:
    words = args.split(None, 2)
    types = ", ".join(TaskType.__members__)
    if len(words) < 2:
        raise CommandFailed(
            f"Usage: {COMMANDS['task'].usage}, e.g. `task event button_pressed A`. Types: {types}."
        )
    type_word, name, rest = words[0], words[1], words[2] if len(words) == 3 else ""
    task_type = TaskType.__members__.get(type_word.lower())
    if task_type is None:
        hint = did_you_mean(type_word.lower(), TaskType.__members__)
        raise CommandFailed(f"Unknown task type {type_word!r}.{hint} Types: {types}.")
    values = parse_values(rest)
    if task_type is TaskType.terminate:
        task = tasks.terminate(f"{name} {rest}".strip())
    elif task_type is TaskType.reload:
        if name != "all":
            p.check_protected(p.full_node("task reload"), name, "reload")
        task = tasks.reload_component(name)
    elif task_type is TaskType.event:
        for target in values if name == tasks.REMOVE_COMPONENT else ():
            p.check_protected(p.parent, str(target), "remove")
        task = tasks.event(name, values)
    elif len(values) != 1:
        raise CommandFailed(
            f"`task {type_word} {name}` needs exactly one value (the data), got "
            f"{len(values)}. Write e.g. `task {type_word} {name} 3.2`, or "
            f"`task {type_word} {name} [1, 2]` for a list."
        )
    elif task_type is TaskType.store_page:
        task = tasks.store_data(name, values[0])
    else:
        task = tasks.process_data(p.parent.page(name, values[0]))
    p.follow_up = task
    return f"Scheduled {format_task(task, values='data')}"


@command(
    "reload all|<component>",
    "Reload a component's code from disk; its factory's state is kept.",
    "`reload all` reloads every component whose factory names modules to reload\n"
    "(super().__init__(my_module)). If the new code fails to load (a syntax error,\n"
    "an exception), the old version keeps running and the reply says why.",
)
def _reload(p: CommandProcessorEndpoint, args: str) -> Answer:
    if not args or len(args.split()) != 1:
        raise CommandFailed(
            f"Usage: {COMMANDS['reload'].usage}. Components: {', '.join(p.parent.components)}."
        )
    node = p.full_node("reload")
    if args != "all":
        p.check_protected(node, args, "reload")
        ok, text = _reload_one(node, args)
        return Reply(Status.OK if ok else Status.ERROR, text)
    names = [
        name
        for name, component in node.components.items()
        if component.factory.reload_targets and not _is_console_part(component, node)
    ]
    if not names:
        return (
            "Nothing to reload: no component's factory names modules to reload. "
            "Pass the module to the factory, e.g. `super().__init__(my_module)`."
        )
    results = [_reload_one(node, name) for name in names]
    failed = sum(not ok for ok, _ in results)
    text = results[0][1]
    if len(results) > 1:
        text = f"Reloaded {len(results) - failed} of {len(results)} components:\n"
        text += "\n".join("  " + message for _, message in results)
    return Reply(Status.ERROR if failed else Status.OK, text)


def _reload_one(node: Node, name: ComponentName) -> Tuple[bool, str]:
    has_modules = bool(node.components[name].factory.reload_targets)
    errors = _ErrorCollector()  # the node logs why a reload failed: quote it back
    node.log.addHandler(errors)
    try:
        rebuilt = node.reload_component(name)
    finally:
        node.log.removeHandler(errors)
    if not rebuilt:
        return False, "\n".join(errors.messages) or (
            f"Reloading {name!r} failed, so the old version keeps running. The node's log says why."
        )
    if not has_modules:
        return True, (
            f"Rebuilt {name!r} from its factory, but the factory names no modules to "
            "reload, so the code is unchanged. To hot-reload it, pass its module to the "
            "factory: `super().__init__(my_module)`."
        )
    return True, f"Reloaded {name!r}; its factory (and the state it keeps) is the same."


@command("list commands|endpoints", "List these commands, or the node's components.")
def _list(p: CommandProcessorEndpoint, args: str) -> Answer:
    if one_choice("list", args, ["commands", "endpoints"]) == "commands":
        return commands_table()
    components = p.parent.components
    lines = [f"Components of node {p.parent.role!r} ({len(components)}):"]
    width = max(map(len, components), default=0)
    for name, component in components.items():
        kind, state = "endpoint", ""
        if isinstance(component, ThreadLoop):
            kind, state = "loop    ", f" ({component.state.value})"
        line = f"  {name:<{width}}  {kind}  {type(component).__name__}{state}"
        modules = [m.__name__ for m in component.factory.reload_targets]
        lines.append(line + (f"  reloads: {', '.join(modules)}" if modules else ""))
    return "\n".join(lines)


@command(
    "dump profiler|datastore [KEY|PREFIX*]",
    "Show handler timings, or the newest page of every key.",
    "`dump datastore` shows every key with a short preview of its value, up to the\n"
    "reply's limit. `dump datastore KEY` shows one key's value in full;\n"
    "`dump datastore PREFIX*` shows the keys that start with PREFIX.",
)
def _dump(p: CommandProcessorEndpoint, args: str) -> Answer:
    words = args.split()
    choice = one_choice("dump", words[0] if words else "", ["profiler", "datastore"])
    if len(words) > (1 if choice == "profiler" else 2):
        raise CommandFailed(f"Usage: {COMMANDS['dump'].usage}.")
    role, profiler = p.parent.role, p.parent.profiler
    if choice == "profiler":
        return (
            profiler.dump()
            if profiler is not None
            else (
                f"Profiling is off for node {role!r}. Turn it on with "
                "Config(..., profile=True); it is on by default in Mode.DEBUG."
            )
        )
    datastore = p.full_node("dump datastore").datastore
    key = words[1] if len(words) == 2 else "*"
    if key.endswith("*"):
        return _list_datastore(role, datastore, key[:-1])
    page = datastore.get(key)
    if page is None:
        raise CommandFailed(
            f"Node {role!r} has no data under {key!r}.{did_you_mean(key, datastore)} "
            "`dump datastore` lists the keys."
        )
    head = f"{key} (from {page.origin!r}, {max(0.0, time.time() - page.created_at_s):.1f} s ago) = "
    text = _whole_values.repr(page.data)
    data: Any = page.data
    cut_items = isinstance(data, (list, tuple, dict, set, frozenset)) and (
        len(data) > _whole_values.maxlist
    )
    if cut_items or len(head) + len(text) > REPLY_BUDGET_CHARS:
        text = text[: REPLY_BUDGET_CHARS - len(head)] + (
            f"\n... (cut: the value is longer than a reply may carry, "
            f"{REPLY_BUDGET_CHARS:,} characters or {_whole_values.maxlist:,} items; "
            f"read it in code with node.get_data({key!r}))"
        )
    return head + text


@command(
    "stats",
    "Show the node's queue and every comms link: pages sent, received, dropped.",
    "Dropped pages are counted per link and per key (a slow peer whose backlog was\n"
    "full); 'heard' is how long ago the peer last sent anything (a beat at least).",
)
def _stats(p: CommandProcessorEndpoint, args: str) -> Answer:
    node = p.full_node("stats")
    queue = node.queue
    lines = [
        f"Queue of node {node.role!r}: {len(queue)} tasks waiting (high-water mark "
        f"{queue.high_water:,}); loops waited for room {queue.waits} times; "
        f"{queue.loss.total} tasks dropped."
    ]
    if node.step_mode.paused:
        waits, dropped = node.step_mode.since_pause()
        lines.append(
            f"The node is paused. Since the pause, loops waited for room in the queue "
            f"{waits:,} times and {dropped:,} of their tasks were dropped."
        )
    comms = [c for c in node.components.values() if isinstance(c, CommsLoop)]
    lines += [f"{loop.name}: {loop.stats_text()}" for loop in comms] or ["No comms links."]
    return "\n".join(lines)


@command("help [command]", "Show the commands, or one command in detail.")
def _help(p: CommandProcessorEndpoint, args: str) -> Answer:
    topic = args.lower()
    if not topic:
        return "Commands (type `help <command>` for details):\n" + commands_table()
    entry = COMMANDS.get(topic)
    if entry is None:
        hint = did_you_mean(topic, COMMANDS)
        raise CommandFailed(
            f"There is no command {topic!r}.{hint} Commands: {', '.join(COMMANDS)}."
        )
    return "\n  ".join([entry.usage, entry.summary, *entry.details.splitlines()])


# -- helpers ---------------------------------------------------------------------
def _is_console_part(component: AbstractComponent, node: AbstractNode) -> bool:
    """A command processor, or a console loop one of them serves."""
    return isinstance(component, CommandProcessorEndpoint) or any(
        isinstance(other, CommandProcessorEndpoint) and other.console_name == component.name
        for other in list(node.components.values())
    )


def no_arguments(command: str, args: str) -> None:
    """Refuse a command typed with words after it.

    Raises:
        CommandFailed: ``args`` is not blank.

    Example::

        no_arguments("pause", "")   # fine; no_arguments("pause", "now") raises
    """
    if args.strip():
        raise CommandFailed(f"{command!r} takes no arguments; got {args.strip()!r}.")


def one_choice(command: str, args: str, choices: List[str]) -> str:
    """``args`` if it is one of ``choices`` (lower-cased).

    Raises:
        CommandFailed: it is not, with the closest choice and the usage.

    Example::

        one_choice("graph", "dot", ["text", "mermaid", "dot"])   # 'dot'
    """
    choice = args.strip().lower()
    if choice in choices:
        return choice
    usage = f"Usage: {command} {'|'.join(choices)}."
    if not choice:
        raise CommandFailed(usage)
    guess = closest_match(choice, choices)
    hint = f" Did you mean `{command} {guess}`?" if guess else ""
    raise CommandFailed(f"{command!r} cannot show {choice!r}.{hint} {usage}")


def number_argument(
    word: str, command: str, name: str, low: float, high: float, kind: type
) -> float:
    """``word`` as a number of ``kind`` from ``low`` to ``high``.

    Raises:
        CommandFailed: it is not, with the command's usage.

    Example::

        number_argument("5", "step", "N", 1, 100, int)   # 5.0
    """
    try:
        value = float(kind(word))
    except ValueError:
        value = float("nan")  # fails the range check below
    if not low <= value <= high:
        raise CommandFailed(
            f"`{command}` takes {name} from {low:g} to {high:g}; got {word!r}. "
            f"Usage: {COMMANDS[command].usage}."
        )
    return value


def preview(data: Any) -> str:
    """A short repr of a page's data: cheap even for a huge value (reprlib stops early).

    Example::

        preview(list(range(1000)))   # '[0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, ...]'
    """
    text = _previews.repr(data)
    return text if len(text) <= _PREVIEW_CHARS else text[: _PREVIEW_CHARS - 3] + "..."


def _list_datastore(role: str, datastore: Mapping[str, Page], prefix: str) -> str:
    """Every key (starting with ``prefix``) and a preview, within the reply's budgets."""
    started = time.perf_counter()
    keys = sorted(key for key in list(datastore) if key.startswith(prefix))
    where = f" starting with {prefix!r}" if prefix else ""
    if not keys:
        return f"The datastore of node {role!r} has no keys{where}."
    now = time.time()
    width = min(max(map(len, keys)), 40)
    lines = [f"Datastore of node {role!r} ({len(keys):,} key{'s' * (len(keys) != 1)}{where}):"]
    size = len(lines[0])
    for shown, key in enumerate(keys):
        page = datastore.get(key)
        if page is None:
            continue  # removed since the keys were listed
        line = (
            f"  {key:<{width}} = {preview(page.data)}  "
            f"(from {page.origin!r}, {max(0.0, now - page.created_at_s):.1f} s ago)"
        )
        size += len(line) + 1
        over_time = shown >= _MIN_LINES and time.perf_counter() - started > REPLY_BUDGET_S
        if size > REPLY_BUDGET_CHARS - 400 or over_time:
            limit = (
                f"{REPLY_BUDGET_S * 1000:g} ms of the node's time"
                if over_time
                else f"{REPLY_BUDGET_CHARS:,} characters"
            )
            lines.append(
                f"... and {len(keys) - shown:,} more keys not shown, from {key!r} on (a "
                f"listing stops at {limit}). Show one key in full with `dump datastore "
                "KEY`, or the keys that start with a prefix with `dump datastore PREFIX*`."
            )
            break
        lines.append(line)
    return "\n".join(lines)


class _ErrorCollector(logging.Handler):
    """Keeps the error messages of a logger (and its children) while it is added to it."""

    snr_only_listens = True  # SNR's stderr handler still prints what this collects

    def __init__(self) -> None:
        super().__init__(logging.ERROR)
        self.messages: List[str] = []

    def emit(self, record: logging.LogRecord) -> None:
        self.messages.append(record.getMessage())
