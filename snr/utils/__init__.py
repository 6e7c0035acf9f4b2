"""Layer 3 of SNR: tools for testing your components (thesis 6.5; docs/utilities.md).

``SNRTestCase`` (with ``unittest``) and the memory link (with comms) are
imported when first used (PEP 562), so a node that runs no test does not pay.

Example::

    from snr.utils import SNRTestCase, ExpectorEndpointFactory, ListReplayerFactory
"""

import importlib
from typing import TYPE_CHECKING, Any, List

from snr.utils.dummy import DummyEndpoint, DummyEndpointFactory
from snr.utils.expector import Expector, MultiProcExpector, OrderedExpector
from snr.utils.expector_endpoint import (
    ExpecterEndpointFactory,
    ExpectorEndpoint,
    ExpectorEndpointFactory,
)
from snr.utils.list_replayer import ListReplayerFactory, ListReplayerLoop
from snr.utils.mock_node import MockNode
from snr.utils.sim_clock import SimClock
from snr.utils.temp_file import TempFile

if TYPE_CHECKING:
    from snr.utils.memory_link import MemoryLinkPair, memory_transport_pair
    from snr.utils.test_case import SNRTestCase

__all__ = [
    "DummyEndpoint",
    "DummyEndpointFactory",
    "ExpecterEndpointFactory",
    "Expector",
    "ExpectorEndpoint",
    "ExpectorEndpointFactory",
    "ListReplayerFactory",
    "ListReplayerLoop",
    "MemoryLinkPair",
    "MockNode",
    "MultiProcExpector",
    "OrderedExpector",
    "SNRTestCase",
    "SimClock",
    "TempFile",
    "memory_transport_pair",
]


_LAZY = {
    "SNRTestCase": "snr.utils.test_case",
    "MemoryLinkPair": "snr.utils.memory_link",
    "memory_transport_pair": "snr.utils.memory_link",
}


def __getattr__(name: str) -> Any:
    """Import ``SNRTestCase`` (with ``unittest``) or the memory link (with comms) on first use."""
    if name in _LAZY:
        globals()[name] = value = getattr(importlib.import_module(_LAZY[name]), name)
        return value
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


def __dir__() -> List[str]:
    return sorted(set(globals()) | set(__all__))
