"""Who may link to a node: its system's name, and its secret (docs/comms.md, "Who may connect").

Both are judged in the hello that starts every link (docs/wire-format.md,
3.1 and 3.5). The system name (``system=``, default: the script's folder)
stops accidents: a node of another team reached by a typo is refused. The
secret (``SNR_SECRET``, ``secret=``, or ``python -m snr secret new``) stops
malice: each side proves it knows it with an HMAC-SHA256 over the other
side's fresh nonce, so the secret never crosses the wire and a recorded
hello cannot be replayed.

Example::

    handshake = Handshake(role="urov", side="server", system="team7", secret=b"s3cret")
    link_first_frame = handshake.hello_frame(beat_s=1.0)
    proof_frame = handshake.on_hello(peer_hello)   # raises Refused if it must be refused
    handshake.on_proof(peer_proof)                 # handshake.done is then True
"""

from __future__ import annotations

import hashlib
import hmac
import os
import secrets
import sys
from pathlib import Path
from typing import Any, Optional

from snr.prelude import ConfigError
from snr.std_mods.codec import Hello, Proof, encode_hello, encode_proof

__all__ = [
    "FROM_ENVIRONMENT",
    "SCRIPT_FOLDER",
    "SECRET_ENV_VAR",
    "Handshake",
    "Refused",
    "derived_word",
    "find_secret",
    "new_secret",
    "proof_mac",
    "resolve_system",
    "secret_file",
]

SCRIPT_FOLDER = "<the script's folder>"
"""The default ``system=`` of comms factories: the config's ``name``, else the script's folder."""

FROM_ENVIRONMENT = "<SNR_SECRET or the secret file>"
"""The default ``secret=`` of comms factories: ``$SNR_SECRET``, else the secret file, else none."""

SECRET_ENV_VAR = "SNR_SECRET"
"""The environment variable that holds a node's secret."""

_NONCE_BYTES = 32  # sent as 64 lowercase hex digits
_OTHER_SIDE = {"client": "server", "server": "client", "pipe": "pipe"}


def resolve_system(system: Optional[str], config: Any, where: str) -> Optional[str]:
    """The system a comms component names: ``system`` as given, or by default (`SCRIPT_FOLDER`)
    the config's ``name``, else the folder of the script that runs, else the current folder's.

    Raises:
        ConfigError: ``system`` is not a non-empty string or None.

    Example::

        resolve_system(SCRIPT_FOLDER, config, "SocketsPair")   # 'team7' for ~/team7/robot.py
        resolve_system(None, config, "SocketsPair")            # None: names none
    """
    if system == SCRIPT_FOLDER:
        name = getattr(config, "name", None)
        if isinstance(name, str) and name:
            return name
        script = sys.argv[0] if sys.argv else ""
        folder = Path(script).resolve().parent if os.path.isfile(script) else Path.cwd()
        return folder.name or "snr"
    if system is None or (isinstance(system, str) and system):
        return system
    raise ConfigError(
        f"{where} got system={system!r}. Give one word naming your robot's system, e.g. "
        '"team7" (every node of it the same), or None to let in nodes that name no system.'
    )


def secret_file() -> Path:
    """Where ``python -m snr secret new`` writes the secret (``$SNR_SECRET_FILE`` changes it).

    Example::

        secret_file()   # PosixPath('/home/student/.config/snr/secret')
    """
    named = os.environ.get("SNR_SECRET_FILE")
    if named:
        return Path(named).expanduser()
    config_home = os.environ.get("XDG_CONFIG_HOME") or str(Path.home() / ".config")
    return Path(config_home) / "snr" / "secret"


def find_secret(secret: Optional[str], where: str) -> Optional[bytes]:
    """The secret a node proves it knows, as bytes, or None for no authentication.

    ``secret`` as given, or by default (`FROM_ENVIRONMENT`) ``$SNR_SECRET``,
    else the first line of `secret_file`, else None; spaces around it dropped.

    Raises:
        ConfigError: the secret is empty, or the secret file cannot be read.

    Example::

        find_secret("correct horse battery", "SocketsPair")   # b'correct horse battery'
    """
    if secret is None:
        return None
    if secret != FROM_ENVIRONMENT:
        if not isinstance(secret, str) or not secret.strip():
            raise ConfigError(
                f"{where} got secret={secret!r:.20}; give a non-empty string (every node of "
                "the system the same), or secret=None for no authentication."
            )
        return secret.strip().encode("utf-8")
    text, source = os.environ.get(SECRET_ENV_VAR), f"${SECRET_ENV_VAR}"
    if text is None:
        path = secret_file()
        if not path.is_file():
            return None
        try:
            lines = path.read_text(encoding="utf-8").strip().splitlines()
        except (OSError, UnicodeDecodeError) as error:
            raise ConfigError(
                f"{where} cannot read its secret from {path}: {error}. Make a new one "
                "with `python -m snr secret new`, or delete the file to run without one."
            ) from None
        text, source = (lines[0] if lines else ""), str(path)
    if not text.strip():
        raise ConfigError(
            f"{where}: the secret in {source} is empty. Make one with "
            "`python -m snr secret new`, or unset it to run without one."
        )
    return text.strip().encode("utf-8")


