"""The board's WiFi bounded waits end to end: the SIL firmware's link drives a model of the NINA module
(firmware/hal/sil/sil_nina.h) through the board's connection policy (core/rw_wifi_supervisor.h) exactly as the
board's arduino_link.cpp does (sil_wifi_link.h); hosts talk to it over real UDP. Judged from the host's
datagrams, the plant's ESC input tick by tick, the device's USB status lines (as a person at a terminal reads
them) and the counters the SIL firmware prints on exit (its WiFi link's and its status LED's):

- a module that never answers at boot: NO_MODULE when the 2 s bound runs out, without a single call into the
  module; the LED steady on, USB says so; the control tick then runs every tick at the ESC's idle pulse;
- the access point lost while the rope flies and the module re-associating by itself: the socket is re-opened
  only once the rope is down; until then the ESC pulse is, tick for tick, the one of the same flight whose host
  simply fell silent; counted (losses, one deferral, connects);
- a slow module (its ready line busy 3 ms after each call, over the 2 ms bound): counted (busy passes, expired
  waits), never NO_MODULE, never a late tick; in flight it leaves the ESC pulse as it is; one busy for seconds
  is hung: NO_MODULE, no datagram moves, the core lands the rope on its heartbeat timeout;
- the boot's other bounds (WiFi.begin 15 s with the access point out of reach; a module slow to start) and new
  credentials after a PROVISION_COMMIT (a new connection at once).
"""

from __future__ import annotations

import io
import json
import subprocess
from pathlib import Path

import pytest

from robowrangler.cli.environment import Environment
from robowrangler.cli.exit_status import ExitStatus
from robowrangler.cli.main import main
from robowrangler.protocol import generated as gen
from robowrangler_sim.sil import SilSession, UsbNotes, WifiModule, WifiModuleError
from robowrangler_sim.sil.firmware import find_sil_binary
from robowrangler_sim.sil.scripted_host import ScriptedHost

P = gen.PARAMS_BY_NAME
BOOT_READY_BOUND_S = 2.0      # RW_WIFI_BOOT_READY_MS
STATUS_POLL_S = 0.5           # rw_wifi_supervisor's status_poll_ms
BOTTOM_PULSE_US = 1000        # the ESC protocol's bottom: the HAL's pulse before the tick starts
IDLE_PULSE_US = 1000          # esc_min_us's default: the core's idle pulse
ROPE_DOWN = {gen.State.DISARMED, gen.State.ARMED, gen.State.RETRACT, gen.State.HOLD, gen.State.FAULT,
             gen.State.ESTOP}


def _pulses(sil: SilSession) -> list[tuple[float, float]]:
    """Per tick from now on: (plant time s, the ESC pulse the plant got: the firmware's, at the timer's 1/3 us)."""
    pulses: list[tuple[float, float]] = []
    sil.tick_hooks.append(lambda s: pulses.append((s.time_s, s.last_esc_pulse_fine_us)))
    return pulses


def _notes(sil: SilSession, usb: UsbNotes) -> list[tuple[float, str]]:
    """Per tick from now on: the device's USB status lines, with the plant time they were read at."""
    notes: list[tuple[float, str]] = []
    sil.tick_hooks.append(lambda s: notes.extend((s.time_s, text) for text in usb.read()))
    return notes


