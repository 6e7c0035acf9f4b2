"""help() and inspect.signature show what a student must pass to SNR's classes.

SNR's ABCs have a metaclass with its own ``__call__`` (to explain a missing
method in plain words); without care, that hides every constructor behind
``(*args, **kwargs)``.
"""

import inspect
import pydoc
import unittest
from typing import List

import snr
from snr.prelude import ComponentError


def _public_classes() -> List[type]:
    return [
        getattr(snr, name)
        for name in snr.__all__
        if isinstance(getattr(snr, name), type) and not name.startswith("_")
    ]


def _init_takes_only_star_args(cls: type) -> bool:
    # The __init__ the class defines or inherits, not what its metaclass makes of a call.
    init = inspect.signature(inspect.getattr_static(cls, "__init__"))
    kinds = {p.kind for p in list(init.parameters.values())[1:]}
    return kinds <= {inspect.Parameter.VAR_POSITIONAL, inspect.Parameter.VAR_KEYWORD}


class TestRealSignatures(unittest.TestCase):
    def test_node_shows_role_and_config(self) -> None:
        self.assertEqual(list(inspect.signature(snr.Node).parameters), ["role", "config"])

    def test_timeout_factory_shows_its_arguments(self) -> None:
        self.assertEqual(
            str(inspect.signature(snr.TimeoutLoopFactory)),
            "(seconds: 'float' = 0.0, ms: 'float' = 0.0, name: 'Optional[str]' = None) -> None",
        )

    def test_help_shows_the_signature(self) -> None:
        text = pydoc.plain(pydoc.render_doc(snr.ThreadLoop))  # as help() prints it
        self.assertIn("ThreadLoop(factory: 'AbstractFactory', parent:", text)
        self.assertNotIn("ThreadLoop(*args", text)

    def test_no_public_class_hides_behind_star_args(self) -> None:
        hidden = []
        for cls in _public_classes():
            try:
                signature = inspect.signature(cls)
            except (TypeError, ValueError):
                continue  # builtins such as enums' members without a signature
            kinds = {p.kind for p in signature.parameters.values()}
            star_only = kinds == {
                inspect.Parameter.VAR_POSITIONAL,
                inspect.Parameter.VAR_KEYWORD,
            }
            if star_only and not _init_takes_only_star_args(cls):
                hidden.append(cls.__name__)
        self.assertEqual(hidden, [])

    def test_abstract_class_still_explains_missing_methods(self) -> None:
        class NoLoop(snr.ThreadLoop):
            pass

        with self.assertRaises(ComponentError):
            # No factory or node: the missing method is reported before they are used.
            NoLoop(None, None, "x")  # type: ignore[arg-type]


if __name__ == "__main__":
    unittest.main()
