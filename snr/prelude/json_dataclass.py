"""`JsonDataclass`: dataclasses-json's methods, imported on first use.

dataclasses-json is slow to import and only ``serialize()``/``deserialize()``
need it (the wire format is plain ``json``), so ``Page`` and ``Task`` get its
mixin's methods from this base, which imports it on first use.
"""

from __future__ import annotations

import functools
import sys
from typing import TYPE_CHECKING, Any, Dict, Type, TypeVar, cast

if TYPE_CHECKING:
    from dataclasses_json.core import Json
    from dataclasses_json.mm import JsonData, SchemaType

__all__ = ["JsonDataclass"]

_J = TypeVar("_J", bound="JsonDataclass")


@functools.cache  # import and register once
def _mixin() -> Any:
    """``dataclasses_json.DataClassJsonMixin``, imported on demand."""
    from dataclasses_json import DataClassJsonMixin

    DataClassJsonMixin.register(JsonDataclass)
    return DataClassJsonMixin


class JsonDataclass:
    """Base of a dataclass with dataclasses-json's methods, loaded lazily.

    A drop-in for ``dataclasses_json.DataClassJsonMixin`` (its methods call the
    mixin's); once loaded, ``isinstance(obj, DataClassJsonMixin)`` is true.

    Example::

        @dataclass
        class Reading(JsonDataclass):
            sensor: str
            value: float

        Reading("depth", 3.2).to_json()   # '{"sensor": "depth", "value": 3.2}'
        Reading.from_json('{"sensor": "depth", "value": 3.2}')
    """

    __slots__ = ()  # so a slotted subclass (Page, Task) has no per-object dict

    def to_json(self, **kw: Any) -> str:
        """This object as JSON text (dataclasses-json's ``to_json``).

        Example::

            Page("k", 1, "a", 0.0).to_json()
            # '{"key": "k", "data": 1, "origin": "a", "created_at_s": 0.0, "process": true}'
        """
        return cast(str, _mixin().to_json(self, **kw))

    @classmethod
    def from_json(cls: Type[_J], s: JsonData, **kw: Any) -> _J:
        """The object that :meth:`to_json` wrote as ``s``.

        Example::

            Page.from_json('{"key": "k", "data": 1, "origin": "a", "created_at_s": 0.0}')
        """
        return cast(_J, _mixin().from_json.__func__(cls, s, **kw))

    @classmethod
    def from_dict(cls: Type[_J], kvs: Json, **kw: Any) -> _J:
        """The object whose :meth:`to_dict` is ``kvs``.

        Example::

            Page.from_dict({"key": "k", "data": 1, "origin": "a", "created_at_s": 0.0})
        """
        return cast(_J, _mixin().from_dict.__func__(cls, kvs, **kw))

    def to_dict(self, encode_json: bool = False) -> Dict[str, Json]:
        """This object's fields as a dict (dataclasses-json's ``to_dict``).

        Example::

            Page("k", 1, "a", 0.0).to_dict()["data"]   # 1
        """
        return cast(Dict[str, "Json"], _mixin().to_dict(self, encode_json=encode_json))

    @classmethod
    def schema(cls: Type[_J], **kw: Any) -> SchemaType[_J]:
        """A marshmallow schema for this class (dataclasses-json's ``schema``).

        Example::

            Page.schema().dump(Page("k", 1, "a", 0.0))["key"]   # 'k'
        """
        return cast("SchemaType[_J]", _mixin().schema.__func__(cls, **kw))


if "dataclasses_json" in sys.modules:  # already paid for: register now
    _mixin()
