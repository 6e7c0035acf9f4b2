# robot.py
from snr import *

class Arm(Endpoint):
    def __init__(self, factory: EndpointFactory, parent: AbstractNode) -> None:
        super().__init__(factory, parent, "arm")
        self.task_handlers = {}

    async def begin(self) -> None:
        print("arm ready")


class ArmFactory(EndpointFactory):
    def get(self, parent: AbstractNode) -> Arm:
        return Arm(self, parent)


CliRunner({"robot": [ArmFactory(), TimeoutLoopFactory(seconds=1)]}).run()
