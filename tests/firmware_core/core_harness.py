"""A fake HAL in Python and a harness that drives the whole firmware core (rw_core) tick by tick.

The core comes from build/native/librw_core.so (loaded by rw_core_ctypes.load, the suite's `rw_core`
fixture). Every input is set exactly by the test: the tick clock (now_us, wraps at 2^32), the encoder
(cumulative counts and the capture time of the latest edge), the battery voltage and the datagrams
the link delivers. Every output is recorded: the ESC pulse of each tick, the replies (ACK/NACK, to the
sender of the received datagram), the frames sent to the peer (PARAM_VALUE, EVENT, TELEMETRY),
accept_peer calls. Frames are built and decoded with the Python generated codec.

Units: times in microseconds (_us) on the tick clock, milliseconds (_ms) for device uptime, rope
speed in m/s (_mps) and mm/s on the wire (_mmps).
"""

from __future__ import annotations

import ctypes
import math
import platform
import sys
from collections import deque
from ctypes import CFUNCTYPE, POINTER, c_bool, c_size_t, c_uint8, c_uint16, c_uint32, c_uint64, c_void_p
from dataclasses import dataclass, field

from robowrangler.link_session import LinkSession
from robowrangler.protocol import generated as proto

U32 = 1 << 32
TICK_US = 1000
_CANARY = b"\xa5" * 64


# ---- HAL structs (firmware/hal/rw_hal*.h) --------------------------------------------------------

# rw_encoder_sample {uint32 counts; uint32 last_edge_us} is returned by value. ctypes callbacks
# cannot return structures, so the callback returns a uint64: on x86-64 (SysV) and AArch64 an
# 8-byte struct of two uint32 comes back in one integer register, first member in the low half.
if platform.machine().lower() not in ("x86_64", "amd64", "aarch64", "arm64") or sys.byteorder != "little":
    raise RuntimeError(f"core_harness: encoder callback ABI: expected a little-endian x86_64/aarch64 host, "
                       f"got {platform.machine()} ({sys.byteorder})")

_EncoderRead = ctypes.CFUNCTYPE(c_uint64, c_void_p)
_BatteryRead = ctypes.CFUNCTYPE(c_uint16, c_void_p)
_EscWrite = ctypes.CFUNCTYPE(None, c_void_p, c_uint16)
_LinkRecv = ctypes.CFUNCTYPE(c_size_t, c_void_p, POINTER(c_uint8), c_size_t)
_LinkOut = ctypes.CFUNCTYPE(None, c_void_p, POINTER(c_uint8), c_size_t)
_LinkAccept = ctypes.CFUNCTYPE(None, c_void_p)
_Overruns = ctypes.CFUNCTYPE(c_uint32, c_void_p)


class _HalEsc(ctypes.Structure):
    _fields_ = [("ctx", c_void_p), ("write_pulse_us", _EscWrite), ("write_pulse_third_us", _EscWrite)]


class _HalEncoder(ctypes.Structure):
    _fields_ = [("ctx", c_void_p), ("read", _EncoderRead)]


class _HalBattery(ctypes.Structure):
    _fields_ = [("ctx", c_void_p), ("read_mv", _BatteryRead)]


class _HalLink(ctypes.Structure):
    _fields_ = [("ctx", c_void_p), ("recv", _LinkRecv), ("reply", _LinkOut), ("accept_peer", _LinkAccept),
                ("send", _LinkOut)]


class _HalScheduler(ctypes.Structure):
    _fields_ = [("ctx", c_void_p), ("tick_overruns", _Overruns)]


class SpindleReading(ctypes.Structure):
    """rw_spindle_reading (rw_hal_spindle.h)."""

    _fields_ = [("position_raw", c_uint16), ("speed_raw", c_uint16), ("load_raw", c_uint16),
                ("limit_switch", ctypes.c_bool)]


_SpindleRead = ctypes.CFUNCTYPE(ctypes.c_bool, c_void_p, POINTER(SpindleReading))
_SpindleWrite = ctypes.CFUNCTYPE(None, c_void_p, c_uint16)


class _HalSpindle(ctypes.Structure):
    _fields_ = [("ctx", c_void_p), ("read", _SpindleRead), ("write_moving_speed_raw", _SpindleWrite)]


