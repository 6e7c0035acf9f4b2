"""How the node puts a student's mistakes into words (docs/errors.md shows each).

Example::

    slow_handler_text(motor.forward, tasks.event("forward"), 0.5)
    # "Task handler Motor.forward (robot.py:14) took 0.500 s handling (event, 'forward'). ..."
"""

from __future__ import annotations

import ast
import inspect
import logging
import threading
from typing import Any, List, NoReturn, Optional, Set

from snr.core.checks.call_checks import bad_data_key, page_as_data, wrong_call
from snr.core.checks.error_text import PAGE_IN_A_HANDLER, exception_text, short_repr
from snr.core.checks.student_code import (
    caller_block,
    caller_location,
    code_name,
    code_of,
    def_block,
    describe_callable,
    describe_class,
    failure_frames,
    is_runtime_file,
    short_path,
    source_block,
    source_node,
    walk_own,
)
from snr.prelude import (
    AbstractComponent,
    AbstractConfig,
    AbstractFactory,
    AbstractLoop,
    AbstractNode,
    ComponentError,
    ConfigError,
    HandlerError,
    LoopError,
    MissingSuperInitError,
    Page,
    SNRError,
    Task,
    TaskHandler,
    ThreadSafetyError,
)
from snr.prelude.abstract import explain_abstract_error  # loads abstract_errors when used
from snr.prelude.task import format_task

__all__ = ["CORE_REFUSED", "bad_result_error", "check_component_args", "check_loop_class"]
__all__ += ["check_node_args", "check_page_args", "component_without_init"]
__all__ += ["factory_without_init", "handler_failure", "handlers_before_init", "log_name_taken"]
__all__ += ["loop_failure", "name_taken_error", "not_stopped_text", "raise_get_failure"]
__all__ += ["page_hint", "reload_failure", "returning_lines", "slow_handler_text"]
__all__ += ["start_failure", "used_before_init", "warn_get_returned_none"]
__all__ += ["wrong_get_result_error", "wrong_thread_error"]


def _fix(error: BaseException, deployed: bool, what: str, kept: str, fix: str) -> str:
    """The last line of a failure: the node goes on (DEPLOYED), or how to fix ``what``."""
    if deployed:
        return f"The node keeps running{kept}."
    if isinstance(error, SNRError):
        return f"Fix the {what} as the message above says."
    return fix


def handler_failure(
    handler: TaskHandler,
    task: Task,
    component: Optional[AbstractComponent],
    error: Exception,
    deployed: bool,
    run_size: int = 1,
) -> HandlerError:
    """The HandlerError for ``handler`` raising ``error`` on ``task`` (first of ``run_size``).

    Example::

        handler_failure(endpoint.on_depth, task, endpoint, ZeroDivisionError(), False)
        # Task handler Depth.on_depth (robot.py:30) of endpoint 'depth' raised ...
    """
    where = ""
    if component is not None:
        kind = "loop" if isinstance(component, AbstractLoop) else "endpoint"
        where = f" of {kind} {component.name!r}"
    handling = f"the task {format_task(task, values='none')}"
    if run_size > 1:
        handling = f"a run of {run_size} tasks given to it at once, the first being {handling}"
    values: object = task.val_list  # a task built by hand may hold anything
    if isinstance(values, list) and len(values) == 1 and isinstance(values[0], Page):
        carrying = (
            f"carrying the page {values[0].key!r} with data {short_repr(values[0].data, 200)}"
        )
    else:
        carrying = f"with values {short_repr(values, 200)}"
    if not isinstance(values, list):
        carrying += (
            f". Its val_list is {short_repr(values, 60)} ({type(values).__name__}), not a list: "
            "whoever built the task must pass the values in a list, e.g. "
            f"Task(TaskType.{task.type.name}, {task.name!r}, [value])"
        )
    fix = _fix(
        error,
        deployed,
        "handler",
        "",
        "Fix the handler, or catch the error in it if it can happen in normal use "
        "(in Mode.DEPLOYED the node logs it and keeps running).",
    )
    failure = HandlerError(
        f"Task handler {describe_callable(handler)}{where} raised "
        f"{page_hint(error, exception_text(error))}\nwhile handling {handling} {carrying}."
        f"{failure_frames(error)}\n{fix}"
    )
    failure.__cause__ = error
    return failure


