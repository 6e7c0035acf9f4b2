"""Zenoh comms: many nodes, one network, pages published by key (the ``zenoh`` extra).

Install it with ``pip install 'snr-robotics[zenoh]'``.

Each node adds one `ZenohCommsFactory`. It publishes the pages stored under
the keys it names, each under the Zenoh key expression ``snr/<system>/<key>``,
and stores the pages of the keys it subscribes to (exact keys or wildcards),
with their origin and creation time, as a `SocketsPair` link does::

    zenoh = snr.ZenohCommsFactory("team7", publish=["sensor_data"], subscribe=["controller_*"])

The payload of every sample is the body of a page frame of
docs/wire-format.md (``{"v":1,"kind":"page","key":...,"data":...,...}``),
declared as ``application/json``, so any Zenoh program in any language can read
SNR pages and publish pages to SNR nodes (docs/comms.md, "Zenoh").

Zenoh runs its own threads. Each subscription's samples wait in a bounded
Zenoh FIFO (`SampleChannel`), which the node's thread empties in batches, one
queued task per batch: a watcher thread only wakes the node for the first
sample of a burst, so the threads take turns on the GIL once a batch instead
of once a page. While the node is idle its own thread waits in the FIFO of one
subscription (`IdleReader`), as it waits on its sockets for `SocketsPair`: a
page that arrives then reaches the handlers with no hand-off between threads.
While a FIFO is full Zenoh's thread waits (Zenoh then slows the sender); if
the node's thread takes nothing for ``max_wait_s`` (it is stuck in a
handler), what waits is dropped and counted, so the senders are never held
for ever. Pages published here are never received here, and a page
that came from Zenoh is never published again (no echo).
"""

from __future__ import annotations

import atexit
import collections
import ipaddress
import json
import logging
import os
import shutil
import socket
import tempfile
import threading
import time
from itertools import zip_longest
from typing import (
    TYPE_CHECKING,
    Any,
    Deque,
    Dict,
    List,
    Mapping,
    Optional,
    Sequence,
    Set,
    Tuple,
)

from snr.core import EndpointFactory, tasks
from snr.core.endpoint import Endpoint
from snr.core.logs import LossReport
from snr.core.node import Node
from snr.core.task_queue import TaskQueue
from snr.extras.zenoh.inbox import (
    WAKE,
    IdleReader,
    SampleChannel,
    SequenceFollower,
    count_attachment,
    read_count,
    wake_key,
)
from snr.prelude import (
    AbstractNode,
    CommsError,
    ConfigError,
    DataKey,
    NotSerializableError,
    Page,
    SomeTasks,
    Task,
    TaskId,
    TaskPriority,
    TaskType,
    WireFormatError,
)
from snr.prelude.install import install_hint
from snr.std_mods.codec import WIRE_VERSION, PageEncoder, load_object, page_from_fields
from snr.std_mods.comms.comms_loop import (
    COMMS_CONNECTED,
    COMMS_DISCONNECTED,
    DEFAULT_DEAD_AFTER_S,
    Keys,
    normalize_keys,
)
from snr.std_mods.comms.handshake import FROM_ENVIRONMENT, derived_word, find_secret
from snr.std_mods.comms.rate_limited_log import RateLimitedLog

if TYPE_CHECKING:  # imported when a node starts: the extra is optional
    import zenoh

__all__ = [
    "BATCH_TIME_LIMIT_MS",
    "DEFAULT_ORIGIN",
    "KEY_PREFIX",
    "MEET_ENDPOINTS_S",
    "ZENOH_USER",
    "IdleReader",
    "SampleChannel",
    "ZenohComms",
    "ZenohCommsFactory",
    "key_expr_of",
    "meet_endpoints",
    "page_from_sample",
    "unmet_endpoints",
    "wake_key",
    "zenoh_config",
    "zenoh_credentials",
]

KEY_PREFIX = "snr"
"""The first chunk of every SNR key expression: ``snr/<system>/<key>``."""

DEFAULT_ORIGIN = "zenoh"
"""The origin of a page whose sample says none (a program that is not SNR sent it)."""

BATCH_TIME_LIMIT_MS = 2
"""How long (ms) Zenoh may hold a page to fill a batch while its link is busy.

Zenoh sends a lone page at once; only while pages queue faster than the link
takes them does it gather them into batches, for at most this long (its own
default is 1 ms). 2 ms let a burst of small pages through about 25 % faster
on a 2-core machine (bench/bench_zenoh.py) and left the round trip unchanged.
Set another value with ``zenoh_settings``.

Example::

    ZenohCommsFactory("team7", publish="scan",
                      zenoh_settings={"transport/link/tx/queue/batching/time_limit": 1})
"""

ZENOH_USER = "snr"
"""The Zenoh user name of every node with a secret (its password comes from the secret).

Example::

    zenoh_credentials(b"s3cret")   # ('snr', '6f1d...'): give a zenohd router these
"""

_PAGE_HEAD = {"v": WIRE_VERSION, "kind": "page"}
_MAX_ECHO_GUARD = (
    10_000  # pages from Zenoh waiting to be stored, remembered so they are not re-sent
)
_FIFO_SAMPLES = 10_000  # samples a subscription's FIFO holds; Zenoh's thread waits above it
_BATCH = 500  # samples decoded per task on the node's thread (then the pages, then the rest)
_POLL_S = 0.025  # how often the watcher of the subscription the node's thread reads looks in
_IDLE_CHECK_S = 0.25  # ... while that thread waits in it (an idle node costs next to nothing)
_BUSY_READS_S = 0.05  # then, once the node's thread has worked this long, it reads for it
_BAD_CHARS = set("*$?#")
_MODES = ("peer", "client", "router")
_STORE_PAGE = TaskType.store_page
_INSTALL = install_hint("zenoh")


def _zenoh_module() -> Any:
    """The ``zenoh`` module, or a ConfigError that says how to install it."""
    try:
        import zenoh
    except ImportError as error:
        raise ConfigError(
            f"ZenohCommsFactory needs the Zenoh library ({error}): {_INSTALL}"
        ) from None
    return zenoh


