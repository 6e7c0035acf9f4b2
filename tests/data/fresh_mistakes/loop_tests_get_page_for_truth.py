# robot.py
from snr import *

class Bumper(ThreadLoop):
    def __init__(self, factory: LoopFactory, parent: AbstractNode) -> None:
        super().__init__(factory, parent, "bumper", max_tick_rate_hz=20)
        self.said = False

    def loop(self) -> None:
        if self.get_page("bumped") and not self.said:
            print("bumped: backing up")
            self.said = True


class BumperFactory(LoopFactory):
    def get(self, parent: AbstractNode) -> Bumper:
        return Bumper(self, parent)


CliRunner({"robot": [
    ListReplayerFactory([False], "bumped"),
    BumperFactory(),
    TimeoutLoopFactory(seconds=1),
]}).run()
