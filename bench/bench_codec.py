"""What the strict page codec costs: pages/s per JSON backend, against the previous codec.

For a few shapes of page data, encodes and decodes comms frames (and, for one
shape, recording lines) with:

* ``before``: the previous codec (stdlib ``json``, no checks for infinity,
  lone surrogates or depth), copied here as it was;
* ``json``: ``snr.std_mods.codec`` with the standard library;
* ``orjson``: the same codec with orjson (``pip install 'snr-robotics[fast]'``).

The ``json`` and ``orjson`` rows write the same bytes and reject the same
input (``tests/test_codec.py`` checks it); only the speed differs.

Run: ``python bench/bench_codec.py [--seconds S]`` (or ``nox -s bench``).
"""

from __future__ import annotations

import argparse
import json
import random
import struct
import time
from functools import partial
from typing import Any, Callable, Dict, List, NoReturn, Tuple

from snr import Page
from snr.std_mods import codec
from snr.std_mods.codec import HEADER_BYTES, decode_body, encode_page

random.seed(1)
SHAPES: List[Tuple[str, Any]] = [
    ("a float", 3.2),
    ("imu dict (4 fields)", {"ax": 0.01, "ay": -9.81, "az": 0.2, "ok": True}),
    ("joystick (axes + buttons)", {"axes": [0.1, -0.5, 0.0, 1.0], "buttons": [0] * 12}),
    ("100 floats", [random.uniform(-10, 10) for _ in range(100)]),
    ("50 [x, y] points", [[random.random(), random.random()] for _ in range(50)]),
    ("text with accents", "température de l'eau: 12,5 °C"),
]

# -- the previous codec (before the strict one), for comparison ---------------------


def _reject_constant(name: str) -> NoReturn:
    raise ValueError(f"{name} is not valid JSON")


_OLD_ENCODER = json.JSONEncoder(separators=(",", ":"), allow_nan=False)
_OLD_DECODER = json.JSONDecoder(parse_constant=_reject_constant)
_HEADER = struct.Struct(">I")


def before_encode_page(page: Page) -> bytes:
    fields = {
        "v": 1,
        "kind": "page",
        "key": page.key,
        "data": page.data,
        "origin": page.origin,
        "created_at_s": page.created_at_s,
        "process": page.process,
    }
    body = _OLD_ENCODER.encode(fields).encode("utf-8")
    return _HEADER.pack(len(body)) + body


def before_decode_body(body: bytes) -> Page:
    obj: Dict[str, Any] = _OLD_DECODER.decode(body.decode("utf-8"))
    version = obj.get("v")
    if version != 1 or isinstance(version, bool) or obj.get("kind") != "page":
        raise ValueError("not a version 1 page")
    key, origin = obj.get("key"), obj.get("origin")
    created, process = obj.get("created_at_s"), obj.get("process", True)
    if (
        type(key) is str
        and key
        and type(origin) is str
        and origin
        and type(created) is float
        and type(process) is bool
        and "data" in obj
    ):
        return Page(key, obj["data"], origin, float(created), process)
    raise ValueError("slow path not copied")


def before_page_to_line(page: Page) -> str:
    fields = {
        "key": page.key,
        "data": page.data,
        "origin": page.origin,
        "created_at_s": page.created_at_s,
        "process": page.process,
    }
    return json.dumps(fields, separators=(",", ":"))


def before_page_from_line(line: str) -> Page:
    fields = json.loads(line)
    return Page(
        fields["key"], fields["data"], fields["origin"], fields["created_at_s"], fields["process"]
    )


# -- measuring --------------------------------------------------------------------


def per_second(action: Callable[[], object], seconds: float) -> float:
    """Calls of ``action`` per second: the best of three runs of about ``seconds`` / 3."""
    n, elapsed = 1, 0.0
    while elapsed < 0.05:  # find a batch size that takes measurable time
        n *= 4
        started = time.perf_counter()
        for _ in range(n):
            action()
        elapsed = time.perf_counter() - started
    batch = max(1, int(n * (seconds / 3) / elapsed))
    best = 0.0
    for _ in range(3):
        started = time.perf_counter()
        for _ in range(batch):
            action()
        best = max(best, batch / (time.perf_counter() - started))
    return best


def row(label: str, rates: List[float]) -> str:
    cells = " ".join(f"{rate:11,.0f}" for rate in rates)
    ratios = " ".join(f"{rate / rates[0]:6.1f}x" for rate in rates[1:])
    return f"  {label:28} {cells}   {ratios}"


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--seconds", type=float, default=0.6, help="per measurement")
    args, _ = parser.parse_known_args()
    backends = codec.available_backends()
    names = ["before", *backends]
    head = " ".join(f"{name:>11}" for name in names)
    ratio_head = " ".join(f"{name:>7}" for name in names[1:])
    print(f"Page codec, pages/s (higher is better; ratios against 'before'); {names}")
    try:
        for direction in ("encode frame", "decode frame"):
            print(f"\n{direction:30} {head}   {ratio_head}")
            for label, data in SHAPES:
                page = Page("sensor", data, "urov", 1700000000.25)
                body = before_encode_page(page)[HEADER_BYTES:]
                if direction == "encode frame":
                    rates = [per_second(partial(before_encode_page, page), args.seconds)]
                else:
                    rates = [per_second(partial(before_decode_body, body), args.seconds)]
                for name in backends:
                    codec.use_backend(name)
                    assert encode_page(page)[HEADER_BYTES:] == body  # the same bytes
                    if direction == "encode frame":
                        rates.append(per_second(partial(encode_page, page), args.seconds))
                    else:
                        rates.append(per_second(partial(decode_body, body), args.seconds))
                print(row(label, rates))
        page = Page("sensor", SHAPES[1][1], "urov", 1700000000.25)
        line = before_page_to_line(page)
        print(f"\n{'recording lines (imu dict)':30} {head}   {ratio_head}")
        writes = [per_second(lambda: before_page_to_line(page), args.seconds)]
        reads = [per_second(lambda: before_page_from_line(line), args.seconds)]
        for name in backends:
            codec.use_backend(name)
            writes.append(per_second(lambda: codec.page_to_line(page), args.seconds))
            reads.append(per_second(lambda: codec.page_from_line(line), args.seconds))
        print(row("page_to_line", writes))
        print(row("page_from_line", reads))
    finally:
        codec.use_backend()


if __name__ == "__main__":
    main()
