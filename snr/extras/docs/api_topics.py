"""What ``from snr import *`` gives, by topic: the start page of the API reference.

`TOPICS` is the one list the start page (``snr.html``, written by
``python -m snr docs``) is made from. Every name of ``snr.__all__`` must be
in exactly one topic: `check_topics` reports any that is not, and the docs
build fails on it, so a new export cannot be left off the page.

Example::

    from snr.extras.docs.api_topics import TOPICS, check_topics, full_entry

    print(TOPICS[0].title)         # Building a robot
    check_topics()                 # [] when every export has its topic
    full_entry("Node")             # 'snr/core.html#Node'
"""

from __future__ import annotations

import ast
import functools
import importlib
import inspect
import pkgutil
from dataclasses import dataclass
from types import ModuleType
from typing import Dict, List, Optional, Sequence, Tuple

import snr
from snr.core.checks.student_code import parse_source

__all__ = ["PAGE_MODULES", "TOPICS", "Topic", "check_topics", "full_entry", "summary"]


@dataclass(frozen=True)
class Topic:
    """One section of the start page: a title, a sentence, its names, its guide pages.

    Example::

        Topic("Errors", "What SNR raises on purpose.", ("SNRError",), ("errors",))
    """

    title: str
    about: str
    names: Tuple[str, ...]
    guide: Tuple[str, ...] = ()
    """Stems of the guide's pages on this topic (``"comms"`` is ``comms.md``)."""


def _names(names: str) -> Tuple[str, ...]:
    return tuple(names.split())


TOPICS: Tuple[Topic, ...] = (
    Topic(
        "Building a robot",
        "A node per role, built from a config of factories; endpoints react to "
        "tasks, loops run beside the node; a runner starts the nodes.",
        _names(
            "Node Config Endpoint EndpointFactory ThreadLoop LoopFactory "
            "SynchronousRunner MultiProcRunner CliRunner Mode ComponentName "
            "ComponentsByRole Timer"
        ),
        _names("concepts tutorial"),
    ),
    Topic(
        "Tasks and pages",
        "Tasks are events handed to endpoints; pages are data stored under a key.",
        _names("Task TaskType tasks TaskId TaskName SomeTasks Page DataKey"),
        _names("concepts"),
    ),
    Topic(
        "Talking to other nodes",
        "Comms components forward pages by key between nodes: TCP sockets, "
        "pipes between processes, a serial port to a device, Zenoh. (The "
        "sockets server and client factories alone, and the loops, are in "
        "snr.std_mods.comms.)",
        _names(
            "SocketsPair PipeLoopFactory SerialLinkFactory ZenohCommsFactory "
            "COMMS_CONNECTED COMMS_DISCONNECTED"
        ),
        _names("comms serial wire-format"),
    ),
    Topic(
        "Filters",
        "Smooth a stream of numbers stored under one key into another key.",
        _names("MovingAvgFilterFactory KalmanFilterFactory"),
        _names("filters"),
    ),
    Topic(
        "Recording and replaying",
        "Record pages to a file, play them back later, or read them as columns to plot "
        "(text files and their readers are in snr.std_mods.io, MCAP in snr.extras.viz).",
        _names("RecorderEndpointFactory ReplayerLoopFactory read_recording"),
        _names("recording"),
    ),
    Topic(
        "Seeing your robot",
        "Watch a node's pages live in Foxglove or Lichtblick.",
        _names("FoxgloveBridgeFactory"),
        _names("viewing"),
    ),
    Topic(
        "The console",
        "Type commands into a running node, from its terminal or over TCP (the "
        "client for scripts, RemoteConsole, is in snr.std_mods.io).",
        _names("CommandReceiverFactory LocalConsoleFactory"),
        _names("console"),
    ),
    Topic(
        "Game controllers",
        "Read a game controller (or a scripted one), rename its controls, react to buttons.",
        _names(
            "ControllerLoopFactory InputMappingFactory ControlProcessorFactory "
            "Joystick SimulatedJoystick"
        ),
        _names("controller"),
    ),
    Topic(
        "Simulating a robot",
        "A 2-D differential-drive robot among walls, storing the pages a real "
        "robot would; drawn in a window or to PNG files (the physics, sensors and "
        "robot spec are in snr.extras.sim).",
        _names("SimRobotFactory SimViewFactory World SimClock"),
        _names("simulator"),
    ),
    Topic(
        "Small helpers: timeout, stopwatch, printer",
        "End a node after a while, time tasks, print them.",
        _names("TimeoutLoopFactory StopwatchEndpointFactory PrinterEndpointFactory"),
        _names("utilities"),
    ),
    Topic(
        "Testing",
        "Run a node in a test, expect the tasks it should run, feed it values "
        "(more tools in snr.utils).",
        _names(
            "SNRTestCase Expector MultiProcExpector ExpectorEndpointFactory "
            "ExpecterEndpointFactory ListReplayerFactory"
        ),
        _names("tutorial utilities"),
    ),
    Topic(
        "Errors",
        "Every error SNR raises on purpose is an SNRError and says what to fix; "
        "the kinds of SNRError are in snr.prelude.",
        _names("SNRError"),
        _names("errors"),
    ),
    Topic(
        "The interfaces",
        "The abstract classes a node, a factory and an endpoint meet; the "
        "others (loops, runners, configs) are in snr.prelude.",
        _names("AbstractNode AbstractFactory AbstractEndpoint"),
        _names("design"),
    ),
    Topic(
        "Code written for the 2021 release",
        "The names the 2021 release exported that today's API does not list (today's "
        "classes, or 2021 calls on top of them); the removed ones raise an error that "
        "says what replaced them.",
        _names(
            "AbstractComponent AbstractLoop AbstractMultiRunner AbstractProfiler "
            "TaskHandlerMap MovingAvgFilter OrderedExpector TestRunner "
            "TextReader PageReader TextReplayerFactory RemoteConsole LocalConsole "
            "ExpectorProtocol MPExpector TaskExpector TaskExpectations "
            "MovingAvgEndpointFactory RemovedApiError AbstractContext Context "
            "Consumer Settings SocketsListenerFactory SocketsLoopFactory "
            "SocketsWrapper"
        ),
        _names("deviations"),
    ),
)
"""The sections of the start page, in reading order."""

