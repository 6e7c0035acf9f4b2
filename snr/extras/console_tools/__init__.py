"""The console's tools beyond its core: step mode, ``echo`` and ``hz``, and the local console.

The kernel's console loads this package through the entry point group
``snr.console_commands`` when a console starts; `step` registers ``pause``,
``step`` and ``resume``, `watches` ``echo KEY`` and ``hz KEY`` (like ``ros2
topic echo`` and ``ros2 topic hz``), with the kernel's `command`, so a
student sees them in ``help`` like any other.
`LocalConsoleFactory` (``local``, also ``snr.LocalConsoleFactory``) reads the
console's commands from the node's own terminal.

Example::

    from snr.extras.console_tools import LocalConsoleFactory

    config = Config({"robot": [MotorFactory(), LocalConsoleFactory()]})
"""

from snr.extras.console_tools import step, watches
from snr.extras.console_tools.local import LocalConsole, LocalConsoleFactory

__all__ = ["LocalConsole", "LocalConsoleFactory", "step", "watches"]
