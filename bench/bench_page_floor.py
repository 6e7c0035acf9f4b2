"""The least a page can cost in CPython, sent and received, against pyzmq's message.

`bench_comms.py` compares two SNR nodes with pyzmq PUSH/PULL. This bench
asks how much of SNR's cost no node design can avoid. Each row is one
thread's CPU time (``time.thread_time``) per message. Sending, with a
separate process draining the socket:

* **pyzmq PUSH**: ``push.send(orjson.dumps(body))``, the PUSH/PULL row of
  `bench_comms.py`; libzmq's own I/O thread does the system calls, off the
  interpreter's lock, and is not counted (that is its advantage);
* **SNR floor**: what every page a node sends must be, with nothing of the
  node around it: its data, a `Page`, a `Task` holding it, the datastore
  write, the frame (`encode_page`, the exact bytes of docs/wire-format.md)
  and its share of one ``sendall`` per 1,000 frames;
* **+ one handler call**: the floor plus one look-up and one call of a
  handler per page (the comms component's), as the run loop makes.

Receiving, with a separate process pushing (pyzmq) or from frames made
beforehand (SNR: no socket, so the floor is lower than any node's):

* **pyzmq PULL**: ``orjson.loads(pull.recv())`` and the benchmark's check
  of the sequence number, the PUSH/PULL row's receiver;
* **SNR floor**: the frames cut from 256 KiB reads (`FrameDecoder`), each
  decoded as strictly as docs/wire-format.md says (`decode_body`), the page
  written to the datastore, a ``process_data`` `Task` for it, and one
  handler look-up and call doing the same check: what a page must go
  through to reach a student's handler.

The targets of `bench_comms.py` are rates of the whole pipeline, where a
sending node's thread costs what it costs (3.8 µs a page in DEBUG mode when
this was written): the difference between that and the floor is the node's
own work (dispatch, the outbox, the profiler's clock in DEBUG mode), which
is what a faster node can still save. See docs/performance.md.

With Zenoh installed (``pip install 'snr-robotics[zenoh]'``), two sending rows more,
between two sessions of this process: **raw Zenoh put** (the raw row of
`bench_zenoh.py`: ``publisher.put(orjson.dumps(body))``) and **SNR floor
over Zenoh** (the page, its task, the datastore write, `PageEncoder` and a
``put`` with the 16-byte count SNR attaches to every sample).

Run: ``python bench/bench_page_floor.py [--messages N] [--rounds N]``
(``--quick`` for a smoke run).
"""

from __future__ import annotations

import argparse
import importlib.util
import json
import multiprocessing
import socket
import statistics
import struct
import sys
import time
from typing import Any, Callable, Dict, List, Optional

from bench_comms import SeqCheck, body, free_port, loads, small_data

from snr import Page, Task, TaskType
from snr.std_mods.codec import FrameDecoder, PageEncoder, decode_body, encode_page

zmq: Any
try:
    import zmq
except ImportError:  # a development dependency: that row is skipped
    zmq = None

KEY = "bench"
BATCH = 1000  # frames joined per sendall in the floor rows
READ_BYTES = 256 * 1024  # what a node's read takes at most


def drain_tcp(port: int) -> None:
    """Child process: accept one connection and read until it ends."""
    with socket.create_server(("127.0.0.1", port)) as server:
        conn, _ = server.accept()
        with conn:
            while conn.recv(1 << 20):
                pass


def drain_zmq(address: str) -> None:
    """Child process: pull messages until an empty one."""
    context = zmq.Context()
    pull = context.socket(zmq.PULL)
    pull.bind(address)
    while pull.recv():
        pass
    pull.close(linger=0)
    context.term()


def pyzmq_push(count: int, wall: List[float]) -> float:
    """CPU µs per message of a pyzmq PUSH sender (the drain runs in a child).

    Appends to ``wall`` the µs per message from the first send until the
    child has pulled the last: the rate of the whole PUSH/PULL pipeline.
    """
    port = free_port()
    address = f"tcp://127.0.0.1:{port}"
    child = multiprocessing.Process(target=drain_zmq, args=(address,), daemon=True)
    child.start()
    context = zmq.Context()
    push = context.socket(zmq.PUSH)
    push.connect(address)
    push.send(b"warm-up")
    started, started_wall = time.thread_time(), time.perf_counter()
    for i in range(count):
        push.send(body(i))
    used = time.thread_time() - started
    push.send(b"")
    child.join(10)
    wall.append((time.perf_counter() - started_wall) / count * 1e6)
    push.close(linger=0)
    context.term()
    return used / count * 1e6


