"""The UROV's components, as the ``urov`` module listing 5.1 imports.

Listing 5.1 starts with ``from urov import *``: run from this folder, that is
this file. The code itself lives in the package, ``snr/extras/demo/urov.py``, so that
``python -m snr demo`` works from an installed SNR; read it there.

Example::

    from urov import *   # SensorReaderFactory, ControlsProcessorFactory, ...
"""

from snr.extras.demo.urov import *
from snr.extras.demo.urov import __all__  # noqa: F401