def _bad_result_hint(result: Any) -> str:
    """A hint for the likely slip behind a bad return value (or "")."""
    items = result if isinstance(result, (list, tuple)) else []
    if isinstance(result, tuple) and all(isinstance(t, Task) for t in items):
        return " Return a list, [task1, task2], not a tuple."
    if isinstance(result, Page):
        return " To store a page, return tasks.store_page(page)."
    if isinstance(result, bool):
        return " Return None when there is nothing to do."
    if inspect.isgenerator(result):
        return " A handler cannot yield its tasks: return them in a list."
    if any(t is None for t in items):
        return " Leave None out of the list."
    if any(isinstance(t, (list, tuple)) for t in items):
        return " Return one flat list of Tasks (join lists with + or extend)."
    return ""


def bad_result_error(result: Any, handler: TaskHandler, task: Task) -> HandlerError:
    """The HandlerError for a handler that returned something other than tasks, at its return.

    Example::

        bad_result_error(42, doubler.double, task)
        # Task handler Doubler.double returned 42 (int) at robot.py:12 while handling ...
        #   File "/home/student/rov/robot.py", line 12, in Doubler.double (defined at line 11)
        #     return task.val_list[0].data * 2
    """
    fix = (
        f"A handler must return a Task, a list of Tasks, or None.{_bad_result_hint(result)} "
        "To store a value, return self.store_data_task(key, value); to announce "
        "something, return tasks.event('name', [value])."
    )
    returned = f"returned {short_repr(result)} ({type(result).__name__})"
    if isinstance(result, list):
        index, bad = next((i, t) for i, t in enumerate(result) if not isinstance(t, Task))
        returned = (
            f"returned a list whose item {index} is {short_repr(bad)} ({type(bad).__name__}),"
            " not a Task,"
        )
    handling = f"while handling {format_task(task, values='none')}"
    code, lines = code_of(handler), returning_lines(handler, result)
    if code is None or not lines:
        return HandlerError(
            f"Task handler {describe_callable(handler)} {returned} {handling}. {fix}"
        )
    name = code_name(code, getattr(handler, "__qualname__", code.co_name))
    short = short_path(code.co_filename)
    at = f"at {short}:{lines[0]}"
    if len(lines) > 1:  # the source cannot tell which: show each
        at = f"at one of its returns, {short}:{', '.join(str(n) for n in lines)},"
    context = f" (defined at line {code.co_firstlineno})"
    blocks = "\n".join(source_block(code.co_filename, n, name, context) for n in lines)
    return HandlerError(f"Task handler {name} {returned} {at} {handling}.\n{blocks}\n{fix}")


def _returns(func: Any) -> Optional[List[ast.Return]]:
    """``func``'s own ``return <value>`` statements; None without a readable ``def``."""
    code = code_of(func)
    node = None if code is None or code.co_flags & inspect.CO_GENERATOR else source_node(code)
    if not isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef)):
        return None
    return [
        n
        for n in walk_own(node)
        if isinstance(n, ast.Return)
        and n.value is not None
        and not (isinstance(n.value, ast.Constant) and n.value.value is None)
    ]


# The kind of value an expression builds, whatever is in it.
_BUILDS = {ast.Tuple: tuple, ast.List: list, ast.ListComp: list, ast.Dict: dict}
_BUILDS.update({ast.DictComp: dict, ast.Set: set, ast.SetComp: set, ast.JoinedStr: str})


def returning_lines(handler: Any, result: Any) -> List[int]:
    """The lines of ``handler``'s ``return`` statements that can have given ``result``.

    That very constant, else a return building that kind of value (a list for
    a list), else any that may; ``[]`` without a source or a ``def`` (a lambda).

    Example::

        returning_lines(doubler.double, 42)   # [12]
    """
    returns = _returns(handler) or []
    exact = [
        r.lineno
        for r in returns
        if isinstance(r.value, ast.Constant)
        and type(r.value.value) is type(result)
        and r.value.value == result
    ]
    same_kind = [r.lineno for r in returns if _BUILDS.get(type(r.value)) is type(result)]
    possible = [
        r.lineno
        for r in returns
        if not isinstance(r.value, ast.Constant) and type(r.value) not in _BUILDS
    ]
    return sorted(exact or same_kind or possible)


