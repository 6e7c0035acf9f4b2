"""A template for a new lesson: copy this folder, rename, and write your own.

It is a real lesson, small on purpose: stop a robot at a set distance from
the wall ahead, with one sensor ray and a proportional controller. Its
``starter``, ``solution`` and ``grader`` follow the shipped lessons' pattern;
docs/teaching.md ("How to write a new lesson") walks through them. It is not
in `snr.extras.lessons.LESSONS`, so ``python -m snr lesson list`` does not
show it; tests/test_lesson_template.py grades its solution and its starter,
so the template keeps working as the lessons' helpers change.
"""

from typing import List

__all__: List[str] = []
