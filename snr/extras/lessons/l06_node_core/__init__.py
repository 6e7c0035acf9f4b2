"""Lesson 6: a node core of your own. `starter`, `solution`, `grader`; the text: docs/lessons.md."""

from typing import List

__all__: List[str] = []
