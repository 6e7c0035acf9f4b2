"""SNR's own tests.

They never use the secret of whoever runs them: a developer with
``~/.config/snr/secret`` (or ``$SNR_SECRET``) would otherwise run every
link and console of the suite authenticated, and the tests that speak the
plain wire format from a socket would be refused. Tests that need a secret
set one themselves (tests/test_comms_trust.py, tests/test_console_secret.py).
"""

import os

os.environ.pop("SNR_SECRET", None)
# A file that does not exist: no secret unless a test gives one.
os.environ["SNR_SECRET_FILE"] = os.path.join(os.devnull + ".missing", "secret")
