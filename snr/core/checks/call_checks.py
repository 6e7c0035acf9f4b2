"""Calls to SNR's constructors and task builders with the wrong arguments, in words.

The runtime calls a ``check_*`` function with the arguments it was given: the
right call returns at once; a wrong one raises an error that shows the call as
written, where, and the signature to follow (`wrong_call`).

Example::

    check_config_args(Config, {"robot": [MyFactory]}, Mode.DEBUG, None)
    # ConfigError: Role 'robot' lists <class 'MyFactory'>, which is not a factory
    # (an EndpointFactory or LoopFactory object). It looks like a class: add () ...
"""

from __future__ import annotations

import enum
import os
import sys
from typing import Any, Iterable, List, Mapping

from snr.core.checks.error_text import did_you_mean, short_repr
from snr.core.checks.student_code import describe_class, frame_location
from snr.core.clock import NodeClock
from snr.prelude import (
    AbstractConfig,
    AbstractFactory,
    ComponentError,
    ConfigError,
    HandlerError,
    Mode,
    Page,
    Task,
)

__all__ = [
    "bad_reload_target",
    "check_cli_args",
    "check_config_args",
    "check_factory_class",
    "check_page_args",
    "check_role",
    "check_runner_args",
    "check_schedule_args",
    "no_sim_clock_across_processes",
    "param_text",
    "values_not_a_list",
    "wrong_call",
]

_SNR_PACKAGE = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__)))) + os.sep


def _call_site() -> str:
    """``"robot.py:12 in Sonar.loop"``: the nearest caller outside the whole ``snr`` package."""
    frame = sys._getframe(1)
    while frame.f_back is not None and frame.f_code.co_filename.startswith(_SNR_PACKAGE):
        frame = frame.f_back
    return frame_location(frame)


def _plain_signature(name: str, function: Any) -> str:
    """``"Node(role, config)"``: a call as a student writes it (no ``self``, no annotations)."""
    import inspect  # only while an error is being explained

    try:
        signature = inspect.signature(function)
    except (TypeError, ValueError):
        return f"{name}(...)"
    parts: List[str] = []
    for parameter in signature.parameters.values():
        if parameter.name == "self":
            continue
        text, default = param_text(parameter), parameter.default
        if isinstance(default, enum.Enum):
            text += f"={type(default).__name__}.{default.name}"
        elif default is not parameter.empty:
            text += f"={default!r}"
        parts.append(text)
    return f"{name}({', '.join(parts)})"


def param_text(parameter: Any) -> str:
    """``"*args"``: an ``inspect.Parameter`` as it is written in a ``def``, without its default.

    Example::

        [param_text(p) for p in inspect.signature(f).parameters.values()]   # ['task', '*args']
    """
    stars = {parameter.VAR_POSITIONAL: "*", parameter.VAR_KEYWORD: "**"}.get(parameter.kind, "")
    return f"{stars}{parameter.name}"


def wrong_call(name: str, function: Any, args: Iterable[Any], problem: str) -> str:
    """The message for a public constructor or runner called with the wrong arguments.

    Example::

        raise ConfigError(wrong_call("Node", Node, (config, "robot"),
                                     "the role and the config are swapped."))
        # Node(Config(roles=['robot'], ...), 'robot') at robot.py:4: the role and the
        # config are swapped. Write it as Node(role, config).
    """
    shown = ", ".join(short_repr(a, 40) for a in args)
    return (
        f"{name}({shown}) at {_call_site()}: {problem} "
        f"Write it as {_plain_signature(name, function)}."
    )


def values_not_a_list(name: str, values: Any) -> str:
    """The message for ``tasks.event(name, values)`` whose values are not a list.

    Example::

        values_not_a_list("say", "hello")
        # tasks.event('say', 'hello') at robot.py:9 in Speaker.begin: ...
    """
    shown = short_repr(values, 40)
    got = f"{shown} is a {type(values).__name__}"
    if isinstance(values, str) and values:
        got += f", so task.val_list[0] would be {values[0]!r}"
    wrapped = f"list({shown})" if isinstance(values, (tuple, set)) else f"[{shown}]"
    return (
        f"tasks.event({name!r}, {shown}) at {_call_site()}: an event's values go in a list "
        f"(its val_list), and {got}. Write tasks.event({name!r}, {wrapped})."
    )


