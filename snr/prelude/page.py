"""`Page`: a piece of data kept in a node's datastore (thesis 4.3.2)."""

from __future__ import annotations

import time
import warnings
from dataclasses import dataclass
from typing import Any, Dict

from snr.prelude.json_dataclass import JsonDataclass
from snr.prelude.names import DataKey
from snr.prelude.not_serializable import check_serializable, not_serializable_error
from snr.prelude.student_code import short_repr

__all__ = ["DataDict", "Page", "preview"]


@dataclass(slots=True)
class Page(JsonDataclass):
    """A value stored under a key, stamped with where and when it was made.

    The newest page for each key stays in the datastore; endpoints usually
    store one with ``self.store_data(key, data)``.

    Attributes:
        key: the data key, e.g. ``"depth_m"``.
        data: the value (JSON-able if it is to cross between nodes).
        origin: the role of the node that made it, e.g. ``"urov"``.
        created_at_s: wall-clock time it was made (``time.time()``).
        process: when true, a ``process_data`` task follows once the page is in
            the datastore.

    Example::

        page = Page("depth_m", 3.2, origin="urov", created_at_s=1700000000.0)
        Page.deserialize(page.serialize()) == page   # True
        print(Page("depth_m", 3.2, "urov", time.time()))
        # Page 'depth_m' = 3.2 from 'urov' (0.0 s ago)
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
        # dataclasses-json would write a set as a list and NaN as NaN (not
        # JSON): refuse what pages sent between nodes may not hold, as they are.
        check_serializable(self.key, self.data)
        try:
            return self.to_json()
        except (TypeError, ValueError, OverflowError, RecursionError) as error:
            raise not_serializable_error(self.key, self.data) from error

    def __bool__(self) -> bool:
        """Always True (a page exists); warns, once per line, when its data is false.

        ``if page:`` never tests the page's value; ``is not None`` tests for a page.

        Example::

            page = self.get_page("obstacle")
            if page is not None and page.data:   # a page was stored, and it says True
                ...
        """
        try:
            false_data = not self.data
        except Exception:  # data with no single truth value (an array): nothing to say
            return True
        if false_data:
            warnings.warn(
                f"'if page:' is true for the page {self.key!r} although its data is "
                f"{preview(self.data)}: a Page is always true. To test its value, write "
                "'if page.data:' (in a handler: 'if task.val_list[0].data:'); to test "
                "whether get_page found one, write 'if page is not None:'.",
                stacklevel=2,
            )
        return True

    @classmethod
    def deserialize(cls, text: str) -> Page:
        """Rebuild a page from :meth:`serialize`'s JSON text."""
        return cls.from_json(text)

    def __str__(self) -> str:
        """The page in one short line: key, data, origin and age.

        Long data is cut short with ``...``; ``repr(page)`` shows it whole.

        Example::

            str(Page("depth", 2.5, "robot", time.time() - 0.3))
            # "Page 'depth' = 2.5 from 'robot' (0.3 s ago)"
            str(Page("depth", 2.5, "robot", 0.0))
            # "Page 'depth' = 2.5 from 'robot' (made 1970-01-01 00:00:00 UTC)"
        """
        age = _age_text(self.created_at_s, time.time())
        return f"Page {self.key!r} = {preview(self.data)} from {self.origin!r} ({age})"


DataDict = Dict[DataKey, Page]
"""A node's datastore: the newest page for every data key."""


def _age_text(created_at_s: float, now_s: float) -> str:
    """How long before ``now_s`` a page was made, in words: ``"0.3 s ago"``.

    A page up to a minute ahead says so (two machines' clocks differ); one
    older than a day, or further ahead, shows its date.
    """
    try:
        age = now_s - created_at_s
        made = time.strftime("%Y-%m-%d %H:%M:%S", time.gmtime(created_at_s))
    except (TypeError, OverflowError, OSError, ValueError):  # not a time: say what it is
        return f"created_at_s={created_at_s!r}"
    for below, unit_s, unit in ((60, 1, "s"), (3600, 60, "min"), (86400, 3600, "h")):
        if -0.05 <= age < below:
            return f"{max(age, 0.0) / unit_s:.1f} {unit} ago"
    if -60 < age < 0:
        return f"{-age:.1f} s in the future: the clocks differ"
    return f"made {made} UTC"


def preview(data: Any) -> str:
    """``repr(data)``, cut short after 1,000 characters: how a page's data is printed.

    Example::

        preview(list(range(5)))      # '[0, 1, 2, 3, 4]'
        len(preview(bytes(10_000)))  # 1000, ending in '...'
    """
    return short_repr(data, 1000, "...")  # a game pad's buttons, not a camera frame