def _check_chunk_text(text: str, what: str, wildcards: bool) -> None:
    if not isinstance(text, str) or not text:
        raise ConfigError(f"{what} must be a non-empty string, not {text!r}.")
    for chunk in text.split("/"):
        if not chunk:
            raise ConfigError(
                f"{what} {text!r} has an empty part (a leading, trailing or double '/'); "
                "Zenoh key expressions cannot have one."
            )
        if chunk.startswith("@"):
            raise ConfigError(
                f"{what} {text!r} has a part starting with '@', which Zenoh keeps for "
                "itself (SNR uses '@node' and '@console' under each system)."
            )
        if wildcards and chunk in ("*", "**"):
            continue
        if _BAD_CHARS & set(chunk):
            allowed = " ('*' or '**' as a whole part matches keys)" if wildcards else ""
            raise ConfigError(
                f"{what} {text!r} has one of * $ ? # inside a part{allowed}; Zenoh key "
                "expressions cannot. Use letters, digits, '_', '-' and '/'."
            )


_WILDCARDS = ("*", "**")


def _differ_before_a_wildcard(first: str, second: str) -> bool:
    """Whether ``first`` and ``second`` differ at a part with no wildcard at or before it.

    Read part by part from the left: a part that is ``*`` or ``**`` in either
    stops the reading (False); two exact parts that differ, or one pattern
    ending before the other, end it (True: no key can match both).
    """
    for x, y in zip_longest(first.split("/"), second.split("/")):  # None past the end
        if x in _WILDCARDS or y in _WILDCARDS:
            return False  # it may stand for the other's part, or for more parts
        if x != y:
            return True  # two different words, or one pattern has ended
    return False  # the same exact key (not given twice: normalize_keys drops repeats)


def _check_no_overlap(patterns: Sequence[str]) -> None:
    """Refuse two subscribe patterns unless they differ before either has a wildcard.

    Each pattern is its own Zenoh subscriber, with its own FIFO; a page both
    match would be received by each, and the two copies taken in no set order.
    The rule is kept simple enough to check by eye, so it refuses some pairs
    that could never share a key (``a/*/x`` and ``a/*/y``).
    """
    for index, first in enumerate(patterns):
        for second in patterns[index + 1 :]:
            if not _differ_before_a_wildcard(first, second):
                raise ConfigError(
                    f"ZenohCommsFactory got subscribe patterns {first!r} and {second!r}, "
                    "which may match a key in common: its pages would arrive twice, out of "
                    "order (each pattern is its own Zenoh subscriber). Two patterns go "
                    "together only if, read part by part from the left, they differ (or one "
                    "ends) before either has a '*' or '**'. Give exact keys, or one wider "
                    "pattern in place of both, or subscribe to one pattern and skip the "
                    "keys you do not want in your handler."
                )


def _empty_fifo(handler: Any) -> None:
    """Take and forget what waits in an undeclared subscription's FIFO (the node is stopping)."""
    for _ in range(_FIFO_SAMPLES + 100):  # bounded: nothing new comes once undeclared
        try:
            if handler.try_recv() is None:
                return
        except Exception:  # closed and empty
            return


def key_expr_of(system: str, key: str) -> str:
    """The Zenoh key expression SNR uses for ``key`` in ``system``.

    Example::

        key_expr_of("team7", "depth_m")   # 'snr/team7/depth_m'
    """
    return f"{KEY_PREFIX}/{system}/{key}"


def page_from_sample(key: str, payload: bytes) -> Page:
    """The page in a Zenoh sample's payload, received under the data key ``key``.

    The payload is a page frame's body (docs/wire-format.md). From programs
    that are not SNR, ``v`` and ``kind`` may be left out, the key is the key
    expression's, a missing origin is ``"zenoh"`` and a missing time is now:
    ``{"data": 3.2}`` published under ``snr/team7/depth_m`` is a page.

    Raises:
        WireFormatError: not a JSON object, another version or kind, a key
            that is not the key expression's, or a field of the wrong type.

    Example::

        page_from_sample("depth_m", b'{"data": 3.2}')   # Page('depth_m', 3.2, 'zenoh', ...)
    """
    fields = load_object(payload)
    version = fields.get("v", WIRE_VERSION)
    if type(version) is not int or version != WIRE_VERSION:
        raise WireFormatError(
            f"the page has version {version!r:.40}; this SNR speaks version {WIRE_VERSION}"
        )
    kind = fields.get("kind", "page")
    if kind != "page":
        raise WireFormatError(f"the sample is a {kind!r:.40}, not a page")
    named = fields.setdefault("key", key)
    if named != key:
        raise WireFormatError(
            f"the page's key {named!r:.60} is not the key of its key expression {key!r}"
        )
    return page_from_fields(fields, default_origin=DEFAULT_ORIGIN)


def zenoh_credentials(secret: bytes) -> Tuple[str, str]:
    """The Zenoh user name and password of a node with this secret.

    The password is a word made from the secret (`derived_word`), so the
    secret itself is neither given to Zenoh nor written to its password file.
    Give a Zenoh router (``zenohd``) these, for nodes with a secret to link to
    it (docs/comms.md, "Who may connect").

    Example::

        zenoh_credentials(b"s3cret")   # ('snr', '6f1d...' (64 hex digits))
    """
    return ZENOH_USER, derived_word(secret, "zenoh-password")


_dictionary_lock = threading.Lock()
_dictionaries: Dict[str, str] = {}  # password -> its file, for the life of this process


def _dictionary_file(user: str, password: str) -> str:
    """Zenoh's list of who may link (one ``user:password`` line), private to this process.

    Zenoh reads it when a session opens; it stays in a folder only this
    process's user can open (``mkdtemp``: mode 0700), and goes at exit.
    """
    with _dictionary_lock:
        path = _dictionaries.get(password)
        if path is None or not os.path.isfile(path):
            folder = tempfile.mkdtemp(prefix="snr-zenoh-")
            atexit.register(shutil.rmtree, folder, True)
            path = os.path.join(folder, "users")
            handle = os.open(path, os.O_WRONLY | os.O_CREAT | os.O_EXCL, 0o600)
            with os.fdopen(handle, "w", encoding="ascii") as file:
                file.write(f"{user}:{password}\n")
            _dictionaries[password] = path
        return path


