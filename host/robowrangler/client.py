"""Client: commands with ACK/NACK and retries, heartbeats, telemetry and events, over any transport.

    with Client("udp://127.0.0.1:14550") as rw:
        rw.arm()
        rw.spin(5.0)
        rw.wait_for_state(State.AIRBORNE, timeout_s=3.0)
        rw.spindown()

Threads: a receiver thread decodes every frame and hands ACK/NACK to the waiting command by
(msg_id, seq), PARAM_VALUE by parameter id, TELEMETRY to `latest_telemetry` and to every open
`telemetry()` iterator, EVENT to `events`. Frames it cannot decode are counted in `stats`, never
raised. A heartbeat thread sends HEARTBEAT at heartbeat_hz while connected (the device spins the
rope down after heartbeat_timeout_s of silence). Heartbeats are also kept on the device's clock: when a
TELEMETRY sample says the device has heard nothing from the host for 1 / heartbeat_hz of its own time, the receiver
sends one at once (at most one per such period of device time). So a device whose clock runs faster than
the host's (a SIL paced above real time) or a heartbeat thread starved on a busy machine does not make the
device spin the rope down while the host is otherwise keeping up.

Retries: a command is retransmitted with the SAME seq and payload after each ack_timeout_s without an
answer (the device answers a retransmission again but never executes it twice), at most `retries`
times, then LinkTimeout; a NACK saying the frame arrived damaged is answered by an immediate
retransmission. A new command always gets a new seq.

Signed links (protocol v2, key=...): connect() asks for the session (HELLO -> SESSION_INFO), then every
frame carries the session id, a counter that only grows (also across processes: it follows the wall
clock in microseconds) and a SipHash-2-4 tag; a retransmission keeps seq and checksum but gets a fresh
counter. Provisioning (key, WiFi) goes over serial:// links only.
"""

from __future__ import annotations

import collections
import queue
import secrets
import struct
import threading
import time
from collections.abc import Callable, Iterable, Iterator
from dataclasses import dataclass, field, replace

from robowrangler import units
from robowrangler.errors import (AuthenticationError, CommandRefused, InvalidArgument, LinkTimeout, NotConnected,
                                 StateTimeout, UnknownParameter)
from robowrangler.link_session import LinkSession, Verdict
from robowrangler.protocol import generated as gen
from robowrangler.protocol.generated import FrameError, MsgId, NackReason, PARAMS, PARAMS_BY_NAME, ParamSpec, State
from robowrangler.telemetry import DeviceEvent, ProvisionStatus, TelemetrySample
from robowrangler.provisioning import staging_messages
from robowrangler.session_epoch import new_session_epoch
from robowrangler.transport import DEFAULT_URL, Transport, open_transport, parse_url

RECV_POLL_S = 0.05  # receiver thread wakes this often to notice close()
TELEMETRY_QUEUE_LEN = 4096  # per telemetry() iterator; the oldest sample is dropped when full (~80 s at 50 Hz)
EVENT_HISTORY_LEN = 10000
NOT_READY_RETRY_S = 0.05  # pause between ARM attempts while the device reports NOT_READY
NOT_READY_WALL_FACTOR = 4.0  # ARM's wall-time bound, in multiples of its timeout on the device's clock
KEYLESS_POLL_S = 0.02  # a keyless connect looks this often whether the device's SESSION_INFO says it signs
_CLOSED = object()
# NACK reasons that mean "the frame arrived damaged": our frames are well-formed, so the link corrupted
# it (or, if it keeps happening, host and firmware disagree on the protocol). UNKNOWN_MESSAGE is not here:
# a corrupted id is reported under that corrupted id and matches no waiter, so an UNKNOWN_MESSAGE naming
# our (msg_id, seq) means the firmware really does not know the command.
TRANSIT_NACK_REASONS = frozenset({NackReason.BAD_MAGIC, NackReason.BAD_VERSION, NackReason.TRUNCATED,
                                  NackReason.BAD_LENGTH, NackReason.OVERSIZE, NackReason.BAD_CHECKSUM,
                                  NackReason.UNSUPPORTED_FLAGS})


@dataclass
class ClientStats:
    """Link counters since connect(); a snapshot is returned by Client.stats."""

    frames_sent: int = 0
    heartbeats_sent: int = 0
    device_clock_heartbeats: int = 0  # of those, sent because telemetry said the device heard none for a period
    commands_sent: int = 0
    retransmissions: int = 0
    send_errors: int = 0
    frames_received: int = 0
    decode_errors: int = 0
    decode_errors_by_reason: dict[str, int] = field(default_factory=dict)
    framing_errors: int = 0
    recv_errors: int = 0
    acks: int = 0
    nacks: int = 0
    transit_nacks: int = 0
    late_replies: int = 0
    param_values: int = 0
    stale_param_values: int = 0
    telemetry_received: int = 0
    telemetry_dropped: int = 0
    events_received: int = 0
    events_lost: int = 0
    burst_frames: int = 0  # BURST_DATA frames received (a recorder on the transport keeps their content)
    unexpected_messages: int = 0
    auth_failures: int = 0
    replayed: int = 0  # signed device frames dropped as stale (an older session or a counter already seen)
    session_changes: int = 0


