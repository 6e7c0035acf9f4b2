"""How to install SNR and its extras: the one place that writes the ``pip`` lines.

SNR is published as ``snr-robotics`` (``snr`` on the index is another project)
and imported as ``snr``.

Example::

    from snr.prelude.install import install_hint

    raise ComponentError(f"Zenoh is not installed: {install_hint('zenoh')}")
    # ... Zenoh is not installed: pip install 'snr-robotics[zenoh]'
"""

from __future__ import annotations

__all__ = ["DISTRIBUTION", "install_hint", "upgrade_hint"]

DISTRIBUTION = "snr-robotics"
"""SNR's name on the package index, what ``pip install`` is given (``import snr`` stays)."""


def install_hint(extra: str = "") -> str:
    """The command that installs SNR with the optional ``extra`` (none: SNR alone).

    The brackets are quoted, as shells such as zsh would read them as a pattern.

    Example::

        install_hint("zenoh")   # "pip install 'snr-robotics[zenoh]'"
        install_hint()          # "pip install snr-robotics"
    """
    if not extra:
        return f"pip install {DISTRIBUTION}"
    return f"pip install '{DISTRIBUTION}[{extra}]'"


def upgrade_hint() -> str:
    """The command that upgrades SNR to its newest release.

    Example::

        upgrade_hint()  # "pip install -U snr-robotics"
    """
    return f"pip install -U {DISTRIBUTION}"
