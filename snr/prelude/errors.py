"""The exceptions SNR raises: every one of them, in one tree.

Every SNR error is an :class:`SNRError`, so one ``except SNRError`` catches them
all. Each message says what went wrong (naming your file and line), why, and
what to do (docs/errors.md).

Example::

    try:
        snr.CliRunner(components, ["main.py", "rover"]).run()
    except snr.SNRError as e:
        print(e)

The tree::

    SNRError
     +-- ConfigError          a config, role or factory list is wrong
     +-- ComponentError       an endpoint, loop or factory is written wrongly
     |    +-- MissingSuperInitError  __init__ did not call super().__init__(...)
     +-- HandlerError         a task handler raised or returned a wrong value
     +-- LoopError            a loop's setup() or loop() raised
     +-- NodeStateError       a node was used in the wrong life-cycle state
     +-- ThreadSafetyError    node state was touched from the wrong thread
     +-- DatastoreWriteError  a component wrote its node's datastore (use store_data)
     +-- CommsError           talking to another node failed
     |    +-- WireFormatError  a frame on the wire is malformed
     |    +-- NotSerializableError  data cannot be sent between nodes
     |    +-- ConsoleConnectionError  a console cannot reach its node, or lost it
     +-- RemovedApiError      a 2021 name was used whose job is done another way now
"""

from __future__ import annotations

__all__ = ["CommsError", "ComponentError", "ConfigError", "ConsoleConnectionError"]
__all__ += ["DatastoreWriteError", "HandlerError", "LoopError", "MissingSuperInitError"]
__all__ += ["NodeStateError", "NotSerializableError", "RemovedApiError", "SNRError"]
__all__ += ["ThreadSafetyError", "WireFormatError"]


class SNRError(Exception):
    """Root of every error SNR raises on purpose.

    Example::

        except snr.SNRError as e: print("SNR says:", e)
    """


class ConfigError(SNRError):
    """A config is wrong: unknown role, empty role, duplicate names.

    Example::

        Config({"robot": []}).get("robot")   # raises ConfigError
    """


class ComponentError(SNRError):
    """An endpoint, loop or factory is written in a way SNR cannot use.

    Example: a handler registered under a bare string key instead of a TaskType.
    """


class MissingSuperInitError(ComponentError, AttributeError):
    """A component's ``__init__`` used the component before ``super().__init__``.

    It is also an ``AttributeError``, so ``hasattr`` keeps working.

    Example::

        class Beeper(Endpoint):
            def __init__(self, factory, parent):
                self.task_handlers = {}          # MissingSuperInitError: too early
                super().__init__(factory, parent, "beeper")
    """


class HandlerError(SNRError):
    """A task handler raised an exception or returned something not a Task.

    Example: ``return 5`` from a handler; the message names the handler.
    """


class LoopError(SNRError):
    """A loop's ``setup()`` or ``loop()`` raised; the loop has stopped.

    Example: ``raise Exception("High velocity impact")`` inside ``loop()``.
    """


class NodeStateError(SNRError):
    """A node (or loop) was asked to do something its life-cycle state forbids.

    Example: calling ``node.loop()`` twice.
    """


class ThreadSafetyError(SNRError):
    """Node state was changed from a thread that does not own it.

    Example: a loop thread calling ``node.execute_task(...)`` directly instead of
    ``self.schedule(...)``.
    """


class DatastoreWriteError(SNRError):
    """Something other than the node tried to change a node's datastore.

    Example: ``self.parent.datastore["depth"] = 2.0`` in a handler or loop,
    where ``self.store_data("depth", 2.0)`` stores it.
    """


class CommsError(SNRError):
    """Talking to another node failed: port in use, peer refused, bad data.

    Example: two nodes both trying to serve on port 9000.
    """


class WireFormatError(CommsError):
    """A frame read from another node is malformed; it is dropped.

    Example: a length header larger than the maximum frame size.
    """


class NotSerializableError(CommsError):
    """A page's data cannot be turned into JSON to send to another node.

    Example: storing a ``set`` or a custom object under a forwarded key.
    """


class ConsoleConnectionError(CommsError):
    """A console could not connect to a node, lost it, or was turned away.

    Example::

        try:
            RemoteConsole("127.0.0.1", 9123).connect()
        except ConsoleConnectionError as e:
            print(e)     # "Could not connect ... connection refused. Is the node running..."
    """


class RemovedApiError(SNRError):
    """A name of the 2021 release was used whose job SNR now does another way.

    The message names the replacement.

    Example::

        try:
            SocketsLoopFactory(("localhost", 9000), ["depth"])
        except RemovedApiError as e:
            print(e)   # ... replaced by SocketsPair(server_tuple).client(keys) ...
    """