def test_a_module_that_never_answers_boots_to_no_module_and_the_tick_runs_on(native_build_dir: Path) -> None:
    with SilSession(speedup=None, wifi=WifiModule(boot_ready_s=None), trace_every=1) as sil:
        # start() stepped the plant through the board's boot until the device's USB said how it ended
        [(t_note, text)] = sil.usb_notes
        assert text.startswith("wifi NO_MODULE") and "LED steady on" in text, text
        assert BOOT_READY_BOUND_S <= t_note <= BOOT_READY_BOUND_S + 0.002, "NO_MODULE when its bound ran out"
        boot = [s.esc_pulse_us for s in sil.trace]
        assert len(boot) >= 2000 and set(boot) == {BOTTOM_PULSE_US}, "the ESCs hold the bottom pulse while booting"
        with UsbNotes(sil.serial_path) as usb:
            pulses, notes = _pulses(sil), _notes(sil, usb)
            host = ScriptedHost(sil, handshake=False)
            host.send(host.link.hello(0x5EED0000))  # WiFi datagrams go nowhere: no module
            host.run_for(10.2)  # a report period: the tick's and the link's counters on USB
            host.close()
        ticks = len(pulses)
    assert {p for _, p in pulses} == {IDLE_PULSE_US}, "the tick ran every tick and held the ESC at its idle pulse"
    assert host.received.raw == [], "nothing came over WiFi"
    tick_line = next(text for _, text in notes if text.startswith("tick "))
    wifi_line = next(text for _, text in notes if text.startswith("wifi calls="))
    assert " overruns=0 " in tick_line and "wifi calls=0 " in wifi_line, (tick_line, wifi_line)
    wifi, led = sil.wifi_counters(), sil.led_counters()
    assert wifi["state"] == "NO_MODULE" and wifi["boot_ms"] == 2000, wifi
    assert wifi["calls"] == 0 and wifi["calls_while_busy"] == 0, "not one call into a module that never answered"
    assert wifi["rx"] == 0 and wifi["lost_rx"] == host.frames_sent, wifi
    # the LED: off during the boot (the board's loop() has not run), then steady on, every tick
    assert led["changes"] == 1 and led["last_change_ms"] == 2000 and led["on"] == 1, led
    assert led["off_ticks"] == 0 and led["on_ticks"] == led["ticks"] >= ticks and led["overruns"] == 0, led


def test_a_module_slow_to_start_and_to_associate_boots_up(native_build_dir: Path) -> None:
    """The board's boot with a module that takes 0.75 s to start and 0.3 s to associate (WiFi.begin blocking):
    the tick starts once the link is UP, about 1.05 s in; then the host talks to the device."""
    with SilSession(speedup=None, wifi="boot=0.75,associate=0.3", trace_every=1) as sil:
        [(t_note, text)] = sil.usb_notes
        assert text == "wifi UP" and 1.05 <= t_note <= 1.06, sil.usb_notes
        assert {s.esc_pulse_us for s in sil.trace} == {BOTTOM_PULSE_US}
        host = ScriptedHost(sil)  # HELLO answered: the link is up
        host.run_for(0.6)  # the ESC arming hold, from the tick's start
        assert isinstance(host.command(gen.Arm()), gen.Ack)
        host.close()
    wifi = sil.wifi_counters()
    assert wifi["state"] == "UP" and 1050 <= wifi["boot_ms"] <= 1052 and wifi["connects"] == 1, wifi


def test_an_access_point_out_of_reach_at_boot_ends_the_blocking_begin_at_its_bound(native_build_dir: Path) -> None:
    """WiFi.begin at boot blocks at most 15 s (RW_WIFI_BOOT_CONNECT_TIMEOUT_MS): then CONNECTING, the tick starts,
    and the policy starts a new connection every 5 s (the rope down)."""
    with SilSession(speedup=None, wifi="lost=0-", trace_every=0) as sil:
        [(t_note, text)] = sil.usb_notes
        assert text == "wifi CONNECTING" and 15.0 <= t_note <= 15.002, sil.usb_notes
        ScriptedHost(sil, handshake=False).run_for(5.1)
    wifi, led = sil.wifi_counters(), sil.led_counters()
    assert 15000 <= wifi["boot_ms"] <= 15002 and wifi["attempts"] == 1 and wifi["associations"] == 0, wifi
    assert wifi["state"] == "CONNECTING" and led["overruns"] == 0 and 45 <= led["changes"] <= 55, led


