"""A scripted UDP peer on 127.0.0.1 that speaks the wire protocol like the device's link layer.

It is a test double for the client side only (retries, duplicates, NACK reasons, silence): it keeps a
duplicate cache keyed by (seq, frame bytes), executes each new command once, and can be told to
drop replies, answer scripted NACKs, or stay silent. The rope "physics" is a ramp, nothing more;
the real device behaviour is tested against the SIL firmware elsewhere.
"""

from __future__ import annotations

import math
import select
import socket
import struct
import threading
import time
from collections import defaultdict, deque

from robowrangler.protocol import generated as gen
from robowrangler.protocol.generated import MsgId, NackReason, PARAMS, State

EVENT_MSG = gen.Event
EV_STATE_CHANGED, EV_PARAM_CHANGED, EV_ARMING_HOLD_DONE = 1, 5, 6
CAUSE_COMMAND, CAUSE_SPEED_REACHED, CAUSE_LOAD_SECURED, CAUSE_STROKE_END = 0, 1, 6, 7
EV_SPINDLE_HOMED, EV_SPINDLE_TARGET_REACHED = 7, 8
P_GUIDE_MIN_MM, P_GUIDE_MAX_MM, P_RELEASE_MM = 18, 19, 28
TRANSIT_REASONS = {int(r) for r in NackReason if r <= NackReason.UNSUPPORTED_FLAGS and r != NackReason.UNKNOWN_MESSAGE}


def make(cls: type[gen.Message], **fields: float) -> gen.Message:
    """A message with the given fields and every other field 0: stays valid when the schema grows."""
    unknown = set(fields) - {f.name for f in cls.FIELDS}
    if unknown:
        raise TypeError(f"{cls.NAME} has no field(s) {sorted(unknown)}")
    return cls(**{f.name: fields.get(f.name, 0) for f in cls.FIELDS})


def _f32(x: float) -> float:
    return struct.unpack("<f", struct.pack("<f", x))[0]


