"""The console's commands: their table, `COMMANDS`, and `CommandProcessorEndpoint`, which runs them.

A console (remote over TCP, local on stdin, or over Zenoh) never touches the
node itself: it turns each line the user typed into a command task, and this
endpoint runs the command in a task handler, on the node's thread, then hands
the reply to the console's `ConsoleSession`. ``help`` and ``list commands``
print `COMMANDS`, `snr-console` completes command words from it, and the
method ``cmd_<word>`` runs each (thesis 6.4.3). ``echo KEY`` and ``hz KEY``,
like ``ros2 topic echo/hz``, are `KeyWatches`.

Example::

    COMMANDS["dump"].usage                 # 'dump profiler|datastore [KEY|PREFIX*]'
    processor.execute("task event beep")   # Reply(Status.OK, "Scheduled ...")
"""

from __future__ import annotations

import logging
import math
import reprlib
import threading
import time
from collections import deque
from dataclasses import dataclass, field
from typing import Any, Callable, Deque, Dict, List, Mapping, Optional, Sequence, Tuple, Union

from snr.core import Endpoint, EndpointFactory, Node, ThreadLoop, plugins, tasks
from snr.core.checks.error_text import closest_match, did_you_mean
from snr.core.checks.step_mode import MAX_STEPS, Step, console_priority
from snr.core.components import NODE_CORE_NAME
from snr.core.logs import RepeatFilter
from snr.prelude import (
    AbstractComponent,
    AbstractNode,
    ComponentName,
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
    "ECHO_DEFAULT_PAGES",
    "ECHO_MAX_PAGES",
    "HZ_DEFAULT_WINDOW_S",
    "HZ_MAX_WINDOW_S",
    "MAX_WATCHES",
    "REPLY_BUDGET_CHARS",
    "REPLY_BUDGET_S",
    "CommandHelp",
    "CommandProcessorEndpoint",
    "CommandProcessorFactory",
    "KeyWatches",
    "commands_table",
]

REPLY_BUDGET_CHARS = 64 * 1024
"""Longest reply a console command builds; a longer one is cut with a note.

The note says how to ask for the rest, e.g. ``dump datastore KEY``.

Example::

    len(processor.execute("dump datastore").text) <= REPLY_BUDGET_CHARS + 400   # True
"""

REPLY_BUDGET_S = 0.01
"""Node-thread time a listing (``dump datastore``) may take before it stops with a note.

Commands run on the node's thread, so a long listing would delay every task
behind it; the reply says what was left out and how to see it. The first 50
keys are always shown (each costs microseconds: values are previewed with
`reprlib`, which stops early).

Example::

    REPLY_BUDGET_S * 1000   # 10.0 ms
"""

ECHO_DEFAULT_PAGES = 20
"""Pages one ``echo KEY`` reply carries at most, unless it asks for another number."""

ECHO_MAX_PAGES = 100
"""The most pages one ``echo`` reply carries, and waits between two ``echo`` of a console."""

HZ_DEFAULT_WINDOW_S = 2.0
"""How long ``hz KEY`` counts pages when no window is given."""

HZ_MAX_WINDOW_S = 60.0
"""The longest window ``hz`` accepts (a reply waits that long)."""

MAX_WATCHES = 32
"""How many ``echo``/``hz`` may be open on one node at once; more are refused."""

_TICK_S = 0.05  # how often open watches check their time limits (a reply is at most this late)
_MIN_LINES = 50  # a listing shows this many keys however slow the node is (each is cheap)
_PREVIEW_CHARS = 120


class _ValueRepr(reprlib.Repr):
    """`reprlib.Repr` that shortens read-only page data (DEBUG, TEST) as the list or dict it is."""

    def repr_ReadOnlyList(self, value: List[Any], level: int) -> str:  # reprlib names it so
        return self.repr_list(value, level)

    def repr_ReadOnlyDict(self, value: Dict[Any, Any], level: int) -> str:
        return self.repr_dict(value, level)


_previews = _ValueRepr()  # a short preview of any value, cheap even for a huge one
_previews.maxstring = _previews.maxother = _PREVIEW_CHARS
_previews.maxlevel = 3
_previews.maxlist = _previews.maxtuple = _previews.maxdict = _previews.maxset = 12
_whole_values = _ValueRepr()  # one value in full, up to a reply's length
_whole_values.maxstring = _whole_values.maxother = REPLY_BUDGET_CHARS
_whole_values.maxlevel = 8
_whole_values.maxlist = _whole_values.maxtuple = _whole_values.maxdict = 2000
_whole_values.maxset = 2000


@dataclass(frozen=True)
class CommandHelp:
    """How to type one command, and what it does (for ``help``).

    Example::

        CommandHelp("exit", "Stop the node and close this console.")
    """

    usage: str
    summary: str
    details: str = ""


