"""The helpers that explain mistakes: read these second, after `snr.core`.

`snr.core` runs a node; what is here watches the run for a student's mistakes
and puts them into words. The core calls in at a few places (a check when a
handler is registered or a component is added, the words of an error once
something went wrong), and a first reading of the runtime can take each such
call as "check this" and come back here for the how:

* ``explain.py``: the words of the errors a node raises or logs, e.g. a handler
  that returns something that is not a Task, swapped arguments, or a loop
  thread that calls a method only the node's thread may call (every mode);
* ``failures.py``: a handler or loop that failed, or a slow handler, logged in
  words; outside DEPLOYED mode the first failure stops the node (every mode);
* ``repeats.py``: a failure repeated over and over, logged in full three times,
  then counted (`RepeatFilter`; components use it too, from ``snr.core.logs``);
* ``component_log.py``: a reload that keeps the old component running, a removal
  refused, a component's ``halt()`` that raised, each logged in words (every mode);
* ``life_cycle.py``: a node run twice, a loop started twice, a ``store_page``
  task without its page (every mode);
* ``call_checks.py``: a constructor or task builder called with the wrong
  arguments (``Config``, the runners, ``tasks.event``, ``store_data``), shown
  as written, with where and the signature to follow (every mode);
* ``handler_checks.py``: a handler registered under a wrong task id, or with
  the wrong parameters, refused when it is registered (every mode);
* ``os_errors.py``: an OS error (a port in use, a missing serial device) in
  words, for the comms and consoles;
* ``class_checks.py``: reads a component's class once, when it is added, for
  names SNR uses and work that can have no effect (DEBUG and TEST);
* ``node_checks.py``: wires the class checks and the DEBUG helpers below into a
  node; `Node` imports it only when its mode is not DEPLOYED;
* ``key_hints.py``: a data key read but never stored (DEBUG);
* ``wiring_checks.py``: an event nothing handles, a handler nothing reaches (DEBUG);
* ``runner_checks.py``: a runner built and never run, said at exit (not in tests);
  a command line that names no role, answered with the roles;
* ``datastore_guard.py``: ``node.datastore`` as components see it, a read-only
  view that names ``store_data`` when written (every mode);
* ``seam_checks.py``: a datastore or node core of the student's own
  (``Config(datastore=..., node_core=...)``), checked where it plugs in;
* ``top_level.py``: an SNR error nobody caught, printed with the student's frames
  only (``import snr`` sets it as ``sys.excepthook``);
* ``watchdog.py``: a node stuck without a word, a loop flooding the queue (DEBUG);
* ``step_mode.py``: a console pauses the node and runs its tasks one at a time
  (every mode: a debugger for event-driven code);
* ``profiler.py``: how often each handler and loop ran and for how long
  (DEBUG, TEST, or ``Config(profile=True)``).
* ``student_code.py``, ``error_text.py``: where the student's code is (source
  lines, tracebacks, another thread's line) and what Python said about an
  error, for the messages of all of the above.

The package itself imports none of them, so importing one of them does not
load the others. These modules may import `snr.core` and `snr.prelude`; none
of them imports `snr.core.node`.

Example::

    from snr.core.checks.watchdog import Watchdog
    from snr.core.checks.explain import slow_handler_text
"""

from typing import List

__all__: List[str] = []  # import names from the modules above, e.g. snr.core.checks.watchdog
