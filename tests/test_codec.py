"""The page codec: strict JSON for frames, recordings and serial lines, with either backend.

Every test of bad input runs once per JSON backend (the standard library's
``json`` and, when installed, ``orjson``): both must reject exactly the same
inputs, read the same values and write the same bytes.
"""

from __future__ import annotations

import enum
import json
import math
import os
import subprocess
import sys
import tempfile
import unittest
from typing import Any, Callable, Dict, Iterator, List, Optional, Tuple
from unittest import mock

from snr import Page
from snr.prelude import NotSerializableError, WireFormatError
from snr.std_mods import codec
from snr.std_mods.codec import HEADER_BYTES, decode_body, encode_hello, encode_page
from snr.std_mods.io import PageReader
from tests.optional import example, given, reason, settings, st

BACKENDS = codec.available_backends()
GOOD_PAGE = b'{"v":1,"kind":"page","key":"k","data":%s,"origin":"o","created_at_s":1.5}'
LINE = b'{"key":"k","data":%s,"origin":"o","created_at_s":1.5}'


def nested(depth: int) -> bytes:
    """``depth`` arrays inside each other: ``nested(2) == b"[[]]"``."""
    return b"[" * depth + b"]" * depth


# Values that may not appear anywhere in a body or a line, as raw JSON text.
BAD_VALUES: List[Tuple[str, bytes]] = [
    ("1e999", b"1e999"),
    ("-1e999", b"-1e999"),
    ("1E400 in a list", b"[1, 1E400]"),
    ("a long mantissa", b"1" + b"0" * 400 + b".0"),
    ("NaN", b"NaN"),
    ("Infinity", b"Infinity"),
    ("-Infinity", b"[-Infinity]"),
    ("a lone high surrogate", b'"\\ud800"'),
    ("a lone low surrogate", b'"x\\udc00y"'),
    ("a surrogate pair backwards", b'"\\ude00\\ud83d"'),
    ("a lone surrogate key", b'{"\\udbff":1}'),
    ("a surrogate as UTF-8 bytes", b'"\xed\xa0\x80"'),
    ("nesting past the limit", nested(codec.MAX_DEPTH)),  # the page object makes it 101
    ("far too deep", nested(100000)),
]

# Values that are fine, and what they read as.
GOOD_VALUES: List[Tuple[bytes, Any]] = [
    (b"1e308", 1e308),
    (b"1e-999", 0.0),
    (b"-0.0", -0.0),
    (b"18446744073709551616", 2**64),  # beyond 64 bits: stays an exact integer
    (b"-9223372036854775809", -(2**63) - 1),
    (b"1" + b"0" * 400, 10**400),
    (b'"\\ud83d\\ude00"', "\U0001f600"),  # a surrogate pair is one character
    (b'"\\u00e9\xe2\x98\x83"', "\u00e9\u2603"),
    (nested(codec.MAX_DEPTH - 1), json.loads(nested(codec.MAX_DEPTH - 1))),
    (b'[1, 2.5, true, null, "x", {"a": [[]]}]', [1, 2.5, True, None, "x", {"a": [[]]}]),
]


class BackendCase(unittest.TestCase):
    """Runs each test with every backend, and restores the default after."""

    def setUp(self) -> None:
        self.addCleanup(codec.use_backend)

    def backends(self) -> Iterator[str]:
        for name in BACKENDS:
            codec.use_backend(name)
            yield name

    def subTest(self, msg: Any = None, **params: Any) -> Any:
        """Every sub-test names the backend it ran with."""
        return super().subTest(msg, backend=codec.backend(), **params)


