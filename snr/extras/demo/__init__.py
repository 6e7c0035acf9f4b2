"""``python -m snr demo``: the underwater vehicle (UROV) of thesis 5.1, simulated.

Two nodes, each in its own process, talk over TCP on 127.0.0.1: *topside*
(a scripted pilot on a simulated game pad, and a live telemetry display) and
*urov* (thrusters driven through a simulated motor board on a serial
pseudo-terminal, and noisy depth and heading sensors). It ships inside the
``snr`` package, so it runs after a plain ``pip install``;
``examples/urov/`` runs the same system from the command line.

* `snr.extras.demo.urov`: the components and the simulated hardware;
* `snr.extras.demo.system`: which components each node runs (thesis listing 5.1);
* `snr.extras.demo.run`: the demo itself: ports, the banner, quiet or verbose logs;
* ``--sim``'s rover is the first lesson's solution,
  `snr.extras.lessons.l01_wall_follower.solution`.

Example::

    from snr.extras.demo import run_demo
    run_demo(seconds=5)        # what `python -m snr demo --seconds 5` does
"""

from snr.extras.demo.run import run_demo, run_sim_demo
from snr.extras.demo.system import make_components

__all__ = ["make_components", "run_demo", "run_sim_demo"]
