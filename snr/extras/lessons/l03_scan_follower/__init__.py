"""Lesson 3: lesson 1's wall follower, seeing by lidar. `starter`, `solution`, `grader`.

The lesson's text is docs/lessons.md.
"""

from typing import List

__all__: List[str] = []
