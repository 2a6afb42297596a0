"""rw_core burst capture (BURST_START -> BURST_DATA), through the real core: every tick after the command is
sampled (encoder, the pulse written, battery), the samples stream out after the capture without delaying
telemetry or changing a single ESC pulse, a lost frame shows as missing samples, and a second burst or a bad
size is refused with a reason."""

from __future__ import annotations

from core_harness import U32, CoreHarness
from robowrangler.protocol import generated as proto
from robowrangler.protocol.generated import Ack, BurstData, BurstStart, Heartbeat, Nack, NackReason
from robowrangler.recorder.burst import assemble, burst_record

MAX_SAMPLES = 1000  # RW_BURST_MAX_SAMPLES (firmware/core/rw_burst.h)


def _airborne(rw_core, **kw) -> CoreHarness:
    h = CoreHarness(rw_core, **kw)
    h.boot_and_arm()
    h.spin_to_airborne(target_mmps=4000)
    return h


def _follow(h: CoreHarness, ms: int, trace: list | None = None) -> None:
    """ms ticks with a perfect plant (the rope at the setpoint) and heartbeats; trace gets (counts, pulse) per
    tick (the HAL's encoder count the tick read and the pulse it wrote)."""
    for _ in range(ms):
        tel = h.telemetry()
        if tel:
            h.encoder.speed_mps = tel[-1].rope_speed_setpoint_mmps / 1000.0
        if h.t_ms % 100 == 0:
            h.heartbeat()
        h.tick()
        if trace is not None:
            trace.append((h.hal.encoder_counts, h.hal.pulses_us[-1]))


def _capture(h: CoreHarness, samples: int, *, stream_ms: int = 1500) -> tuple[Ack, list, list]:
    """BURST_START, follow the setpoint until every frame is out; (verdict, trace from the command's tick on,
    the BURST_DATA frames as Out records)."""
    since = len(h.hal.out)
    verdict = h.command(BurstStart(samples))
    trace: list = [(h.hal.encoder_counts, h.hal.pulses_us[-1])]  # the tick that took the command is sample 0
    _follow(h, stream_ms, trace)
    return verdict, trace, h.sent(BurstData, since=since)


def test_burst_samples_every_tick_and_streams_them_all(rw_core):
    h = _airborne(rw_core, encoder_count_offset=U32 - 300)  # the counter wraps during the burst
    counts0 = h.hal.encoder_counts
    verdict, trace, frames = _capture(h, 400)
    assert isinstance(verdict, Ack)
    assert len(frames) == -(-400 // proto.BURST_SAMPLES_PER_FRAME)
    burst, = assemble([burst_record(o.msg, seq=o.frame.seq) for o in frames])
    assert burst.complete and burst.sample_count == 400 and burst.tick_s == 1e-3
    # sample 0 is the tick that took the command: the pulse that tick wrote, the count it read, and so on
    expected_pulse = [3 * p / 3 for _, p in trace[:400]]
    assert list(burst.esc_pulse_fine_us) == expected_pulse
    expected_counts = [((c - counts0) - (trace[0][0] - counts0)) % U32 for c, _ in trace[:400]]
    assert list(burst.encoder_counts) == expected_counts
    assert expected_counts[-1] > 100, "the rope turned during the burst"
    assert set(burst.battery_v) == {h.hal.battery_mv / 1000}
    # the M/T period from the samples: 4 m/s on a 15 mm wheel with 64 edges a turn = 368 us an edge
    period_us = burst.edge_period_us()
    mean = sum(p for p in period_us if p == p) / sum(1 for p in period_us if p == p)
    assert abs(mean - 2e6 * 3.141592653589793 * 0.015 / (4.0 * 64)) < 5.0


def test_burst_changes_no_pulse_and_no_telemetry(rw_core):
    with_burst, without = _airborne(rw_core), _airborne(rw_core)
    since = len(with_burst.hal.out), len(without.hal.out)
    assert isinstance(with_burst.command(BurstStart(MAX_SAMPLES)), Ack)
    without.queue(without.frame(Heartbeat(without.t_ms)))  # the same tick receives a frame there too
    without.tick()
    _follow(with_burst, 3500)  # 1 s of capture, then about 80 frames a second at 50 Hz telemetry
    _follow(without, 3500)
    assert with_burst.hal.pulses_us == without.hal.pulses_us, "not one ESC pulse differs"
    tel_a = [o.msg for o in with_burst.sent(proto.Telemetry, since=since[0])]
    tel_b = [o.msg for o in without.sent(proto.Telemetry, since=since[1])]
    assert [t.time_ms for t in tel_a] == [t.time_ms for t in tel_b], "every telemetry frame, on time"
    assert tel_a[-1].tx_dropped == 0 and tel_a[-1].tick_overruns == 0
    assert len(with_burst.sent(BurstData, since=since[0])) == -(-MAX_SAMPLES // proto.BURST_SAMPLES_PER_FRAME)
    # and the frames leave in the link's order: telemetry never waits behind a burst frame for long
    tel_out = [o.tick_ms - o.msg.time_ms for o in with_burst.sent(proto.Telemetry, since=since[0])]
    assert max(tel_out) <= 10


def test_a_lost_burst_frame_is_a_gap(rw_core):
    h = _airborne(rw_core)
    _, _, frames = _capture(h, 100)
    kept = [o for i, o in enumerate(frames) if i != 3]  # the link loses the fourth frame
    burst, = assemble([burst_record(o.msg, seq=o.frame.seq) for o in kept])
    n = proto.BURST_SAMPLES_PER_FRAME
    assert not burst.complete and burst.missing == [(3 * n, 4 * n - 1)] and burst.missing_samples == n
    assert all(v != v for v in burst.esc_pulse_fine_us[3 * n:4 * n]), "NaN where nothing came"


def test_burst_refusals_name_the_reason(rw_core):
    h = _airborne(rw_core)
    for samples in (0, MAX_SAMPLES + 1):
        nack = h.command(BurstStart(samples))
        assert isinstance(nack, Nack) and nack.reason == NackReason.OUT_OF_RANGE and nack.detail == MAX_SAMPLES
    assert isinstance(h.command(BurstStart(200)), Ack)
    _follow(h, 50)
    busy = h.command(BurstStart(10))
    assert isinstance(busy, Nack) and busy.reason == NackReason.BURST_BUSY
    assert 0 < busy.detail <= 200, "samples still to capture or stream"
    _follow(h, 1000)  # captured and streamed: a new burst is taken, with the next burst id
    assert isinstance(h.command(BurstStart(10)), Ack)
    _follow(h, 100)
    ids = [o.msg.burst_id for o in h.sent(BurstData)]
    assert ids[0] == 0 and ids[-1] == 1
