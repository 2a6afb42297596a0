"""rw_core and the link: at most one datagram received and one sent per tick, outbox priority
(PARAM_VALUE before EVENT before TELEMETRY), telemetry dropped first when the outbox is full,
telemetry at telemetry_rate_hz."""

from __future__ import annotations

from collections import Counter

import pytest

from core_harness import CoreHarness
from robowrangler.protocol import generated as proto
from robowrangler.protocol.generated import PARAMS_BY_NAME, Ack, EventKind, ParamGet, ParamSet

P = PARAMS_BY_NAME
BAD = b"\xb7\x01\x00"  # TRUNCATED: answered by a NACK, queues nothing


def test_two_queued_frames_are_processed_on_consecutive_ticks(rw_core):
    h = CoreHarness(rw_core)
    h.tick()
    h.run_ms(5)
    i0 = len(h.hal.out)
    h.queue(h.frame(ParamGet(0)))
    h.queue(h.frame(ParamGet(1)))
    h.tick()
    first = h.replies(since=i0)
    assert len(first) == 1 and first[0].msg.cmd_seq == h.seq - 1
    assert len(h.hal.inbox) == 1, "the second datagram waits for the next tick"
    h.tick()
    both = h.replies(since=i0)
    assert [r.msg.cmd_seq for r in both] == [h.seq - 1, h.seq]
    assert [r.tick_ms for r in both] == [h.t_ms - 1, h.t_ms]


def test_never_more_than_one_datagram_out_per_tick(rw_core):
    h = CoreHarness(rw_core, params={"telemetry_rate_hz": 100.0})
    h.boot_and_arm()
    h.spin_to_airborne(target_mmps=4000)
    for i in range(200):  # a busy host: a command every other tick
        if i % 2 == 0:
            h.queue(h.frame(ParamGet(i % len(proto.PARAMS))))
        h.tick()
    per_tick = Counter(o.tick_ms for o in h.hal.out)
    assert max(per_tick.values()) == 1
    assert len(h.hal.pulses_us) == h.t_ms + 1, "one ESC write per tick"


@pytest.mark.parametrize("command_at_ms", range(12))
def test_frames_from_boot_are_numbered_0_1_2_without_repeat_or_hole(rw_core, command_at_ms):
    """A reply may leave before the boot EVENT whose signing began first (it overtakes it, numbered one later):
    whenever the first command arrives, the frames sent from boot carry seq 0, 1, 2 ... each once."""
    h = CoreHarness(rw_core)
    h.run_ms(command_at_ms)
    h.queue(h.frame(ParamGet(P["telemetry_rate_hz"].id)))
    h.run_ms(30)
    seqs = [o.frame.seq for o in h.hal.out]
    assert sorted(seqs) == list(range(len(seqs))) and len(seqs) >= 4
    assert [type(o.msg) for o in h.replies()] == [Ack]


def test_outbox_sends_param_value_then_event_then_telemetry(rw_core):
    h = CoreHarness(rw_core)  # 50 Hz: telemetry is queued at t = 0, 20, 40 ... ms
    h.tick()
    h.run_ms(39)
    h.drain(0)
    i0 = len(h.hal.out)
    t0 = h.t_ms + 1
    # The PARAM_SET queues (in this order) a PARAM_CHANGED event, then the PARAM_VALUE, then the next
    # telemetry tick queues its telemetry; the command tick's one datagram is the ACK. The queued frames are
    # signed over idle ticks (rw_core.h) and leave replies first, then events, then telemetry.
    ack = h.command(ParamSet(P["speed_kp"].id, 0.05))
    assert isinstance(ack, Ack)
    h.drain(0)
    out = h.hal.out[i0:]
    kinds = [type(o.msg).__name__ for o in out]
    assert kinds == ["Ack", "ParamValue", "Event", "Telemetry"]
    assert out[2].msg.event == EventKind.PARAM_CHANGED
    times = [o.tick_ms for o in out]
    assert times[0] == t0 and times == sorted(set(times)), "one datagram a tick, in that order"
    assert times[-1] - t0 <= 20, f"all out within 20 ms of the command: {times}"


