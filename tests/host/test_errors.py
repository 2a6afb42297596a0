"""Every NACK reason turns into a CommandRefused whose message names the command, the reason and what to do."""

from __future__ import annotations

import pytest

from robowrangler.errors import CommandRefused, UnknownParameter
from robowrangler.protocol.generated import MsgId, NackReason, State


@pytest.mark.parametrize("reason", list(NackReason))
@pytest.mark.parametrize("command", [MsgId.ARM, MsgId.SET_ROPE_SPEED, MsgId.PARAM_SET])
def test_every_reason_gives_a_readable_message(reason: NackReason, command: MsgId) -> None:
    err = CommandRefused(command_msg_id=command, reason=reason, state=State.ARMED, detail=0)
    text = str(err)
    assert text.startswith(f"{command.name} refused: {reason.name}: ") and len(text) > len(command.name) + 30
    assert err.reason is reason and err.state is State.ARMED


def test_unknown_reason_and_state_from_a_newer_firmware_are_kept_as_numbers() -> None:
    err = CommandRefused(command_msg_id=99, reason=200, state=42, detail=7)
    assert err.reason == 200 and err.state == 42
    assert str(err).startswith("message 99 refused: reason 200: ")


def test_frame_level_refusals_point_at_a_schema_mismatch() -> None:
    err = CommandRefused(command_msg_id=MsgId.ARM, reason=NackReason.BAD_CHECKSUM, state=State.DISARMED, detail=0)
    assert "the link corrupts data, or host and firmware protocol versions or schemas differ" in str(err)


def test_unknown_parameter_suggests_close_names_or_lists_all() -> None:
    typo = UnknownParameter("tov_margn")
    assert typo.close_matches[0] == "tov_margin" and str(typo).startswith("unknown parameter 'tov_margn'; did you mean tov_margin")
    assert "known: tov_mps, tov_margin" in str(UnknownParameter("zzz"))


@pytest.mark.parametrize("reason, text", [
    (NackReason.NOT_ON_THIS_LINK, "connect with serial://"),
    (NackReason.NO_KEY, "provision one over USB serial"),
    (NackReason.AUTH_FAILED, "connect with the device's link key"),
    (NackReason.NOT_HOMED, "command home first"),
])
def test_link_and_spindle_refusals_are_not_mistaken_for_damaged_frames(reason: NackReason, text: str) -> None:
    err = CommandRefused(command_msg_id=MsgId.ARM, reason=reason, state=State.DISARMED, detail=0)
    assert text in str(err) and "corrupts data" not in str(err)
