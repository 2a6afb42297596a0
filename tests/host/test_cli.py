"""`wrangler` in-process via main(argv, env): exit statuses, stdout/stderr discipline, --json output,
against the real firmware core on UDP (core_device.py; unsigned frames reach its trusted serial link, signed
ones its WiFi link)."""

from __future__ import annotations

import io
import json
import re

import pytest

from robowrangler.cli.environment import Environment
from robowrangler.cli.exit_status import ExitStatus
from robowrangler.cli.main import main
from robowrangler.client import Client
from host_settings import QUICK_ARM
from core_device import CoreDevice, lose_messages
from core_harness import TEST_KEY, CoreHarness, FakeSpindle
from robowrangler.protocol import generated as gen
from robowrangler.protocol.generated import PARAMS, MsgId

FAST_SPINDLE = {**QUICK_ARM, "lead_mm_per_rev": 20.0, "spindle_max_speed_mmps": 15.0, "homing_speed_mmps": 15.0}


@pytest.fixture
def device(core_lib):
    """The core past its arming hold, on UDP, its serial link (the CLI's default: no key), a fast lead screw, its
    clock at twice the wall clock."""
    with CoreDevice(core_lib, link="serial", params=FAST_SPINDLE, spindle=FakeSpindle(lead_mm_per_rev=20.0),
                    boot_s=0.25, speedup=2.0) as dev:
        yield dev


class Run:
    def __init__(self, status: ExitStatus, stdout: str, stderr: str) -> None:
        self.status, self.stdout, self.stderr = status, stdout, stderr

    @property
    def json(self) -> dict:
        """The single JSON object on stdout (fails if there is anything else)."""
        lines = self.stdout.splitlines()
        assert len(lines) == 1, self.stdout
        return json.loads(lines[0])

    @property
    def json_lines(self) -> list[dict]:
        return [json.loads(line) for line in self.stdout.splitlines()]


def wrangler(*argv: str, environ: dict[str, str] | None = None) -> Run:
    env = Environment(stdout=io.StringIO(), stderr=io.StringIO(), environ=environ or {})
    status = main(list(argv), env)
    assert isinstance(status, ExitStatus)
    return Run(status, env.stdout.getvalue(), env.stderr.getvalue())


def test_exit_statuses_are_the_documented_numbers() -> None:
    assert {s.name: int(s) for s in ExitStatus} == {"OK": 0, "ERROR": 1, "USAGE": 2, "NACK": 3, "LINK_TIMEOUT": 4,
                                                    "AUTH": 5, "CTRL_C": 130}


def test_arm_ok_human_and_json(device: CoreDevice) -> None:
    human = wrangler("--url", device.url, "arm")
    assert human.status == ExitStatus.OK and human.stdout == "armed (state ARMED)\n" and human.stderr == ""
    machine = wrangler("--url", device.url, "--json", "disarm")
    assert machine.status == ExitStatus.OK and machine.stderr == ""
    assert machine.json == {"type": "result", "ok": True, "command": "disarm", "state": "DISARMED"}
    assert device.executed_names() == ["ARM", "DISARM"]


def test_url_comes_from_the_environment_and_the_option_wins(device: CoreDevice) -> None:
    assert wrangler("arm", environ={"ROBOWRANGLER_URL": device.url}).status == ExitStatus.OK
    overridden = wrangler("--url", device.url, "--json", "estop", environ={"ROBOWRANGLER_URL": "udp://127.0.0.1:9"})
    assert overridden.status == ExitStatus.OK and overridden.json["state"] == "ESTOP"


def test_nack_exits_3_with_one_line_on_stderr_and_the_reason_in_json(device: CoreDevice) -> None:
    human = wrangler("--url", device.url, "spin", "5")
    assert human.status == ExitStatus.NACK and human.stdout == ""
    assert human.stderr == ("wrangler: SET_ROPE_SPEED refused: BAD_STATE: not accepted in state DISARMED; "
                            "arm first\n")
    machine = wrangler("--url", device.url, "--json", "spin", "5")
    assert machine.status == ExitStatus.NACK
    obj = machine.json
    assert obj["ok"] is False and obj["exit_status"] == "NACK" and obj["exit_code"] == 3
    assert (obj["command"], obj["reason"], obj["state"]) == ("SET_ROPE_SPEED", "BAD_STATE", "DISARMED")
    assert machine.stderr.count("\n") == 1


