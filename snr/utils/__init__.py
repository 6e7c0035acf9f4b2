"""Layer 3 of SNR: tools for testing your components (thesis 6.5).

Example::

    from snr.utils import SNRTestCase, ExpectorEndpointFactory, ListReplayerFactory

``SNRTestCase`` is a ``unittest.TestCase``; it and ``unittest`` are imported
the first time the name is used, so a node that never runs tests does not pay
for them (PEP 562 module ``__getattr__``).
"""

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
from snr.utils.temp_file import TempFile

if TYPE_CHECKING:
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
    "MockNode",
    "MultiProcExpector",
    "OrderedExpector",
    "SNRTestCase",
    "TempFile",
]


def __getattr__(name: str) -> Any:
    """Import ``SNRTestCase`` (and with it ``unittest``) on first use."""
    if name == "SNRTestCase":
        from snr.utils.test_case import SNRTestCase

        globals()[name] = SNRTestCase
        return SNRTestCase
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


def __dir__() -> List[str]:
    return sorted(set(globals()) | set(__all__))
