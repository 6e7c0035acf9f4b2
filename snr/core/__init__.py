"""Layer 1 of SNR: the runtime (nodes, components, factories, runners).

Example::

    from snr.core import Config, Node, Endpoint, EndpointFactory, tasks
"""

from snr.core import tasks
from snr.core.component import Component
from snr.core.config import Config
from snr.core.dispatch import HandlerMap, HandlerTable
from snr.core.endpoint import Endpoint
from snr.core.factory import EndpointFactory, Factory, LoopFactory
from snr.core.key_hints import MissingKeyHints
from snr.core.logs import ensure_log_handler
from snr.core.loop import LoopState, ThreadLoop
from snr.core.moving_avg_filter import MovingAvgFilter
from snr.core.node import Node, NodeState
from snr.core.node_core import NodeCoreEndpoint, NodeCoreFactory
from snr.core.profiler import Profiler
from snr.core.runners import CliRunner, MultiProcRunner, SynchronousRunner, TestRunner
from snr.core.sim_clock import SimClock
from snr.core.task_queue import TaskQueue
from snr.core.timer import Clock, Timer

__all__ = [
    "CliRunner",
    "Clock",
    "Component",
    "Config",
    "Endpoint",
    "EndpointFactory",
    "Factory",
    "HandlerMap",
    "HandlerTable",
    "LoopFactory",
    "LoopState",
    "MissingKeyHints",
    "MovingAvgFilter",
    "MultiProcRunner",
    "Node",
    "NodeCoreEndpoint",
    "NodeCoreFactory",
    "NodeState",
    "Profiler",
    "SimClock",
    "SynchronousRunner",
    "TaskQueue",
    "TestRunner",
    "ThreadLoop",
    "Timer",
    "ensure_log_handler",
    "tasks",
]
