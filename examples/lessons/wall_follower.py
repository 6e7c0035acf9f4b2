"""Lesson 1: a wall follower (docs/lessons.md), run from the lessons' folder.

The lesson's code is ``snr/extras/demo/wall_follower.py`` (read it there): it ships
inside the package so that ``python -m snr demo --sim`` runs it from an
installed SNR too. This file runs it, with the same options::

    python examples/lessons/wall_follower.py --seconds 30
    python examples/lessons/wall_follower.py --seconds 5 --frames my_frames

To change the controller, copy ``snr/extras/demo/wall_follower.py`` here and edit it.
"""

import sys

from snr.extras.demo.wall_follower import *
from snr.extras.demo.wall_follower import main

if __name__ == "__main__":
    main(sys.argv)
