"""SI views of TELEMETRY and EVENT messages (wire units converted by robowrangler.units)."""

from __future__ import annotations

import enum
from dataclasses import asdict, dataclass
from typing import Any

from robowrangler import units
from robowrangler.protocol import generated as gen
from robowrangler.protocol.generated import Cause, EventKind, Fault, State




def _enum_or_int(enum_cls, value: int):
    try:
        return enum_cls(value)
    except ValueError:  # a newer firmware may know more values: keep the number
        return value


@dataclass(frozen=True)
class TelemetrySample:
    """One TELEMETRY message in SI units.

    time_s: device time since boot [s]; received_s: host time.monotonic() at reception [s].
    Speeds in m/s at the wheel surface; counters are the device's wrapping uint16 counters.
    """

    time_s: float
    state: State
    fault_bits: Fault
    rope_speed_mps: float
    rope_speed_setpoint_mps: float
    rope_speed_target_mps: float
    motor_rpm: int
    esc_pulse_us: int
    battery_v: float
    heartbeat_age_s: float
    rx_ok: int
    rx_bad: int
    rx_duplicates: int
    nacks: int
    events: int
    tick_overruns: int
    received_s: float

    @classmethod
    def from_wire(cls, msg: gen.Telemetry, *, received_s: float) -> TelemetrySample:
        return cls(
            time_s=units.ms_to_s(msg.time_ms),
            state=_enum_or_int(State, msg.state),
            fault_bits=Fault(msg.fault_bits),
            rope_speed_mps=units.mmps_to_mps(msg.rope_speed_mmps),
            rope_speed_setpoint_mps=units.mmps_to_mps(msg.rope_speed_setpoint_mmps),
            rope_speed_target_mps=units.mmps_to_mps(msg.rope_speed_target_mmps),
            motor_rpm=msg.motor_rpm,
            esc_pulse_us=msg.esc_pulse_us,
            battery_v=units.mv_to_v(msg.battery_mv),
            heartbeat_age_s=units.ms_to_s(msg.heartbeat_age_ms),
            rx_ok=msg.rx_ok,
            rx_bad=msg.rx_bad,
            rx_duplicates=msg.rx_duplicates,
            nacks=msg.nacks,
            events=msg.events,
            tick_overruns=msg.tick_overruns,
            received_s=received_s,
        )

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready dict: enums as names, fault_bits as a list of fault names."""
        d = asdict(self)
        d["state"] = _name(self.state)
        d["fault_bits"] = [f.name for f in Fault if f in self.fault_bits]
        return d


@dataclass(frozen=True)
class DeviceEvent:
    """One EVENT message. `arg` is the raw argument; `cause` (STATE_CHANGED), `fault` (FAULT_RAISED),
    `speed_mps` (LOOP_COLLAPSED), `silence_s` (HEARTBEAT_LOST) and `param` (PARAM_CHANGED) give it in SI
    or as an enum where the event kind defines one, else None."""

    time_s: float
    event_seq: int
    kind: EventKind | int  # int for a kind this host does not know
    state_from: State
    state_to: State
    arg: int
    received_s: float

    @classmethod
    def from_wire(cls, msg: gen.Event, *, received_s: float) -> DeviceEvent:
        return cls(
            time_s=units.ms_to_s(msg.time_ms),
            event_seq=msg.event_seq,
            kind=_enum_or_int(EventKind, msg.event),
            state_from=_enum_or_int(State, msg.state_from),
            state_to=_enum_or_int(State, msg.state_to),
            arg=msg.arg,
            received_s=received_s,
        )

    @property
    def cause(self) -> Cause | int | None:
        return _enum_or_int(Cause, self.arg) if self.kind == EventKind.STATE_CHANGED else None

    @property
    def fault(self) -> Fault | None:
        return Fault(self.arg & 0xFFFF) if self.kind == EventKind.FAULT_RAISED else None

    @property
    def speed_mps(self) -> float | None:
        return units.mmps_to_mps(self.arg) if self.kind == EventKind.LOOP_COLLAPSED else None

    @property
    def silence_s(self) -> float | None:
        return units.ms_to_s(self.arg) if self.kind == EventKind.HEARTBEAT_LOST else None

    @property
    def param(self) -> str | None:
        if self.kind != EventKind.PARAM_CHANGED:
            return None
        return gen.PARAMS[self.arg].name if 0 <= self.arg < len(gen.PARAMS) else str(self.arg)

    def describe(self) -> str:
        """One human line, e.g. 'STATE_CHANGED ARMED -> SPINUP (COMMAND)'."""
        text = f"{_name(self.kind)} {_name(self.state_from)} -> {_name(self.state_to)}"
        extra = {
            EventKind.STATE_CHANGED: lambda: _name(self.cause),
            EventKind.FAULT_RAISED: lambda: str(self.fault.name if self.fault else self.arg),
            EventKind.LOOP_COLLAPSED: lambda: f"{self.speed_mps:.2f} m/s",
            EventKind.HEARTBEAT_LOST: lambda: f"silent {self.silence_s:.3f} s",
            EventKind.PARAM_CHANGED: lambda: str(self.param),
        }.get(self.kind)
        return f"{text} ({extra()})" if extra else text

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready dict: enums as names, plus the interpreted argument where there is one."""
        d = asdict(self)
        for key in ("kind", "state_from", "state_to"):
            d[key] = _name(d[key])
        for key in ("cause", "speed_mps", "silence_s", "param"):
            value = getattr(self, key)
            if value is not None:
                d[key] = _name(value)
        if self.fault is not None:
            d["fault"] = [f.name for f in Fault if f in self.fault]
        return d


def _name(value: Any) -> Any:
    return value.name if isinstance(value, enum.Enum) else value