class TestStrictReading(BackendCase):
    def test_frames_reject_every_bad_value(self) -> None:
        for _ in self.backends():
            for what, value in BAD_VALUES:
                with self.subTest(what), self.assertRaises(WireFormatError):
                    decode_body(GOOD_PAGE % value)

    def test_a_bad_value_in_an_unknown_field_is_rejected_too(self) -> None:
        for _ in self.backends():
            for what, value in BAD_VALUES:
                with self.subTest(what), self.assertRaises(WireFormatError):
                    decode_body(b'{"v":1,"kind":"hello","role":"r","extra":%s}' % value)

    def test_lines_reject_every_bad_value(self) -> None:
        for _ in self.backends():
            for what, value in BAD_VALUES:
                with self.subTest(what):
                    with self.assertRaises(WireFormatError):
                        codec.page_from_line(LINE % value)
                    with self.assertRaises(WireFormatError):  # serial lines arrive as bytes
                        codec.page_from_line(LINE % value + b"\r")

    def test_text_lines_with_a_raw_lone_surrogate_are_rejected(self) -> None:
        for _ in self.backends():
            with self.assertRaises(WireFormatError):
                codec.page_from_line('{"key":"k","data":"\ud800"}')

    def test_the_time_may_not_be_infinite(self) -> None:
        for _ in self.backends():
            with self.assertRaises(WireFormatError):
                decode_body(
                    b'{"v":1,"kind":"page","key":"k","data":1,"origin":"o","created_at_s":1e999}'
                )

    def test_good_values_read_the_same_with_every_backend(self) -> None:
        for _ in self.backends():
            for raw, expected in GOOD_VALUES:
                with self.subTest(raw=raw[:30]):
                    page = decode_body(GOOD_PAGE % raw)
                    assert isinstance(page, Page)
                    self.assertEqual(page.data, expected)
                    self.assertIs(type(page.data), type(expected))
                    line_page = codec.page_from_line(LINE % raw)
                    assert line_page is not None
                    self.assertEqual(line_page.data, expected)

    def test_whitespace_around_a_frame_is_fine_and_trailing_text_is_named(self) -> None:
        body = GOOD_PAGE % b"[1, 2]"
        for _ in self.backends():
            for framed in (b" " + body, body + b" \n", b"\t" + body + b"\r\n"):
                with self.subTest(framed=framed[:3] + framed[-3:]):
                    page = decode_body(framed)
                    assert isinstance(page, Page)
                    self.assertEqual(page.data, [1, 2])
            for bad, words in (
                (body + b"x", "Extra data"),
                (body + body, "Extra data"),
                (body[:-1], "Expecting"),
                (b"", "Expecting value"),
                (b"   ", "Expecting value"),
            ):
                with self.subTest(bad=bad[-8:]), self.assertRaises(WireFormatError) as ctx:
                    decode_body(bad)
                self.assertIn("not JSON", str(ctx.exception))
                self.assertIn(words, str(ctx.exception))  # the stdlib's words, either backend

    def test_the_version_must_be_the_integer_1(self) -> None:
        for _ in self.backends():
            for version in (b"1.0", b'"1"', b"true", b"null", b"[1]", b"3"):
                with self.subTest(version=version), self.assertRaises(WireFormatError) as ctx:
                    decode_body(b'{"v":%s,"kind":"hello","role":"r"}' % version)
                with self.subTest(page_version=version), self.assertRaises(WireFormatError):
                    decode_body(b'{"v":2,"kind":"page","key":"k","data":1,"origin":"o"}')
                self.assertIn("version", str(ctx.exception))
            for version in (b"1.0", b'"1"', b"true", b"0"):
                with self.subTest(header=version), self.assertRaises(WireFormatError):
                    codec.page_from_line(b'{"format":"snr-pages","version":%s}' % version)

    def test_non_utf8_and_byte_order_marks_are_rejected(self) -> None:
        for _ in self.backends():
            for raw in (b"\xff" + GOOD_PAGE % b"1", b"\xef\xbb\xbf" + GOOD_PAGE % b"1"):
                with self.subTest(raw=raw[:6]), self.assertRaises(WireFormatError):
                    decode_body(raw)

    def test_recordings_skip_bad_lines_and_log_only_the_first_few(self) -> None:
        lines = [b'{"format":"snr-pages","version":1}']
        lines += [LINE % value for _, value in BAD_VALUES] * 3
        lines += [LINE % b"42"]
        with tempfile.TemporaryDirectory() as folder:
            path = os.path.join(folder, "bad.jsonl")
            with open(path, "wb") as file:
                file.write(b"\n".join(lines) + b"\n")
            for _ in self.backends():
                reader = PageReader(path)
                with self.assertLogs("snr.replay", "WARNING") as logs:
                    pages = list(reader)
                self.assertEqual([p.data for p in pages], [42])
                self.assertEqual(len(reader.problems), 3 * len(BAD_VALUES))
                self.assertIn("bad.jsonl:2:", reader.problems[0])
                # five in full, then one line with the count (at the end of the file)
                self.assertEqual(len(logs.output), 6, logs.output)
                self.assertIn(f"{3 * len(BAD_VALUES) - 5} more times", logs.output[-1])