MEET_ENDPOINTS_S = 2.0
"""How long a new session may take to meet a node at each of its ``connect`` endpoints.

A console waits this long at most before its first command; a node warns
(without waiting: in the background) about each endpoint it has not met by then.
"""


def _locators_of(endpoint: str) -> Set[str]:
    """The locators a link to ``endpoint`` may show as its ``dst``: the endpoint, resolved.

    Zenoh shows a link's far end by address (``tcp/127.0.0.1:7447``), so an
    endpoint given by name (``tcp/robot.local:7447``) is matched by the
    addresses its name has now.
    """
    locator = endpoint.split("#")[0].split("?")[0]  # no metadata, no configuration
    found = {locator}
    protocol, _, address = locator.partition("/")
    host, _, port = address.rpartition(":")
    host = host.strip("[]")
    try:
        ipaddress.ip_address(host)
    except ValueError:  # a name: look it up (in the background, never on the node's thread)
        try:
            for *_, sockaddr in socket.getaddrinfo(host, port or None):
                ip = str(sockaddr[0])
                found.add(f"{protocol}/[{ip}]:{port}" if ":" in ip else f"{protocol}/{ip}:{port}")
        except (OSError, UnicodeError):  # no such name: nothing else to match
            pass
    return found


def meet_endpoints(
    session: Any,
    connect: Sequence[str],
    mode: str = "peer",
    bound_s: float = MEET_ENDPOINTS_S,
    quiet_s: Optional[float] = None,
    stop: Optional[threading.Event] = None,
) -> bool:
    """Wait until a Zenoh session has met a node at each ``connect`` endpoint; say if it did.

    Zenoh opens a session at once and connects in the background, and it says
    nothing when a link fails (nobody listening, or its authentication
    refused the other side). So this counts the peers and routers the
    session has met, every 5 ms, until there is one per endpoint (a
    ``"client"`` needs one router in all), ``bound_s`` has passed, ``stop``
    is set, or (with ``quiet_s``) that long has passed since the last one met,
    if it met any. `unmet_endpoints` then says which endpoints were not met.

    Example::

        session = zenoh.open(zenoh_config(connect=["tcp/127.0.0.1:7447"], scouting=False))
        meet_endpoints(session, ["tcp/127.0.0.1:7447"])   # True once a node is met there
    """
    if not connect:
        return True  # scouting: there is no knowing how many nodes to meet
    info = session.info
    wanted = 1 if mode == "client" else len(connect)
    started = time.monotonic()
    deadline = started + bound_s
    count, counted_at = 0, started
    while True:
        now = time.monotonic()
        latest = len(list(info.peers_zid())) + len(list(info.routers_zid()))
        if latest != count:
            count, counted_at = latest, now
        if count >= wanted:
            return True
        if now >= deadline or (stop is not None and stop.is_set()):
            return False
        # An endpoint nobody listens on would hold a console up for the whole bound.
        if quiet_s is not None and count and now - counted_at >= quiet_s:
            return False
        time.sleep(0.005)


def unmet_endpoints(session: Any, connect: Sequence[str], mode: str = "peer") -> List[str]:
    """The ``connect`` endpoints a Zenoh session has no open link to (a client: all, or none).

    A name in an endpoint is looked up, so call it off the node's thread.

    Example::

        unmet_endpoints(session, ["tcp/127.0.0.1:7447"])   # ['tcp/127.0.0.1:7447']: no link
    """
    info = session.info
    if mode == "client" and (list(info.routers_zid()) or list(info.peers_zid())):
        return []  # a client needs one router, whichever endpoint it came from
    linked = {str(link.dst) for link in info.links()}
    return [endpoint for endpoint in connect if not _locators_of(endpoint) & linked]


def zenoh_config(
    mode: str = "peer",
    connect: Sequence[str] = (),
    listen: Sequence[str] = (),
    scouting: bool = True,
    dead_after_s: float = DEFAULT_DEAD_AFTER_S,
    extra: Optional[Mapping[str, Any]] = None,
    secret: Optional[bytes] = None,
) -> Any:
    """A ``zenoh.Config`` for one node (what `ZenohCommsFactory` opens its session with).

    ``extra`` maps more Zenoh configuration paths to values (JSON), set last,
    e.g. ``{"transport/link/tx/queue/congestion_control/drop/wait_before_drop": 5000}``.

    With a ``secret``, Zenoh's own user/password authentication is on
    (``transport/auth/usrpwd``, with `zenoh_credentials`): the session links
    only to peers that prove the same password, in both directions, so a
    session without it neither hears this system nor speaks into it.

    Example::

        zenoh.open(zenoh_config(connect=["tcp/127.0.0.1:7447"], scouting=False))
        zenoh.open(zenoh_config(listen=["tcp/127.0.0.1:7447"], secret=b"s3cret"))
    """
    zenoh = _zenoh_module()
    config = zenoh.Config()
    settings: Dict[str, Any] = {
        "mode": mode,
        "scouting/multicast/enabled": scouting,
        # A node whose peer is not up yet still starts, and keeps trying
        # (0.1 s, doubling, at most 1 s apart, as a sockets client does).
        "connect/exit_on_failure": False,
        "connect/retry": {
            "period_init_ms": 100,
            "period_max_ms": 1000,
            "period_increase_factor": 2.0,
        },
        # A peer not heard from for this long is lost (Zenoh beats 4 times per lease).
        "transport/link/tx/lease": int(dead_after_s * 1000),
        # Fuller batches while the link is busy: fewer wake-ups and system calls
        # on both sides when a node streams pages (see BATCH_TIME_LIMIT_MS).
        "transport/link/tx/queue/batching/time_limit": BATCH_TIME_LIMIT_MS,
    }
    if connect:
        settings["connect/endpoints"] = list(connect)
    if listen:
        settings["listen/endpoints"] = list(listen)
    if not scouting:
        settings["scouting/delay"] = 0  # nothing to wait for: open at once
    if secret is not None:
        user, password = zenoh_credentials(secret)
        settings["transport/auth/usrpwd/user"] = user
        settings["transport/auth/usrpwd/password"] = password
        settings["transport/auth/usrpwd/dictionary_file"] = _dictionary_file(user, password)
    settings.update(extra or {})
    for path, value in settings.items():
        try:
            config.insert_json5(path, json.dumps(value))
        except Exception as error:  # zenoh.ZError: an unknown path or a bad value
            raise ConfigError(
                f"Zenoh refused the setting {path} = {value!r}: {error}. See the Zenoh "
                "configuration reference (DEFAULT_CONFIG.json5) for the paths it knows."
            ) from None
    return config