def check_page_args(key: Any, data: Any) -> None:
    """Raise a `ComponentError` for a data key that is not a str, or a whole `Page` as data.

    Example::

        check_page_args("depth_m", 3.2)   # fine: returns None
        check_page_args(21.5, "depth_m")  # ComponentError: ... the key and the data look swapped
    """
    if not isinstance(key, str):
        shown = short_repr(key, 40)
        fix = "Write store_data(key, data) with a key such as 'depth_m'."
        if isinstance(data, str):
            fix = f"The key and the data look swapped: write store_data({data!r}, {shown})."
        raise ComponentError(
            f"Data stored under the key {shown} at {_call_site()}: a data key must be a str, "
            f"and {shown} is a {type(key).__name__} (the data is {short_repr(data, 40)}). {fix}"
        )
    if data.__class__ is Page:
        raise ComponentError(
            f"Data stored under {key!r} at {_call_site()} is a whole Page (as a handler "
            "gets it in task.val_list), so readers of "
            f"{key!r} would get a Page inside a Page. Store its value, page.data "
            "(e.g. task.val_list[0].data), or pass the page on as it is with "
            "tasks.store_page(page)."
        )


def check_config_args(config_class: Any, factories: Any, mode: Any, clock: Any) -> None:
    """Raise a `ConfigError` that says what is wrong with ``Config(...)``'s arguments.

    Example::

        check_config_args(Config, {"robot": [MyFactory()]}, Mode.DEBUG, None)   # fine
        check_config_args(Config, [MyFactory()], Mode.DEBUG, None)   # ConfigError: ... a dict
    """
    if isinstance(factories, (list, tuple)):
        problem = (
            "a Config needs a dict from each role to its list of factories, not "
            'the list alone: Config({"robot": [...]}).'
        )
        raise ConfigError(wrong_call("Config", config_class, (factories,), problem))
    if not isinstance(factories, Mapping):
        raise ConfigError(
            f"Config(factories=...) got {type(factories).__name__}; it needs a dict "
            'from role to a list of factories, e.g. {"robot": [MyFactory()]}.'
        )
    if not isinstance(mode, Mode):
        raise ConfigError(
            f"Config(mode=...) got {mode!r}; use Mode.DEBUG, Mode.TEST or Mode.DEPLOYED."
        )
    for role, facs in factories.items():
        if not isinstance(facs, (list, tuple)):
            raise ConfigError(
                f"Role {role!r} maps to {type(facs).__name__}, not a list of "
                f"factories. Write {role!r}: [MyFactory(), ...]."
            )
        for fac in facs:
            if not isinstance(fac, AbstractFactory):
                hint = " It looks like a class: add () to make a factory object."
                raise ConfigError(
                    f"Role {role!r} lists {fac!r}, which is not a factory (an EndpointFactory "
                    f"or LoopFactory object).{hint if isinstance(fac, type) else ''}"
                )
    if clock is not None and not isinstance(clock, NodeClock):
        raise ConfigError(
            f"Config(clock=...) got {clock!r}; it takes a snr.SimClock (simulated "
            "time) or None (the wall clock)."
        )


def check_role(role: Any, factories: Mapping[Any, Any]) -> None:
    """Raise a `ConfigError` unless ``role`` is one of ``factories`` with at least one factory.

    Example::

        check_role("urv", {"urov": [...]})
        # ConfigError: Unknown role 'urv'. This config has roles: 'urov'. Did you mean 'urov'?
    """
    if role not in factories:
        known = ", ".join(repr(r) for r in factories) or "(none)"
        hint = did_you_mean(role, factories)
        raise ConfigError(f"Unknown role {role!r}. This config has roles: {known}.{hint}")
    if not factories[role]:
        raise ConfigError(
            f"Role {role!r} has no components: its factory list is empty. Add at "
            "least one factory, e.g. snr.TimeoutLoopFactory(seconds=5)."
        )


