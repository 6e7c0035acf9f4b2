"""Lesson 6's grader: does the node core do what a node needs of it?

It plugs the student's class into real nodes, ``Config(node_core=...)``,
where SNR's ``NodeCoreEndpoint`` goes, and checks what happened in them
(`snr.extras.lessons.probe`), never how the class is written:

* it is a node core (a `NodeCore`, or an endpoint named ``node_core`` with a
  ``store_page_handler``) that the node builds;
* the node runs without an exception;
* each page is in the datastore when its handlers run;
* each page with ``process`` true gets one ``process_data`` task, after it is
  stored, in the order stored; a page with ``process`` false gets none;
* pages from another node, 200 over an in-memory link, reach the datastore
  and the handlers, every one, in the order sent;
* it adds, removes and reloads a component when asked;
* the node stops on a terminate task.

SNR's own core passes every check (tests/test_lesson_assignments.py).

Example::

    for check in grade(Path("node_core.py")):
        print(check.passed, check.name)
"""

from __future__ import annotations

from pathlib import Path
from typing import Any, List, Optional, Type

from snr import AbstractFactory, AbstractNode, Endpoint, EndpointFactory
from snr.core import NodeCore
from snr.extras.lessons.grading import Check, load_submission
from snr.extras.lessons.probe import (
    ALONE,
    BURST,
    DONE,
    MANY,
    SCRIPT,
    SENT,
    at_class_line,
    find_class,
    method_line,
    over_comms,
    page_words,
    probe,
)

__all__ = ["CoreFactory", "grade", "grade_core", "is_node_core"]


def is_node_core(cls: type) -> bool:
    """True for a class that can be a node core: a `NodeCore`, or an endpoint with its method.

    Example::

        is_node_core(snr.core.NodeCoreEndpoint)    # True
    """
    return issubclass(cls, NodeCore) or (
        issubclass(cls, Endpoint) and callable(getattr(cls, "store_page_handler", None))
    )


class CoreFactory(EndpointFactory):
    """Builds the student's node core class, whatever their own factory is called.

    Example::

        Config({"grade": [...]}, node_core=CoreFactory(MyNodeCore))
    """

    def __init__(self, cls: Type[Endpoint]) -> None:
        super().__init__()
        self.cls = cls

    def get(self, parent: AbstractNode) -> Endpoint:
        return self.cls(self, parent)  # type: ignore[call-arg]


def _handler_line(cls: Any, *names: str) -> Optional[int]:
    """The line of the first of ``names`` the class has (the student's names may differ)."""
    for name in names:
        line = method_line(cls, name)
        if line is not None:
            return line
    return method_line(cls, "__init__")


def grade(path: Path) -> List[Check]:
    """The checks of lesson 6 for the student's file at ``path``.

    Raises:
        SubmissionError: the file cannot be loaded, or has no node core class.

    Example::

        all(check.passed for check in grade(Path("node_core.py")))
    """
    module = load_submission(path)
    cls = find_class(module, is_node_core, "node core class (extending snr.core.NodeCore)")
    return grade_core(CoreFactory(cls), cls, path)


