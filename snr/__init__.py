"""SNR is Not ROS: small typed modules that pass messages, in pure Python.

Everything a student needs is here::

    from snr import *

That gives ``__all__`` below: what the listings, tutorial and examples use, and
the 2021 release's names. The rest is imported from its own module, e.g.
``from snr.std_mods.comms import SocketsServerFactory``.

``python -m snr docs`` builds and opens the guide and API reference, offline;
``python -m snr demo`` runs the thesis's underwater vehicle.

``import snr`` is kept light: the ready-made components (``snr.std_mods``),
the extras (``snr.extras``: Zenoh, serial, controller, simulator...),
the testing utilities (``snr.utils``, ``SNRTestCase`` with ``unittest``)
and the 2021 names are imported the first time one is used;
``from snr import *`` imports everything it names.
"""

# This file is the one list of the public names (docs/design.md, "The public
# names"). To add one: import it below from its package, add it to __all__ and,
# if it is loaded on first use, to _LAZY; tests/test_public_api.py and the docs
# build say what is missing.

from typing import TYPE_CHECKING, Any, Dict, List, Tuple

from snr.core import (
    Config,
    Endpoint,
    EndpointFactory,
    LoopFactory,
    MovingAvgFilter,
    Node,
    SynchronousRunner,
    ThreadLoop,
    Timer,
    tasks,
)
from snr.prelude import (
    AbstractComponent,
    AbstractEndpoint,
    AbstractFactory,
    AbstractLoop,
    AbstractMultiRunner,
    AbstractNode,
    AbstractProfiler,
    ComponentName,
    ComponentsByRole,
    DataKey,
    Mode,
    Page,
    SNRError,
    SomeTasks,
    Task,
    TaskHandlerMap,
    TaskId,
    TaskName,
    TaskType,
)

if TYPE_CHECKING:  # loaded on first use (_LAZY); these lines let type checkers see them
    from snr.extras.compat2021 import (
        AbstractContext,
        Consumer,
        Context,
        ExpectorProtocol,
        LocalConsole,
        MovingAvgEndpointFactory,
        MPExpector,
        PageReader,
        RemoteConsole,
        RemovedApiError,
        Settings,
        SocketsListenerFactory,
        SocketsLoopFactory,
        SocketsWrapper,
        TaskExpectations,
        TaskExpector,
        TestRunner,
        TextReader,
        TextReplayerFactory,
    )
    from snr.extras.console_tools import LocalConsoleFactory
    from snr.extras.controller import (
        ControllerLoopFactory,
        ControlProcessorFactory,
        InputMappingFactory,
        Joystick,
        SimulatedJoystick,
    )
    from snr.extras.plot import read_recording
    from snr.extras.serial import SerialLinkFactory
    from snr.extras.sim import SimRobotFactory, SimViewFactory, World
    from snr.extras.viz import FoxgloveBridgeFactory
    from snr.extras.zenoh import ZenohCommsFactory
    from snr.std_mods.comms import (
        COMMS_CONNECTED,
        COMMS_DISCONNECTED,
        PipeLoopFactory,
        SocketsPair,
    )
    from snr.std_mods.filters import KalmanFilterFactory, MovingAvgFilterFactory
    from snr.std_mods.io import (
        CommandReceiverFactory,
        RecorderEndpointFactory,
        ReplayerLoopFactory,
    )
    from snr.std_mods.runners import CliRunner, MultiProcRunner
    from snr.std_mods.utils import (
        PrinterEndpointFactory,
        StopwatchEndpointFactory,
        TimeoutLoopFactory,
    )
    from snr.utils import (
        ExpecterEndpointFactory,
        Expector,
        ExpectorEndpointFactory,
        ListReplayerFactory,
        MultiProcExpector,
        OrderedExpector,
        SimClock,
    )
    from snr.utils.test_case import SNRTestCase