def test_negative_speed_is_sent_and_refused_by_the_device(device: CoreDevice) -> None:
    wrangler("--url", device.url, "arm")
    run = wrangler("--url", device.url, "--json", "spin", "--", "-1")
    assert run.status == ExitStatus.NACK and run.json["reason"] == "OUT_OF_RANGE"


def test_no_device_exits_4_naming_the_url(core_lib) -> None:
    quiet = CoreDevice(core_lib, link="serial")  # never started: nothing answers on its port
    run = wrangler("--url", quiet.url, "--timeout", "0.2", "--json", "status")
    assert run.status == ExitStatus.LINK_TIMEOUT
    assert run.json["exit_status"] == "LINK_TIMEOUT" and run.json["url"] == quiet.url
    assert quiet.url in run.stderr and run.stderr.count("\n") == 1


def test_silent_device_after_connect_exits_4(device: CoreDevice) -> None:
    device.to_device.append(lose_messages(gen.Arm))  # telemetry flows, the ARMs are lost: 6 sends x 0.2 s
    run = wrangler("--url", device.url, "--json", "arm")
    assert run.status == ExitStatus.LINK_TIMEOUT and "no ACK/NACK" in run.json["message"]
    assert len(device.host_sent(MsgId.ARM)) == 6


@pytest.mark.parametrize("argv, expected", [
    (["spin", "fast"], "Invalid value for 'MPS'"),
    (["spin", "nan"], "MPS: expected a real number, not NaN"),
    (["spin"], "Missing argument 'MPS'"),
    (["param", "get", "tov"], "unknown parameter 'tov'; did you mean tov_mps?"),
    (["param", "set", "tov_mps", "nan"], "tov_mps: expected a real number, not NaN"),
    (["fly"], "No such command 'fly'"),
    (["--timeout", "0", "status"], "Invalid value for '--timeout'"),
    (["--url", "tcp://x:1", "status"], "url: expected a scheme udp:// or serial://"),
])
def test_usage_errors_exit_2_before_touching_the_link(device: CoreDevice, argv: list[str], expected: str) -> None:
    dev = device
    run = wrangler("--url", dev.url, *argv) if "--url" not in argv else wrangler(*argv)
    machine = wrangler("--json", "--url", dev.url, *argv) if "--url" not in argv else wrangler("--json", *argv)
    assert dev.host_frames == []
    assert run.status == ExitStatus.USAGE and expected in run.stderr and run.stdout == ""
    assert run.stderr.count("\n") == 1
    assert machine.status == ExitStatus.USAGE and machine.json["exit_status"] == "USAGE"


def test_help_goes_to_stdout_and_exits_0() -> None:
    run = wrangler("--help")
    assert run.status == ExitStatus.OK and "Exit status: 0 OK" in run.stdout and "param" in run.stdout


def test_status_prints_one_sample(device: CoreDevice) -> None:
    table = wrangler("--url", device.url, "status")
    assert table.status == ExitStatus.OK and "state" in table.stdout and "DISARMED" in table.stdout
    obj = wrangler("--url", device.url, "--json", "status").json
    assert obj["telemetry"]["state"] == "DISARMED" and obj["telemetry"]["battery_v"] == 14.8


def test_watch_streams_json_lines_for_the_duration(device: CoreDevice) -> None:
    run = wrangler("--url", device.url, "--json", "watch", "--duration", "0.3")
    lines = run.json_lines
    assert run.status == ExitStatus.OK and run.stderr == ""
    assert len(lines) >= 1 and all(line["type"] == "telemetry" for line in lines)
    times = [line["time_s"] for line in lines]
    assert times == sorted(times)