class ScriptedDevice:
    """Run with `with ScriptedDevice(...) as dev:`; `dev.url` is the udp:// URL to connect to.

    Knobs (set before or while running):
        silent: answer no command (telemetry still flows unless telemetry_hz is 0).
        drop_replies[msg_id]: drop this many of the next ACKs for that command (it still executes).
        drop_param_values: drop this many of the next PARAM_VALUE messages.
        nack_script[msg_id]: list of (NackReason, detail) answered to the next new commands of that id
            (frame-level reasons such as BAD_CHECKSUM play a frame damaged on the way: not cached).
        arm_hold_s: ARM is refused with NOT_READY this long after start.
        drop_event_seqs: event_seq values whose EVENT is not sent (to test lost-event counting).
        guide_speed_mps, object_at_m: spindle speed; guide position where RETRACT secures a load (None: none).
        spindle_unavailable: spindle commands are refused SPINDLE_UNAVAILABLE.
        key, session_id: with a key, unsigned or wrongly signed frames (but HELLO) are dropped and counted
            in auth_failed, other sessions or non-growing counters in replayed; the device signs its frames.
        stale_param_values: PARAM_VALUEs with these values are sent around each parameter answer, as late
            duplicates of older answers would arrive (before the ACK; for PARAM_SET also after it).
    Records: received (frames with msg), executed (msg name, seq) per executed command,
    duplicates (retransmissions answered from the cache).
    """

    def __init__(self, *, telemetry_hz: float = 50.0, arm_hold_s: float = 0.0, state: State = State.DISARMED,
                 ramp_mps2: float = 100.0, key: bytes | None = None, session_id: int = 7) -> None:
        self._sock = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
        self._sock.bind(("127.0.0.1", 0))
        self.port = self._sock.getsockname()[1]
        self.url = f"udp://127.0.0.1:{self.port}"
        self.telemetry_hz = telemetry_hz
        self.arm_hold_s = arm_hold_s
        self.state = state
        self.ramp_mps2 = ramp_mps2
        self.silent = False
        self.drop_replies: dict[int, int] = defaultdict(int)
        self.drop_param_values = 0
        self.nack_script: dict[int, list[tuple[NackReason, int]]] = defaultdict(list)
        self.drop_event_seqs: set[int] = set()
        self.stale_param_values: list[float] = []
        # link security: with a key every frame but HELLO must be signed for session_id with a growing counter
        self.key = key
        self.session_id = session_id
        self.auth_failed = 0
        self.replayed = 0
        self._last_counter = 0
        self._counter = 0
        # spindle: the guide moves at guide_speed_mps; a retract secures a load when it reaches object_at_m
        self.guide_speed_mps = 1.5
        self.object_at_m: float | None = None
        self.spindle_unavailable = False
        self.homed = False
        self.homing = False
        self.guide_m = 0.05
        self.guide_target_m = 0.05
        self.grasp_pending = False
        self.load_permille = 0
        self.params = {p.id: _f32(p.default) for p in PARAMS}
        self.received: list[tuple[gen.Frame, gen.Message]] = []
        self.executed: list[tuple[str, int]] = []
        self.duplicates = 0
        self.bad_frames = 0
        self.nacks_sent = 0
        self.target_mps = 0.0
        self.setpoint_mps = 0.0
        self._cache: deque[tuple[int, int, list[bytes]]] = deque(maxlen=8)
        self._host = None
        self._seq = 0
        self._event_seq = 0
        self._last_host_frame_s: float | None = None
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._run, name="scripted-device", daemon=True)
        self._start_s = time.monotonic()
        self.lock = threading.Lock()

    # ------------------------------------------------------------------ lifecycle
    def __enter__(self) -> ScriptedDevice:
        self._start_s = time.monotonic()
        self._thread.start()
        return self

    def __exit__(self, *exc: object) -> None:
        self._stop.set()
        self._thread.join(timeout=2.0)
        self._sock.close()

    def halt(self) -> None:
        """Stop the device loop: no telemetry, no answers (a board that lost power)."""
        self._stop.set()
        self._thread.join(timeout=2.0)

    def send_raw(self, data: bytes) -> None:
        """Send arbitrary bytes to the host that last sent a frame (bad-data tests)."""
        with self.lock:
            if self._host is not None:
                self._sock.sendto(data, self._host)

    def executed_names(self) -> list[str]:
        with self.lock:
            return [name for name, _ in self.executed]

    def received_commands(self, msg_id: int) -> list[tuple[int, bytes]]:
        """(seq, raw frame bytes re-encoded) for every received frame of msg_id, in order."""
        with self.lock:
            return [(f.seq, gen.encode_frame(m, f.seq)) for f, m in self.received if f.msg_id == msg_id]

    # ------------------------------------------------------------------ loop
    def _run(self) -> None:
        period_s = 1.0 / self.telemetry_hz if self.telemetry_hz > 0 else None
        next_tick = time.monotonic()
        while not self._stop.is_set():
            timeout = 0.05 if period_s is None else max(0.0, next_tick - time.monotonic())
            ready, _, _ = select.select([self._sock], [], [], timeout)
            if ready:
                try:
                    data, addr = self._sock.recvfrom(2048)
                except OSError:
                    continue
                with self.lock:
                    self._on_datagram(data, addr)
            if period_s is not None and time.monotonic() >= next_tick:
                next_tick += period_s
                with self.lock:
                    self._tick(period_s)

    def _send(self, msg: gen.Message) -> bytes:
        if self.key is None:
            frame = gen.encode_frame(msg, self._seq)
        else:
            self._counter += 1
            frame = gen.encode_frame(msg, self._seq, key=self.key, session_id=self.session_id, counter=self._counter)
        self._seq = (self._seq + 1) & 0xFFFF
        return frame

    def _emit(self, frames: list[bytes]) -> None:
        if self._host is not None:
            for f in frames:
                self._sock.sendto(f, self._host)
                if f[3] == MsgId.TELEMETRY:
                    self._last_telemetry_frame = f

    def last_sent_telemetry(self) -> bytes | None:
        """The bytes of the last TELEMETRY sent (to replay it at the host)."""
        with self.lock:
            return getattr(self, "_last_telemetry_frame", None)

    def _on_datagram(self, data: bytes, addr) -> None:
        try:
            frame, msg = gen.decode_message(data)
        except gen.FrameError as err:
            self.bad_frames += 1
            self._host = addr
            self.nacks_sent += 1
            self._emit([self._send(gen.Nack(err.msg_id if err.msg_id is not None else 255, err.seq or 0,
                                            err.reason, self.state, 0))])
            return
        if frame.msg_id == MsgId.HELLO:  # unsigned, from anyone; does not make the sender the telemetry peer
            self.received.append((frame, msg))
            info = gen.SessionInfo(msg.host_nonce, self.session_id, int(self.key is not None), gen.SCHEMA_HASH)
            self._sock.sendto(self._send(info), addr)
            return
        if self.key is not None:
            if not frame.signed or not gen.tag_valid(frame, self.key):
                self.auth_failed += 1
                return
            if frame.session_id != self.session_id or frame.counter <= self._last_counter:
                self.replayed += 1
                return
            self._last_counter = frame.counter
        self._host = addr
        self._last_host_frame_s = time.monotonic()
        self.received.append((frame, msg))
        if msg.KIND != gen.MsgKind.COMMAND or self.silent:
            return
        for seq, raw, replies in self._cache:
            if seq == frame.seq and raw == frame.checksum:  # same seq and checksum: a retransmission
                self.duplicates += 1
                # the same verdict, framed afresh (new seq, and counter when signing) as the firmware does it
                self._deliver(frame.msg_id, [self._send(gen.decode_message(r)[1]) for r in replies])
                return
        replies = self._execute(frame, msg)
        answers = [r for r in replies if r[3] != MsgId.EVENT]  # a retransmission is answered, events are not repeated
        if not (answers and answers[0][3] == MsgId.NACK and answers[0][10] in TRANSIT_REASONS):
            self._cache.append((frame.seq, frame.checksum, answers))  # a damaged frame's bytes are never seen again
        self._deliver(frame.msg_id, replies)

    def _deliver(self, cmd_msg_id: int, replies: list[bytes]) -> None:
        """Send replies except the ones the script says to drop."""
        sent = []
        for r in replies:
            if r[3] == MsgId.ACK and self.drop_replies.get(cmd_msg_id, 0) > 0:
                self.drop_replies[cmd_msg_id] -= 1
                continue
            if r[3] == MsgId.PARAM_VALUE and self.drop_param_values > 0:
                self.drop_param_values -= 1
                continue
            sent.append(r)
        self._emit(sent)

    def _nack(self, frame: gen.Frame, reason: NackReason, detail: int = 0) -> list[bytes]:
        self.nacks_sent += 1
        return [self._send(gen.Nack(frame.msg_id, frame.seq, reason, self.state, detail))]

    def _ack(self, frame: gen.Frame) -> bytes:
        return self._send(gen.Ack(frame.msg_id, frame.seq, self.state))

    def _set_state(self, new: State, cause: int) -> list[bytes]:
        old, self.state = self.state, new
        return self._event(EV_STATE_CHANGED, old, new, cause)

    def _event(self, kind: int, old: State, new: State, arg: int) -> list[bytes]:
        seq = self._event_seq
        self._event_seq = (seq + 1) & 0xFFFF
        if seq in self.drop_event_seqs:
            return []
        return [self._send(make(EVENT_MSG, time_ms=self._time_ms(), event_seq=seq, event=kind, state_from=old,
                                state_to=new, arg=arg))]

    def _time_ms(self) -> int:
        return int((time.monotonic() - self._start_s) * 1000) & 0xFFFFFFFF

    def _guard_mps(self) -> float:
        return self.params[0] * self.params[1]

    def _execute(self, frame: gen.Frame, msg: gen.Message) -> list[bytes]:
        script = self.nack_script.get(frame.msg_id)
        if script:
            reason, detail = script.pop(0)
            return self._nack(frame, reason, detail)
        mid, s = frame.msg_id, self.state
        if mid == MsgId.ARM:
            if time.monotonic() - self._start_s < self.arm_hold_s:
                return self._nack(frame, NackReason.NOT_READY)
            if s != State.DISARMED:
                return self._nack(frame, NackReason.BAD_STATE)
            events = self._set_state(State.ARMED, CAUSE_COMMAND)
        elif mid == MsgId.DISARM:
            if s not in (State.ARMED, State.FAULT, State.ESTOP):
                return self._nack(frame, NackReason.BAD_STATE)
            events = self._set_state(State.DISARMED, CAUSE_COMMAND)
        elif mid == MsgId.SET_ROPE_SPEED:
            v = msg.rope_speed_mmps / 1000.0
            max_mps = self.params[10]
            if s not in (State.ARMED, State.SPINUP, State.AIRBORNE):
                return self._nack(frame, NackReason.BAD_STATE)
            if v <= 0:
                return self._nack(frame, NackReason.OUT_OF_RANGE, 0)
            if v > max_mps:
                return self._nack(frame, NackReason.OUT_OF_RANGE, round(max_mps * 1000))
            if s == State.AIRBORNE and v < self._guard_mps():
                return self._nack(frame, NackReason.BELOW_TOV_GUARD, round(self._guard_mps() * 1000))
            self.target_mps = v
            events = self._set_state(State.SPINUP, CAUSE_COMMAND) if s == State.ARMED else []
        elif mid == MsgId.SPINDOWN:
            if s not in (State.SPINUP, State.AIRBORNE, State.SPINDOWN):
                return self._nack(frame, NackReason.BAD_STATE)
            self.target_mps = 0.0
            events = self._set_state(State.SPINDOWN, CAUSE_COMMAND) if s != State.SPINDOWN else []
        elif mid == MsgId.ESTOP:
            self.target_mps = self.setpoint_mps = 0.0
            events = self._set_state(State.ESTOP, CAUSE_COMMAND) if s != State.ESTOP else []
        elif mid in (MsgId.PARAM_GET, MsgId.PARAM_SET):
            if msg.param_id not in self.params:
                return self._nack(frame, NackReason.UNKNOWN_PARAM, msg.param_id)
            spec = PARAMS[msg.param_id]
            events = []
            if mid == MsgId.PARAM_SET:
                if spec.locked and s != State.DISARMED:
                    return self._nack(frame, NackReason.PARAM_LOCKED)
                x = msg.value
                if math.isnan(x) or not spec.min <= x <= spec.max or (spec.integer and x != int(x)):
                    return self._nack(frame, NackReason.OUT_OF_RANGE)
                self.params[spec.id] = _f32(x)
                events = self._event(EV_PARAM_CHANGED, s, s, spec.id)
            self.executed.append((msg.NAME, frame.seq))
            stale = [self._send(gen.ParamValue(spec.id, v, len(PARAMS))) for v in self.stale_param_values]
            ack, value = self._ack(frame), self._send(gen.ParamValue(spec.id, self.params[spec.id], len(PARAMS)))
            if mid == MsgId.PARAM_SET:  # late duplicates of older answers on both sides of the ACK
                return stale + [ack] + stale + [value] + events
            return stale + [ack, value] + events
        elif mid in (MsgId.HOME, MsgId.SET_LOOP, MsgId.RELAX, MsgId.RETRACT, MsgId.GRASP, MsgId.RELEASE):
            refusal = self._spindle_refusal(mid, msg, s)
            if refusal is not None:
                return self._nack(frame, *refusal)
            events = []
            if mid == MsgId.HOME:
                self.homing, self.guide_target_m = True, -1.0  # towards the end stop, wherever it is
            elif mid == MsgId.SET_LOOP:
                self.guide_target_m = msg.guide_position_um / 1e6
            elif mid == MsgId.RELAX or mid == MsgId.GRASP:
                self.target_mps, self.grasp_pending = 0.0, mid == MsgId.GRASP
                events = self._set_state(State.RELAX, CAUSE_COMMAND)
            elif mid == MsgId.RETRACT:
                events = self._start_retract(CAUSE_COMMAND)
            elif mid == MsgId.RELEASE:
                self.guide_target_m = max(0.0, self.guide_m - self.params[P_RELEASE_MM] / 1000)
                self.load_permille = 0
                events = self._set_state(State.ARMED, CAUSE_COMMAND)
        else:
            return self._nack(frame, NackReason.NOT_A_COMMAND)
        self.executed.append((msg.NAME, frame.seq))
        return [self._ack(frame)] + events

    def _spindle_refusal(self, mid: int, msg: gen.Message, s: State) -> tuple[NackReason, int] | None:
        stopped = self.setpoint_mps == 0.0
        allowed = {
            MsgId.HOME: s in (State.DISARMED, State.ARMED) and stopped,
            MsgId.SET_LOOP: s in (State.ARMED, State.SPINUP, State.AIRBORNE),
            MsgId.RELAX: s in (State.SPINUP, State.AIRBORNE),
            MsgId.RETRACT: s == State.ARMED or (s == State.RELAX and stopped),
            MsgId.GRASP: s == State.AIRBORNE,
            MsgId.RELEASE: s == State.HOLD,
        }[mid]
        if not allowed:
            return NackReason.BAD_STATE, 0
        if mid in (MsgId.HOME, MsgId.SET_LOOP, MsgId.RETRACT, MsgId.GRASP) and self.spindle_unavailable:
            return NackReason.SPINDLE_UNAVAILABLE, 0x10
        if mid in (MsgId.SET_LOOP, MsgId.RETRACT, MsgId.GRASP) and not self.homed:
            return NackReason.NOT_HOMED, 0
        if mid == MsgId.SET_LOOP:
            lo_um, hi_um = round(self.params[P_GUIDE_MIN_MM] * 1000), round(self.params[P_GUIDE_MAX_MM] * 1000)
            if not lo_um <= msg.guide_position_um <= hi_um:
                return NackReason.OUT_OF_RANGE, lo_um if msg.guide_position_um < lo_um else hi_um
        return None

    def _start_retract(self, cause: int) -> list[bytes]:
        self.grasp_pending = False
        self.guide_target_m = self.params[P_GUIDE_MAX_MM] / 1000
        return self._set_state(State.RETRACT, cause)

    def _spindle_tick(self, dt_s: float) -> list[bytes]:
        out: list[bytes] = []
        if self.state == State.RELAX and self.grasp_pending and self.setpoint_mps == 0.0:
            out += self._start_retract(CAUSE_SPEED_REACHED)
        if self.state == State.HOLD:
            return out
        step = self.guide_speed_mps * dt_s
        before = self.guide_m
        self.guide_m += max(-step, min(step, self.guide_target_m - self.guide_m))
        if self.homing and self.guide_m <= 0.0:  # the end stop
            self.guide_m = self.guide_target_m = 0.0
            self.homed, self.homing = True, False
            out += self._event(EV_SPINDLE_HOMED, self.state, self.state, 1)
        elif self.state == State.RETRACT:
            if self.object_at_m is not None and self.guide_m >= self.object_at_m:
                self.guide_target_m, self.load_permille = self.guide_m, 150
                out += self._set_state(State.HOLD, CAUSE_LOAD_SECURED)
            elif self.guide_m >= self.guide_target_m:
                out += self._set_state(State.ARMED, CAUSE_STROKE_END)
        elif before != self.guide_m and self.guide_m == self.guide_target_m and self.homed:
            out += self._event(EV_SPINDLE_TARGET_REACHED, self.state, self.state, round(self.guide_m * 1e6))
        return out

    def _tick(self, dt_s: float) -> None:
        step = self.ramp_mps2 * dt_s
        self.setpoint_mps += max(-step, min(step, self.target_mps - self.setpoint_mps))
        out = []
        if self.state == State.SPINUP and self.setpoint_mps >= self._guard_mps():
            out += self._set_state(State.AIRBORNE, CAUSE_SPEED_REACHED)
        if self.state == State.SPINDOWN and self.setpoint_mps <= 0.0:
            out += self._set_state(State.ARMED, CAUSE_SPEED_REACHED)
        out += self._spindle_tick(dt_s)
        flags = (0x01 if self.homed else 0) | 0x02 | (0x08 if self.guide_m != self.guide_target_m else 0) | \
            (0x10 if self.homing else 0)
        age_ms = 65535 if self._last_host_frame_s is None else int((time.monotonic() - self._last_host_frame_s) * 1000)
        mmps = round(self.setpoint_mps * 1000)
        out.append(self._send(make(
            gen.Telemetry, time_ms=self._time_ms(), state=self.state, rope_speed_target_mmps=round(self.target_mps * 1000),
            rope_speed_setpoint_mmps=mmps, rope_speed_mmps=mmps,
            motor_rpm=round(self.setpoint_mps / (2 * math.pi * 0.015) * 60), esc_pulse_us=1000 + min(1000, mmps // 20),
            battery_mv=12600, heartbeat_age_ms=min(age_ms, 65535), rx_ok=len(self.received) & 0xFFFF,
            rx_bad=self.bad_frames & 0xFFFF, rx_duplicates=self.duplicates & 0xFFFF, nacks=self.nacks_sent & 0xFFFF,
            events=self._event_seq & 0xFFFF, guide_position_um=round(self.guide_m * 1e6),
            guide_target_um=round(max(self.guide_target_m, 0.0) * 1e6), spindle_load_permille=self.load_permille,
            spindle_flags=flags, rx_auth_failed=self.auth_failed & 0xFFFF, rx_replayed=self.replayed & 0xFFFF)))
        self._emit(out)
