"""rw_spindle_exchange: the AX-12A's read and write split between the control tick and the bus side.

The tick takes the reading the bus completed since its previous take and asks for the next; it posts the
moving speed to write. The bus side writes the latest post first, then reads the latest request. A lost
reply or a late bus is a step without a reading (counted), never a stale or half-written one.
"""

from __future__ import annotations

from board_io_ctypes import JobKind, SpindleExchange
from spindle_ctypes import SpindleReading


def reading(position_raw: int, *, load_raw: int = 0, switch: bool = False) -> SpindleReading:
    return SpindleReading(position_raw=position_raw, speed_raw=0, load_raw=load_raw, limit_switch=switch)


def serve(ex: SpindleExchange, value: SpindleReading | None, *, answered: bool = True) -> list[JobKind]:
    """Run the bus side until it has nothing to do; reads answer with value (None: reply lost)."""
    done = []
    for _ in range(10):
        job = ex.next_job()
        if job.kind == JobKind.NONE:
            return done
        if job.kind == JobKind.WRITE:
            ex.write_done(job, answered=answered)
        else:
            ex.read_done(job, value)
        done.append(JobKind(job.kind))
    raise AssertionError("the bus side never ran out of jobs")


def test_a_reading_reaches_the_core_one_step_after_its_request(rw_core) -> None:
    ex = SpindleExchange(rw_core)
    assert ex.take() is None  # nothing read yet: the first step has no reading
    ex.post(100)
    assert serve(ex, reading(512, load_raw=30)) == [JobKind.WRITE, JobKind.READ]  # the write goes first
    got = ex.take()
    assert got is not None and got.position_raw == 512 and got.load_raw == 30
    assert ex.take() is None, "a reading is handed over once"
    c = ex.counters
    assert (c.requests, c.taken, c.missing, c.reads_ok, c.writes_ok) == (3, 1, 2, 1, 1)


def test_a_lost_reply_is_a_step_without_reading_and_the_next_read_works(rw_core) -> None:
    ex = SpindleExchange(rw_core)
    ex.take()
    serve(ex, reading(400))
    assert ex.take().position_raw == 400
    serve(ex, None)  # the reply to this request is lost
    assert ex.take() is None
    serve(ex, reading(410))
    assert ex.take().position_raw == 410
    c = ex.counters
    assert (c.reads_ok, c.reads_failed, c.missing, c.late) == (2, 1, 2, 0)


def test_only_the_latest_post_is_written(rw_core) -> None:
    ex = SpindleExchange(rw_core)
    for raw in (10, 20, 1024 + 30):  # three spindle steps while the bus side was busy elsewhere
        ex.post(raw)
    job = ex.next_job()
    assert job.kind == JobKind.WRITE and job.moving_speed_raw == 1024 + 30
    ex.write_done(job, answered=False)  # no status packet: counted, not retried
    assert ex.next_job().kind == JobKind.NONE
    assert (ex.counters.writes_ok, ex.counters.writes_failed) == (0, 1)


def test_a_late_bus_serves_the_latest_request_once_and_counts_the_late_ones(rw_core) -> None:
    ex = SpindleExchange(rw_core)
    for _ in range(3):
        assert ex.take() is None  # the bus side did not run between these steps
    assert serve(ex, reading(700)) == [JobKind.READ]
    assert ex.take().position_raw == 700
    assert ex.counters.late == 2


def test_a_tick_between_job_and_result_neither_loses_nor_doubles_anything(rw_core) -> None:
    ex = SpindleExchange(rw_core)
    ex.take()
    job = ex.next_job()  # the bus side starts the read ...
    assert job.kind == JobKind.READ
    assert ex.take() is None  # ... the tick interrupts: no reading yet, a new request
    ex.post(55)
    ex.read_done(job, reading(123))  # ... the bus side finishes the first read
    assert ex.take().position_raw == 123
    kinds = serve(ex, reading(124))
    assert kinds == [JobKind.WRITE, JobKind.READ]
    assert ex.take().position_raw == 124


def test_results_of_the_wrong_kind_are_ignored(rw_core) -> None:
    ex = SpindleExchange(rw_core)
    ex.post(5)
    job = ex.next_job()
    ex.read_done(job, reading(1))  # a write job reported as a read: nothing published, nothing served
    assert ex.take() is None and ex.next_job().kind == JobKind.WRITE
