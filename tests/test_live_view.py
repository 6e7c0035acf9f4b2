"""The live view: schemas, the Foxglove WebSocket protocol as a viewer sees it, slow viewers."""

from __future__ import annotations

import asyncio
import contextlib
import io
import json
import logging
import socket
import struct
import sys
import threading
import time
import unittest
from typing import Any, Dict, List, Tuple
from unittest import mock

from snr import Config, Mode, Node, Page, SNRTestCase, tasks
from snr.extras.viz.live_view import FoxgloveBridgeFactory, foxglove_app_url
from snr.extras.viz.page_schema import data_schema, page_schema
from snr.prelude import ConfigError
from snr.prelude.install import install_hint
from snr.std_mods.codec import page_json
from tests.optional import reason
from tests.quiet import capture_test_logs

try:
    from websockets.asyncio.client import ClientConnection, connect
    from websockets.exceptions import InvalidStatus
    from websockets.typing import Subprotocol

    SDK = Subprotocol("foxglove.sdk.v1")  # what current viewers offer
    OLDER = Subprotocol("foxglove.websocket.v1")  # viewers before it
    HAVE_WEBSOCKETS = True
except ImportError:  # the view extra is optional
    HAVE_WEBSOCKETS = False

NEEDS_WEBSOCKETS = unittest.skipUnless(HAVE_WEBSOCKETS, reason("websockets"))
DEADLINE_S = 5.0
Frame = Tuple[int, int, Dict[str, Any]]  # subscription id, log time (ns), page fields


class TestSchemas(SNRTestCase):
    def test_numbers_strings_lists_and_dicts(self) -> None:
        self.assertEqual(data_schema(2), {"type": "number"})
        self.assertEqual(data_schema(2.5), {"type": "number"})
        self.assertEqual(data_schema(True), {"type": "boolean"})
        self.assertEqual(data_schema("dive"), {"type": "string"})
        self.assertEqual(data_schema(None), {})
        self.assertEqual(data_schema([1, 2.5]), {"type": "array", "items": {"type": "number"}})
        self.assertEqual(data_schema(["a", 1]), {"type": "array", "items": {}})
        self.assertEqual(data_schema([]), {"type": "array", "items": {}})
        self.assertEqual(
            data_schema({"depth_m": 1.5, "motors": [{"pwm": 3}]}),
            {
                "type": "object",
                "properties": {
                    "depth_m": {"type": "number"},
                    "motors": {
                        "type": "array",
                        "items": {"type": "object", "properties": {"pwm": {"type": "number"}}},
                    },
                },
            },
        )

    def test_deep_data_does_not_overflow_the_stack(self) -> None:
        data: Any = 1.0
        for _ in range(5000):
            data = [data]
        schema = data_schema(data)
        for _ in range(5000):
            schema = schema["items"]
        self.assertEqual(schema, {"type": "number"})

    def test_a_page_schema_describes_the_codec_fields(self) -> None:
        schema = page_schema({"x": 1.0})
        written = json.loads(page_json(Page("k", 1, "robot", 0.5)))
        self.assertEqual(set(schema["properties"]), set(written))
        self.assertEqual(schema["properties"]["data"]["properties"]["x"], {"type": "number"})


