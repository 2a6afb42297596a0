"""Soak: seeded random valid and invalid commands through an impaired, signed link, invariants checked every tick.

Lockstep and deterministic: a ScriptedHost talks to the SIL firmware through an ImpairmentProxy stepped by
simulated time (ImpairedLockstep); the link key derives from the seed. The host signs every frame and
retries a command like the Client does (same seq and payload, signed afresh with a new counter, every
ack_timeout_s or at once after a NACK saying the frame was damaged on the way, at most `retries` times). Besides malformed datagrams it also sends frames the device must
drop unanswered: commands unsigned or signed with another key, earlier frames again byte for byte, frames
signed for another session. Every tick the proxy's log gives the device-side truth (every frame the
firmware got, every frame it sent) and the invariants are checked:

* authentic and fresh only: the device's gate (link_gate, the protocol's rule) says, for every delivered
  datagram in the order the firmware reads it, whether it must be dropped unanswered (a wrong or missing
  tag; another session or a counter not above the last accepted: a network duplicate, a frame a newer one
  overtook, a replay); every TELEMETRY.rx_auth_failed and rx_replayed must equal the drops the firmware
  had read by the tick the sample was packed (one datagram a tick, in delivery order). Every frame the
  firmware sends verifies with the key.
* executed once: the firmware takes its datagrams in order, so each verdict (ACK/NACK) it sends belongs to
  the next delivered frame that gets one (not a heartbeat, HELLO or dropped frame); an accepted repeat of
  a command frame (same msg_id, seq, checksum: a host retransmission) must get the first verdict again,
  and every TELEMETRY.rx_duplicates must equal the repeats answered before it (a re-execution would not
  count); a verdict for a frame that had to be dropped is a violation; PARAM_CHANGED events = PARAM_SETs
  first accepted.
* the ToV guard: while the device reports AIRBORNE (latest telemetry or STATE_CHANGED, by sequence
  number) the setpoint is at or over tov x margin and the plant's rope speed is over ToV (the loop really
  flies); the plant speed under tov x margin is counted, not judged (a step down to the guard is judged
  by the step-down tests in test_soak.py); no LOOP_COLLAPSED (nothing loads the rope here); a
  HEARTBEAT_LOST comes within heartbeat_timeout_s + one tick.
* no crash: the firmware process answers every tick; plant speed and battery voltage stay finite.
* every gap accounted for: each sequence number the firmware used left it (no hole: its outbox dropped
  nothing) and reached the host exactly when the proxy delivered a clean copy of it; whatever the host
  missed, the proxy dropped or corrupted. The host keeps a frame only if it verifies and is fresher than
  the last it kept: its counts of replays (clean copies delivered after a newer frame), of tag failures
  (corrupted copies the checksum passed) and of decode errors must match the proxy's log.
"""

from __future__ import annotations

import bisect
import math
import time
from collections import Counter, deque
from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np

from robowrangler.client import TRANSIT_NACK_REASONS
from robowrangler.protocol import generated as gen
from robowrangler_sim.sil import SilError, SilSession
from robowrangler_sim.sil.impairment import ImpairedLockstep, ImpairmentConfig, ImpairmentProxy, LinkImpairment
from robowrangler_sim.sil.scripted_host import Received, ScriptedHost

from link_gate import DeviceGate, Fate, seeded_key
from link_ledger import COMMAND_IDS

DEFAULT_LINK = ImpairmentConfig.symmetric(LinkImpairment(
    loss_prob_good=0.03, loss_prob_bad=0.6, good_to_bad_prob=0.02, bad_to_good_prob=0.25,  # ~9 % in bursts
    duplicate_prob=0.03, corrupt_prob=0.01, reorder_prob=0.03, reorder_delay_ms=8.0, delay_ms=1.0, jitter_ms=3.0))
P = gen.PARAMS_BY_NAME
TUNABLE = (("collapse_time_s", 0.2, 0.5), ("ramp_up_mps2", 10.0, 40.0), ("ramp_down_mps2", 5.0, 20.0),
           ("speed_filter_tau_s", 0.005, 0.02), ("speed_kp", 0.03, 0.05))


