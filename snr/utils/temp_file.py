"""`TempFile`: the path `SNRTestCase.temp_file` returns, a ``str`` with the 2021 helpers."""

from __future__ import annotations

import os
from typing import IO, TYPE_CHECKING, Any, Optional, Tuple

from snr.utils.expector import fail

if TYPE_CHECKING:  # unittest costs ~10 ms to import
    import unittest

__all__ = ["TempFile"]


class TempFile(str):
    """The path of a file in a fresh temp folder; a ``str`` with test helpers.

    Example::

        path = self.temp_file(".jsonl")            # use it as a str path
        RecorderEndpointFactory(path, ["depth"])

        with self.temp_file("out.txt") as f:       # 2021 style
            with f.open() as text:
                text.write("hello")
            f.assertExists()
        # leaving the block fails unless the file exists, then removes it
    """

    testcase: Optional[unittest.TestCase]
    cleanup: bool

    def __new__(
        cls,
        path: str,
        testcase: Optional[unittest.TestCase] = None,
        cleanup: bool = True,
    ) -> TempFile:
        self = super().__new__(cls, path)
        self.testcase = testcase
        self.cleanup = cleanup
        return self

    @property
    def path(self) -> str:
        """The file's path, as a plain ``str``."""
        return str.__str__(self)

    def __reduce__(self) -> Tuple[Any, ...]:
        # sent to another process as the plain path: the test case stays here
        return (str, (self.path,))

    def open(self, mode: str = "w", encoding: str = "utf-8") -> IO[Any]:
        """Open the file, for writing text unless ``mode`` says otherwise.

        Example::

            with temp.open() as f:
                f.write("line\\n")
        """
        return open(self.path, mode, encoding=None if "b" in mode else encoding)

    def exists(self) -> bool:
        """True when the file exists."""
        return os.path.exists(self.path)

    def assertExists(self) -> None:
        """Fail the test unless the file exists."""
        if not self.exists():
            fail(self.testcase, f"The temp file {self.path!r} does not exist; nothing wrote it.")

    def assertDoesNotExist(self) -> None:
        """Fail the test if the file exists."""
        if self.exists():
            fail(self.testcase, f"The temp file {self.path!r} exists, but should not.")

    def remove(self) -> None:
        """Delete the file now, if it exists."""
        try:
            os.remove(self.path)
        except FileNotFoundError:
            pass

    def __enter__(self) -> TempFile:
        return self

    def __exit__(self, exc_type: Any, *rest: Any) -> None:
        if exc_type is None:
            self.assertExists()
        if self.cleanup:
            self.remove()
