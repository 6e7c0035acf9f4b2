"""What ``from snr import *`` gives, by topic: the start page of the API reference.

`TOPICS` is the one list the start page (``snr.html``, written by
``python -m snr docs``) is made from. Every name of ``snr.__all__`` must be
in exactly one topic: `check_topics` reports any that is not, and the docs
build fails on it, so a new export cannot be left off the page.

Example::

    from snr.api_topics import TOPICS, check_topics, full_entry

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
            "SynchronousRunner MultiProcRunner CliRunner TestRunner Mode Role "
            "ComponentName ComponentsByRole"
        ),
        _names("concepts tutorial"),
    ),
    Topic(
        "Tasks and pages",
        "Tasks are events handed to endpoints; pages are data stored under a key.",
        _names(
            "Task TaskType TaskPriority tasks TaskId TaskName TaskHandler "
            "TaskHandlerMap TaskScheduler SomeTasks Page DataKey DataDict "
            "Serializable"
        ),
        _names("concepts"),
    ),
    Topic(
        "Talking to other nodes",
        "Comms components forward pages by key between nodes: TCP sockets, "
        "pipes between processes, a serial port to a device, Zenoh.",
        _names(
            "SocketsPair SocketsServerFactory SocketsServerLoop "
            "SocketsClientFactory SocketsClientLoop PipeLoopFactory PipeLoop "
            "CommsLoop COMMS_CONNECTED COMMS_DISCONNECTED SerialLinkFactory "
            "SerialLinkLoop ZenohCommsFactory ZenohComms"
        ),
        _names("comms serial wire-format"),
    ),
    Topic(
        "Filters",
        "Smooth a stream of numbers stored under one key into another key.",
        _names(
            "MovingAvgFilterFactory MovingAvgEndpoint MovingAvgFilter "
            "DEFAULT_FILTER_LENGTH KalmanFilterFactory KalmanFilterEndpoint "
            "KalmanFilter"
        ),
        _names("filters"),
    ),
    Topic(
        "Recording and replaying",
        "Record pages to a file and play them back later, or feed a text file in.",
        _names(
            "RecorderEndpointFactory RecorderEndpoint ReplayerLoopFactory "
            "ReplayerLoop PageReader TextReplayerFactory TextReplayerLoop "
            "TextReader"
        ),
        _names("recording"),
    ),
    Topic(
        "Seeing your robot",
        "Watch a node's pages live in Foxglove or Lichtblick.",
        _names("FoxgloveBridgeFactory FoxgloveBridge"),
        _names("viewing"),
    ),
    Topic(
        "The console",
        "Type commands into a running node, from its terminal or over TCP.",
        _names(
            "CommandReceiverFactory CommandReceiverLoop CommandProcessorEndpoint "
            "LocalConsoleFactory LocalConsole RemoteConsole DEFAULT_CONSOLE_PORT"
        ),
        _names("console"),
    ),
    Topic(
        "Game controllers",
        "Read a game controller (or a scripted one), rename its controls, react to buttons.",
        _names(
            "ControllerLoopFactory ControllerLoop InputMappingFactory "
            "InputMappingEndpoint ControlProcessorFactory ControlProcessorEndpoint "
            "Joystick SimulatedJoystick JoystickStep DEFAULT_JOYSTICK_SCRIPT "
            "STEAM_CONTROLLER_BUTTONS STEAM_CONTROLLER_MAPPING"
        ),
        _names("controller"),
    ),
    Topic(
        "Simulating a robot",
        "A 2-D differential-drive robot among walls, storing the pages a real "
        "robot would; drawn in a window or to PNG files (the physics, sensors and "
        "robot spec are in snr.std_mods.sim).",
        _names("SimRobotFactory SimRobotLoop SimViewFactory SimViewLoop World SimClock"),
        _names("simulator"),
    ),
    Topic(
        "Small helpers: timeout, stopwatch, printer",
        "End a node after a while, time tasks, print them.",
        _names(
            "TimeoutLoopFactory TimeoutLoop StopwatchEndpointFactory "
            "StopwatchEndpoint PrinterEndpointFactory PrinterEndpoint format_task"
        ),
        _names("utilities"),
    ),
    Topic(
        "Testing",
        "Run a node in a test, expect the tasks it should run, feed it values.",
        _names(
            "SNRTestCase Expector OrderedExpector MultiProcExpector "
            "ExpectorEndpointFactory ExpecterEndpointFactory ExpectorEndpoint "
            "ListReplayerFactory ListReplayerLoop DummyEndpointFactory "
            "DummyEndpoint MockNode TempFile"
        ),
        _names("tutorial utilities"),
    ),
    Topic(
        "Inside a node: time, queues, profiling",
        "What a node uses to run its tasks and loops, and to tell you how it went.",
        _names("Timer Clock Profiler TaskQueue NodeState LoopState MissingKeyHints"),
        _names("design performance"),
    ),
    Topic(
        "Errors",
        "Every error SNR raises on purpose is an SNRError; each says what to fix.",
        _names(
            "SNRError ConfigError ComponentError MissingSuperInitError HandlerError "
            "LoopError NodeStateError ThreadSafetyError CommsError WireFormatError "
            "NotSerializableError"
        ),
        _names("errors"),
    ),
    Topic(
        "The interfaces",
        "The abstract classes of ``snr.prelude``: what a node, a component or a "
        "runner must do, for writing a new kind of one.",
        _names(
            "AbstractComponent AbstractEndpoint AbstractLoop AbstractFactory "
            "AbstractNode AbstractConfig AbstractRunner AbstractMultiRunner "
            "AbstractTaskQueue AbstractProfiler"
        ),
        _names("design"),
    ),
    Topic(
        "Code written for the 2021 release",
        "Names the 2021 release used that the thesis does not print; the removed "
        "ones raise an error that says what replaced them.",
        _names(
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
    "snr.compat2021",
)
"""The modules documented in full, one page each, in the order a name is looked up."""

_NOT_LISTED = {"__version__"}


def check_topics(topics: Sequence[Topic] = TOPICS) -> List[str]:
    """One problem per export of ``snr`` in no topic or two, and per topic name not exported.

    Example::

        check_topics()   # [] when the start page lists every export once
    """
    problems: List[str] = []
    seen: Dict[str, str] = {}
    exported = set(snr.__all__) - _NOT_LISTED
    for topic in topics:
        for name in topic.names:
            if name in seen:
                problems.append(
                    f"snr.api_topics: {name} is in two topics, {seen[name]!r} and "
                    f"{topic.title!r}; keep it in one."
                )
            seen[name] = topic.title
            if name not in exported:
                problems.append(
                    f"snr.api_topics: topic {topic.title!r} lists {name}, which is not "
                    "in snr.__all__. Remove it from the topic, or export it."
                )
    for name in sorted(exported - set(seen)):
        problems.append(
            f"snr.api_topics: snr.__all__ has {name}, which no topic of the API "
            "reference's start page lists. Add it to a topic in TOPICS."
        )
    return problems


def full_entry(name: str) -> Optional[str]:
    """Where the export ``name`` is documented in full, relative to the reference's root.

    The page of the module that defines it, if that is one of
    `PAGE_MODULES`; else the first of them that exports it. None if none does.

    Example::

        full_entry("Node")     # 'snr/core.html#Node'
        full_entry("tasks")    # 'snr/core/tasks.html'
    """
    value = getattr(snr, name)
    if inspect.ismodule(value):
        return value.__name__.replace(".", "/") + ".html"
    defined_in = getattr(value, "__module__", None) or ""
    exporters = [m for m in PAGE_MODULES if name in _exports(m)]
    home = [m for m in exporters if defined_in == m or defined_in.startswith(m + ".")]
    chosen = home or exporters
    return f"{chosen[0].replace('.', '/')}.html#{name}" if chosen else None


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
        tree = ast.parse(inspect.getsource(importlib.import_module(module_name)))
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
