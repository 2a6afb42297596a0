"""Typed exceptions of the host library: every message names what was expected and what happened.

The CLI maps each class to one exit status (robowrangler.cli.exit_status); nothing else should need
to parse these messages.
"""

from __future__ import annotations

import difflib

from robowrangler.protocol.generated import MsgId, NackReason, PARAMS, PARAMS_BY_NAME, State


class RoboWranglerError(Exception):
    """Base of every error this package raises on purpose."""


class InvalidArgument(RoboWranglerError, ValueError):
    """A local argument cannot be used (wrong type, NaN, not encodable on the wire, malformed URL).

    Raised before anything is sent. Values the device range-checks are sent anyway so that the
    device answers with a NACK (CommandRefused): range checking is the device's job.
    """

    def __init__(self, argument: str, expected: str, actual: object) -> None:
        super().__init__(f"{argument}: expected {expected}, got {actual!r}")
        self.argument = argument
        self.expected = expected
        self.actual = actual


class UnknownParameter(RoboWranglerError, LookupError):
    """A parameter name that is not in the protocol's parameter table."""

    def __init__(self, name: object) -> None:
        known = [p.name for p in PARAMS]
        close = difflib.get_close_matches(str(name), known, n=3)
        hint = f"; did you mean {', '.join(close)}?" if close else f"; known: {', '.join(known)}"
        super().__init__(f"unknown parameter {name!r}{hint}")
        self.name = name
        self.close_matches = close

    def __str__(self) -> str:  # LookupError would repr() the message
        return self.args[0]


class LinkTimeout(RoboWranglerError, TimeoutError):
    """The device did not answer in time (no TELEMETRY on connect, no ACK/NACK after every retry,
    or the telemetry stream stopped). `url` names the link, `waited_s` how long was waited."""

    def __init__(self, message: str, *, url: str, waited_s: float) -> None:
        super().__init__(message)
        self.url = url
        self.waited_s = waited_s


class LinkError(RoboWranglerError, OSError):
    """The link cannot be opened (serial port missing or busy, host name not resolvable)."""

    def __init__(self, message: str, *, url: str) -> None:
        super().__init__(message)
        self.url = url

    def __str__(self) -> str:  # OSError would format (errno, strerror) pairs
        return self.args[0]


class AuthenticationError(RoboWranglerError):
    """The link key and the device do not agree: no key given where the device requires signed frames,
    a wrong key (the device's SESSION_INFO does not verify), or a device without a provisioned key.
    ``needs_key``: the first case (this host has no key; the device signs)."""

    def __init__(self, message: str, *, url: str, needs_key: bool = False) -> None:
        super().__init__(message)
        self.url = url
        self.needs_key = needs_key


class StateTimeout(RoboWranglerError, TimeoutError):
    """Telemetry kept arriving but the device did not reach the awaited state (or condition) in time.
    `expected` is a tuple of States or a description of the condition."""

    def __init__(self, *, expected: tuple[State, ...] | str, actual: State | None, waited_s: float) -> None:
        names = expected if isinstance(expected, str) else " or ".join(s.name for s in expected)
        got = actual.name if actual is not None else "no telemetry"
        super().__init__(f"state: expected {names} within {waited_s:g} s, still {got}")
        self.expected = expected
        self.actual = actual
        self.waited_s = waited_s


class NotConnected(RoboWranglerError):
    """A command or telemetry read on a client that is not connected (call connect() or use `with`)."""


