"""Extension points: how the kernel finds what an extra provides, by group and name.

The kernel never imports an extra: an extra declares what it provides as an
entry point in ``pyproject.toml`` (as gpiozero's pin factories)::

    [project.entry-points."snr.recording_formats"]
    mcap = "snr.extras.viz.mcap_format:MCAP"

and the kernel asks for it with `load` when it is needed (after editing them,
``pip install -e .`` again). The groups, `GROUPS`, are in docs/design.md
("Extras and extension points").

Example::

    from snr.core.plugins import load

    command = load("snr.commands", "demo", "python -m snr demo")
    command.run(args)
"""

from __future__ import annotations

import functools
from typing import TYPE_CHECKING, Any, Dict, Tuple

from snr.prelude import ConfigError

if TYPE_CHECKING:
    from importlib import metadata

__all__ = ["GROUPS", "load", "names"]

GROUPS: Dict[str, str] = {
    "snr.commands": "the `python -m snr` commands kept in extras",
    "snr.console_transports": "the ways snr-console reaches a node besides TCP",
    "snr.console_commands": "the console commands kept in extras",
    "snr.recording_formats": "the recording formats besides JSON lines",
    "snr.json_backends": "the faster JSON backends of the page codec",
}
"""The extension points of the kernel: entry point group -> what an extra provides there."""


@functools.cache
def _entry_points(group: str) -> Tuple[metadata.EntryPoint, ...]:
    from importlib import metadata  # only now: it costs milliseconds

    found: Any = metadata.entry_points()
    if hasattr(found, "select"):  # Python 3.10 and later
        points = tuple(found.select(group=group))
    else:  # Python 3.9: a dict of groups
        points = tuple(found.get(group, ()))
    first: Dict[str, metadata.EntryPoint] = {}
    for point in points:  # an entry point installed twice: the first one found wins
        first.setdefault(point.name, point)
    return tuple(first.values())


def names(group: str) -> Tuple[str, ...]:
    """The names installed packages provide in ``group``, sorted (nothing is imported).

    Example::

        names("snr.recording_formats")   # ('mcap',)
    """
    return tuple(sorted(point.name for point in _entry_points(group)))


def load(group: str, name: str, what: str) -> Any:
    """The object an extra provides under ``name`` in ``group``, imported now.

    Args:
        group: the entry point group, one of `GROUPS`.
        name: the name in that group, e.g. ``"mcap"``.
        what: what needs it, for the error, e.g. ``"python -m snr demo"``.

    Raises:
        ConfigError: no installed package provides ``name``, or it cannot be imported.

    Example::

        client = load("snr.console_transports", "zenoh", "snr-console --zenoh")
    """
    for point in _entry_points(group):
        if point.name == name:
            try:
                return point.load()
            except ImportError as error:
                raise ConfigError(
                    f"{what} needs {point.value}, which could not be imported: {error}. "
                    "Install the package it names, e.g. with the pip extra its docs page gives."
                ) from error
    known = ", ".join(names(group)) or "none"
    raise ConfigError(
        f"{what} needs {name!r} from the entry point group {group!r} ({GROUPS.get(group, '')}), "
        f"which no installed package provides (it has: {known}). SNR's extras register "
        "theirs when SNR is installed: in a copy of SNR's source run `pip install -e .` "
        "again (after any change to pyproject.toml too)."
    )