def derived_word(secret: bytes, purpose: str) -> str:
    """A word made from the secret for one ``purpose`` that does not give the secret away.

    HMAC-SHA256 keyed with the secret over ``snr-<purpose>``, in hex: the
    console's token, Zenoh's password.

    Example::

        derived_word(b"s3cret", "console-token")   # '9a1e...' (64 hex digits)
    """
    return hmac.new(secret, f"snr-{purpose}".encode("ascii"), hashlib.sha256).hexdigest()


def new_secret() -> str:
    """A fresh random secret: 32 random bytes as 43 URL-safe characters.

    Example::

        new_secret()   # 'mZ3k...'
    """
    return secrets.token_urlsafe(32)


def proof_mac(secret: bytes, side: str, prover_nonce: str, verifier_nonce: str) -> str:
    """The proof that the ``side`` (``"client"``, ``"server"`` or ``"pipe"``) knows the secret.

    HMAC-SHA256 over ``snr-proof <side> <prover's nonce> <verifier's nonce>``
    (docs/wire-format.md, 3.5); the side keeps a server from answering its own challenge.

    Example::

        proof_mac(b"s3cret", "client", "ab" * 32, "cd" * 32)   # '5f0c...'
    """
    text = f"snr-proof {side} {prover_nonce} {verifier_nonce}".encode("ascii")
    return hmac.new(secret, text, hashlib.sha256).hexdigest()


class Refused(Exception):
    """The peer may not link to this node; ``kind`` is ``"system"``, ``"secret"`` or ``"order"``.

    Example::

        raise Refused("system", "it belongs to system 'team3', this node to 'team7'")
    """

    def __init__(self, kind: str, reason: str) -> None:
        super().__init__(reason)
        self.kind = kind
        self.reason = reason


class Handshake:
    """One link's hello and proofs: judges the peer before any page may pass.

    ``needed`` is False with no system and no secret: a version 1 hello, pages at once.

    Example::

        shake = Handshake("urov", "server", system="team7", secret=None)
        shake.on_hello(Hello("topside", system="team7"))   # None: nothing to send
        shake.done                                          # True
    """

    def __init__(self, role: str, side: str, system: Optional[str], secret: Optional[bytes]):
        self.role = role
        self.side = side
        self.system = system
        self.secret = secret
        self.nonce = None if secret is None else secrets.token_hex(_NONCE_BYTES)
        self.needed = system is not None or secret is not None
        self.peer_nonce: Optional[str] = None
        self.done = not self.needed

    def hello_frame(self, beat_s: Optional[float]) -> bytes:
        """The hello this node sends first: version 2 with its system and nonce if it has them."""
        return encode_hello(self.role, beat_s, bye=True, system=self.system, nonce=self.nonce)

    def on_hello(self, hello: Hello) -> Optional[bytes]:
        """Judge the peer's hello; the proof frame to send back, if any.

        Raises:
            Refused: another system, no system while this node names one, a
                secret on one side only, or this node's own nonce sent back.
        """
        # A client trusts the address it was given to a server that names no
        # system; a server does not trust every program that reaches its port.
        if self.system is not None and hello.system != self.system:
            if hello.system is not None:
                raise Refused(
                    "system",
                    f"it belongs to system {hello.system!r:.60}, this node to system "
                    f"{self.system!r} (a wrong address? if it is one "
                    "of yours, give both sides the same system=...; see docs/comms.md)",
                )
            if self.side != "client":
                raise Refused(
                    "system",
                    "it names no system (an older SNR, or a program that sends a version 1 "
                    f"hello) and this node belongs to system {self.system!r} "
                    "(to let such nodes in, give this node system=None; see docs/comms.md)",
                )
        if self.secret is None or self.nonce is None:
            if hello.nonce is not None:
                raise Refused(
                    "secret",
                    "it asks for a secret and this node has none: give this node the same "
                    f"secret (${SECRET_ENV_VAR}, secret=..., or `python -m snr secret new` "
                    "and copy the file; see docs/comms.md)",
                )
            self.done = True
            return None
        if hello.nonce is None:
            raise Refused(
                "secret",
                "it has no secret and this node has one: it cannot prove it belongs here "
                f"(give it the same secret: ${SECRET_ENV_VAR} or the secret file; see "
                "docs/comms.md)",
            )
        if hello.nonce == self.nonce:
            raise Refused("secret", "it sent this node's own challenge back (a replay)")
        self.peer_nonce = hello.nonce
        return encode_proof(proof_mac(self.secret, self.side, self.nonce, hello.nonce))

    def on_proof(self, proof: Proof) -> None:
        """Check the peer's proof; ``done`` is True after.

        Raises:
            Refused: a proof before a hello, or one made with another secret.
        """
        if self.secret is None or self.peer_nonce is None or self.nonce is None:
            raise Refused("order", "it sent a proof before its hello, or one nobody asked for")
        expected = proof_mac(self.secret, _OTHER_SIDE[self.side], self.peer_nonce, self.nonce)
        if not hmac.compare_digest(expected, proof.mac):
            raise Refused(
                "secret",
                "its proof does not match this node's secret: the two secrets differ "
                f"(give both the same one: ${SECRET_ENV_VAR} or the secret file; see "
                "docs/comms.md)",
            )
        self.done = True
