"""See your robot: MCAP recordings and the live view for Foxglove or Lichtblick.

Needs ``pip install 'snr-robotics[viz]'`` (mcap and websockets; ``[view]`` or
``[mcap]`` installs one of them). ``mcap_files`` writes and reads MCAP
(the recorder and replayer find it through the entry point
``snr.recording_formats``, ``mcap_format``), ``convert`` is
``python -m snr convert``, ``live_view`` serves a node's pages over the
Foxglove WebSocket protocol (`FoxgloveBridgeFactory`).

Example::

    from snr.extras.viz import FoxgloveBridgeFactory

    components = {"topside": [FoxgloveBridgeFactory(["depth_m"])]}
"""

from snr.extras.viz.convert import convert_recording
from snr.extras.viz.live_view import FoxgloveBridge, FoxgloveBridgeFactory

__all__ = ["FoxgloveBridge", "FoxgloveBridgeFactory", "convert_recording"]