def page_hint(error: BaseException, text: str, in_a_loop: bool = False) -> str:
    """``text`` with the fix for a Page used as its value, ``get_data`` if from ``get_page``.

    Example::

        page_hint(error, exception_text(error), in_a_loop=True)
        # "TypeError: '>' not supported ... 'Page' and 'float'. get_page(key) gives ..."
    """
    if PAGE_IN_A_HANDLER not in text:
        return text
    tb, names = error.__traceback__, frozenset[str]()
    while tb is not None:
        if not is_runtime_file(tb.tb_frame.f_code.co_filename):
            names = frozenset(tb.tb_frame.f_code.co_names)  # the innermost frame of the student's
        tb = tb.tb_next
    if in_a_loop or ("get_page" in names and "val_list" not in names):
        return text.replace(
            PAGE_IN_A_HANDLER,
            ". get_page(key) gives the whole Page (its data, time and origin); for the value "
            "alone, read self.get_data(key), or use page.data.",
        )
    return text


def slow_handler_text(handler: TaskHandler, task: Task, took_s: float) -> str:
    """The warning for a handler that held the node's thread too long."""
    return (
        f"Task handler {describe_callable(handler)} took {took_s:.3f} s handling "
        f"{format_task(task, values='none')}. While it runs the node can run no other task. "
        "Move slow or blocking work (time.sleep, waiting for a device) into a ThreadLoop, "
        "and let the handler only read and store data."
    )


def loop_failure(loop: AbstractLoop, error: BaseException, deployed: bool) -> LoopError:
    """The LoopError for ``loop``'s thread ending with ``error`` (``sys.exit()`` and Ctrl-C too)."""
    what = page_hint(error, exception_text(error), in_a_loop=True)
    if isinstance(error, SystemExit):
        what = f"sys.exit({'' if error.code is None else repr(error.code)})"
        fix = (
            "sys.exit() in a loop ends only the loop's thread, not the program. To stop "
            "this loop, call self.set_terminate_flag('why'); to stop the node, "
            "self.schedule(tasks.terminate('why'))."
        )
    elif isinstance(error, KeyboardInterrupt):
        fix = "Ctrl-C stops the whole node; a loop need not catch or raise it."
    else:
        fix = _fix(
            error,
            deployed,
            "loop",
            " without this loop",
            "Fix loop() (or setup()), or catch the error there if it can happen in "
            "normal use (in Mode.DEPLOYED the node keeps running without the loop).",
        )
    failure = LoopError(
        f"Loop {loop.name!r} ({describe_class(type(loop))}) stopped: it raised {what}"
        f"{failure_frames(error)}\n{fix}"
    )
    failure.__cause__ = error
    return failure


def reload_failure(error: BaseException) -> str:
    """Where a reload went wrong: a SyntaxError's file and line, else the student's frames.

    Example::

        reload_failure(error)   # "robot.py:12: SyntaxError: invalid syntax\n    def f(:"
    """
    if isinstance(error, SyntaxError):
        line = (error.text or "").strip()
        shown = f"\n    {line}" if line else ""
        return f"{error.filename}:{error.lineno}: SyntaxError: {error.msg}{shown}"
    return f"{exception_text(error)}{failure_frames(error)}"


def check_page_args(key: Any, data: Any) -> None:
    """Raise a `ComponentError` for a data key that is not a str, or a whole `Page` as data.

    Example::

        check_page_args("depth_m", 3.2)   # fine: returns None
        check_page_args(21.5, "depth_m")  # ComponentError: ... the key and the data look swapped
    """
    if not isinstance(key, str):
        raise ComponentError(bad_data_key(key, data))
    if data.__class__ is Page:
        raise ComponentError(page_as_data(key))


