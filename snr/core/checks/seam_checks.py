"""A datastore or node core of the student's own, checked where it plugs in.

``Config(datastore=MyDatastore, node_core=MyNodeCoreFactory())`` replaces
the node's ``dict`` and its `NodeCoreEndpoint` (docs/assignments.md). A
mistake in either would show far away: a ``get`` that returns the data
instead of the page fails in some handler's ``page.data``; a core that does
not handle ``terminate`` leaves a node that never stops. So the node checks
them as it builds them, and says which method is missing or wrong:

* `check_seam_args`: the config was given a class to make a datastore with,
  and a factory for the core (not an instance, not a class);
* `checked_datastore`: the datastore has the four methods of `Datastore`;
  in DEBUG and TEST its answers are checked as they are given
  (`CheckedDatastore`: a Page or None, keys that are strings, a length);
* `checked_core`: the core is a component named ``node_core`` with a
  ``store_page_handler``; in DEBUG and TEST what that returns is checked,
  and a task the core does not handle is said once, in the log.

SNR's own datastore (a ``dict``) and core pass through untouched: the
default path pays nothing.

Example::

    store = checked_datastore(MyDatastore, node)   # MyDatastore(), checked
    core = checked_core(factory.get(node), factory, node)
"""

from __future__ import annotations

import inspect
from typing import Any, Callable, Iterator, List, Optional, Tuple

from snr.core.checks.student_code import describe_class
from snr.core.components import NODE_CORE_NAME
from snr.core.tasks import ADD_COMPONENT, REMOVE_COMPONENT, STORE_PAGES
from snr.prelude import (
    AbstractComponent,
    AbstractNode,
    ComponentError,
    ConfigError,
    DataKey,
    Datastore,
    Mode,
    Page,
    SNRError,
    SomeTasks,
    Task,
    TaskId,
    TaskType,
)
from snr.prelude.student_code import short_repr

__all__ = ["CheckedDatastore", "check_seam_args", "checked_core", "checked_datastore"]

DATASTORE_METHODS = ("__setitem__", "get", "__iter__", "__len__")
"""What a datastore must have (`Datastore`): ``dict`` has them all."""
CORE_TASKS: Tuple[Tuple[TaskId, str, str], ...] = (
    (TaskType.terminate, "terminate", "the node will not stop when a terminate task asks it to"),
    ((TaskType.event, STORE_PAGES), "STORE_PAGES", "pages from other nodes are never stored"),
    (TaskType.reload, "reload", "a reload (the console's, a file's change) does nothing"),
    ((TaskType.event, ADD_COMPONENT), "ADD_COMPONENT", "no component can be added as it runs"),
    ((TaskType.event, REMOVE_COMPONENT), "REMOVE_COMPONENT", "no component can be removed"),
)
"""The tasks a node core handles besides ``store_page``: id, name, what is lost without it."""
_SEE = "docs/assignments.md"


def _name(thing: Any) -> str:
    return getattr(thing, "__qualname__", None) or type(thing).__name__


def check_seam_args(datastore: Any, node_core: Any) -> None:
    """Raise a ConfigError when ``Config(datastore=..., node_core=...)`` got the wrong kind.

    Example::

        check_seam_args(MyDatastore(), None)
        # ConfigError: Config(datastore=...) takes what makes a datastore ...
    """
    if datastore is not None and not callable(datastore):
        raise ConfigError(
            f"Config(datastore=...) takes what makes a datastore, each node its own: the "
            f"class, as in Config(..., datastore={_name(datastore)}), not an instance of it "
            f"(got {datastore!r}). See {_SEE}."
        )
    if node_core is not None and (inspect.isclass(node_core) or not hasattr(node_core, "get")):
        what = "the class itself" if inspect.isclass(node_core) else repr(node_core)
        raise ConfigError(
            f"Config(node_core=...) takes a factory whose get(parent) builds the node core, "
            f"as in Config(..., node_core=MyNodeCoreFactory()), an instance of the factory; "
            f"got {what}. See {_SEE}."
        )


def checked_datastore(make: Callable[[], Any], node: AbstractNode) -> Datastore:
    """``make()``, the node's datastore, once it is known to have `Datastore`'s four methods.

    In DEBUG and TEST a datastore other than ``dict`` comes wrapped in a
    `CheckedDatastore`, which checks each answer.

    Raises:
        ConfigError: ``make()`` raised, or what it made lacks a method.

    Example::

        checked_datastore(dict, node)   # {}: SNR's own, as it is
    """
    if make is dict:
        return {}
    try:
        store = make()
    except SNRError:
        raise
    except Exception as error:
        raise ConfigError(
            f"Config(datastore={_name(make)}) could not make node {node.role!r}'s datastore: "
            f"{type(error).__name__}: {error}. The node calls it with no arguments."
        ) from error
    missing = [name for name in DATASTORE_METHODS if not callable(getattr(store, name, None))]
    if missing:
        raise ConfigError(
            f"{describe_class(type(store))}, the datastore of Config(datastore=...), has no "
            f"{', '.join(missing)}: a datastore needs {', '.join(DATASTORE_METHODS)} "
            f"(snr.prelude.Datastore says what each does; {_SEE})."
        )
    return store if node.mode is Mode.DEPLOYED else CheckedDatastore(store)