class TestStrictWriting(BackendCase):
    def test_nan_and_infinity_are_refused_with_the_clear_message(self) -> None:
        for _ in self.backends():
            for value in (math.nan, math.inf, -math.inf, [1.0, math.nan], {"x": math.inf}):
                for write in (encode_page, codec.page_to_line):
                    with self.subTest(value=value, write=write.__name__):
                        with self.assertRaises(NotSerializableError) as ctx:
                            write(Page("depth", value, "urov", 1.0))
                        message = str(ctx.exception)
                        self.assertIn("'depth'", message)
                        self.assertIn("NaN", message)
                        self.assertIn("is a float", message)

    def test_lone_surrogates_are_refused(self) -> None:
        for _ in self.backends():
            for value in ("\ud800", ["ok", "a\udfffb"], {"\ud800": 1}):
                with self.subTest(value=value), self.assertRaises(NotSerializableError) as ctx:
                    encode_page(Page("name", value, "urov", 1.0))
                self.assertIn("surrogate", str(ctx.exception))

    def test_data_may_nest_one_less_than_the_limit(self) -> None:
        fine = json.loads(nested(codec.MAX_DEPTH - 1))
        too_deep = [fine]
        for _ in self.backends():
            page = Page("tree", fine, "urov", 1.0)
            self.assertEqual(decode_body(encode_page(page)[HEADER_BYTES:]), page)
            with self.assertRaises(NotSerializableError) as ctx:
                codec.page_to_line(Page("tree", too_deep, "urov", 1.0))
            self.assertIn(f"more than {codec.MAX_DEPTH - 1} deep", str(ctx.exception))

    def test_data_that_contains_itself_is_refused_not_looped_over(self) -> None:
        loop: List[Any] = [1.0]
        loop.append(loop)
        for _ in self.backends():
            for value in (loop, {"history": loop}):
                with self.subTest(value=repr(value)[:20]):
                    with self.assertRaises(NotSerializableError) as ctx:
                        encode_page(Page("k", value, "urov", 1.0))
                    self.assertIn("contains itself", str(ctx.exception))

    def test_other_things_json_cannot_hold(self) -> None:
        class Colour(enum.Enum):
            RED = 1

        for _ in self.backends():
            for value in ({1, 2}, Colour.RED, object(), {(1, 2): "a"}, b"raw"):
                with self.subTest(value=value), self.assertRaises(NotSerializableError):
                    encode_page(Page("k", value, "urov", 1.0))

    def test_the_hello_and_header_are_the_same_bytes(self) -> None:
        for _ in self.backends():
            self.assertEqual(encode_hello("r")[HEADER_BYTES:], b'{"v":1,"kind":"hello","role":"r"}')
            self.assertEqual(codec.header_line(), '{"format":"snr-pages","version":1}')


class Level(enum.IntEnum):
    LOW = 1


class Key(str, enum.Enum):
    A = "a"


# Data both backends must write identically: awkward floats, non-ASCII and
# control characters, big integers, tuples, subclasses, None.
awkward_floats = st.floats(allow_nan=False, allow_infinity=False) | st.sampled_from(
    [1e-5, 1.5e-7, 0.0001, 1e16, 1e22, -0.0, 5e-324, 1e-320, 123456789.123]
)
scalars = (
    st.none()
    | st.booleans()
    | st.integers(min_value=-(2**70), max_value=2**70)
    | awkward_floats
    | st.text()
    | st.sampled_from([Level.LOW, Key.A, "\x7f", "null", "e-1", "0.0000"])
)
json_data = st.recursive(
    scalars,
    lambda inner: (
        st.lists(inner, max_size=5)
        | st.lists(inner, max_size=3).map(tuple)
        | st.dictionaries(st.text(max_size=5) | st.integers(), inner, max_size=4)
    ),
    max_leaves=20,
)


