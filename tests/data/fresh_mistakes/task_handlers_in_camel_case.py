# robot.py
from snr import *

class Greeter(Endpoint):
    def __init__(self, factory: EndpointFactory, parent: AbstractNode) -> None:
        super().__init__(factory, parent, "greeter")
        self.taskHandlers = {(TaskType.event, "hello"): self.greet}

    def greet(self, task: Task, key: TaskId) -> SomeTasks:
        print("hello!")
        return None


class GreeterFactory(EndpointFactory):
    def get(self, parent: AbstractNode) -> Greeter:
        return Greeter(self, parent)


CliRunner({"robot": [GreeterFactory(), TimeoutLoopFactory(seconds=1)]}).run()
