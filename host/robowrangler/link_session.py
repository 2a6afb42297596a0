"""One signed link session, host side: HELLO -> SESSION_INFO, signing, counters and freshness.

The rules are the device's (firmware/core/rw_core_commands.c `authentic`, protocol/docs/security.md); every
host-side peer of the protocol uses this class: the client, the SIL's scripted host, the test transports.

Device -> host (`LinkSession.check`), the rule a host applies to the device's signed frames:
  - the tag must verify with the key (else BAD_TAG);
  - the SESSION_INFO that answers this host's current HELLO (its nonce echoed, signed) sets the session,
    whatever its id: the nonce proves it fresh. This is how a host follows a re-provisioned device, whose new
    epoch may give a lower session id (ANSWERED);
  - before that answer no frame can be judged fresh (STALE);
  - a frame of a newer session (a larger id: within one provisioning session ids only grow) means the device
    rebooted: it is taken and the host signs for that session from now on (FOLLOWED);
  - within the session a frame counts only if its counter is above the last one taken (ACCEPTED), else it
    is a replay or a copy reordered behind a later frame (STALE); a frame of an older session is STALE.
Host -> device (`device_takes`), the rule the device applies to the host's frames: the session must be
exactly the device's current one and the counter above the last the device accepted. The difference is
deliberate: the device owns the session, the host follows it.

Counters: the host's counter only grows. With `clock_us` (the client: microseconds since the Unix epoch) the
counter is max(last + 1, clock_us()), so it keeps growing across host processes with no state on disk; without
it (scripted hosts) it counts 1, 2, 3, ... so that runs are reproducible.
"""

from __future__ import annotations

import enum
import secrets
import threading
from collections.abc import Callable

from robowrangler.errors import InvalidArgument, RoboWranglerError
from robowrangler.protocol import generated as gen


class NoSession(RoboWranglerError):
    """A signed frame was asked for before the device's session is known (no SESSION_INFO answered the HELLO)."""


class Verdict(enum.Enum):
    """What a host does with one frame from the device (LinkSession.check)."""

    ACCEPTED = "accepted"  # fresh, of the current session
    FOLLOWED = "followed"  # fresh, of a newer session (the device rebooted): the host now signs for it
    ANSWERED = "answered"  # the SESSION_INFO answering this host's HELLO: the host signs for its session
    BAD_TAG = "bad_tag"    # unsigned, or not signed with this key: dropped, counted as an authentication failure
    STALE = "stale"        # an older session, a counter not above the last, or no session yet: dropped as a replay

    @property
    def taken(self) -> bool:
        return self in (Verdict.ACCEPTED, Verdict.FOLLOWED, Verdict.ANSWERED)


def device_takes(frame: gen.Frame, *, session_id: int | None, last_counter: int) -> bool:
    """The device's freshness rule for a host frame whose tag verified: its session exactly, a counter above the last."""
    return session_id is not None and frame.session_id == session_id and frame.counter > last_counter