class TestConfiguration(SNRTestCase):
    def test_without_websockets_one_line_names_the_install_command(self) -> None:
        hidden = {"websockets": None, "websockets.asyncio": None, "websockets.asyncio.server": None}
        with mock.patch.dict(sys.modules, hidden):
            with self.assertRaises(ConfigError) as caught:
                FoxgloveBridgeFactory(["depth_m"])
        message = str(caught.exception)
        self.assertIn(install_hint("view"), message)
        self.assertNotIn("\n", message)

    @NEEDS_WEBSOCKETS
    def test_bad_keys_and_ports_are_refused(self) -> None:
        with self.assertRaisesRegex(ConfigError, "keys must be a list"):
            FoxgloveBridgeFactory([])
        with self.assertRaisesRegex(ConfigError, "port must be a whole number"):
            FoxgloveBridgeFactory("depth_m", port=70000)

    @NEEDS_WEBSOCKETS
    def test_loopback_by_default_and_the_app_url(self) -> None:
        bridge = FoxgloveBridgeFactory("depth_m")
        self.assertEqual(bridge.keys, ["depth_m"])
        self.assertEqual(bridge.url, "ws://127.0.0.1:8765")
        self.assertEqual(
            foxglove_app_url(bridge.url),
            "https://app.foxglove.dev/?ds=foxglove-websocket&ds.url=ws%3A%2F%2F127.0.0.1%3A8765",
        )

    @NEEDS_WEBSOCKETS
    def test_a_port_in_use_stops_the_node_with_the_port_named(self) -> None:
        capture_test_logs(self)  # and the INFO level this DEBUG node gives "snr.robot" goes
        with socket.create_server(("127.0.0.1", 0)) as taken:
            port = taken.getsockname()[1]
            node = Node("robot", Config({"robot": [FoxgloveBridgeFactory("x", port=port)]}))
            with self.assertRaisesRegex(Exception, f"127.0.0.1:{port}: port {port} is in use"):
                node.loop()


class LiveNode:
    """A node with a live view, run on a thread; the test stores pages into it."""

    def __init__(self, test: SNRTestCase, keys: List[str]) -> None:
        # The view's lines (viewers come and go; pages dropped for a slow one,
        # depending on timing) stay out of the run's output.
        capture_test_logs(test)
        self.bridge = FoxgloveBridgeFactory(keys, port=0)
        self.node = Node("robot", Config({"robot": [self.bridge]}, mode=Mode.TEST))
        self.thread = threading.Thread(target=self.node.loop, daemon=True)
        self.thread.start()
        test.addCleanup(self.stop)
        wait_for(lambda: self.bridge.port != 0, "the live view to listen")

    def store(self, key: str, data: Any) -> Page:
        page = Page(key, data, "robot", time.time(), process=False)
        self.node.schedule(tasks.store_page(page))
        return page

    def stop(self) -> None:
        self.node.schedule(tasks.terminate("test over"))
        self.thread.join(DEADLINE_S)
        assert not self.thread.is_alive(), "the node did not stop"
        assert not any(t.name.endswith("live-view") for t in threading.enumerate())


def wait_for(condition: Any, what: str) -> None:
    deadline = time.monotonic() + DEADLINE_S
    while not condition():
        if time.monotonic() > deadline:
            raise AssertionError(f"timed out waiting for {what}")
        time.sleep(0.005)


async def next_json(viewer: ClientConnection) -> Dict[str, Any]:
    message = await asyncio.wait_for(viewer.recv(), DEADLINE_S)
    assert isinstance(message, str), f"expected a JSON text message, got {message[:40]!r}"
    fields: Dict[str, Any] = json.loads(message)
    return fields


async def next_frame(viewer: ClientConnection) -> Frame:
    message = await asyncio.wait_for(viewer.recv(), DEADLINE_S)
    assert isinstance(message, bytes), f"expected a binary frame, got {message[:80]!r}"
    opcode, subscription, log_time_ns = struct.unpack_from("<BIQ", message)
    assert opcode == 0x01, f"opcode {opcode} is not messageData"
    return subscription, log_time_ns, json.loads(message[13:])


async def subscribe_all(viewer: ClientConnection) -> Dict[str, int]:
    """Read serverInfo and advertise; subscribe to every channel (id = channel id + 100)."""
    info = await next_json(viewer)
    assert info["op"] == "serverInfo", info
    advertised = await next_json(viewer)
    assert advertised["op"] == "advertise", advertised
    channels = advertised["channels"]
    subscriptions = [{"id": c["id"] + 100, "channelId": c["id"]} for c in channels]
    await viewer.send(json.dumps({"op": "subscribe", "subscriptions": subscriptions}))
    return {c["topic"]: c["id"] + 100 for c in channels}