def check_component_args(component_class: type, factory: Any, parent: Any, name: Any) -> None:
    """Raise a `ComponentError` that says what is wrong with ``super().__init__``'s arguments.

    Example::

        check_component_args(Beeper, factory, node, "beeper")   # fine: no error
        check_component_args(Beeper, node, factory, "beeper")   # ComponentError: ... swapped.
    """
    good_factory, good_parent = (
        isinstance(factory, AbstractFactory),
        isinstance(parent, AbstractNode),
    )
    if good_factory and good_parent and isinstance(name, str) and name:
        return  # the common case: no need to look up the source file
    call = "super().__init__(factory, parent, name)"
    order = "Check the order of the arguments."
    if isinstance(factory, AbstractNode) and isinstance(parent, AbstractFactory):
        problem = (
            "passed the node as its factory and the factory as its parent: the arguments "
            f"are swapped. Write {call}, in that order (check the order in your "
            "__init__ and in the factory's get() call too)."
        )
    elif isinstance(factory, str) or isinstance(parent, str):
        shown = ", ".join(short_repr(a, 40) for a in (factory, parent, name))
        problem = (
            f"passed its arguments in the wrong order: {shown}. Write {call}: "
            "the factory first, then the parent node, then the name."
        )
    elif not good_factory:
        problem = (
            f"passed {factory!r} as its factory. The first argument of {call} must be "
            f"the factory that builds it (inside a factory's get(), pass `self`). {order}"
        )
    elif not good_parent:
        problem = (
            f"passed {parent!r} as its parent node. The second argument of {call} must "
            f"be the node (the `parent` given to the factory's get()). {order}"
        )
    else:
        problem = (
            f"passed {name!r} as its name. The third argument of {call} must be a "
            "non-empty string that is unique in the node, such as 'depth_filter'."
        )
    raise ComponentError(f"{describe_class(component_class)} {problem}")


def check_node_args(node_class: Any, role: Any, config: Any) -> None:
    """Raise a `ConfigError` that says what is wrong with ``Node(role, config)``'s arguments.

    Example::

        check_node_args(Node, "robot", Config({"robot": [...]}))   # fine: no error
        check_node_args(Node, config, "robot")   # ConfigError: ... are swapped.
    """
    if isinstance(role, AbstractConfig) and isinstance(config, str):
        swapped = "the role and the config are swapped."
        raise ConfigError(wrong_call("Node", node_class, (role, config), swapped))
    if not isinstance(role, str) or not role:
        raise ConfigError(f"A node's role must be a non-empty string, not {role!r}.")
    if not isinstance(config, AbstractConfig):
        raise ConfigError(
            f"Node({role!r}, ...) needs a snr.Config as its second argument, not "
            f"{type(config).__name__}. Wrap a dict of factories: Config({{'robot': [...]}})."
        )


_INSTEAD = {
    "add_component": "self.schedule(tasks.add_component(factory))",
    "remove_component": "self.schedule(tasks.remove_component(name))",
    "reload_component": "self.schedule(tasks.reload_component(name))",
    "write_page": "self.store_page(page) or self.store_data(key, value)",
    "terminate": "self.schedule(tasks.terminate(reason))",
}


def wrong_thread_error(role: str, method: str) -> ThreadSafetyError:
    """The error for ``method`` called on node ``role`` from a thread that is not the node's.

    Example::

        raise wrong_thread_error("robot", "write_page")
        # write_page() was called on node 'robot' from thread 'snr-robot-clock' ...
    """
    return ThreadSafetyError(
        f"{method}() was called on node {role!r} from thread "
        f"{threading.current_thread().name!r} (at {caller_location()}), but only "
        "the node's own thread may change the node, and a loop runs on a thread "
        f"of its own. Use {_INSTEAD.get(method, 'self.schedule(task)')} instead: it hands "
        "the work to the node's thread and is safe from any thread."
    )


def _wrong_get_signature(factory: AbstractFactory, error: TypeError) -> Optional[ComponentError]:
    """The error for a ``get()`` that cannot be called as ``get(parent)``, or None."""
    get = type(factory).get
    if error.__traceback__ is None or error.__traceback__.tb_next is not None:
        return None  # raised inside get(): not a call that failed to bind
    try:
        inspect.signature(get).bind(factory, object())
        return None
    except TypeError:
        pass
    except ValueError:
        return None
    params = ", ".join(inspect.signature(get).parameters)
    block = "\n" + def_block(get) if hasattr(get, "__code__") else ""
    return ComponentError(
        f"{describe_callable(get)} is written as `def get({params})`, but the node calls "
        "get(parent) with itself as the one argument. Write it as `def get(self, "
        "parent: AbstractNode) -> MyComponent:` and pass `parent` on: "
        f"`return MyComponent(self, parent)`.{block}"
    )