class CommandRefused(RoboWranglerError):
    """The device answered a command with NACK: nothing was executed.

    Attributes: command (message name), reason (NackReason), state (device State when refusing),
    detail (raw NACK.detail, wire units), value (the SI argument sent, if any), param (parameter
    name for PARAM_GET/PARAM_SET, else None).
    """

    def __init__(self, *, command_msg_id: int, reason: int, state: int, detail: int,
                 value: float | None = None, param: str | None = None) -> None:
        self.command_msg_id = command_msg_id
        self.command = _msg_name(command_msg_id)
        self.reason = _as_enum(NackReason, reason)
        self.state = _as_enum(State, state)
        self.detail = detail
        self.value = value
        self.param = param
        super().__init__(f"{self.command} refused: {_reason_name(self.reason)}: {self._explain()}")

    def _explain(self) -> str:
        from robowrangler import units  # units raises InvalidArgument: import here, not at module level

        r, st, cmd = self.reason, _state_name(self.state), self.command_msg_id
        if r == NackReason.BELOW_TOV_GUARD:
            guard = units.mmps_to_mps(self.detail)
            return (f"{_fmt(self.value)} m/s is under the ToV guard {guard:.2f} m/s while airborne; "
                    "command spindown to land")
        if r == NackReason.OUT_OF_RANGE:
            if cmd == MsgId.SET_ROPE_SPEED and self.value is not None and self.value == 0:
                return "0 m/s is not a speed target: to stop the rope, command spindown (`wrangler spindown`)"
            if cmd == MsgId.SET_ROPE_SPEED:
                limit = units.mmps_to_mps(self.detail)
                return (f"rope speed {_fmt(self.value)} m/s is out of range (limit crossed: {limit:g} m/s; "
                        "valid: 0 < v <= max_rope_speed_mps)")
            if cmd == MsgId.SET_LOOP:
                limit_mm = units.m_to_mm(units.um_to_m(self.detail))
                where = "" if self.value is None else f"{units.m_to_mm(self.value):g} mm "
                return (f"guide position {where}is outside the soft limits (limit crossed: {limit_mm:g} mm; "
                        "valid: guide_min_mm..guide_max_mm)")
            spec = PARAMS_BY_NAME.get(self.param or "")
            if spec is not None:
                if (spec.integer and self.value is not None and spec.min <= self.value <= spec.max
                        and self.value != int(self.value)):
                    return f"{spec.name} = {_fmt(self.value)} is not an integer ({spec.units})"
                return (f"{spec.name} = {_fmt(self.value)} is outside [{spec.min:g}, {spec.max:g}] {spec.units}"
                        + ("; it must be an integer" if spec.integer else ""))
            return f"a field is out of range (limit crossed: {self.detail}, wire units)"
        if r == NackReason.BAD_STATE:
            return f"not accepted in state {st}; {_bad_state_advice(cmd, self.state)}"
        if r == NackReason.NOT_READY:
            return "the ESC arming hold after boot is not finished; retry in a moment"
        if r == NackReason.UNKNOWN_PARAM:
            return (f"the device has no parameter {self.param!r}: host and firmware parameter tables "
                    "differ; update one of them")
        if r == NackReason.PARAM_CONFLICT:
            other = PARAMS[self.detail].name if 0 <= self.detail < len(PARAMS) else f"parameter #{self.detail}"
            rule = ("guide_min_mm must stay below guide_max_mm" if other.startswith("guide_")
                    else "tov_mps x tov_margin (the ToV guard) must stay at or below max_rope_speed_mps")
            return (f"{self.param} = {_fmt(self.value)} breaks a rule with {other}: {rule}; "
                    f"change {other} first (`wrangler param get {other}`)")
        if r == NackReason.PARAM_LOCKED:
            return f"{self.param} can only be set while DISARMED (state is {st}); disarm first"
        if r == NackReason.NOT_HOMED:
            return "the spindle has not been homed since boot; command home first"
        if r == NackReason.SPINDLE_UNAVAILABLE:
            return (f"the spindle servo does not answer or is in fault (fault bits 0x{self.detail & 0xFFFF:X}); "
                    "check the AX-12A's power and bus, then disarm to clear the fault")
        if r == NackReason.NOT_ON_THIS_LINK:
            return "provisioning is taken on the USB serial link only: connect with serial://"
        if r == NackReason.NO_KEY:
            return ("the device has no link key, so it takes no command over WiFi: provision one over USB serial "
                    "(wrangler provision set --generate-key PATH)")
        if r in (NackReason.UNSIGNED, NackReason.AUTH_FAILED, NackReason.REPLAYED):
            return ("the frame's signature was refused (missing, wrong key, or an old session/counter): connect "
                    "with the device's link key")
        if r == NackReason.NOT_A_COMMAND:
            return "the device does not accept this message from a host"
        if r == NackReason.UNKNOWN_MESSAGE:
            return "the firmware does not know this command: update the firmware or use an older host"
        return ("the device could not read the frame on any attempt: the link corrupts data, or host and "
                "firmware protocol versions or schemas differ (update one of them)")


def _bad_state_advice(cmd: int, state: State | int) -> str:
    if state in (State.ESTOP, State.FAULT):
        return "disarm to clear it once the rope has stopped, then arm"
    if cmd == MsgId.SET_ROPE_SPEED and state == State.DISARMED:
        return "arm first"
    if cmd == MsgId.DISARM:
        return "spin down first and wait for ARMED"
    if cmd == MsgId.ARM:
        return "the device is already armed or the rope still moves"
    if cmd == MsgId.SPINDOWN:
        return "nothing to spin down"
    needs = {
        MsgId.SET_LOOP: "the loop size can be set in ARMED, SPINUP or AIRBORNE",
        MsgId.RELAX: "relax needs a spinning rope (SPINUP or AIRBORNE)",
        MsgId.RETRACT: "retract needs ARMED, or RELAX once the rope has stopped",
        MsgId.GRASP: "grasp needs AIRBORNE: spin up above the ToV guard first",
        MsgId.RELEASE: "release needs HOLD (an object held)",
        MsgId.HOME: "home needs DISARMED or ARMED with the rope stopped",
    }
    if cmd in needs:
        return needs[cmd]
    return "check the state with `wrangler status`"


def _fmt(value: float | None) -> str:
    return "?" if value is None else f"{value:g}"


def _as_enum(enum_cls, value: int):
    try:
        return enum_cls(value)
    except ValueError:
        return value


def _reason_name(reason: NackReason | int) -> str:
    return reason.name if isinstance(reason, NackReason) else f"reason {reason}"


def _state_name(state: State | int) -> str:
    return state.name if isinstance(state, State) else f"state {state}"


def _msg_name(msg_id: int) -> str:
    try:
        return MsgId(msg_id).name
    except ValueError:
        return f"message {msg_id}"
