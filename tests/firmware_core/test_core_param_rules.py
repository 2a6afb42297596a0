"""Parameters that must hold together are checked together, on the device (issue 18 item 5): a PARAM_SET
that breaks guide_min_mm < guide_max_mm or tov_mps x tov_margin <= max_rope_speed_mps is refused with
PARAM_CONFLICT (detail = the other parameter's id) and changes nothing; every SET_LOOP stays possible."""

from __future__ import annotations

import pytest

from core_harness import CoreHarness
from robowrangler.protocol.generated import PARAMS_BY_NAME, Ack, EventKind, Nack, NackReason, ParamSet

P = PARAMS_BY_NAME


def _booted(rw_core) -> CoreHarness:
    h = CoreHarness(rw_core)
    h.tick()
    h.run_ms(50)
    return h


def _set(h: CoreHarness, name: str, value: float):
    return h.command(ParamSet(P[name].id, value))


@pytest.mark.parametrize("first, second, other", [
    (("guide_min_mm", 150.0), ("guide_max_mm", 50.0), "guide_min_mm"),   # the issue's sequence
    (("guide_max_mm", 50.0), ("guide_min_mm", 150.0), "guide_max_mm"),
    (("guide_max_mm", 50.0), ("guide_min_mm", 50.0), "guide_max_mm"),    # equal: no room at all
    (("tov_mps", 8.0), ("max_rope_speed_mps", 9.0), "tov_mps"),           # 8 x 1.15 = 9.2 > 9
    (("max_rope_speed_mps", 5.0), ("tov_mps", 4.5), "max_rope_speed_mps"),
    (("max_rope_speed_mps", 5.0), ("tov_margin", 2.0), "max_rope_speed_mps"),  # 2.6 x 2 = 5.2 > 5
])
def test_a_value_that_breaks_a_rule_is_refused_and_changes_nothing(rw_core, first, second, other) -> None:
    h = _booted(rw_core)
    assert isinstance(_set(h, *first), Ack)
    h.run_ms(20)  # the first change's PARAM_CHANGED event goes out
    events = len(h.events())
    before = h.get_param_value(second[0])
    reply = _set(h, *second)
    assert isinstance(reply, Nack) and reply.reason == NackReason.PARAM_CONFLICT
    assert reply.detail == P[other].id
    assert h.get_param_value(second[0]) == before
    h.run_ms(20)
    assert [e for e in h.events()[events:] if e.event == EventKind.PARAM_CHANGED] == []


def test_the_rules_allow_every_consistent_order_of_changes(rw_core) -> None:
    """Narrowing the guide to 40..60 mm and the speeds to a 5 m/s cap works in the natural order."""
    h = _booted(rw_core)
    for name, value in (("guide_max_mm", 60.0), ("guide_min_mm", 40.0), ("max_rope_speed_mps", 5.0),
                        ("tov_mps", 4.0), ("tov_margin", 1.25)):
        assert isinstance(_set(h, name, value), Ack), name
        assert h.get_param_value(name) == pytest.approx(value)


def test_a_loop_stays_possible_after_the_issues_sequence(rw_core) -> None:
    """The sequence of issue 18 leaves a guide range that SET_LOOP can use (guide_min 150, max stays 180)."""
    h = _booted(rw_core)
    assert isinstance(_set(h, "guide_min_mm", 150.0), Ack)
    assert _set(h, "guide_max_mm", 50.0).reason == NackReason.PARAM_CONFLICT
    assert h.get_param_value("guide_min_mm") < h.get_param_value("guide_max_mm")


def test_rw_params_check_reports_the_conflict_for_the_stored_configuration_path(rw_core) -> None:
    """rw_core_set_param (the path of a stored configuration and of PARAM_SET) applies the same rules."""
    h = _booted(rw_core)
    h.set_param("guide_max_mm", 20.0)
    with pytest.raises(ValueError, match="PARAM_CONFLICT"):
        h.set_param("guide_min_mm", 30.0)