PAGE_MODULES: Tuple[str, ...] = (
    "snr.prelude",
    "snr.core",
    "snr.std_mods",
    "snr.utils",
    "snr.extras.zenoh",
    "snr.extras.serial",
    "snr.extras.viz",
    "snr.extras.controller",
    "snr.extras.sim",
    "snr.extras.graph",
    "snr.extras.console_tools",
    "snr.extras.plot",
    "snr.extras.compat2021",
)
"""The modules documented in full, one page each, in the order a name is looked up."""


def check_topics(topics: Sequence[Topic] = TOPICS) -> List[str]:
    """One problem per export of ``snr`` in no topic or two, and per topic name not exported.

    Example::

        check_topics()   # [] when the start page lists every export once
    """
    problems: List[str] = []
    seen: Dict[str, str] = {}
    exported = set(snr.__all__)
    for topic in topics:
        for name in topic.names:
            if name in seen:
                problems.append(
                    f"snr.extras.docs.api_topics: {name} is in two topics, {seen[name]!r} and "
                    f"{topic.title!r}; keep it in one."
                )
            seen[name] = topic.title
            if name not in exported:
                problems.append(
                    f"snr.extras.docs.api_topics: topic {topic.title!r} lists {name}, which is not "
                    "in snr.__all__. Remove it from the topic, or export it."
                )
    for name in sorted(exported - set(seen)):
        problems.append(
            f"snr.extras.docs.api_topics: snr.__all__ has {name}, which no topic of the API "
            "reference's start page lists. Add it to a topic in TOPICS."
        )
    return problems


