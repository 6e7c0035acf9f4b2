"""The helpers that explain mistakes: read these second, after `snr.core`.

The core calls in at a few places ("check this", "word that failure"); the how
is here, one module per kind of mistake (docs/design.md lists them). A DEPLOYED
node never loads ``node_checks.py`` and the DEBUG checks it wires in. The
package imports none of its modules; none of them imports `snr.core.node`.

Example::

    from snr.core.checks.watchdog import Watchdog
    from snr.core.checks.explain import slow_handler_text
"""

from typing import List

__all__: List[str] = []  # import names from the modules above, e.g. snr.core.checks.watchdog
