"""Thesis listing 6.1: Pseudo code interface for node control flow.

Printed in section 6.2.6, AbstractNode (line 596 of the thesis text).
Not runnable: it is pseudo code (signatures without ``def`` or ``self``,
some ending in ``:``), kept here as printed in ``PRINTED``.
tests/test_listings.py checks what it states: ``snr.AbstractNode`` and
``snr.Node`` have each method, with these parameters in this order.
Deviations: none.
"""

PRINTED = """\
loop() -> None
set_terminate_flag(reason: str) -> None:
terminate() -> None:
is_terminated() -> bool:
"""