def full_entry(name: str) -> Optional[str]:
    """Where the export ``name`` is documented in full, relative to the reference's root.

    The page of the package nearest the top that exports it on the way to the
    module that defines it (``snr.std_mods.comms`` for `SocketsPair`, defined
    in ``snr.std_mods.comms.sockets``); else the first of `PAGE_MODULES` that
    exports it. None if none does.

    Example::

        full_entry("Node")          # 'snr/core.html#Node'
        full_entry("SocketsPair")   # 'snr/std_mods/comms.html#SocketsPair'
        full_entry("tasks")         # 'snr/core/tasks.html'
    """
    value = getattr(snr, name)
    if inspect.ismodule(value):
        return value.__name__.replace(".", "/") + ".html"
    defined_in = getattr(value, "__module__", None) or ""
    if not defined_in.startswith("snr."):
        # A constant or an alias (COMMS_CONNECTED = "..."): where snr loads it from.
        defined_in = snr._HOME.get(name, "")
    parts = defined_in.split(".")
    on_the_way = [".".join(parts[:end]) for end in range(2, len(parts) + 1)]
    home = [m for m in on_the_way if _on_a_page(m) and name in _exports(m)]
    chosen = home or [m for m in PAGE_MODULES if name in _exports(m)]
    return f"{chosen[0].replace('.', '/')}.html#{name}" if chosen else None


def _on_a_page(module_name: str) -> bool:
    """True if pdoc writes a page for ``module_name`` (one of `PAGE_MODULES` or inside one)."""
    return any(module_name == m or module_name.startswith(m + ".") for m in PAGE_MODULES)


def _exports(module_name: str) -> Sequence[str]:
    return getattr(importlib.import_module(module_name), "__all__", ())


def summary(name: str) -> str:
    """The first paragraph of the docstring of ``snr.name``, as one line ("" if none).

    Type aliases and constants (``DataKey = str``) have no ``__doc__`` of their
    own (``str.__doc__`` is not about data keys): their docstring is the
    string written under them in the module that assigns them, read from the
    source.

    Example::

        summary("Node")      # 'Builds its components from the config's factories ...'
        summary("DataKey")   # 'The name a page is stored under in a node's datastore, ...'
    """
    value = getattr(snr, name)
    own = inspect.ismodule(value) or inspect.isclass(value) or inspect.isroutine(value)
    if own and (getattr(value, "__module__", None) or value.__name__).startswith("snr"):
        doc = inspect.getdoc(value) or ""
    else:
        doc = next(
            (
                _attribute_docstrings(module.__name__)[name]
                for module in _snr_modules()
                if vars(module).get(name) is value
                and name in _attribute_docstrings(module.__name__)
            ),
            "",
        )
    first_paragraph = doc.strip().split("\n\n")[0]
    return " ".join(line.strip() for line in first_paragraph.split("\n"))


@functools.cache
def _snr_modules() -> Tuple[ModuleType, ...]:
    """Every module of SNR (but ``__main__``), in a fixed order."""
    names = sorted(info.name for info in pkgutil.walk_packages(snr.__path__, "snr."))
    return tuple(importlib.import_module(n) for n in names if not n.endswith("__main__"))


@functools.cache
def _attribute_docstrings(module_name: str) -> Dict[str, str]:
    """Name -> docstring of each top-level assignment of the module followed by a string."""
    try:
        tree = parse_source(inspect.getsource(importlib.import_module(module_name)))
    except (OSError, TypeError, SyntaxError):
        return {}
    found: Dict[str, str] = {}
    for statement, following in zip(tree.body, tree.body[1:]):
        if not (
            isinstance(following, ast.Expr)
            and isinstance(following.value, ast.Constant)
            and isinstance(following.value.value, str)
        ):
            continue
        targets: List[ast.expr] = []
        if isinstance(statement, ast.Assign):
            targets = statement.targets
        elif isinstance(statement, ast.AnnAssign):
            targets = [statement.target]
        for target in targets:
            if isinstance(target, ast.Name):
                found[target.id] = inspect.cleandoc(following.value.value)
    return found
