"""Lesson 2: go to a goal (docs/lessons.md), run from the lessons' folder.

The lesson's code is ``snr/extras/lessons/l02_go_to_goal/solution.py`` (read it
there): it ships inside the package, with the lesson's starter file and grader
(``python -m snr lesson start 2``). This file runs it, with the same options::

    python examples/lessons/go_to_goal.py --seconds 30
    python examples/lessons/go_to_goal.py --seconds 5 --frames my_frames
"""

import sys

from snr.extras.lessons.l02_go_to_goal.solution import *
from snr.extras.lessons.l02_go_to_goal.solution import main

if __name__ == "__main__":
    main(sys.argv)