_ConfigLoad = CFUNCTYPE(c_bool, c_void_p, c_void_p, c_size_t)
_ConfigSave = CFUNCTYPE(c_bool, c_void_p, c_void_p, c_size_t)
_ConfigSaveStatus = CFUNCTYPE(ctypes.c_uint8, c_void_p)
CONFIG_SAVE_BUSY, CONFIG_SAVE_DONE, CONFIG_SAVE_FAILED = 1, 2, 3  # rw_config_save_status (hal/rw_hal_config_store.h)


class _HalConfigStore(ctypes.Structure):
    _fields_ = [("ctx", c_void_p), ("load", _ConfigLoad), ("save", _ConfigSave), ("request_save", _ConfigSave),
                ("save_status", _ConfigSaveStatus)]


class _Hal(ctypes.Structure):
    # spindle: NULL when no spindle is fitted; serial: NULL (no USB serial). Interfaces added to rw_hal
    # later must be appended here too; the trailing NULL pointers keep an older mirror from handing the
    # core garbage meanwhile.
    _fields_ = [("esc", POINTER(_HalEsc)), ("encoder", POINTER(_HalEncoder)), ("battery", POINTER(_HalBattery)),
                ("link", POINTER(_HalLink)), ("scheduler", POINTER(_HalScheduler)), ("spindle", POINTER(_HalSpindle)),
                ("serial", c_void_p), ("config", POINTER(_HalConfigStore)), ("_reserved_null", c_void_p * 2)]


TEST_KEY = bytes(range(16))  # the harness's provisioned link key (its "flash" holds it); never a real one
SESSION_ID = 1  # a fresh flash record has boot counter 0: the first boot is session 1


def declare_core(lib: ctypes.CDLL) -> ctypes.CDLL:
    """Declares the top-level core API (rw_core.h) on the loaded library; returns lib."""
    lib.rw_core_sizeof.restype = c_size_t
    lib.rw_core_sizeof.argtypes = []
    lib.rw_core_init.restype = None
    lib.rw_core_init.argtypes = [c_void_p]
    lib.rw_core_tick.restype = None
    lib.rw_core_tick.argtypes = [c_void_p, POINTER(_Hal), c_uint32]
    lib.rw_core_tx_idle.restype = ctypes.c_bool
    lib.rw_core_tx_idle.argtypes = [c_void_p]
    lib.rw_core_set_param.restype = ctypes.c_int
    lib.rw_core_set_param.argtypes = [c_void_p, c_uint8, ctypes.c_float]
    lib.rw_config_defaults.restype = None
    lib.rw_config_defaults.argtypes = [c_void_p]
    lib.rw_config_set_params.restype = None
    lib.rw_config_set_params.argtypes = [c_void_p, c_void_p]  # rw_core's params.value is at offset 0
    lib.rw_config_set_key.restype = None
    lib.rw_config_set_key.argtypes = [c_void_p, ctypes.c_char_p]
    return lib


# ---- Records -------------------------------------------------------------------------------------

@dataclass(frozen=True)
class Out:
    """One datagram the core emitted: channel 'reply' (to the sender) or 'send' (to the peer), on link 'wifi' or
    'serial' (the USB serial link, when the harness has one)."""

    tick_ms: int          # harness time of the tick that emitted it, ms since the first tick
    channel: str
    raw: bytes
    frame: proto.Frame
    msg: proto.Message
    link: str = "wifi"


@dataclass
class FakeHal:
    """The HAL's state: inputs the test sets, outputs the core produced."""

    encoder_counts: int = 0
    encoder_last_edge_us: int = 0
    battery_mv: int = 14800
    tick_overruns: int = 0
    inbox: deque = field(default_factory=deque)   # datagrams (bytes) waiting for recv
    serial_inbox: deque = field(default_factory=deque)  # frames (bytes) waiting on the USB serial link
    pulses_us: list = field(default_factory=list)  # one per tick
    out: list = field(default_factory=list)        # list[Out]
    accept_peer_calls: int = 0
    recv_calls: int = 0


# ---- Encoder model ---------------------------------------------------------------------------------

