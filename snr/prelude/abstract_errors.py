"""Why a class cannot be built: the methods it lacks, in words (thesis 7.3).

Instead of Python's "Can't instantiate abstract class X with abstract methods
halt", SNR's interfaces raise the ComponentError made here (loaded only then).

Example::

    missing_methods_error(HalfEndpoint)
    # Cannot create HalfEndpoint (robot.py:5): it lacks these methods that
    # AbstractEndpoint requires: halt, terminate. Easiest fix: subclass ...
"""

from __future__ import annotations

import re
from typing import Any, Dict, List, Optional

from snr.prelude.errors import ComponentError
from snr.prelude.student_code import describe_class, frame_location

__all__ = ["explain_abstract_error", "missing_methods_error"]

_SNR_INTERFACES = "snr.prelude.abstract"
_EASY_FIX = {
    "AbstractLoop": (
        "subclass snr.ThreadLoop instead of AbstractLoop: it runs loop() on its own "
        "thread and provides everything else (setup(), halt() and terminate() do "
        "nothing unless you override them). Then write `def loop(self) -> None:`."
    ),
    "AbstractEndpoint": (
        "subclass snr.Endpoint instead of AbstractEndpoint: it provides all of these "
        "(begin(), halt() and terminate() do nothing unless you override them)."
    ),
    "AbstractComponent": (
        "subclass snr.Endpoint (or snr.ThreadLoop for code that loops on its own "
        "thread): they provide all of these."
    ),
    "AbstractFactory": (
        "subclass snr.EndpointFactory or snr.LoopFactory instead of AbstractFactory: "
        "they provide reload(); you write only "
        "`def get(self, parent: AbstractNode) -> MyEndpoint:`."
    ),
}


def missing_methods_error(cls: type, created_at: str = "") -> ComponentError:
    """The ComponentError for building ``cls`` while it lacks required methods.

    Example::

        missing_methods_error(HalfEndpoint)
        # Cannot create HalfEndpoint (robot.py:5): it lacks these methods that
        # AbstractEndpoint requires: halt, terminate. Easiest fix: subclass ...
    """
    # The nearest of SNR's interfaces that cls subclasses: AbstractLoop before AbstractComponent.
    interface = next(
        (b for b in cls.__mro__ if b.__module__ == _SNR_INTERFACES and b.__name__ in _EASY_FIX),
        None,
    )
    by_requirer: Dict[type, List[str]] = {}
    for name in sorted(getattr(cls, "__abstractmethods__", ())):
        # the nearest base class that declares the method abstract
        declares = (
            b for b in cls.__mro__[1:] if getattr(vars(b).get(name), "__isabstractmethod__", 0)
        )
        requirer = next(declares, cls)
        if requirer.__module__ == _SNR_INTERFACES:  # one of SNR's: name the one cls subclasses
            requirer = interface or requirer
        by_requirer.setdefault(requirer, []).append(name)
    lacks, fixes = [], []
    for requirer, names in by_requirer.items():
        lacks.append(f"that {requirer.__name__} requires: {', '.join(names)}")
        if requirer is interface:
            fixes.append("Easiest fix: " + _EASY_FIX[requirer.__name__] + " Or add them.")
        else:
            fixes.append(
                f"Add {', '.join(names)} to {cls.__name__}, with the same arguments as "
                f"in {requirer.__name__}."
            )
    where = f" (It was being created at {created_at}.)" if created_at else ""
    return ComponentError(
        f"Cannot create {describe_class(cls)}: it lacks these methods {'; and '.join(lacks)}. "
        f"{' '.join(fixes)}{where}"
    )


def explain_abstract_error(error: TypeError) -> Optional[ComponentError]:
    """Re-word Python's "Can't instantiate abstract class" TypeError (any class), or None.

    Example::

        try:
            component = factory.get(node)
        except TypeError as error:
            raise (explain_abstract_error(error) or error) from error
    """
    match = re.search(r"Can't instantiate abstract class (\w+)", str(error))
    if match is None:
        return None
    name = match.group(1)
    tb = error.__traceback__
    while tb is not None and tb.tb_next is not None:
        tb = tb.tb_next
    cls: Any = None
    created_at = ""
    if tb is not None:  # the frame that called the class: look the name up there
        frame = tb.tb_frame
        cls = frame.f_locals.get(name, frame.f_globals.get(name))
        created_at = frame_location(frame, tb.tb_lineno)
    if not isinstance(cls, type) or not getattr(cls, "__abstractmethods__", None):
        where = f" (It was being created at {created_at}.)" if created_at else ""
        return ComponentError(
            f"Cannot create {name}: it lacks methods that its base class requires "
            f"({error}). Add them to {name}.{where}"
        )
    return missing_methods_error(cls, created_at)
