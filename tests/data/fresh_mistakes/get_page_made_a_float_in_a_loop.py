# robot.py
from snr import *

class DepthLog(ThreadLoop):
    def __init__(self, factory: LoopFactory, parent: AbstractNode) -> None:
        super().__init__(factory, parent, "depth_log", max_tick_rate_hz=20)

    def loop(self) -> None:
        depth = self.get_page("depth")
        if depth is not None:
            print(f"depth {float(depth):.1f} m")


class DepthLogFactory(LoopFactory):
    def get(self, parent: AbstractNode) -> DepthLog:
        return DepthLog(self, parent)


CliRunner({"robot": [
    ListReplayerFactory([2.5], "depth"),
    DepthLogFactory(),
    TimeoutLoopFactory(seconds=1),
]}).run()
