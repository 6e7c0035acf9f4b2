"""The wire format: frames, the page codec, and every kind of bad frame."""

from __future__ import annotations

import json
import math
import os
import re
import struct
import unittest
from typing import Any, List

from snr import Page
from snr.prelude import NotSerializableError, WireFormatError
from snr.std_mods.codec import (
    HEADER_BYTES,
    MAX_FRAME_BYTES,
    WIRE_VERSION,
    FrameDecoder,
    Hello,
    decode_body,
    encode_bye,
    encode_hello,
    encode_page,
)
from tests.optional import given, settings, st

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))

json_values = st.recursive(
    st.none()
    | st.booleans()
    | st.integers(min_value=-(2**63), max_value=2**63)
    | st.floats(allow_nan=False, allow_infinity=False)
    | st.text(),
    lambda inner: st.lists(inner, max_size=4) | st.dictionaries(st.text(), inner, max_size=4),
    max_leaves=12,
)


def body(**fields: Any) -> bytes:
    return json.dumps(fields).encode("utf-8")


def good_fields() -> dict[str, Any]:
    return {
        "v": 1,
        "kind": "page",
        "key": "k",
        "data": 1,
        "origin": "o",
        "created_at_s": 1.0,
        "process": True,
    }


class TestCodec(unittest.TestCase):
    def test_page_round_trip_keeps_every_field(self) -> None:
        page = Page("speed", {"x": 0.5, "ids": [1, 2]}, "topside", 1700000000.25, False)
        frame = encode_page(page)
        (length,) = struct.unpack(">I", frame[:HEADER_BYTES])
        self.assertEqual(length, len(frame) - HEADER_BYTES)
        self.assertEqual(decode_body(frame[HEADER_BYTES:]), page)

    def test_the_bytes_are_compact_json_in_a_fixed_field_order(self) -> None:
        frame = encode_page(Page("x", [1, 2], "robot", 1.5))
        self.assertEqual(
            frame[HEADER_BYTES:],
            b'{"v":1,"kind":"page","key":"x","data":[1,2],"origin":"robot",'
            b'"created_at_s":1.5,"process":true}',
        )
        self.assertEqual(encode_bye(), b'\x00\x00\x00\x14{"v":1,"kind":"bye"}')

    def test_hello(self) -> None:
        frame = encode_hello("receiver")
        self.assertEqual(frame[HEADER_BYTES:], b'{"v":1,"kind":"hello","role":"receiver"}')
        self.assertEqual(decode_body(frame[HEADER_BYTES:]), Hello("receiver"))

    def test_non_ascii_text_is_utf8(self) -> None:
        page = Page("température", "eau ☃", "bateau", 2.0)
        self.assertEqual(decode_body(encode_page(page)[HEADER_BYTES:]), page)
        raw = body(**{**good_fields(), "data": "☃"}).replace(b"\\u2603", "☃".encode())
        self.assertEqual(decode_body(raw), Page("k", "☃", "o", 1.0))  # raw UTF-8 also works

    def test_optional_process_and_unknown_fields(self) -> None:
        fields = good_fields()
        del fields["process"]
        fields["extra"] = "ignored"
        fields["created_at_s"] = 3  # an integer is a number too
        page = decode_body(json.dumps(fields).encode())
        self.assertEqual(page, Page("k", 1, "o", 3.0, True))
        assert isinstance(page, Page)
        self.assertIsInstance(page.created_at_s, float)

    @settings(max_examples=150, deadline=None, database=None)
    @given(
        key=st.text(min_size=1),
        data=json_values,
        origin=st.text(min_size=1),
        created=st.floats(allow_nan=False, allow_infinity=False),
        process=st.booleans(),
    )
    def test_round_trip_any_json_data(
        self, key: str, data: Any, origin: str, created: float, process: bool
    ) -> None:
        page = Page(key, data, origin, created, process)
        decoder = FrameDecoder()
        decoder.feed(encode_page(page))
        frame = decoder.next_frame()
        assert frame is not None
        self.assertEqual(decode_body(frame), page)


