"""Lesson 5: a datastore of your own (docs/lessons.md), the reference solution.

A node keeps the newest page under each key in its datastore (thesis 4.2):
SNR's own is a ``dict``. `HashDatastore` is one written from scratch, a hash
table: a list of buckets, each a short list of ``(key, page)`` pairs; a key's
bucket is ``hash(key) % len(buckets)``. It has the four methods a node uses
(`snr.prelude.Datastore`), so ``Config(datastore=HashDatastore)`` makes every
node keep its pages in one.

Run it: lesson 1's wall follower drives its room for a while, in simulated
time as fast as the computer goes, with this datastore in its node; it
prints where the robot got to and what the datastore holds::

    python datastore.py --seconds 30

To write it yourself, ``python -m snr lesson start 5`` writes the starter
file into your folder, and ``python -m snr lesson grade 5`` grades it.
"""

from __future__ import annotations

import argparse
import sys
from typing import Any, Callable, Iterator, List, Optional, Tuple

from snr import DataKey, Page

__all__ = ["HashDatastore", "main"]

BUCKETS = 8
"""How many buckets a new datastore has."""
MOST_PER_BUCKET = 2
"""Grow (twice the buckets) when there are more keys than this many per bucket."""

Bucket = List[Tuple[DataKey, Page]]


class HashDatastore:
    """A datastore in a hash table of its own: the newest page of each key.

    Only the node's thread writes it (the node core stores each page); any
    thread may read it, so a reader must never see it half-changed: a write
    changes one list item or appends one, and growing builds a new table and
    puts it in place with one assignment.

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
        bucket = self.bucket(key)
        for index, (other, _) in enumerate(bucket):
            if other == key:
                bucket[index] = (key, page)  # the newer page, in the older one's place
                return
        bucket.append((key, page))
        self.order.append(key)
        if len(self.order) > MOST_PER_BUCKET * len(self.buckets):
            self.grow()

    def get(self, key: DataKey) -> Optional[Page]:
        for other, page in self.bucket(key):
            if other == key:
                return page
        return None

    def __iter__(self) -> Iterator[DataKey]:
        return iter(list(self.order))  # a copy: the node may store a new key meanwhile

    def __len__(self) -> int:
        return len(self.order)

    def grow(self) -> None:
        """Twice the buckets, every pair moved to its new bucket."""
        bigger: List[Bucket] = [[] for _ in range(2 * len(self.buckets))]
        for bucket in self.buckets:
            for key, page in bucket:
                bigger[hash(key) % len(bigger)].append((key, page))
        self.buckets = bigger  # one assignment: readers see the old table or the new


def main(argv: List[str], datastore: Optional[Callable[[], Any]] = None) -> None:
    """``python datastore.py [--seconds S]``: lesson 1's robot, S simulated seconds.

    ``datastore``: what makes the node's datastore (this file's by default).
    """
    from snr.extras.lessons.probe import demo

    parser = argparse.ArgumentParser(prog=argv[0], description="Lesson 5: a datastore.")
    parser.add_argument(
        "--seconds", type=float, default=10.0, help="how long the robot drives (simulated)"
    )
    options = parser.parse_args(argv[1:])
    if options.seconds <= 0:
        parser.error(f"--seconds {options.seconds:g}: give more than 0")
    demo(options.seconds, datastore=datastore or HashDatastore)


if __name__ == "__main__":
    main(sys.argv)