def test_full_outbox_drops_telemetry_not_events_or_replies(rw_core):
    h = CoreHarness(rw_core, params={"telemetry_rate_hz": 100.0})
    h.tick()
    h.run_ms(9)
    # 100 ticks with a refused datagram each: every tick's one datagram is a NACK, nothing drains,
    # telemetry fills the 12 slots (10 are due, and the frame being signed waits: some are dropped).
    i_block = len(h.hal.out)
    for _ in range(100):
        h.queue(BAD)
        h.tick()
    assert h.sent(since=i_block) == [], "replies take the tick's one datagram"
    # Two more commands: their events and PARAM_VALUEs must displace stale telemetry, not be lost.
    i0 = len(h.hal.out)
    for pid, value in ((P["speed_kp"].id, 0.05), (P["speed_ki"].id, 0.6)):
        assert isinstance(h.command(ParamSet(pid, value)), Ack)
    h.drain(20, max_ms=1000)  # at 100 Hz the backlog drains at about 50 frames/s
    sent = h.sent(since=i0)
    if isinstance(sent[0].msg, proto.Telemetry):  # it was being signed before the commands came
        sent = sent[1:]
    kinds = [type(o.msg).__name__ for o in sent]
    assert kinds[:4] == ["ParamValue", "ParamValue", "Event", "Event"], kinds
    assert [o.msg.param_id for o in sent[:2]] == [P["speed_kp"].id, P["speed_ki"].id]
    events = h.events()
    assert [e.event_seq for e in events] == list(range(1, len(events) + 1)), "no event lost"
    tel_times = [o.msg.time_ms for o in sent[4:] if isinstance(o.msg, proto.Telemetry)]
    assert len(tel_times) >= 6, "the telemetry that was kept follows"
    assert tel_times == sorted(tel_times)
    steps = {b - a for a, b in zip(tel_times, tel_times[1:])}
    assert max(steps) > 10, "some telemetry was dropped while the outbox was full"


def test_events_survive_a_flood_of_commands(rw_core):
    h = CoreHarness(rw_core)
    h.tick()
    for i in range(4):  # 4 ticks in a row, each: ACK now, PARAM_CHANGED + PARAM_VALUE queued
        h.queue(h.frame(ParamSet(P["speed_kp"].id, 0.01 * (i + 1))))
        h.tick()
    h.drain(20)
    assert len(h.events(EventKind.PARAM_CHANGED)) == 4
    assert [o.msg.value for o in h.sent(proto.ParamValue)] == pytest.approx([0.01, 0.02, 0.03, 0.04])


@pytest.mark.parametrize("rate_hz, period_ms", [(1.0, 1000), (10.0, 100), (25.0, 40), (50.0, 20), (100.0, 10)])
def test_telemetry_rate_follows_telemetry_rate_hz(rw_core, rate_hz, period_ms):
    h = CoreHarness(rw_core, params={"telemetry_rate_hz": rate_hz})
    h.tick()
    h.run_ms(3000)
    h.drain(0)  # the frame queued at t = 3000 ms is still being signed
    times = [t.time_ms for t in h.telemetry() if t.time_ms <= 3000]
    assert times[0] == 0
    assert {b - a for a, b in zip(times, times[1:])} == {period_ms}
    assert len(times) == 3000 // period_ms + 1


def test_telemetry_rate_change_takes_effect(rw_core):
    h = CoreHarness(rw_core)
    h.tick()
    h.run_ms(200)
    assert isinstance(h.command(ParamSet(P["telemetry_rate_hz"].id, 100.0)), Ack)
    t_set = h.t_ms
    h.run_ms(500)
    late = [t.time_ms for t in h.telemetry() if t.time_ms > t_set + 40]
    assert {b - a for a, b in zip(late, late[1:])} == {10}


def test_faster_telemetry_rate_takes_effect_within_one_new_period(rw_core):
    h = CoreHarness(rw_core, params={"telemetry_rate_hz": 1.0})
    h.tick()
    h.run_ms(100)
    assert isinstance(h.command(ParamSet(P["telemetry_rate_hz"].id, 100.0)), Ack)
    t_set = h.t_ms
    h.run_ms(200)
    after = [t.time_ms for t in h.telemetry() if t.time_ms >= t_set]
    assert after and after[0] <= t_set + 10 + 3, f"first telemetry after the change at {after[:1]} (set at {t_set})"


def test_telemetry_reports_counters_and_tick_overruns(rw_core):
    h = CoreHarness(rw_core, battery_mv=15234)
    h.hal.tick_overruns = 7
    h.tick()
    h.command(BAD)
    h.command(ParamGet(3))
    h.run_ms(40)
    tel = h.telemetry()[-1]
    assert (tel.battery_mv, tel.tick_overruns, tel.rx_ok, tel.rx_bad, tel.nacks) == (15234, 7, 1, 1, 1)
    assert tel.heartbeat_age_ms == h.t_ms - 2 - (h.t_ms - tel.time_ms), "age since the valid PARAM_GET"
