"""Tools around SNR that no node runs: the documentation builder.

Nothing in the layers (``snr.prelude``, ``snr.core``, ``snr.std_mods``,
``snr.utils``) imports from here, and ``import snr`` does not load it. It
ships inside the package so that ``python -m snr docs`` works after a plain
``pip install``.

Example::

    python -m snr docs --build-only     # snr.tools.docsite
"""

from typing import List

__all__: List[str] = []
