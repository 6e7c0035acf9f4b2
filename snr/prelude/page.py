"""`Page`: a piece of data kept in a node's datastore (thesis 4.3.2)."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

from snr.prelude.errors import not_serializable_error
from snr.prelude.json_dataclass import JsonDataclass
from snr.prelude.names import DataKey

__all__ = ["Page"]


@dataclass
class Page(JsonDataclass):
    """A value stored under a key, stamped with where and when it was made.

    Pages outlive tasks: the newest page for each key stays in the datastore.
    Endpoints make pages with ``self.page(key, data)`` or, more often, store
    them straight away with ``self.store_data(key, data)``.

    Attributes:
        key: the data key, e.g. ``"depth_m"``.
        data: the value (JSON-able if it is to cross between nodes).
        origin: the role of the node that made it, e.g. ``"urov"``.
        created_at_s: wall-clock time it was made (``time.time()``), so pages
            from different machines can be compared.
        process: when true, a ``process_data`` task follows once the page is in
            the datastore.

    Example::

        page = Page("depth_m", 3.2, origin="urov", created_at_s=1700000000.0)
        Page.deserialize(page.serialize()) == page   # True
    """

    key: DataKey
    data: Any
    origin: str
    created_at_s: float
    process: bool = True

    def serialize(self) -> str:
        """This page as JSON text (the data must be JSON-able).

        Raises:
            NotSerializableError: naming the key and where in the data the
                part JSON cannot hold is, e.g. ``data['pose'][2] is a set``.
        """
        try:
            return self.to_json()
        except (TypeError, ValueError, OverflowError, RecursionError) as error:
            raise not_serializable_error(self.key, self.data) from error

    @classmethod
    def deserialize(cls, text: str) -> Page:
        """Rebuild a page from :meth:`serialize`'s JSON text."""
        return cls.from_json(text)
