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

# The one list of the public names (docs/design.md, "The public names"): to add
# one, import it below, add it to __all__ and, if loaded on first use, to _LAZY.

from typing import TYPE_CHECKING, Any, Dict, List

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

_LAZY: Dict[str, str] = {
    "snr.extras.compat2021": (
        "AbstractContext Consumer Context ExpectorProtocol LocalConsole "
        "MovingAvgEndpointFactory MPExpector PageReader RemoteConsole "
        "RemovedApiError Settings SocketsListenerFactory SocketsLoopFactory "
        "SocketsWrapper TaskExpectations TaskExpector TestRunner TextReader "
        "TextReplayerFactory"
    ),
    "snr.extras.console_tools": "LocalConsoleFactory",
    "snr.extras.controller": (
        "ControllerLoopFactory ControlProcessorFactory InputMappingFactory "
        "Joystick SimulatedJoystick"
    ),
    "snr.extras.plot": "read_recording",
    "snr.extras.serial": "SerialLinkFactory",
    "snr.extras.sim": "SimRobotFactory SimViewFactory World",
    "snr.extras.viz": "FoxgloveBridgeFactory",
    "snr.extras.zenoh": "ZenohCommsFactory",
    "snr.std_mods.comms": "COMMS_CONNECTED COMMS_DISCONNECTED PipeLoopFactory SocketsPair",
    "snr.std_mods.filters": "KalmanFilterFactory MovingAvgFilterFactory",
    "snr.std_mods.runners": "CliRunner MultiProcRunner",
    "snr.std_mods.io": "CommandReceiverFactory RecorderEndpointFactory ReplayerLoopFactory",
    "snr.std_mods.utils": "PrinterEndpointFactory StopwatchEndpointFactory TimeoutLoopFactory",
    "snr.utils": (
        "ExpecterEndpointFactory Expector ExpectorEndpointFactory ListReplayerFactory "
        "MultiProcExpector OrderedExpector SimClock"
    ),
    "snr.utils.test_case": "SNRTestCase",
}
"""The public names imported on first use, by module: the ready-made components, the testing
utilities and the 2021 names cost more to import than all the rest."""

__version__ = "0.1.0"

__all__ = ["AbstractComponent", "AbstractContext", "AbstractEndpoint", "AbstractFactory"]
__all__ += ["AbstractLoop", "AbstractMultiRunner", "AbstractNode", "AbstractProfiler"]
__all__ += ["COMMS_CONNECTED", "COMMS_DISCONNECTED", "CliRunner", "CommandReceiverFactory"]
__all__ += ["ComponentName", "ComponentsByRole", "Config", "Consumer", "Context"]
__all__ += ["ControlProcessorFactory", "ControllerLoopFactory", "DataKey", "Endpoint"]
__all__ += ["EndpointFactory", "ExpecterEndpointFactory", "Expector", "ExpectorEndpointFactory"]
__all__ += ["ExpectorProtocol", "FoxgloveBridgeFactory", "InputMappingFactory", "Joystick"]
__all__ += ["KalmanFilterFactory", "ListReplayerFactory", "LocalConsole", "LocalConsoleFactory"]
__all__ += ["LoopFactory", "MPExpector", "Mode", "MovingAvgEndpointFactory", "MovingAvgFilter"]
__all__ += ["MovingAvgFilterFactory", "MultiProcExpector", "MultiProcRunner", "Node"]
__all__ += ["OrderedExpector", "Page", "PageReader", "PipeLoopFactory", "PrinterEndpointFactory"]
__all__ += ["RecorderEndpointFactory", "RemoteConsole", "RemovedApiError", "ReplayerLoopFactory"]
__all__ += ["SNRError", "SNRTestCase", "SerialLinkFactory", "Settings", "SimClock"]
__all__ += ["SimRobotFactory", "SimViewFactory", "SimulatedJoystick", "SocketsListenerFactory"]
__all__ += ["SocketsLoopFactory", "SocketsPair", "SocketsWrapper", "SomeTasks"]
__all__ += ["StopwatchEndpointFactory", "SynchronousRunner", "Task", "TaskExpectations"]
__all__ += ["TaskExpector", "TaskHandlerMap", "TaskId", "TaskName", "TaskType", "TestRunner"]
__all__ += ["TextReader", "TextReplayerFactory", "ThreadLoop", "TimeoutLoopFactory", "Timer"]
__all__ += ["World", "ZenohCommsFactory", "read_recording", "tasks"]


def _set_excepthook() -> None:
    """An SNR error a student's own call raises shows their frames, not SNR's (errors.md 16p)."""
    from snr.core.checks.runner_checks import install_excepthook

    install_excepthook()


_set_excepthook()

_HOME: Dict[str, str] = {name: module for module, names in _LAZY.items() for name in names.split()}


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