# The usual robot page: a scalar, or a small flat list or dict, under ASCII
# names. Mostly ASCII: one odd value sends the whole page to json.
flat_scalars = (
    st.none()
    | st.booleans()
    | st.integers(min_value=-(2**70), max_value=2**70)
    | awkward_floats
    | st.floats()
    | st.text(st.characters(max_codepoint=127), max_size=5)
    | st.sampled_from([Key.A, "\x7f", "a\x7f", "\u00e9", math.nan, math.inf, -math.inf])
)
flat_data = (
    flat_scalars
    | st.lists(flat_scalars, max_size=20)
    | st.dictionaries(st.text(st.characters(max_codepoint=127), max_size=3), flat_scalars)
    | st.dictionaries(st.integers() | st.sampled_from(["\x7f", "\u00e9"]), flat_scalars)
    | st.dictionaries(st.sampled_from(["axes", "buttons"]), st.lists(flat_scalars, max_size=8))
    | st.lists(st.lists(st.lists(flat_scalars, max_size=2), max_size=2), max_size=2)
)


# Where orjson and json part ways, one case each: the backend must answer
# as json does there, or leave the case to json. Raw JSON text to read:
EDGE_TEXTS: List[bytes] = [
    b"1000000000000000000",  # 19 digits, within 64 bits
    b"9223372036854775807",
    b"9223372036854775808",
    b"18446744073709551615",  # the largest 64-bit integer
    b"18446744073709551616",  # 20 digits, one beyond: orjson reads a float
    b"99999999999999999999",
    b"100000000000000000000",  # 21 digits
    b"-9223372036854775808",
    b"-9223372036854775809",
    b"-18446744073709551616",
    b'{"a":18446744073709551616,"a":1}',  # a duplicate key hides the big integer
    b'{"a":1,"a":2}',
    b"1e19",
    b"1.8446744073709552e19",
    b"1.8446744073709552e+19",
    b"9.223372036854776e18",
    b"-0.0",
    b"-0",
    b"1e-5",
    b"0.00001",
    b"0.1000000000000000055511151231257827021181583404541015625",  # a long mantissa
    b"123456789.1234567890123456789",
    b'"12345678901234567890"',  # 20 digits in text are text
    b"NaN",
    b"[Infinity]",
    b"-Infinity",
    b"1e999",
    nested(codec.MAX_DEPTH),  # as deep as may be
    nested(codec.MAX_DEPTH + 1),  # one beyond
    b'{"k\x7f":"v\x7f"}',  # DEL, raw
    b'{"\\u007f":"\\u00e9"}',
    b'{"\xc3\xa9":"\xe2\x98\x83"}',  # non-ASCII, raw UTF-8
    b'"\\ud800"',
    b'{"\\udc00":1}',
    b'"\xed\xa0\x80"',
    b'{"true":1,"1":true}',
]

# Page data to write: big integers, awkward floats, odd keys and text, a dict
# subclass, bools as keys, nesting at the limit and one beyond.
_DEEPEST = json.loads(nested(codec.MAX_DEPTH - 1))  # as deep as a page's data may be


class _Dict(Dict[Any, Any]):
    """A dict subclass: both backends write it as a dict."""


EDGE_DATA: List[Any] = [
    *(n for i in (18, 19, 20) for n in (10**i, 10**i - 1, -(10**i), -(10**i) + 1)),
    *(n for i in (63, 64) for n in (2**i - 1, 2**i, -(2**i), -(2**i) - 1)),
    1e19,
    1.8446744073709552e19,
    -0.0,
    1e-5,
    -1e-5,
    1e-4,
    -1e-4,
    9.99e-5,
    5e-324,
    1.7976931348623157e308,
    math.nan,
    math.inf,
    -math.inf,
    {"seq": 2**64, "value": 0.5},
    {"seq": 2**63 - 1, "value": -0.0, "tiny": -1e-4},
    {"k\x7f": 1},
    {"k": "v\x7f"},
    {"\u00e9": 1},
    {"k": "\u00e9"},
    {"\ud800": 1},
    {"k": "\udfff"},
    ["\ud800"],
    {True: 1, False: 2},
    {1: "a", "1": "b"},  # json writes two "1" keys
    _Dict(seq=1, value=0.5),
    _Dict(seq=1, value=math.nan),
    _Dict({True: 1}),
    {"axes": [0.5, 1e-5]},
    [1, [2**64]],
    _DEEPEST,
    [_DEEPEST],
]


def written(backend: str, write: Callable[[Page], Any], page: Page) -> Any:
    codec.use_backend(backend)
    try:
        return write(page)
    except NotSerializableError as error:
        return ("refused", str(error))


def read(backend: str, raw: bytes) -> Any:
    codec.use_backend(backend)
    try:
        value = codec.load_json(raw)
    except WireFormatError:
        return "rejected"
    return ("read", json.dumps(value), repr(value))  # types too: 1 is not 1.0


