"""How the node puts a student's mistakes into words (docs/errors.md shows each).

A failed handler or loop is worded by `snr.core.checks.failures.FailureReport`.

Example::

    raise wrong_thread_error("robot", "write_page")
    # ThreadSafetyError: write_page() was called on node 'robot' from thread ...
"""

from __future__ import annotations

import ast
import inspect
import logging
import threading
from typing import Any, List, NoReturn, Optional, Set

from snr.core.checks.call_checks import check_page_args, wrong_call
from snr.core.checks.error_text import PAGE_IN_A_HANDLER, exception_text, short_repr
from snr.core.checks.student_code import (
    caller_block,
    caller_location,
    code_of,
    def_block,
    describe_callable,
    describe_class,
    failure_frames,
    is_runtime_file,
    source_node,
    walk_own,
)
from snr.prelude import (
    AbstractComponent,
    AbstractConfig,
    AbstractFactory,
    AbstractNode,
    ComponentError,
    ConfigError,
    MissingSuperInitError,
    ThreadSafetyError,
)

# check_page_args is call_checks' (it names the student's call): named here for the node.
__all__ = ["check_component_args", "check_loop_class", "check_node_args", "check_page_args"]
__all__ += ["component_without_init", "factory_without_init", "handlers_before_init"]
__all__ += ["log_name_taken", "name_taken_error", "page_hint", "raise_get_failure"]
__all__ += ["reload_failure", "returning_lines", "start_failure", "used_before_init"]
__all__ += ["warn_get_returned_none", "wrong_get_result_error", "wrong_thread_error"]


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
        from snr.prelude.abstract_errors import explain_abstract_error  # loaded only now

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