def test_new_credentials_reconnect_at_once_and_the_link_comes_back(native_build_dir: Path) -> None:
    """A PROVISION_COMMIT that changes the SSID (rope down): the socket closed, the module disconnected, a new
    connection started at once; the link is UP again after the next status poll (the SIL joins any SSID)."""
    with SilSession(speedup=None) as sil:
        host = ScriptedHost(sil)
        host.run_for(0.2)
        sil.provision(wifi_ssid="lab")  # over USB, the plant clock standing still
        with UsbNotes(sil.serial_path) as usb:
            notes = _notes(sil, usb)
            host.run_for(0.7)
        assert [text for _, text in notes] == ["wifi UP"] and 0.69 < notes[0][0] < 0.71, notes
        host.hello()  # the commit began a new session: HELLO answered over the new connection
        assert isinstance(host.command(gen.Arm()), gen.Ack)
        host.close()
    wifi = sil.wifi_counters()
    assert wifi["connects"] == 2 and wifi["attempts"] == 1 and wifi["losses"] == 0 and wifi["lost_rx"] > 0, wifi


def _flight(wifi: WifiModule | None, *, silence_at_s: float | None = None, read_usb: bool = False,
            end_s: float = 7.0):
    """Home-free flight at 5 m/s with a 2 s heartbeat timeout: ARM and spin from 0.6 s, airborne by 2.5 s; the
    host falls silent at silence_at_s (None: heartbeats throughout, lost while the link is down); to end_s."""
    sil = SilSession(speedup=None, wifi=wifi, trace_every=1).start()
    usb = UsbNotes(sil.serial_path) if read_usb else None
    try:
        host = ScriptedHost(sil)
        host.run_for(0.6)
        assert isinstance(host.command(gen.ParamSet(P["heartbeat_timeout_s"].id, 2.0)), gen.Ack)
        pulses = _pulses(sil)
        notes = _notes(sil, usb) if usb else []
        host.arm_and_spin(5000, settle_s=1.85)
        assert host.last_telemetry.state == gen.State.AIRBORNE, host.last_telemetry
        if silence_at_s is not None:
            host.run_for(silence_at_s - sil.time_s)
            host.heartbeats_enabled = False
        host.run_for(end_s - sil.time_s)
        host.close()
    finally:
        if usb:
            usb.close()
        sil.stop()
    return sil, host, pulses, notes


def test_a_link_lost_in_flight_is_reopened_only_once_the_rope_is_down(native_build_dir: Path) -> None:
    lost_s, back_s = 2.6, 3.3  # spans the status poll at 3.0 s; the module re-associates by itself at 3.3 s
    sil, host, pulses, notes = _flight(WifiModule(ap_lost_s=lost_s, ap_back_s=back_s), read_usb=True)
    ref_sil, ref_host, ref_pulses, _ = _flight(None, silence_at_s=lost_s)
    texts = [text for _, text in notes if not text.startswith(("tick ", "wifi calls="))]
    assert texts == ["wifi CONNECTING", "wifi UP"], notes
    t_down = next(t for t, text in notes if text == "wifi CONNECTING")
    t_up = next(t for t, text in notes if text == "wifi UP")
    assert lost_s < t_down <= lost_s + STATUS_POLL_S + 0.002, "the loss is seen at the next status poll"
    # the rope lands on the heartbeat timeout (2 s after the last frame that arrived), then spins down
    ref_states = [(t.time_ms / 1000, t.state) for t in ref_host.received.telemetry]
    t_landed = next(t for t, state in ref_states if t > lost_s and state in ROPE_DOWN)
    assert any(state == gen.State.AIRBORNE for t, state in ref_states if back_s + STATUS_POLL_S < t < t_landed - 0.5)
    assert t_up >= t_landed - 0.021, "the socket re-opened only once the rope was down"
    assert t_up - back_s > 1.0, "re-associated by itself at 3.3 s, the socket waited for the landing"
    trace_at_up = min(sil.trace, key=lambda s: abs(s.time_s - t_up))
    assert not trace_at_up.loop_airborne and trace_at_up.esc_pulse_us == IDLE_PULSE_US
    # the speed loop never noticed: the pulse tick for tick is the one of the flight whose host fell silent
    until_up = [p for p in pulses if p[0] < t_up]
    assert len({p for _, p in until_up}) > 10, "the speed loop was working"
    assert until_up == [p for p in ref_pulses if p[0] < t_up], "the WiFi loss or the deferred reconnect changed an ESC pulse"
    # the host hears the device again after the landing
    after = [t for t in host.received.telemetry if t.time_ms / 1000 > t_up]
    assert after and after[0].state in ROPE_DOWN and after[-1].tick_overruns == 0
    wifi = sil.wifi_counters()
    assert wifi["losses"] == 1 and wifi["deferred"] == 1 and wifi["connects"] == 2, wifi
    assert wifi["association_losses"] == 1 and wifi["associations"] == 2 and wifi["calls_while_busy"] == 0, wifi
    assert wifi["lost_rx"] > 0 and wifi["module_hangs"] == 0 and wifi["state"] == "UP", wifi
    assert ref_sil.wifi_counters()["losses"] == 0 and sil.led_counters()["overruns"] == 0