def raise_get_failure(factory: AbstractFactory, error: Exception, role: str) -> NoReturn:
    """Raise the ComponentError for a factory's ``get()`` that raised ``error``.

    Example::

        except Exception as error:
            raise_get_failure(factory, error, node.role)
    """
    if isinstance(error, TypeError):
        explained = explain_abstract_error(error) or _wrong_get_signature(factory, error)
        if explained is not None:
            raise explained from None
    raise ComponentError(
        f"{describe_callable(type(factory).get)} raised {exception_text(error)}"
        f"\nwhile building a component for node {role!r}.{failure_frames(error)}"
    ) from error


def wrong_get_result_error(factory: AbstractFactory, component: Any) -> ComponentError:
    """The ComponentError for a ``get()`` that returned something not a component."""
    get = describe_callable(type(factory).get)
    if isinstance(component, type):
        name = component.__name__
        return ComponentError(
            f"{get} returned the class {name} itself, not a component made from it. "
            f"Call the class: `return {name}(self, parent)`."
        )
    return ComponentError(
        f"{get} returned {short_repr(component)} ({type(component).__name__}), "
        "not an endpoint or loop. get() must build and return the component, "
        "e.g. `return MyEndpoint(self, parent)`."
    )


def warn_get_returned_none(
    factory: AbstractFactory, role: str, running: bool, told: Set[Any], log: logging.Logger
) -> None:
    """A ``get()`` returned None: refuse one that never returns a value, else warn once.

    At run time None is the documented "add nothing"; ``told`` holds the ``get``s named.
    """
    get = type(factory).get
    if _returns(get) == []:
        raise ComponentError(
            f"{describe_callable(get)} returned None: it has no `return` with a "
            f"value, so role {role!r} can never get a component from it. "
            "Return what it builds: `return MyEndpoint(self, parent)`."
        )
    if not running and get not in told:
        told.add(get)
        log.warning(
            "%s returned None this time, so role %r gets no component from it. If you "
            "meant to add one, check the conditions before its `return`. (Said once per "
            "factory class.)",
            describe_callable(get),
            role,
        )


def factory_without_init(factory: AbstractFactory) -> ComponentError:
    """The ComponentError for a factory whose ``__init__`` skipped ``super().__init__()``."""
    return ComponentError(
        f"{describe_class(type(factory))} did not call super().__init__() in its __init__. "
        "Add `super().__init__()` (or `super().__init__(my_module)` to hot-reload "
        "my_module) as its first line."
    )


def component_without_init(component: Any) -> ComponentError:
    """The ComponentError for a component whose ``__init__`` skipped ``super().__init__``."""
    cls = type(component)
    init = next(vars(k)["__init__"] for k in cls.__mro__ if "__init__" in vars(k))
    code = code_of(init)
    block = "" if code is None or is_runtime_file(code.co_filename) else "\n" + def_block(init)
    return ComponentError(
        f"{describe_class(cls)}: its __init__ did not call "
        "super().__init__(factory, parent, name). Add that line first in "
        f"__init__ so SNR can give the component its name and task handlers.{block}"
    )


def name_taken_error(role: str, component: Any, other: Any) -> ConfigError:
    """The ConfigError for a component whose name ``other`` already has in node ``role``."""
    name, factory = component.name, getattr(component, "factory", None)
    if getattr(other, "factory", None) is factory:
        return ConfigError(
            f"Node {role!r} got two components named {name!r} from the same "
            f"{type(factory).__name__} object: it is listed twice in the config, "
            "or its get() gives every component the same name. List it once, or "
            "add another factory object that uses another name."
        )
    return ConfigError(
        f"Node {role!r} already has a component named {name!r} "
        f"({describe_class(type(other))}); {describe_class(type(component))} wants the "
        "same name. Give each component a unique name (e.g. pass a name to its factory)."
    )


