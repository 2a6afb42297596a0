"""Telemetry, events, heartbeats and bad data as the client sees them, from the real firmware core
(core_device.py). Times are the device's (simulated) clock; wall time only as a lower bound."""

from __future__ import annotations

import time

import pytest

from host_settings import FAST, QUICK_ARM
from core_device import CoreDevice, lose_messages
from robowrangler.client import Client
from robowrangler.errors import LinkTimeout, StateTimeout
from robowrangler.protocol import generated as gen
from robowrangler.protocol.generated import Cause, EventKind, Fault, MsgId, State
from robowrangler.telemetry import TelemetrySample
from wire import make

PAST_HOLD = dict(params=QUICK_ARM, boot_s=0.25)


def client(device: CoreDevice, **options) -> Client:
    return Client(transport=device.transport(), key=device.key, **{**FAST, **options})


def test_telemetry_samples_are_si_and_in_order(core_lib) -> None:
    with CoreDevice(core_lib, **PAST_HOLD) as device, client(device) as rw:
        rw.arm()
        rw.spin(4.0)
        samples = []
        for s in rw.telemetry():
            samples.append(s)
            if len(samples) == 10:
                break
    times = [s.time_s for s in samples]
    assert times == sorted(times) and times[-1] - times[0] == pytest.approx(0.18)  # 50 Hz of device time
    last = samples[-1]
    assert last.rope_speed_target_mps == 4.0 and 0 < last.rope_speed_mps <= 4.0
    assert last.battery_v == 14.8 and last.fault_bits == Fault(0) and isinstance(last.state, State)
    d = last.to_dict()
    assert d["state"] in ("SPINUP", "AIRBORNE") and d["fault_bits"] == []


def test_wait_for_state_returns_the_sample_and_times_out_typed(core_lib) -> None:
    with CoreDevice(core_lib, **PAST_HOLD) as device, client(device) as rw:
        rw.arm()
        rw.spin(5.0)
        reached = rw.wait_for_state(State.AIRBORNE, timeout_s=2.0)
        assert reached.state == State.AIRBORNE and reached.rope_speed_mps >= 2.99
        with pytest.raises(StateTimeout) as info:
            rw.wait_for_state([State.DISARMED, State.ESTOP], timeout_s=0.2)
    assert info.value.actual == State.AIRBORNE
    assert str(info.value) == "state: expected DISARMED or ESTOP within 0.2 s, still AIRBORNE"


def test_telemetry_that_stops_is_a_link_timeout(device: CoreDevice) -> None:
    with client(device) as rw:
        device.halt()
        with pytest.raises(LinkTimeout, match="telemetry from .* stopped: no sample for 0.2 s"):
            for _ in rw.telemetry(timeout_s=0.2):
                pass


def test_closing_the_client_ends_open_telemetry_iterators(device: CoreDevice) -> None:
    rw = client(device).connect()
    stream = rw.telemetry()
    next(stream)
    rw.close()
    rest = list(stream)  # ends, instead of waiting connect_timeout_s for a sample and raising LinkTimeout
    assert len(rest) <= 3  # at most what was queued when the client closed


def test_heartbeats_keep_a_spinning_rope_up_while_the_host_idles(core_lib) -> None:
    with CoreDevice(core_lib, **PAST_HOLD) as device, client(device, heartbeat_hz=10.0) as rw:
        rw.arm()
        rw.spin(5.0)
        rw.wait_for_state(State.AIRBORNE, timeout_s=2.0)
        start_s = device.time_s
        while device.time_s < start_s + 1.0:  # 1 s of device time: twice heartbeat_timeout_s
            time.sleep(0.05)
        sample = next(rw.telemetry())
    assert sample.state == State.AIRBORNE and sample.heartbeat_age_s < 0.5
    assert not [t for t in device.transitions() if t[3] == Cause.HEARTBEAT_LOST]
    assert len(device.host_sent(MsgId.HEARTBEAT)) >= 5


