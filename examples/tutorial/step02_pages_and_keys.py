"""Tutorial step 2: pages and keys.

Endpoints never call each other. One stores data under a key; storing it is a
task, and any endpoint registered for that key reacts. Here a thermometer
stores readings under ``temperature_c``; a converter reacts and stores
``temperature_f``; a reporter reacts to that and prints it.

    python step02_pages_and_keys.py

prints three lines such as ``temperature_f = 68.0 (from thermometer_node)``,
then the newest Celsius reading in the node's datastore.
"""

from typing import List

from snr import (
    AbstractNode,
    Config,
    Endpoint,
    EndpointFactory,
    Page,
    SomeTasks,
    SynchronousRunner,
    Task,
    TaskId,
    TaskType,
    tasks,
)

READINGS_C: List[float] = [20.0, 21.5, 23.0]


class Thermometer(Endpoint):
    """Stores a few readings when the node starts (step 3 shows a real sensor loop)."""

    def __init__(self, factory: EndpointFactory, parent: AbstractNode) -> None:
        super().__init__(factory, parent, "thermometer")

    def begin(self) -> None:
        for reading in READINGS_C:
            # Queue a task that puts a page under the key "temperature_c".
            self.store_data("temperature_c", reading)


class CelsiusToFahrenheit(Endpoint):
    """Converts every page stored under ``temperature_c``."""

    def __init__(self, factory: EndpointFactory, parent: AbstractNode) -> None:
        super().__init__(factory, parent, "converter")
        # A store_page task is named after the page's key.
        self.task_handlers = {(TaskType.store_page, "temperature_c"): self.convert}

    def convert(self, task: Task, key: TaskId) -> SomeTasks:
        page = task.val_list[0]  # the stored page travels in the task
        if not isinstance(page, Page) or not isinstance(page.data, (int, float)):
            self.warn("Expected a number, got %s", task)
            return None
        return self.store_data_task("temperature_f", page.data * 9 / 5 + 32)


class Reporter(Endpoint):
    """Prints each Fahrenheit page once it is in the datastore; stops after three."""

    def __init__(self, factory: EndpointFactory, parent: AbstractNode) -> None:
        super().__init__(factory, parent, "reporter")
        # process_data follows store_page once the page is in the datastore.
        self.task_handlers = {(TaskType.process_data, "temperature_f"): self.report}
        self.reported = 0

    def report(self, task: Task, key: TaskId) -> SomeTasks:
        page = task.val_list[0]  # this task's page: one of the three readings
        print(f"{page.key} = {page.data:.1f} (from {page.origin})")
        self.reported += 1
        if self.reported < len(READINGS_C):
            return None
        # The datastore keeps only the newest page under each key.
        print(f"newest temperature_c in the datastore: {self.get_data('temperature_c')}")
        return tasks.terminate("reported every reading")


class ThermometerFactory(EndpointFactory):
    def get(self, parent: AbstractNode) -> Thermometer:
        return Thermometer(self, parent)


class CelsiusToFahrenheitFactory(EndpointFactory):
    def get(self, parent: AbstractNode) -> CelsiusToFahrenheit:
        return CelsiusToFahrenheit(self, parent)


class ReporterFactory(EndpointFactory):
    def get(self, parent: AbstractNode) -> Reporter:
        return Reporter(self, parent)


config = Config(
    {
        "thermometer_node": [
            ThermometerFactory(),
            CelsiusToFahrenheitFactory(),
            ReporterFactory(),
        ]
    }
)

if __name__ == "__main__":
    SynchronousRunner("thermometer_node", config).run()
