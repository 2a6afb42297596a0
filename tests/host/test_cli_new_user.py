"""`wrangler` as a new user meets it (issue 18): first commands on a fresh HOME, bad numbers, no subcommand,
--version, `help CMD`, --json after the verb. In-process through main(argv, env), against the real firmware core (tests/host/core_device.py)."""

from __future__ import annotations

import threading
import time

import pytest

from robowrangler.cli.exit_status import ExitStatus
from robowrangler.protocol.generated import PARAMS
from core_device import CoreDevice
from core_harness import FakeSpindle, TEST_KEY
from host_settings import QUICK_ARM
from robowrangler.protocol.generated import MsgId, decode_frame
from test_cli import FAST_SPINDLE, wrangler

@pytest.fixture
def device(core_lib):
    """The real core past its arming hold on its serial link (the CLI's default: no key), reached over UDP, with a
    fast lead screw, its clock at twice the wall clock (as test_cli.py's)."""
    with CoreDevice(core_lib, link="serial", params=FAST_SPINDLE, spindle=FakeSpindle(lead_mm_per_rev=20.0),
                    boot_s=0.25, speedup=2.0) as dev:
        yield dev



def test_keygen_creates_the_missing_config_folder_privately(tmp_path) -> None:
    path = tmp_path / "home" / ".config" / "robowrangler" / "link.key"
    run = wrangler("keygen", str(path))
    assert run.status == ExitStatus.OK, run.stderr
    assert len(bytes.fromhex(path.read_text().strip())) == 16
    assert oct(path.stat().st_mode & 0o777) == "0o600" and oct(path.parent.stat().st_mode & 0o777) == "0o700"
    again = wrangler("keygen", str(path))
    assert again.status == ExitStatus.USAGE and again.stderr.startswith("wrangler: PATH: expected a path that does "
                                                                         "not exist yet")


def test_keygen_errors_name_the_argument_the_user_typed(tmp_path) -> None:
    blocker = tmp_path / "file"
    blocker.write_text("not a folder")
    run = wrangler("keygen", str(blocker / "link.key"))
    assert run.status == ExitStatus.USAGE and run.stderr.startswith("wrangler: PATH: ")
    assert "--generate-key" not in run.stderr and str(blocker) in run.stderr


@pytest.mark.parametrize("argv, expected", [
    (["spin", "1e308"], "MPS: expected a speed encodable as int32 mm/s"),
    (["spin", "--", "-1e308"], "MPS: expected a speed encodable as int32 mm/s"),
    (["loop", "1e308"], "GUIDE_MM: expected a guide position encodable on the wire (|x| <= 2147483.647 mm)"),
    (["loop", "1e9"], "(|x| <= 2147483.647 mm), got 1000000000.0"),
    (["spin", "2", "--hold", "nan"], "'nan' is not a finite number of seconds"),
    (["loop", "50", "--within", "nan"], "'nan' is not a finite number of seconds"),
    (["watch", "--duration", "inf"], "'inf' is not a finite number of seconds"),
    (["param", "set", "encoder_counts_per_rev", "64.5"], "encoder_counts_per_rev: expected an integer"),
])
def test_numbers_nothing_can_carry_are_usage_errors_before_the_link(argv: list[str], expected: str,
                                                                    core_lib) -> None:
    with CoreDevice(core_lib, link="serial") as dev:
        run = wrangler("--url", dev.url, *argv)
        assert dev.host_sent() == []
    assert run.status == ExitStatus.USAGE and expected in run.stderr, run.stderr
    assert run.stderr.count("\n") == 1 and "internal error" not in run.stderr


@pytest.mark.parametrize("argv, usage", [([], "wrangler [OPTIONS] COMMAND"), (["param"], "wrangler param [OPTIONS]"),
                                         (["provision"], "wrangler provision [OPTIONS]")])
def test_no_subcommand_prints_the_help_as_help_not_one_line(argv: list[str], usage: str) -> None:
    run = wrangler(*argv)
    assert run.status == ExitStatus.USAGE and run.stdout == ""
    lines = run.stderr.splitlines()
    assert lines[0] == f"Usage: {usage} COMMAND [ARGS]..." if argv else lines[0].startswith(f"Usage: {usage}")
    assert len(lines) > 8 and "Commands:" in run.stderr
    assert lines[-1].startswith("wrangler: missing command")


def test_version_and_help_command() -> None:
    version = wrangler("--version")
    assert version.status == ExitStatus.OK and version.stdout.startswith("wrangler 0.") and "protocol v2" in version.stdout
    helped = wrangler("help", "param", "set")
    assert helped.status == ExitStatus.OK and helped.stdout == wrangler("param", "set", "--help").stdout
    assert wrangler("help").stdout == wrangler("--help").stdout
    unknown = wrangler("help", "fly")
    assert unknown.status == ExitStatus.USAGE and "No such command 'fly'" in unknown.stderr


