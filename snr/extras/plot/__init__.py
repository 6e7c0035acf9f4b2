"""Pictures of a run: ``python -m snr plot RECORDING KEY...`` draws keys over time.

One subplot per key, each numeric field of its data a line, written to a
PNG file. It needs matplotlib (``pip install 'snr-robotics[plot]'``), which
draws without a screen (on a robot, over SSH). In a notebook,
`snr.read_recording` gives the same columns to plot your own way.

Example::

    from snr.extras.plot import plot_recording

    plot_recording("dive.jsonl", ["depth_m", "heading_deg"], "dive.png")
"""

from snr.extras.plot.columns import Column, Recording, read_recording
from snr.extras.plot.command import add_arguments, plot_recording, run

__all__ = ["Column", "Recording", "add_arguments", "plot_recording", "read_recording", "run"]
