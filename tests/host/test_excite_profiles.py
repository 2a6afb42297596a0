"""Excitation profiles as data: the shipped ones load and stay within the default limits; a malformed profile or
one that leaves the device's limits is refused with the step, the key, what was expected and the value."""

from __future__ import annotations

from pathlib import Path

import pytest

from robowrangler.excite.profile import Limits, ProfileError, check_limits, list_profiles, load_profile


def test_the_shipped_profiles_load_and_stay_within_the_default_limits() -> None:
    names = list_profiles()
    assert {"standard", "drive", "spindle", "quick"} <= set(names)
    for name in names:
        p = load_profile(name)
        check_limits(p, Limits.defaults())
        assert p.description and p.reveals, f"{name}: the README table needs both"
        kinds = {s.kind for s in p.steps}
        assert "spindown" in kinds, f"{name} lands the rope"


def test_the_standard_profile_has_every_kind_of_excitation() -> None:
    kinds = {s.kind for s in load_profile("standard").steps}
    assert kinds == {"speed", "ramp", "chirp", "hold", "loop", "burst", "spindown"}


def _write(tmp_path: Path, text: str) -> Path:
    path = tmp_path / "p.toml"
    path.write_text(text)
    return path


@pytest.mark.parametrize(("text", "says"), [
    ('[[step]]\nkind = "speed"\nspeed_mps = 4.0\n', "step 1 (speed).hold_s: expected a value (required)"),
    ('[[step]]\nkind = "speed"\nspeed_mps = 4.0\nhold_s = 1\nwobble = 2\n', "keys speed_mps, hold_s, got ['wobble']"),
    ('[[step]]\nkind = "hold"\nduration_s = "long"\n', "duration_s: expected a finite number, got 'long'"),
    ('[[step]]\nkind = "hold"\nduration_s = -1\n', "duration_s: expected a number > 0, got -1"),
    ('[[step]]\nkind = "burst"\nsamples = 2.5\n', "samples: expected a whole number, got 2.5"),
    ('title = "x"\n[[step]]\nkind = "hold"\nduration_s = 1\n', "top-level keys"),
    ('name = "empty"\n', "at least one [[step]]"),
    ('[[step]\n', "a readable TOML file"),
])
def test_malformed_profiles_say_what_is_wrong(tmp_path: Path, text: str, says: str) -> None:
    with pytest.raises(ProfileError, match=None) as exc:
        load_profile(_write(tmp_path, text))
    assert says in str(exc.value)


@pytest.mark.parametrize(("text", "says"), [
    ('[[step]]\nkind = "ramp"\nto_mps = 2.5\nduration_s = 1\n', "ramp).to_mps: expected a speed >= the ToV guard"),
    ('[[step]]\nkind = "speed"\nspeed_mps = 30\nhold_s = 1\n', "expected a speed <= max_rope_speed_mps 20"),
    ('[[step]]\nkind = "loop"\nguide_mm = 200\n', "guide_mm: expected a guide position in 0..180 mm"),
    ('[[step]]\nkind = "burst"\nsamples = 1001\n', "samples: expected 1..1000"),
    ('[[step]]\nkind = "chirp"\ncenter_mps = 6\namplitude_mps = 1\nf0_hz = 1\nf1_hz = 20\nduration_s = 5\n',
     "f1_hz: expected at most update_hz / 4 = 12.5 Hz"),
])
def test_profiles_leaving_the_limits_are_refused(tmp_path: Path, text: str, says: str) -> None:
    profile = load_profile(_write(tmp_path, text))
    with pytest.raises(ProfileError) as exc:
        check_limits(profile, Limits.defaults())
    assert says in str(exc.value)


def test_limits_come_from_the_devices_parameters(tmp_path: Path) -> None:
    profile = load_profile(_write(tmp_path, '[[step]]\nkind = "speed"\nspeed_mps = 3.2\nhold_s = 1\n'))
    check_limits(profile, Limits.defaults())  # 3.2 m/s flies with ToV 2.6 m/s x 1.15
    with pytest.raises(ProfileError, match=r"ToV guard 3\.450 m/s \(tov_mps 3 x tov_margin 1\.15\)"):
        check_limits(profile, Limits.from_params({"tov_mps": 3.0}))