def grade_core(factory: AbstractFactory, cls: type, path: Path) -> List[Check]:
    """The checks of lesson 6 for the node core ``factory`` builds, of class ``cls``.

    Example::

        grade_core(NodeCoreFactory(), NodeCoreEndpoint, Path("snr"))   # all pass
    """
    store = method_line(cls, "store_page_handler")
    checks = [
        Check(
            "the node core",
            True,
            happened=f"{cls.__qualname__}, built by the node in place of SNR's own",
            line=method_line(cls, "__init__"),
        )
    ]
    run = probe(None, factory, path)
    if run.error is not None:
        return [*checks, at_class_line(run.error, cls)]
    checks.append(Check("runs without an exception", True))
    script = run.at_store[: len(SCRIPT)]
    lost = [(key, value, got) for key, value, got in script if getattr(got, "data", None) != value]
    happened = f"{len(script) - len(lost)} of {len(SCRIPT)} pages stored"
    if lost:
        key, value, got = lost[0]
        happened += f"; while {key!r} = {value!r} was handled, get_page gave {page_words(got)}"
    checks.append(
        Check(
            "stores each page before its handlers run",
            len(script) == len(SCRIPT) and not lost,
            expected=f"each of {len(SCRIPT)} pages in the datastore when its handlers run",
            happened=happened,
            hint="store_page_handler puts the page in self.pages under page.key (step 1)",
            line=store,
        )
    )
    wanted = [(key, value) for key, value, process in SCRIPT if process] + [ALONE]
    processed = [(key, value) for key, value, _ in run.at_process]
    # When its process_data task runs, a page (or a newer one of its key) is stored.
    late = [(key, value) for key, value, now in run.at_process if now not in _since(key, value)]
    said = f"{len(processed)} process_data tasks: {processed[:3]}" + (
        "..." if len(processed) > 3 else ""
    )
    if late:
        said += f"; {late[0][0]!r} = {late[0][1]!r} was not in the datastore when it ran"
    checks.append(
        Check(
            "sends process_data after storing the page",
            processed == wanted and not late,
            expected=f"one process_data task for each of the {len(wanted)} pages with "
            f"process true, in the order stored, each page stored first: {wanted[:3]}...",
            happened=said,
            hint="after storing it, return Task(TaskType.process_data, page.key, [page]) "
            "when page.process is true (step 2)",
            line=store,
        )
    )
    unwanted = [(key, value) for key, value, process in SCRIPT if not process]
    extra = [pair for pair in processed if pair in unwanted or pair[0].startswith("k")]
    checks.append(
        Check(
            "no process_data for a page with process false",
            not extra and len(processed) <= len(wanted),
            expected=f"no process_data task for the {len(unwanted)} pages of the script "
            f"nor the {MANY} after it, stored with process=False",
            happened=f"{len(extra)} of them got one" + (f", e.g. {extra[0]}" if extra else ""),
            hint="return the process_data task only when page.process is true (step 2)",
            line=store,
        )
    )
    burst = [
        (value, getattr(got, "data", None)) for key, value, got in run.at_store if key == "burst"
    ]
    handled = [value for value, _ in burst]
    unstored = [value for value, stored in burst if stored != value]
    checks.append(
        Check(
            "stores a burst of pages, each as its own store_page task",
            handled == list(range(BURST)) and not unstored,
            expected=f"the {BURST} pages of one STORE_PAGES event (0 to {BURST - 1}, from "
            "node 'other') handled in order, each stored when its handlers run",
            happened=f"{_handled(handled)}"
            + (f"; {unstored[0]!r} was not stored when handled" if unstored else ""),
            hint="pages from another node come many at once, as one STORE_PAGES event: "
            "return a store_page task for each, in order (step 3)",
            line=_handler_line(cls, "store_pages", "store_pages_handler"),
        )
    )
    got = over_comms(None, factory, path)
    if got.error is not None:
        return [*checks, at_class_line(got.error, cls)]
    # How the pages are cut into bursts depends on timing: the burst check above says
    # whether each is handled; this one, that they end in the datastore, none out of order.
    in_order = all(a < b for a, b in zip(got.seen, got.seen[1:]))
    stored = getattr(got.last, "data", None) == SENT - 1 and got.last.origin == "sender"
    checks.append(
        Check(
            "stores pages from another node, in order",
            in_order and stored,
            expected=f"the {SENT} 'count' pages node 'sender' sends, 0 to {SENT - 1}: none "
            "handled out of order, and the last in the datastore, from 'sender'",
            # How many were handled depends on how the link cut the bursts: say the order.
            happened=("none out of order" if in_order else _handled(got.seen))
            + f"; get_page('count') gave {page_words(got.last)}",
            hint="a page from another node is stored as any other: by store_page_handler, "
            "or by the store_page tasks of a burst (steps 1, 3)",
            line=_handler_line(cls, "store_pages", "store_pages_handler"),
        )
    )
    checks.append(
        Check(
            "adds and removes a component",
            run.added is True and run.removed is True,
            expected="the component of an ADD_COMPONENT event in node.components, then "
            "gone after a REMOVE_COMPONENT event",
            happened=f"added: {_yes(run.added)}; removed: {_yes(run.removed)}",
            hint="parent.build_component(factory), then parent.add_component(component); "
            "parent.remove_component(name) (step 4)",
            line=_handler_line(cls, "add", "add_component_handler"),
        )
    )
    checks.append(
        Check(
            "reloads the component a reload task names",
            run.reloaded == ["grader"],
            expected="a reload task for 'grader': parent.reload_component('grader')",
            happened=f"reload_component was called with {run.reloaded}"
            if run.reloaded
            else "reload_component was not called",
            hint='parent.reload_component(task.name or "all") (step 4)',
            line=_handler_line(cls, "reload", "reload_handler"),
        )
    )
    checks.append(
        Check(
            "stops the node on a terminate task",
            run.stop_reason == DONE,
            expected=f"the node stops, for the reason the task names: {DONE!r}",
            happened=f"it stopped: {run.stop_reason!r}",
            hint="parent.set_terminate_flag(task.name) (step 5)",
            line=_handler_line(cls, "stop", "terminate_handler"),
        )
    )
    return checks


def _since(key: str, value: Any) -> List[Any]:
    """The values of ``key`` from ``value`` on, as the probe stores them."""
    values = [one for k, one, _ in SCRIPT if k == key] + [ALONE[1]] * (key == ALONE[0])
    return values[values.index(value) :] if value in values else []


def _handled(seen: List[Any]) -> str:
    """How many pages the receiver's handler saw, and where the order went wrong, if it did."""
    if not seen:
        return "none handled"
    wrong = next((i for i in range(1, len(seen)) if seen[i] <= seen[i - 1]), None)
    order = "" if wrong is None else f", not in order: {seen[wrong]!r} after {seen[wrong - 1]!r}"
    return f"{len(seen)} handled{order}"


def _yes(answer: Optional[bool]) -> str:
    return {True: "yes", False: "no", None: "not tried (the run stopped before)"}[answer]
