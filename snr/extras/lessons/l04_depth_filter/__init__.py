"""Lesson 4: a filter. `starter`, `solution` and `grader`; the text is docs/lessons.md."""

from typing import List

__all__: List[str] = []