@unittest.skipUnless("orjson" in BACKENDS, reason("orjson"))
class TestBackendsAgree(BackendCase):
    @settings(max_examples=150, deadline=None, database=None)
    @given(data=json_data, created=awkward_floats)
    def test_the_same_bytes(self, data: Any, created: float) -> None:
        page = Page("k\u00e9y", data, "origin", created)
        for write in (encode_page, codec.page_to_line):
            self.assertEqual(written("json", write, page), written("orjson", write, page))

    @settings(max_examples=150, deadline=None, database=None)
    @given(data=flat_data, created=awkward_floats, origin=st.text(max_size=5))
    @example(data={"a": "b\x7f"}, created=1.0, origin="o")
    @example(data=[0.5, math.nan], created=1.0, origin="o")
    @example(data={"x": 1e-5}, created=1.0, origin="o")
    @example(data=[1, 2**64], created=1.0, origin="o")
    @example(data={1: 2}, created=1.0, origin="o")
    @example(data=3.5, created=1e-7, origin="\x7f")
    @example(data={"axes": [0.5, math.inf]}, created=1.0, origin="o")
    def test_the_same_bytes_for_flat_data(self, data: Any, created: float, origin: str) -> None:
        page = Page("key", data, origin or "o", created)
        for write in (encode_page, codec.page_to_line):
            self.assertEqual(written("json", write, page), written("orjson", write, page))

    @settings(max_examples=150, deadline=None, database=None)
    @given(
        st.one_of(
            st.binary(max_size=40),
            json_data.map(lambda d: json.dumps(d).encode("utf-8")),
            st.lists(
                st.sampled_from(
                    [
                        b"[",
                        b"]",
                        b"{",
                        b"}",
                        b'"a"',
                        b":",
                        b",",
                        b"1",
                        b"-",
                        b"e",
                        b"E",
                        b"9" * 20,
                        b".5",
                        b"0",
                        b"NaN",
                        b"\\ud800",
                        b'"',
                        b"\\",
                        b"u",
                        b"d",
                        b"\xed\xa0\x80",
                        b"\xef\xbb\xbf",
                        b" ",
                        b"\n",
                        b"true",
                        b"null",
                        b"+",
                        b"1e400",
                        b"\x00",
                    ]
                ),
                max_size=12,
            ).map(b"".join),
        )
    )
    def test_the_same_verdict_on_any_input(self, raw: bytes) -> None:
        self.assertEqual(read("json", raw), read("orjson", raw))

    def test_the_same_verdicts_at_the_edges(self) -> None:
        for raw in EDGE_TEXTS:
            for text in (raw, GOOD_PAGE % raw, LINE % raw):
                with self.subTest(text=text[:80]):
                    self.assertEqual(read("json", text), read("orjson", text))

    def test_the_same_bytes_at_the_edges(self) -> None:
        for data in EDGE_DATA:
            for created in (1.5, 1e-5, -0.0, 1.8446744073709552e19):
                page = Page("key", data, "origin", created)
                with self.subTest(data=repr(data)[:40], created=created):
                    for write in (encode_page, codec.page_to_line, codec.PageEncoder({"v": 1})):
                        expected = written("json", write, page)
                        self.assertEqual(written("orjson", write, page), expected)