@dataclass(frozen=True)
class SoakConfig:
    """What the soak does. Times in simulated seconds.

    duration_s: length of the soak. seed: seeds the plant, the proxy and the command choice.
    link: the impairment outside blackouts. command_gap_s: (min, max) pause after a command's verdict
    (or time-out). ack_timeout_s, retries: the host's retransmission policy. blackout_every_s,
    blackout_s: in each window of blackout_every_s one total blackout of blackout_s starts at a random time
    (0 = none). invalid_fraction: share of invalid commands, malformed datagrams and unauthentic or
    replayed frames.
    """

    duration_s: float = 30.0
    seed: int = 0
    link: ImpairmentConfig = DEFAULT_LINK
    command_gap_s: tuple[float, float] = (0.05, 0.4)
    ack_timeout_s: float = 0.06
    retries: int = 8
    blackout_every_s: float = 15.0
    blackout_s: float = 0.8
    invalid_fraction: float = 0.25

    def __post_init__(self) -> None:
        if not (isinstance(self.duration_s, (int, float)) and 0 < self.duration_s <= 24 * 3600):
            raise ValueError(f"duration_s: expected a duration in (0, 86400] s, got {self.duration_s!r}")
        lo, hi = self.command_gap_s
        if not 0 < lo <= hi:
            raise ValueError(f"command_gap_s: expected 0 < min <= max s, got {self.command_gap_s!r}")
        if not 0 <= self.invalid_fraction <= 1:
            raise ValueError(f"invalid_fraction: expected a fraction in [0, 1], got {self.invalid_fraction!r}")
        if self.blackout_s and self.blackout_s >= self.blackout_every_s:
            raise ValueError(f"blackout_s: expected < blackout_every_s {self.blackout_every_s}, got {self.blackout_s}")


@dataclass
class SoakFigures:
    """What happened in a soak (counts over the whole run)."""

    simulated_s: float = 0.0
    wall_s: float = 0.0
    commands_sent: int = 0
    malformed_sent: int = 0  # malformed or wrong-direction datagrams (NACKed)
    forged_sent: int = 0  # commands unsigned or signed with another key (dropped unanswered)
    replays_sent: int = 0  # earlier frames byte for byte, or signed for another session (dropped unanswered)
    transmissions: int = 0
    retransmissions: int = 0
    commands_answered: int = 0
    commands_timed_out: int = 0  # given up after the retries (time-outs, or NACKs for a frame damaged on the way)
    transit_nacks: int = 0  # NACKs saying the command's frame was damaged on the way: sent again at once
    commands_executed: int = 0  # distinct command frames the firmware got (each acted on once)
    commands_accepted: int = 0
    commands_refused: int = 0
    duplicates_answered: int = 0  # retransmissions the firmware answered from its cache (its rx_duplicates)
    auth_failed_dropped: int = 0  # delivered frames the firmware had to drop for their tag (its rx_auth_failed)
    replays_dropped: int = 0  # ... as replays: network copies, overtaken frames, replays_sent (its rx_replayed)
    verdicts_checked: int = 0
    telemetry_checked: int = 0
    ticks_checked: int = 0
    airborne_ticks: int = 0
    min_airborne_margin_mps: float = math.inf  # plant speed minus the guard, lowest while AIRBORNE
    min_airborne_margin_at_s: float = 0.0
    airborne_ticks_under_guard: int = 0  # plant speed under tov x margin while AIRBORNE (speed-loop undershoot)
    heartbeat_losses: int = 0
    blackouts: int = 0
    device_frames: int = 0
    host_frames_missing: int = 0  # device frames the host never got, all dropped/corrupted by the proxy
    host_frames_stale: int = 0  # device frames delivered after a newer one: the host drops them as replays
    proxy: dict = field(default_factory=dict)
    violations: int = 0
    first_violations: list[str] = field(default_factory=list)


class _Pending:
    __slots__ = ("message", "msg_id", "seq", "sent_us", "attempts")

    def __init__(self, message: gen.Message, seq: int, sent_us: int) -> None:
        self.message, self.msg_id, self.seq, self.sent_us, self.attempts = message, message.MSG_ID, seq, sent_us, 1


