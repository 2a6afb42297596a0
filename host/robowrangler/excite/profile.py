"""Excitation profiles: a designed identification run as data (TOML) a user can edit.

A profile file:

    name = "drive"                      # optional (default: the file stem)
    description = "speed steps, ramps and chirps between speed bands; bursts at the steps"
    reveals = ["rope drag law", "ESC latency", ...]      # what the run can show (the README's table)

    [[step]]                            # the steps, in order; every speed in m/s at the rope, times in s of
    kind = "speed"                      # device time (telemetry time_s), so a SIL at any speed-up runs them right
    speed_mps = 4.0
    hold_s = 3.0

Step kinds and their keys (all required unless a default is given):
    speed    speed_mps, hold_s                 SET_ROPE_SPEED, then hold (the first one spins up from ARMED)
    ramp     to_mps, duration_s, [update_hz=20] setpoints from the previous speed to to_mps, linearly
    chirp    center_mps, amplitude_mps, f0_hz, f1_hz, duration_s, [update_hz=50]
             center + amplitude sin(phase), frequency sweeping linearly f0 -> f1
    hold     duration_s                        keep the setpoint
    loop     guide_mm, [timeout_s=30]          SET_LOOP, wait until the guide is there (needs HOME: the run
                                               homes the spindle first, rope stopped, when any loop step exists)
    burst    samples                           BURST_START (1 kHz capture, streamed afterwards), no wait
    spindown [timeout_s=30]                    SPINDOWN and wait for ARMED (landing: speeds below the guard then)

Checks (ProfileError, naming the step, the key, what was expected and the value): unknown kinds or keys,
types and signs; against the device's limits (Limits, from its parameters): every speed a step commands or
passes through between the ToV guard (tov_mps x tov_margin) and max_rope_speed_mps, once the rope flies
(speeds after a spindown spin up again from ARMED and may not go below the guard either: excitation runs
stay in the band where the loop flies), guide positions within guide_min_mm..guide_max_mm, burst sizes
1..BURST_MAX_SAMPLES, update rates up to MAX_UPDATE_HZ. The firmware enforces its limits anyway; these checks
refuse a profile before anything moves instead of halfway through.
"""

from __future__ import annotations

import math
import tomllib
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from robowrangler.errors import InvalidArgument
from robowrangler.protocol.generated import PARAMS_BY_NAME

PROFILE_DIR = Path(__file__).resolve().parent / "profiles"
BURST_MAX_SAMPLES = 1000  # the device's burst buffer (firmware/core/rw_burst.h RW_BURST_MAX_SAMPLES)
MAX_UPDATE_HZ = 50.0  # setpoints a second during ramps and chirps (each is a command the device ACKs)
MAX_DURATION_S = 1800.0

# kind -> {key: default (None = required)}
STEP_KEYS: dict[str, dict[str, float | None]] = {
    "speed": {"speed_mps": None, "hold_s": None},
    "ramp": {"to_mps": None, "duration_s": None, "update_hz": 20.0},
    "chirp": {"center_mps": None, "amplitude_mps": None, "f0_hz": None, "f1_hz": None, "duration_s": None,
              "update_hz": 50.0},
    "hold": {"duration_s": None},
    "loop": {"guide_mm": None, "timeout_s": 30.0},
    "burst": {"samples": None},
    "spindown": {"timeout_s": 30.0},
}


class ProfileError(InvalidArgument):
    """A profile that cannot be run: unknown, malformed, or leaving the device's safe limits.

    The CLI exits with USAGE (2) and the message names the profile, the step and what is wrong."""

    def __init__(self, where: str, expected: str, actual: object) -> None:
        super().__init__(where, expected, actual)