def test_a_slow_module_hits_the_bounded_waits_counted_and_never_blocks_the_tick(native_build_dir: Path) -> None:
    slow = WifiModule(busy_after_call_us=3000)  # over RW_WIFI_CALL_READY_WAIT_US (2 ms) after every call
    with SilSession(speedup=None, wifi=slow, trace_every=0) as sil:
        pulses = _pulses(sil)
        with UsbNotes(sil.serial_path) as usb:
            notes = _notes(sil, usb)
            host = ScriptedHost(sil, handshake=False)
            host.send(host.link.hello(0x5EED0000))
            host.run_for(10.2)
            host.close()
    wifi, led = sil.wifi_counters(), sil.led_counters()
    assert wifi["state"] == "CONNECTING" and wifi["module_hangs"] == 0, "slow is not hung: never NO_MODULE"
    assert wifi["boot_ms"] < 10 and wifi["connects"] == 0, "the boot's socket step gave up on the busy line (bounded)"
    # each poll finds the module associated, each socket step gives up after noLowPowerMode (counted)
    assert wifi["polls"] >= 20 and wifi["ready_waits_expired"] >= wifi["polls"] - 1, wifi
    assert wifi["module_busy"] >= 2 * wifi["polls"] and wifi["sockets_opened"] == 0, wifi
    assert wifi["calls_while_busy"] == 1, "only the boot's WiFi.begin, right after the first status, as on the board"
    assert {p for _, p in pulses} == {IDLE_PULSE_US} and len(pulses) >= 10_200 and led["overruns"] == 0, led
    assert host.received.raw == [] and any("module_busy=" in text for _, text in notes)
    assert 40 <= led["changes"] <= 110, "the LED blinks CONNECTING's 5 Hz"


def test_a_module_slow_in_flight_leaves_the_esc_pulse_alone(native_build_dir: Path) -> None:
    _, _, healthy, _ = _flight(None)
    sil, host, slowed, _ = _flight(WifiModule(busy_after_call_us=3000, slow_from_s=2.6))
    assert len({p for _, p in healthy}) > 10 and slowed == healthy, "a slow module changed an ESC pulse"
    wifi = sil.wifi_counters()
    assert wifi["state"] == "UP" and wifi["losses"] == 0 and wifi["module_busy"] >= 3 * 8, wifi
    assert host.last_telemetry.state == gen.State.AIRBORNE and host.last_telemetry.tick_overruns == 0


def test_a_module_that_hangs_in_flight_is_no_module_and_the_rope_lands(native_build_dir: Path) -> None:
    """Busy 5 s after the status poll at 3.0 s: hung after 1 s of it (the policy's module_hung_ms), no datagram
    moves any more, the host falls silent for the core, which lands the rope on its heartbeat timeout."""
    sil, host, pulses, notes = _flight(WifiModule(busy_after_call_us=5_000_000, slow_from_s=2.6), read_usb=True,
                                       end_s=8.0)
    t_hung = next(t for t, text in notes if text.startswith("wifi NO_MODULE"))
    assert 3.9 < t_hung < 4.1, notes
    assert max(t.time_ms for t in host.received.telemetry) / 1000 <= t_hung + 0.002, "no datagram after the hang"
    wifi, led = sil.wifi_counters(), sil.led_counters()
    assert wifi["state"] == "NO_MODULE" and wifi["module_hangs"] == 1 and wifi["calls_while_busy"] == 0, wifi
    assert led["on"] == 1 and abs(led["last_change_ms"] - t_hung * 1000) <= 2 and led["overruns"] == 0, led
    end = sil.trace[-1]
    assert not end.loop_airborne and end.esc_pulse_us == IDLE_PULSE_US, "landed on the heartbeat timeout"


