"""Layer 1 of SNR: the runtime (nodes, components, factories, runners).

The package gives what its modules below export (each module's ``__all__``),
so a name is listed once, in the module that defines it; the names for
students are chosen in ``snr/__init__.py``. ``from snr.core import *`` works
as in the 2021 release (thesis listing A.1 gets ``MovingAvgFilter`` from it).

Example::

    from snr.core import Config, Node, Endpoint, EndpointFactory, tasks
"""

# ruff: noqa: F403  (each module's names, by its own __all__)
from typing import List

from snr.core import (
    clock,
    component,
    config,
    dispatch,
    endpoint,
    factory,
    logs,
    loop,
    moving_avg_filter,
    node,
    runners,
    task_queue,
    tasks,
    timer,
)
from snr.core.checks import key_hints, profiler
from snr.core.checks.key_hints import *
from snr.core.checks.profiler import *
from snr.core.clock import *
from snr.core.component import *
from snr.core.config import *
from snr.core.dispatch import *
from snr.core.endpoint import *
from snr.core.factory import *
from snr.core.logs import *
from snr.core.loop import *
from snr.core.moving_avg_filter import *
from snr.core.node import *
from snr.core.runners import *
from snr.core.task_queue import *
from snr.core.timer import *

__all__: List[str] = ["tasks"]
__all__ += clock.__all__
__all__ += component.__all__
__all__ += config.__all__
__all__ += dispatch.__all__
__all__ += endpoint.__all__
__all__ += factory.__all__
__all__ += key_hints.__all__
__all__ += logs.__all__
__all__ += loop.__all__
__all__ += moving_avg_filter.__all__
__all__ += node.__all__
__all__ += profiler.__all__
__all__ += runners.__all__
__all__ += task_queue.__all__
__all__ += timer.__all__
