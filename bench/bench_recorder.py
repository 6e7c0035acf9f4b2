"""What recording costs: the page codec, and a node storing pages with a recorder.

1. Encoding and decoding one page: the recorder's stdlib-json lines
   (``page_to_line`` / ``page_from_line``) against the dataclasses-json
   ``Page.serialize()`` / ``Page.deserialize()`` baseline.
2. A node storing N pages: without a recorder (the baseline), with a
   recorder (one write + flush per page), and with ``sync=True`` (an fsync
   per page; on a laptop SSD this is the slow one).
3. MCAP (when the mcap package is installed: ``pip install 'snr-robotics[mcap]'``):
   raw ``mcap`` writes (``json.dumps`` + ``add_message`` + flush per page)
   against SNR's `McapPageWriter`, and a node recording to MCAP against
   the same node recording JSON lines, all in this one run.

Run: ``python bench/bench_recorder.py [--pages N]`` (or ``nox -s bench``).
"""

from __future__ import annotations

import argparse
import importlib.util
import json
import logging
import os
import shutil
import tempfile
import time
from typing import Any, Callable, List, Optional

from snr import (
    AbstractFactory,
    AbstractNode,
    Config,
    Endpoint,
    EndpointFactory,
    Mode,
    Node,
    Page,
    RecorderEndpointFactory,
    SomeTasks,
    Task,
    TaskId,
    TaskType,
    tasks,
)
from snr.extras.viz.mcap_files import McapPageWriter
from snr.prelude.install import install_hint
from snr.std_mods.codec import page_from_line, page_to_line

SAMPLE = Page("imu", {"ax": 0.01, "ay": -9.81, "az": 0.2, "ok": True}, "urov", 1.7e9)


def sample_now() -> Page:
    """The sample page, made now (as a recorder sees each new page)."""
    return Page("imu", SAMPLE.data, "urov", time.time())


def per_second(action: Callable[[], object], repeat: int) -> float:
    started = time.perf_counter()
    for _ in range(repeat):
        action()
    return repeat / (time.perf_counter() - started)


class Burst(Endpoint):
    """Schedules ``count`` pages at start; stops the node when the last is stored."""

    def __init__(self, factory: BurstFactory, parent: AbstractNode) -> None:
        super().__init__(factory, parent, "burst")
        self.burst = factory
        self.task_handlers = {(TaskType.store_page, "imu"): self.on_page}
        self.seen = 0

    def begin(self) -> None:
        self.burst.started = time.perf_counter()
        self.schedule([self.store_data_task("imu", SAMPLE.data) for _ in range(self.burst.count)])

    def on_page(self, task: Task, key: TaskId) -> SomeTasks:
        self.seen += 1
        if self.seen < self.burst.count:
            return None
        self.burst.finished = time.perf_counter()
        return tasks.terminate("burst stored")


class BurstFactory(EndpointFactory):
    def __init__(self, count: int) -> None:
        super().__init__()
        self.count = count
        self.started = 0.0
        self.finished = 0.0

    def get(self, parent: AbstractNode) -> Burst:
        return Burst(self, parent)


def node_pages_per_second(count: int, recorder: Optional[AbstractFactory]) -> float:
    burst = BurstFactory(count)
    factories: List[AbstractFactory] = [burst] + ([recorder] if recorder else [])
    Node("bench", Config({"bench": factories}, mode=Mode.DEPLOYED, profile=False)).loop()
    return count / (burst.finished - burst.started)


def raw_mcap_per_second(path: str, count: int) -> float:
    """The mcap package alone: one JSON channel, each message written and flushed."""
    from mcap.writer import CompressionType, Writer

    with open(path, "wb") as file:
        writer: Any = Writer(file, compression=CompressionType.NONE, use_chunking=False)
        writer.start()
        schema = writer.register_schema("imu", "jsonschema", b'{"type":"object"}')
        channel = writer.register_channel("/imu", "json", schema)

        def write() -> None:  # the same page, the same bytes as SNR writes
            now = time.time()
            fields = {"key": "imu", "data": SAMPLE.data, "origin": "urov", "created_at_s": now}
            fields["process"] = True
            body = json.dumps(fields, separators=(",", ":")).encode()
            when = int(now * 1e9)
            writer.add_message(channel, log_time=when, data=body, publish_time=when)
            file.flush()

        rate = per_second(write, count)
        writer.finish()
    return rate


def page_writer_per_second(path: str, count: int) -> float:
    """SNR's McapPageWriter: the codec's line, the channel lookup, a flush per page."""
    with open(path, "wb") as file:
        writer = McapPageWriter(file)
        rate = per_second(lambda: writer.write(sample_now()), count)
        writer.close()
    return rate


