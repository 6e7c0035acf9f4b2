"""Lesson 5: a datastore of your own. `starter`, `solution`, `grader`; the text: docs/lessons.md."""

from typing import List

__all__: List[str] = []
