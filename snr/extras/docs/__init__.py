"""The documentation builder: ``python -m snr docs`` (the guide and the API reference).

Needs ``pip install 'snr-robotics[docs]'`` (pdoc). ``docsite`` builds and serves the
docs; ``api_topics`` sorts what ``from snr import *`` gives into the topics
of the reference's start page. The kernel finds ``docsite`` through the
entry point ``snr.commands``; ``import snr`` does not load it. It ships
inside the package so that ``python -m snr docs`` works after a plain
``pip install``.

Example::

    python -m snr docs --build-only     # snr.extras.docs.docsite
"""

from typing import List

__all__: List[str] = []
