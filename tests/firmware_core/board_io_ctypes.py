"""ctypes bindings of the core modules between the board's control tick and its background loop:
rw_spindle_exchange (the split spindle transaction), rw_frame_queue (frames between the tick and the
background loop) and rw_wifi_supervisor (the WiFi connection policy).

The Structure classes mirror firmware/core/rw_spindle_exchange.h, rw_frame_queue.h and rw_wifi_supervisor.h
field for field (same order, same types); change both together. Objects are held with the canary block of
rw_core_ctypes, so a mirror smaller than the C struct fails loudly.
"""

from __future__ import annotations

import ctypes
from ctypes import c_bool, c_int, c_size_t, c_uint8, c_uint16, c_uint32, c_void_p
from enum import IntEnum

from rw_core_ctypes import _Guarded
from spindle_ctypes import SpindleReading

MAX_FRAME_LEN = 93  # RW_MAX_FRAME_LEN (generated protocol header)
QUEUE_SLOTS = 4  # RW_FRAME_QUEUE_SLOTS
OVERSIZE = MAX_FRAME_LEN + 1  # RW_FRAME_QUEUE_OVERSIZE


class JobKind(IntEnum):
    """rw_spindle_job_kind."""

    NONE = 0
    WRITE = 1
    READ = 2


class SpindleJob(ctypes.Structure):
    _fields_ = [("kind", c_uint8), ("moving_speed_raw", c_uint16), ("seq", c_uint32)]


class SpindleExchangeCounters(ctypes.Structure):
    _fields_ = [(name, c_uint32) for name in ("requests", "taken", "missing", "late", "reads_ok", "reads_failed",
                                              "writes_ok", "writes_failed")]


class SpindleExchangeStruct(ctypes.Structure):
    _fields_ = [("post_seq", c_uint32), ("post_raw", c_uint16), ("request_seq", c_uint32),
                ("taken_reading_seq", c_uint32), ("written_seq", c_uint32), ("served_seq", c_uint32),
                ("reading_seq", c_uint32), ("reading", SpindleReading), ("counters", SpindleExchangeCounters)]


class FrameQueueSlot(ctypes.Structure):
    _fields_ = [("addr", c_uint32), ("port", c_uint16), ("len", c_uint16), ("bytes", c_uint8 * MAX_FRAME_LEN)]


class FrameQueueStruct(ctypes.Structure):
    _fields_ = [("slots", FrameQueueSlot * QUEUE_SLOTS), ("head", c_uint32), ("tail", c_uint32),
                ("pushed", c_uint32), ("dropped", c_uint32), ("oversize", c_uint32), ("high_water", c_uint32)]


class WifiState(IntEnum):
    """rw_wifi_state."""

    NOT_PROVISIONED = 0
    NO_MODULE = 1
    CONNECTING = 2
    UP = 3


class WifiAction(IntEnum):
    """rw_wifi_action."""

    NOTHING = 0
    POLL_STATUS = 1
    START_CONNECT = 2
    OPEN_SOCKET = 3
    CLOSE_SOCKET = 4
    IO = 5


class WifiSupervisorConfig(ctypes.Structure):
    _fields_ = [("status_poll_ms", c_uint32), ("reconnect_interval_ms", c_uint32), ("module_hung_ms", c_uint32)]


class WifiSupervisorCounters(ctypes.Structure):
    _fields_ = [(name, c_uint32) for name in ("polls", "connects", "losses", "attempts", "deferred", "module_busy",
                                              "module_hangs")]


class WifiSupervisorStruct(ctypes.Structure):
    _fields_ = [("cfg", WifiSupervisorConfig), ("state", c_uint8), ("associated", c_bool),
                ("close_pending", c_bool), ("deferring", c_bool), ("busy", c_bool), ("busy_since_ms", c_uint32),
                ("last_poll_ms", c_uint32), ("last_attempt_ms", c_uint32), ("counters", WifiSupervisorCounters)]


def declare(lib: ctypes.CDLL) -> ctypes.CDLL:
    """Declare the signatures used here on the loaded core library; returns it."""
    p = c_void_p
    sigs = {
        "rw_spindle_exchange_init": (None, [p]),
        "rw_spindle_exchange_take": (c_bool, [p, ctypes.POINTER(SpindleReading)]),
        "rw_spindle_exchange_post": (None, [p, c_uint16]),
        "rw_spindle_exchange_next_job": (SpindleJob, [p]),
        "rw_spindle_exchange_write_done": (None, [p, ctypes.POINTER(SpindleJob), c_bool]),
        "rw_spindle_exchange_read_done": (None, [p, ctypes.POINTER(SpindleJob), ctypes.POINTER(SpindleReading)]),
        "rw_frame_queue_init": (None, [p]),
        "rw_frame_queue_push": (c_bool, [p, ctypes.c_char_p, c_size_t, c_uint32, c_uint16]),
        "rw_frame_queue_reserve": (ctypes.POINTER(FrameQueueSlot), [p]),
        "rw_frame_queue_publish": (None, [p]),
        "rw_frame_queue_peek": (ctypes.POINTER(FrameQueueSlot), [p]),
        "rw_frame_queue_release": (None, [p]),
        "rw_wifi_supervisor_config_defaults": (None, [ctypes.POINTER(WifiSupervisorConfig)]),
        "rw_wifi_supervisor_init": (None, [p, ctypes.POINTER(WifiSupervisorConfig), c_int, c_uint32]),
        "rw_wifi_supervisor_restart": (None, [p, c_bool, c_uint32]),
        "rw_wifi_supervisor_step": (c_int, [p, c_uint32, c_bool, c_bool]),
        "rw_wifi_supervisor_status": (None, [p, c_uint32, c_bool]),
        "rw_wifi_supervisor_socket": (None, [p, c_bool]),
    }
    for name, (res, args) in sigs.items():
        fn = getattr(lib, name)
        fn.restype = res
        fn.argtypes = args
    return lib