class RopeEncoder:
    """Edges of a wheel turning at a set rope speed: cumulative counts and the time of the latest edge.

    phase_counts integrates rate = v / (2 pi r) * counts_per_rev; an edge happens at every whole count,
    its time (rounded to the microsecond) is interpolated inside the tick.
    """

    def __init__(self, *, wheel_radius_m: float = 0.015, counts_per_rev: int = 64) -> None:
        self.wheel_radius_m = wheel_radius_m
        self.counts_per_rev = counts_per_rev
        self.speed_mps = 0.0
        self.phase_counts = 0.0
        self.last_edge_t_us = 0.0

    def counts_per_s(self) -> float:
        return self.speed_mps / (2.0 * math.pi * self.wheel_radius_m) * self.counts_per_rev

    def advance(self, t_us: int, dt_us: int) -> None:
        """Move from t_us - dt_us to t_us at the current speed."""
        rate_per_us = self.counts_per_s() * 1e-6
        if rate_per_us <= 0.0:
            return
        before = math.floor(self.phase_counts)
        self.phase_counts += rate_per_us * dt_us
        after = math.floor(self.phase_counts)
        if after > before:
            self.last_edge_t_us = t_us - (self.phase_counts - after) / rate_per_us

    @property
    def counts(self) -> int:
        return math.floor(self.phase_counts)


# ---- Spindle model (AX-12A in wheel mode on a lead screw, with end stops and an object) -------------

AX12_DEG_S_PER_MOVING_UNIT = 59.0 * 6.0 / 1023.0  # no-load wheel speed over the moving-speed range
AX12_DEG_S_PER_SPEED_UNIT = 0.111 * 6.0
AX12_DEG_PER_POSITION_UNIT = 300.0 / 1023.0
AX12_DIRECTION_BIT = 0x400


class FakeSpindle:
    """The servo turns at the last commanded moving speed (counter-clockwise = + = retract); the guide
    position x_mm = (angle - home_stop_deg) * lead / 360 is held in [0, stroke_mm] by end stops and, if
    object_mm is set, retraction stops there (the rope tightens around the object). Blocked: speed 0,
    load `blocked_load_permille` in the pushing direction; free: speed as commanded, load
    `free_load_permille`. The position register reads angle mod 360 over 0-300 degrees and
    `dead_zone_reading` in the 60 degree dead zone. answering=False: reads fail."""

    def __init__(self, *, lead_mm_per_rev: float = 8.0, start_mm: float = 3.0, stroke_mm: float = 185.0,
                 home_stop_deg: float = 1000.0, has_switch: bool = False) -> None:
        self.lead_mm_per_rev = lead_mm_per_rev
        self.home_stop_deg = home_stop_deg
        self.stroke_mm = stroke_mm
        self.angle_deg = home_stop_deg + start_mm * 360.0 / lead_mm_per_rev
        self.command_deg_s = 0.0
        self.object_mm: float | None = None
        self.has_switch = has_switch
        self.answering = True
        self.blocked = False
        self.free_load_permille = 30
        self.blocked_load_permille = 600
        self.dead_zone_reading = 1023
        self.writes: list[int] = []
        self.last_t_us: int | None = None

    @property
    def x_mm(self) -> float:
        return (self.angle_deg - self.home_stop_deg) * self.lead_mm_per_rev / 360.0

    def _deg(self, x_mm: float) -> float:
        return self.home_stop_deg + x_mm * 360.0 / self.lead_mm_per_rev

    def advance(self, t_us: int) -> None:
        dt_s = 0.0 if self.last_t_us is None else (t_us - self.last_t_us) * 1e-6
        self.last_t_us = t_us
        self.angle_deg += self.command_deg_s * dt_s
        upper = self.stroke_mm if self.object_mm is None else min(self.stroke_mm, self.object_mm)
        self.blocked = False
        if self.x_mm <= 0.0 and self.command_deg_s < 0.0:
            self.angle_deg, self.blocked = self._deg(0.0), True
        elif self.x_mm >= upper and self.command_deg_s > 0.0:
            self.angle_deg, self.blocked = self._deg(upper), True

    def reading(self) -> SpindleReading:
        speed = 0.0 if self.blocked else self.command_deg_s
        load = self.blocked_load_permille if self.blocked else (self.free_load_permille if speed else 0)
        sign_bit = AX12_DIRECTION_BIT if self.command_deg_s < 0.0 else 0
        w = self.angle_deg % 360.0
        pos = round(w / AX12_DEG_PER_POSITION_UNIT) if w < 300.0 else self.dead_zone_reading
        mag = min(1023, round(abs(speed) / AX12_DEG_S_PER_SPEED_UNIT))
        return SpindleReading(min(pos, 1023), mag | (AX12_DIRECTION_BIT if speed < 0.0 else 0),
                              min(load, 1023) | (sign_bit if load else 0),
                              self.has_switch and self.x_mm <= 0.5)

    def write(self, raw: int) -> None:
        self.writes.append(raw)
        mag = raw & 0x3FF
        self.command_deg_s = -mag * AX12_DEG_S_PER_MOVING_UNIT if raw & AX12_DIRECTION_BIT else mag * AX12_DEG_S_PER_MOVING_UNIT

    @property
    def moving(self) -> bool:
        return bool(self.writes) and (self.writes[-1] & 0x3FF) != 0


