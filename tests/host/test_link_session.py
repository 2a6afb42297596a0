"""The one signed-link session (robowrangler.link_session): HELLO, signing, counters, freshness of device frames.

Before it, the rules were written four times and two disagreed: the client refused only sessions older than
the one it signed for (so before its session was known, or after a SESSION_INFO of another nonce, an older
session's frame was taken again), and the scripted host compared (session, counter) as a tuple (so it could
never follow a re-provisioned device whose new epoch gives a lower session id, not even through its own
HELLO). The sequences below are those cases; every host now judges them one way, the device's.
"""

from __future__ import annotations

import pytest

from robowrangler.errors import InvalidArgument
from robowrangler.link_session import LinkSession, NoSession, Verdict, device_takes
from robowrangler.protocol import generated as gen

KEY = bytes(range(16))
OTHER_KEY = bytes(range(1, 17))


def device_frame(message: gen.Message, *, session: int, counter: int, key: bytes = KEY) -> tuple[gen.Frame, gen.Message]:
    """A frame the device signed, decoded as a host receives it."""
    return gen.decode_message(gen.encode_frame(message, 1, key=key, session_id=session, counter=counter))


def telemetry(session: int, counter: int, *, key: bytes = KEY) -> tuple[gen.Frame, gen.Message]:
    return device_frame(gen.Heartbeat(0), session=session, counter=counter, key=key)  # any signed message will do


def answer(link: LinkSession, session: int, counter: int, *, nonce: int | None = None) -> tuple[gen.Frame, gen.Message]:
    info = gen.SessionInfo(link.nonce if nonce is None else nonce, session, 1, gen.SCHEMA_HASH)
    return device_frame(info, session=session, counter=counter)


def connected(session: int = 7, counter: int = 1) -> LinkSession:
    link = LinkSession(KEY)
    link.hello(0x1234)
    assert link.check(*answer(link, session, counter)) == Verdict.ANSWERED
    return link


def test_nothing_is_signed_before_the_session_and_hello_is_never_signed() -> None:
    link = LinkSession(KEY)
    with pytest.raises(NoSession, match="ARM: no device session yet; say HELLO"):
        link.sign(gen.Arm(), 1)
    frame, _ = gen.decode_message(link.sign(link.hello(5), 1))
    assert not frame.signed and link.counter == 0


def test_signed_frames_carry_the_session_and_a_counter_that_only_grows() -> None:
    link = connected(session=7)
    frames = [gen.decode_frame(link.sign(gen.Heartbeat(i), i)) for i in range(5)]
    assert [f.counter for f in frames] == [1, 2, 3, 4, 5]
    assert all(f.session_id == 7 and gen.tag_valid(f, KEY) for f in frames)


def test_a_clock_sets_the_floor_of_the_counter_and_never_lets_it_go_back() -> None:
    readings = iter([1_000_000, 1_000_000, 999_000, 2_000_000])
    link = LinkSession(KEY, clock_us=lambda: next(readings), session_id=3)
    assert [link.next_counter() for _ in range(4)] == [1_000_000, 1_000_001, 1_000_002, 2_000_000]


def test_frames_not_signed_with_the_key_are_bad_tags() -> None:
    link = connected()
    assert link.check(*telemetry(7, 5, key=OTHER_KEY)) == Verdict.BAD_TAG
    unsigned = gen.decode_message(gen.encode_frame(gen.Heartbeat(0), 1))
    assert link.check(*unsigned) == Verdict.BAD_TAG
    assert link.check(*telemetry(7, 5)) == Verdict.ACCEPTED  # a bad tag moved nothing


def test_within_a_session_only_a_growing_counter_is_taken() -> None:
    link = connected(session=7, counter=1)
    assert [link.check(*telemetry(7, c)) for c in (2, 3, 3, 2, 10, 9)] == [
        Verdict.ACCEPTED, Verdict.ACCEPTED, Verdict.STALE, Verdict.STALE, Verdict.ACCEPTED, Verdict.STALE]


def test_a_newer_session_is_followed_and_the_older_one_is_stale_from_then_on() -> None:
    link = connected(session=7, counter=40)
    assert link.check(*telemetry(8, 1)) == Verdict.FOLLOWED  # the device rebooted: its counter starts again
    assert link.session_id == 8
    assert link.check(*telemetry(7, 41)) == Verdict.STALE
    assert gen.decode_frame(link.sign(gen.Arm(), 1)).session_id == 8


def test_before_the_answer_to_its_hello_a_host_takes_nothing() -> None:
    """Old client rule: with no session yet, session 5 then session 4 were both taken (a replay of an older
    session); old scripted-host rule: the first frame seen, whatever it was, set the bar."""
    link = LinkSession(KEY)
    link.hello(99)
    assert [link.check(*telemetry(5, 9)), link.check(*telemetry(4, 20))] == [Verdict.STALE, Verdict.STALE]
    assert link.check(*answer(link, 5, 10)) == Verdict.ANSWERED and link.session_id == 5
    assert link.check(*telemetry(4, 21)) == Verdict.STALE


def test_an_older_session_stays_stale_after_a_session_info_of_another_nonce() -> None:
    """Old client rule: a SESSION_INFO of a newer session answering someone else's HELLO moved the bar to that
    session without the client signing for it, after which frames of its own (older) session were taken
    again with their counters forgotten."""
    link = connected(session=7, counter=50)
    assert link.check(*answer(link, 8, 1, nonce=0xBEEF)) == Verdict.FOLLOWED
    assert link.check(*telemetry(7, 30)) == Verdict.STALE and link.session_id == 8


def test_the_answer_to_a_new_hello_follows_a_re_provisioned_device_to_a_lower_session() -> None:
    """Old scripted-host rule (tuple order): after PROVISION_COMMIT drew a new epoch below the old one, the
    device's answer to a new HELLO was dropped as a replay, and the host could never talk to it again."""
    link = connected(session=0x50000, counter=300)
    assert link.check(*telemetry(0x1000, 301)) == Verdict.STALE  # lower, and no HELLO of ours answered it
    link.hello(0x777)
    assert link.check(*answer(link, 0x1000, 302)) == Verdict.ANSWERED and link.session_id == 0x1000
    assert link.check(*answer(link, 0x1000, 302)) == Verdict.STALE  # the same answer again is a copy
    assert link.check(*telemetry(0x50000, 400)) == Verdict.FOLLOWED  # (a later boot of the old range is newer)


def test_an_old_answer_to_an_earlier_hello_does_not_set_the_session() -> None:
    link = connected(session=0x50000, counter=300)
    old_nonce = link.nonce
    link.hello(0x778)
    assert link.check(*answer(link, 0x1000, 305, nonce=old_nonce)) == Verdict.STALE
    assert link.session_id == 0x50000


def test_the_device_takes_only_its_own_session_with_a_growing_counter() -> None:
    frame, _ = gen.decode_message(gen.encode_frame(gen.Arm(), 1, key=KEY, session_id=7, counter=10))
    assert device_takes(frame, session_id=7, last_counter=9)
    assert not device_takes(frame, session_id=7, last_counter=10)
    assert not device_takes(frame, session_id=6, last_counter=0)  # a newer session is not the device's
    assert not device_takes(frame, session_id=None, last_counter=0)


@pytest.mark.parametrize("key", [b"short", "0123456789abcdef", None])
def test_the_key_must_be_16_bytes(key: object) -> None:
    with pytest.raises(InvalidArgument, match="key: expected 16 bytes"):
        LinkSession(key)