class TestPageEncoder(BackendCase):
    """A link's encoder writes exactly what page_json writes, and refuses what it refuses."""

    HEAD = {"v": 1, "kind": "page"}
    PAGES = [
        Page("bench", {"seq": 1, "value": 0.5}, "sender", 1700000000.25),
        Page("bench", {"seq": 2, "value": 0.5}, "sender", 1700000000.5, process=False),
        Page("bench", [1, 2.5], "other", 3),  # an int time, a second origin under the key
        Page("bench", 1e-5, "sender", 1.0),  # a tiny float: json's spelling
        Page("bench", 2**70, "sender", 1.0),  # beyond 64 bits: orjson refuses, json writes
        Page("bench", {1: "a"}, "sender", 1.0),  # a non-str dict key
        Page("k\u00e9y", "x", "sender", 1.0),  # a key orjson would write unescaped
        Page("bench", "x", "\x7f", 1.0),
        Page("bench", 0.5, "sender", 5e-324),
        Page("bench", list(range(40)), "sender", 1.0),  # past the small-page checks
        # flat dicts, checked in one call: each value kind, and what must fall back
        Page("bench", {"a": None, "b": True, "c": "x", "d": 7}, "sender", 2.0),
        Page("bench", {"tiny": 1e-5, "n": 1}, "sender", 2.0),
        Page("bench", {"k\u00e9y": 1}, "sender", 2.0),
        Page("bench", {"text": "caf\u00e9"}, "sender", 2.0),
        Page("bench", {"axes": {"x": [0.5, 1.0]}}, "sender", 2.0),
        Page("bench", {"big": 2**70}, "sender", 2.0),
        Page("bench", 0.5, "sender", -2e-5),  # a tiny negative time
        Page("bench", True, "sender", 0.0),
        Page("bench", "\U0001f600", "sender", 1.0),  # a surrogate pair once escaped
        Page("bench", {2.5: 1, True: 2, None: 3}, "sender", 1.0),  # keys json turns to text
        Page("bench", json.loads(nested(codec.MAX_DEPTH - 1)), "sender", 1.0),  # as deep as may be
        Page("bench", "x", "sender", 1700000000),  # an int time
        Page("bench", {"a": [1e16, -0.0, 1e-4], "b": ["\U0001f600"]}, "sender", 1e22),
        Page("bench", [[0.5] * 17, list(range(17))], "sender", 1.0),  # past _SMALL
        Page("bench", [None, "null", "e-5"], "sender", 1.0),  # what the search looks for
        Page("bench", ["\u00e9"] * 3, "sender", 1.0),
    ]

    def test_the_same_bytes_as_page_json(self) -> None:
        for _ in self.backends():
            encode = codec.PageEncoder(self.HEAD)
            for page in self.PAGES:
                with self.subTest(page=page):
                    self.assertEqual(encode(page), codec.page_json(page, self.HEAD))

    def test_lines_are_page_json_without_a_head(self) -> None:
        for _ in self.backends():
            for page in self.PAGES:
                with self.subTest(page=page):
                    expected = codec.page_json(page, to="to a recording or serial link")
                    self.assertEqual(codec.page_to_line(page), expected.decode("ascii"))

    def test_the_same_refusal(self) -> None:
        for _ in self.backends():
            encode = codec.PageEncoder(self.HEAD)
            itself: List[Any] = [1]
            itself.append(itself)
            too_deep = [json.loads(nested(codec.MAX_DEPTH - 1))]
            for data in ({1, 2}, math.nan, [math.inf], "\ud800", {"a": "\udfff"}, itself, too_deep):
                page = Page("bench", data, "sender", 1.0)
                with self.subTest(data=data):
                    with self.assertRaises(NotSerializableError) as expected:
                        codec.page_json(page, self.HEAD)
                    with self.assertRaises(NotSerializableError) as got:
                        encode(page)
                    self.assertEqual(str(got.exception), str(expected.exception))

    def test_the_same_bytes_for_every_key_and_origin_with_each_backend(self) -> None:
        for _ in self.backends():
            encode = codec.PageEncoder(self.HEAD)
            for key, origin in (("k", "o"), ("k\u00e9", "o"), ("k", "\U0001f600"), ("k", "\ud800")):
                page = Page(key, [1, {"a": 0.25}], origin, 1.5)
                with self.subTest(key=key, origin=origin):
                    try:
                        expected = codec.page_json(page, self.HEAD)
                    except NotSerializableError:
                        self.assertRaises(NotSerializableError, encode, page)
                        continue
                    self.assertEqual(encode(page), expected)

    def test_a_head_naming_a_page_field_keeps_page_json_s_order(self) -> None:
        for _ in self.backends():
            for head in ({"origin": "x", "v": 1}, {"key": 0}, {"process": 1}):
                encode = codec.PageEncoder(head)
                page = Page("bench", 0.5, "sender", 1.0)
                with self.subTest(head=head):
                    self.assertEqual(encode(page), codec.page_json(page, head))

    def test_many_keys_keep_the_same_bytes_past_the_bound(self) -> None:
        for _ in self.backends():
            encode = codec.PageEncoder(self.HEAD)
            for i in range(codec._MAX_ENVELOPES + 10):
                page = Page(f"k{i % (codec._MAX_ENVELOPES + 5)}", i, "sender", 1.0)
                self.assertEqual(encode(page), codec.page_json(page, self.HEAD))
            self.assertLessEqual(len(encode._envelopes), codec._MAX_ENVELOPES)