class ZenohCommsFactory(EndpointFactory):
    """Builds a `ZenohComms`: pages by key over Zenoh, between any number of nodes.

    Args:
        system: the name that keeps one robot's nodes apart from another's on the
            same network (one part: letters, digits, ``_``, ``-``).
        publish: the data key (or keys) whose pages this node publishes.
        subscribe: keys whose pages this node stores: exact keys, or patterns with
            ``*`` (one part of a key) and ``**`` (any number of parts). Two patterns
            must differ (or one end) before either has a wildcard, read from the
            left: else a key both match would bring its pages twice.
        mode: ``"peer"`` (default: talk to other nodes directly) or ``"client"``
            (talk through a Zenoh router, ``zenohd``).
        connect: endpoints to connect to, e.g. ``["tcp/192.168.1.10:7447"]``.
        listen: endpoints to listen on, e.g. ``["tcp/0.0.0.0:7447"]``.
        scouting: find peers by UDP multicast (default True; turn it off where
            multicast is blocked, and give ``connect`` endpoints instead).
        congestion: ``"drop"`` (default: a page that finds Zenoh's send queue full
            is dropped; the receiver counts the gap) or ``"block"`` (the node
            waits for room; nothing is dropped while the peer lives).
        dead_after_s: seconds of silence after which a peer counts as gone.
        max_wait_s: how long a received page waits for room in the node's queue
            before it is dropped (and counted).
        zenoh_settings: more Zenoh configuration paths and values, set last.
        secret: the system's secret: by default ``SNR_SECRET`` or the secret
            file (docs/comms.md, "Who may connect"); ``None``: none. With one,
            the session links only to sessions with the same secret (Zenoh's
            user/password authentication).
        name: the component name (default ``"zenoh_comms"``).

    Example::

        ZenohCommsFactory("team7", publish=["sensor_data"], subscribe=["controller_*"])
        ZenohCommsFactory("team7", subscribe="**", connect=["tcp/192.168.1.10:7447"],
                          scouting=False)
    """

    def __init__(
        self,
        system: str,
        publish: Keys = None,
        subscribe: Keys = None,
        *,
        mode: str = "peer",
        connect: Sequence[str] = (),
        listen: Sequence[str] = (),
        scouting: bool = True,
        congestion: str = "drop",
        dead_after_s: float = DEFAULT_DEAD_AFTER_S,
        max_wait_s: float = 1.0,
        zenoh_settings: Optional[Mapping[str, Any]] = None,
        secret: Optional[str] = FROM_ENVIRONMENT,
        name: Optional[str] = None,
    ) -> None:
        super().__init__()
        if not isinstance(system, str) or "/" in system:
            raise ConfigError(
                f"ZenohCommsFactory got system={system!r}. Give one word naming your robot's "
                'system, e.g. "team7": nodes only hear nodes of the same system.'
            )
        _check_chunk_text(system, "The system name", wildcards=False)
        self.system = system
        self.publish = normalize_keys(publish, "ZenohCommsFactory publish")
        self.subscribe = normalize_keys(subscribe, "ZenohCommsFactory subscribe")
        for key in self.publish:
            _check_chunk_text(key, "The published key", wildcards=False)
        for key in self.subscribe:
            _check_chunk_text(key, "The subscribed key", wildcards=True)
        _check_no_overlap(self.subscribe)
        if not self.publish and not self.subscribe:
            raise ConfigError(
                "ZenohCommsFactory got no keys to publish and none to subscribe to: give "
                'publish=["key", ...] and/or subscribe=["key", "sensors/*"] ("**": every key).'
            )
        if mode not in _MODES:
            raise ConfigError(f"ZenohCommsFactory got mode={mode!r}; use one of {_MODES}.")
        if congestion not in ("drop", "block"):
            raise ConfigError(
                f'ZenohCommsFactory got congestion={congestion!r}; use "drop" or "block".'
            )
        for what, endpoints in (("connect", connect), ("listen", listen)):
            if isinstance(endpoints, str) or not all(isinstance(e, str) for e in endpoints):
                raise ConfigError(
                    f"ZenohCommsFactory got {what}={endpoints!r}; give a list of endpoints, "
                    'e.g. ["tcp/192.168.1.10:7447"].'
                )
        if not dead_after_s > 0 or not max_wait_s >= 0:
            raise ConfigError(
                f"ZenohCommsFactory got dead_after_s={dead_after_s!r}, max_wait_s="
                f"{max_wait_s!r}; give seconds (dead_after_s above 0, max_wait_s 0 or more)."
            )
        self.mode = mode
        self.connect = list(connect)
        self.listen = list(listen)
        self.scouting = scouting
        self.congestion = congestion
        self.dead_after_s = dead_after_s
        self.max_wait_s = max_wait_s
        self.zenoh_settings = dict(zenoh_settings or {})
        self.secret = secret
        self.name = name or "zenoh_comms"

    def get(self, parent: AbstractNode) -> ZenohComms:
        return ZenohComms(self, parent)