def push_bodies(address: str, count: int) -> None:
    """Child process: push ``count`` page bodies, then an empty message."""
    context = zmq.Context()
    push = context.socket(zmq.PUSH)
    push.connect(address)
    for i in range(count):
        push.send(body(i))
    push.send(b"")
    push.close(linger=-1)
    context.term()


def pyzmq_pull(count: int) -> float:
    """CPU µs per message of a pyzmq PULL receiver (the pusher runs in a child)."""
    context = zmq.Context()
    pull = context.socket(zmq.PULL)
    port = pull.bind_to_random_port("tcp://127.0.0.1")
    child = multiprocessing.Process(
        target=push_bodies, args=(f"tcp://127.0.0.1:{port}", count), daemon=True
    )
    child.start()
    check = SeqCheck(count)
    first = pull.recv()  # not counted: the wait for the child to start
    started = time.thread_time()
    message = first
    while message:
        check.note(loads(message)["data"]["seq"])
        message = pull.recv()
    used = time.thread_time() - started
    child.join(10)
    pull.close(linger=0)
    context.term()
    return used / count * 1e6


def snr_receive_floor(count: int) -> float:
    """CPU µs per page of the receiving floor (see the module docstring)."""
    stream = b"".join(
        encode_page(Page(KEY, small_data(i), "sender", time.time())) for i in range(count)
    )
    reads = [stream[start : start + READ_BYTES] for start in range(0, len(stream), READ_BYTES)]
    check = SeqCheck(count)
    datastore: Dict[str, Page] = {}
    process_data = TaskType.process_data

    def handle(task: Task, key: Any) -> None:  # the benchmark's handler
        check.note(task.val_list[0].data["seq"])

    handlers: Dict[Any, Callable[[Task, Any], None]] = {(process_data, KEY): handle}
    decoder = FrameDecoder()
    started = time.thread_time()
    for read in reads:
        bodies: List[bytes] = []
        decoder.cut_frames(read, bodies)
        for frame_body in bodies:
            page = decode_body(frame_body)
            assert isinstance(page, Page)
            datastore[page.key] = page
            task = Task(process_data, page.key, [page])
            handlers[(task.type, task.name)](task, KEY)
    used = time.thread_time() - started
    if check.counts() != (0, 0, 0):
        raise RuntimeError(f"the floor lost pages: {check.counts()}")
    return used / count * 1e6


def snr_floor(count: int, handler_call: bool) -> float:
    """CPU µs per page of the floor (see the module docstring)."""
    port = free_port()
    child = multiprocessing.Process(target=drain_tcp, args=(port,), daemon=True)
    child.start()
    sock = _connect(port)
    datastore: Dict[str, Page] = {}
    frames: List[bytes] = []
    store_page = TaskType.store_page

    def forward(task: Task, key: Any) -> None:  # what a comms handler must do at least
        frames.append(encode_page(task.val_list[0]))

    handlers: Dict[Any, Callable[[Task, Any], None]] = {(store_page, KEY): forward}
    started = time.thread_time()
    for i in range(count):
        page = Page(KEY, small_data(i), "sender", time.time(), True)
        task = Task(store_page, KEY, [page])
        datastore[page.key] = page
        if handler_call:
            handlers[(task.type, task.name)](task, KEY)
        else:
            frames.append(encode_page(page))
        if len(frames) >= BATCH:
            sock.sendall(b"".join(frames))
            frames.clear()
    sock.sendall(b"".join(frames))
    used = time.thread_time() - started
    sock.close()
    child.join(10)
    return used / count * 1e6


def _connect(port: int) -> socket.socket:
    for _ in range(200):  # the child may not listen yet
        try:
            return socket.create_connection(("127.0.0.1", port))
        except ConnectionRefusedError:
            time.sleep(0.01)
    raise RuntimeError(f"the draining process never listened on port {port}")