class TestChoosingTheBackend(BackendCase):
    def test_the_environment_variable_forces_the_stdlib(self) -> None:
        code = "from snr.std_mods import codec; print(codec.backend())"
        env = {**os.environ, codec.BACKEND_ENV_VAR: "json"}
        out = subprocess.run(
            [sys.executable, "-c", code], env=env, capture_output=True, text=True, check=True
        )
        self.assertEqual(out.stdout.strip(), "json")

    def test_unknown_names_are_refused(self) -> None:
        with self.assertRaises(ValueError):
            codec.use_backend("pickle")

    def test_the_default_prefers_orjson(self) -> None:
        default: Optional[str] = None
        if os.environ.get(codec.BACKEND_ENV_VAR):
            self.skipTest("the environment chooses the backend")
        default = codec.use_backend()
        self.assertEqual(default, "orjson" if "orjson" in BACKENDS else "json")


class StepsAside:
    """A JSON backend that leaves everything to json."""

    def dumps(self, value: Any) -> Optional[bytes]:
        return None

    def loads(self, raw: Any) -> Any:
        raise ValueError("json reads it")


class TestTheExtensionPoint(BackendCase):
    """Whatever a backend does, the codec writes json's bytes and refuses what json refuses."""

    def test_a_backend_that_steps_aside_leaves_json_s_bytes_and_verdicts(self) -> None:
        page = Page("k\u00e9y", {"a": [1, 2.5, None]}, "origin", 1.5)
        expected = codec.page_json(page, {"v": 1, "kind": "page"})
        with mock.patch.object(codec, "_fast", StepsAside()):
            self.assertEqual(encode_page(page)[HEADER_BYTES:], expected)
            self.assertEqual(codec.load_json(b"[1, 2.5]"), [1, 2.5])
            with self.assertRaises(WireFormatError):
                codec.load_json(b"[NaN]")

    @unittest.skipUnless("orjson" in BACKENDS, reason("orjson"))
    def test_the_orjson_backend_steps_aside_where_the_codec_does_not_look_again(self) -> None:
        from snr.extras.orjson import OrjsonBackend

        fast = OrjsonBackend()
        deepest = json.loads(nested(codec.MAX_DEPTH - 1))  # as deep as a page's data may be
        self.assertEqual(fast.dumps(deepest), nested(codec.MAX_DEPTH - 1))
        for data in ([deepest], "\ud800", {"a": ["\udfff"]}, [1e-5], {"x": math.nan}):
            with self.subTest(data=repr(data)[:20]):
                self.assertIsNone(fast.dumps(data))

    @unittest.skipUnless("orjson" in BACKENDS, reason("orjson"))
    def test_the_orjson_backend_writes_a_dict_of_names_and_scalars_as_json_does(self) -> None:
        from snr.extras.orjson import OrjsonBackend

        fast = OrjsonBackend()
        written = [{"seq": 1, "value": 0.5}, {"on": True, "off": None, "name": "a\tb"}, {}]
        written += [{"big": 1e300, "zero": -0.0, "negative": -7}]
        for data in written:
            with self.subTest(data=data):
                self.assertEqual(fast.dumps(data), json.dumps(data, separators=(",", ":")).encode())
        stepped_aside = [{"x": 1e-5}, {"x": math.inf}, {"é": 1}, {"x": "é"}, {"x": "\x7f"}]
        stepped_aside += [{"x": 2**70}, {1: 2}]
        for data in stepped_aside:
            with self.subTest(data=repr(data)):
                self.assertIsNone(fast.dumps(data))

    @unittest.skipUnless("orjson" in BACKENDS, reason("orjson"))
    def test_a_backend_not_installed_names_the_pip_line(self) -> None:
        from snr.extras import orjson as extra

        with mock.patch.object(extra, "_orjson", None), mock.patch.dict(codec._loaded, clear=True):
            with self.assertRaises(ValueError) as caught:
                codec.use_backend("orjson")
        self.assertEqual(
            str(caught.exception),
            "the orjson JSON backend is not installed (SNR_JSON=orjson?): "
            "pip install 'snr-robotics[fast]', or use 'json'",
        )


if __name__ == "__main__":
    unittest.main()