def test_spin_hold_streams_then_spins_down_and_lands(device: CoreDevice) -> None:
    assert wrangler("--url", device.url, "arm").status == ExitStatus.OK
    run = wrangler("--url", device.url, "--json", "spin", "5", "--hold", "0.3")
    lines = run.json_lines
    assert run.status == ExitStatus.OK, run.stderr
    kinds = [line["type"] for line in lines]
    assert kinds[-1] == "result" and kinds.count("telemetry") >= 10 and "event" in kinds
    assert lines[-1]["state"] == "ARMED" and lines[-1]["ok"] is True
    assert any(line.get("state") == "AIRBORNE" for line in lines if line["type"] == "telemetry")
    events = [(line["state_from"], line["state_to"]) for line in lines if line["type"] == "event"]
    assert events[:2] == [("ARMED", "SPINUP"), ("SPINUP", "AIRBORNE")]  # the spin's own event is not missed
    assert device.executed_names() == ["ARM", "SET_ROPE_SPEED", "SPINDOWN"]


def test_ctrl_c_during_hold_spins_down_and_exits_130(device: CoreDevice, monkeypatch) -> None:
    original = Client.telemetry

    def interrupted(self, **kwargs):
        for i, sample in enumerate(original(self, **kwargs)):
            if i == 3:
                raise KeyboardInterrupt
            yield sample

    monkeypatch.setattr(Client, "telemetry", interrupted)
    wrangler("--url", device.url, "arm")
    run = wrangler("--url", device.url, "--json", "spin", "5", "--hold", "10")
    assert run.status == ExitStatus.CTRL_C
    assert run.json_lines[-1]["exit_status"] == "CTRL_C" and "interrupted" in run.stderr
    assert device.executed_names() == ["ARM", "SET_ROPE_SPEED", "SPINDOWN"]


def test_unexpected_exceptions_become_one_line_and_exit_1(device: CoreDevice, monkeypatch) -> None:
    def broken(self, **kwargs):
        raise RuntimeError("boom\nsecond line")

    monkeypatch.setattr(Client, "arm", broken)
    run = wrangler("--url", device.url, "--json", "arm")
    assert run.status == ExitStatus.ERROR
    assert run.stderr == "wrangler: internal error: RuntimeError: boom second line\n"
    assert run.json["error"] == "RuntimeError"


def test_param_list_get_set(device: CoreDevice) -> None:
    listing = wrangler("--url", device.url, "--json", "param", "list").json
    assert [p["name"] for p in listing["params"]][:2] == ["tov_mps", "tov_margin"] and len(listing["params"]) == len(PARAMS)
    assert wrangler("--url", device.url, "param", "get", "tov_mps").stdout == "tov_mps = 2.6 m/s\n"
    held = wrangler("--url", device.url, "--json", "param", "set", "tov_margin", "1.3").json
    assert held["value"] == 1.3 and held["units"] == "1"
    refused = wrangler("--url", device.url, "--json", "param", "set", "tov_mps", "50")
    assert refused.status == ExitStatus.NACK and refused.json["reason"] == "OUT_OF_RANGE"
    human = wrangler("--url", device.url, "param", "list")
    assert "wheel_radius_m" in human.stdout and "locked" in human.stdout


class ClosedAfterOneLine(io.StringIO):
    """stdout of `wrangler ... | head -1`: the second write finds the pipe closed."""

    def write(self, text: str) -> int:
        if self.getvalue():
            raise BrokenPipeError(32, "Broken pipe")
        return super().write(text)


def test_a_reader_that_stops_reading_ends_the_stream_quietly(device: CoreDevice) -> None:
    env = Environment(stdout=ClosedAfterOneLine(), stderr=io.StringIO(), environ={})
    assert main(["--url", device.url, "--json", "watch"], env) == ExitStatus.OK
    assert env.stderr.getvalue() == "" and len(env.stdout.getvalue().splitlines()) == 1


def test_a_link_that_cannot_be_opened_exits_1_with_the_reason() -> None:
    run = wrangler("--json", "--url", "serial:///dev/robowrangler-does-not-exist", "status")
    assert run.status == ExitStatus.ERROR and run.json["error"] == "LinkError"
    assert run.stderr.startswith("wrangler: cannot open serial:///dev/robowrangler-does-not-exist: ")