class SpindleExchange(_Guarded):
    """The split spindle transaction: tick side take/post, bus side next_job/write_done/read_done."""

    struct_type = SpindleExchangeStruct

    def __init__(self, lib: ctypes.CDLL) -> None:
        super().__init__(declare(lib))
        self._call("rw_spindle_exchange_init")

    # tick side
    def take(self) -> SpindleReading | None:
        out = SpindleReading()
        fresh = self._call("rw_spindle_exchange_take", ctypes.byref(out))
        return out if fresh else None

    def post(self, moving_speed_raw: int) -> None:
        if not 0 <= moving_speed_raw <= 2047:
            raise ValueError(f"moving_speed_raw: expected 0..2047, got {moving_speed_raw!r}")
        self._call("rw_spindle_exchange_post", moving_speed_raw)

    # bus side
    def next_job(self) -> SpindleJob:
        return self._call("rw_spindle_exchange_next_job")

    def write_done(self, job: SpindleJob, *, answered: bool) -> None:
        self._call("rw_spindle_exchange_write_done", ctypes.byref(job), answered)

    def read_done(self, job: SpindleJob, reading: SpindleReading | None) -> None:
        self._call("rw_spindle_exchange_read_done", ctypes.byref(job),
                   None if reading is None else ctypes.byref(reading))

    @property
    def counters(self) -> SpindleExchangeCounters:
        return self.obj.counters


class FrameQueue(_Guarded):
    """One producer, one consumer queue of frames with an address and port."""

    struct_type = FrameQueueStruct

    def __init__(self, lib: ctypes.CDLL) -> None:
        super().__init__(declare(lib))
        self._call("rw_frame_queue_init")

    def push(self, frame: bytes, *, addr: int = 0, port: int = 0) -> bool:
        return self._call("rw_frame_queue_push", frame, len(frame), addr, port)

    def reserve(self):  # noqa: ANN201 - a ctypes pointer to the slot, or None
        slot = self._call("rw_frame_queue_reserve")
        return slot.contents if slot else None

    def publish(self) -> None:
        self._call("rw_frame_queue_publish")

    def pop(self) -> tuple[bytes, int, int, int] | None:
        """(bytes, len field, addr, port) of the oldest frame, released; None when empty."""
        slot = self._call("rw_frame_queue_peek")
        if not slot:
            return None
        s = slot.contents
        n = min(s.len, MAX_FRAME_LEN)
        out = (bytes(s.bytes[:n]), s.len, s.addr, s.port)
        self._call("rw_frame_queue_release")
        return out

    @property
    def count(self) -> int:
        return (self.obj.head - self.obj.tail) & 0xFFFF_FFFF


class WifiSupervisor(_Guarded):
    """The WiFi connection policy; times in milliseconds."""

    struct_type = WifiSupervisorStruct

    def __init__(self, lib: ctypes.CDLL, *, state: WifiState, now_ms: int = 0, **cfg: int) -> None:
        super().__init__(declare(lib))
        config = WifiSupervisorConfig()
        self.lib.rw_wifi_supervisor_config_defaults(ctypes.byref(config))
        for name, value in cfg.items():
            if name not in dict(WifiSupervisorConfig._fields_):
                raise ValueError(f"cfg: expected fields of rw_wifi_supervisor_config, got {name!r}")
            setattr(config, name, value)
        self._call("rw_wifi_supervisor_init", ctypes.byref(config), int(state), now_ms)

    def step(self, now_ms: int, *, module_ready: bool = True, rope_down: bool = True) -> WifiAction:
        return WifiAction(self._call("rw_wifi_supervisor_step", now_ms, module_ready, rope_down))

    def status(self, now_ms: int, *, connected: bool) -> None:
        self._call("rw_wifi_supervisor_status", now_ms, connected)

    def socket(self, *, opened: bool) -> None:
        self._call("rw_wifi_supervisor_socket", opened)

    def restart(self, now_ms: int, *, provisioned: bool) -> None:
        self._call("rw_wifi_supervisor_restart", provisioned, now_ms)

    @property
    def state(self) -> WifiState:
        return WifiState(self.obj.state)

    @property
    def counters(self) -> WifiSupervisorCounters:
        return self.obj.counters