class Soak:
    """One soak run on a started SilSession; run() returns SoakFigures (violations listed there)."""

    def __init__(self, sil: SilSession, config: SoakConfig) -> None:
        self.sil = sil
        self.config = config
        self.rng = np.random.default_rng(config.seed)
        self.proxy = ImpairmentProxy(device_port=sil.cmd_port, seed=config.seed + 1, keep_log=True)
        self.host = ScriptedHost(ImpairedLockstep(sil, self.proxy))
        self.figures = SoakFigures()
        self.tick_ms = sil.tick_us / 1000
        link = config.link
        self.max_delay_us = round(1000 * max(l.delay_ms + l.jitter_ms + l.reorder_delay_ms
                                             for l in (link.to_device, link.to_host))) + 50_000
        # device-side truth
        self.gate = DeviceGate(key=sil.key)
        self._read_us = -1 << 62  # the tick the firmware read the last delivered datagram
        self._dropped_read_us: dict[Fate, list[int]] = {Fate.AUTH_FAILED: [], Fate.REPLAYED: []}  # ticks read
        self._drop_offset: dict[Fate, int] = {Fate.AUTH_FAILED: 0, Fate.REPLAYED: 0}
        self._awaiting_verdict: deque[tuple[tuple | None, bool]] = deque()  # (command key or None, no verdict)
        self._first_verdict: dict[tuple, tuple[bool, int, int]] = {}  # key -> (ack, reason, detail)
        self._key_params: dict[tuple, int] = {}
        self._repeat_verdict_seqs: list[int] = []
        self._telemetry_seqs: list[int] = []  # unwrapped seqs of the TELEMETRY frames received, sorted
        self._dup_offset = 0
        self._accepted_param_sets: Counter = Counter()
        self._param_changed: Counter = Counter()
        self._last_dev_seq: int | None = None
        self._dev_state: tuple[int, int] = (-1, gen.State.DISARMED)  # (seq, state)
        self._seq_fate: dict[int, list[int]] = {}  # device seq -> [first seen us, clean out, corrupted out, dropped]
        self._host_seqs: set[int] = set()
        self._host_last: tuple[int, int] = (-1, -1)  # (session, counter) of the last device frame the host kept
        self._host_expected: Counter = Counter()  # what the host must have dropped: replayed, auth_failed, decode
        self._host_counted: Counter = Counter()  # what it says it dropped
        self._max_seq_seen = -1
        self._pruned_below = None
        # the device numbers its frames on all links with one seq: the SIL device was provisioned over its USB
        # serial before the host's HELLO, so numbers under the SESSION_INFO that answered it went to the serial
        self._holes_from: int | None = None
        # host side
        self._pending: _Pending | None = None
        self._next_command_us = sil.plant.time_us + 200_000
        self._blackout: tuple[int, int] | None = None
        self._host_verdicts: dict[tuple[int, int], bool] = {}  # (msg_id, seq) -> only transit NACKs so far
        self._captured: bytes | None = None  # the last command frame sent: replayed byte for byte later
        self._answered: list[tuple[int, int]] = []  # (msg_id, seq) of the commands the host got a verdict for

    # ------------------------------------------------------------------------------------------ run
    def run(self, *, progress: Callable[[SoakFigures], None] | None = None, progress_every_s: float = 60.0) -> SoakFigures:
        cfg = self.config
        wall0 = time.perf_counter()
        self.host.run_for(0.6)  # clean link through the ESC arming hold
        self._digest()
        self.proxy.config = cfg.link
        start_us = self.sil.plant.time_us
        end_us = start_us + round(cfg.duration_s * 1e6)
        next_window_us = start_us
        next_progress_us = start_us + round(progress_every_s * 1e6)
        try:
            while self.sil.plant.time_us < end_us:
                now = self.sil.plant.time_us
                if cfg.blackout_s and now >= next_window_us:
                    span = round((cfg.blackout_every_s - cfg.blackout_s) * 1e6)
                    begin = now + int(self.rng.integers(0, span))
                    self._blackout = (begin, begin + round(cfg.blackout_s * 1e6))
                    next_window_us = now + round(cfg.blackout_every_s * 1e6)
                self._apply_blackout(now)
                self._drive_host(now)
                try:
                    self.host.tick()
                except SilError as exc:
                    self._violation(f"t={now / 1e6:.3f}s firmware crashed or hung: {exc}")
                    break
                self._digest()
                self._check_plant()
                self.figures.ticks_checked += 1
                if progress is not None and self.sil.plant.time_us >= next_progress_us:
                    next_progress_us += round(progress_every_s * 1e6)
                    self._finish_figures(start_us, wall0)
                    progress(self.figures)
            self.proxy.config = ImpairmentConfig()
            self.host.run_for(0.3)  # let the last frames land
            self._digest()
            self._prune(final=True)
            self._check_final()
        finally:
            self._finish_figures(start_us, wall0)
            self.host.close()
            self.proxy.close()
        return self.figures

    def _finish_figures(self, start_us: int, wall0: float) -> None:
        f = self.figures
        f.simulated_s = (self.sil.plant.time_us - start_us) * 1e-6
        f.wall_s = time.perf_counter() - wall0
        f.proxy = {d: vars(c).copy() for d, c in self.proxy.counters.items()}
        f.auth_failed_dropped = len(self._dropped_read_us[Fate.AUTH_FAILED])
        f.replays_dropped = len(self._dropped_read_us[Fate.REPLAYED])

    def _violation(self, text: str) -> None:
        f = self.figures
        f.violations += 1
        if len(f.first_violations) < 20:
            f.first_violations.append(text)

    # ------------------------------------------------------------------------------------------ host
    def _apply_blackout(self, now: int) -> None:
        b = self._blackout
        if b is None:
            return
        if now == b[0] or (b[0] <= now < b[1] and self.proxy.config is self.config.link):
            self.proxy.config = ImpairmentConfig.symmetric(LinkImpairment.blackout())
            self.figures.blackouts += 1
        elif now >= b[1]:
            self.proxy.config = self.config.link
            self._blackout = None

    def _drive_host(self, now: int) -> None:
        cfg, f = self.config, self.figures
        pending = self._pending
        if pending is not None:
            answered = self._host_verdict(pending)
            if answered:
                f.commands_answered += 1
                self._answered.append((pending.msg_id, pending.seq))
                self._pending = None
                self._schedule_next(now)
            elif answered is False or now - pending.sent_us >= round(cfg.ack_timeout_s * 1e6):
                f.transit_nacks += answered is False
                if pending.attempts > cfg.retries:
                    f.commands_timed_out += 1
                    self._pending = None
                    self._schedule_next(now)
                else:
                    self.host.send(pending.message, seq=pending.seq)  # same seq and payload, a fresh counter
                    pending.attempts += 1
                    pending.sent_us = now
                    f.transmissions += 1
                    f.retransmissions += 1
            return
        if now < self._next_command_us:
            return
        kind, payload = self._choose()
        if kind != "msg":
            self._send_unanswerable(kind, payload)
            self._schedule_next(now)
            return
        seq = self.host.seq
        self.host.seq = (seq + 1) & 0xFFFF
        frame = self.host.frame(payload, seq)
        self.host.send_raw(frame)
        self._captured = frame
        self._pending = _Pending(payload, seq, now)
        self._host_verdicts.clear()  # answers the host got before sending it are not for it
        f.commands_sent += 1
        f.transmissions += 1

    def _send_unanswerable(self, kind: str, payload) -> None:
        """Send a datagram the host expects no useful answer to: malformed or wrong-direction (NACKed),
        unauthentic or replayed (dropped unanswered)."""
        f, host = self.figures, self.host
        if kind == "raw":
            host.send_raw(payload)
            f.malformed_sent += 1
        elif kind == "wrong_direction":
            host.send(payload)  # signed: the device reads it and refuses it (NOT_A_COMMAND)
            f.malformed_sent += 1
        elif kind == "unsigned":
            host.send(payload, signed=False)
            f.forged_sent += 1
        elif kind == "wrong_key":
            host.send_raw(gen.encode_frame(payload, host.seq, key=bytes(reversed(host.key)),
                                           session_id=host.session_id, counter=host.counter + 1))
            f.forged_sent += 1
        elif kind == "other_session":
            host.send_raw(gen.encode_frame(payload, host.seq, key=host.key,
                                           session_id=(host.session_id + 1) & 0xFFFFFFFF, counter=host.counter + 1))
            f.replays_sent += 1
        elif kind == "replay":
            host.send_raw(self._captured if self._captured is not None else host.frame(payload, 0))
            f.replays_sent += 1
        else:
            raise AssertionError(f"unknown datagram kind {kind!r}")

    def _schedule_next(self, now: int) -> None:
        lo, hi = self.config.command_gap_s
        self._next_command_us = now + round(self.rng.uniform(lo, hi) * 1e6)

    def _host_verdict(self, pending: _Pending) -> bool | None:
        """True once the host got an ACK or NACK for the pending command; False if it got only NACKs saying
        the frame was damaged on the way (the Client sends it again at once); None if nothing yet."""
        transit = self._host_verdicts.pop((pending.msg_id, pending.seq), None)
        if transit is None:
            return None
        if not transit:
            self._host_verdicts.clear()  # older answers (to retransmissions) are of no further use
        return not transit

    def _choose(self) -> tuple[str, object]:
        rng = self.rng
        u = rng.random()
        if u < self.config.invalid_fraction:
            return self._choose_invalid()
        choices = ("arm", "speed", "speed", "speed", "spindown", "disarm", "param_get", "param_set", "home",
                   "set_loop", "relax", "estop", "grasp")
        weights = np.array([12, 10, 10, 10, 8, 8, 8, 10, 3, 4, 3, 1, 1], dtype=float)
        pick = choices[rng.choice(len(choices), p=weights / weights.sum())]
        if pick == "arm":
            return "msg", gen.Arm()
        if pick == "speed":
            return "msg", gen.SetRopeSpeed(int(rng.integers(3200, 8001)))
        if pick == "spindown":
            return "msg", gen.Spindown()
        if pick == "disarm":
            return "msg", gen.Disarm()
        if pick == "param_get":
            return "msg", gen.ParamGet(int(rng.integers(0, len(gen.PARAMS))))
        if pick == "param_set":
            name, lo, hi = TUNABLE[int(rng.integers(0, len(TUNABLE)))]
            return "msg", gen.ParamSet(P[name].id, float(np.float32(rng.uniform(lo, hi))))
        if pick == "home":
            return "msg", gen.Home()
        if pick == "set_loop":
            return "msg", gen.SetLoop(int(rng.integers(0, 180_001)))
        if pick == "relax":
            return "msg", gen.Relax()
        if pick == "estop":
            return "msg", gen.Estop()
        return "msg", gen.Grasp()

    def _choose_invalid(self) -> tuple[str, object]:
        rng = self.rng
        k = int(rng.integers(0, 16))
        # numbered half the seq space away from the host's commands: its NACK can never pass for theirs
        seq = (self.host.seq + 0x8000 + int(rng.integers(0, 0x4000))) & 0xFFFF
        good = gen.encode_frame(gen.SetRopeSpeed(5000), seq, key=self.host.key,
                                session_id=self.host.session_id, counter=self.host.counter + 1)
        forged = (gen.Estop(), gen.Arm(), gen.SetRopeSpeed(8000), gen.Disarm())[int(rng.integers(0, 4))]
        return [
            ("msg", gen.SetRopeSpeed(0)),
            ("msg", gen.SetRopeSpeed(-int(rng.integers(1, 10_000)))),
            ("msg", gen.SetRopeSpeed(int(rng.integers(20_001, 100_000)))),
            ("msg", gen.SetRopeSpeed(int(rng.integers(500, 2990)))),  # under the guard: refused while AIRBORNE
            ("msg", gen.ParamSet(int(rng.integers(len(gen.PARAMS), 256)), 1.0)),
            ("msg", gen.ParamSet(P["speed_kp"].id, float(rng.choice([5.0, -1.0, float("nan"), float("inf")])))),
            ("msg", gen.SetLoop(int(rng.choice([-5000, 500_000])))),
            ("raw", bytes(rng.integers(0, 256, int(rng.integers(0, 40)), dtype=np.uint8))),
            ("raw", good[:-1]),
            ("raw", good + b"\x00"),
            ("raw", bytes([good[0], good[1], good[2] | 0x02]) + good[3:]),  # a flag this version lacks
            ("wrong_direction", gen.Telemetry(*([0] * len(gen.Telemetry.FIELDS)))),
            ("unsigned", forged),
            ("wrong_key", forged),
            ("other_session", forged),
            ("replay", forged),
        ][k]

    # ------------------------------------------------------------------------------------------ device truth
    def _digest(self) -> None:
        for e in self.proxy.take_log():
            if e.direction == "to_device":
                if e.kind == "out":
                    self._on_delivered_to_device(e.time_us, e.data)
            elif e.kind == "in":
                self._on_device_frame(e.time_us, e.data)
            else:
                self._on_to_host_fate(e)
        r = self.host.received
        for data in r.raw:
            try:
                frame = gen.decode_frame(data)
            except gen.FrameError:
                continue
            if gen.tag_valid(frame, self.gate.key):  # a corrupted copy may decode (a flip in the signature block)
                self._host_seqs.add(self._unwrap(frame.seq))
        for reply in r.acks + r.nacks:
            transit = isinstance(reply, gen.Nack) and reply.reason in TRANSIT_NACK_REASONS
            key = (reply.cmd_msg_id, reply.cmd_seq)
            self._host_verdicts[key] = self._host_verdicts.get(key, True) and transit
        self._host_counted.update(replayed=r.replayed, auth_failed=r.auth_failed, decode_errors=r.decode_errors)
        self.host.received = Received()
        self._check_host_drops()
        self._prune()

    def _check_host_drops(self) -> None:
        """The host read every datagram the proxy delivered to it in the same tick: its drops must match."""
        for what in ("replayed", "auth_failed", "decode_errors"):
            if self._host_counted[what] != self._host_expected[what]:
                self._violation(f"t={self.sil.plant.time_us / 1e6:.3f}s the host counted {self._host_counted[what]} "
                                f"{what}, the proxy's log says {self._host_expected[what]}")
                self._host_counted[what] = self._host_expected[what]  # one violation per incident

    def _unwrap(self, seq: int) -> int:
        ref = self._max_seq_seen if self._max_seq_seen >= 0 else seq
        return ref + ((seq - ref + 0x8000) & 0xFFFF) - 0x8000

    def _on_delivered_to_device(self, time_us: int, data: bytes) -> None:
        # the firmware reads one datagram a tick, in delivery order (those delivered at t before its tick t)
        self._read_us = max(time_us, self._read_us + self.sil.tick_us)
        d = self.gate.deliver(data)
        if d.fate in (Fate.AUTH_FAILED, Fate.REPLAYED):
            self._dropped_read_us[d.fate].append(self._read_us)  # dropped unanswered, counted
            self._awaiting_verdict.append((None, True))
            return
        if d.fate in (Fate.EMPTY, Fate.HELLO):  # an empty datagram reads as none (as on the board); HELLO: SESSION_INFO
            self._awaiting_verdict.append((None, True))
            return
        if d.fate is Fate.MALFORMED:
            self._awaiting_verdict.append((None, False))
            return
        frame, msg = d.frame, d.message
        if frame.msg_id == gen.MsgId.HEARTBEAT:
            self._awaiting_verdict.append((None, True))
            return
        if frame.msg_id not in COMMAND_IDS:
            self._awaiting_verdict.append((None, False))
            return
        key = (frame.msg_id, frame.seq, frame.checksum)
        if isinstance(msg, gen.ParamSet):
            self._key_params[key] = msg.param_id
        self._awaiting_verdict.append((key, False))

    def _on_device_frame(self, time_us: int, data: bytes) -> None:
        f = self.figures
        try:
            frame, msg = gen.decode_message(data)
        except gen.FrameError as err:
            self._violation(f"t={time_us / 1e6:.3f}s the firmware sent an undecodable frame: {err}")
            return
        if not gen.tag_valid(frame, self.gate.key):
            self._violation(f"t={time_us / 1e6:.3f}s the firmware sent {msg.NAME} unsigned or wrongly signed")
        self.gate.learn_session(frame)
        seq = self._unwrap(frame.seq)
        if self._pruned_below is not None and seq < self._pruned_below:
            self._violation(f"t={time_us / 1e6:.3f}s device frame seq {seq} arrived long after its turn")
        self._seq_fate.setdefault(seq, [time_us, 0, 0, 0])
        self._max_seq_seen = max(self._max_seq_seen, seq)
        f.device_frames += 1
        if isinstance(msg, (gen.Ack, gen.Nack)):
            self._on_verdict(time_us, seq, msg)
        elif isinstance(msg, gen.Telemetry):
            self._on_telemetry(time_us, seq, msg)
        elif isinstance(msg, gen.Event):
            self._on_event(time_us, seq, msg)
        elif isinstance(msg, gen.SessionInfo) and self._holes_from is None:
            self._holes_from = seq

    def _on_to_host_fate(self, e) -> None:
        frame = None if e.corrupted else gen.decode_frame(e.data)
        if e.kind == "drop":
            seq = self._unwrap(frame.seq)
            if seq in self._seq_fate:
                self._seq_fate[seq][3] += 1
        elif e.corrupted:
            seq = self._unwrap(gen.decode_frame(e.original).seq)
            if seq in self._seq_fate:
                self._seq_fate[seq][2] += 1
            try:
                damaged = gen.decode_frame(e.data)
            except gen.FrameError:
                self._host_expected["decode_errors"] += 1
                return
            if gen.tag_valid(damaged, self.gate.key):
                self._violation(f"t={e.time_us / 1e6:.3f}s a corrupted device frame still verifies: CRC and tag missed it")
            self._host_expected["auth_failed"] += 1
        else:
            seq = self._unwrap(frame.seq)
            if seq in self._seq_fate:
                self._seq_fate[seq][1] += 1
            if (frame.session_id, frame.counter) > self._host_last:
                self._host_last = (frame.session_id, frame.counter)
            else:
                self._host_expected["replayed"] += 1  # overtaken on the way or a network copy: stale at the host
                self.figures.host_frames_stale += 1

    def _on_verdict(self, time_us: int, seq: int, msg: gen.Ack | gen.Nack) -> None:
        f = self.figures
        f.verdicts_checked += 1
        while self._awaiting_verdict and self._awaiting_verdict[0][1]:
            self._awaiting_verdict.popleft()  # heartbeats: no verdict
        if not self._awaiting_verdict:
            self._violation(f"t={time_us / 1e6:.3f}s verdict {msg} for no delivered frame")
            return
        key, _ = self._awaiting_verdict.popleft()
        if key is not None and (msg.cmd_msg_id, msg.cmd_seq) != key[:2]:
            # resynchronise on the frame this verdict belongs to, so one miss is one violation, not a cascade
            ahead = [k for k, hb in list(self._awaiting_verdict)[:16] if k is not None and not hb]
            if (msg.cmd_msg_id, msg.cmd_seq) in [k[:2] for k in ahead]:
                self._violation(f"t={time_us / 1e6:.3f}s command {key[:2]} got no verdict")
                while True:
                    key, hb = self._awaiting_verdict.popleft()
                    if key is not None and key[:2] == (msg.cmd_msg_id, msg.cmd_seq):
                        break
        verdict = (isinstance(msg, gen.Ack), 0 if isinstance(msg, gen.Ack) else msg.reason,
                   0 if isinstance(msg, gen.Ack) else msg.detail)
        if key is None:
            if not isinstance(msg, gen.Nack):
                self._violation(f"t={time_us / 1e6:.3f}s a malformed or wrong-direction frame was ACKed: {msg}")
            return
        if (msg.cmd_msg_id, msg.cmd_seq) != key[:2]:
            self._violation(f"t={time_us / 1e6:.3f}s verdict for {msg.cmd_msg_id}/{msg.cmd_seq}, expected {key[:2]}")
            return
        first = self._first_verdict.get(key)
        if first is None:
            self._first_verdict[key] = verdict
            f.commands_executed += 1
            f.commands_accepted += verdict[0]
            f.commands_refused += not verdict[0]
            if verdict[0] and key in self._key_params:
                self._accepted_param_sets[self._key_params[key]] += 1
        else:
            self._repeat_verdict_seqs.append(seq)
            if verdict != first:
                self._violation(f"t={time_us / 1e6:.3f}s repeat of {key[:2]} answered {verdict}, first {first}: "
                                "executed again?")

    def _on_telemetry(self, time_us: int, seq: int, t: gen.Telemetry) -> None:
        f = self.figures
        f.telemetry_checked += 1
        # Queued frames are numbered when their signing begins, a few ticks after they were packed: a telemetry
        # frame counts every repeat answered before the previous telemetry frame was numbered (that one was
        # packed earlier), and at most those numbered before it.
        expected = bisect.bisect_left(self._repeat_verdict_seqs, seq)
        i = bisect.bisect_left(self._telemetry_seqs, seq)  # the telemetry frame before it (reordering allowed)
        previous = self._telemetry_seqs[i - 1] if i > 0 else 0
        bisect.insort(self._telemetry_seqs, seq)
        at_least = bisect.bisect_left(self._repeat_verdict_seqs, previous)
        counted = (t.rx_duplicates - self._dup_offset) & 0xFFFF
        if not at_least <= counted <= expected:
            self._violation(f"t={time_us / 1e6:.3f}s rx_duplicates {t.rx_duplicates}, expected "
                            f"{(at_least + self._dup_offset) & 0xFFFF}..{(expected + self._dup_offset) & 0xFFFF}: "
                            "a repeated command was executed again")
            self._dup_offset = t.rx_duplicates - expected  # one violation per incident, not per sample after it
        f.duplicates_answered = expected
        for fate, field_name in ((Fate.AUTH_FAILED, "rx_auth_failed"), (Fate.REPLAYED, "rx_replayed")):
            dropped = bisect.bisect_right(self._dropped_read_us[fate], t.time_ms * 1000)
            want = (dropped + self._drop_offset[fate]) & 0xFFFF
            got = getattr(t, field_name)
            if got != want:
                self._violation(f"t={time_us / 1e6:.3f}s {field_name} {got}, expected {want} "
                                f"(frames read by {t.time_ms} ms that had to be dropped)")
                self._drop_offset[fate] = got - dropped  # one violation per incident, not per sample after it
        if seq > self._dev_state[0]:
            self._dev_state = (seq, t.state)
        guard_mmps = math.floor(P["tov_mps"].default * P["tov_margin"].default * 1000)
        if t.state == gen.State.AIRBORNE and t.rope_speed_setpoint_mmps < guard_mmps - 1:
            self._violation(f"t={time_us / 1e6:.3f}s AIRBORNE with the setpoint {t.rope_speed_setpoint_mmps} mm/s "
                            f"under the guard {guard_mmps} mm/s")

    def _on_event(self, time_us: int, seq: int, e: gen.Event) -> None:
        kind = e.event
        if kind == gen.EventKind.STATE_CHANGED and seq > self._dev_state[0]:
            self._dev_state = (seq, e.state_to)
        elif kind == gen.EventKind.PARAM_CHANGED:
            self._param_changed[e.arg] += 1
        elif kind == gen.EventKind.LOOP_COLLAPSED:
            self._violation(f"t={time_us / 1e6:.3f}s LOOP_COLLAPSED at {e.arg} mm/s with nothing loading the rope")
        elif kind == gen.EventKind.HEARTBEAT_LOST:
            self.figures.heartbeat_losses += 1
            timeout_ms = 1000 * gen.PARAMS_BY_NAME["heartbeat_timeout_s"].default
            if not timeout_ms < e.arg <= timeout_ms + self.tick_ms:
                self._violation(f"t={time_us / 1e6:.3f}s HEARTBEAT_LOST after {e.arg} ms of silence")

    def _prune(self, *, final: bool = False) -> None:
        """Judge device frames old enough that no copy can still be in flight: gap accounting."""
        f = self.figures
        horizon = self.sil.plant.time_us - self.max_delay_us
        while self._seq_fate:
            seq = min(self._seq_fate)  # frames leave slightly out of seq order (queued ones after replies)
            first_us, clean, corrupted, dropped = self._seq_fate[seq]
            if not final and first_us > horizon:
                return
            del self._seq_fate[seq]
            if self._pruned_below is not None and seq != self._pruned_below:
                first_hole = self._pruned_below if self._holes_from is None else max(self._pruned_below, self._holes_from)
                for hole in range(first_hole, min(seq, first_hole + 5)):
                    self._violation(f"device seq {hole} never left the firmware (outbox drop): unaccounted gap")
            self._pruned_below = seq + 1
            got = seq in self._host_seqs
            self._host_seqs.discard(seq)
            if got != (clean > 0):
                self._violation(f"device seq {seq}: host {'got' if got else 'missed'} it, proxy delivered "
                                f"{clean} clean copies ({corrupted} corrupted, {dropped} dropped)")
            elif not got:
                f.host_frames_missing += 1
                if corrupted + dropped == 0:
                    self._violation(f"device seq {seq} missing at the host with no drop or corruption")

    # ------------------------------------------------------------------------------------------ checks
    def _check_plant(self) -> None:
        plant = self.sil.plant
        if not (math.isfinite(plant.rope_speed_mps) and math.isfinite(plant.battery_v)):
            self._violation(f"t={plant.time_us / 1e6:.3f}s plant not finite: {plant.rope_speed_mps}, {plant.battery_v}")
        if self._dev_state[1] == gen.State.AIRBORNE:
            guard_mps = P["tov_mps"].default * P["tov_margin"].default
            f = self.figures
            f.airborne_ticks += 1
            margin = plant.rope_speed_mps - guard_mps
            if margin < f.min_airborne_margin_mps:
                f.min_airborne_margin_mps, f.min_airborne_margin_at_s = margin, plant.time_us * 1e-6
            if plant.rope_speed_mps < P["tov_mps"].default:
                self._violation(f"t={plant.time_us / 1e6:.3f}s AIRBORNE at {plant.rope_speed_mps:.3f} m/s, under ToV")
            elif margin < 0.0:
                f.airborne_ticks_under_guard += 1  # counted (test_soak's step-down tests judge the guard)

    def _check_final(self) -> None:
        executed = {key[:2] for key in self._first_verdict}
        for msg_id, seq in self._answered:
            if (msg_id, seq) not in executed:
                self._violation(f"the host took a verdict for command {msg_id}/{seq}, which never reached the firmware")
        if self._param_changed != self._accepted_param_sets:
            self._violation(f"PARAM_CHANGED events {dict(self._param_changed)} != accepted PARAM_SETs "
                            f"{dict(self._accepted_param_sets)}")
        if self.sil._firmware.poll() is not None:  # noqa: SLF001 - the process is the thing under test
            self._violation("the firmware process has exited")


def run_soak(config: SoakConfig, *, progress: Callable[[SoakFigures], None] | None = None,
             progress_every_s: float = 60.0) -> SoakFigures:
    """Start a SIL session, run the soak on it, stop it; returns the figures."""
    with SilSession(speedup=None, seed=config.seed, trace_every=0, key=seeded_key(config.seed)) as sil:
        return Soak(sil, config).run(progress=progress, progress_every_s=progress_every_s)