def lines_per_second(path: str, count: int) -> float:
    """What the JSON-lines recorder does per page, without the node: encode, write, flush."""
    with open(path, "w", encoding="utf-8", newline="\n") as file:

        def write() -> None:
            file.write(page_to_line(sample_now()) + "\n")
            file.flush()

        return per_second(write, count)


def mcap_table(folder: str, n: int, rounds: int) -> None:
    """MCAP beside JSON lines and beside raw mcap writes: interleaved, best of ``rounds``."""
    if importlib.util.find_spec("mcap") is None:
        print(f"\nMCAP: skipped, the mcap package is not installed ({install_hint('mcap')})")
        return
    mcap_path, jsonl_path = os.path.join(folder, "m.mcap"), os.path.join(folder, "j.jsonl")
    raw = writer = lines = jsonl = recorded = 0.0
    for _ in range(rounds):  # interleaved, so a busy moment slows every row alike
        raw = max(raw, raw_mcap_per_second(mcap_path, n))
        writer = max(writer, page_writer_per_second(mcap_path, n))
        lines = max(lines, lines_per_second(jsonl_path, n))
        jsonl_recorder = RecorderEndpointFactory(jsonl_path, ["imu"], overwrite=True)
        jsonl = max(jsonl, node_pages_per_second(n, jsonl_recorder))
        mcap_recorder = RecorderEndpointFactory(mcap_path, ["imu"], overwrite=True)
        recorded = max(recorded, node_pages_per_second(n, mcap_recorder))
    print(f"\nMCAP beside JSON lines, flushed per page ({n} pages, best of {rounds})")
    print(f"  {'':34} {'pages/s':>10} {'ratio':>7}")
    print(f"  {'raw mcap writes (baseline)':34} {raw:10,.0f} {1.0:7.2f}")
    print(f"  {'McapPageWriter.write':34} {writer:10,.0f} {writer / raw:7.2f}")
    print(f"  {'a JSON line written and flushed':34} {lines:10,.0f} {lines / raw:7.2f}")
    print(f"  {'node + JSON-lines recorder (base)':34} {jsonl:10,.0f} {1.0:7.2f}")
    print(f"  {'node + MCAP recorder':34} {recorded:10,.0f} {recorded / jsonl:7.2f}")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--pages", type=int, default=20_000)
    parser.add_argument("--rounds", type=int, default=3, help="MCAP table: best of this many")
    args, _ = parser.parse_known_args()
    logging.getLogger("snr.bench").setLevel(logging.WARNING)  # no "terminated" lines
    n = args.pages
    line = page_to_line(SAMPLE)
    text = SAMPLE.serialize()

    print(f"Page codec, {n} pages (higher is better)")
    base_enc = per_second(SAMPLE.serialize, n)
    base_dec = per_second(lambda: Page.deserialize(text), n)
    enc = per_second(lambda: page_to_line(SAMPLE), n)
    dec = per_second(lambda: page_from_line(line), n)
    print(f"  {'':34} {'pages/s':>10} {'ratio':>7}")
    print(f"  {'Page.serialize (baseline)':34} {base_enc:10,.0f} {1.0:7.1f}")
    print(f"  {'page_to_line':34} {enc:10,.0f} {enc / base_enc:7.1f}")
    print(f"  {'Page.deserialize (baseline)':34} {base_dec:10,.0f} {1.0:7.1f}")
    print(f"  {'page_from_line':34} {dec:10,.0f} {dec / base_dec:7.1f}")

    folder = tempfile.mkdtemp(prefix="snr-bench-")
    path = os.path.join(folder, "bench.jsonl")
    sync_n = max(1, n // 20)  # fsync is slow: fewer pages
    print(f"\nA node storing pages, DEPLOYED mode ({n} pages; {sync_n} with fsync)")
    plain = node_pages_per_second(n, None)
    recorded = node_pages_per_second(n, RecorderEndpointFactory(path, ["imu"]))
    synced = node_pages_per_second(sync_n, RecorderEndpointFactory(path, ["imu"], sync=True))
    print(f"  {'':34} {'pages/s':>10} {'ratio':>7}")
    print(f"  {'no recorder (baseline)':34} {plain:10,.0f} {1.0:7.2f}")
    print(f"  {'recorder (write + flush per page)':34} {recorded:10,.0f} {recorded / plain:7.2f}")
    print(f"  {'recorder, sync=True (fsync)':34} {synced:10,.0f} {synced / plain:7.3f}")
    mcap_table(folder, n, args.rounds)
    shutil.rmtree(folder)  # the recorder kept each earlier run beside the file


if __name__ == "__main__":
    main()