COMMANDS: Dict[str, CommandHelp] = {
    "exit": CommandHelp("exit", "Stop the node and close this console."),
    "task": CommandHelp(
        "task <type> <name> [values...]",
        "Schedule a task on the node.",
        "Types: event, store_page (alias store_data), process_data, reload, terminate.\n"
        'Values are JSON where they parse (1, 2.5, true, null, "two words", [1, 2],\n'
        '{"k": 1}), otherwise plain words (A, hello). Examples:\n'
        "  task event button_pressed A\n"
        "  task store_page depth_m 3.2\n"
        "  task terminate done",
    ),
    "reload": CommandHelp(
        "reload all|<component>",
        "Reload a component's code from disk; its factory's state is kept.",
        "`reload all` reloads every component whose factory names modules to reload\n"
        "(super().__init__(my_module)). If the new code fails to load (a syntax error,\n"
        "an exception), the old version keeps running and the reply says why.",
    ),
    "list": CommandHelp(
        "list commands|endpoints", "List these commands, or the node's components."
    ),
    "dump": CommandHelp(
        "dump profiler|datastore [KEY|PREFIX*]",
        "Show handler timings, or the newest page of every key.",
        "`dump datastore` shows every key with a short preview of its value, up to the\n"
        "reply's limit. `dump datastore KEY` shows one key's value in full;\n"
        "`dump datastore PREFIX*` shows the keys that start with PREFIX.",
    ),
    "stats": CommandHelp(
        "stats",
        "Show the node's queue and every comms link: pages sent, received, dropped.",
        "Dropped pages are counted per link and per key (a slow peer whose backlog was\n"
        "full); 'heard' is how long ago the peer last sent anything (a beat at least).",
    ),
    "graph": CommandHelp(
        "graph [text|mermaid|dot]",
        "Show the node's components, the data keys each stores and handles, and its links.",
        "`text` (the default) is for reading here; `mermaid` can be pasted into a\n"
        "Markdown file (GitHub draws it), `dot` into Graphviz. Keys read but never\n"
        "stored, or stored but never read, are marked (!). `python -m snr graph main.py`\n"
        "draws the whole system without running it.",
    ),
    "echo": CommandHelp(
        "echo KEY [N]",
        "Show the next pages stored under KEY (snr-console repeats it until Ctrl-C).",
        f"One reply carries at most N pages (default {ECHO_DEFAULT_PAGES}, at most "
        f"{ECHO_MAX_PAGES}): it comes\nwhen N pages have come, a quarter second after the "
        "first, or after 1 s\nwithout one. Pages that come between two `echo KEY` wait "
        "for the next one,\nso repeating it shows every page.",
    ),
    "hz": CommandHelp(
        "hz KEY [WINDOW_S]",
        "Measure how often KEY is stored, and the jitter of the time between pages.",
        f"Counts pages for WINDOW_S seconds (default {HZ_DEFAULT_WINDOW_S:g}, at most "
        f"{HZ_MAX_WINDOW_S:g}), then replies with\nthe rate and the period's mean, min, max "
        "and standard deviation, timed when\nthis node stores each page.",
    ),
    "pause": CommandHelp(
        "pause",
        "Pause the node: it runs no task but the console's until `step` or `resume`.",
        "The node finishes the task it is running, then holds every other task in its\n"
        "queue, in order. dump, list, stats, graph and exit keep working. Loops keep\n"
        "running: their pages wait in the queue (a full queue makes them wait, then\n"
        "drops and counts their pages; the replies say how many).",
    ),
    "step": CommandHelp(
        "step [N]",
        "Run the next task (or N, at most 100) of a paused node and show what it did.",
        "For each task: which task ran, the handlers it went to, what they returned;\n"
        "then what waits next in the queue.",
    ),
    "resume": CommandHelp("resume", "Let a paused node run freely again."),
    "help": CommandHelp("help [command]", "Show the commands, or one command in detail."),
}
"""Every console command, in the order ``help`` lists them."""


def commands_table() -> str:
    """Every command's usage and summary, one aligned line each (``help``, ``list commands``).

    Example::

        print(commands_table())   #   exit    Stop the node and close this console. ...
    """
    width = max(len(entry.usage) for entry in COMMANDS.values())
    return "\n".join(f"  {e.usage:<{width}}  {e.summary}" for e in COMMANDS.values())


class _CommandFailed(Exception):
    """A command cannot run as typed; the message is the reply."""


# What a command returns: the text of an OK reply, a reply, or None: it replies later.
_Answer = Union[str, Reply, None]


