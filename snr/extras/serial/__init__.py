"""Serial links to microcontrollers, and the board protocol (heartbeats, failsafe).

Needs ``pip install 'snr-robotics[serial]'`` (pyserial). ``link`` exchanges pages or
text lines over a serial port (`SerialLinkFactory`), ``port`` opens ports
with errors that explain, ``board`` is the protocol of SNR's board sketches.

Example::

    from snr.extras.serial import SerialLinkFactory

    components = {"urov": [SerialLinkFactory("/dev/ttyACM0", send_keys=["thrust"])]}
"""

from snr.extras.serial.link import SerialLinkFactory, SerialLinkLoop

__all__ = ["SerialLinkFactory", "SerialLinkLoop"]
