"""The `Serializable` protocol: things that turn into JSON text and back."""

from __future__ import annotations

from typing import Protocol, Type, TypeVar, runtime_checkable

__all__ = ["Serializable"]

_T = TypeVar("_T", bound="Serializable")


@runtime_checkable
class Serializable(Protocol):
    """Anything with ``serialize() -> str`` and ``deserialize(text)``.

    ``Page`` and ``Task`` are Serializable without naming this class
    (structural typing, thesis 6.2.3).

    Example::

        def save(item: Serializable) -> str:
            return item.serialize()

        isinstance(Page("k", 1, "n", 0.0), Serializable)   # True
    """

    def serialize(self) -> str:
        """JSON text for this object."""
        ...

    @classmethod
    def deserialize(cls: Type[_T], text: str) -> _T:
        """The object that ``serialize()`` wrote as ``text``."""
        ...
