"""Thesis listing 6.4: Pseudo code interface for datastore access.

Printed in section 6.2.6, AbstractNode (line 636 of the thesis text).
Not runnable: it is pseudo code (signatures without ``def`` or ``self``,
some ending in ``:``), kept here as printed in ``PRINTED``.
tests/test_listings.py checks what it states: ``snr.AbstractNode`` and
``snr.Node`` have each method, with these parameters in this order.
Deviations: none.
"""

PRINTED = """\
page(key: DataKey, data: Any, process: bool) -> Page
store_data(key: DataKey, data: Any, process: bool) -> None
get_page(key: DataKey) -> Optional[Page]
get_data(key: DataKey) -> Optional[Any]
"""