class ZenohComms(Endpoint):
    """Publishes pages under its keys to Zenoh and stores the pages it subscribes to.

    Built by `ZenohCommsFactory`. A Zenoh session is opened when the node
    starts and closed when it stops. Other nodes of the same system are
    announced with the events ``COMMS_CONNECTED`` and ``COMMS_DISCONNECTED``
    (values ``[component name, peer role]``), from Zenoh liveliness tokens.

    Example::

        comms = ZenohCommsFactory("team7", publish="depth_m").get(node)
        comms.stats()["published"]

    Attributes:
        peers: the roles of the other nodes of the system now present, by Zenoh id.
        lost_report: counts pages that never arrived from a sender (gaps in its
            count: Zenoh dropped them under congestion, or the path broke).
        queue_report: counts received pages dropped because the node's thread
            took none for ``max_wait_s`` (it was stuck).
    """

    def __init__(self, factory: ZenohCommsFactory, parent: AbstractNode) -> None:
        super().__init__(factory, parent, factory.name)
        self.zenoh = _zenoh_module()
        self.spec = factory
        self.prefix = f"{KEY_PREFIX}/{factory.system}/"
        self.session: Any = None
        self.peers: Dict[str, str] = {}
        self.published = 0
        self.received = 0
        self.bad_samples = 0
        self._sender_id = os.urandom(8)
        self._counts: Dict[DataKey, int] = {}
        # page_json with the sample's head: the same bytes as a TCP frame's body.
        self._encode = PageEncoder(_PAGE_HEAD, to="over Zenoh")
        self._publishers: Dict[DataKey, Any] = {}
        self._declared: List[Any] = []
        self._sequences = SequenceFollower()
        self._arrived: Dict[int, Page] = {}  # the echo guard: id(page) -> page
        self._published_keys = frozenset(factory.publish)
        self._unsendable_reported: Set[Tuple[DataKey, type]] = set()
        self._bad_reported = 0
        # Each subscription's samples, and the liveliness changes (as tuples)
        # that Zenoh's threads report, waiting for the node's thread.
        self._channels: List[SampleChannel] = []
        self._watchers: List[threading.Thread] = []
        self._reader: Optional[IdleReader] = None  # the node's thread reads one channel when idle
        self._peer_changes: Deque[Any] = collections.deque()  # (kind, key expression)
        self._batch_queued = False  # a task to take what waits is queued or running
        self._closed = threading.Event()
        batch_event = f"{factory.name}_arrived"
        # The first task of a burst jumps the queue (it never waits for room,
        # so it is never dropped); the next one queues behind its batch's pages.
        self._first_batch = Task(TaskType.event, batch_event, priority=TaskPriority.high)
        self._next_batch = Task(TaskType.event, batch_event)
        self.lost_report = LossReport(
            self.log,
            "pages from Zenoh",
            "they never arrived: a sender's queue was full (Zenoh drops under congestion) "
            "or the path broke",
            verb="Lost",
        )
        self.queue_report = LossReport(
            self.log,
            "pages from Zenoh",
            f"the node's thread took none for {factory.max_wait_s:g} s (a handler is stuck, "
            "or the node's queue stayed full)",
        )
        # Endpoints met by no node within MEET_ENDPOINTS_S of opening: each is said
        # once a session, and a node with many of them says a count after five.
        self.unmet_endpoints = 0
        self._unmet_news = RateLimitedLog(self.log, burst=5, window_s=60.0)
        self.task_handlers = {
            (TaskType.store_page, key): self.publish_page for key in factory.publish
        }
        self.task_handlers[(TaskType.event, batch_event)] = self.take_batch
        self.burst_handlers = {
            (TaskType.store_page, key): self.publish_burst for key in factory.publish
        }
        if parent.profiler is not None:
            parent.profiler.add_report(self.name, self.stats_text)

    # -- starting and stopping --------------------------------------------------
    def begin(self) -> None:
        """Open the Zenoh session; declare the publishers, subscribers and this node's token."""
        zenoh, spec = self.zenoh, self.spec
        secret = find_secret(spec.secret, f"ZenohCommsFactory of node {self.parent.role!r}")
        config = zenoh_config(
            spec.mode,
            spec.connect,
            spec.listen,
            spec.scouting,
            spec.dead_after_s,
            spec.zenoh_settings,
            secret,
        )
        try:
            self.session = zenoh.open(config)
        except zenoh.ZError as error:
            said = str(error).split(" at /")[0]
            if "Unable to connect" in said:
                # A client must reach a router at once; Zenoh says neither why nor who refused.
                mine = "this node has one" if secret is not None else "this node has none"
                fix = (
                    " Likely causes: (1) no router (zenohd, or `python -m snr router`) runs "
                    "there; (2) the router has another secret, or only one side has one "
                    f"({mine}): both need the same SNR_SECRET (docs/comms.md, 'Who may connect')."
                )
            else:
                fix = " If a port is in use, stop the other program or pick another port."
            raise CommsError(
                f"Node {self.parent.role!r} could not open its Zenoh session (listen="
                f"{spec.listen}, connect={spec.connect}, mode={spec.mode!r}): {said}.{fix}"
            ) from None
        session = self.session
        congestion = (
            zenoh.CongestionControl.BLOCK
            if spec.congestion == "block"
            else zenoh.CongestionControl.DROP
        )
        for key in spec.publish:
            self._publishers[key] = session.declare_publisher(
                self.prefix + key,
                encoding=zenoh.Encoding.APPLICATION_JSON,
                congestion_control=congestion,
            )
        # A FIFO per subscription, emptied by the node's thread (SampleChannel):
        # a Python callback per sample, on a thread of Zenoh's or on its
        # network thread, took the GIL from the node's thread once a page.
        # The node's thread waits in one of them while idle (IdleReader).
        idle = self._idle_subscription()
        for index, pattern in enumerate(spec.subscribe):
            reads_idle = idle is not None and idle[0] == index
            subscriber = session.declare_subscriber(
                self.prefix + pattern,
                zenoh.handlers.FifoChannel(_FIFO_SAMPLES),
                # Never hear our own pages; the idle reader's wake-ups are ours, but
                # its pattern matches none of the keys this node publishes.
                allowed_origin=zenoh.Locality.ANY if reads_idle else zenoh.Locality.REMOTE,
            )
            self._declared.append(subscriber)
            channel = SampleChannel(subscriber.handler)
            if idle is not None and reads_idle:
                reader = IdleReader(
                    channel,
                    idle[1],
                    take=self._take_now,
                    put_wake=self._put_wake,
                    has_room=self._node_has_room,
                )
                queue = self._node_queue()
                if queue is not None and queue.use_waiter(reader):
                    self._reader = reader
            self._watch_channel(channel)
        me = str(session.zid())
        liveliness = session.liveliness()
        self._declared.append(
            liveliness.declare_token(f"{self.prefix}@node/{self.parent.role}/{me}")
        )
        self._declared.append(
            liveliness.declare_subscriber(
                f"{self.prefix}@node/**", self._on_liveliness, history=True
            )
        )
        self.info(
            "Zenoh session %s open for system %r (publishing %s, subscribed to %s)",
            me[:8],
            spec.system,
            list(spec.publish),
            list(spec.subscribe),
        )
        if spec.connect:  # in the background: the node starts at once
            checker = threading.Thread(
                target=self._check_endpoints,
                args=(session, secret is not None),
                name=f"{self.name}-endpoints",
                daemon=True,
            )
            self._watchers.append(checker)
            checker.start()

    def _check_endpoints(self, session: Any, has_secret: bool) -> None:
        """Warn about each ``connect`` endpoint where no node was met, with its likely causes.

        Zenoh refuses a session with another secret inside its own hello and
        says nothing to SNR, on either side: an endpoint that stays unmet is
        the only sign this side can give (docs/comms.md, "Who may connect").
        """
        spec = self.spec
        try:
            met = meet_endpoints(session, spec.connect, spec.mode, stop=self._closed)
            unmet = [] if met else unmet_endpoints(session, spec.connect, spec.mode)
        except Exception:  # zenoh.ZError: the session closed under us, as the node stopped
            return
        if self._closed.is_set():
            return  # stopped meanwhile: not meeting anyone is no news
        mine = "this node has one" if has_secret else "this node has none"
        for endpoint in unmet:
            self.unmet_endpoints += 1
            self._unmet_news.report(
                "Zenoh endpoints not met",
                logging.WARNING,
                "Node %r has met no Zenoh node at %s after %g s (Zenoh keeps trying). "
                "Likely causes, most likely first: (1) nothing listens there: is the "
                "other node (or zenohd) running, with this address in its listen "
                "endpoints? (2) a different secret, or only one side has one (%s): both "
                "sides need the same SNR_SECRET (docs/comms.md, 'Who may connect'); "
                "(3) something else listens there: not a Zenoh node, or a Zenoh of a "
                "different version.",
                self.parent.role,
                endpoint,
                MEET_ENDPOINTS_S,
                mine,
            )

    def halt(self) -> None:
        """Close the session (the node is stopping or this component is reloaded)."""
        self._close()

    def terminate(self) -> None:
        """Close the session if it is still open."""
        self._close()

    def _idle_subscription(self) -> Optional[Tuple[int, str]]:
        """The subscription the node's thread may wait in while idle, and the key that wakes it.

        The first whose pattern matches none of the keys this node publishes
        (its wake-ups come from this session, so its pages would too) and
        has a key to wake it with; None if there is none.
        """
        zenoh = self.zenoh
        published = [zenoh.KeyExpr(self.prefix + key) for key in self.spec.publish]
        for index, pattern in enumerate(self.spec.subscribe):
            key = wake_key(pattern)
            if key is None:
                continue
            expr = zenoh.KeyExpr(self.prefix + pattern)
            try:
                matched = expr.includes(zenoh.KeyExpr(self.prefix + key))
            except zenoh.ZError:  # not a valid key after all
                continue
            if matched and not any(expr.intersects(other) for other in published):
                return index, self.prefix + key
        return None

    def _node_queue(self) -> Optional[TaskQueue]:
        """The node's task queue, where the idle reader is installed; None for a mock node."""
        parent = self.parent
        return parent.queue if isinstance(parent, Node) else None

    def _node_has_room(self) -> bool:
        """The node's queue is below its high-water mark (for the idle reader)."""
        return self.parent.wait_for_room(0)

    def _put_wake(self, key: str) -> None:
        """Put a wake-up sample for the idle reader (see `IdleReader`)."""
        session = self.session
        if session is None or self._closed.is_set():
            return  # closing: nobody reads, and a full FIFO would hold the put for ever
        try:
            session.put(
                key, b"", attachment=WAKE, allowed_destination=self.zenoh.Locality.SESSION_LOCAL
            )
        except Exception:  # closed meanwhile: nobody waits any more
            pass

    def _close(self) -> None:
        self._closed.set()  # the watchers stop waiting for the node
        reader, self._reader = self._reader, None
        queue = self._node_queue()
        if reader is not None and queue is not None:  # the node waits on its bell again
            queue.stop_waiter(reader)
        for channel in self._channels:
            channel.emptied.set()
        session, self.session = self.session, None
        if session is None:
            return
        # Undeclare first: closing a session with callbacks still declared can
        # hang (zenoh-python #434). A subscriber's FIFO closes with it, which
        # ends its watcher's wait.
        for entity in reversed(self._declared):
            try:
                entity.undeclare()
            except Exception:  # already gone with the session
                pass
        self._declared.clear()
        self._publishers.clear()
        # A put that found a FIFO full waits in it (a wake-up put just before
        # closing began): emptying the FIFOs lets it go. Nothing new comes in.
        for channel in self._channels:
            _empty_fifo(channel.handler)
        session.close()
        self._unmet_news.flush()
        for watcher in self._watchers:
            watcher.join(1.0)
        self._watchers.clear()
        self._channels.clear()

    # -- node thread: publishing --------------------------------------------------
    def publish_page(self, task: Task, key: TaskId) -> SomeTasks:
        """Publish the page just stored, unless it came from Zenoh."""
        page = task.page()
        if page is None:
            return None  # the node core has already reported the bad task
        arrived = self._arrived
        if arrived and arrived.pop(id(page), None) is page:
            return None  # it came from Zenoh: never send it back
        publisher = self._publishers.get(page.key)
        if publisher is None:
            return None  # not started, or stopping
        try:
            body = self._encode(page)
        except NotSerializableError as error:
            kind = (page.key, type(page.data))
            if kind not in self._unsendable_reported:
                self._unsendable_reported.add(kind)
                self.err("%s The page was dropped; the node keeps running.", error)
            return None
        count = self._counts.get(page.key, 0) + 1
        self._counts[page.key] = count
        self.published += 1
        publisher.put(body, attachment=count_attachment(self._sender_id, count))
        return None

    def publish_burst(self, run: List[Task]) -> SomeTasks:
        """`publish_page` for a run of pages under one key, in one call from the node.

        Each page is still its own sample (Zenoh has no batch put in Python);
        what a run saves is the node's dispatch and timing of every page.

        Example (the node calls it for the pages a handler stored at once)::

            comms.publish_burst([tasks.store_page(page) for page in pages])
        """
        publish = self.publish_page
        for task in run:
            publish(task, _STORE_PAGE)
        return None

    # -- watcher threads: waking the node for a burst ------------------------------
    def _watch_channel(self, channel: SampleChannel) -> None:
        """Start the thread that wakes the node when ``channel`` has samples."""
        self._channels.append(channel)
        read_by_node = self._reader is not None and self._reader.channel is channel
        watcher = threading.Thread(
            target=self._watch_for_node if read_by_node else self._watch,
            args=(channel,),
            name=f"snr-{self.parent.role}-zenoh-{len(self._channels)}",
            daemon=True,  # it ends when the subscriber is undeclared; never holds up an exit
        )
        self._watchers.append(watcher)
        watcher.start()

    def _watch(self, channel: SampleChannel) -> None:
        """Watcher thread: hand over a burst's first sample; wait while the node takes it all."""
        handler = channel.handler
        wait_s = max(self.spec.max_wait_s, 0.01)  # max_wait_s may be 0: never spin
        while not self._closed.is_set():
            try:
                sample = handler.recv()  # waits without the GIL
            except Exception as error:  # zenoh.ZError "channel is empty and closed"
                if not self._closed.is_set():  # not undeclared by us: say it, never silent
                    self.err(
                        "Stopped taking samples from Zenoh for %s: %s. Pages under its keys "
                        "no longer arrive; reload this component to subscribe again.",
                        self.name,
                        error,
                    )
                return
            self._hand_over(channel, sample)
            taken = channel.taken
            while not channel.emptied.wait(wait_s) and not self._closed.is_set():
                if channel.taken == taken:  # nothing taken for max_wait_s: stuck
                    self._relieve(channel)
                taken = channel.taken

    def _watch_for_node(self, channel: SampleChannel) -> None:
        """Watcher of the channel the node's thread reads while idle: it reads while the node works.

        It looks every `_POLL_S` (it cannot wait in the FIFO: the node's
        thread does), and every `_IDLE_CHECK_S` while that thread waits in
        the FIFO, when it only wakes the thread at the time it asked for.
        Once the thread has worked `_BUSY_READS_S` without waiting, the
        watcher hands over a burst that came meanwhile, as `_watch` does. If
        the node's thread takes nothing of a burst for ``max_wait_s``, what
        waits is dropped and counted.
        """
        reader = self._reader
        assert reader is not None
        wait_s = max(self.spec.max_wait_s, 0.01)
        taken, since = channel.taken, time.monotonic()
        pause = _POLL_S
        while not self._closed.wait(pause):
            now = time.monotonic()
            pause = _POLL_S
            if not channel.emptied.is_set():  # the node's thread is taking a burst
                if channel.taken != taken:
                    taken, since = channel.taken, now
                elif now - since >= wait_s:  # nothing taken for max_wait_s: stuck
                    self._relieve(channel)
                    since = now
                continue
            taken, since = channel.taken, now
            if reader.reading:
                deadline = reader.deadline
                if deadline is not None and now >= deadline:
                    reader.deadline = None
                    reader.wake()
                    continue
                left = _IDLE_CHECK_S if deadline is None else deadline - now
                pause = min(max(left, _POLL_S), _IDLE_CHECK_S)
                continue
            if now - reader.busy_since < _BUSY_READS_S:
                continue
            if not channel.take_lock.acquire(blocking=False):
                continue  # the node's thread is about to wait in the FIFO
            try:
                if channel.emptied.is_set():
                    sample = channel.handler.try_recv()
                    if sample is not None:
                        self._hand_over(channel, sample)
            except Exception:  # undeclared meanwhile: the component is closing
                return
            finally:
                channel.take_lock.release()

    def _hand_over(self, channel: SampleChannel, sample: Any) -> None:
        """Give ``sample`` to the node's thread, which then owns the channel."""
        channel.first = sample  # set before emptied is cleared: the node takes it
        channel.emptied.clear()
        self._ask_for_batch()

    def _relieve(self, channel: SampleChannel) -> None:
        """The node's thread is stuck: drop and count what waits in the FIFO.

        Zenoh's thread waits while the FIFO is full, and under ``"block"``
        the senders wait with it; pages that waited this long are stale.
        """
        dropped = 0
        sequences = self._sequences
        while True:
            with sequences.lock:  # a gap the node's thread finds meanwhile waits for this count
                sample = channel.handler.try_recv()
                if sample is None:
                    break
                attachment = sample.attachment
                counted = None if attachment is None else attachment.to_bytes()
                if counted == WAKE:
                    continue  # only woke the node's thread: not a page
                dropped += 1
                numbered = read_count(counted)
                if numbered is not None:
                    sender, count = numbered
                    sequences.dropped(sender, str(sample.key_expr)[len(self.prefix) :], count)
        if dropped:
            self.queue_report.dropped(dropped)

    def _on_liveliness(self, sample: zenoh.Sample) -> None:
        # Never dropped (one per peer coming or going); taken once the pages
        # that wait in the channels have been.
        self._peer_changes.append((sample.kind, str(sample.key_expr)))
        self._ask_for_batch()

    def _ask_for_batch(self) -> None:
        """Queue a task to take what waits, unless one is queued (one task a burst)."""
        if not self._batch_queued:
            self._batch_queued = True
            self.parent.schedule(self._first_batch)

    # -- node thread: receiving ---------------------------------------------------
    def take_batch(self, task: Task, key: TaskId) -> SomeTasks:
        """Decode up to a batch of received samples; return one task that stores them.

        The next batch is asked for behind these pages, so the node's queue
        holds at most a batch of pages from Zenoh at a time. While the queue
        is above its high-water mark (other work fills it) nothing is taken:
        the samples wait in Zenoh's FIFO, and a full FIFO slows the senders.
        Peers coming and going are announced once no page waits before them.
        """
        if not self._node_has_room():
            self._batch_queued = True
            return [self._next_batch]  # asked again once the node worked its queue down
        return self._take_waiting()

    def _take_now(self) -> None:
        """Node's thread, after its idle wait (`IdleReader`): queue what waits now, if it has room.

        A sample the wait took was handed over in its channel (``first``);
        with no room, it waits there for the node.
        """
        if self._node_has_room():
            self.parent.schedule(self._take_waiting())

    def _take_waiting(self) -> List[Task]:
        """`take_batch`'s work: the tasks that store what waits, up to a batch."""
        # Cleared first: a hand-over after this asks for a new batch, and one
        # before it is taken below.
        self._batch_queued = False
        out: List[Task] = []
        budget = _BATCH
        for channel in self._channels:
            samples: List[Any] = []
            if channel.emptied.is_set():
                continue  # its watcher waits for a sample: nothing here
            if channel.first is not None:
                samples.append(channel.first)
                channel.first = None
            try_recv = channel.handler.try_recv
            fifo_empty = False
            while len(samples) < budget and not fifo_empty:
                sample = try_recv()
                if sample is None:
                    fifo_empty = True
                else:
                    samples.append(sample)
            if fifo_empty:  # else more than a batch waits: the node's thread takes it on
                channel.emptied.set()  # the watcher waits for the next burst
            channel.taken += len(samples)
            budget -= len(samples)
            pages = self._pages_of(samples)
            if len(pages) == 1:  # the usual page of a quiet link: no burst to split
                out.append(tasks.store_page(pages[0]))
            elif pages:  # stored by the node core in one call, as a link's burst is
                out.append(tasks.store_pages(pages))
        if self.queue_report.dropping and budget > 0:
            self.queue_report.recovered()
        changes = self._peer_changes
        if budget > 0:  # every channel emptied: peers' news, after their pages
            while changes:
                out.extend(self._peer_changed(*changes.popleft()))
        if out and not self._batch_queued:
            # The next batch queues behind these pages, even if every FIFO is
            # empty now: a burst handed over meanwhile waits for it, so the
            # urgent `_first_batch` never takes more before these are handled
            # (it did, and a slow node's queue grew without end).
            self._batch_queued = True
            out.append(self._next_batch)
        return out

    def _pages_of(self, samples: Sequence[zenoh.Sample]) -> List[Page]:
        """The pages of one subscription's ``samples``, in order; wake-ups and bad samples left out.

        The senders' counts are followed for the whole batch at once
        (`SequenceFollower.taken_all`): a burst from one sender costs one
        comparison a page.
        """
        pages: List[Page] = []
        counted: List[Tuple[str, bytes]] = []
        cut = len(self.prefix)
        published, arrived = self._published_keys, self._arrived
        for sample in samples:
            attachment = sample.attachment
            count = None if attachment is None else attachment.to_bytes()
            if count == WAKE:  # only woke the node's thread (IdleReader)
                continue
            key = str(sample.key_expr)[cut:]
            try:
                page = page_from_sample(key, sample.payload.to_bytes())
            except WireFormatError as error:
                self._bad_sample(self.prefix + key, error)
                continue
            if count is not None:
                counted.append((key, count))
            if key in published:  # never sent back out (the echo guard)
                if len(arrived) >= _MAX_ECHO_GUARD:  # their tasks were dropped: forget them
                    arrived.clear()
                arrived[id(page)] = page
            pages.append(page)
        if counted:
            self._follow_sequences(counted)
        self.received += len(pages)
        return pages

    def _follow_sequences(self, counted: Sequence[Tuple[str, bytes]]) -> None:
        lost = self._sequences.taken_all(counted)
        if lost:
            self.lost_report.dropped(lost)
        elif self.lost_report.dropping and time.monotonic() - self.lost_report.last_drop > 1.0:
            self.lost_report.recovered()

    def _bad_sample(self, key_expr: str, error: WireFormatError) -> None:
        self.bad_samples += 1
        if self._bad_reported < 5:
            self._bad_reported += 1
            self.warn(
                "Bad sample under %s: %s (dropped; the node keeps running; see docs/comms.md, "
                "Zenoh)%s",
                key_expr,
                error,
                "" if self._bad_reported < 5 else ". Further bad samples are only counted",
            )

    def _peer_changed(self, kind: Any, key_expr: str) -> List[Task]:
        """A node of the system appeared or went: note it, and the event to announce it."""
        parts = key_expr[len(self.prefix) :].split("/")
        if len(parts) != 3 or self.session is None:
            return []
        _, role, zid = parts
        if zid == str(self.session.zid()):
            return []
        if kind == self.zenoh.SampleKind.PUT:
            self.peers[zid] = role
            self.info("Node %r joined system %r over Zenoh", role, self.spec.system)
            return [tasks.event(COMMS_CONNECTED, [self.name, role])]
        self.peers.pop(zid, None)
        self.info(
            "Node %r left system %r (it stopped, or nothing was heard from it for %g s)",
            role,
            self.spec.system,
            self.spec.dead_after_s,
        )
        return [tasks.event(COMMS_DISCONNECTED, [self.name, role])]

    # -- counters ---------------------------------------------------------------
    def stats(self) -> Dict[str, Any]:
        """The counters: published, received, lost, dropped, bad samples, peers.

        Example::

            comms.stats()   # {'published': 120, 'received': 80, 'lost': 0, ...}
        """
        return {
            "system": self.spec.system,
            "published": self.published,
            "received": self.received,
            "lost": self.lost_report.total,
            "dropped": self.queue_report.total,
            "bad_samples": self.bad_samples,
            "peers": sorted(self.peers.values()),
            "unmet_endpoints": self.unmet_endpoints,
        }

    def stats_text(self) -> str:
        """`stats` as one line for people (the console's ``stats``, the profiler's dump).

        Example::

            print(comms.stats_text())
            # Zenoh system 'team7': published 120, received 80, lost 0, ... peers ['urov']
        """
        s = self.stats()
        return (
            f"Zenoh system {s['system']!r}: published {s['published']:,}, received "
            f"{s['received']:,}, lost {s['lost']:,}, dropped {s['dropped']:,}, bad samples "
            f"{s['bad_samples']:,}, peers {s['peers']}"
        )
