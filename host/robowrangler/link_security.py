"""Link security on the host side: the key file, signing what the host sends, checking what it receives.

Over WiFi (UDP) every frame is signed (SipHash-2-4, 128-bit key, 64-bit tag; the codec is generated from
the protocol spec) for the device's current session with a counter that only grows:

- session: the device's boot counter, learnt from SESSION_INFO (the answer to HELLO) and from every signed
  device frame; a device reboot shows up as a higher session and is followed at once. Frames of an older
  session are replays and are dropped.
- host counter: microseconds since the Unix epoch, bumped by one when two frames fall in the same
  microsecond, so it keeps growing across host restarts without any state on disk.
- device counter: the device numbers its signed frames within a session; a repeat or an older number is a
  replay and is dropped.

The key never leaves this process except into the device over USB serial (provisioning); it is not
logged, printed or recorded. Key files hold 32 hex digits and are created with mode 0600.
"""

from __future__ import annotations

import os
import secrets
import stat
import threading
import time
from dataclasses import dataclass
from pathlib import Path

from robowrangler.errors import RoboWranglerError
from robowrangler.protocol import generated as gen

KEY_FILE_ENV_VAR = "ROBOWRANGLER_KEY_FILE"
DEFAULT_KEY_FILE = Path("~/.config/robowrangler/link.key")


class KeyFileError(RoboWranglerError):
    """A key file is missing, unreadable, malformed or readable by others; the message says which and how to fix."""


def generate_key() -> bytes:
    """A fresh random 128-bit key (the OS's CSPRNG)."""
    return secrets.token_bytes(gen.KEY_LEN)


def default_key_path(environ: os._Environ | dict | None = None) -> Path:
    env = os.environ if environ is None else environ
    return Path(env.get(KEY_FILE_ENV_VAR) or DEFAULT_KEY_FILE).expanduser()


def write_key_file(path: str | Path, key: bytes, *, force: bool = False) -> Path:
    """Write key as 32 hex digits to path, mode 0600 (created so, never world-readable for an instant)."""
    path = Path(path).expanduser()
    if len(key) != gen.KEY_LEN:
        raise KeyFileError(f"key: expected {gen.KEY_LEN} bytes, got {len(key)}")
    if path.exists() and not force:
        raise KeyFileError(f"{path} exists; keep it (the device is provisioned with it) or pass --force to replace it")
    path.parent.mkdir(parents=True, exist_ok=True, mode=0o700)
    tmp = path.with_name(path.name + ".tmp")
    fd = os.open(tmp, os.O_WRONLY | os.O_CREAT | os.O_TRUNC, 0o600)
    try:
        os.write(fd, (key.hex() + "\n").encode("ascii"))
    finally:
        os.close(fd)
    os.replace(tmp, path)
    return path


def read_key_file(path: str | Path) -> bytes:
    """The key in path. KeyFileError if missing, malformed, or readable by group/others."""
    path = Path(path).expanduser()
    try:
        st = path.stat()
        text = path.read_text(encoding="ascii").strip()
    except FileNotFoundError:
        raise KeyFileError(f"no key file at {path}: create one with `wrangler keygen --out {path}` and provision "
                           "the device with it over USB (`wrangler provision --port ...`)") from None
    except (OSError, UnicodeDecodeError) as exc:
        raise KeyFileError(f"cannot read the key file {path}: {exc}") from None
    if st.st_mode & (stat.S_IRWXG | stat.S_IRWXO):
        raise KeyFileError(f"{path} is accessible to other users (mode {stat.S_IMODE(st.st_mode):o}); "
                           f"run `chmod 600 {path}`")
    try:
        key = bytes.fromhex(text)
    except ValueError:
        key = b""
    if len(key) != gen.KEY_LEN:
        raise KeyFileError(f"{path}: expected {2 * gen.KEY_LEN} hex digits, found something else")
    return key


@dataclass
class SecurityStats:
    """Frames the host dropped: unsigned or wrongly signed (auth_failed), old session or counter (replayed)."""

    auth_failed: int = 0
    replayed: int = 0
    session_changes: int = 0


class LinkSecurity:
    """Signs outgoing frames and checks incoming ones for one device. Thread-safe.

    key None: a trusted link (USB serial): frames go unsigned and unsigned frames are accepted.
    """

    def __init__(self, key: bytes | None) -> None:
        if key is not None and (not isinstance(key, (bytes, bytearray)) or len(key) != gen.KEY_LEN):
            raise KeyFileError(f"key: expected {gen.KEY_LEN} bytes")
        self._key = bytes(key) if key is not None else None
        self._lock = threading.Lock()
        self._last_counter = 0
        self.session_id: int | None = None
        self._device_counter = -1
        self.stats = SecurityStats()

    @property
    def signing(self) -> bool:
        return self._key is not None

    def _next_counter(self) -> int:
        with self._lock:
            self._last_counter = max(self._last_counter + 1, time.time_ns() // 1000)
            return self._last_counter

    def encode(self, message: gen.Message, seq: int) -> bytes:
        """The frame to send now (a retransmission calls this again: same seq and payload, fresh counter)."""
        if self._key is None or message.KIND == gen.MsgKind.HELLO:
            return gen.encode_frame(message, seq)
        return gen.encode_frame(message, seq, key=self._key, session_id=self.session_id or 0,
                                counter=self._next_counter())

    def accept(self, frame: gen.Frame) -> bool:
        """True if a received frame may be used; False (counted) if it must be dropped."""
        if self._key is None:
            return True
        if not frame.signed or not gen.tag_valid(frame, self._key):
            with self._lock:
                self.stats.auth_failed += 1
            return False
        with self._lock:
            if self.session_id is None or frame.session_id > self.session_id:
                if self.session_id is not None:
                    self.stats.session_changes += 1  # the device rebooted
                self.session_id = frame.session_id
                self._device_counter = -1
            if frame.session_id < self.session_id or frame.counter <= self._device_counter:
                self.stats.replayed += 1
                return False
            self._device_counter = frame.counter
            return True

    def tag_valid(self, frame: gen.Frame) -> bool:
        """Only the tag (no replay bookkeeping): for telling a wrong key from a replay."""
        return self._key is not None and frame.signed and gen.tag_valid(frame, self._key)
