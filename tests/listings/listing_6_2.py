"""Thesis listing 6.2: Pseudo code interface for task execution.

Printed in section 6.2.6, AbstractNode (line 609 of the thesis text).
Not runnable: it is pseudo code (signatures without ``def`` or ``self``,
some ending in ``:``), kept here as printed in ``PRINTED``.
tests/test_listings.py checks what it states: ``snr.AbstractNode`` and
``snr.Node`` have each method, with these parameters in this order.
Deviations: none.
"""

PRINTED = """\
get_task_handlers(task: Task) -> List[Tuple[TaskHandler, TaskId]]
handle_task(handler: TaskHandler, task: Task, key: TaskId
            ) -> Optional[List[Task]]
execute_task(t: Task) -> None:
"""
