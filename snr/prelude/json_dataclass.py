"""`JsonDataclass`: dataclasses-json's methods, imported on first use.

``Page`` and ``Task`` used to subclass ``dataclasses_json.DataClassJsonMixin``.
Importing dataclasses-json pulls in marshmallow and ``importlib.metadata``,
over a third of what ``import snr`` cost, while only ``serialize()`` /
``deserialize()`` need it (nodes talk to each other with the plain ``json``
wire format). This base class offers the same methods, with the same
arguments and results, and imports dataclasses-json the first time one of
them runs.
"""

from __future__ import annotations

import sys
from typing import TYPE_CHECKING, Any, Callable, Dict, Optional, Tuple, Type, TypeVar, Union, cast

if TYPE_CHECKING:
    from dataclasses_json.core import Json
    from dataclasses_json.mm import JsonData, SchemaType

__all__ = ["JsonDataclass"]

_J = TypeVar("_J", bound="JsonDataclass")


_MIXIN: Any = None


def _mixin() -> Any:
    """``dataclasses_json.DataClassJsonMixin``, imported (once) on demand."""
    global _MIXIN
    if _MIXIN is None:
        from dataclasses_json import DataClassJsonMixin

        DataClassJsonMixin.register(JsonDataclass)
        _MIXIN = DataClassJsonMixin
    return _MIXIN


class JsonDataclass:
    """Base of a dataclass with dataclasses-json's methods, loaded lazily.

    A drop-in for ``dataclasses_json.DataClassJsonMixin``: ``to_json``,
    ``from_json``, ``to_dict``, ``from_dict`` and ``schema`` behave exactly as
    the mixin's do (they call them). dataclasses-json is imported the first
    time one is called; from then on the class (and every subclass) is also
    registered as a virtual subclass of ``DataClassJsonMixin``, so
    ``isinstance(obj, DataClassJsonMixin)`` is true as it was before.

    Example::

        @dataclass
        class Reading(JsonDataclass):
            sensor: str
            value: float

        Reading("depth", 3.2).to_json()   # '{"sensor": "depth", "value": 3.2}'
        Reading.from_json('{"sensor": "depth", "value": 3.2}')
    """

    __slots__ = ()  # so a slotted subclass (Page, Task) has no per-object dict

    def to_json(
        self,
        *,
        skipkeys: bool = False,
        ensure_ascii: bool = True,
        check_circular: bool = True,
        allow_nan: bool = True,
        indent: Optional[Union[int, str]] = None,
        separators: Optional[Tuple[str, str]] = None,
        default: Optional[Callable[[Any], Any]] = None,
        sort_keys: bool = False,
        **kw: Any,
    ) -> str:
        """This object as JSON text (dataclasses-json's ``to_json``).

        Example::

            Page("k", 1, "a", 0.0).to_json()
            # '{"key": "k", "data": 1, "origin": "a", "created_at_s": 0.0, "process": true}'
        """
        text: str = _mixin().to_json(
            self,
            skipkeys=skipkeys,
            ensure_ascii=ensure_ascii,
            check_circular=check_circular,
            allow_nan=allow_nan,
            indent=indent,
            separators=separators,
            default=default,
            sort_keys=sort_keys,
            **kw,
        )
        return text

    @classmethod
    def from_json(
        cls: Type[_J],
        s: JsonData,
        *,
        parse_float: Optional[Callable[[str], Any]] = None,
        parse_int: Optional[Callable[[str], Any]] = None,
        parse_constant: Optional[Callable[[str], Any]] = None,
        infer_missing: bool = False,
        **kw: Any,
    ) -> _J:
        """The object that :meth:`to_json` wrote as ``s``.

        Example::

            Page.from_json('{"key": "k", "data": 1, "origin": "a", "created_at_s": 0.0}')
        """
        function = _mixin().from_json.__func__
        return cast(
            _J,
            function(
                cls,
                s,
                parse_float=parse_float,
                parse_int=parse_int,
                parse_constant=parse_constant,
                infer_missing=infer_missing,
                **kw,
            ),
        )

    @classmethod
    def from_dict(cls: Type[_J], kvs: Json, *, infer_missing: bool = False) -> _J:
        """The object whose :meth:`to_dict` is ``kvs``.

        Example::

            Page.from_dict({"key": "k", "data": 1, "origin": "a", "created_at_s": 0.0})
        """
        return cast(_J, _mixin().from_dict.__func__(cls, kvs, infer_missing=infer_missing))

    def to_dict(self, encode_json: bool = False) -> Dict[str, Json]:
        """This object's fields as a dict (dataclasses-json's ``to_dict``).

        Example::

            Page("k", 1, "a", 0.0).to_dict()["data"]   # 1
        """
        fields: Dict[str, Json] = _mixin().to_dict(self, encode_json=encode_json)
        return fields

    @classmethod
    def schema(
        cls: Type[_J],
        *,
        infer_missing: bool = False,
        only: Any = None,
        exclude: Any = (),
        many: bool = False,
        context: Any = None,
        load_only: Any = (),
        dump_only: Any = (),
        partial: bool = False,
        unknown: Any = None,
    ) -> SchemaType[_J]:
        """A marshmallow schema for this class (dataclasses-json's ``schema``).

        Example::

            Page.schema().dump(Page("k", 1, "a", 0.0))["key"]   # 'k'
        """
        function = _mixin().schema.__func__
        return cast(
            "SchemaType[_J]",
            function(
                cls,
                infer_missing=infer_missing,
                only=only,
                exclude=exclude,
                many=many,
                context=context,
                load_only=load_only,
                dump_only=dump_only,
                partial=partial,
                unknown=unknown,
            ),
        )


if "dataclasses_json" in sys.modules:  # already paid for: register now
    _mixin()
