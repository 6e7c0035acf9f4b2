"""Layer 3 of SNR: tools for testing your components (thesis 6.5).

Example::

    from snr.utils import SNRTestCase, ExpectorEndpointFactory, ListReplayerFactory
"""

from snr.utils.dummy import DummyEndpoint, DummyEndpointFactory
from snr.utils.expector import Expector, MultiProcExpector, OrderedExpector
from snr.utils.expector_endpoint import (
    ExpecterEndpointFactory,
    ExpectorEndpoint,
    ExpectorEndpointFactory,
)
from snr.utils.list_replayer import ListReplayerFactory, ListReplayerLoop
from snr.utils.mock_node import MockNode
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
]
