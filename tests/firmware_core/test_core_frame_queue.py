"""rw_frame_queue: frames between the board's control tick and its background loop.

FIFO with the sender/destination kept; a full queue refuses (counted) instead of waiting or overwriting; a
frame longer than a slot is kept truncated and marked oversize so the core refuses it as a whole.
"""

from __future__ import annotations

from board_io_ctypes import MAX_FRAME_LEN, OVERSIZE, QUEUE_SLOTS, FrameQueue


def test_frames_come_out_in_order_with_their_addresses(rw_core) -> None:
    q = FrameQueue(rw_core)
    frames = [bytes([i]) * (i + 1) for i in range(QUEUE_SLOTS)]
    for i, f in enumerate(frames):
        assert q.push(f, addr=0x0A000001 + i, port=14550 + i)
    assert q.count == QUEUE_SLOTS
    for i, f in enumerate(frames):
        assert q.pop() == (f, len(f), 0x0A000001 + i, 14550 + i)
    assert q.pop() is None


def test_a_full_queue_refuses_and_counts_never_overwrites(rw_core) -> None:
    q = FrameQueue(rw_core)
    for i in range(QUEUE_SLOTS):
        assert q.push(bytes([i]))
    assert not q.push(b"\xff")
    assert q.reserve() is None  # in-place producers are refused the same way
    assert q.obj.dropped == 2 and q.obj.high_water == QUEUE_SLOTS
    assert q.pop()[0] == b"\x00"
    assert q.push(b"\xee")
    assert [q.pop()[0] for _ in range(QUEUE_SLOTS)] == [b"\x01", b"\x02", b"\x03", b"\xee"]


def test_an_oversize_frame_is_marked_so_the_core_refuses_it(rw_core) -> None:
    q = FrameQueue(rw_core)
    long_frame = bytes(range(MAX_FRAME_LEN)) + b"tail"
    assert q.push(long_frame)
    data, length, _, _ = q.pop()
    assert length == OVERSIZE and data == long_frame[:MAX_FRAME_LEN]
    assert q.obj.oversize == 1


def test_reserve_fills_in_place_and_nothing_shows_before_publish(rw_core) -> None:
    q = FrameQueue(rw_core)
    slot = q.reserve()
    slot.bytes[0], slot.bytes[1] = 0xAA, 0xBB
    slot.len, slot.addr, slot.port = 2, 7, 8
    assert q.pop() is None, "a reserved slot is not visible to the consumer until published"
    q.publish()
    assert q.pop() == (b"\xaa\xbb", 2, 7, 8)


def test_the_indices_wrap_around_2_to_the_32(rw_core) -> None:
    q = FrameQueue(rw_core)
    q.obj.head = q.obj.tail = 0xFFFF_FFFE
    for i in range(3 * QUEUE_SLOTS):
        assert q.push(bytes([i, i]))
        assert q.count == 1
        assert q.pop()[0] == bytes([i, i])
    assert q.obj.head == q.obj.tail == (0xFFFF_FFFE + 3 * QUEUE_SLOTS) & 0xFFFF_FFFF
