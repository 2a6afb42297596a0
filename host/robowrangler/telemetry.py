"""SI views of TELEMETRY and EVENT messages (wire units converted by robowrangler.units)."""

from __future__ import annotations

import enum
from dataclasses import asdict, dataclass
from typing import Any

from robowrangler import units
from robowrangler.protocol import generated as gen
from robowrangler.protocol.generated import Cause, EventKind, Fault, SpindleFlag, State




def _enum_or_int(enum_cls, value: int):
    try:
        return enum_cls(value)
    except ValueError:  # a newer firmware may know more values: keep the number
        return value


@dataclass(frozen=True)
class TelemetrySample:
    """One TELEMETRY message in SI units.

    time_s: device time since boot [s]; received_s: host time.monotonic() at reception [s].
    Speeds in m/s at the wheel surface; guide positions in m from home (valid when spindle_flags has
    HOMED); spindle_load_pct in % of the AX-12A's maximum torque, + = resisting retraction; counters are
    the device's wrapping uint16 counters. esc_pulse_fine_us is the pulse at the PWM timer's 1/3 us;
    encoder_counts (edges since boot) and encoder_edge_us (latest edge, us since boot) wrap at 2^32: between
    two samples their differences give the raw M/T edge period (robowrangler.recorder.encoder_period).
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
    guide_position_m: float
    guide_target_m: float
    spindle_load_pct: float
    spindle_flags: SpindleFlag
    spindle_rejected: int
    rx_auth_failed: int
    rx_replayed: int
    tx_dropped: int
    esc_pulse_fine_us: float
    spindle_moving_speed_raw: int
    encoder_counts: int
    encoder_edge_us: int
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
            guide_position_m=units.um_to_m(msg.guide_position_um),
            guide_target_m=units.um_to_m(msg.guide_target_um),
            spindle_load_pct=units.permille_to_pct(msg.spindle_load_permille),
            spindle_flags=SpindleFlag(msg.spindle_flags),
            spindle_rejected=msg.spindle_rejected,
            rx_auth_failed=msg.rx_auth_failed,
            rx_replayed=msg.rx_replayed,
            tx_dropped=msg.tx_dropped,
            esc_pulse_fine_us=msg.esc_pulse_third_us / 3,
            spindle_moving_speed_raw=msg.spindle_moving_speed_raw,
            encoder_counts=msg.encoder_counts,
            encoder_edge_us=msg.encoder_edge_us,
            received_s=received_s,
        )

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready dict: enums as names, fault_bits as a list of fault names."""
        d = asdict(self)
        d["state"] = _name(self.state)
        d["fault_bits"] = [f.name for f in Fault if f in self.fault_bits]
        d["spindle_flags"] = [f.name for f in SpindleFlag if f in self.spindle_flags]
        return d


@dataclass(frozen=True)
class DeviceEvent:
    """One EVENT message. `arg` is the raw argument; `cause` (STATE_CHANGED), `fault` (FAULT_RAISED,
    FAULT_CLEARED), `speed_mps` (LOOP_COLLAPSED), `silence_s` (HEARTBEAT_LOST), `param` (PARAM_CHANGED),
    `guide_position_m` (SPINDLE_TARGET_REACHED) and `homed_by` (SPINDLE_HOMED) give it in SI or as an enum
    where the event kind defines one, else None."""

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
        """The fault bits raised (FAULT_RAISED) or cleared (FAULT_CLEARED)."""
        if self.kind in (EventKind.FAULT_RAISED, EventKind.FAULT_CLEARED):
            return Fault(self.arg & 0xFFFF)
        return None

    @property
    def guide_position_m(self) -> float | None:
        """Where the guide stopped (SPINDLE_TARGET_REACHED)."""
        return units.um_to_m(self.arg) if self.kind == EventKind.SPINDLE_TARGET_REACHED else None

    @property
    def homed_by(self) -> str | None:
        """SPINDLE_HOMED: 'stall' or 'limit_switch'."""
        if self.kind != EventKind.SPINDLE_HOMED:
            return None
        return {1: "stall", 2: "limit_switch"}.get(self.arg, str(self.arg))

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
            EventKind.FAULT_RAISED: lambda: _flags(self.fault),
            EventKind.FAULT_CLEARED: lambda: _flags(self.fault),
            EventKind.SPINDLE_TARGET_REACHED: lambda: f"guide at {units.m_to_mm(self.guide_position_m):.1f} mm",
            EventKind.SPINDLE_HOMED: lambda: f"by {self.homed_by}",
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
        for key in ("cause", "speed_mps", "silence_s", "param", "guide_position_m", "homed_by"):
            value = getattr(self, key)
            if value is not None:
                d[key] = _name(value)
        if self.fault is not None:
            d["fault"] = [f.name for f in Fault if f in self.fault]
        return d


@dataclass(frozen=True)
class ProvisionStatus:
    """PROVISION_STATUS: what the device has stored (the key and the WiFi password are never sent back).

    boot_counter is the session id of the current boot; commits counts flash writes (wear); dirty says
    something was set since the last commit."""

    key_set: bool
    password_set: bool
    wifi_ssid: str
    boot_counter: int
    commits: int
    config_version: int
    dirty: bool

    @classmethod
    def from_wire(cls, msg: Any) -> ProvisionStatus:
        return cls(bool(msg.key_set), bool(msg.password_set), msg.wifi_ssid, msg.boot_counter, msg.commits,
                   msg.config_version, bool(msg.dirty))

    def to_dict(self) -> dict[str, Any]:
        return asdict(self)


def _flags(bits: Fault | None) -> str:
    return "|".join(f.name for f in Fault if bits is not None and f in bits) or "none"


def _name(value: Any) -> Any:
    return value.name if isinstance(value, enum.Enum) else value