class CheckedDatastore:
    """A student's datastore, each answer checked to be of the kind a node expects.

    Writes go straight through; ``get`` must give a `Page` (of the key
    asked) or None, ``__iter__`` strings, ``__len__`` a number. A wrong
    answer is a ComponentError that names the method and says what it should
    have given. Used in DEBUG and TEST only.

    Example::

        store = CheckedDatastore(MyDatastore())
        store.get("depth")      # ComponentError if MyDatastore.get returned 3.2
    """

    __slots__ = ("store",)

    def __init__(self, store: Datastore) -> None:
        self.store = store

    def _wrong(self, call: str, answer: Any, should: str) -> ComponentError:
        return ComponentError(
            f"{describe_class(type(self.store))}, the datastore: {call} returned "
            f"{short_repr(answer)} ({type(answer).__name__}); it should return {should} ({_SEE})."
        )

    def __setitem__(self, key: DataKey, page: Page) -> None:
        self.store[key] = page  # writes go straight through

    def get(self, key: DataKey) -> Optional[Page]:
        """The student's ``get(key)``, checked."""
        page = self.store.get(key)
        if page is not None and not (isinstance(page, Page) and page.key == key):
            should = f"the whole Page stored under {key!r} (not its data), or None"
            raise self._wrong(f"get({key!r})", page, should)
        return page

    def __iter__(self) -> Iterator[DataKey]:
        keys: List[Any] = list(self.store)
        if not all(isinstance(key, str) for key in keys) or len(set(keys)) != len(keys):
            raise self._wrong("iter()", keys, "each key that has a page (a str), once")
        return iter(keys)

    def __len__(self) -> int:
        count = len(self.store)
        if not isinstance(count, int) or count < 0:
            raise self._wrong("len()", count, "how many keys have a page")
        return count

    def __repr__(self) -> str:
        return repr(self.store)


def checked_core(core: Optional[AbstractComponent], factory: Any, node: AbstractNode) -> Any:
    """``core``, once it is known to be a node core; checked as it runs in DEBUG and TEST.

    Raises:
        ConfigError: ``factory.get()`` gave None, or a component not named
            ``node_core``, or one without a ``store_page_handler``.

    Example::

        core = checked_core(factory.get(node), factory, node)
    """
    made = f"{_name(type(factory))}.get(), the node_core of the Config,"
    if core is None:
        raise ConfigError(f"{made} returned None: return the node core endpoint it builds.")
    if core.name != NODE_CORE_NAME or not callable(getattr(core, "store_page_handler", None)):
        raise ConfigError(
            f"{made} built {describe_class(type(core))}, named {core.name!r}: a node core is "
            f"named {NODE_CORE_NAME!r} and has a store_page_handler(task, key). Extend "
            f"snr.core.NodeCore, which names it, and write that method ({_SEE})."
        )
    if node.mode is Mode.DEPLOYED or type(core).__module__ == "snr.core.node":
        return core  # SNR's own: as it is
    for task_id, name, lost in CORE_TASKS:
        if task_id not in core.task_handlers:
            warning = "The node core %s handles no %s task: %s (%s)."
            node.log.warning(warning, type(core).__name__, name, lost, _SEE)
    # An instance attribute: the node reads core.store_page_handler after this.
    core.store_page_handler = _CheckedStore(core.store_page_handler)  # type: ignore[attr-defined]
    return core


class _CheckedStore:
    """A node core's ``store_page_handler``, what it returns checked: None, or one ``process_data``.

    A callable object, not a function, so that a failure in it names the
    student's method and line: ``__func__`` and ``__self__`` are the method's.
    """

    def __init__(self, handler: Any) -> None:
        self.handler = handler
        self.__func__ = getattr(handler, "__func__", handler)
        self.__self__ = getattr(handler, "__self__", None)
        self.__qualname__ = _name(self.__func__)

    def __call__(self, task: Task, key: TaskId) -> SomeTasks:
        result = self.handler(task, key)
        if result is None or (isinstance(result, Task) and result.type is TaskType.process_data):
            return result
        raise ComponentError(
            f"{self.__qualname__} returned {short_repr(result)} for the page of {task.name!r}: "
            "a node core's store_page_handler returns the page's process_data task, "
            "Task(TaskType.process_data, page.key, [page]), or None; never a list, "
            f"and never the store_page task itself ({_SEE})."
        )
