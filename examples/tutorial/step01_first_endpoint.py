"""Tutorial step 1: your first endpoint.

An endpoint is a class whose methods run when a task arrives. This one says
hello when it gets a ``say_hello`` event, then stops the node.

    python step01_first_endpoint.py

prints ``Hello, world!``, then the node logs why it stopped.
"""

from snr import (
    AbstractNode,
    Config,
    Endpoint,
    EndpointFactory,
    SomeTasks,
    SynchronousRunner,
    Task,
    TaskId,
    TaskType,
    tasks,
)


class HelloEndpoint(Endpoint):
    """Prints a greeting for every ``say_hello`` event."""

    def __init__(self, factory: EndpointFactory, parent: AbstractNode) -> None:
        # Every component has a factory, a parent node and a unique name.
        super().__init__(factory, parent, "hello")
        # Which method runs for which task: (type, name) -> handler.
        self.task_handlers = {(TaskType.event, "say_hello"): self.say_hello}

    def begin(self) -> None:
        # Runs once when the node starts: give ourselves something to do.
        self.schedule(tasks.event("say_hello", ["world"]))

    def say_hello(self, task: Task, key: TaskId) -> SomeTasks:
        print(f"Hello, {task.val_list[0]}!")
        # A handler returns the tasks that follow: here, stop the node.
        return tasks.terminate("said hello")


class HelloFactory(EndpointFactory):
    """Builds the endpoint when the node is made (a config holds factories)."""

    def get(self, parent: AbstractNode) -> HelloEndpoint:
        return HelloEndpoint(self, parent)


# A config says which components each role's node gets.
config = Config({"greeter": [HelloFactory()]})

if __name__ == "__main__":
    SynchronousRunner("greeter", config).run()
