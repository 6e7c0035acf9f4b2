"""Lesson 3: lesson 1's wall follower seeing by lidar (docs/lessons.md), from the lessons' folder.

The lesson's code is ``snr/extras/lessons/l03_scan_follower/solution.py``
(read it there), shipped in the package with the lesson's starter file and
grader (``python -m snr lesson start 3``). This file runs it, with lesson 1's
options::

    python examples/lessons/scan_follower.py --seconds 30
    python examples/lessons/scan_follower.py --seconds 60 --speed 0
"""

import sys

from snr.extras.lessons.l03_scan_follower.solution import *
from snr.extras.lessons.l03_scan_follower.solution import main

if __name__ == "__main__":
    main(sys.argv)