@pytest.mark.parametrize("argv", [["status", "--json"], ["watch", "--duration", "0.1", "--json"],
                                  ["param", "get", "tov_mps", "--json"], ["arm", "--json"]])
def test_json_works_after_any_verb(device: CoreDevice, argv: list[str]) -> None:
    run = wrangler("--url", device.url, *argv)
    assert run.status == ExitStatus.OK, run.stderr
    assert run.json_lines and all(isinstance(line, dict) for line in run.json_lines)


def test_loop_progress_timeout_and_no_wait_say_what_the_guide_does(device: CoreDevice) -> None:
    """Item 4: a guide move needs a live host. The wait shows progress; a --within timeout says where the guide
    is and that it stops there; --no-wait says the guide goes on only while a host is alive."""
    url = ("--url", device.url)
    assert wrangler(*url, "arm").status == ExitStatus.OK
    assert wrangler(*url, "home").status == ExitStatus.OK
    # the fixture's guide moves at most 15 mm/s: 150 mm take seconds more than the 2.5 s allowed
    late = wrangler(*url, "loop", "150", "--within", "2.5")
    assert late.status == ExitStatus.ERROR and late.stdout == ""
    lines = late.stderr.splitlines()
    assert lines[0].startswith("wrangler: loop: guide at ") and "of the target 150 mm" in lines[0]  # progress
    assert lines[-1].startswith("wrangler: loop: not done within 2.5 s: the guide is at ")
    assert "still moving; the device stops it there heartbeat_timeout_s after this command exits" in lines[-1]
    quick = wrangler(*url, "--json", "loop", "20", "--no-wait")
    assert quick.status == ExitStatus.OK and quick.json["guide_target_mm"] == 20
    assert "the guide goes on only while a host is alive" in quick.stderr
    helped = wrangler("loop", "--help").stdout
    assert "alone it stops where it is" in " ".join(helped.split())


def test_spin_hold_below_the_tov_guard_says_the_loop_never_flew(device: CoreDevice) -> None:
    assert wrangler("--url", device.url, "arm").status == ExitStatus.OK
    run = wrangler("--url", device.url, "spin", "2.5", "--hold", "0.4")
    assert run.status == ExitStatus.OK, run.stderr
    assert "the loop never flew: 2.5 m/s is under the ToV guard" in run.stdout and "held" not in run.stdout
    flown = wrangler("--url", device.url, "--json", "spin", "5", "--hold", "0.4")
    assert flown.json_lines[-1]["airborne"] is True


def test_spin_zero_points_at_spindown(device: CoreDevice) -> None:
    assert wrangler("--url", device.url, "arm").status == ExitStatus.OK
    run = wrangler("--url", device.url, "spin", "0")
    assert run.status == ExitStatus.NACK and "command spindown (`wrangler spindown`)" in run.stderr
    assert "limit crossed" not in run.stderr


def test_two_hosts_through_a_proxy_the_holder_reports_what_the_other_did(device: CoreDevice, tmp_path) -> None:
    """Host A holds 4 m/s through `wrangler proxy`; host B changes the speed, then ESTOPs. A says the target was
    changed by another host, and after the ESTOP that the device left the spin, not that it was interrupted."""
    import socket
    import threading
    import time

    with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as s:
        s.bind(("127.0.0.1", 0))
        port = s.getsockname()[1]
    proxy_run: list = []
    proxy = threading.Thread(target=lambda: proxy_run.append(
        wrangler("--url", device.url, "proxy", "--listen", str(port), "--duration", "6")), daemon=True)
    proxy.start()
    tool = ("--url", f"udp://127.0.0.1:{port}")
    deadline = time.monotonic() + 5
    while wrangler(*tool, "--timeout", "0.3", "arm").status != ExitStatus.OK:
        assert time.monotonic() < deadline
    held: list = []
    a = threading.Thread(target=lambda: held.append(wrangler(*tool, "spin", "4", "--hold", "1.2")), daemon=True)
    a.start()
    time.sleep(0.6)
    assert wrangler(*tool, "spin", "6").status == ExitStatus.OK
    a.join(10)
    assert held[0].status == ExitStatus.OK, held[0].stderr
    assert "the target was changed to 6 m/s by another host" in held[0].stdout
    stopped: list = []
    a = threading.Thread(target=lambda: stopped.append(wrangler(*tool, "spin", "4", "--hold", "3")), daemon=True)
    a.start()
    time.sleep(0.6)
    assert wrangler(*tool, "estop").status == ExitStatus.OK
    a.join(10)
    assert stopped[0].status == ExitStatus.ERROR, stopped[0].stderr
    assert stopped[0].stderr.splitlines()[-1] == ("wrangler: spin --hold: the device went to ESTOP during the hold "
                                                  "(another host or a fault: see `wrangler status`); the rope is not "
                                                  "driven")
    assert "interrupt" not in stopped[0].stderr
    proxy.join(10)
    assert proxy_run[0].status == ExitStatus.OK, proxy_run[0].stderr