@dataclass(frozen=True)
class Step:
    """One step: its kind, its keys (defaults filled in), and its index in the profile (from 1)."""

    index: int
    kind: str
    values: dict[str, float]

    def __getattr__(self, key: str) -> float:
        try:
            return self.__dict__["values"][key]
        except KeyError:
            raise AttributeError(key) from None

    @property
    def duration_s(self) -> float:
        """Time the step takes at least (device time; loop and spindown: 0, they wait for the device)."""
        v = self.values
        return float(v.get("hold_s", v.get("duration_s", 0.0))) if self.kind not in ("loop", "spindown") else 0.0


@dataclass(frozen=True)
class Profile:
    name: str
    description: str
    reveals: tuple[str, ...]
    steps: tuple[Step, ...]
    path: Path | None = None

    @property
    def duration_s(self) -> float:
        return sum(s.duration_s for s in self.steps)

    @property
    def needs_home(self) -> bool:
        return any(s.kind == "loop" for s in self.steps)

    def speeds_mps(self) -> list[tuple[Step, str, float]]:
        """Every speed the profile commands or passes through: (step, key, value)."""
        out = []
        for s in self.steps:
            if s.kind == "speed":
                out.append((s, "speed_mps", s.speed_mps))
            elif s.kind == "ramp":
                out.append((s, "to_mps", s.to_mps))
            elif s.kind == "chirp":
                out.append((s, "center_mps - amplitude_mps", s.center_mps - s.amplitude_mps))
                out.append((s, "center_mps + amplitude_mps", s.center_mps + s.amplitude_mps))
        return out


@dataclass(frozen=True)
class Limits:
    """What the device allows, from its parameters (SI)."""

    tov_mps: float
    tov_margin: float
    max_rope_speed_mps: float
    guide_min_mm: float
    guide_max_mm: float

    @property
    def guard_mps(self) -> float:
        return self.tov_mps * self.tov_margin

    @classmethod
    def from_params(cls, params: dict[str, float]) -> Limits:
        """From the device's parameters by name (read_device_params); missing ones take the protocol default."""
        def get(name: str) -> float:
            return float(params.get(name, PARAMS_BY_NAME[name].default))
        return cls(get("tov_mps"), get("tov_margin"), get("max_rope_speed_mps"), get("guide_min_mm"),
                   get("guide_max_mm"))

    @classmethod
    def defaults(cls) -> Limits:
        return cls.from_params({})


def list_profiles() -> list[str]:
    """Names of the shipped profiles (host/robowrangler/excite/profiles/*.toml)."""
    return sorted(p.stem for p in PROFILE_DIR.glob("*.toml"))


def profile_path(name_or_path: str | Path) -> Path:
    """A shipped profile's file by name, or a path to a user's file (anything ending in .toml or existing)."""
    text = str(name_or_path)
    candidate = Path(text)
    if text.endswith(".toml") or candidate.exists():
        if not candidate.is_file():
            raise ProfileError("--profile", "a shipped profile name or an existing .toml file", text)
        return candidate
    shipped = PROFILE_DIR / f"{text}.toml"
    if not shipped.is_file():
        raise ProfileError("--profile", f"one of {', '.join(list_profiles())} or a .toml file", text)
    return shipped


def _number(where: str, value: Any, *, positive: bool = False, integer: bool = False) -> float:
    if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value):
        raise ProfileError(where, "a finite number", value)
    if integer and (not isinstance(value, int)):
        raise ProfileError(where, "a whole number", value)
    if positive and value <= 0:
        raise ProfileError(where, "a number > 0", value)
    return value


