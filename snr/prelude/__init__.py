"""Layer 0 of SNR: data types, type aliases, errors and interfaces.

Nothing here imports from the rest of ``snr``. Example::

    from snr.prelude import Page, Task, TaskType
"""

from snr.prelude.abstract import (
    AbstractComponent,
    AbstractConfig,
    AbstractEndpoint,
    AbstractFactory,
    AbstractLoop,
    AbstractMultiRunner,
    AbstractNode,
    AbstractProfiler,
    AbstractRunner,
    AbstractTaskQueue,
    IdleWaiter,
)
from snr.prelude.errors import (
    CommsError,
    ComponentError,
    ConfigError,
    HandlerError,
    LoopError,
    MissingSuperInitError,
    NodeStateError,
    NotSerializableError,
    SNRError,
    ThreadSafetyError,
    WireFormatError,
)
from snr.prelude.names import (
    ComponentName,
    ComponentsByRole,
    DataDict,
    DataKey,
    Mode,
    Role,
    SomeTasks,
    StatsCell,
    TaskHandler,
    TaskHandlerMap,
    TaskId,
    TaskName,
    TaskPriority,
    TaskScheduler,
    TaskType,
)
from snr.prelude.page import Page
from snr.prelude.serializable import Serializable
from snr.prelude.task import Task

__all__ = [
    "AbstractComponent",
    "AbstractConfig",
    "AbstractEndpoint",
    "AbstractFactory",
    "AbstractLoop",
    "AbstractMultiRunner",
    "AbstractNode",
    "AbstractProfiler",
    "AbstractRunner",
    "AbstractTaskQueue",
    "IdleWaiter",
    "CommsError",
    "ComponentError",
    "ComponentName",
    "ComponentsByRole",
    "ConfigError",
    "DataDict",
    "DataKey",
    "HandlerError",
    "LoopError",
    "MissingSuperInitError",
    "Mode",
    "NodeStateError",
    "NotSerializableError",
    "Page",
    "Role",
    "SNRError",
    "Serializable",
    "SomeTasks",
    "StatsCell",
    "Task",
    "TaskHandler",
    "TaskHandlerMap",
    "TaskId",
    "TaskName",
    "TaskPriority",
    "TaskScheduler",
    "TaskType",
    "ThreadSafetyError",
    "WireFormatError",
]
