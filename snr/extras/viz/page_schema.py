"""JSON Schemas for pages, guessed from their data: what viewers need to show a key.

Viewers such as Foxglove and Lichtblick list a channel's fields from its
schema (to plot ``depth_m.data`` they must know it is a number). SNR pages
carry no declared type, so the schema is inferred from one page's data:

=====================  =========================================
data                   schema
=====================  =========================================
``True``               ``{"type": "boolean"}``
``3`` or ``3.5``       ``{"type": "number"}`` (an int may become a float later)
``"dive"``             ``{"type": "string"}``
``None``               ``{}`` (anything: the first page says nothing)
``[1.0, 2.0]``         ``{"type": "array", "items": {"type": "number"}}``
``{"x": 1.0}``         ``{"type": "object", "properties": {"x": ...}}``
=====================  =========================================

A list whose items are not all of one kind gets ``"items": {}``; otherwise its
first item stands for all of them. Nothing is ever
refused: the schema describes, it does not validate, so a later page that
differs is still sent.

Example::

    data_schema({"depth_m": 1.5, "ok": True})
    # {'type': 'object', 'properties': {'depth_m': {'type': 'number'},
    #                                   'ok': {'type': 'boolean'}}}
    page_schema(2.5)["properties"]["data"]   # {'type': 'number'}
"""

from __future__ import annotations

from typing import Any, Dict, List, Tuple

__all__ = ["PAGE_SCHEMA_NAME", "data_schema", "page_schema"]

PAGE_SCHEMA_NAME = "snr.Page"
"""The schema name viewers show for a channel of SNR pages."""

Schema = Dict[str, Any]


def data_schema(data: Any) -> Schema:
    """The JSON Schema of ``data``, as inferred from this one value.

    Nesting is followed iteratively, so deep data cannot overflow the stack.

    Example::

        data_schema([1, 2.5])   # {'type': 'array', 'items': {'type': 'number'}}
        data_schema(["a", 1])   # {'type': 'array', 'items': {}}
    """
    root: Schema = {}
    stack: List[Tuple[Any, Schema]] = [(data, root)]
    while stack:
        value, schema = stack.pop()
        if isinstance(value, bool):  # before int: bool is a subclass of int
            schema["type"] = "boolean"
        elif isinstance(value, (int, float)):
            schema["type"] = "number"
        elif isinstance(value, str):
            schema["type"] = "string"
        elif isinstance(value, dict):
            properties: Schema = {}
            schema["type"] = "object"
            schema["properties"] = properties
            for key, item in value.items():
                child: Schema = {}
                properties[str(key)] = child
                stack.append((item, child))
        elif isinstance(value, (list, tuple)):
            schema["type"] = "array"
            items: Schema = {}
            schema["items"] = items
            if value and _all_alike(value):
                stack.append((value[0], items))
        # None and anything else: {} (any value)
    return root


def _all_alike(values: Any) -> bool:
    """True when every item has the JSON kind of the first (so one schema fits all)."""
    first = _kind(values[0])
    return all(_kind(value) == first for value in values)


def _kind(value: Any) -> str:
    if isinstance(value, bool):
        return "boolean"
    if isinstance(value, (int, float)):
        return "number"
    if isinstance(value, str):
        return "string"
    if isinstance(value, dict):
        return "object"
    if isinstance(value, (list, tuple)):
        return "array"
    return "any"


def page_schema(data: Any) -> Schema:
    """The JSON Schema of a whole page (as the codec writes it) whose data looks like ``data``.

    Example::

        schema = page_schema({"x": 1.0})
        schema["properties"]["data"]   # {'type': 'object', 'properties': {'x': {...}}}
        sorted(schema["properties"])   # ['created_at_s', 'data', 'key', 'origin', 'process']
    """
    return {
        "title": PAGE_SCHEMA_NAME,
        "type": "object",
        "properties": {
            "key": {"type": "string"},
            "data": data_schema(data),
            "origin": {"type": "string"},
            "created_at_s": {"type": "number"},
            "process": {"type": "boolean"},
        },
    }
