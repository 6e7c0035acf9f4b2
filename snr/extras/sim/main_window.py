"""`run_in_window`: the simulator's window on the main thread, the node on another.

macOS lets only a program's main thread open a window and read its events
(a rule of its window system, which SDL and so pygame follow); a window
opened by a loop's thread fails or hangs there. Linux and Windows do not
mind. So a program that wants a window on every platform keeps the main
thread for the window and runs the node beside it: `run_in_window` does
that, and ``python -m snr demo --sim`` uses it everywhere. The node is the
same one a runner would build; only `SimViewFactory` is left out of its
components, because this function draws what it describes instead.

Example::

    view = SimViewFactory(world)                  # the window's settings
    config = Config({"sim": [SimRobotFactory(world), WallFollowerFactory()]})
    node = run_in_window("sim", config, view)     # returns once the node has stopped
"""

from __future__ import annotations

import threading
from typing import List

from snr.core import Node, tasks
from snr.extras.sim.components import SimViewFactory
from snr.extras.sim.draw import NO_PICTURES, import_pygame, open_window, window_closed
from snr.prelude import AbstractConfig, ComponentError, Role

__all__ = ["run_in_window"]


def run_in_window(role: Role, config: AbstractConfig, view: SimViewFactory) -> Node:
    """Run the node of ``role`` on a thread; draw ``view``'s window on this one until it stops.

    Call it from the main thread. Closing the window or Ctrl-C stops the
    node; the window's arrow keys / WASD go to ``view.keyboard`` (teleop).
    Without pygame the node runs here, undrawn, after a warning saying how to
    get the window. Returns the node once it has stopped.

    Raises:
        What ``node.loop()`` raised (a handler's error in DEBUG/TEST mode).

    Example::

        node = run_in_window("sim", config, SimViewFactory(world))
        node.terminate_reason       # 'simulator window closed', say
    """
    node = Node(role, config)
    try:
        pygame = import_pygame()
    except ComponentError:
        node.log.warning("%s", NO_PICTURES)
        node.loop()
        return node
    failures: List[BaseException] = []

    def run_node() -> None:
        try:
            node.loop()
        except BaseException as error:  # raised again on the main thread, below
            failures.append(error)

    scene = view.scene(pygame)
    window = open_window(pygame, scene.view.size_px, view.title)
    thread = threading.Thread(target=run_node, name=f"snr-{role}-node")
    thread.start()
    try:
        while thread.is_alive():
            scene.draw(node.get_data, window)
            pygame.display.flip()
            if window_closed(pygame, view.keyboard):
                node.schedule(tasks.terminate("simulator window closed"))
            thread.join(1.0 / view.rate_hz)  # one frame's time, or less if the node stops
    except KeyboardInterrupt:
        node.set_terminate_flag("interrupted by user (Ctrl-C)")
    finally:
        pygame.display.quit()
        _join(thread, node)
    if failures:
        raise failures[0]
    return node


def _join(thread: threading.Thread, node: Node) -> None:
    """Wait for the node's thread; ask it to stop first if it has not (the window went away)."""
    if thread.is_alive() and not node.is_terminated():
        node.set_terminate_flag("simulator window closed")
    thread.join(5.0)  # a node stops its loops within a second each
