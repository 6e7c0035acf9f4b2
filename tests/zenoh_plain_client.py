"""A Zenoh program that is not SNR: reads SNR pages and publishes one (test helper).

Usage: ``python tests/zenoh_plain_client.py ENDPOINT SYSTEM COUNT``. It connects
to ENDPOINT, prints the first COUNT samples under ``snr/SYSTEM/**`` as JSON
lines (key expression, encoding, payload), publishes ``{"data": 42}`` under
``snr/SYSTEM/from_plain`` until told to stop on stdin, and checks that nothing
of SNR was imported. It imports only ``zenoh`` and the standard library, as a
program in any language would use only its own Zenoh binding.
"""

from __future__ import annotations

import json
import sys
import threading
import time
from typing import Any, Dict, List

import zenoh


def main() -> int:
    endpoint, system, count = sys.argv[1], sys.argv[2], int(sys.argv[3])
    config = zenoh.Config()
    config.insert_json5("mode", '"peer"')
    config.insert_json5("scouting/multicast/enabled", "false")
    config.insert_json5("connect/endpoints", json.dumps([endpoint]))
    samples: List[Dict[str, Any]] = []
    got_all = threading.Event()

    def on_sample(sample: zenoh.Sample) -> None:
        if len(samples) < count:
            samples.append(
                {
                    "key_expr": str(sample.key_expr),
                    "encoding": str(sample.encoding),
                    "payload": json.loads(sample.payload.to_bytes()),
                }
            )
        if len(samples) >= count:
            got_all.set()

    session = zenoh.open(config)
    subscriber = session.declare_subscriber(f"snr/{system}/**", on_sample)
    publisher = session.declare_publisher(
        f"snr/{system}/from_plain", encoding=zenoh.Encoding.APPLICATION_JSON
    )
    got_all.wait(10.0)
    for sample in samples:
        print(json.dumps(sample), flush=True)
    print(json.dumps({"snr_imported": any(m.split(".")[0] == "snr" for m in sys.modules)}))
    print("publishing", flush=True)
    stop = threading.Event()

    def stop_when_told() -> None:
        sys.stdin.readline()
        stop.set()

    threading.Thread(target=stop_when_told, daemon=True).start()
    deadline = time.monotonic() + 10.0
    while not stop.is_set() and time.monotonic() < deadline:  # until the node has it
        publisher.put(b'{"data": 42}')
        stop.wait(0.02)
    subscriber.undeclare()
    publisher.undeclare()
    session.close()
    return 0


if __name__ == "__main__":
    sys.exit(main())