def test_param_list_is_a_table_with_units_defaults_and_changes_marked(device: CoreDevice) -> None:
    assert wrangler("--url", device.url, "param", "set", "TOV_Margin", "1.3").stdout == "tov_margin = 1.3 1\n"
    table = wrangler("--url", device.url, "param", "list").stdout.splitlines()
    assert table[0].split() == ["name", "value", "unit", "default", "range"]
    rows = {line.split()[0]: line.split() for line in table[1:]}
    assert rows["tov_margin"][:5] == ["tov_margin", "1.3*", "1", "1.15", "[1,"]  # changed: marked
    assert rows["tov_mps"][:4] == ["tov_mps", "2.6", "m/s", "2.6"]
    assert "integer" in table[[r.split()[0] for r in table].index("encoder_counts_per_rev")]
    assert len(rows) == len(PARAMS)


def test_param_names_are_case_insensitive_with_did_you_mean(device: CoreDevice) -> None:
    assert wrangler("--url", device.url, "param", "get", "TOV_MPS").stdout == "tov_mps = 2.6 m/s\n"
    typo = wrangler("--url", device.url, "param", "get", "Tov_Mrgin")
    assert typo.status == ExitStatus.USAGE and "did you mean tov_margin" in typo.stderr


def test_no_key_at_all_fails_at_the_devices_first_answer_not_after_the_connect_timeout(core_lib) -> None:
    # a keyed device over WiFi answers the keyless HELLO with a signed SESSION_INFO and then stays silent: the
    # CLI must say so at that answer, with where it looked for a key and how to get one, not after --timeout
    timeout_s = 600.0
    runs: list = []
    with CoreDevice(core_lib, params=QUICK_ARM, boot_s=0.25) as dev:  # its flash holds TEST_KEY
        start_s = time.monotonic()
        cli = threading.Thread(target=lambda: runs.append(wrangler("--url", dev.url, "--timeout", str(timeout_s),
                                                                   "--json", "arm")), daemon=True)
        cli.start()
        cli.join(timeout_s / 5)
        waited_s = time.monotonic() - start_s
        assert not cli.is_alive(), "a keyless command waited for its connect timeout"
        sent = [decode_frame(frame).msg_id for frame in dev.host_frames]
        assert dev.executed_names() == []
    (run,) = runs
    assert waited_s < timeout_s  # the answer ended it, not the timeout
    assert run.status == ExitStatus.AUTH == 5 and run.json["needs_key"] is True
    message = run.stderr
    for hint in ("--key-file PATH", "$ROBOWRANGLER_KEY_FILE", "neither was set", "wrangler keygen PATH",
                 "wrangler provision --port /dev/ttyACM0 set --link-key-file PATH"):
        assert hint in message, (hint, message)
    assert message.count("\n") == 1 and "key=" not in message and TEST_KEY.hex() not in message
    assert MsgId.HELLO in sent


@pytest.mark.parametrize(("argv", "refused"), [
    (["loop", "-5"], "guide position -5 mm"),
    (["spin", "-1", "--hold", "1"], "rope speed -1 m/s"),
    (["param", "set", "guide_min_mm", "-3"], "guide_min_mm = -3"),
])
def test_a_negative_number_reaches_the_device_instead_of_being_taken_for_an_option(device: CoreDevice, argv: list[str],
                                                                                     refused: str) -> None:
    # click read `-5` as an unknown option ("No such option '-5'"): the user never learnt the device's limit
    assert wrangler("--url", device.url, "arm").status == ExitStatus.OK
    if argv[0] == "loop":
        assert wrangler("--url", device.url, "home").status == ExitStatus.OK
    run = wrangler("--url", device.url, *argv)
    assert run.status == ExitStatus.NACK, run.stderr
    assert "OUT_OF_RANGE" in run.stderr and refused in run.stderr and "No such option" not in run.stderr


def test_a_word_that_is_no_number_is_still_an_unknown_option() -> None:
    run = wrangler("--url", "udp://127.0.0.1:9", "spin", "-x")
    assert run.status == ExitStatus.USAGE and "No such option '-x'" in run.stderr
    inf = wrangler("--url", "udp://127.0.0.1:9", "loop", "-inf")
    assert inf.status == ExitStatus.USAGE and "expected a finite number, got -inf" in inf.stderr
