"""Input and output: console, recorder, replayer, controller."""

from typing import List

__all__: List[str] = []