class LinkSession:
    """The host's end of one signed link. Thread-safe (one lock guards the counters and the session).

    Args:
        key: the 16-byte link key.
        clock_us: where counters start from (see the module text); None: a plain count from 1.
        random_nonce: draws a HELLO nonce (32 bits) when hello() is not given one.
        session_id: a session known without a HELLO (a test harness that boots the core itself); None: learn
            it from the SESSION_INFO that answers hello().
    """

    def __init__(self, key: bytes, *, clock_us: Callable[[], int] | None = None,
                 random_nonce: Callable[[], int] = lambda: secrets.randbelow(1 << 32),
                 session_id: int | None = None) -> None:
        if not isinstance(key, (bytes, bytearray)) or len(key) != gen.KEY_LEN:
            raise InvalidArgument("key", f"{gen.KEY_LEN} bytes (a 128-bit link key)",
                                  f"{type(key).__name__} of length {len(key) if hasattr(key, '__len__') else '?'}")
        self.key = bytes(key)
        self._clock_us = clock_us
        self._random_nonce = random_nonce
        self._lock = threading.Lock()
        if session_id is not None and (isinstance(session_id, bool) or not isinstance(session_id, int)
                                       or not 0 <= session_id < 1 << 32):
            raise InvalidArgument("session_id", "None or an integer in [0, 2^32)", session_id)
        self._session_id: int | None = session_id  # the session this host signs for (= the newest device session taken)
        self._device_counter = 0  # the counter of the newest device frame taken in that session
        self._counter = 0  # the counter of the last frame this host signed
        self._nonce: int | None = None

    # ------------------------------------------------------------------ state
    @property
    def session_id(self) -> int | None:
        """The device session this host signs for; None until a SESSION_INFO answered the HELLO."""
        return self._session_id

    @property
    def counter(self) -> int:
        """The counter of the last frame this host signed (0: none yet)."""
        return self._counter

    @property
    def nonce(self) -> int | None:
        """The nonce of the current HELLO (None: no HELLO yet)."""
        return self._nonce

    # ------------------------------------------------------------------ host -> device
    def hello(self, nonce: int | None = None) -> gen.Hello:
        """A new HELLO (unsigned); its nonce is the one a SESSION_INFO must echo from now on."""
        if nonce is None:
            nonce = self._random_nonce()
        if isinstance(nonce, bool) or not isinstance(nonce, int) or not 0 <= nonce < 1 << 32:
            raise InvalidArgument("nonce", "an integer in [0, 2^32)", nonce)
        with self._lock:
            self._nonce = nonce
        return gen.Hello(nonce)

    def next_counter(self) -> int:
        """Take the next counter: above every one before (and at least clock_us() when there is a clock)."""
        with self._lock:
            return self._take_counter()

    def _take_counter(self) -> int:
        floor = self._clock_us() if self._clock_us is not None else 0
        self._counter = max(self._counter + 1, int(floor))
        return self._counter

    def sign(self, message: gen.Message, seq: int) -> bytes:
        """The frame of message with seq, signed for the session with the next counter (HELLO: unsigned).

        Raises NoSession before the session is known. Send frames in the order they were signed: the device
        drops a counter that is not above the last it accepted.
        """
        if message.KIND == gen.MsgKind.HELLO:
            return gen.encode_frame(message, seq)
        with self._lock:
            if self._session_id is None:
                raise NoSession(f"{message.NAME}: no device session yet; say HELLO and wait for its SESSION_INFO "
                                "before sending signed frames")
            return gen.encode_frame(message, seq, key=self.key, session_id=self._session_id,
                                    counter=self._take_counter())

    # ------------------------------------------------------------------ device -> host
    def verified(self, frame: gen.Frame) -> bool:
        """True if the frame is signed with this session's key."""
        return gen.tag_valid(frame, self.key)

    def check(self, frame: gen.Frame, message: gen.Message) -> Verdict:
        """Judge one frame from the device (see the module text) and, when taken, move the session on."""
        if not self.verified(frame):
            return Verdict.BAD_TAG
        with self._lock:
            if (isinstance(message, gen.SessionInfo) and self._nonce is not None and message.host_nonce == self._nonce
                    and frame.session_id == message.session_id
                    and not (frame.session_id == self._session_id and frame.counter <= self._device_counter)):
                self._session_id, self._device_counter = frame.session_id, frame.counter
                return Verdict.ANSWERED
            if self._session_id is None:
                return Verdict.STALE
            if frame.session_id > self._session_id:
                self._session_id, self._device_counter = frame.session_id, frame.counter
                return Verdict.FOLLOWED
            if frame.session_id == self._session_id and frame.counter > self._device_counter:
                self._device_counter = frame.counter
                return Verdict.ACCEPTED
            return Verdict.STALE


__all__ = ["LinkSession", "NoSession", "Verdict", "device_takes"]
