"""Lesson 7: a task queue for many producers. `starter`, `solution`, `grader`; docs/lessons.md."""

from typing import List

__all__: List[str] = []
