"""A node's datastore as its components see it: read-only, and saying so.

A value written into ``self.parent.datastore`` directly would be a bare value
where readers expect a Page, from a thread that may not be the node's, with no
``process_data`` for the key's handlers. So ``node.datastore`` is a live,
read-only view of the node's own ``node.pages`` that refuses every change at
the line that tries it, naming ``store_data`` (docs/design.md, "Only the node
writes its datastore"). It reads through `Datastore`'s four methods only.

Example::

    pages = {}
    store = NodeDatastore(pages, "robot")
    pages["depth"] = page           # the node, on its own thread
    store["depth"]                  # the same Page: reads see the node's dict
    store["depth"] = 2.0            # DatastoreWriteError: ... use self.store_data(...)
"""

from __future__ import annotations

import threading
from typing import Any, Callable, Dict, Iterator, Mapping, NoReturn, Optional, Tuple

from snr.core.task_queue import TaskQueue
from snr.prelude import DataKey, Datastore, DatastoreWriteError, Page
from snr.prelude.student_code import caller_location

__all__ = ["NodeDatastore"]


def _refused(what: str, names_key: bool = False) -> Callable[..., NoReturn]:
    """A method that refuses ``what``, naming the key it was given when ``names_key``."""

    def refuse(self: NodeDatastore, *args: Any, **kwargs: Any) -> NoReturn:
        key = args[0] if names_key and args else None
        self._refuse(what.format(key=repr(key)), key)

    refuse.__doc__ = "Refused: the node alone writes its datastore."
    return refuse


class NodeDatastore(Mapping[DataKey, Page]):
    """A live, read-only view of a node's pages that refuses every change, naming store_data.

    Example::

        store = NodeDatastore({}, "robot")
        store.get("depth")        # None: reads as a dict
        store.pop("depth")        # DatastoreWriteError naming store_data
    """

    __slots__ = ("_pages", "queue", "role")

    def __init__(self, pages: Datastore, role: str, queue: Optional[TaskQueue] = None) -> None:
        self._pages = pages
        self.role = role
        self.queue = queue  # its owner_thread: the node's thread, once the node runs

    def __getitem__(self, key: DataKey) -> Page:
        page = self._pages.get(key)
        if page is None:
            raise KeyError(key)
        return page

    def __contains__(self, key: object) -> bool:
        return isinstance(key, str) and self._pages.get(key) is not None

    def __iter__(self) -> Iterator[DataKey]:
        return iter(self._pages)

    def __len__(self) -> int:
        return len(self._pages)

    def __repr__(self) -> str:
        return repr(self.copy())

    def copy(self) -> Dict[DataKey, Page]:
        """A plain dict of the pages now, the caller's own to change."""
        pages = self._pages  # list(): the keys now, as the node may store more
        return {key: page for key in list(pages) if (page := pages.get(key)) is not None}

    def _refuse(self, what: str, key: Any = None) -> NoReturn:
        name = "key" if key is None else repr(key)
        if self.queue is not None and threading.get_ident() == self.queue.owner_thread:
            how = (
                f"call self.store_data({name}, value), or return "
                f"self.store_data_task({name}, value) from a handler"
            )
        else:  # a loop's thread, or before the node runs
            how = (
                f"call self.store_data({name}, value); from a loop's thread it is also the "
                "thread-safe way, as it hands the page to the node's thread"
            )
        raise DatastoreWriteError(
            f"Only node {self.role!r} writes its datastore, so {what} at "
            f"{caller_location()} was refused: the node keeps a Page (data, time, origin) "
            f"under each key and tells the key's handlers. To store a value, {how}. "
            f"Read it back with self.get_data({name})."
        )

    # Every way to change a dict; "{key}": the key given, in the message.
    __setitem__ = _refused("datastore[{key}] = value", names_key=True)
    __delitem__ = _refused("del datastore[{key}]", names_key=True)
    __ior__ = _refused("datastore |= other")
    update = _refused("datastore.update()")
    pop = _refused("datastore.pop()", names_key=True)
    popitem = _refused("datastore.popitem()")
    clear = _refused("datastore.clear()")
    setdefault = _refused("datastore.setdefault()", names_key=True)

    def __reduce__(self) -> Tuple[Any, ...]:
        # copy.copy, deepcopy and pickle: a copy is a plain dict, the copier's own.
        return (dict, (self.copy(),))