@NEEDS_WEBSOCKETS
class TestHandOver(SNRTestCase):
    def test_the_newest_page_of_each_key_is_kept_and_every_replaced_one_counted(self) -> None:
        from snr.extras.viz.live_view_server import LiveViewServer

        with socket.socket() as unused:
            server = LiveViewServer("robot", unused, logging.getLogger("snr.test.live_view"))
            for i in range(5):  # the server's thread is not running: nothing is taken
                server.publish(Page("depth_m", float(i), "robot", 1.0 + i))
            server.publish(Page("mode", "dive", "robot", 1.0))
            self.assertEqual(
                {k: p.data for k, p in server._inbox.items()}, {"depth_m": 4.0, "mode": "dive"}
            )
            with self.assertLogs("snr.test.live_view", "WARNING") as logs:
                server._take_inbox()
            self.assertEqual(server.stats.dropped_before_sending, 4)
            self.assertIn("Dropped 4 pages for the live view", logs.output[0])
            self.assertEqual(server._inbox, {})
            server.publish(Page("depth_m", 5.0, "robot", 6.0))
            server._take_inbox()
            self.assertEqual(server.stats.pages_dropped, 4)  # nothing replaced this time


@NEEDS_WEBSOCKETS
class TestViewer(SNRTestCase):
    def test_channels_with_schemas_then_pages_as_the_codec_writes_them(self) -> None:
        live = LiveNode(self, ["depth_m", "imu"])
        first = [live.store("depth_m", 0.0), live.store("imu", {"ax": 0.5, "ok": True})]
        wait_for(lambda: live.node.get_page("imu") is not None, "the first pages")

        async def view() -> None:
            async with connect(live.bridge.url, subprotocols=[SDK]) as viewer:
                self.assertEqual(viewer.subprotocol, "foxglove.sdk.v1")
                info = await next_json(viewer)
                self.assertEqual(info["op"], "serverInfo")
                advertised = await next_json(viewer)
                channels = {c["topic"]: c for c in advertised["channels"]}
                self.assertEqual(set(channels), {"/depth_m", "/imu"})
                imu = channels["/imu"]
                self.assertEqual(
                    (imu["encoding"], imu["schemaName"], imu["schemaEncoding"]),
                    ("json", "snr.Page", "jsonschema"),
                )
                schema = json.loads(imu["schema"])
                self.assertEqual(schema, page_schema({"ax": 0.5, "ok": True}))
                depth_id = channels["/depth_m"]["id"]
                await viewer.send(
                    json.dumps(
                        {
                            "op": "subscribe",
                            "subscriptions": [
                                {"id": 7, "channelId": depth_id},
                                {"id": 8, "channelId": imu["id"]},
                            ],
                        }
                    )
                )
                # A new subscriber gets each key's current page at once.
                current = [await next_frame(viewer), await next_frame(viewer)]
                by_id = {sub: (log_ns, fields) for sub, log_ns, fields in current}
                self.assertEqual(set(by_id), {7, 8})
                for sub, page in ((7, first[0]), (8, first[1])):
                    log_ns, fields = by_id[sub]
                    self.assertEqual(
                        json.dumps(fields, separators=(",", ":")).encode(), page_json(page)
                    )
                    self.assertEqual(log_ns, int(page.created_at_s * 1e9))
                # Then pages as they are stored: in order, the newest always arrives.
                stored = [live.store("depth_m", float(i)) for i in range(1, 30)]
                seen: List[float] = []
                while not seen or seen[-1] != stored[-1].data:
                    sub, _, fields = await next_frame(viewer)
                    self.assertEqual(sub, 7)
                    seen.append(fields["data"])
                self.assertEqual(seen, sorted(seen))

        asyncio.run(view())

    def test_older_viewers_connect_and_a_client_without_the_protocol_is_refused(self) -> None:
        live = LiveNode(self, ["depth_m"])

        async def view() -> None:
            async with connect(live.bridge.url, subprotocols=[OLDER]) as viewer:
                self.assertEqual(viewer.subprotocol, "foxglove.websocket.v1")
                self.assertEqual((await next_json(viewer))["op"], "serverInfo")
            with self.assertRaises(InvalidStatus) as refused:
                async with connect(live.bridge.url):
                    pass
            self.assertEqual(refused.exception.response.status_code, 400)

        asyncio.run(view())

    def test_a_stalled_viewer_gets_the_newest_page_of_each_key_and_slows_no_one(self) -> None:
        live = LiveNode(self, ["big", "rare"])
        live.store("big", -1)
        live.store("rare", "r0")
        wait_for(lambda: live.node.get_page("rare") is not None, "the first pages")
        blob = "x" * 65536  # a few dozen of these fill the socket buffers on the way
        stats = live.bridge.stats

        async def view() -> None:
            small = socket.create_connection(("127.0.0.1", live.bridge.port))
            small.setsockopt(socket.SOL_SOCKET, socket.SO_RCVBUF, 1 << 18)
            async with (
                connect(
                    live.bridge.url,
                    sock=small,
                    subprotocols=[SDK],
                    max_queue=1,
                    close_timeout=1,
                ) as stalled,
                connect(live.bridge.url, subprotocols=[SDK], close_timeout=1) as fast,
            ):
                for viewer in (stalled, fast):
                    await subscribe_all(viewer)
                    await next_frame(viewer)  # the current pages: subscribed
                    await next_frame(viewer)
                # The stalled viewer reads nothing from here on. The fast one paces
                # the pages, so the server offers each to both viewers; it goes on
                # until pages for the stalled one are being dropped, and a bit more.
                last, i, more = -1, -1, 20
                while more and i < 500:
                    i += 1
                    live.store("big", [i, blob])
                    if i == 10:
                        live.store("rare", "r1")
                    while last < i:  # the newest arrives, whatever was merged on the way
                        _, _, fields = await next_frame(fast)
                        if fields["key"] == "big":
                            last = fields["data"][0]
                    if stats.dropped_for_viewers:
                        more -= 1
                self.assertGreater(live.bridge.stats.dropped_for_viewers, 0)
                # Read again: the newest page of each key is waiting, in order.
                got: Dict[str, List[Any]] = {"big": [], "rare": []}
                while not got["big"] or got["big"][-1] != i or not got["rare"]:
                    _, _, fields = await next_frame(stalled)
                    data = fields["data"]
                    got[fields["key"]].append(data[0] if fields["key"] == "big" else data)
                self.assertEqual(got["rare"], ["r1"])
                self.assertEqual(got["big"], sorted(got["big"]))
                self.assertLess(len(got["big"]), i + 1)  # the rest were dropped and counted

        asyncio.run(view())


class TestDemoOption(SNRTestCase):
    def test_view_passes_the_port_to_the_demo(self) -> None:
        from snr.__main__ import main

        with mock.patch("snr.extras.demo.command.run_demo", return_value=0) as run_demo:
            self.assertEqual(main(["demo", "--seconds", "1", "--view", "--view-port", "9999"]), 0)
            self.assertEqual(run_demo.call_args.kwargs["view_port"], 9999)
            main(["demo", "--seconds", "1"])
            self.assertIsNone(run_demo.call_args.kwargs["view_port"])

    def test_without_websockets_the_demo_says_what_to_install_and_starts_nothing(self) -> None:
        from snr.extras.demo import run_demo

        hidden = {"websockets": None, "websockets.asyncio": None, "websockets.asyncio.server": None}
        err = io.StringIO()
        with mock.patch.dict(sys.modules, hidden), contextlib.redirect_stderr(err):
            with mock.patch("snr.MultiProcRunner") as runner:
                self.assertEqual(run_demo(1.0, view_port=8765), 2)
        runner.assert_not_called()
        self.assertEqual(err.getvalue().count("\n"), 1)
        self.assertIn(install_hint("view"), err.getvalue())
