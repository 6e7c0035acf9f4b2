"""Lesson 5's grader: does the datastore keep each key's newest page, as a node needs?

It plugs the student's class into real nodes, ``Config(datastore=...)``,
where SNR's ``dict`` goes, and checks what the nodes read back from it
(`snr.extras.lessons.probe`), never how the class is written:

* it is a class with the four methods, made with no arguments;
* the node runs without an exception;
* each page stored is what ``get_page`` gives for its key, while the page's
  handlers run; a key stored again gives the newer page;
* a key never stored gives None;
* ``list(node.datastore)`` is each key once, first stored first, and
  ``len`` says how many;
* 300 more keys are all kept, each with its own page;
* pages from another node, 200 over an in-memory link, are stored as they come.

SNR's own datastore, a ``dict``, passes every check
(tests/test_lesson_assignments.py).

Example::

    for check in grade(Path("datastore.py")):
        print(check.passed, check.name)
"""

from __future__ import annotations

from pathlib import Path
from typing import Any, Callable, List, Optional

from snr.core.checks.seam_checks import DATASTORE_METHODS
from snr.extras.lessons.grading import Check, load_submission
from snr.extras.lessons.probe import (
    MANY,
    SCRIPT,
    SENT,
    UNKNOWN,
    at_class_line,
    find_class,
    method_line,
    over_comms,
    page_words,
    probe,
)

__all__ = ["grade", "grade_datastore", "is_datastore"]


def is_datastore(cls: type) -> bool:
    """True for a class with the four methods of a datastore (`snr.prelude.Datastore`).

    Example::

        is_datastore(dict)    # True
    """
    return all(callable(getattr(cls, name, None)) for name in DATASTORE_METHODS)


def grade(path: Path) -> List[Check]:
    """The checks of lesson 5 for the student's file at ``path``.

    Raises:
        SubmissionError: the file cannot be loaded, or has no datastore class.

    Example::

        all(check.passed for check in grade(Path("datastore.py")))
    """
    module = load_submission(path)
    what = "datastore class (with __setitem__, get, __iter__, __len__)"
    cls = find_class(module, is_datastore, what)
    return grade_datastore(cls, path)


def grade_datastore(make: Callable[[], Any], path: Path) -> List[Check]:
    """The checks of lesson 5 for the datastore ``make()`` makes (a class, or ``dict``).

    Example::

        grade_datastore(dict, Path("snr"))    # SNR's own: every check passes
    """
    name = getattr(make, "__qualname__", repr(make))
    setitem, get = method_line(make, "__setitem__"), method_line(make, "get")
    checks = [
        Check(
            "the datastore",
            True,
            happened=f"{name}, made with {name}() for each node",
            line=method_line(make, "__init__"),
        )
    ]
    run = probe(make, None, path)
    if run.error is not None:
        return [*checks, at_class_line(run.error, make)]
    checks.append(Check("runs without an exception", True))
    firsts: List[Any] = []
    agains: List[Any] = []
    seen = set()
    for key, value, got in run.at_store[: len(SCRIPT)]:
        (agains if key in seen else firsts).append((key, value, got))
        seen.add(key)
    checks.append(_kept("gives back the page stored under a key", firsts, setitem, "steps 1, 2"))
    checks.append(_kept("gives the newest page of a key stored again", agains, setitem, "step 1"))
    checks.append(
        Check(
            "gives None for a key never stored",
            run.unknown is None,
            expected=f"get_page({UNKNOWN!r}) is None",
            happened=f"it gave {run.unknown!r}",
            hint="get returns None when no pair in the key's bucket has the key (step 2)",
            line=get,
        )
    )
    keys = list(dict.fromkeys(key for key, _, _ in SCRIPT))
    checks.append(
        Check(
            "lists each key once, first stored first",
            run.keys == keys and run.count == len(keys),
            expected=f"list(datastore) == {keys}, len(datastore) == {len(keys)}",
            happened=f"list(datastore) == {run.keys}, len(datastore) == {run.count!r}",
            hint="append a key to self.order only the first time it is stored; iterate "
            "over a copy of it (step 3)",
            line=method_line(make, "__iter__"),
        )
    )
    many = [f"k{i:03d}" for i in range(MANY)]
    wrong = [key for index, key in enumerate(many) if run.many.get(key) != index]
    first = f"; get_data({wrong[0]!r}) gave {run.many.get(wrong[0])!r}" if wrong else ""
    listed = run.all_keys == keys + many
    checks.append(
        Check(
            f"keeps {MANY} more keys",
            not wrong and listed,
            expected=f"get_data('k000') to get_data('k{MANY - 1}') give 0 to {MANY - 1}, and "
            f"list(datastore) has all {len(keys) + MANY} keys in order",
            happened=f"{MANY - len(wrong)} of {MANY} right{first}; list(datastore) has "
            f"{len(run.all_keys)} keys{'' if listed else ', not in the order stored'}",
            hint="each key stored is found again in its bucket (steps 1, 2); when the "
            "table grows, every pair moves to its new bucket (step 4)",
            line=method_line(make, "grow") or setitem,
        )
    )
    got = over_comms(make, None, path)
    if got.error is not None:
        return [*checks, at_class_line(got.error, make)]
    last = got.last
    arrived = (
        getattr(last, "data", None) == SENT - 1
        and getattr(last, "origin", None) == "sender"
        and "count" in got.keys
    )
    checks.append(
        Check(
            "stores pages from another node",
            arrived,
            expected=f"the {SENT} 'count' pages node 'sender' sends (0 to {SENT - 1}): "
            f"get_page('count') is the last, from 'sender'",
            happened=f"{len(got.seen)} arrived; get_page('count') gave {page_words(last)}",
            hint="pages from another node are stored as any other: by __setitem__ (step 1)",
            line=setitem,
        )
    )
    return checks


def _kept(name: str, stored: List[Any], line: Optional[int], step: str) -> Check:
    """The check that ``get_page`` gave each page of ``stored`` while its handlers ran."""
    lost = [(key, value, got) for key, value, got in stored if not _is(got, key, value)]
    happened = f"{len(stored) - len(lost)} of {len(stored)} pages given back"
    if lost:
        key, value, got = lost[0]
        gave = page_words(got)
        happened += f"; after {key!r} = {value!r} was stored, get_page({key!r}) gave {gave}"
    return Check(
        name,
        bool(stored) and not lost,
        expected=f"for each of {len(stored)} pages, get_page(key) is that page while its "
        "handlers run",
        happened=happened,
        hint=f"keep (key, page) in the key's bucket, replacing the pair of the same key; "
        f"get returns the page paired with the key ({step})",
        line=line,
    )


def _is(got: Any, key: str, value: Any) -> bool:
    return getattr(got, "key", None) == key and getattr(got, "data", None) == value
