"""The SIL board's NINA WiFi module and its scripted faults (firmware/hal/sil/sil_nina.h, sil_wifi_link.h).

The SIL firmware's WiFi link drives a small model of the module through the board's connection policy
(firmware/core/rw_wifi_supervisor.h), as the board's arduino_link.cpp drives the real one: the ready line after
its reset and after each call, association with the access point, the UDP socket. Datagrams between a host and
the core pass only while the module is associated with its socket open. The default module is healthy: it
answers at once, associates at once, never loses the access point (the link is up from the first tick).

Faults, all in plant time:
- ``boot_ready_s``: the ready line rises this long after the module's reset; None: never (a hung module: the
  boot reaches NO_MODULE after its 2 s bound, the status LED stays on, USB says so);
- ``associate_s``: association takes this long (at boot, after a WiFi.begin, and when the module joins again
  by itself);
- ``ap_lost_s`` / ``ap_back_s``: the access point is out of reach from ap_lost_s until ap_back_s (None: for
  good); the module re-associates by itself once it is back, and the board's policy re-opens the socket only
  while the rope is down;
- ``busy_after_call_us``: after each call the ready line stays busy this long (from ``slow_from_s`` on): a slow
  module; over 2000 us the HAL's bounded waits run out (counted), the tick never waits; over 1 s the policy
  calls it hung: NO_MODULE (until a reset), no more datagrams.

Spec text (``wrangler sil --wifi``, ``SilSession(wifi="...")``): comma-separated ``key=value`` items,
``boot=never|S``, ``associate=S``, ``lost=S-S`` or ``lost=S-`` (for good), ``busy_us=N``, ``slow_from=S``;
e.g. ``--wifi lost=3.0-3.8`` or ``--wifi boot=never``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

MAX_TIME_S = 86_400.0
"""Fault times are plant time up to a day (the firmware's option range, 86,400,000 ms)."""
MAX_BUSY_US = 10_000_000
"""A ready line busy up to 10 s after a call (over 1 s running: the board's policy calls the module hung)."""


class WifiModuleError(ValueError):
    """A WiFi module option out of range or malformed: names the option, what was expected and what was given."""

    def __init__(self, option: str, expected: str, got: object) -> None:
        super().__init__(f"{option}: expected {expected}, got {got!r}")
        self.option = option
        self.expected = expected
        self.got = got


def _check_time(option: str, value: object, *, allow_none: bool) -> None:
    if value is None and allow_none:
        return
    expected = f"seconds of plant time in [0, {MAX_TIME_S:g}]" + (" or None (never)" if allow_none else "")
    if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value) \
            or not 0.0 <= value <= MAX_TIME_S:
        raise WifiModuleError(option, expected, value)


def _ms(value_s: float | None) -> str:
    return "never" if value_s is None else str(round(value_s * 1000.0))