@pytest.mark.parametrize("kwargs, option", [
    ({"boot_ready_s": -1.0}, "boot_ready_s"), ({"associate_s": float("nan")}, "associate_s"),
    ({"ap_back_s": 3.0}, "ap_back_s"), ({"ap_lost_s": 3.0, "ap_back_s": 2.0}, "ap_back_s"),
    ({"busy_after_call_us": 2.5}, "busy_after_call_us"), ({"slow_from_s": 1e9}, "slow_from_s"),
])
def test_bad_module_options_are_typed_errors_naming_the_option(kwargs: dict, option: str) -> None:
    with pytest.raises(WifiModuleError) as err:
        WifiModule(**kwargs)
    assert err.value.option == option and str(err.value).startswith(f"{option}: expected ")


@pytest.mark.parametrize("spec, option", [("boot=soon", "boot"), ("lost=3", "lost"), ("lost=a-b", "lost"),
                                          ("busy_us=1.5", "busy_us"), ("colour=red", "wifi"), ("boot", "wifi")])
def test_bad_module_specs_are_typed_errors(spec: str, option: str) -> None:
    with pytest.raises(WifiModuleError) as err:
        WifiModule.parse(spec)
    assert err.value.option == option
    with pytest.raises(WifiModuleError):
        SilSession(wifi=spec)


def test_module_specs_parse() -> None:
    assert WifiModule.parse("boot=never, lost=3.0-3.8, busy_us=3000, slow_from=5") == WifiModule(
        boot_ready_s=None, ap_lost_s=3.0, ap_back_s=3.8, busy_after_call_us=3000, slow_from_s=5.0)
    assert WifiModule.parse("lost=4-").ap_back_s is None and WifiModule.parse("") == WifiModule()


@pytest.mark.parametrize("args, message", [
    (["--wifi-boot-ready-ms", "soon"], "whole number 0..86400000 or never"),
    (["--wifi-associate-ms", "never"], "whole number 0..86400000"),
    (["--wifi-ap-back-ms", "10"], "--wifi-ap-back-ms needs --wifi-ap-lost-ms"),
    (["--wifi-ap-lost-ms", "10", "--wifi-ap-back-ms", "5"], "later than --wifi-ap-lost-ms"),
])
def test_the_firmware_refuses_bad_wifi_options(native_build_dir: Path, args: list[str], message: str) -> None:
    run = subprocess.run([str(find_sil_binary()), *args], capture_output=True, text=True, timeout=10)
    assert run.returncode == 2 and message in run.stderr, run.stderr


def _wrangler(*argv: str) -> tuple[ExitStatus, list[dict], str]:
    out, err = io.StringIO(), io.StringIO()
    status = main(["--json", *argv], Environment(out, err, {}))
    return status, [json.loads(x) for x in out.getvalue().splitlines() if x.strip()], err.getvalue()


def test_wrangler_sil_serves_a_device_with_a_hung_module(native_build_dir: Path) -> None:
    status, out, err = _wrangler("sil", "--port", "0", "--unpaced", "--duration", "2.5", "--wifi", "boot=never")
    assert status == ExitStatus.OK, err
    assert out[-1]["wifi"]["state"] == "NO_MODULE" and out[-1]["wifi"]["boot_ms"] == 2000, out[-1]


@pytest.mark.parametrize("spec, words", [("boot=soon", "boot: expected seconds or never"),
                                         ("lost=5-4", "ap_back_s: expected a time later than ap_lost_s"),
                                         ("volume=11", "wifi: expected one of boot")])
def test_wrangler_sil_refuses_a_bad_wifi_spec_as_a_usage_error(spec: str, words: str) -> None:
    status, _, err = _wrangler("sil", "--wifi", spec)
    assert status == ExitStatus.USAGE and words in err, err
