"""Layer 0 of SNR: data types, type aliases, errors and interfaces.

Nothing here imports from the rest of ``snr``; the package gives each module's
``__all__`` (``from snr.prelude import *``, thesis listing A.1).

Example::

    from snr.prelude import Page, Task, TaskType
"""

# ruff: noqa: F403  (each module's names, by its own __all__)
from typing import List

from snr.prelude import abstract, errors, names, page, serializable, task
from snr.prelude.abstract import *
from snr.prelude.errors import *
from snr.prelude.names import *
from snr.prelude.page import *
from snr.prelude.serializable import *
from snr.prelude.task import *

__all__: List[str] = []
__all__ += abstract.__all__
__all__ += errors.__all__
__all__ += names.__all__
__all__ += page.__all__
__all__ += serializable.__all__
__all__ += task.__all__
