"""Thesis listing 6.3: Pseudo code interface for task scheduling.

Printed in section 6.2.6, AbstractNode (line 624 of the thesis text).
Not runnable: it is pseudo code (signatures without ``def`` or ``self``,
some ending in ``:``), kept here as printed in ``PRINTED``.
tests/test_listings.py checks what it states: ``snr.AbstractNode`` and
``snr.Node`` have each method, with these parameters in this order.
Deviations: none.
"""

PRINTED = """\
schedule(t: SomeTasks) -> None
task_store_page(page: Page) -> Task
task_store_data(key: DataKey, data: Any, process: bool) -> Task
"""