class _Waiter:
    """One awaited reply. For PARAM_VALUE: `armed` once the ACK of the request arrived (PARAM_VALUE carries
    no seq: a PARAM_GET takes only values received after its ACK), `expect_bits` the float32 a PARAM_SET
    wrote (a PARAM_SET takes only that value)."""

    __slots__ = ("event", "reply", "param_waiter", "armed", "expect_bits")

    def __init__(self, *, expect_bits: bytes | None = None) -> None:
        self.event = threading.Event()
        self.reply: gen.Message | None = None
        self.param_waiter: _Waiter | None = None
        self.armed = False
        self.expect_bits = expect_bits


def param_spec(name: object) -> ParamSpec:
    """The protocol's entry for a parameter name; UnknownParameter if there is none."""
    if not isinstance(name, str) or name not in PARAMS_BY_NAME:
        raise UnknownParameter(name)
    return PARAMS_BY_NAME[name]


def _check_positive(argument: str, value: object, *, allow_zero: bool = False) -> float:
    x = units.check_real(argument, value, allow_inf=False)
    if x < 0 or (x == 0 and not allow_zero):
        raise InvalidArgument(argument, "a number >= 0" if allow_zero else "a number > 0", value)
    return x


class Client:
    """A connection to one RoboWrangler device (board or SIL), identified by a link URL.

    Args:
        url: udp://HOST:PORT or serial://PORT?baud=N (see robowrangler.transport).
        ack_timeout_s: wait for ACK/NACK per transmission [s].
        retries: retransmissions (same seq) after the first send before LinkTimeout.
        heartbeat_hz: HEARTBEAT rate while connected [Hz].
        connect_timeout_s: wait for the first TELEMETRY in connect(); also the longest telemetry gap
            telemetry() and wait_for_state() accept before LinkTimeout [s].
        first_seq: sequence number of the first frame (0..65535); None draws a random one so that a
            new process never repeats the bytes of a previous one inside the device's duplicate window.
        transport: an already open Transport to use instead of opening `url` (tests, custom links).
        key: the 16-byte link key. Given, connect() asks the device for its session (HELLO ->
            SESSION_INFO, whose tag must verify) and every frame is signed (session id, a counter that
            only grows, SipHash-2-4 tag); signed frames from the device with a wrong tag are dropped and
            counted (stats.auth_failures). None: unsigned frames (USB serial, a device without a key).
    """

    def __init__(self, url: str = DEFAULT_URL, *, ack_timeout_s: float = 0.2, retries: int = 5,
                 heartbeat_hz: float = 10.0, connect_timeout_s: float = 3.0, first_seq: int | None = None,
                 transport: Transport | None = None, key: bytes | None = None) -> None:
        if transport is None:
            parse_url(url)  # raises InvalidArgument before any socket is opened
        self.url = url if transport is None else getattr(transport, "url", url)
        self.ack_timeout_s = _check_positive("ack_timeout_s", ack_timeout_s)
        if isinstance(retries, bool) or not isinstance(retries, int) or retries < 0:
            raise InvalidArgument("retries", "an integer >= 0", retries)
        self.retries = retries
        self.heartbeat_hz = _check_positive("heartbeat_hz", heartbeat_hz)
        self.connect_timeout_s = _check_positive("connect_timeout_s", connect_timeout_s)
        if first_seq is None:
            first_seq = secrets.randbelow(0x10000)
        if isinstance(first_seq, bool) or not isinstance(first_seq, int) or not 0 <= first_seq <= 0xFFFF:
            raise InvalidArgument("first_seq", "an integer in [0, 65535] or None", first_seq)
        self._next_seq_value = first_seq
        if key is not None and (not isinstance(key, (bytes, bytearray)) or len(key) != gen.KEY_LEN):
            raise InvalidArgument("key", f"{gen.KEY_LEN} bytes (a 128-bit link key)",
                                  f"{type(key).__name__} of length {len(key) if hasattr(key, '__len__') else '?'}")
        self._key = None if key is None else bytes(key)
        # the signed session (HELLO, counters, freshness): one set of rules for every host (link_session.py)
        self._link: LinkSession | None = None  # made by connect() when there is a key
        self._hello_nonce: int | None = None
        self._session_info: gen.Message | None = None
        self._session_info_signed = False
        self._session_event = threading.Event()
        self._transport = transport
        self._lock = threading.Lock()  # guards waiters, subscribers, stats, events
        self._send_lock = threading.Lock()  # seq allocation + send keep frames in seq order
        self._waiters: dict[tuple[int, int], _Waiter] = {}
        self._param_waiters: dict[int, list[_Waiter]] = collections.defaultdict(list)
        self._status_waiters: list[_Waiter] = []
        self._subscribers: list[queue.Queue] = []
        self._events: collections.deque[DeviceEvent] = collections.deque(maxlen=EVENT_HISTORY_LEN)
        self._last_event_seq: int | None = None
        self._latest: TelemetrySample | None = None
        self._first_telemetry = threading.Event()
        self._device_heartbeat_s: float | None = None  # device time of the last heartbeat sent on its clock
        self._stats = ClientStats()
        self._stop = threading.Event()
        self._threads: list[threading.Thread] = []
        self._connected = False
        self._heartbeat_idle: Callable[[], bool] | None = None

    # ----------------------------------------------------------------- lifecycle

    def connect(self) -> Client:
        """Open the link, start the receiver and heartbeat threads, wait for the first TELEMETRY.

        Raises LinkTimeout (naming the URL) if none arrives within connect_timeout_s; the link is
        closed again in that case. Returns self.
        """
        if self._connected:
            return self
        if self._transport is None:
            self._transport = open_transport(self.url)
        self._stop.clear()
        self._first_telemetry.clear()
        self._session_event.clear()
        self._session_info = None
        self._session_info_signed = False
        self._device_heartbeat_s = None
        if self._key is not None:  # a new connection learns the session afresh (the counter keeps growing)
            self._link = LinkSession(self._key, clock_us=lambda: time.time_ns() // 1000)
        self._connected = True
        receiver = threading.Thread(target=self._receive_loop, name="robowrangler-rx", daemon=True)
        heartbeat = threading.Thread(target=self._heartbeat_loop, name="robowrangler-hb", daemon=True)
        self._threads = [receiver, heartbeat]
        receiver.start()
        try:
            self._hello()  # unsigned and harmless: tells a keyless host why a keyed device stays silent
            if self._key is not None:
                self._establish_session()
            heartbeat.start()
            if not self._wait_first_telemetry():
                info = self._session_info
                if self._key is None and info is not None and info.key_set:  # silent to a keyless host all along
                    raise self._needs_key_error()
                raise LinkTimeout(f"no TELEMETRY from {self.url} within {self.connect_timeout_s:g} s: is the device "
                                  "(or the SIL firmware) running and listening at that address?",
                                  url=self.url, waited_s=self.connect_timeout_s)
        except BaseException:
            self.close()
            raise
        return self

    def _wait_first_telemetry(self) -> bool:
        """Wait up to connect_timeout_s for the first TELEMETRY; without a key, stop as soon as the device's
        SESSION_INFO comes signed with a key set (it will stay silent to this host: no need to wait)."""
        deadline = time.monotonic() + self.connect_timeout_s
        while True:
            remaining_s = deadline - time.monotonic()
            if self._first_telemetry.wait(max(0.0, min(KEYLESS_POLL_S, remaining_s))):
                return True
            if self._keyless_but_device_signs():
                raise self._needs_key_error()
            if remaining_s <= 0:
                return False

    def _keyless_but_device_signs(self) -> bool:
        """No key here, and the device answered HELLO with a signed SESSION_INFO saying a key is provisioned:
        it takes only signed frames on this link (over USB serial the same device answers unsigned and takes
        unsigned frames)."""
        info = self._session_info
        return self._key is None and info is not None and bool(info.key_set) and self._session_info_signed

    def _needs_key_error(self) -> AuthenticationError:
        return AuthenticationError(f"{self.url} requires signed frames (its SESSION_INFO is signed: a key is "
                                   "provisioned) and no link key was given: pass key=... (wrangler --key-file)",
                                   url=self.url, needs_key=True)

    def _hello(self) -> None:
        hello = gen.Hello(secrets.randbelow(2**32)) if self._link is None else self._link.hello()
        self._hello_nonce = hello.host_nonce
        self._send_new(hello, sign=False)

    def _establish_session(self) -> None:
        """Wait for the SESSION_INFO answering our HELLO (resending HELLO each ack_timeout_s).

        An answer that does not verify with our key (wrong key, a device without one, or a forgery: HELLO
        and its nonce travel in clear) is believed only if no verified answer follows within two more
        HELLO rounds.
        """
        start = time.monotonic()
        deadline = start + self.connect_timeout_s
        unverified_until: float | None = None
        while self.session_id is None:
            self._session_event.wait(min(self.ack_timeout_s, max(0.0, deadline - time.monotonic())))
            if self.session_id is not None:
                break
            now = time.monotonic()
            if self._session_info is not None:
                unverified_until = unverified_until or now + 2 * self.ack_timeout_s
                if now >= unverified_until:
                    break
                self._session_event.clear()
            if now >= deadline:
                if self._session_info is not None:
                    break
                raise LinkTimeout(f"no SESSION_INFO from {self.url} within {self.connect_timeout_s:g} s: is the "
                                  "device running, and does its firmware speak protocol version "
                                  f"{gen.PROTOCOL_VERSION}?", url=self.url, waited_s=self.connect_timeout_s)
            self._send_new(gen.Hello(self._hello_nonce), sign=False)
        info = self._session_info
        if info.schema_hash != gen.SCHEMA_HASH:
            raise AuthenticationError(f"{self.url} speaks protocol schema 0x{info.schema_hash:04X}, this host "
                                      f"0x{gen.SCHEMA_HASH:04X}: update the firmware or the host", url=self.url)
        if self.session_id is None and not info.key_set:
            raise AuthenticationError(f"{self.url} has no link key provisioned, so it takes no command over WiFi: "
                                      "provision one over USB serial", url=self.url)
        if self.session_id is None:
            raise AuthenticationError(f"the SESSION_INFO from {self.url} is not signed with the given key: the "
                                      "host's and the device's link keys differ", url=self.url)

    @property
    def session_id(self) -> int | None:
        """The device session this client signs for (None: unsigned link, or no session yet)."""
        return None if self._link is None else self._link.session_id

    def close(self) -> None:
        """Stop the threads and release the link; open telemetry() iterators end. Idempotent.

        Heartbeats stop, so a device left spinning lands by itself after heartbeat_timeout_s.
        """
        self._stop.set()
        for t in self._threads:
            if t is not threading.current_thread() and t.ident is not None:  # started
                t.join(timeout=2.0)
        self._threads = []
        if self._transport is not None:
            self._transport.close()
            self._transport = None
        self._connected = False
        with self._lock:
            for q in self._subscribers:
                _put_dropping_oldest(q, _CLOSED)

    def __enter__(self) -> Client:
        return self.connect()

    def __exit__(self, *exc_info: object) -> None:
        self.close()

    @property
    def connected(self) -> bool:
        return self._connected

    @property
    def stats(self) -> ClientStats:
        """A snapshot of the link counters."""
        with self._lock:
            snap = replace(self._stats, decode_errors_by_reason=dict(self._stats.decode_errors_by_reason))
        if self._transport is not None:
            snap.framing_errors = self._transport.framing_errors
        return snap

    # ----------------------------------------------------------------- commands

    def arm(self, *, timeout_s: float | None = None) -> State:
        """DISARMED -> ARMED; returns the state the ACK reports.

        While the device answers NOT_READY (ESC arming hold after boot) ARM is sent again, each time
        with a new seq, until timeout_s (default connect_timeout_s) of the device's time has passed (the
        hold runs on its clock: the TELEMETRY time_s; wall time until a sample has arrived), and at most
        NOT_READY_WALL_FACTOR x timeout_s of wall time (a device whose clock a busy machine slows); then
        the last CommandRefused(NOT_READY) is raised. Any other NACK is raised at once.
        """
        limit_s = self.connect_timeout_s if timeout_s is None else _check_positive("timeout_s", timeout_s)
        wall_start_s = time.monotonic()
        first = self._latest  # the device's clock when the wait began on it
        before_first_s = 0.0  # wall time waited before any sample had arrived
        while True:
            try:
                return State(self._command(gen.Arm()).state)
            except CommandRefused as refused:
                if refused.reason != NackReason.NOT_READY:
                    raise
                wall_s = time.monotonic() - wall_start_s
                now = self._latest
                if first is None and now is not None:
                    first, before_first_s = now, wall_s
                waited_s = before_first_s + now.time_s - first.time_s if first is not None else wall_s
                if (waited_s + NOT_READY_RETRY_S > limit_s
                        or wall_s + NOT_READY_RETRY_S > NOT_READY_WALL_FACTOR * limit_s):
                    raise
            time.sleep(NOT_READY_RETRY_S)

    def disarm(self) -> State:
        """ARMED, FAULT or ESTOP -> DISARMED (BAD_STATE while the rope moves)."""
        return State(self._command(gen.Disarm()).state)

    def spin(self, rope_speed_mps: float) -> State:
        """Set the rope speed target [m/s]; from ARMED this starts the spin-up.

        Only values that cannot be encoded (NaN, inf, not a number) raise InvalidArgument here; the
        device range-checks the rest (OUT_OF_RANGE, BELOW_TOV_GUARD -> CommandRefused).
        """
        mmps = units.mps_to_mmps(rope_speed_mps)
        return State(self._command(gen.SetRopeSpeed(mmps), value=float(rope_speed_mps)).state)

    def spindown(self) -> State:
        """Controlled ramp to zero at ramp_down_mps2; the device ends in ARMED."""
        return State(self._command(gen.Spindown()).state)

    def estop(self) -> State:
        """Emergency stop: ESC minimum at once, latched until disarm(). Accepted in every state."""
        return State(self._command(gen.Estop()).state)

    def set_loop(self, guide_position_m: float) -> State:
        """Move the rope guide to guide_position_m [m] from home (larger = more rope inside = smaller loop).

        Needs a homed spindle (NOT_HOMED) and ARMED, SPINUP or AIRBORNE; the device checks the soft
        limits guide_min_mm..guide_max_mm (OUT_OF_RANGE). Returns when accepted, not when reached: wait
        with wait_for(lambda s: ...) or for the SPINDLE_TARGET_REACHED event.
        """
        um = units.m_to_um(guide_position_m)
        return State(self._command(gen.SetLoop(um), value=float(guide_position_m)).state)

    def relax(self) -> State:
        """SPINUP or AIRBORNE -> RELAX: the rope ramps to a stop so the loop settles onto the object."""
        return State(self._command(gen.Relax()).state)

    def retract(self) -> State:
        """ARMED, or RELAX with the rope stopped -> RETRACT: reel in until the load secures the object
        (-> HOLD) or the stroke ends (-> ARMED). Needs a homed spindle."""
        return State(self._command(gen.Retract()).state)

    def grasp(self) -> State:
        """AIRBORNE -> RELAX -> RETRACT -> HOLD in one command. Returns when accepted: wait for HOLD (or
        ARMED, the stroke end without a load) with wait_for_state."""
        return State(self._command(gen.Grasp()).state)

    def release(self) -> State:
        """HOLD -> extend the guide by release_mm to let the object go -> ARMED."""
        return State(self._command(gen.Release()).state)

    def home(self) -> State:
        """DISARMED or ARMED with the rope stopped: drive the guide to the home end (stall or limit
        switch), position 0 there. Returns when accepted; telemetry spindle_flags gets HOMED when done."""
        return State(self._command(gen.Home()).state)

    def start_burst(self, samples: int) -> State:
        """BURST_START: the device samples every control tick (1 kHz) for `samples` ticks (1..1000), then streams
        them as BURST_DATA (a recorder writes them to /device/burst). Refused (NackError) while a burst is
        captured or streamed (BURST_BUSY) or for a size out of range (OUT_OF_RANGE, detail = the maximum)."""
        if isinstance(samples, bool) or not isinstance(samples, int) or not 1 <= samples <= 0xFFFF:
            raise InvalidArgument("samples", "an integer 1..1000 (the device's burst buffer)", samples)
        return State(self._command(gen.BurstStart(samples)).state)

    # ----------------------------------------------------------------- provisioning (USB serial only)

    def provision_status(self) -> ProvisionStatus:
        """What the device has stored (PROVISION_GET -> ACK + PROVISION_STATUS). Serial links only."""
        self._require_serial_link()
        for _ in range(self.retries + 1):
            waiter = _Waiter()
            with self._lock:
                self._status_waiters.append(waiter)
            try:
                self._command(gen.ProvisionGet(), param_waiter=waiter)
                if waiter.event.wait(self.ack_timeout_s):
                    return ProvisionStatus.from_wire(waiter.reply)
            finally:
                with self._lock:
                    if waiter in self._status_waiters:
                        self._status_waiters.remove(waiter)
        raise LinkTimeout(f"PROVISION_GET: ACKed by {self.url} but no PROVISION_STATUS arrived after "
                          f"{self.retries + 1} requests", url=self.url, waited_s=(self.retries + 1) * self.ack_timeout_s)

    def provision(self, *, key: bytes | None = None, wifi_ssid: str | None = None,
                  wifi_password: str | None = None, commit: bool = True) -> ProvisionStatus:
        """Store a link key and/or WiFi credentials on the device, then (commit=True) write them to flash.

        Only over a serial:// link: a key or a password never travels over WiFi, so any other link is
        refused here, before anything is sent (InvalidArgument naming the URL). key: 16 bytes;
        wifi_ssid: at most 32 UTF-8 bytes; wifi_password: at most 63 bytes (the device checks WPA2's
        8-63 or empty). Error messages never contain the key or the password. Returns the status after.
        """
        self._require_serial_link()
        if key is not None and (not isinstance(key, (bytes, bytearray)) or len(key) != gen.KEY_LEN):
            raise InvalidArgument("key", f"{gen.KEY_LEN} bytes", f"{type(key).__name__} of length "
                                  f"{len(key) if hasattr(key, '__len__') else '?'}")
        if wifi_ssid is not None and (not isinstance(wifi_ssid, str) or len(wifi_ssid.encode()) > 32 or "\0" in wifi_ssid):
            raise InvalidArgument("wifi_ssid", "text of at most 32 UTF-8 bytes without NUL", wifi_ssid)
        if wifi_password is not None and (not isinstance(wifi_password, str) or len(wifi_password.encode()) > 63
                                          or "\0" in wifi_password):
            length = len(wifi_password.encode()) if isinstance(wifi_password, str) else "?"
            raise InvalidArgument("wifi_password", "text of at most 63 bytes without NUL",
                                  f"a {type(wifi_password).__name__} of {length} bytes (not shown)")
        for message in staging_messages(key=key, wifi_ssid=wifi_ssid, wifi_password=wifi_password):
            self._command(message)
        if commit:
            self._command(gen.ProvisionCommit(new_session_epoch()))  # a fresh random base for the session ids
        return self.provision_status()

    def _require_serial_link(self) -> None:
        if not self.url.startswith("serial://"):
            raise InvalidArgument("url", "a serial:// link: provisioning (keys, WiFi passwords) never travels "
                                  "over WiFi", self.url)

    def get_param(self, name: str) -> float:
        """A parameter's value on the device, in its SI unit (see robowrangler.protocol PARAMS)."""
        spec = param_spec(name)
        return self._param_exchange(spec, gen.ParamGet(spec.id), value=None)

    def set_param(self, name: str, value: float) -> float:
        """Set a parameter; returns the value the device now holds (float32, shortest decimal).

        NaN or a non-number raises InvalidArgument; out-of-range values are sent and refused by the
        device (CommandRefused OUT_OF_RANGE / PARAM_LOCKED).
        """
        spec = param_spec(name)
        x = units.param_to_float32(name, value)
        return self._param_exchange(spec, gen.ParamSet(spec.id, x), value=x)

    def params(self) -> dict[str, float]:
        """Every parameter of the protocol table, read from the device: {name: value}."""
        return {p.name: self.get_param(p.name) for p in PARAMS}

    # ----------------------------------------------------------------- telemetry and events

    @property
    def latest_telemetry(self) -> TelemetrySample | None:
        """The most recent TelemetrySample, or None before the first one."""
        return self._latest

    @property
    def events(self) -> list[DeviceEvent]:
        """Every EVENT received since connect (oldest first, at most the last 10000)."""
        with self._lock:
            return list(self._events)

    def telemetry(self, *, timeout_s: float | None = None) -> Iterator[TelemetrySample]:
        """Iterate over TELEMETRY samples received from now on (every sample, in order).

        timeout_s: longest gap between samples before LinkTimeout [s]; None uses connect_timeout_s.
        The iterator ends when the client is closed. Break out of the loop to stop.
        """
        gap_s = self.connect_timeout_s if timeout_s is None else _check_positive("timeout_s", timeout_s)
        self._require_connected()
        return self._iterate(self._subscribe(), gap_s)

    def _subscribe(self) -> queue.Queue:
        q: queue.Queue = queue.Queue(maxsize=TELEMETRY_QUEUE_LEN)
        with self._lock:
            self._subscribers.append(q)
        return q

    def _unsubscribe(self, q: queue.Queue) -> None:
        with self._lock:
            if q in self._subscribers:
                self._subscribers.remove(q)

    def _iterate(self, q: queue.Queue, gap_s: float) -> Iterator[TelemetrySample]:
        try:
            while True:
                try:
                    item = q.get(timeout=gap_s)
                except queue.Empty:
                    raise LinkTimeout(f"telemetry from {self.url} stopped: no sample for {gap_s:g} s",
                                      url=self.url, waited_s=gap_s) from None
                if item is _CLOSED:
                    return
                yield item
        finally:
            self._unsubscribe(q)

    def wait_for_state(self, state: State | Iterable[State], *, timeout_s: float) -> TelemetrySample:
        """Wait for a TELEMETRY sample received after this call whose state is `state` (or one of them).

        Returns that sample. StateTimeout (naming the last state seen) if that state does not come
        within timeout_s; LinkTimeout if no telemetry arrives for connect_timeout_s.
        """
        wanted = (state,) if isinstance(state, (State, int)) else tuple(state)
        try:
            wanted = tuple(State(s) for s in wanted)
        except (ValueError, TypeError):
            raise InvalidArgument("state", "a State or an iterable of States", state) from None
        if not wanted:
            raise InvalidArgument("state", "at least one State", state)
        return self.wait_for(lambda s: s.state in wanted, timeout_s=timeout_s, expected=wanted)

    def wait_for(self, predicate: Callable[[TelemetrySample], bool], *, timeout_s: float,
                 expected: tuple[State, ...] | str = "the awaited condition") -> TelemetrySample:
        """Wait for a TELEMETRY sample received after this call for which predicate(sample) is true.

        Returns that sample. StateTimeout if none comes within timeout_s (`expected` names what was
        awaited in its message); LinkTimeout if no telemetry arrives for connect_timeout_s.
        """
        if not callable(predicate):
            raise InvalidArgument("predicate", "a callable taking a TelemetrySample", predicate)
        wanted = expected
        limit_s = _check_positive("timeout_s", timeout_s)
        self._require_connected()
        deadline = time.monotonic() + limit_s
        last_sample_s = time.monotonic()
        last: TelemetrySample | None = None
        q = self._subscribe()
        try:
            while (remaining_s := deadline - time.monotonic()) > 0:
                gap_left_s = last_sample_s + self.connect_timeout_s - time.monotonic()
                if gap_left_s <= 0:
                    raise LinkTimeout(f"telemetry from {self.url} stopped: no sample for "
                                      f"{self.connect_timeout_s:g} s", url=self.url, waited_s=self.connect_timeout_s)
                try:
                    item = q.get(timeout=min(remaining_s, gap_left_s))
                except queue.Empty:
                    continue
                if item is _CLOSED:
                    raise NotConnected("the client was closed while waiting for a state")
                last_sample_s, last = time.monotonic(), item
                if predicate(item):
                    return item
        finally:
            self._unsubscribe(q)
        latest = last or self._latest
        raise StateTimeout(expected=wanted, actual=latest.state if latest else None, waited_s=limit_s)

    # ----------------------------------------------------------------- internals: sending

    def _require_connected(self) -> None:
        if not self._connected or self._transport is None:
            raise NotConnected(f"not connected to {self.url}: call connect() or use `with Client(...)`")

    def _encode(self, message: gen.Message, seq: int, *, sign: bool = True) -> bytes:
        """Frame a message; signed (session id, next counter) when the client has a key and a session.

        The counter is the larger of the last one + 1 and the wall clock in microseconds, so it keeps
        growing across host processes within one device session (the device drops a counter that is not
        above the last it accepted). Call with _send_lock held.
        """
        if not sign or self._link is None or self._link.session_id is None:
            return gen.encode_frame(message, seq)
        return self._link.sign(message, seq)

    def _send_new(self, message: gen.Message, waiter_key_msg_id: int | None = None,
                  param_waiter: _Waiter | None = None, *, sign: bool = True) -> tuple[int, bytes, _Waiter | None]:
        """Allocate a seq, encode and send; registers an ACK/NACK waiter first if asked."""
        with self._send_lock:
            seq = self._next_seq_value
            self._next_seq_value = (seq + 1) & 0xFFFF
            frame = self._encode(message, seq, sign=sign)
            waiter = None
            if waiter_key_msg_id is not None:
                waiter = _Waiter()
                waiter.param_waiter = param_waiter
                with self._lock:
                    self._waiters[(waiter_key_msg_id, seq)] = waiter
            self._send_raw(frame)
        return seq, frame, waiter

    def _send_raw(self, frame: bytes) -> None:
        transport = self._transport
        if transport is None:
            raise NotConnected(f"not connected to {self.url}")
        try:
            transport.send(frame)
        except OSError:
            with self._lock:
                self._stats.send_errors += 1
            return  # a lost frame: the retries and timeouts report it
        with self._lock:
            self._stats.frames_sent += 1

    def _command(self, message: gen.Message, *, value: float | None = None, param: str | None = None,
                 param_waiter: _Waiter | None = None) -> gen.Ack:
        """Send a command and wait for its ACK (returned) or NACK (CommandRefused), retransmitting the same
        bytes every ack_timeout_s up to `retries` times; LinkTimeout after that.

        A NACK saying the device could not read the frame (TRANSIT_NACK_REASONS: corrupted on the way)
        is answered by retransmitting at once, within the same `retries` budget; only the last such
        NACK is raised."""
        self._require_connected()
        seq, frame, waiter = self._send_new(message, waiter_key_msg_id=message.MSG_ID, param_waiter=param_waiter)
        key = (message.MSG_ID, seq)
        with self._lock:
            self._stats.commands_sent += 1
        try:
            attempts = 1
            while True:
                if waiter.event.wait(self.ack_timeout_s):
                    reply = waiter.reply
                    if not (isinstance(reply, gen.Nack) and reply.reason in TRANSIT_NACK_REASONS
                            and attempts <= self.retries):
                        break
                    with self._lock:  # the frame was damaged on the way: the same bytes go again at once
                        self._stats.transit_nacks += 1
                        waiter.reply = None
                        waiter.event.clear()
                elif attempts > self.retries:
                    waited_s = attempts * self.ack_timeout_s
                    raise LinkTimeout(
                        f"{message.NAME} (seq {seq}): no ACK/NACK from {self.url} after {attempts} attempts "
                        f"in {waited_s:.2f} s; the link or the device is down", url=self.url, waited_s=waited_s)
                self._require_connected()
                if self._key is not None:  # same seq and payload (same checksum), a fresh counter, and sent
                    with self._send_lock:  # under the lock: no frame with a higher counter may overtake it
                        frame = self._encode(message, seq)
                        self._send_raw(frame)
                else:
                    self._send_raw(frame)
                attempts += 1
                with self._lock:
                    self._stats.retransmissions += 1
        finally:
            with self._lock:
                self._waiters.pop(key, None)
        reply = waiter.reply
        if isinstance(reply, gen.Nack):
            raise CommandRefused(command_msg_id=message.MSG_ID, reason=reply.reason, state=reply.state,
                                 detail=reply.detail, value=value, param=param)
        return reply

    def _param_exchange(self, spec: ParamSpec, message: gen.Message, *, value: float | None) -> float:
        """PARAM_GET or PARAM_SET, then the PARAM_VALUE that follows its ACK.

        PARAM_VALUE carries no seq: for a PARAM_GET only a value received after its ACK counts, for a
        PARAM_SET only the float32 that was written (and only once the ACK says it was accepted); others
        are late duplicates of older answers, ignored and counted in stats.stale_param_values. If the PARAM_VALUE is lost, a PARAM_GET (new seq; reading
        twice is harmless) asks again, up to `retries` times.
        """
        request: gen.Message = message
        expect_bits = None if value is None else struct.pack("<f", value)
        for _ in range(self.retries + 1):
            waiter = _Waiter(expect_bits=expect_bits)
            with self._lock:
                self._param_waiters[spec.id].append(waiter)
            try:
                self._command(request, value=value, param=spec.name, param_waiter=waiter)
                if waiter.event.wait(self.ack_timeout_s):
                    return units.float32_to_si(waiter.reply.value)
            finally:
                with self._lock:
                    if waiter in self._param_waiters[spec.id]:
                        self._param_waiters[spec.id].remove(waiter)
            request, expect_bits = gen.ParamGet(spec.id), None
        waited_s = (self.retries + 1) * self.ack_timeout_s
        raise LinkTimeout(f"{spec.name}: ACKed by {self.url} but no PARAM_VALUE arrived after "
                          f"{self.retries + 1} requests", url=self.url, waited_s=waited_s)

    def request(self, message: gen.Message) -> gen.Ack | gen.Nack:
        """Send any command message and return the device's answer, its ACK or its NACK (not raised).

        For a tool that carries other hosts' commands (wrangler proxy); retries and LinkTimeout as for
        every command. PARAM_GET/PARAM_SET: use get_param/set_param, which also wait for the PARAM_VALUE.
        """
        try:
            return self._command(message)
        except CommandRefused as err:
            return gen.Nack(message.MSG_ID, 0, int(err.reason), int(err.state), err.detail)

    def pause_heartbeats_while(self, idle: Callable[[], bool] | None) -> None:
        """Send no HEARTBEAT while idle() is true (None: always send). A proxy passes "no local tool is
        alive", so that the device's live-host rule (heartbeat_timeout_s) still follows the tools."""
        self._heartbeat_idle = idle

    def _heartbeat_loop(self) -> None:
        period_s = 1.0 / self.heartbeat_hz
        next_s = time.monotonic()
        while not self._stop.is_set():
            try:
                idle = self._heartbeat_idle
                if idle is None or not idle():
                    self._send_new(gen.Heartbeat(units.s_to_ms_u32(time.monotonic())))
                    with self._lock:
                        self._stats.heartbeats_sent += 1
            except NotConnected:
                return
            next_s += period_s
            now = time.monotonic()
            if next_s < now:  # fell behind (suspended process): do not burst
                next_s = now
            self._stop.wait(next_s - now)

    def _heartbeat_on_device_clock(self, sample: TelemetrySample) -> None:
        """A heartbeat now if the device, by its own clock, has heard none for a heartbeat period."""
        period_s = 1.0 / self.heartbeat_hz
        last_s = self._device_heartbeat_s
        idle = self._heartbeat_idle  # paused (a proxy with no live tool): no heartbeat by either clock
        if (not self._connected or sample.heartbeat_age_s < period_s
                or (last_s is not None and 0.0 <= sample.time_s - last_s < period_s)
                or (idle is not None and idle())):
            return
        self._device_heartbeat_s = sample.time_s
        try:
            self._send_new(gen.Heartbeat(units.s_to_ms_u32(time.monotonic())))
        except NotConnected:
            return
        with self._lock:
            self._stats.heartbeats_sent += 1
            self._stats.device_clock_heartbeats += 1

    # ----------------------------------------------------------------- internals: receiving

    def _receive_loop(self) -> None:
        transport = self._transport
        while not self._stop.is_set():
            try:
                data = transport.recv(RECV_POLL_S)
            except Exception:  # a dying link must not kill the thread: timeouts will report it
                with self._lock:
                    self._stats.recv_errors += 1
                self._stop.wait(RECV_POLL_S)
                continue
            if data is None:
                continue
            try:
                self._handle_datagram(data, time.monotonic())
            except Exception:  # noqa: BLE001 - a bug in dispatch must not silence the link; counted
                self._count_decode_error("DISPATCH")

    def _handle_datagram(self, data: bytes, received_s: float) -> None:
        try:
            frame, msg = gen.decode_message(data)
        except FrameError as err:
            self._count_decode_error(err.reason.name)
            return
        except Exception:  # noqa: BLE001 - any unpack failure is bad data, counted not raised
            self._count_decode_error("UNPACK")
            return
        if frame.signed and not self._accept_signed(frame, msg):
            return
        with self._lock:
            self._stats.frames_received += 1
        msg_id = frame.msg_id
        if msg_id == MsgId.SESSION_INFO:
            self._on_session_info(frame, msg)
            return
        if msg_id in (MsgId.ACK, MsgId.NACK):
            self._on_reply(msg)
        elif msg_id == MsgId.PARAM_VALUE:
            with self._lock:
                self._stats.param_values += 1
                taken = False
                for w in self._param_waiters.get(msg.param_id, []):
                    if w.reply is None and (w.armed if w.expect_bits is None
                                            else struct.pack("<f", msg.value) == w.expect_bits):
                        w.reply = msg
                        w.event.set()
                        taken = True
                if not taken:
                    self._stats.stale_param_values += 1
        elif msg_id == MsgId.PROVISION_STATUS:
            with self._lock:
                for w in self._status_waiters:
                    if w.armed and w.reply is None:
                        w.reply = msg
                        w.event.set()
        elif msg_id == MsgId.TELEMETRY:
            self._on_telemetry(TelemetrySample.from_wire(msg, received_s=received_s))
        elif msg_id == MsgId.EVENT:
            self._on_event(DeviceEvent.from_wire(msg, received_s=received_s))
        elif msg_id == MsgId.BURST_DATA:
            with self._lock:
                self._stats.burst_frames += 1
        else:
            with self._lock:
                self._stats.unexpected_messages += 1

    def _accept_signed(self, frame: gen.Frame, msg: gen.Message) -> bool:
        """A signed frame from the device counts only if the link session takes it (LinkSession.check: the tag
        verifies with our key, and it is fresh); a frame of a newer session (the device rebooted) moves the
        client to that session."""
        if self._link is None:
            return True  # nothing to check it with; an unsigned link trusts the transport
        verdict = self._link.check(frame, msg)
        if verdict == Verdict.BAD_TAG:
            with self._lock:
                self._stats.auth_failures += 1
            if (frame.msg_id == MsgId.SESSION_INFO and msg.host_nonce == self._hello_nonce
                    and self._link.session_id is None):
                self._session_info = msg  # an answer to our HELLO signed with another key (or forged)
                self._session_event.set()
            return False
        if verdict == Verdict.STALE:
            with self._lock:
                self._stats.replayed += 1
            return False
        if verdict == Verdict.FOLLOWED:
            with self._lock:
                self._stats.session_changes += 1
        return True

    def _on_session_info(self, frame: gen.Frame, msg: gen.Message) -> None:
        if msg.host_nonce != self._hello_nonce:
            with self._lock:
                self._stats.unexpected_messages += 1  # someone else's HELLO, or a replayed answer
            return
        verified = self._link is not None and frame.signed  # the link session checked the tag and took the session
        if verified or self.session_id is None:  # an unverified answer never replaces a verified one
            self._session_info = msg
            self._session_info_signed = bool(frame.signed)
        self._session_event.set()

    def _count_decode_error(self, reason: str) -> None:
        with self._lock:
            self._stats.decode_errors += 1
            by_reason = self._stats.decode_errors_by_reason
            by_reason[reason] = by_reason.get(reason, 0) + 1

    def _on_reply(self, msg: gen.Ack | gen.Nack) -> None:
        with self._lock:
            if isinstance(msg, gen.Nack):
                self._stats.nacks += 1
            else:
                self._stats.acks += 1
            waiter = self._waiters.get((msg.cmd_msg_id, msg.cmd_seq))
            if waiter is None or waiter.reply is not None:
                self._stats.late_replies += 1  # answer to a retransmission, or after a timeout
                return
            waiter.reply = msg
            if isinstance(msg, gen.Ack) and waiter.param_waiter is not None:
                waiter.param_waiter.armed = True  # the PARAM_VALUE that follows this ACK is ours
            waiter.event.set()

    def _on_telemetry(self, sample: TelemetrySample) -> None:
        self._heartbeat_on_device_clock(sample)
        self._latest = sample
        with self._lock:
            self._stats.telemetry_received += 1
            for q in self._subscribers:
                if _put_dropping_oldest(q, sample):
                    self._stats.telemetry_dropped += 1
        self._first_telemetry.set()

    def _on_event(self, event: DeviceEvent) -> None:
        with self._lock:
            self._stats.events_received += 1
            if self._last_event_seq is not None:
                gap = (event.event_seq - self._last_event_seq - 1) & 0xFFFF
                if gap >= 0x8000:  # a repeated or reordered (older) event: keep it, count nothing
                    self._events.append(event)
                    return
                self._stats.events_lost += gap
            self._last_event_seq = event.event_seq
            self._events.append(event)


def _put_dropping_oldest(q: queue.Queue, item: object) -> bool:
    """Put without blocking; if the queue is full drop its oldest item. True if one was dropped."""
    try:
        q.put_nowait(item)
        return False
    except queue.Full:
        try:
            q.get_nowait()
        except queue.Empty:
            pass
        q.put_nowait(item)
        return True


__all__ = ["Client", "ClientStats", "DeviceEvent", "State", "TelemetrySample", "param_spec"]
