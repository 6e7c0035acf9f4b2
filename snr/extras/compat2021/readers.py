"""The 2021 readers and text replayer, on top of today's (`snr.std_mods.io`).

The 2021 release made a reader with its context first,
``TextReader(parent, name, filename)``, and read it with ``open()``,
``read()`` and ``close()``, or as a context manager. Today's readers are made
from the file name alone and iterated over. The classes here are today's
readers (subclasses), so they read and report bad lines the same way; they
take both calls and add the 2021 methods.

Example::

    with TextReader(self, "commands", "commands.txt") as reader:
        line = reader.read()
        while line is not None:
            print(line)
            line = reader.read()
"""

from __future__ import annotations

from types import TracebackType
from typing import TYPE_CHECKING, Generic, Iterator, Optional, Tuple, Type, TypeVar, Union

from snr.prelude import AbstractComponent, AbstractNode, DataKey, Page
from snr.std_mods.codec import PathLike
from snr.std_mods.io import replayer

if TYPE_CHECKING:  # for annotations only: typing_extensions takes ~2 ms to import
    import unittest

    from typing_extensions import Self

__all__ = ["PageReader", "Parent", "TextReader", "TextReplayerFactory"]

Parent = Union[AbstractNode, AbstractComponent, "unittest.TestCase"]
"""What a 2021 reader took as its context: a node, a component or a test case."""

Item = TypeVar("Item")


def _split_call(
    cls: str,
    parent_or_filename: Union[Parent, PathLike],
    name: Optional[str],
    filename: Optional[PathLike],
) -> Tuple[Optional[Parent], str, PathLike]:
    """(parent, name, filename) of ``cls(filename)`` or ``cls(parent, name, filename)``."""
    import os
    import unittest  # here: only a 2021 call that passes a test case needs it

    if name is None and filename is None and isinstance(parent_or_filename, (str, os.PathLike)):
        return None, cls.lower(), parent_or_filename  # today's call: cls(filename)
    if not isinstance(parent_or_filename, (AbstractNode, AbstractComponent, unittest.TestCase)):
        raise TypeError(
            f"{cls}({parent_or_filename!r}, {name!r}, {filename!r}): the first argument is "
            "the reader's parent, a node, a component (self in an endpoint or loop) or a "
            f"test case (self in a test), as in {cls}(self, 'reader', 'data.txt'); or give "
            f"the file name alone: {cls}('data.txt')."
        )
    if name is None or filename is None:
        raise TypeError(
            f"{cls}(parent, name, filename) needs all three: e.g. "
            f"{cls}(self, 'reader', 'data.txt'), or {cls}('data.txt') alone."
        )
    return parent_or_filename, name, filename


class _OpenReadClose(Generic[Item]):
    """``open()``, ``read()``, ``close()`` and ``with``, over a reader's iteration."""

    def __iter__(self) -> Iterator[Item]:  # pragma: no cover  # the reader's, first in the MRO
        raise NotImplementedError

    def _start(self) -> None:
        self._items: Optional[Iterator[Item]] = None
        self._closed = False

    def open(self) -> None:
        """Start reading at the top of the file (again, after a ``close()``)."""
        self.close()
        self._items, self._closed = iter(self), False

    def read(self) -> Optional[Item]:
        """The next item, or None at the end of the file or after ``close()``.

        The file is opened on the first ``read()`` if ``open()`` was not called.
        """
        if self._items is None and not self._closed:
            self.open()
        return None if self._items is None else next(self._items, None)

    def close(self) -> None:
        """Close the file now (safe to call twice)."""
        items, self._items, self._closed = self._items, None, True
        close = getattr(items, "close", None)
        if close is not None:
            close()  # the reader's generator closes its file

    def __enter__(self) -> Self:
        self.open()
        return self

    def __exit__(
        self,
        exc_type: Optional[Type[BaseException]],
        exc: Optional[BaseException],
        tb: Optional[TracebackType],
    ) -> None:
        self.close()


class TextReader(replayer.TextReader, _OpenReadClose[str]):
    """A text file's lines, one per ``read()``, as the 2021 release read them.

    Today's `snr.std_mods.io.TextReader`, made the 2021 way or today's, with
    the 2021 methods. ``read()`` gives the next line without its line ending
    (``""`` for an empty line), and None at the end of the file.

    Args:
        parent_or_filename: the 2021 context, a node, a component or a test
            case; or, today's way, the file name alone.
        name: the reader's name (2021 call).
        filename: the file (2021 call).
        encoding: the file's text encoding.

    Raises:
        ConfigError: the file does not exist.

    Example::

        with TextReader(self, "gps", "gps_log.txt") as reader:
            first = reader.read()        # 'GPGGA,...' or None for an empty file
    """

    def __init__(
        self,
        parent_or_filename: Union[Parent, PathLike],
        name: Optional[str] = None,
        filename: Optional[PathLike] = None,
        encoding: str = "utf-8",
    ) -> None:
        self.parent, self.name, path = _split_call("TextReader", parent_or_filename, name, filename)
        super().__init__(path, encoding)
        self._start()


class PageReader(replayer.PageReader, _OpenReadClose[Page]):
    """The pages of a recording, one per ``read()``, as the 2021 release read them.

    Today's `snr.std_mods.io.PageReader`, made the 2021 way or today's, with
    the 2021 methods. ``read()`` gives the next page of the file, and None at
    its end. It reads what `RecorderEndpointFactory` writes and what the 2021
    recorder wrote, a ``Page.serialize()`` text per line; bad lines are
    skipped and reported, as today's reader does.

    Args:
        parent_or_filename: the 2021 context, a node, a component or a test
            case; or, today's way, the file name alone.
        name: the reader's name (2021 call).
        filename: the recording (2021 call).

    Raises:
        ConfigError: the file does not exist.

    Example::

        with PageReader(self, "pages", "dive.jsonl") as reader:
            page = reader.read()          # a Page, or None at the end
    """

    def __init__(
        self,
        parent_or_filename: Union[Parent, PathLike],
        name: Optional[str] = None,
        filename: Optional[PathLike] = None,
    ) -> None:
        self.parent, self.name, path = _split_call("PageReader", parent_or_filename, name, filename)
        super().__init__(path)
        self._start()


class TextReplayerFactory(replayer.TextReplayerFactory):
    """The 2021 release's arguments for today's `snr.std_mods.io.TextReplayerFactory`.

    Stores each line of a text file as a page under ``output_data_name``, as
    fast as the node takes them, then stops the node if ``exit``. An empty
    file ends at once.

    Args:
        input_filename: the text file.
        output_data_name: the data key each line is stored under.
        exit: stop the node after the last line.
        period_s: seconds between lines (today's option; 0 in 2021).

    Example::

        TextReplayerFactory("commands.txt", "command", exit=True)
    """

    def __init__(
        self,
        input_filename: PathLike,
        output_data_name: DataKey,
        exit: bool = False,
        period_s: float = 0.0,
    ) -> None:
        super().__init__(input_filename, output_data_name, period_s, exit_when_done=exit)

    @property
    def input_filename(self) -> str:
        """The file (2021 name of ``filename``)."""
        return self.filename

    @property
    def output_data_name(self) -> DataKey:
        """The data key (2021 name of ``key``)."""
        return self.key

    @property
    def exit(self) -> bool:
        """Whether the node stops after the last line (2021 name of ``exit_when_done``)."""
        return self.exit_when_done
