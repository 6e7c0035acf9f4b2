"""Lesson 5: a datastore of your own: your file (docs/lessons.md, "Lesson 5: a datastore").

A node keeps the newest page under each key in its datastore; SNR's own is a
``dict``. Write `HashDatastore`, a hash table of your own, with the four
methods a node uses: ``store[key] = page``, ``store.get(key)``, ``iter(store)``
and ``len(store)``. As it is, it forgets every page it is given.

Run it (lesson 1's robot drives with your datastore in its node), and grade it::

    python datastore.py --seconds 30
    python -m snr lesson grade 5

No dict or set inside: building the table is the lesson (a dict passes the
grade, as SNR's own is one, but teaches nothing).
"""

from __future__ import annotations

import sys
from typing import Iterator, List, Optional, Tuple

from snr import DataKey, Page
from snr.extras.lessons.l05_datastore.solution import main

__all__ = ["HashDatastore"]

BUCKETS = 8
"""How many buckets a new datastore has."""
MOST_PER_BUCKET = 2
"""Grow (twice the buckets) when there are more keys than this many per bucket."""

Bucket = List[Tuple[DataKey, Page]]


class HashDatastore:
    """A datastore in a hash table of its own: the newest page of each key.

    Example::

        store = HashDatastore()
        store["depth"] = Page("depth", 2.5, "robot", 0.0)
        store.get("depth").data     # 2.5
        store.get("speed")          # None: never stored
        list(store), len(store)     # ['depth'], 1
    """

    def __init__(self) -> None:
        self.buckets: List[Bucket] = [[] for _ in range(BUCKETS)]
        self.order: List[DataKey] = []
        """Every key, once, in the order each was first stored."""

    def bucket(self, key: DataKey) -> Bucket:
        """The bucket ``key`` belongs in."""
        buckets = self.buckets  # read once: a reader's table, even if it grows meanwhile
        return buckets[hash(key) % len(buckets)]

    def __setitem__(self, key: DataKey, page: Page) -> None:
        # TODO (step 1): in key's bucket, replace the pair of this key with
        #                (key, page), if there is one; else append (key, page)
        #                and append the key to self.order.
        # TODO (step 4): then, with more than MOST_PER_BUCKET keys a bucket, grow.
        pass

    def get(self, key: DataKey) -> Optional[Page]:
        # TODO (step 2): the page paired with key in its bucket, or None.
        return None

    def __iter__(self) -> Iterator[DataKey]:
        # TODO (step 3): the keys, each once, first stored first (a copy of self.order).
        return iter([])

    def __len__(self) -> int:
        # TODO (step 3): how many keys have a page.
        return 0

    def grow(self) -> None:
        """Twice the buckets, every pair moved to its new bucket."""
        # TODO (step 4): make twice as many empty buckets, put each (key, page)
        #                in its bucket there, then self.buckets = the new list.


if __name__ == "__main__":
    main(sys.argv, HashDatastore)