class CommandProcessorEndpoint(Endpoint):
    """Runs console command lines in a task handler and replies to the console.

    Its consoles schedule ``Task(TaskType.event, <its task name>, [line,
    session])``; you do not build it yourself: `CommandReceiverFactory` and
    `LocalConsoleFactory` add one to the node. A failing command is reported
    to the console and logged; it never stops the node.

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
        self.console_name = factory.console
        self.watches = KeyWatches(self, f"{task_name}:tick")
        self.task_handlers = {
            (TaskType.event, task_name): self.on_command,
            (TaskType.event, self.watches.tick_name): self.watches.on_tick,
        }
        self._session: Optional[ConsoleSession] = None  # of the command being run
        self._follow_up: SomeTasks = None  # the tasks the command asks for
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
        self._session = session
        try:
            reply, follow_up = self._run(str(line))
        finally:
            self._session = None
        if reply is not None:
            session.send(reply)
        return follow_up

    def terminate(self) -> None:
        """Stop the timer of open ``echo``/``hz`` watches."""
        self.watches.close()

    def execute(self, line: str) -> Reply:
        """Run one command line now and return the reply (on the node's thread).

        Tasks the command asks for (e.g. ``task event go``) are scheduled.
        """
        reply, follow_up = self._run(line)
        self.schedule(follow_up)
        return reply or Reply(Status.OK, "")

    def _run(self, line: str) -> Tuple[Optional[Reply], SomeTasks]:
        """The reply to ``line`` (None: it comes later), and the tasks it asks for."""
        words = line.split(None, 1)
        if not words:
            return Reply(Status.OK, ""), None
        word, args = words[0].lower(), words[1] if len(words) > 1 else ""
        if word not in COMMANDS:
            hint = did_you_mean(word, COMMANDS)
            text = f"Unknown command {word!r}.{hint} Type 'help' to see the commands."
            return Reply(Status.ERROR, text), None
        command: Callable[[str], _Answer] = getattr(self, f"cmd_{word}")
        self._follow_up = None
        try:
            answer = command(args)
        except _CommandFailed as refused:
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
        if answer is not None:
            answer = Reply(answer.status, _bounded(answer.text))
        return answer, self._follow_up

    # -- commands -------------------------------------------------------------
    def cmd_exit(self, args: str) -> _Answer:
        """``exit``: stop the node; the console is closed after the reply."""
        _no_arguments("exit", args)
        self._follow_up = tasks.terminate(f"exit command from {self._session or 'console'}")
        return Reply(Status.BYE, f"Stopping node {self.parent.role!r}. Bye.")

    def cmd_task(self, args: str) -> _Answer:
        """``task <type> <name> [values...]``: schedule a task."""
        words = args.split(None, 2)
        types = ", ".join(TaskType.__members__)
        if len(words) < 2:
            raise _CommandFailed(
                f"Usage: {COMMANDS['task'].usage}, e.g. `task event button_pressed A`. "
                f"Types: {types}."
            )
        type_word, name, rest = words[0], words[1], words[2] if len(words) == 3 else ""
        task_type = TaskType.__members__.get(type_word.lower())
        if task_type is None:
            hint = did_you_mean(type_word.lower(), TaskType.__members__)
            raise _CommandFailed(f"Unknown task type {type_word!r}.{hint} Types: {types}.")
        values = parse_values(rest)
        if task_type is TaskType.terminate:
            task = tasks.terminate(f"{name} {rest}".strip())
        elif task_type is TaskType.reload:
            if name != "all":
                self._check_protected(self._full_node("task reload"), name, "reload")
            task = tasks.reload_component(name)
        elif task_type is TaskType.event:
            if name == tasks.REMOVE_COMPONENT:
                for target in values:
                    self._check_protected(self.parent, str(target), "remove")
            task = tasks.event(name, values)
        elif len(values) != 1:
            raise _CommandFailed(
                f"`task {type_word} {name}` needs exactly one value (the data), got "
                f"{len(values)}. Write e.g. `task {type_word} {name} 3.2`, or "
                f"`task {type_word} {name} [1, 2]` for a list."
            )
        elif task_type is TaskType.store_page:
            task = tasks.store_data(name, values[0])
        else:
            task = tasks.process_data(self.parent.page(name, values[0]))
        self._follow_up = task
        return f"Scheduled {format_task(task, values='data')}"

    def cmd_reload(self, args: str) -> _Answer:
        """``reload all|<component>``: hot-reload source code, keep factory state."""
        target = args.strip()
        if not target or len(target.split()) != 1:
            raise _CommandFailed(
                f"Usage: {COMMANDS['reload'].usage}. Components: {self._component_names()}."
            )
        node = self._full_node("reload")
        names = [target]
        if target == "all":
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
        else:
            self._check_protected(node, target, "reload")
        results = [self._reload_one(node, name) for name in names]
        failed = [message for ok, message in results if not ok]
        text = results[0][1]
        if len(results) > 1:
            text = f"Reloaded {len(results) - len(failed)} of {len(results)} components:\n"
            text += "\n".join("  " + message for _, message in results)
        return Reply(Status.ERROR if failed else Status.OK, text)

    def _check_protected(self, node: AbstractNode, name: ComponentName, action: str) -> None:
        """Refuse to ``action`` ("remove" or "reload") the node's core or a console part.

        The refusal is the reply, and it is logged (repeats are counted, not repeated).
        """
        component = node.components.get(name)
        if name == NODE_CORE_NAME and action == "remove":
            reason = (
                f"Refused: {name!r} is the node's own core. It stores every page, adds, "
                "removes and reloads components, and stops the node on `exit`; without "
                "it the node would run on deaf. To stop the node, type `exit`."
            )
        elif name == NODE_CORE_NAME:
            reason = (
                f"Refused: {name!r} is the node's own core and runs every reload itself; "
                "SNR's own code is not reloaded while the node runs. Restart the node to "
                "load a new SNR."
            )
        elif component is None and action == "reload":
            hint = did_you_mean(name, node.components)
            raise _CommandFailed(
                f"No component named {name!r} in node {node.role!r}.{hint} "
                f"Components: {self._component_names()}."
            )
        elif component is None or not _is_console_part(component, self.parent):
            return
        elif action == "remove":
            reason = (
                f"Refused: {name!r} is part of a console; removing it would cut off the "
                "consoles that use it, maybe this one. Type `quit` to leave this console, "
                "or `exit` to stop the node."
            )
        else:
            reason = (
                f"{name!r} is part of the console, which cannot reload itself while it "
                "carries this command. Restart the node to load new console code."
            )
        self._refusals.report(
            ("refused", reason[:60]),
            "Refused console commands",
            logging.WARNING,
            "Console %s: %s",
            self._session or "console",
            reason,
        )
        raise _CommandFailed(reason)

    def _reload_one(self, node: Node, name: ComponentName) -> Tuple[bool, str]:
        has_modules = bool(node.components[name].factory.reload_targets)
        errors = _ErrorCollector()  # the node logs why a reload failed: quote it back
        node.log.addHandler(errors)
        try:
            rebuilt = node.reload_component(name)
        finally:
            node.log.removeHandler(errors)
        if not rebuilt:
            return False, "\n".join(errors.messages) or (
                f"Reloading {name!r} failed, so the old version keeps running. "
                "The node's log says why."
            )
        if not has_modules:
            return True, (
                f"Rebuilt {name!r} from its factory, but the factory names no modules to "
                "reload, so the code is unchanged. To hot-reload it, pass its module to the "
                "factory: `super().__init__(my_module)`."
            )
        return True, f"Reloaded {name!r}; its factory (and the state it keeps) is the same."

    def cmd_list(self, args: str) -> _Answer:
        """``list commands|endpoints``."""
        if _one_choice("list", args, ["commands", "endpoints"]) == "commands":
            return commands_table()
        components = self.parent.components
        lines = [f"Components of node {self.parent.role!r} ({len(components)}):"]
        width = max((len(name) for name in components), default=0)
        for name, component in components.items():
            kind = "loop" if isinstance(component, ThreadLoop) else "endpoint"
            line = f"  {name:<{width}}  {kind:<8}  {type(component).__name__}"
            if isinstance(component, ThreadLoop):
                line += f" ({component.state.value})"
            modules = [m.__name__ for m in component.factory.reload_targets]
            if modules:
                line += f"  reloads: {', '.join(modules)}"
            lines.append(line)
        return "\n".join(lines)

    def cmd_dump(self, args: str) -> _Answer:
        """``dump profiler|datastore [KEY|PREFIX*]``."""
        words = args.split()
        choice = _one_choice("dump", words[0] if words else "", ["profiler", "datastore"])
        if len(words) > (1 if choice == "profiler" else 2):
            raise _CommandFailed(f"Usage: {COMMANDS['dump'].usage}.")
        if choice == "profiler":
            if self.parent.profiler is None:
                return (
                    f"Profiling is off for node {self.parent.role!r}. Turn it on with "
                    "Config(..., profile=True); it is on by default in Mode.DEBUG."
                )
            return self.parent.profiler.dump()
        datastore = self._full_node("dump datastore").datastore
        if len(words) < 2 or words[1].endswith("*"):
            prefix = words[1][:-1] if len(words) == 2 else ""
            return _list_datastore(self.parent.role, datastore, prefix)
        key = words[1]
        page = datastore.get(key)
        if page is None:
            hint = did_you_mean(key, datastore)
            raise _CommandFailed(
                f"Node {self.parent.role!r} has no data under {key!r}.{hint} "
                "`dump datastore` lists the keys."
            )
        age_s = max(0.0, time.time() - page.created_at_s)
        head = f"{key} (from {page.origin!r}, {age_s:.1f} s ago) = "
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

    def cmd_stats(self, args: str) -> _Answer:
        """``stats``: the task queue's and every comms link's counters."""
        node = self._full_node("stats")
        queue = node.queue
        lines = [
            f"Queue of node {node.role!r}: {len(queue)} tasks waiting (high-water mark "
            f"{queue.high_water:,}); loops waited for room {queue.waits} times; "
            f"{queue.loss.total} tasks dropped."
        ]
        if node.step_mode.paused:
            lines.append(f"The node is paused. {_loss_while_paused(node)}")
        comms = [c for c in node.components.values() if isinstance(c, CommsLoop)]
        lines += [f"{loop.name}: {loop.stats_text()}" for loop in comms] or ["No comms links."]
        return "\n".join(lines)

    def cmd_graph(self, args: str) -> _Answer:
        """``graph [text|mermaid|dot]``: this node's data-flow graph, as it runs now."""
        choice = _one_choice("graph", args or "text", ["text", "mermaid", "dot"])
        # The graph is an extra (it loads ast): found by its entry point, only when asked.
        draw = plugins.load("snr.console_commands", "graph", "The console's `graph` command")
        return str(draw(self._full_node("graph"), choice))

    def cmd_echo(self, args: str) -> _Answer:
        """``echo KEY [N]``: the next pages of KEY (the reply waits for them)."""
        words = args.split()
        if not 1 <= len(words) <= 2:
            raise _CommandFailed(f"Usage: {COMMANDS['echo'].usage}, e.g. `echo depth`.")
        wanted = ECHO_DEFAULT_PAGES
        if len(words) == 2:
            wanted = int(_number(words[1], "echo", "N", 1, ECHO_MAX_PAGES, int))
        return self.watches.echo(words[0], wanted, self._console())

    def cmd_hz(self, args: str) -> _Answer:
        """``hz KEY [WINDOW_S]``: the rate and jitter of KEY (the reply comes after the window)."""
        words = args.split()
        if not 1 <= len(words) <= 2:
            raise _CommandFailed(f"Usage: {COMMANDS['hz'].usage}, e.g. `hz depth 2`.")
        window_s = HZ_DEFAULT_WINDOW_S
        if len(words) == 2:
            window_s = _number(words[1], "hz", "WINDOW_S", 0.1, HZ_MAX_WINDOW_S, float)
        self.watches.hz(words[0], window_s, self._console())
        return None

    def _console(self) -> ConsoleSession:
        """The session of the command being run, for a reply that comes later."""
        if self._session is None:
            raise _CommandFailed(
                "`echo` and `hz` reply once pages have come, so they need a console to reply to: "
                "type them in snr-console or a LocalConsoleFactory console."
            )
        return self._session

    def cmd_pause(self, args: str) -> _Answer:
        """``pause``: hold the node's tasks (the console's own still run)."""
        _no_arguments("pause", args)
        node = self._full_node("pause")
        if node.step_mode.paused:
            return f"Node {node.role!r} is already paused. {_loss_while_paused(node)}"
        node.step_mode.pause()
        return (
            f"Paused node {node.role!r}: its tasks wait in its queue (high-water mark "
            f"{node.queue.high_water:,}) until you step or resume.\n"
            f"{_next_line(node.step_mode.next_tasks(), len(node.queue))}\n"
            "Type `step` to run the next task, `resume` to let the node run on."
        )

    def cmd_step(self, args: str) -> _Answer:
        """``step [N]``: run the next task(s) of a paused node; the reply says what they did."""
        words = args.split()
        if len(words) > 1:
            raise _CommandFailed(f"Usage: {COMMANDS['step'].usage}, e.g. `step` or `step 5`.")
        count = int(_number(words[0], "step", "N", 1, MAX_STEPS, int)) if words else 1
        step_mode = self._full_node("step").step_mode
        if not step_mode.paused:
            raise _CommandFailed(
                f"Node {self.parent.role!r} is running, so there is nothing to step: "
                "type `pause` first."
            )
        session = self._session
        if session is None:
            raise _CommandFailed("`step` replies once its tasks ran: type it in a console.")
        try:
            step_mode.step(count, lambda steps: session.send(Reply(Status.OK, _steps_text(steps))))
        except ValueError as refused:
            raise _CommandFailed(str(refused)) from None
        return None

    def cmd_resume(self, args: str) -> _Answer:
        """``resume``: let a paused node run freely again."""
        _no_arguments("resume", args)
        node = self._full_node("resume")
        if not node.step_mode.paused:
            return f"Node {node.role!r} is not paused."
        waiting = len(node.queue)
        lost = _loss_while_paused(node)
        node.step_mode.resume()
        plural = "s" if waiting != 1 else ""
        return f"Resumed node {node.role!r} with {waiting:,} task{plural} waiting. {lost}"

    def cmd_help(self, args: str) -> _Answer:
        """``help [command]``."""
        topic = args.strip().lower()
        if not topic:
            return "Commands (type `help <command>` for details):\n" + commands_table()
        entry = COMMANDS.get(topic)
        if entry is None:
            hint = did_you_mean(topic, COMMANDS)
            raise _CommandFailed(
                f"There is no command {topic!r}.{hint} Commands: {', '.join(COMMANDS)}."
            )
        return "\n  ".join([entry.usage, entry.summary, *entry.details.splitlines()])

    def _full_node(self, command: str) -> Node:
        if not isinstance(self.parent, Node):
            raise _CommandFailed(
                f"{command!r} needs a running snr.Node; this component's parent is a "
                f"{type(self.parent).__name__}."
            )
        return self.parent

    def _component_names(self) -> str:
        return ", ".join(self.parent.components)


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


# -- echo KEY and hz KEY ---------------------------------------------------------
@dataclass
class _Echo:
    key: DataKey
    console: str
    pages: Deque[Tuple[Page, float]] = field(default_factory=lambda: deque(maxlen=ECHO_MAX_PAGES))
    skipped: int = 0
    session: Optional[ConsoleSession] = None  # of the request waiting for pages
    wanted: int = ECHO_DEFAULT_PAGES
    asked_at: float = 0.0
    first_at: Optional[float] = None
    idle_since: float = 0.0


@dataclass
class _Rate:
    key: DataKey
    session: ConsoleSession
    window_s: float
    ends_at: float
    count: int = 0
    last_at: Optional[float] = None
    periods: int = 0
    mean: float = 0.0
    m2: float = 0.0  # Welford's running sum of squared differences
    low: float = math.inf
    high: float = 0.0

    def add(self, now: float) -> None:
        self.count += 1
        if self.last_at is not None:
            period = now - self.last_at
            self.periods += 1
            delta = period - self.mean
            self.mean += delta / self.periods
            self.m2 += delta * (period - self.mean)
            self.low, self.high = min(self.low, period), max(self.high, period)
        self.last_at = now


class KeyWatches:
    """The open ``echo`` and ``hz`` watches of one command processor.

    While a console watches a key, the processor handles ``(store_page,
    KEY)``: it sees each page right after the node core stored it, and costs
    the node nothing once the watch ends (the handler is removed). While any
    watch is open a timer schedules a tick task every 50 ms, so a watch ends
    on time even when no page comes. Pages that come between two ``echo KEY``
    of one console (within 2 s) wait for the next one, up to `ECHO_MAX_PAGES`;
    more are counted, and the reply says how many were skipped. ``hz`` keeps
    constant memory however fast the key is. All of it runs on the node's
    thread, but the timer, which only schedules the tick.

    Example::

        processor.watches.hz("depth", 2.0, session)   # the reply goes to session in 2 s
    """

    def __init__(self, owner: CommandProcessorEndpoint, tick_name: str) -> None:
        self.owner = owner
        self.tick_name = tick_name
        #: When an echo reply goes out: this long after its first page, or with no
        #: page after echo_wait_s; a console's echo is dropped after echo_keep_s unasked.
        self.echo_batch_s, self.echo_wait_s, self.echo_keep_s = 0.25, 1.0, 2.0
        self._echoes: Dict[Tuple[str, DataKey], _Echo] = {}
        self._rates: List[_Rate] = []
        self._timer: Optional[threading.Timer] = None
        self._closed = False

    def echo(self, key: DataKey, wanted: int, session: ConsoleSession) -> Optional[Reply]:
        """Start (or continue) this console's echo of ``key``; a reply now, or None (later)."""
        console = str(session)
        echo = self._echoes.get((console, key))
        if echo is None:
            self._check_room()
            echo = self._echoes[(console, key)] = _Echo(key, console)
            self.owner.task_handlers[(TaskType.store_page, key)] = self.on_page
        elif echo.session is not None:  # a second request while one waits: answer that one
            echo.session.send(self._echo_reply(echo))
        now = time.perf_counter()
        echo.session, echo.wanted, echo.asked_at = session, wanted, now
        echo.first_at = now if echo.pages else None
        if len(echo.pages) >= wanted:
            return self._echo_reply(echo)
        self._arm()
        return None

    def hz(self, key: DataKey, window_s: float, session: ConsoleSession) -> None:
        """Count the pages of ``key`` for ``window_s``; the reply goes to ``session`` then."""
        self._check_room()
        self._rates.append(_Rate(key, session, window_s, time.perf_counter() + window_s))
        self.owner.task_handlers[(TaskType.store_page, key)] = self.on_page
        self._arm()

    def _check_room(self) -> None:
        if len(self._echoes) + len(self._rates) >= MAX_WATCHES:
            raise _CommandFailed(
                f"Too many echo and hz at once on this node ({MAX_WATCHES}); wait for one "
                "to finish, or stop an echo with Ctrl-C."
            )

    def on_page(self, task: Task, key: TaskId) -> SomeTasks:
        """A page of a watched key was stored: note it for every watch of that key."""
        page = task.page()
        if page is None:
            return None
        now = time.perf_counter()
        for rate in self._rates:
            if rate.key == page.key:
                rate.add(now)
        for echo in list(self._echoes.values()):
            if echo.key != page.key:
                continue
            if len(echo.pages) == echo.pages.maxlen:
                echo.skipped += 1  # the oldest page falls out of the deque
            echo.pages.append((page, time.time() - page.created_at_s))
            if echo.session is not None:
                if echo.first_at is None:
                    echo.first_at = now
                if len(echo.pages) >= echo.wanted:
                    echo.session.send(self._echo_reply(echo))
        return None

    def on_tick(self, task: Task, key: TaskId) -> SomeTasks:
        """Send the replies that are due; forget echoes nobody asks for any more."""
        self._timer = None
        now = time.perf_counter()
        for rate in [r for r in self._rates if now >= r.ends_at]:
            self._rates.remove(rate)
            self._unwatch(rate.key)
            rate.session.send(Reply(Status.OK, self._rate_text(rate)))
        for echo in list(self._echoes.values()):
            if echo.session is not None:
                batch_due = echo.first_at is not None and now - echo.first_at >= self.echo_batch_s
                if batch_due or now - echo.asked_at >= self.echo_wait_s:
                    echo.session.send(self._echo_reply(echo))
            elif now - echo.idle_since >= self.echo_keep_s:
                del self._echoes[(echo.console, echo.key)]
                self._unwatch(echo.key)
        if self._echoes or self._rates:
            self._arm()
        return None

    def close(self) -> None:
        """Stop the timer (the node is stopping); open watches get no reply."""
        self._closed = True
        if self._timer is not None:
            self._timer.cancel()
            self._timer = None

    def _unwatch(self, key: DataKey) -> None:
        """Stop seeing the pages of ``key`` once no watch of it is left."""
        keys = [rate.key for rate in self._rates] + [echo.key for echo in self._echoes.values()]
        if key not in keys:
            self.owner.task_handlers.pop((TaskType.store_page, key), None)

    def _arm(self) -> None:
        if self._timer is None and not self._closed:
            self._timer = threading.Timer(_TICK_S, self._tick)
            self._timer.daemon = True
            self._timer.start()

    def _tick(self) -> None:
        """The timer's task; urgent while the node is paused, as the console's commands."""
        priority = console_priority(self.owner.parent)
        self.owner.schedule(Task(TaskType.event, self.tick_name, priority=priority))

    def _echo_reply(self, echo: _Echo) -> Reply:
        echo.session, echo.first_at = None, None
        echo.idle_since = time.perf_counter()
        lines = []
        if echo.skipped:
            lines.append(
                f"... {echo.skipped} pages of {echo.key!r} not shown: they came faster than "
                "this console asked for them."
            )
            echo.skipped = 0
        for _ in range(min(echo.wanted, len(echo.pages))):
            page, age_s = echo.pages.popleft()
            lines.append(
                f"{page.key} = {_preview(page.data)}  "
                f"(from {page.origin!r}, {max(0.0, age_s) * 1000:.0f} ms old)"
            )
        if not lines:
            lines.append(
                f"No page under {echo.key!r} in the last {self.echo_wait_s:g} s."
                f"{self._hint(echo.key)}"
            )
        return Reply(Status.OK, "\n".join(lines))

    def _rate_text(self, rate: _Rate) -> str:
        head = f"{rate.key}: "
        if rate.count == 0:
            return f"{head}no page in {rate.window_s:g} s.{self._hint(rate.key)}"
        if rate.periods == 0:
            return f"{head}1 page in {rate.window_s:g} s: too few to measure a period."
        std = math.sqrt(rate.m2 / rate.periods)
        return (
            f"{head}{1.0 / rate.mean:.3g} Hz over {rate.window_s:g} s ({rate.count} pages); "
            f"period mean {_ms(rate.mean)}, min {_ms(rate.low)}, max {_ms(rate.high)}, "
            f"std {_ms(std)} (jitter)"
        )

    def _hint(self, key: DataKey) -> str:
        datastore = getattr(self.owner.parent, "datastore", {})
        if key in datastore:
            return ""
        maybe = did_you_mean(key, datastore) if isinstance(key, str) else ""
        return (
            f" The node has no data under {key!r} yet.{maybe} `dump datastore` lists the "
            "keys; `graph` shows who stores what."
        )


# -- helpers ---------------------------------------------------------------------
def _ms(seconds: float) -> str:
    return f"{seconds * 1000:.1f} ms"


def _is_console_part(component: AbstractComponent, node: AbstractNode) -> bool:
    """A command processor, or a console loop one of them serves."""
    return isinstance(component, CommandProcessorEndpoint) or any(
        isinstance(other, CommandProcessorEndpoint) and other.console_name == component.name
        for other in list(node.components.values())
    )


def _no_arguments(command: str, args: str) -> None:
    if args.strip():
        raise _CommandFailed(f"{command!r} takes no arguments; got {args.strip()!r}.")


def _one_choice(command: str, args: str, choices: List[str]) -> str:
    choice = args.strip().lower()
    if choice in choices:
        return choice
    usage = f"Usage: {command} {'|'.join(choices)}."
    if not choice:
        raise _CommandFailed(usage)
    guess = closest_match(choice, choices)
    hint = f" Did you mean `{command} {guess}`?" if guess else ""
    raise _CommandFailed(f"{command!r} cannot show {choice!r}.{hint} {usage}")


def _number(word: str, command: str, name: str, low: float, high: float, kind: type) -> float:
    """``word`` as a number of ``kind`` from ``low`` to ``high``, or a reply saying why not."""
    try:
        value = float(kind(word))
    except ValueError:
        value = float("nan")  # fails the range check below
    if not low <= value <= high:
        raise _CommandFailed(
            f"`{command}` takes {name} from {low:g} to {high:g}; got {word!r}. "
            f"Usage: {COMMANDS[command].usage}."
        )
    return value


def _steps_text(steps: List[Step]) -> str:
    """What ``step`` did, task by task, and what waits next."""
    lines: List[str] = []
    for step in steps:
        if step.task is None:
            lines.append(
                "Nothing to step: no task waits. Tasks you schedule (`task ...`) and the "
                "pages of loops wait here while the node is paused."
            )
            continue
        lines.append(f"Ran {format_task(step.task, values='data')}")
        went_to = ", ".join(step.handlers) or "no handler (nothing handles this task)"
        lines.append(f"  went to: {went_to}")
        if step.returned:
            returned = ", ".join(format_task(t, values="data") for t in step.returned)
            lines.append(f"  returned: {returned}")
    if steps and steps[-1].task is not None:
        lines.append(_next_line(steps[-1].next_tasks, steps[-1].waiting))
    return "\n".join(lines)


def _loss_while_paused(node: Node) -> str:
    """How the loops fared since the pause: their waits for room and their dropped tasks."""
    waits, dropped = node.step_mode.since_pause()
    return (
        f"Since the pause, loops waited for room in the queue {waits:,} times and "
        f"{dropped:,} of their tasks were dropped."
    )


def _next_line(next_tasks: List[Task], waiting: int) -> str:
    """``Next: <task> (N tasks waiting)``, or that nothing waits."""
    if not next_tasks:
        return "Next: nothing waits."
    plural = "s" if waiting != 1 else ""
    return f"Next: {format_task(next_tasks[0], values='data')} ({waiting:,} task{plural} waiting)"


def _preview(data: Any) -> str:
    """A short repr: cheap even for a huge value (reprlib stops early)."""
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
    width = min(max(len(key) for key in keys), 40)
    count = f"{len(keys):,} key{'s' if len(keys) != 1 else ''}{where}"
    lines = [f"Datastore of node {role!r} ({count}):"]
    size = len(lines[0])
    for shown, key in enumerate(keys):
        page = datastore.get(key)
        if page is None:
            continue  # removed since the keys were listed
        line = (
            f"  {key:<{width}} = {_preview(page.data)}  "
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


def _bounded(text: str) -> str:
    """``text``, cut to `REPLY_BUDGET_CHARS` with a note when longer."""
    if len(text) <= REPLY_BUDGET_CHARS:
        return text
    return text[:REPLY_BUDGET_CHARS] + (
        f"\n... (reply cut: {len(text) - REPLY_BUDGET_CHARS:,} more characters; ask for "
        "less, e.g. `dump datastore KEY` for one key)"
    )


class _ErrorCollector(logging.Handler):
    """Keeps the error messages of a logger (and its children) while it is added to it."""

    snr_only_listens = True  # SNR's stderr handler still prints what this collects

    def __init__(self) -> None:
        super().__init__(logging.ERROR)
        self.messages: List[str] = []

    def emit(self, record: logging.LogRecord) -> None:
        self.messages.append(record.getMessage())
