"""PROVISION_COMMIT's flash write happens outside the control tick (hal/rw_hal_config_store.h): the tick hands
the record to the store (request_save), the store's background side writes it (on the board up to ~25 ms with
the CPU stalled on flash), and the core answers the command once the store says it is written:

- ACK only after the write is done (never before), the new session in force from then on, the record in flash;
- meanwhile ARM and every other PROVISION_* but GET are refused NOT_READY (the rope stays down while the flash
  is written), a retransmission of the same commit is counted and answered by the one ACK when it comes;
- a failed write: NACK STORE_FAILED (detail 1), nothing changed (session, key, record);
- the flight gate: PROVISION_* (but GET) only while DISARMED, over USB serial only.
"""

from __future__ import annotations

import pytest
from core_harness import CoreHarness
from robowrangler.protocol import generated as proto

FLASH_TICKS = 25  # the board's erase + write, about 25 ms


def _serial(h: CoreHarness, msg: proto.Message, seq: int) -> bytes:
    data = proto.encode_frame(msg, seq)
    h.hal.serial_inbox.append(data)
    return data


def _serial_replies(h: CoreHarness, since: int) -> list[proto.Message]:
    return [o.msg for o in h.hal.out[since:] if o.channel == "reply" and o.link == "serial"]


def _serial_command(h: CoreHarness, msg: proto.Message, seq: int) -> proto.Message:
    before = len(h.hal.out)
    _serial(h, msg, seq)
    h.tick()
    replies = _serial_replies(h, before)
    assert len(replies) == 1, replies
    return replies[0]


def _booted(**kw) -> CoreHarness:
    h = CoreHarness(kw.pop("lib"), serial=True, flash_save_ticks=FLASH_TICKS, **kw)
    h.run_ms(600)  # the arming hold
    return h


def test_commit_is_acked_only_once_the_flash_is_written(rw_core) -> None:
    h = _booted(lib=rw_core)
    assert isinstance(_serial_command(h, proto.ProvisionSetWifiSsid(ssid="lab"), 1), proto.Ack)
    before = len(h.hal.out)
    commit = _serial(h, proto.ProvisionCommit(session_epoch=123_456), 2)
    h.tick()
    assert _serial_replies(h, before) == [], "no answer before the write is done"
    assert h.flash_save_requests == 1
    # meanwhile: ARM and provisioning refused NOT_READY, GET answered, the same commit again not executed twice
    arm = h.command(proto.Arm())
    assert isinstance(arm, proto.Nack) and arm.reason == proto.NackReason.NOT_READY, arm
    nack = _serial_command(h, proto.ProvisionSetWifiSsid(ssid="other"), 3)
    assert isinstance(nack, proto.Nack) and nack.reason == proto.NackReason.NOT_READY, nack
    assert isinstance(_serial_command(h, proto.ProvisionGet(), 4), proto.Ack)
    h.hal.serial_inbox.append(commit)
    h.tick()
    assert h.flash_save_requests == 1, "a retransmission is not written again"
    answers: list[proto.Message] = []
    ticks = 0
    while not answers and ticks < 3 * FLASH_TICKS:
        mark = len(h.hal.out)
        h.tick()
        ticks += 1
        answers = [m for m in _serial_replies(h, mark) if getattr(m, "cmd_msg_id", None) == proto.MsgId.PROVISION_COMMIT]
    assert len(answers) == 1 and isinstance(answers[0], proto.Ack) and answers[0].cmd_seq == 2, answers
    assert 4 + ticks >= FLASH_TICKS, "the ACK came before the write could be done"
    assert h.flash is not None and b"lab" in h.flash and b"other" not in h.flash
    # the retransmission again now: the cached ACK, nothing written
    assert isinstance(_serial_command(h, proto.ProvisionCommit(session_epoch=123_456), 2), proto.Ack)
    assert h.flash_save_requests == 1
    tel = [o.msg for o in h.hal.out if isinstance(o.msg, proto.Telemetry)]
    assert tel, "telemetry went on while the flash was written"


def test_a_failed_write_is_refused_and_changes_nothing(rw_core) -> None:
    h = _booted(lib=rw_core)
    h.flash_save_fails = True
    stored = h.flash
    before = len(h.hal.out)
    _serial(h, proto.ProvisionCommit(session_epoch=99), 1)
    for _ in range(FLASH_TICKS + 2):
        h.tick()
    answers = _serial_replies(h, before)
    assert len(answers) == 1 and isinstance(answers[0], proto.Nack), answers
    assert answers[0].reason == proto.NackReason.STORE_FAILED and answers[0].detail == 1
    assert h.flash == stored
    # the WiFi session is the one of the boot: a signed command still counts
    assert isinstance(h.command(proto.Arm()), proto.Ack)


@pytest.mark.parametrize("msg", [proto.ProvisionSetWifiSsid(ssid="x"), proto.ProvisionCommit(session_epoch=5)],
                         ids=lambda m: m.NAME)
def test_provisioning_is_refused_unless_disarmed(rw_core, msg: proto.Message) -> None:
    h = _booted(lib=rw_core)
    assert isinstance(h.command(proto.Arm()), proto.Ack)
    nack = _serial_command(h, msg, 1)
    assert isinstance(nack, proto.Nack) and nack.reason == proto.NackReason.BAD_STATE, nack
    assert h.flash_save_requests == 0