CORE_REFUSED = {
    "remove component": (
        "Refused to remove %r from node %r: it is the node's own core, which "
        "stores every page, adds, removes and reloads components, and stops the "
        "node on a terminate task; without it the node would run on deaf. To stop "
        "the node, schedule a terminate task (or type `exit` in a console)."
    ),
    "reload": (
        "Refused to reload %r in node %r: it is the node's own core and runs this "
        "very reload (and every store, add, remove and terminate); SNR's own code "
        "is not reloaded while the node runs. Restart the node to load a new SNR."
    ),
}
"""The log messages (name, role) for removing or reloading ``node_core``.

Example::

    log.error(CORE_REFUSED["reload"], "node_core", node.role)
"""


def not_stopped_text(component: AbstractComponent, timeout_s: float, reload: bool) -> str:
    """The log message for a loop still running ``timeout_s`` after it was asked to stop."""
    where = component.where_running() if isinstance(component, AbstractLoop) else ""
    advice = (
        "Make loop() return often: give reads a timeout and wait with self.wait_s(seconds) "
        "instead of time.sleep(), so the loop notices when it should stop."
    )
    if reload:
        return (
            f"Cannot reload loop {component.name!r}: it did not stop within "
            f"{timeout_s:.1f} s of being asked{f' (it is at {where})' if where else ''}, and "
            "a new copy would run beside it. Reload refused; the old version keeps "
            f"running. {advice}"
        )
    return (
        f"Loop {component.name!r} did not stop within {timeout_s:.1f} s of being asked"
        f"{f': it is at {where}' if where else ''}. Its terminate() runs now anyway, while "
        f"its thread is still going (the thread ends with the program). {advice}"
    )


def start_failure(component: AbstractComponent, error: Exception) -> ComponentError:
    """The ComponentError for a component whose ``begin()`` (or thread start) raised ``error``."""
    return ComponentError(
        f"{describe_class(type(component))} {component.name!r} failed to start: "
        f"{exception_text(error)}{failure_frames(error)}"
    )


def log_name_taken(component_class: type) -> ComponentError:
    """The ComponentError for ``self.log = ...`` in a component: ``log`` is its logger."""
    return ComponentError(
        caller_block(
            f"{describe_class(component_class)} uses the name 'log' for its own value, but "
            "'log' is already the component's logger (self.info(...), self.warn(...) write "
            f"to it). Use another name, e.g. self.{component_class.__name__.lower()}_log."
        )
    )


def handlers_before_init(component_class: type) -> MissingSuperInitError:
    """The error for ``self.task_handlers = ...`` before ``super().__init__``."""
    return MissingSuperInitError(
        caller_block(
            f"{describe_class(component_class)} sets self.task_handlers before calling "
            "super().__init__(factory, parent, name). Call super().__init__(...) "
            "first in __init__, then set task_handlers."
        )
    )


def used_before_init(component: Any, attribute: str) -> AttributeError:
    """The error for a missing component attribute: Python's own once initialised, else why not."""
    if "_task_handlers" in component.__dict__ or attribute.startswith("__"):
        error = AttributeError(
            f"{type(component).__name__!r} object has no attribute {attribute!r}"
        )
        error.name, error.obj = attribute, component  # Python's "Did you mean" uses these
        return error
    return MissingSuperInitError(
        caller_block(
            f"{describe_class(type(component))} has no {attribute!r} yet: its __init__ did "
            "not call super().__init__(factory, parent, name), or used the component "
            'before calling it. Make `super().__init__(factory, parent, "my_name")` '
            "the first line of __init__."
        )
    )


def check_loop_class(loop_class: type, base_loop: Any, max_tick_rate_hz: float) -> None:
    """Raise a ComponentError for a ThreadLoop without its own ``loop()``, or a negative rate.

    Example::

        check_loop_class(type(self), ThreadLoop.loop, max_tick_rate_hz)
    """
    if getattr(loop_class, "loop", None) is base_loop:
        raise ComponentError(
            f"{describe_class(loop_class)} is a ThreadLoop but has no loop() method. "
            "Add `def loop(self) -> None:` with the work to repeat, or make it an "
            "Endpoint if it only reacts to tasks."
        )
    if max_tick_rate_hz < 0:
        raise ComponentError(
            f"{describe_class(loop_class)} asked for max_tick_rate_hz="
            f"{max_tick_rate_hz}; use a positive rate, or 0 for no limit."
        )
