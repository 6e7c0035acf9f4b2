"""MCAP as a recording format of the recorder, replayer and converter (``snr.recording_formats``).

The kernel's recorder and replayer find it by the entry point ``mcap`` in
SNR's ``pyproject.toml``; the work is done by `snr.extras.viz.mcap_files`.

Example::

    from snr.extras.viz.mcap_format import MCAP

    with open("dive.mcap", "wb") as file:
        writer = MCAP.writer(file)
        writer.write(Page("depth_m", 3.2, "urov", 1700000000.25))
        writer.close()
"""

from __future__ import annotations

import importlib
from typing import IO, Any, Callable, Dict, Iterator, Optional, Tuple

from snr.extras.viz.mcap_files import (
    COMPRESSION_PACKAGES,
    COMPRESSIONS,
    DEBIAN_HINT,
    INSTALL_HINT,
    MCAP_MAGIC,
    McapPageWriter,
    read_mcap_pages,
    require_mcap,
)
from snr.prelude import ConfigError, Page
from snr.std_mods.codec import PathLike

__all__ = ["MCAP", "McapFormat"]


class McapFormat:
    """MCAP files, written and read with the ``mcap`` package (``[mcap]`` extra).

    Example::

        MCAP.require("Writing dive.mcap")   # a ConfigError if mcap is not installed
    """

    magic: bytes = MCAP_MAGIC
    unit: str = "message"
    compressions: Tuple[str, ...] = COMPRESSIONS
    compression_packages: Dict[str, str] = COMPRESSION_PACKAGES
    install_hint: str = f"{INSTALL_HINT} ({DEBIAN_HINT})"

    def check(self, call: str, compression: Optional[str], append: bool) -> None:
        """Refuse an unknown ``compression``, and ``append`` (an MCAP file ends with its index).

        Example::

            MCAP.check("RecorderEndpointFactory('run.mcap'", "gzip", False)   # ConfigError
        """
        if compression is not None and compression not in self.compressions:
            raise ConfigError(
                f"{call}, compression={compression!r}): compression is for MCAP recordings, "
                f"one of {self.compressions}."
            )
        if append:
            raise ConfigError(
                f"{call}): append=True works for JSON lines only (an MCAP file ends "
                "with an index written when it closes). "
                "Record each run to its own .mcap file, or append to a .jsonl file."
            )

    def require(self, what: str, part: str = "writer", compression: str = "none") -> Any:
        """The ``mcap.<part>`` module, or a `ConfigError` naming the install command.

        ``what`` names the call that needs it, e.g. ``"RecorderEndpointFactory('dive.mcap')"``;
        a ``compression`` whose package is missing is named after it.
        """
        module = require_mcap(what, part)
        package = self.compression_packages.get(compression)
        if package is not None:
            try:
                importlib.import_module(package)
            except ImportError:
                raise ConfigError(
                    f"{what[:-1]}, compression={compression!r}) needs the {package} package: "
                    f"{self.install_hint}, or leave compression out"
                ) from None
        return module

    def writer(
        self, file: IO[bytes], compression: str = "none", flush: bool = True, sync: bool = False
    ) -> McapPageWriter:
        """A `McapPageWriter` on ``file``."""
        return McapPageWriter(file, compression, flush=flush, sync=sync)

    def read_pages(
        self, filename: PathLike, report: Callable[[int, str], None]
    ) -> Iterator[Tuple[int, Page, bool]]:
        """The pages of an MCAP file (`read_mcap_pages`)."""
        return read_mcap_pages(filename, report)


MCAP = McapFormat()
"""The MCAP recording format, the entry point ``mcap`` of ``snr.recording_formats``."""