def main(argv: List[str]) -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--quick", action="store_true", help="a smoke run")
    parser.add_argument("--messages", type=int, help="messages a row (200000; --quick 5000)")
    parser.add_argument("--rounds", type=int, help="interleaved rounds (5; --quick 1)")
    args = parser.parse_args(argv)
    count = args.messages or (5000 if args.quick else 200_000)
    rounds = args.rounds or (1 if args.quick else 5)
    rows: Dict[str, Callable[[], float]] = {}
    pipeline: List[float] = []  # µs a message, PUSH to PULL
    if zmq is not None:
        rows["pyzmq PUSH, one message"] = lambda: pyzmq_push(count, pipeline)
    rows["SNR floor, one page"] = lambda: snr_floor(count, handler_call=False)
    rows["+ one handler call"] = lambda: snr_floor(count, handler_call=True)
    received: Dict[str, Callable[[], float]] = {}
    if zmq is not None:
        received["pyzmq PULL, one message"] = lambda: pyzmq_pull(count)
    received["SNR floor, one page"] = lambda: snr_receive_floor(count)
    over_zenoh: Dict[str, Callable[[], float]] = {}
    zenoh_pair: Optional[ZenohPair] = None
    if importlib.util.find_spec("zenoh") is not None:
        zenoh_pair = ZenohPair()
        pair = zenoh_pair
        over_zenoh["raw Zenoh put, one message"] = lambda: pair.raw(count)
        over_zenoh["SNR floor over Zenoh"] = lambda: pair.snr_floor(count)
    tables = (rows, over_zenoh, received)
    results: List[Dict[str, List[float]]] = [{name: [] for name in table} for table in tables]
    for _ in range(rounds):
        for table, found in zip(tables, results):
            for name, run in table.items():
                found[name].append(run())
    if zenoh_pair is not None:
        zenoh_pair.close()
    print(f"CPU of one thread per message: {count:,} messages, {rounds} interleaved rounds.")
    sent, sent_over_zenoh, got = results
    print(f"{'sending':28} {'us':>6} {'spread':>12} {'x pyzmq':>8}")
    _table(sent, sent.get("pyzmq PUSH, one message"))
    if sent_over_zenoh:
        print(f"{'sending over Zenoh':28} {'us':>6} {'spread':>12} {'x raw':>8}")
        _table(sent_over_zenoh, sent_over_zenoh.get("raw Zenoh put, one message"))
    print(f"{'receiving':28} {'us':>6} {'spread':>12} {'x pyzmq':>8}")
    _table(got, got.get("pyzmq PULL, one message"))
    if sent.get("pyzmq PUSH, one message"):
        per_message = statistics.median(pipeline)
        print(
            f"(pyzmq PUSH/PULL here: a message every {per_message:.2f} us end to end, "
            f"{1e6 / per_message:,.0f}/s; libzmq's I/O threads and the puller set that pace.)"
        )


class ZenohPair:
    """Two Zenoh sessions of this process on 127.0.0.1, one publishing to the other."""

    def __init__(self) -> None:
        import zenoh as zenoh_module

        self.zenoh = zenoh_module
        endpoint = json.dumps([f"tcp/127.0.0.1:{free_port()}"])
        self.sessions = []
        for side in ("listen", "connect"):
            config = zenoh_module.Config()
            config.insert_json5("scouting/multicast/enabled", "false")
            config.insert_json5(f"{side}/endpoints", endpoint)
            self.sessions.append(zenoh_module.open(config))
        key = f"snr/floor/{KEY}"
        self.subscriber = self.sessions[1].declare_subscriber(
            key, zenoh_module.handlers.RingChannel(1000)
        )
        self.publisher = self.sessions[0].declare_publisher(
            key,
            encoding=zenoh_module.Encoding.APPLICATION_JSON,
            congestion_control=zenoh_module.CongestionControl.DROP,
        )
        time.sleep(0.5)  # the two sessions meet

    def raw(self, count: int) -> float:
        """CPU µs per message of ``put(orjson.dumps(body))``."""
        put = self.publisher.put
        started = time.thread_time()
        for i in range(count):
            put(body(i))
        return (time.thread_time() - started) / count * 1e6

    def snr_floor(self, count: int) -> float:
        """CPU µs per page of the floor over Zenoh (see the module docstring)."""
        put = self.publisher.put
        encode = PageEncoder({"v": 1, "kind": "page"}, to="over Zenoh")
        count_of = struct.Struct(">4s8sQ")  # what ZenohComms attaches: mark, sender id, count
        mark, sender = b"snr#", b"floor-01"
        datastore: Dict[str, Page] = {}
        store_page = TaskType.store_page
        started = time.thread_time()
        for i in range(count):
            page = Page(KEY, small_data(i), "sender", time.time(), True)
            task = Task(store_page, KEY, [page])
            datastore[page.key] = task.val_list[0]
            put(encode(page), attachment=count_of.pack(mark, sender, i))
        return (time.thread_time() - started) / count * 1e6

    def close(self) -> None:
        for session in self.sessions:
            session.close()


def _table(results: Dict[str, List[float]], base: Optional[List[float]]) -> None:
    for name, values in results.items():
        ratio = f"{statistics.median([v / b for v, b in zip(values, base)]):8.2f}" if base else ""
        spread = f"{min(values):.2f}-{max(values):.2f}"
        print(f"{name:28} {statistics.median(values):6.2f} {spread:>12} {ratio}")


if __name__ == "__main__":
    main(sys.argv[1:])