# ---- The harness -----------------------------------------------------------------------------------

MAX_FRAMES_SIGNING = 2  # frames the core signs at once (rw_core.h: state.signers): replies may overtake them


class CoreHarness:
    """One rw_core instance with a fake HAL. tick() advances the harness time t_us by dt_us and calls
    rw_core_tick(core, hal, (clock_offset_us + t_us) mod 2^32); the first tick is at t_us = 0.

    Keyword options: clock_offset_us puts the tick clock anywhere (to cross the 2^32 wrap);
    encoder_count_offset starts the encoder's cumulative count anywhere (to cross its wrap);
    battery_mv the battery reading; params {name: value} set through rw_core_set_param before the first
    tick (the checks are those of PARAM_SET, a refusal raises ValueError); serial=True fits a USB serial link
    (hal.serial_inbox in, Out.link == 'serial' out; trusted: unsigned frames and PROVISION_*); provisioned=False
    boots from a flash record without a link key (the core then takes nothing over WiFi); flash_save_ticks:
    a PROVISION_COMMIT's write (request_save) is done that many ticks after the tick that asked for it, between
    ticks as the board's background loop does it (0: at once, in the request).
    """

    def __init__(self, lib: ctypes.CDLL, *, clock_offset_us: int = 0, battery_mv: int = 14800,
                 params: dict[str, float] | None = None, spindle: FakeSpindle | None = None,
                 encoder_count_offset: int = 0, serial: bool = False, provisioned: bool = True,
                 flash_save_ticks: int = 1) -> None:
        self.lib = declare_core(lib)
        self.clock_offset_us = int(clock_offset_us)
        self.size = int(lib.rw_core_sizeof())
        self._mem = ctypes.create_string_buffer(self.size + len(_CANARY))
        ctypes.memmove(ctypes.addressof(self._mem) + self.size, _CANARY, len(_CANARY))
        self.core = ctypes.addressof(self._mem)
        lib.rw_core_init(self.core)
        self.encoder_count_offset = int(encoder_count_offset)
        self.hal = FakeHal(battery_mv=battery_mv, encoder_last_edge_us=self.clock_offset_us % U32,
                           encoder_counts=self.encoder_count_offset % U32)
        self.encoder = RopeEncoder()
        self.spindle = spindle
        self._events: list[proto.Event] = []          # sent EVENT frames, in order (cache of hal.out)
        self._transitions: list[tuple[int, int, int, int]] = []
        self._telemetry: list[proto.Telemetry] = []
        # a host's view of the core's signed frames: every one must be taken (tag, session, a growing counter)
        self._host_view = LinkSession(TEST_KEY, session_id=SESSION_ID)
        self._commit_key: bytes | None = None  # expect_commit(): the key signed frames may carry from this tick on
        # per link: highest seq sent so far; a fresh core numbers from 0, so the first frame out may be seq 1 when a
        # reply overtakes frame 0 while it is being signed (seen in CI: the boot EVENT after a HELLO's reply)
        self._max_seq: dict[str, int] = {"wifi": 65535, "serial": 65535}
        # per link: seqs skipped by a reply that overtook a frame being signed
        self._seq_holes: dict[str, set[int]] = {"wifi": set(), "serial": set()}
        self._serial = bool(serial)
        self._provisioned = bool(provisioned)
        self._callback_errors: list[Exception] = []  # raised in a HAL callback, re-raised by tick()
        self.t_us = 0
        self.started = False
        self.seq = 0
        self.flash_save_ticks = int(flash_save_ticks)
        self.flash_save_requests = 0
        self.flash_save_fails = False  # the background write fails (the read-back differs): status FAILED
        self._save_pending: bytes | None = None
        self._save_countdown = 0
        self._save_status = 0
        self._build_hal()
        for name, value in (params or {}).items():
            self.set_param(name, value)

    # -- HAL callbacks --
    def _build_hal(self) -> None:
        hal = self.hal

        def encoder_read(_ctx):
            return (hal.encoder_counts & 0xFFFFFFFF) | ((hal.encoder_last_edge_us & 0xFFFFFFFF) << 32)

        def battery_read(_ctx):
            return hal.battery_mv

        def esc_write(_ctx, pulse_us):
            hal.pulses_us.append(int(pulse_us))

        def link_recv(_ctx, buf, cap, inbox=None):
            hal.recv_calls += 1
            inbox = hal.inbox if inbox is None else inbox
            if not inbox:
                return 0
            data = inbox.popleft()
            n = min(len(data), cap)
            ctypes.memmove(buf, data, n)
            return len(data) if len(data) <= cap else cap + 1

        def record(channel, link="wifi"):
            def out(_ctx, frame, length):
                # an exception cannot cross the C frames of a ctypes callback: it is kept and raised by tick()
                try:
                    checked(ctypes.string_at(frame, length))
                except Exception as err:  # noqa: BLE001 - re-raised after rw_core_tick returns
                    self._callback_errors.append(err)

            def checked(raw):
                fr, msg = proto.decode_message(raw)  # the core must only emit well-formed frames
                if fr.signed:  # as a host checks it (LinkSession): the tag, and a counter above every one before
                    verdict = self._host_view.check(fr, msg)
                    if not verdict.taken and self._commit_key is not None:  # a PROVISION_COMMIT in this tick
                        self._host_view = LinkSession(self._commit_key, session_id=0)  # its new key and epoch
                        self._commit_key = None
                        verdict = self._host_view.check(fr, msg)
                    if not verdict.taken:
                        raise AssertionError(f"a host would drop this frame of the core ({verdict.name}): session "
                                             f"{fr.session_id}, counter {fr.counter} ({msg})")
                self._check_numbering(fr.seq, msg, link)
                hal.out.append(Out(self.t_us // 1000, channel, raw, fr, msg, link))
                if channel == "send" and isinstance(msg, proto.Event):
                    self._events.append(msg)
                    if msg.event == proto.EventKind.STATE_CHANGED:
                        self._transitions.append((msg.time_ms, msg.state_from, msg.state_to, msg.arg))
                elif channel == "send" and isinstance(msg, proto.Telemetry):
                    self._telemetry.append(msg)
            return out

        def accept_peer(_ctx):
            hal.accept_peer_calls += 1

        def overruns(_ctx):
            return hal.tick_overruns

        def spindle_read(_ctx, out):
            sp = self.spindle
            sp.advance(self.t_us)
            if not sp.answering:
                return False
            out[0] = sp.reading()
            return True

        def spindle_write(_ctx, raw):
            self.spindle.advance(self.t_us)
            self.spindle.write(int(raw))

        # Keep every CFUNCTYPE object alive as long as the harness.
        self._callbacks = [_EncoderRead(encoder_read), _BatteryRead(battery_read), _EscWrite(esc_write),
                           _LinkRecv(link_recv), _LinkOut(record("reply")), _LinkAccept(accept_peer),
                           _LinkOut(record("send")), _Overruns(overruns)]
        enc_r, bat_r, esc_w, recv, reply, accept, send, ovr = self._callbacks
        self._esc = _HalEsc(None, esc_w)
        self._enc = _HalEncoder(None, enc_r)
        self._bat = _HalBattery(None, bat_r)
        self._link = _HalLink(None, recv, reply, accept, send)
        self._sched = _HalScheduler(None, ovr)
        self._hal = _Hal(ctypes.pointer(self._esc), ctypes.pointer(self._enc), ctypes.pointer(self._bat),
                         ctypes.pointer(self._link), ctypes.pointer(self._sched))
        # the flash: a record with TEST_KEY, as if provisioned over USB serial; writes are kept in self.flash
        self.flash: bytes | None = None

        def config_load(_ctx, buf, length):
            if self.flash is not None:
                ctypes.memmove(buf, self.flash, min(length, len(self.flash)))
                return len(self.flash) == length
            self.lib.rw_config_defaults(buf)
            self.lib.rw_config_set_params(buf, self.core)  # the parameters set before the first tick
            if self._provisioned:
                self.lib.rw_config_set_key(buf, TEST_KEY)
            return True

        def config_save(_ctx, buf, length):
            self.flash = ctypes.string_at(buf, length)
            return True

        def request_save(_ctx, buf, length):
            if self._save_status == CONFIG_SAVE_BUSY:
                return False
            self.flash_save_requests += 1
            self._save_pending = ctypes.string_at(buf, length)
            self._save_countdown = self.flash_save_ticks
            self._save_status = CONFIG_SAVE_BUSY
            self._service_save(in_request=True)
            return True

        def save_status(_ctx):
            return self._save_status

        self._config_cbs = [_ConfigLoad(config_load), _ConfigSave(config_save), _ConfigSave(request_save),
                            _ConfigSaveStatus(save_status)]
        self._config = _HalConfigStore(None, *self._config_cbs)
        self._hal.config = ctypes.pointer(self._config)
        if self._serial:
            self._serial_cbs = [_LinkRecv(lambda ctx, buf, cap: link_recv(ctx, buf, cap, hal.serial_inbox)),
                                _LinkOut(record("reply", "serial")), _LinkAccept(lambda _ctx: None),
                                _LinkOut(record("send", "serial"))]
            self._serial_link = _HalLink(None, *self._serial_cbs)
            self._hal.serial = ctypes.cast(ctypes.pointer(self._serial_link), c_void_p)
        self.counter = 0
        if self.spindle is not None:
            self._callbacks += [_SpindleRead(spindle_read), _SpindleWrite(spindle_write)]
            self._spin = _HalSpindle(None, self._callbacks[-2], self._callbacks[-1])
            self._hal.spindle = ctypes.pointer(self._spin)

    def expect_commit(self, key: bytes | None) -> None:
        """A PROVISION_COMMIT reaches the core on the next tick: from then on its signed frames may carry a new
        session (a new epoch) and, if one was staged, a new key (None: the key stays)."""
        self._commit_key = self._host_view.key if key is None else bytes(key)

    def _check_numbering(self, seq: int, msg: proto.Message, link: str = "wifi") -> None:
        """Frames are numbered as they leave (a queued one when its signing begins): the next seq, or one more
        when replies overtake the frames being signed, whose seq comes later. Never a repeat, never a third hole:
        at most two frames are being signed (rw_core.h: state.signers)."""
        holes = self._seq_holes[link]
        ahead = (seq - self._max_seq[link]) % 65536
        if 1 <= ahead <= 1 + MAX_FRAMES_SIGNING - len(holes):
            for skipped in range(1, ahead):
                holes.add((self._max_seq[link] + skipped) % 65536)
            self._max_seq[link] = seq
        elif seq in holes:
            holes.discard(seq)
        else:
            raise AssertionError(f"the core's seq {seq} after {self._max_seq[link]} on {link} (holes {holes}): {msg}")

    def _check_canary(self) -> None:
        if ctypes.string_at(self.core + self.size, len(_CANARY)) != _CANARY:
            raise AssertionError("rw_core wrote past rw_core_sizeof() bytes")

    # -- time --
    @property
    def now_us(self) -> int:
        """The tick clock value of the latest tick (wraps at 2^32)."""
        return (self.clock_offset_us + self.t_us) % U32

    @property
    def t_ms(self) -> int:
        return self.t_us // 1000

    def tick(self, dt_us: int = TICK_US) -> None:
        """One control tick dt_us after the previous one (the first tick is at t_us = 0)."""
        if self.started:
            self.t_us += int(dt_us)
            self.encoder.advance(self.t_us, int(dt_us))
        self.started = True
        if self.encoder.speed_mps > 0.0 or self.encoder.counts > 0:
            self.hal.encoder_counts = (self.encoder_count_offset + self.encoder.counts) % U32
            self.hal.encoder_last_edge_us = (self.clock_offset_us + round(self.encoder.last_edge_t_us)) % U32
        self.lib.rw_core_tick(self.core, ctypes.byref(self._hal), self.now_us)
        self._service_save(in_request=False)
        self._check_canary()
        if self._callback_errors:
            raise self._callback_errors.pop(0)

    def _service_save(self, *, in_request: bool) -> None:
        """The store's background side: a requested write is done flash_save_ticks ticks after its request."""
        if self._save_status != CONFIG_SAVE_BUSY:
            return
        if not in_request:
            self._save_countdown -= 1
        if self._save_countdown <= 0:
            if self.flash_save_fails:
                self._save_status = CONFIG_SAVE_FAILED
                return
            self.flash = self._save_pending
            self._save_status = CONFIG_SAVE_DONE

    def run_ms(self, ms: int) -> None:
        for _ in range(int(ms)):
            self.tick()

    def run_until(self, predicate, *, max_ms: int, what: str) -> None:
        """Ticks until predicate() is true; AssertionError naming `what` after max_ms."""
        for _ in range(int(max_ms)):
            if predicate():
                return
            self.tick()
        if not predicate():
            raise AssertionError(f"{what}: not reached within {max_ms} ms (t = {self.t_ms} ms)")

    # -- link input --
    def next_seq(self) -> int:
        self.seq = (self.seq + 1) & 0xFFFF
        return self.seq

    def frame(self, msg: proto.Message, *, seq: int | None = None, signed: bool = True) -> bytes:
        """msg framed as a host sends it over WiFi: signed with TEST_KEY for the session, counter + 1."""
        seq = self.next_seq() if seq is None else seq
        if not signed:
            return proto.encode_frame(msg, seq)
        self.counter += 1
        return proto.encode_frame(msg, seq, key=TEST_KEY, session_id=SESSION_ID, counter=self.counter)

    def queue(self, data: bytes) -> bytes:
        """Queues one datagram for the link (received on a coming tick); returns it."""
        self.hal.inbox.append(bytes(data))
        return bytes(data)

    def command(self, msg: proto.Message | bytes, *, seq: int | None = None) -> proto.Message:
        """Queues msg (a Message, or raw bytes), runs one tick and returns the reply of that tick."""
        data = msg if isinstance(msg, (bytes, bytearray)) else self.frame(msg, seq=seq)
        before = len(self.hal.out)
        self.queue(data)
        self.tick()
        replies = [o for o in self.hal.out[before:] if o.channel == "reply"]
        if len(replies) != 1:
            raise AssertionError(f"expected exactly one reply in the tick, got {len(replies)}")
        return replies[0].msg

    def heartbeat(self) -> None:
        self.queue(self.frame(proto.Heartbeat(self.t_ms)))

    def set_param(self, name: str, value: float) -> None:
        """rw_core_set_param by parameter name (same checks as PARAM_SET)."""
        spec = proto.PARAMS_BY_NAME[name]
        result = self.lib.rw_core_set_param(self.core, spec.id, value)
        if result != 0:
            raise ValueError(f"set_param({name}={value}): refused with {proto.NackReason(result).name}")
        if name == "wheel_radius_m":
            self.encoder.wheel_radius_m = value
        if name == "encoder_counts_per_rev":
            self.encoder.counts_per_rev = int(value)

    # -- outputs --
    def sent(self, cls: type | None = None, *, since: int = 0) -> list[Out]:
        """Frames sent to the peer (not replies), optionally of one message class, from index since."""
        return [o for o in self.hal.out[since:] if o.channel == "send" and (cls is None or isinstance(o.msg, cls))]

    def replies(self, *, since: int = 0) -> list[Out]:
        return [o for o in self.hal.out[since:] if o.channel == "reply"]

    def events(self, kind: proto.EventKind | None = None) -> list[proto.Event]:
        """EVENT messages sent so far, optionally of one kind."""
        return [e for e in self._events if kind is None or e.event == kind]

    def transitions(self) -> list[tuple[int, int, int, int]]:
        """(time_ms, from, to, cause) of every STATE_CHANGED event sent so far."""
        return list(self._transitions)

    def telemetry(self) -> list[proto.Telemetry]:
        """TELEMETRY messages sent so far (the live list: it grows with later ticks; do not modify)."""
        return self._telemetry

    def drain(self, ticks: int = 12, *, max_ms: int = 200) -> None:
        """Runs `ticks` ticks with heartbeats withheld, then more until every queued frame has gone out (the
        core signs on idle ticks, so a frame leaves a few ticks after it was queued); AssertionError if the
        queue has not emptied within max_ms."""
        for _ in range(ticks):
            self.tick()
        for _ in range(int(max_ms)):
            if self.tx_idle:
                return
            self.tick()
        raise AssertionError(f"frames still queued after {max_ms} ms (t = {self.t_ms} ms)")

    @property
    def tx_idle(self) -> bool:
        """Nothing queued and nothing being signed in the core."""
        return bool(self.lib.rw_core_tx_idle(self.core))

    @property
    def state(self) -> proto.State:
        """The state the peer has been told last (latest STATE_CHANGED event sent; DISARMED before any)."""
        tr = self._transitions
        return proto.State(tr[-1][2]) if tr else proto.State.DISARMED

    @property
    def pulse_us(self) -> int:
        return self.hal.pulses_us[-1]

    # -- scenario steps --
    def boot_and_arm(self) -> None:
        """Ticks through the arming hold, then ARM; the ARM must be ACKed."""
        self.tick()
        hold_ms = round(self.get_param_value("arm_hold_s") * 1000)
        while self.t_ms <= hold_ms:
            self.tick()
        reply = self.command(proto.Arm())
        if not isinstance(reply, proto.Ack):
            raise AssertionError(f"ARM after the hold: expected ACK, got {reply}")

    def get_param_value(self, name: str) -> float:
        """Reads a parameter straight from rw_core.params (the first member: float value[RW_PARAM_COUNT])."""
        spec = proto.PARAMS_BY_NAME[name]
        return ctypes.c_float.from_address(self.core + 4 * spec.id).value

    def spin_to_airborne(self, *, target_mmps: int = 4000, max_ms: int = 2000) -> None:
        """From ARMED: SET_ROPE_SPEED, then the rope follows the setpoint (encoder at the telemetry
        setpoint, a perfect plant) until the core reports AIRBORNE; heartbeats every 100 ms."""
        reply = self.command(proto.SetRopeSpeed(target_mmps))
        if not isinstance(reply, proto.Ack):
            raise AssertionError(f"SET_ROPE_SPEED {target_mmps}: expected ACK, got {reply}")
        self.follow_setpoint(until=lambda: self.state == proto.State.AIRBORNE, max_ms=max_ms, what="AIRBORNE")

    def follow_setpoint(self, *, until, max_ms: int, what: str, heartbeat_ms: int | None = 100) -> None:
        """Ticks with the rope speed tracking the last telemetry setpoint (a perfect plant) until
        until() is true; a heartbeat every heartbeat_ms (None: the host stays silent)."""
        for _ in range(int(max_ms)):
            if until():
                return
            tel = self.telemetry()
            if tel:
                self.encoder.speed_mps = tel[-1].rope_speed_setpoint_mmps / 1000.0
            if heartbeat_ms is not None and self.t_ms % heartbeat_ms == 0:
                self.heartbeat()
            self.tick()
        if not until():
            raise AssertionError(f"{what}: not reached within {max_ms} ms (t = {self.t_ms} ms)")


# ---- Helpers for raw (possibly malformed) frames -------------------------------------------------------

def raw_frame(msg_id: int, seq: int, payload: bytes, *, crc_extra: int | None = None, version: int = proto.PROTOCOL_VERSION,
              flags: int = 0, magic: int = proto.MAGIC) -> bytes:
    """A frame built byte by byte; the checksum uses crc_extra (default: the message's own, 0 if unknown)."""
    if crc_extra is None:
        cls = proto.MESSAGES.get(msg_id)
        crc_extra = cls.CRC_EXTRA if cls is not None else 0
    body = bytes([magic, version, flags, msg_id]) + seq.to_bytes(2, "little") + bytes([len(payload) & 0xFF]) + payload
    return body + proto.checksum(body[1:], crc_extra).to_bytes(2, "little")


def telemetry_without(tel: proto.Telemetry, *names: str) -> dict:
    """The telemetry fields as a dict, without the named ones."""
    return {f.name: getattr(tel, f.name) for f in tel.FIELDS if f.name not in names}
