"""`Config`: the blueprint of a system, one factory list per role."""

from __future__ import annotations

from typing import Callable, Dict, List, Mapping, Optional, Sequence

from snr.core.checks.call_checks import check_config_args, check_role
from snr.core.checks.profiler import Profiler
from snr.core.clock import NodeClock
from snr.core.node import NodeCoreFactory
from snr.prelude.abstract import AbstractConfig, AbstractFactory, AbstractProfiler, Datastore
from snr.prelude.names import Mode, Role

__all__ = ["Config"]


class Config(AbstractConfig):
    """Which components each role's node gets, and how strict nodes are.

    Args:
        factories: for every role, the factories of its components.
        mode: ``Mode.DEBUG`` (default), ``Mode.TEST`` or ``Mode.DEPLOYED``.
        profile: time every handler; defaults to on in DEBUG mode only.
        clock: a `SimClock` to run every node built from this config in
            simulated time (docs/simulator.md); None (the default): the wall clock.
        datastore: what makes each node's `Datastore`, called with no
            arguments: None (the default) is ``dict``, SNR's own; or a class
            of your own.
        node_core: the factory of each node's core endpoint (a `NodeCore`):
            None (the default) is ``NodeCoreFactory()``, SNR's own.
            docs/assignments.md: writing either yourself.

    Example::

        config = snr.Config(factories={
            "lunar_module": [RadarSensorLoopFactory(100), ControllerFactory()],
        })
        snr.SynchronousRunner("lunar_module", config).run()

        snr.Config({"sim": [...]}, clock=snr.SimClock())   # faster than real time
        snr.Config({"sim": [...]}, datastore=MyDatastore, node_core=MyNodeCoreFactory())
    """

    def __init__(
        self,
        factories: Optional[Mapping[Role, Sequence[AbstractFactory]]] = None,
        mode: Mode = Mode.DEBUG,
        profile: Optional[bool] = None,
        clock: Optional[NodeClock] = None,
        datastore: Optional[Callable[[], Datastore]] = None,
        node_core: Optional[AbstractFactory] = None,
    ) -> None:
        from snr.core.checks.seam_checks import check_seam_args

        if factories is None:
            factories = {}
        check_config_args(Config, factories, mode, clock)
        self.factories: Dict[Role, List[AbstractFactory]] = {
            role: list(f) for role, f in factories.items()
        }
        self.mode = mode
        self.profile = (mode is Mode.DEBUG) if profile is None else profile
        self.clock = clock
        check_seam_args(datastore, node_core)
        self.datastore: Callable[[], Datastore] = dict if datastore is None else datastore
        self.node_core = NodeCoreFactory() if node_core is None else node_core

    def roles(self) -> List[Role]:
        """Every role in the config, in the order written."""
        return list(self.factories)

    def get(self, role: Role) -> List[AbstractFactory]:
        """The factories for ``role``.

        Raises:
            ConfigError: the role is unknown (the message lists the known ones
                and the closest match) or has no factories.
        """
        check_role(role, self.factories)
        return list(self.factories[role])

    def get_profiler(self) -> Optional[AbstractProfiler]:
        """A new `Profiler` when profiling is on, else None."""
        return Profiler() if self.profile else None

    def __repr__(self) -> str:
        clock = "" if self.clock is None else f", clock={self.clock!r}"
        return f"Config(roles={self.roles()!r}, mode={self.mode}{clock})"