class TestNotSerializable(unittest.TestCase):
    def test_names_key_and_type(self) -> None:
        for data, type_name in [({1, 2}, "set"), (object(), "object"), ({"a": {3}}, "dict")]:
            with self.assertRaises(NotSerializableError) as ctx:
                encode_page(Page("thrusters", data, "urov", 1.0))
            message = str(ctx.exception)
            self.assertIn("'thrusters'", message)
            self.assertIn(type_name, message)

    def test_nan_and_infinity_are_not_json(self) -> None:
        for value in (math.nan, math.inf, [-math.inf]):
            with self.assertRaises(NotSerializableError) as ctx:
                encode_page(Page("depth", value, "urov", 1.0))
            self.assertIn("NaN", str(ctx.exception))

    def test_too_deep(self) -> None:
        deep: Any = []
        for _ in range(100000):
            deep = [deep]
        with self.assertRaises(NotSerializableError):
            encode_page(Page("tree", deep, "urov", 1.0))

    def test_too_big(self) -> None:
        with self.assertRaises(NotSerializableError) as ctx:
            encode_page(Page("image", "x" * (MAX_FRAME_BYTES + 1), "camera", 1.0))
        self.assertIn("frame limit", str(ctx.exception))


class TestBadFrames(unittest.TestCase):
    def assertBad(self, raw: bytes, words: str) -> None:
        with self.assertRaises(WireFormatError) as ctx:
            decode_body(raw)
        self.assertIn(words, str(ctx.exception))

    def test_every_kind_of_bad_body(self) -> None:
        good = good_fields()
        cases = [
            (b"\xff\xfe\x00garbage", "not UTF-8"),
            ('{"v":1}'.encode("utf-16"), "not UTF-8"),
            (b"{not json", "not JSON"),
            (b"", "not JSON"),
            (b'{"v":1,"kind":"page","key":"k","data":NaN}', "not JSON"),
            (b"[1, 2]", "not an object"),
            (b'"page"', "not an object"),
            (body(**{**good, "v": 2}), "version 2"),
            (body(**{**good, "v": True}), "version True"),
            (body(**{k: v for k, v in good.items() if k != "v"}), "version None"),
            (body(**{**good, "kind": "pickle"}), "unknown frame kind"),
            (body(**{k: v for k, v in good.items() if k != "key"}), "no 'key'"),
            (body(**{k: v for k, v in good.items() if k != "data"}), "no 'data'"),
            (body(**{**good, "key": 5}), "'key'"),
            (body(**{**good, "key": ""}), "must not be empty"),
            (body(**{**good, "origin": None}), "'origin'"),
            (body(**{**good, "created_at_s": "yesterday"}), "must be a number"),
            (body(**{**good, "created_at_s": True}), "must be a number"),
            (body(**{**good, "created_at_s": 10**400}), "too large"),
            (b"[" * 100000, "more than 100 deep"),
            (body(**{**good, "process": "yes"}), "'process'"),
            (body(v=1, kind="hello"), "no 'role'"),
            (body(v=1, kind="hello", role=""), "must not be empty"),
            (body(v=1, kind="hello", role="r", beat_s=10**400), "too large for a double"),
        ]
        for raw, words in cases:
            with self.subTest(raw=raw[:40]):
                self.assertBad(raw, words)

    def test_decoder_waits_for_a_whole_frame(self) -> None:
        frames = encode_page(Page("a", 1, "o", 1.0)) + encode_page(Page("b", 2, "o", 2.0))
        decoder = FrameDecoder()
        bodies: List[bytes] = []
        for i in range(len(frames)):  # one byte at a time: the worst a recv can do
            decoder.feed(frames[i : i + 1])
            frame = decoder.next_frame()
            if frame is not None:
                bodies.append(frame)
        pages = [decode_body(body) for body in bodies]
        self.assertEqual([p.key if isinstance(p, Page) else p for p in pages], ["a", "b"])
        self.assertEqual(decoder.pending_bytes(), 0)
        decoder.feed(frames[:10])
        self.assertIsNone(decoder.next_frame())
        self.assertEqual(decoder.pending_bytes(), 10)  # truncated: reported at EOF

    @settings(max_examples=200, deadline=None, database=None)
    @given(
        st.lists(st.integers(min_value=0, max_value=12), min_size=1, max_size=6),
        st.lists(st.integers(min_value=1, max_value=40), max_size=8),
    )
    def test_cut_frames_gives_what_feed_and_next_frame_give(
        self, sizes: List[int], cuts: List[int]
    ) -> None:
        stream = b"".join(struct.pack(">I", n) + bytes([65 + n]) * n for n in sizes)
        cut_at = sorted({min(c, len(stream)) for c in cuts} | {len(stream)})
        fast, slow = FrameDecoder(), FrameDecoder()
        fast_bodies: List[bytes] = []
        slow_bodies: List[bytes] = []
        start = 0
        for end in cut_at:  # the stream in chunks, as recv might return it
            fast.cut_frames(stream[start:end], fast_bodies)
            slow.feed(stream[start:end])
            body = slow.next_frame()
            while body is not None:
                slow_bodies.append(body)
                body = slow.next_frame()
            self.assertEqual(fast.pending_bytes(), slow.pending_bytes())
            start = end
        self.assertEqual(fast_bodies, slow_bodies)
        self.assertEqual(fast_bodies, [bytes([65 + n]) * n for n in sizes])

    def test_cut_frames_keeps_the_frames_before_a_bad_header(self) -> None:
        good = encode_page(Page("a", 1, "o", 1.0))
        for split in (0, 3):  # straight from the read, and behind a buffered part
            with self.subTest(split=split):
                decoder = FrameDecoder(max_frame_bytes=1000)
                bodies: List[bytes] = []
                data = good + struct.pack(">I", 1001) + b"{}"
                decoder.cut_frames(data[:split], bodies)
                with self.assertRaises(WireFormatError) as ctx:
                    decoder.cut_frames(data[split:], bodies)
                self.assertIn("maximum frame size", str(ctx.exception))
                self.assertEqual(bodies, [good[HEADER_BYTES:]])

    def test_oversized_length_header(self) -> None:
        decoder = FrameDecoder()
        decoder.feed(struct.pack(">I", MAX_FRAME_BYTES + 1) + b"{}")
        with self.assertRaises(WireFormatError) as ctx:
            decoder.next_frame()
        self.assertIn("maximum frame size", str(ctx.exception))

    @settings(max_examples=300, deadline=None, database=None)
    @given(st.binary(max_size=200))
    def test_random_bytes_only_ever_raise_wire_format_error(self, raw: bytes) -> None:
        decoder = FrameDecoder(max_frame_bytes=1000)
        decoder.feed(raw)
        try:
            frame = decoder.next_frame()
            while frame is not None:
                try:
                    decode_body(frame)
                except WireFormatError:
                    pass
                frame = decoder.next_frame()
        except WireFormatError:
            pass


class TestSpecDocument(unittest.TestCase):
    def test_the_hex_example_in_the_docs_is_what_snr_sends(self) -> None:
        with open(os.path.join(ROOT, "docs", "wire-format.md"), encoding="utf-8") as f:
            text = f.read()
        block = re.search(r"```hex\n(.*?)```", text, re.S)
        assert block is not None, "docs/wire-format.md has a ```hex block"
        hex_digits = "".join(
            line.split("|")[0].split(":", 1)[1] for line in block.group(1).splitlines()
        )
        documented = bytes.fromhex(hex_digits)
        page = Page("depth_m", 3.2, "urov", 1700000000.5)
        self.assertEqual(documented, encode_page(page))
        self.assertIn(f"version {WIRE_VERSION}", text.splitlines()[0])


if __name__ == "__main__":
    unittest.main()