def test_events_arrive_in_si_and_lost_ones_are_counted(core_lib) -> None:
    with CoreDevice(core_lib, **PAST_HOLD) as device:
        device.to_host.append(lose_messages(gen.Event, 1, when=lambda e: e.state_to == State.SPINUP))
        with client(device) as rw:
            rw.arm()                            # DISARMED -> ARMED
            rw.spin(5.0)                        # ARMED -> SPINUP (lost on the way)
            rw.wait_for_state(State.AIRBORNE, timeout_s=2.0)
            rw.wait_for(lambda s: True, timeout_s=1.0)  # SPINUP -> AIRBORNE is in by the next sample
            events, stats = rw.events, rw.stats
    changes = [e for e in events if e.kind == EventKind.STATE_CHANGED]
    assert [e.state_to for e in changes] == [State.ARMED, State.AIRBORNE]
    assert stats.events_lost == 1 and changes[1].event_seq - changes[0].event_seq == 2
    assert changes[1].describe() == "STATE_CHANGED SPINUP -> AIRBORNE (SPEED_REACHED)"
    assert changes[1].to_dict()["cause"] == "SPEED_REACHED"


def test_bad_datagrams_are_counted_never_raised(core_lib) -> None:
    with CoreDevice(core_lib, **PAST_HOLD) as device, client(device) as rw:
        good = gen.encode_frame(make(gen.Telemetry), 7)
        corrupted = good[:-1] + bytes([good[-1] ^ 0xFF])
        for junk in (b"", b"\x00" * 3, b"hello world", corrupted, good + b"\x00"):
            device.send_to_host(junk)
        assert rw.arm() == State.ARMED  # the receiver thread survived
        stats = rw.stats
    assert stats.decode_errors == 5
    assert stats.decode_errors_by_reason == {"TRUNCATED": 2, "BAD_MAGIC": 1, "BAD_CHECKSUM": 1, "BAD_LENGTH": 1}


def test_wait_for_state_tells_a_silent_link_from_a_slow_state(device: CoreDevice) -> None:
    with client(device, connect_timeout_s=0.3) as rw:
        device.halt()
        with pytest.raises(StateTimeout) as slow:  # shorter than a telemetry gap: just not there yet
            rw.wait_for_state(State.ARMED, timeout_s=0.1)
        with pytest.raises(LinkTimeout) as gone:  # longer: the link is gone
            rw.wait_for_state(State.ARMED, timeout_s=5.0)
    assert slow.value.actual == State.DISARMED and gone.value.waited_s == pytest.approx(0.3)


def test_values_from_a_newer_firmware_are_kept_not_fatal(core_lib) -> None:
    """Unsigned (serial link): a newer firmware's state and fault bit, and an event kind this host does not know."""
    with CoreDevice(core_lib, link="serial", **PAST_HOLD) as device:
        with Client(transport=device.transport(), **FAST) as rw:
            stream = rw.telemetry()  # subscribed from here on
            future = make(gen.Telemetry, time_ms=987654, state=99, fault_bits=0x80, esc_pulse_us=1000,
                          battery_mv=12000)
            device.send_to_host(gen.encode_frame(future, 1))
            device.send_to_host(gen.encode_frame(make(gen.Event, time_ms=987654, event=77, state_from=1,
                                                      state_to=1), 2))
            odd = next(s for s in stream if s.time_s == 987.654)
            assert rw.arm() == State.ARMED
            rw.wait_for(lambda s: True, timeout_s=1.0)
            events, stats = rw.events, rw.stats
    assert odd.state == 99 and int(odd.fault_bits) == 0x80
    assert events[0].kind == 77 and events[0].describe() == "77 ARMED -> ARMED"
    assert stats.decode_errors == 0


SI_NAMES = {"_mmps": "_mps", "_um": "_m", "_mv": "_v", "_ms": "_s", "_permille": "_pct"}


def _si_name(wire_name: str) -> str:
    for wire, si in SI_NAMES.items():
        if wire_name.endswith(wire):
            return wire_name[: -len(wire)] + si
    return {"battery_mv": "battery_v"}.get(wire_name, wire_name)


def test_every_telemetry_field_on_the_wire_has_its_si_view() -> None:
    import dataclasses

    sample_fields = {f.name for f in dataclasses.fields(TelemetrySample)}
    assert {_si_name(f.name) for f in gen.Telemetry.FIELDS} == sample_fields - {"received_s"}


def test_si_values_are_the_wire_values_converted() -> None:
    wire = make(gen.Telemetry, time_ms=1234, rope_speed_mmps=2990, battery_mv=11100, guide_position_um=62500,
                spindle_load_permille=-125, heartbeat_age_ms=40, rx_replayed=3)
    s = TelemetrySample.from_wire(wire, received_s=0.0)
    assert (s.time_s, s.rope_speed_mps, s.battery_v, s.guide_position_m, s.spindle_load_pct, s.heartbeat_age_s,
            s.rx_replayed) == (1.234, 2.99, 11.1, 0.0625, -12.5, 0.04, 3)
