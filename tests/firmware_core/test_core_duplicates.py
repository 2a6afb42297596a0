"""rw_core retransmissions: the same command (same seq and payload, signed afresh by the host) is answered
again with the same verdict and never executed twice; same seq with other bytes is a new command;
rx_duplicates counts. A copy of the very same bytes (the network duplicating or an attacker replaying) is
dropped unanswered as a replay (its counter is not fresh) and counted in rx_replayed."""

from __future__ import annotations

from core_harness import CoreHarness
from robowrangler.protocol import generated as proto
from robowrangler.protocol.generated import (
    PARAMS_BY_NAME, Ack, Arm, EventKind, Nack, NackReason, ParamSet, SetRopeSpeed, State,
)


def _armed(rw_core) -> CoreHarness:
    h = CoreHarness(rw_core)
    h.boot_and_arm()
    return h


def test_param_set_twice_is_executed_once_and_acked_twice(rw_core):
    h = CoreHarness(rw_core)
    h.tick()
    msg = ParamSet(PARAMS_BY_NAME["speed_kp"].id, 0.07)
    first = h.command(msg, seq=60)
    h.run_ms(3)
    again = h.command(msg, seq=60)  # the host's retransmission: same seq, fresh counter
    h.drain(25)
    assert isinstance(first, Ack) and first == again, "same verdict, same fields"
    changed = h.events(EventKind.PARAM_CHANGED)
    assert len(changed) == 1, "executed once: one PARAM_CHANGED event"
    values = h.sent(proto.ParamValue)
    assert len(values) == 2 and all(abs(v.msg.value - 0.07) < 1e-7 for v in values), \
        "the retransmission gets its PARAM_VALUE too"
    tel = h.telemetry()[-1]
    assert (tel.rx_duplicates, tel.rx_ok, tel.nacks) == (1, 2, 0)


def test_retransmitted_old_speed_does_not_undo_a_newer_one(rw_core):
    h = _armed(rw_core)
    five = h.frame(SetRopeSpeed(5000), seq=50)
    assert isinstance(h.command(five), Ack)
    h.run_ms(2)
    assert isinstance(h.command(SetRopeSpeed(6000), seq=51), Ack)
    h.run_ms(2)
    late = h.command(SetRopeSpeed(5000), seq=50)  # the host retransmits the old one (its ACK was lost)
    assert isinstance(late, Ack) and late.cmd_seq == 50
    before = len(h.replies())
    h.queue(five)  # and the network delivers a copy of the first transmission, late
    h.tick()
    assert len(h.replies()) == before, "a replayed copy is not answered"
    h.heartbeat()
    h.run_ms(25)
    tel = h.telemetry()[-1]
    assert tel.rope_speed_target_mmps == 6000
    assert (tel.rx_duplicates, tel.rx_replayed) == (1, 1)


def test_same_seq_with_other_bytes_is_a_new_command(rw_core):
    h = _armed(rw_core)
    assert isinstance(h.command(SetRopeSpeed(5000), seq=40), Ack)
    h.run_ms(2)
    assert isinstance(h.command(SetRopeSpeed(6000), seq=40), Ack)
    h.heartbeat()
    h.run_ms(25)
    tel = h.telemetry()[-1]
    assert tel.rope_speed_target_mmps == 6000
    assert tel.rx_duplicates == 0


def test_same_bytes_under_another_seq_is_a_new_command(rw_core):
    h = CoreHarness(rw_core)
    h.tick()
    msg = ParamSet(PARAMS_BY_NAME["speed_ki"].id, 0.5)
    h.command(msg, seq=7)
    h.command(msg, seq=8)
    h.drain(25)
    assert len(h.events(EventKind.PARAM_CHANGED)) == 2
    assert h.telemetry()[-1].rx_duplicates == 0


def test_retransmitted_refusal_gets_the_same_nack(rw_core):
    h = _armed(rw_core)
    first = h.command(SetRopeSpeed(30000), seq=70)
    again = h.command(SetRopeSpeed(30000), seq=70)
    assert isinstance(first, Nack) and first == again
    assert (first.reason, first.detail) == (NackReason.OUT_OF_RANGE, 20000)
    h.run_ms(25)
    tel = h.telemetry()[-1]
    assert (tel.rx_duplicates, tel.nacks) == (1, 2), "each NACK sent is counted"


def test_retransmitted_arm_keeps_its_verdict_a_new_arm_is_judged_anew(rw_core):
    """A retransmission is the same request, answered as it was; asking again needs a new seq."""
    h = CoreHarness(rw_core)
    h.tick()
    h.run_ms(300)
    assert h.command(Arm(), seq=80).reason == NackReason.NOT_READY
    h.run_ms(300)  # the hold is over now
    assert h.command(Arm(), seq=80).reason == NackReason.NOT_READY, "answered from the cache, not re-executed"
    reply = h.command(Arm())
    assert isinstance(reply, Ack) and reply.state == State.ARMED


def test_heartbeats_are_not_duplicates(rw_core):
    h = CoreHarness(rw_core)
    h.tick()
    for _ in range(3):
        h.queue(h.frame(proto.Heartbeat(1), seq=5))  # same seq and payload, each signed afresh
        h.tick()
    h.run_ms(25)
    tel = h.telemetry()[-1]
    assert (tel.rx_ok, tel.rx_duplicates) == (3, 0)
    assert h.replies() == [], "heartbeats are not answered"