def check_runner_args(runner_class: Any, role: Any, config: Any) -> None:
    """Raise a `ConfigError` when ``SynchronousRunner(role, config)`` has them swapped.

    Example::

        check_runner_args(SynchronousRunner, "robot", config)   # fine
        check_runner_args(SynchronousRunner, config, "robot")   # ConfigError: ... swapped
    """
    if not isinstance(role, str) and isinstance(config, str):
        problem = "the role and the config are swapped: the role comes first."
        raise ConfigError(wrong_call("SynchronousRunner", runner_class, (role, config), problem))


def check_cli_args(runner_class: Any, components_or_config: Any, argv: Any) -> None:
    """Raise a `ConfigError` when ``CliRunner`` is given a role instead of the components.

    Example::

        check_cli_args(CliRunner, components, sys.argv)   # fine
        check_cli_args(CliRunner, "urov", sys.argv)       # ConfigError: ... reads the role ...
    """
    role = components_or_config
    if isinstance(role, str):
        problem = (
            f"the first argument is the role {role!r}, but CliRunner takes the components "
            f"(or a Config) and reads the role from the command line: `python robot.py {role}`."
        )
        raise ConfigError(wrong_call("CliRunner", runner_class, (role, argv), problem))


def no_sim_clock_across_processes(config: AbstractConfig) -> None:
    """Refuse a `SimClock` config for `MultiProcRunner`: the clock keeps one process's time.

    Example::

        no_sim_clock_across_processes(Config({"a": [...]}, clock=SimClock()))   # ConfigError
    """
    if isinstance(getattr(config, "clock", None), NodeClock):
        raise ConfigError(
            "MultiProcRunner runs each node in a process of its own, but a SimClock "
            "keeps the time of one process. Run the nodes in one process (each "
            "node's loop() on a thread of its own) or build the Config without clock=."
        )


def check_schedule_args(tasks: Any) -> None:
    """Raise a `HandlerError` unless ``tasks`` (given to ``schedule()``) is a list of Tasks.

    Example::

        check_schedule_args([tasks.event("a")])   # fine
        check_schedule_args("go")   # HandlerError: Cannot schedule 'go' (str): ...
    """
    if not isinstance(tasks, list):
        raise HandlerError(
            f"Cannot schedule {tasks!r} ({type(tasks).__name__}): schedule() takes a Task, "
            "a list of Tasks or None. Build tasks with snr.tasks, e.g. "
            "tasks.event('name')."
        )
    for task in tasks:
        if not isinstance(task, Task):
            raise HandlerError(
                f"Cannot schedule {task!r} ({type(task).__name__}): only Task "
                "objects can be queued. Build tasks with snr.tasks, e.g. "
                "tasks.event('name') or self.store_data_task(key, data)."
            )


def check_factory_class(factory_class: type, base_get: Any) -> None:
    """Raise a `ComponentError` when a factory class has no ``get()`` of its own (``base_get``).

    Example::

        check_factory_class(DoublerFactory, Factory.get)   # fine: it defines get()
    """
    if getattr(factory_class, "get", None) is base_get:
        raise ComponentError(
            f"{describe_class(factory_class)} has no get() method. A factory must build "
            "its component: add `def get(self, parent: AbstractNode) -> MyEndpoint:` "
            "returning `MyEndpoint(self, parent, ...)`."
        )


def bad_reload_target(owner: type, target: Any) -> str:
    """The message for a factory that names something other than a module to reload.

    Example::

        bad_reload_target(DoublerFactory, 42)
        # "DoublerFactory (robot.py:3) passed 42 as a module to reload. Pass the ..."
    """
    return (
        f"{describe_class(owner)} passed {target!r} as a module to reload. Pass the "
        "module object itself: `import my_endpoint` then "
        "`super().__init__(my_endpoint)` (or a list of modules, or nothing)."
    )