@dataclass(frozen=True)
class WifiModule:
    """The NINA module of a SIL session (see the module docstring); the defaults are a healthy module."""

    boot_ready_s: float | None = 0.0
    associate_s: float = 0.0
    ap_lost_s: float | None = None
    ap_back_s: float | None = None
    busy_after_call_us: int = 0
    slow_from_s: float = 0.0

    def __post_init__(self) -> None:
        _check_time("boot_ready_s", self.boot_ready_s, allow_none=True)
        _check_time("associate_s", self.associate_s, allow_none=False)
        _check_time("ap_lost_s", self.ap_lost_s, allow_none=True)
        _check_time("ap_back_s", self.ap_back_s, allow_none=True)
        _check_time("slow_from_s", self.slow_from_s, allow_none=False)
        if self.ap_back_s is not None and self.ap_lost_s is None:
            raise WifiModuleError("ap_back_s", "None unless ap_lost_s is given (the access point is never lost)",
                                  self.ap_back_s)
        if self.ap_back_s is not None and round(self.ap_back_s * 1000) <= round(self.ap_lost_s * 1000):
            raise WifiModuleError("ap_back_s", f"a time later than ap_lost_s ({self.ap_lost_s!r} s) by at least 1 ms",
                                  self.ap_back_s)
        if isinstance(self.busy_after_call_us, bool) or not isinstance(self.busy_after_call_us, int) \
                or not 0 <= self.busy_after_call_us <= MAX_BUSY_US:
            raise WifiModuleError("busy_after_call_us", f"a whole number of microseconds in [0, {MAX_BUSY_US}]",
                                  self.busy_after_call_us)

    @property
    def boot_takes_time(self) -> bool:
        """Whether the board's WiFi boot spans ticks (a slow or hung module, an association that takes time, or an
        access point out of reach when the session starts)."""
        ap_lost_at_start = self.ap_lost_s is not None and round(self.ap_lost_s * 1000.0) == 0
        return self.boot_ready_s != 0.0 or self.associate_s > 0.0 or ap_lost_at_start

    def firmware_args(self) -> list[str]:
        """rw_sil's --wifi-* options for this module (none for the healthy default)."""
        args: list[str] = []
        if self.boot_ready_s != 0.0:
            args += ["--wifi-boot-ready-ms", _ms(self.boot_ready_s)]
        if self.associate_s:
            args += ["--wifi-associate-ms", _ms(self.associate_s)]
        if self.ap_lost_s is not None:
            args += ["--wifi-ap-lost-ms", _ms(self.ap_lost_s), "--wifi-ap-back-ms", _ms(self.ap_back_s)]
        if self.busy_after_call_us:
            args += ["--wifi-busy-us", str(self.busy_after_call_us)]
        if self.slow_from_s:
            args += ["--wifi-slow-from-ms", _ms(self.slow_from_s)]
        return args

    @classmethod
    def parse(cls, spec: str) -> WifiModule:
        """A module from spec text (module docstring); WifiModuleError naming the item on bad text."""
        if not isinstance(spec, str):
            raise WifiModuleError("wifi", "spec text such as 'boot=never' or 'lost=3.0-3.8'", spec)
        fields: dict[str, object] = {}
        for item in (part.strip() for part in spec.split(",")):
            if not item:
                continue
            key, sep, value = item.partition("=")
            key, value = key.strip(), value.strip()
            if not sep or not value:
                raise WifiModuleError("wifi", "items key=value (boot, associate, lost, busy_us, slow_from)", item)
            if key == "boot":
                fields["boot_ready_s"] = None if value == "never" else _seconds(key, value, allow_never=True)
            elif key == "associate":
                fields["associate_s"] = _seconds(key, value)
            elif key == "lost":
                start, dash, end = value.partition("-")
                if not dash:
                    raise WifiModuleError("lost", "START-END or START- (seconds; START- = for good)", value)
                fields["ap_lost_s"] = _seconds("lost", start)
                fields["ap_back_s"] = _seconds("lost", end) if end.strip() else None
            elif key == "busy_us":
                try:
                    fields["busy_after_call_us"] = int(value)
                except ValueError:
                    raise WifiModuleError("busy_us", "a whole number of microseconds", value) from None
            elif key == "slow_from":
                fields["slow_from_s"] = _seconds(key, value)
            else:
                raise WifiModuleError("wifi", "one of boot, associate, lost, busy_us, slow_from", key)
        return cls(**fields)


def _seconds(option: str, text: str, *, allow_never: bool = False) -> float:
    try:
        value = float(text)
    except ValueError:
        raise WifiModuleError(option, "seconds" + (" or never" if allow_never else ""), text) from None
    if not math.isfinite(value):
        raise WifiModuleError(option, "a finite number of seconds", text)
    return value


def parse_counters(stderr: str, prefix: str) -> dict[str, int | str]:
    """The key=value counters of the SIL firmware's exit line that starts with prefix ("rw_sil wifi", ...)."""
    for line in stderr.splitlines():
        if line.startswith(prefix + " "):
            out: dict[str, int | str] = {}
            for item in line[len(prefix) + 1:].split():
                key, _, value = item.partition("=")
                out[key] = int(value) if value.lstrip("-").isdigit() else value
            return out
    raise KeyError(f"no '{prefix}' line on the SIL firmware's stderr (is the session stopped?): {stderr!r}")
