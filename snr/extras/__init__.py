"""SNR's extras: the optional parts, one package each, outside the kernel.

The kernel (``snr.prelude``, ``snr.core``, ``snr.std_mods``, ``snr.utils``)
is what a student reads; an *extra* is a part they may never open: Zenoh,
serial links and boards, viewing (MCAP, the live view), the game
controller, the simulator, the graph, the demo, the docs builder, a faster
JSON backend (orjson) and the names of the 2021 release. Extras ship in the
same package; only the third-party packages some of them need are pip
extras (e.g. ``pip install 'snr-robotics[zenoh]'``).

``import snr`` loads none of them. The kernel never imports an extra: an
extra uses the kernel's public names, and plugs into the kernel only
through the entry points declared in ``pyproject.toml``
(`snr.core.plugins`; ``docs/design.md``, "Extras and extension points").
The names students use are also in ``snr`` (``from snr import *``),
loaded on first use.

Example::

    from snr.extras.zenoh import ZenohCommsFactory   # or: from snr import ZenohCommsFactory
"""

from typing import List

__all__: List[str] = []
