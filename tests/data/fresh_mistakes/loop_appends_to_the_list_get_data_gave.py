# robot.py
from snr import *

class Trail(ThreadLoop):
    def __init__(self, factory: LoopFactory, parent: AbstractNode) -> None:
        super().__init__(factory, parent, "trail", max_tick_rate_hz=20)

    def loop(self) -> None:
        trail = self.get_data("trail")
        if trail is None:
            self.store_data("trail", [])
        else:
            trail.append(len(trail))


class TrailFactory(LoopFactory):
    def get(self, parent: AbstractNode) -> Trail:
        return Trail(self, parent)


CliRunner({"robot": [TrailFactory(), TimeoutLoopFactory(seconds=1)]}).run()
