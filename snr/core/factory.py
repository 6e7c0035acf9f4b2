"""Factories: build components for a node and reload their source code.

A config lists factories, not components, which must not start before their
node runs (thesis 6.2.10). A factory keeps its component's modules to reload
them; state kept on the factory survives the reload.
"""

from __future__ import annotations

import importlib
import sys
from types import ModuleType
from typing import Any, Dict, List, Optional, Sequence, Union

from snr.core.checks.call_checks import bad_reload_target, check_factory_class
from snr.prelude import AbstractComponent, AbstractFactory, AbstractNode, ComponentError

__all__ = ["EndpointFactory", "Factory", "LoopFactory", "ReloadTargets"]

ReloadTargets = Union[None, ModuleType, str, Sequence[Union[ModuleType, str]]]
"""What to reload: a module, a module name, a list of them, or None."""


def _as_module(target: Union[ModuleType, str], owner: type) -> ModuleType:
    if isinstance(target, ModuleType):
        return target
    if isinstance(target, str):
        return sys.modules.get(target) or importlib.import_module(target)
    raise ComponentError(bad_reload_target(owner, target))


class Factory(AbstractFactory):
    """Common base of `EndpointFactory` and `LoopFactory`.

    Example::

        class MyFactory(EndpointFactory):
            def __init__(self) -> None:
                super().__init__(my_endpoint)      # module(s) to hot-reload

            def get(self, parent: AbstractNode) -> MyEndpoint:
                return my_endpoint.MyEndpoint(self, parent)
    """

    def __init__(self, reload_targets: ReloadTargets = None) -> None:
        check_factory_class(type(self), Factory.get)
        if isinstance(reload_targets, (ModuleType, str)):
            reload_targets = [reload_targets]
        self.reload_targets = [_as_module(t, type(self)) for t in reload_targets or []]

    def get(self, parent: AbstractNode) -> Optional[AbstractComponent]:
        """Build the component for ``parent`` (override this), or return None."""
        raise NotImplementedError  # replaced by every subclass (checked in __init__)

    def reload(self) -> None:
        """Reload every module in ``reload_targets`` from its source file.

        Raises whatever the import raises (e.g. ``SyntaxError``): the node then
        keeps the old component running and reports the error.
        """
        fresh: List[ModuleType] = []
        for module in self.reload_targets:
            current = sys.modules.get(module.__name__, module)
            fresh.append(importlib.reload(current))
        self.reload_targets = fresh

    # Modules cannot be pickled; send their names instead so configs can be
    # passed to processes started with "spawn" (MultiProcRunner on macOS).
    def __getstate__(self) -> Dict[str, Any]:
        state = dict(self.__dict__)
        state["reload_targets"] = [m.__name__ for m in self.reload_targets]
        return state

    def __setstate__(self, state: Dict[str, Any]) -> None:
        names = state.pop("reload_targets", [])
        self.__dict__.update(state)
        self.reload_targets = [_as_module(name, type(self)) for name in names]

    def __repr__(self) -> str:
        return f"{type(self).__name__}()"


class EndpointFactory(Factory):
    """Subclass this to build an `Endpoint` (thesis listing A.2).

    Example::

        class DoublerFactory(EndpointFactory):
            def get(self, parent: AbstractNode) -> Doubler:
                return Doubler(self, parent)
    """


class LoopFactory(Factory):
    """Subclass this to build a `ThreadLoop` (thesis listing A.9).

    Example::

        class ClockFactory(LoopFactory):
            def get(self, parent: AbstractNode) -> Clock:
                return Clock(self, parent)
    """