_LAZY: Dict[str, Tuple[str, ...]] = {
    "snr.extras.compat2021": (
        "AbstractContext",
        "Consumer",
        "Context",
        "ExpectorProtocol",
        "LocalConsole",
        "MovingAvgEndpointFactory",
        "MPExpector",
        "PageReader",
        "RemoteConsole",
        "RemovedApiError",
        "Settings",
        "SocketsListenerFactory",
        "SocketsLoopFactory",
        "SocketsWrapper",
        "TaskExpectations",
        "TaskExpector",
        "TestRunner",
        "TextReader",
        "TextReplayerFactory",
    ),
    "snr.extras.console_tools": ("LocalConsoleFactory",),
    "snr.extras.controller": (
        "ControllerLoopFactory",
        "ControlProcessorFactory",
        "InputMappingFactory",
        "Joystick",
        "SimulatedJoystick",
    ),
    "snr.extras.plot": ("read_recording",),
    "snr.extras.serial": ("SerialLinkFactory",),
    "snr.extras.sim": ("SimRobotFactory", "SimViewFactory", "World"),
    "snr.extras.viz": ("FoxgloveBridgeFactory",),
    "snr.extras.zenoh": ("ZenohCommsFactory",),
    "snr.std_mods.comms": (
        "COMMS_CONNECTED",
        "COMMS_DISCONNECTED",
        "PipeLoopFactory",
        "SocketsPair",
    ),
    "snr.std_mods.filters": ("KalmanFilterFactory", "MovingAvgFilterFactory"),
    "snr.std_mods.runners": ("CliRunner", "MultiProcRunner"),
    "snr.std_mods.io": (
        "CommandReceiverFactory",
        "RecorderEndpointFactory",
        "ReplayerLoopFactory",
    ),
    "snr.std_mods.utils": (
        "PrinterEndpointFactory",
        "StopwatchEndpointFactory",
        "TimeoutLoopFactory",
    ),
    "snr.utils": (
        "ExpecterEndpointFactory",
        "Expector",
        "ExpectorEndpointFactory",
        "ListReplayerFactory",
        "MultiProcExpector",
        "OrderedExpector",
        "SimClock",
    ),
    "snr.utils.test_case": ("SNRTestCase",),
}
"""The public names imported on first use, by the module each comes from.

The ready-made components (``snr.std_mods``) and ``SNRTestCase``
(``unittest``) cost more to import than the rest of SNR together; a program
pays for them, and the other testing utilities, only when it uses them. The
names kept for code written against the 2021 release
(``snr.extras.compat2021``) come with the components they alias."""

__version__ = "0.1.0"

__all__ = [
    "AbstractComponent",
    "AbstractContext",
    "AbstractEndpoint",
    "AbstractFactory",
    "AbstractLoop",
    "AbstractMultiRunner",
    "AbstractNode",
    "AbstractProfiler",
    "COMMS_CONNECTED",
    "COMMS_DISCONNECTED",
    "CliRunner",
    "CommandReceiverFactory",
    "ComponentName",
    "ComponentsByRole",
    "Config",
    "Consumer",
    "Context",
    "ControlProcessorFactory",
    "ControllerLoopFactory",
    "DataKey",
    "Endpoint",
    "EndpointFactory",
    "ExpecterEndpointFactory",
    "Expector",
    "ExpectorEndpointFactory",
    "ExpectorProtocol",
    "FoxgloveBridgeFactory",
    "InputMappingFactory",
    "Joystick",
    "KalmanFilterFactory",
    "ListReplayerFactory",
    "LocalConsole",
    "LocalConsoleFactory",
    "LoopFactory",
    "MPExpector",
    "Mode",
    "MovingAvgEndpointFactory",
    "MovingAvgFilter",
    "MovingAvgFilterFactory",
    "MultiProcExpector",
    "MultiProcRunner",
    "Node",
    "OrderedExpector",
    "Page",
    "PageReader",
    "PipeLoopFactory",
    "PrinterEndpointFactory",
    "RecorderEndpointFactory",
    "RemoteConsole",
    "RemovedApiError",
    "ReplayerLoopFactory",
    "SNRError",
    "SNRTestCase",
    "SerialLinkFactory",
    "Settings",
    "SimClock",
    "SimRobotFactory",
    "SimViewFactory",
    "SimulatedJoystick",
    "SocketsListenerFactory",
    "SocketsLoopFactory",
    "SocketsPair",
    "SocketsWrapper",
    "SomeTasks",
    "StopwatchEndpointFactory",
    "SynchronousRunner",
    "Task",
    "TaskExpectations",
    "TaskExpector",
    "TaskHandlerMap",
    "TaskId",
    "TaskName",
    "TaskType",
    "TestRunner",
    "TextReader",
    "TextReplayerFactory",
    "ThreadLoop",
    "TimeoutLoopFactory",
    "Timer",
    "World",
    "ZenohCommsFactory",
    "read_recording",
    "tasks",
]


def _set_excepthook() -> None:
    """An SNR error a student's own call raises shows their frames, not SNR's (errors.md 16p)."""
    from snr.core.checks.runner_checks import install_excepthook

    install_excepthook()


_set_excepthook()

_HOME: Dict[str, str] = {name: module for module, names in _LAZY.items() for name in names}


def __getattr__(name: str) -> Any:
    """Import a name of ``_LAZY`` (or the ``snr.std_mods`` package) on first use (PEP 562)."""
    import importlib

    if name == "std_mods":
        return importlib.import_module("snr.std_mods")
    module = _HOME.get(name)
    if module is None:
        raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
    value = getattr(importlib.import_module(module), name)
    globals()[name] = value
    return value


def __dir__() -> List[str]:
    return sorted(set(globals()) | set(__all__))
