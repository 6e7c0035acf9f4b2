"""Lesson 1: a wall follower (docs/lessons.md), run from the lessons' folder.

The lesson's code is ``snr/extras/lessons/l01_wall_follower/solution.py`` (read
it there): it ships inside the package, so that ``python -m snr demo --sim``
runs it from an installed SNR too, with the lesson's starter file and grader
(``python -m snr lesson start 1``). This file runs it, with the same options::

    python examples/lessons/wall_follower.py --seconds 30
    python examples/lessons/wall_follower.py --seconds 5 --frames my_frames
"""

import sys

from snr.extras.lessons.l01_wall_follower.solution import *
from snr.extras.lessons.l01_wall_follower.solution import main

if __name__ == "__main__":
    main(sys.argv)