def test_home_loop_grasp_release_from_the_shell(device: CoreDevice) -> None:
    device.spindle.object_mm = 75.0
    url = ("--url", device.url)
    assert wrangler(*url, "arm").status == ExitStatus.OK
    not_homed = wrangler(*url, "--json", "loop", "50")
    assert not_homed.status == ExitStatus.NACK and not_homed.json["reason"] == "NOT_HOMED"
    homed = wrangler(*url, "--json", "home")
    assert homed.status == ExitStatus.OK and homed.json["guide_mm"] == 0.0
    moved = wrangler(*url, "loop", "62.5")
    assert moved.status == ExitStatus.OK and moved.stdout.startswith("guide at 62.")  # within spindle_tolerance_mm
    assert moved.stdout.endswith(" mm (target 62.5 mm, state ARMED)\n")
    assert wrangler(*url, "--json", "loop", "500").json["reason"] == "OUT_OF_RANGE"
    assert wrangler(*url, "spin", "5").status == ExitStatus.OK
    assert wrangler(*url, "watch", "--duration", "0.2").status == ExitStatus.OK  # airborne by then
    held = wrangler(*url, "--json", "grasp")
    assert held.status == ExitStatus.OK, held.stderr
    assert held.json["state"] == "HOLD" and abs(held.json["guide_mm"] - 75.0) < 1.0
    assert wrangler(*url, "--json", "release").json["state"] == "ARMED"
    assert [n for n in device.executed_names() if n != "SET_ROPE_SPEED"] == [
        "ARM", "HOME", "SET_LOOP", "GRASP", "RELEASE"]


def test_loop_is_not_done_on_the_samples_sent_before_the_spindle_loop_acted(core_lib) -> None:
    """The core's own telemetry after SET_LOOP: the first frame may carry the new target but no moving speed yet (the
    spindle loop steps every SPINDLE_PERIOD_MS), the guide where it was. `wrangler loop` must not stop there, on
    whichever sample a busy machine happens to deliver first."""
    from robowrangler.cli.spindle import _settled_at
    from robowrangler.telemetry import TelemetrySample

    def move_after(delay_ms: int) -> list[TelemetrySample]:
        """The core's telemetry from a SET_LOOP 12 mm sent delay_ms into a 20 ms telemetry period."""
        h = CoreHarness(core_lib, params=QUICK_ARM, spindle=FakeSpindle(start_mm=6.0))
        h.run_ms(600)
        h.command(gen.Home())
        h.run_until(lambda: h.events(gen.EventKind.SPINDLE_HOMED) != [], max_ms=3000, what="SPINDLE_HOMED")
        h.command(gen.Arm())
        h.run_ms(100)
        sent = len(h.telemetry())
        h.run_until(lambda: len(h.telemetry()) > sent, max_ms=40, what="a telemetry frame")
        h.run_ms(delay_ms)
        n = len(h.telemetry())
        h.command(gen.SetLoop(12_000))
        for _ in range(40):  # a live host: the guide moves only while one heartbeats
            h.heartbeat()
            h.run_ms(100)
        return [TelemetrySample.from_wire(t, received_s=0.0) for t in h.telemetry()[n:]]

    for delay_ms in range(0, 20, 3):  # the command's phase against the spindle loop's steps
        samples = move_after(delay_ms)
        first = samples[0]
        if gen.SpindleFlag.MOVING not in first.spindle_flags:
            break
    assert abs(first.guide_target_m - 0.012) < 1e-6 and gen.SpindleFlag.MOVING not in first.spindle_flags
    assert first.guide_position_m < 0.001  # the sample a naive "target and not MOVING" would take as done
    done = _settled_at(0.012)
    end = next(s for s in samples if done(s))
    assert abs(end.guide_position_m - 0.012) < 0.0006  # within spindle_tolerance_mm of the target


