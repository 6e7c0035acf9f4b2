"""The helpers that explain mistakes: read these second, after `snr.core`.

The core calls in at a few places ("check this", "word that failure"); the how is here:

* ``explain.py``: the words of the errors a node raises or logs;
* ``failures.py``, ``repeats.py``: a failed handler or loop in words, logged
  (repeats counted); outside DEPLOYED the first failure stops the node;
* ``life_cycle.py``: reloads, removals, a node run twice;
* ``call_checks.py``, ``handler_checks.py``: wrong arguments and wrong
  ``task_handlers`` entries, refused where they are written;
* ``os_errors.py``: a port in use, a missing serial device;
* ``class_checks.py``, ``key_hints.py``, ``wiring_checks.py``, ``watchdog.py``:
  silent mistakes (DEBUG, and TEST for the class checks), wired into a node by
  ``node_checks.py``, which a DEPLOYED node never loads;
* ``runner_checks.py``: a runner never run, a command line without a role, an
  SNR error nobody caught (``sys.excepthook``);
* ``read_only.py``: the datastore and page data as components see them;
* ``seam_checks.py``: a datastore or node core of the student's own
  (``Config(datastore=..., node_core=...)``), checked where it plugs in;
* ``step_mode.py``, ``profiler.py``: a console's pause and step; handler timings;
* ``student_code.py``, ``error_text.py``: where the student's code is, and what
  Python said, for all of the above.

The package imports none of them; none of them imports `snr.core.node`.

Example::

    from snr.core.checks.watchdog import Watchdog
    from snr.core.checks.explain import wrong_thread_error
"""

from typing import List

__all__: List[str] = []  # import names from the modules above, e.g. snr.core.checks.watchdog
