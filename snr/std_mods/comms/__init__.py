"""Communication between nodes: pipes, TCP sockets, serial links."""

from typing import List

__all__: List[str] = []