def test_a_retract_that_secures_nothing_exits_1(device: CoreDevice) -> None:
    wrangler("--url", device.url, "param", "set", "guide_max_mm", "30")  # a short stroke keeps the test short
    wrangler("--url", device.url, "arm")
    wrangler("--url", device.url, "home")
    run = wrangler("--url", device.url, "--json", "retract")
    assert run.status == ExitStatus.ERROR and run.json["error"] == "NothingGrasped"
    assert re.search(r"the end of the stroke \((29\.9|30\.0)[0-9]* mm\) without securing a load", run.stderr)


def test_signed_link_from_a_key_file(core_lib, tmp_path) -> None:
    key = TEST_KEY
    key_file = tmp_path / "link.key"
    key_file.write_text(key.hex() + "\n")
    with CoreDevice(core_lib, params=QUICK_ARM, boot_s=0.25) as device:  # its flash holds TEST_KEY
        run = wrangler("--url", device.url, "--key-file", str(key_file), "--json", "arm")
        assert run.status == ExitStatus.OK and run.json["state"] == "ARMED"
        via_env = wrangler("--url", device.url, "--json", "disarm", environ={"ROBOWRANGLER_KEY_FILE": str(key_file)})
        assert via_env.status == ExitStatus.OK
        keyless = wrangler("--url", device.url, "--timeout", "0.3", "--json", "status")
        assert keyless.status == ExitStatus.AUTH and keyless.json["error"] == "AuthenticationError"
        assert "no link key was given: wrangler reads the key from --key-file PATH, else from the file " \
               "$ROBOWRANGLER_KEY_FILE names" in keyless.stderr
        assert "key=" not in keyless.stderr  # the Python API's wording stays out of the CLI
    assert key.hex() not in run.stdout + run.stderr + keyless.stdout + keyless.stderr


@pytest.mark.parametrize("content, expected", [("abc", "32 hex digits"), ("zz" * 16, "32 hex digits")])
def test_a_bad_key_file_is_a_usage_error_that_does_not_echo_it(tmp_path, content: str, expected: str) -> None:
    key_file = tmp_path / "bad.key"
    key_file.write_text(content)
    run = wrangler("--url", "udp://127.0.0.1:9", "--key-file", str(key_file), "status")
    assert run.status == ExitStatus.USAGE and expected in run.stderr and content not in run.stderr
    missing = wrangler("--url", "udp://127.0.0.1:9", "--key-file", str(tmp_path / "none"), "status")
    assert missing.status == ExitStatus.USAGE and "readable file" in missing.stderr


def test_provision_over_serial_generates_a_key_and_never_prints_it(core_lib, tmp_path) -> None:
    key_path = tmp_path / "link.key"
    password_path = tmp_path / "wifi.pw"
    password_path.write_text("correct horse\n")
    with CoreDevice(core_lib, link="serial", provisioned=False) as dev:
        url = f"serial://{dev.open_pty()}"
        run = wrangler("--url", url, "--json", "provision", "set", "--generate-key", str(key_path),
                       "--wifi-ssid", "lab", "--wifi-password-file", str(password_path))
        status = wrangler("--url", url, "provision", "status")
        again = wrangler("--url", url, "provision", "set", "--generate-key", str(key_path))
    assert run.status == ExitStatus.OK, run.stderr
    assert run.json["key_set"] is True and run.json["wifi_ssid"] == "lab" and run.json["commits"] == 1
    key_hex = key_path.read_text().strip()
    assert bytes.fromhex(key_hex) in dev.harness.flash and b"correct horse" in dev.harness.flash  # the core's record
    assert oct(key_path.stat().st_mode & 0o777) == "0o600"
    for out in (run, status, again):
        assert key_hex not in out.stdout + out.stderr and "correct horse" not in out.stdout + out.stderr
    assert "link key       set" in status.stdout
    assert again.status == ExitStatus.USAGE and "a key is never overwritten" in again.stderr


def test_provision_refuses_a_wifi_link_before_connecting(device: CoreDevice) -> None:
    run = wrangler("--url", device.url, "--json", "provision", "set", "--wifi-ssid", "lab")
    assert run.status == ExitStatus.USAGE and "provisioning never travels over WiFi" in run.json["message"]
    assert device.host_frames == []