def load_profile(name_or_path: str | Path) -> Profile:
    """Read and check the form of a profile (not yet its limits: check_limits). ProfileError when it is unknown
    or malformed."""
    path = profile_path(name_or_path)
    try:
        raw = tomllib.loads(path.read_text(encoding="utf-8"))
    except (OSError, UnicodeDecodeError, tomllib.TOMLDecodeError) as exc:
        raise ProfileError(f"profile {path}", "a readable TOML file", str(exc)) from None
    name = str(raw.get("name", path.stem))
    unknown = set(raw) - {"name", "description", "reveals", "step"}
    if unknown:
        raise ProfileError(f"profile {name}", "top-level keys name, description, reveals, [[step]]", sorted(unknown))
    reveals = raw.get("reveals", [])
    if not isinstance(reveals, list) or not all(isinstance(r, str) for r in reveals):
        raise ProfileError(f"profile {name}: reveals", "a list of strings", reveals)
    raw_steps = raw.get("step", [])
    if not isinstance(raw_steps, list) or not raw_steps:
        raise ProfileError(f"profile {name}", "at least one [[step]]", raw_steps)
    steps = []
    for i, rs in enumerate(raw_steps, start=1):
        kind = rs.get("kind")
        where = f"profile {name} step {i}"
        if kind not in STEP_KEYS:
            raise ProfileError(f"{where}: kind", f"one of {', '.join(STEP_KEYS)}", kind)
        where = f"{where} ({kind})"
        keys = STEP_KEYS[kind]
        extra = set(rs) - set(keys) - {"kind"}
        if extra:
            raise ProfileError(where, f"keys {', '.join(keys)}", sorted(extra))
        values: dict[str, float] = {}
        for key, default in keys.items():
            if key not in rs:
                if default is None:
                    raise ProfileError(f"{where}.{key}", "a value (required)", None)
                values[key] = default
                continue
            values[key] = _number(f"{where}.{key}", rs[key], integer=key == "samples",
                                  positive=key not in ("guide_mm", "amplitude_mps"))
        if kind == "chirp" and values["amplitude_mps"] < 0:
            raise ProfileError(f"{where}.amplitude_mps", "a number >= 0", values["amplitude_mps"])
        steps.append(Step(i, kind, values))
    profile = Profile(name, str(raw.get("description", "")), tuple(reveals), tuple(steps), path)
    if profile.duration_s > MAX_DURATION_S:
        raise ProfileError(f"profile {name}", f"a run of at most {MAX_DURATION_S:g} s", profile.duration_s)
    return profile


def check_limits(profile: Profile, limits: Limits) -> None:
    """ProfileError for the first step that leaves what the device allows (see the module docstring)."""
    guard = limits.guard_mps
    for step, key, v in profile.speeds_mps():
        where = f"profile {profile.name} step {step.index} ({step.kind}).{key}"
        if v < guard:
            raise ProfileError(where, f"a speed >= the ToV guard {guard:.3f} m/s (tov_mps {limits.tov_mps:g} x "
                               f"tov_margin {limits.tov_margin:g}): excitation stays where the loop flies", v)
        if v > limits.max_rope_speed_mps:
            raise ProfileError(where, f"a speed <= max_rope_speed_mps {limits.max_rope_speed_mps:g} m/s", v)
    for step in profile.steps:
        where = f"profile {profile.name} step {step.index} ({step.kind})"
        if step.kind == "loop" and not limits.guide_min_mm <= step.guide_mm <= limits.guide_max_mm:
            raise ProfileError(f"{where}.guide_mm", f"a guide position in {limits.guide_min_mm:g}.."
                               f"{limits.guide_max_mm:g} mm (guide_min_mm..guide_max_mm)", step.guide_mm)
        if step.kind == "burst" and not 1 <= step.samples <= BURST_MAX_SAMPLES:
            raise ProfileError(f"{where}.samples", f"1..{BURST_MAX_SAMPLES} (the device's burst buffer)",
                               step.samples)
        if "update_hz" in step.values and step.update_hz > MAX_UPDATE_HZ:
            raise ProfileError(f"{where}.update_hz", f"at most {MAX_UPDATE_HZ:g} setpoints a second", step.update_hz)
        if step.kind == "chirp" and max(step.f0_hz, step.f1_hz) > step.update_hz / 4:
            raise ProfileError(f"{where}.f1_hz", f"at most update_hz / 4 = {step.update_hz / 4:g} Hz (4 setpoints a "
                               "period at least)", max(step.f0_hz, step.f1_hz))
