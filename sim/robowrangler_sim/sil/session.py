"""A SIL session: the firmware process, the drive and spindle plants and the lockstep between them.

The plant owns the clock: each tick the session sends the plants' sensor values at time t, the firmware
runs one control tick and answers with its ESC pulse and spindle command, and the plants integrate
[t, t + tick) through the plant contract (plants/contract.py: ``update(inputs, dt_s) -> outputs``). Nothing
depends on the wall clock, so the same seed and the same host frames at the same ticks give the same
telemetry at any pacing. Pacing (``speedup``): 1.0 is real time, 10.0 ten times faster, None as fast
as the machine goes; a busy machine makes a paced session slower, never bursty (PACE_SLACK_S).
"""

from __future__ import annotations

import heapq
import itertools
import secrets
import tempfile
import threading
import time
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from robowrangler.protocol.generated import KEY_LEN
from robowrangler.telemetry import ProvisionStatus
from robowrangler.transport_serial import SerialTransport
from robowrangler_sim.plants import DriveParams, DrivePlant
from robowrangler_sim.plants.contract import Plant
from robowrangler_sim.plants.drive import DriveInputs, DriveOutputs
from robowrangler_sim.plants.spindle import SpindleInputs, SpindleOutputs, SpindleParams, SpindlePlant
from robowrangler_sim.sil.errors import SilError, SilFirmwareError
from robowrangler_sim.sil.firmware import FirmwareProcess
from robowrangler_sim.sil.lockstep import LockstepLink
from robowrangler_sim.sil.provisioning_jig import Provisioner
from robowrangler_sim.sil.usb_notes import UsbNotes
from robowrangler_sim.sil.wifi_module import WifiModule, WifiModuleError, parse_counters

BOOT_LIMIT_S = 20.0
"""The longest WiFi boot a session waits for before provisioning (the board's bounds: 2 s for the module's ready
line, 15 s for the blocking WiFi.begin; plant time)."""


@dataclass(frozen=True)
class PlantSample:
    """Plant truth at one tick (what the firmware cannot see directly)."""

    time_s: float
    rope_speed_mps: float
    esc_pulse_us: int
    battery_v: float
    external_rope_load_n: float
    loop_airborne: bool
    guide_position_mm: float
    loop_length_m: float
    rope_tension_n: float


@dataclass(frozen=True)
class SensorValues:
    """The sensor values the plant hands the firmware at one tick (the SIL_SENSORS fields but the barrier)."""

    time_us: int
    encoder_counts: int
    encoder_last_edge_us: int
    battery_mv: int
    spindle_position_raw: int = 0
    spindle_speed_raw: int = 0
    spindle_load_raw: int = 0
    spindle_answered: bool = False
    limit_switch: bool = False


PACE_SLACK_S = 0.02
"""A paced session further behind the wall clock than this re-anchors its pacing: speedup is an upper bound,
never a rate to catch up to (at most PACE_SLACK_S x speedup of simulated time runs unpaced)."""

SensorFilter = Callable[[SensorValues], "SensorValues | None"]
"""Per tick, before the exchange: returns the values the firmware sees, or None = the firmware misses this tick."""
ActuatorFilter = Callable[[int], int]
"""Per tick, after the exchange: maps the ESC pulse the firmware drives (us) to the pulse the plant's ESC gets."""
TickHook = Callable[["SilSession"], None]
"""Per tick, after the drive and spindle plants stepped: couples another plant (e.g. the rope chain) in lockstep."""


@dataclass
class PlantLoads:
    """What the scene applies to the plants, held until changed (set between ticks: at(), tick hooks, tests).

    Attributes:
        external_rope_load_n: disturbance force on the rope, N (>= 0), opposing its motion (DriveInputs).
        battery_aux_current_a: other loads on the pack, A; None: the drive params' value (DriveInputs).
        guide_load_n: the rope's pull on the guide from another plant (the rope chain), N; None: the spindle
            plant's own stand-in object (SpindleInputs).
        rope_exposed_length_m: rope in moving air, m (DriveInputs); None: the spindle's loop length (clamped to
            0.05 m .. the drive's rope_loop_length_m). 0: no rope flies (a broken rope).
    """

    external_rope_load_n: float = 0.0
    battery_aux_current_a: float | None = None
    guide_load_n: float | None = None
    rope_exposed_length_m: float | None = None


def _make_plant(kind: str, given: Any, params: Any, seed: int, default_cls: type) -> Any:
    """A session plant from SilSession's ``drive`` / ``spindle`` argument (see there)."""
    if given is None:
        return default_cls(params, seed=seed)
    if isinstance(given, type) or (callable(given) and not isinstance(given, Plant)):
        made = given(params, seed=seed)
        if not isinstance(made, Plant):
            raise TypeError(f"{kind}: expected the factory to return a plant meeting the plant contract "
                            f"(update/outputs/reset), got {type(made).__name__}")
        return made
    if isinstance(given, Plant):
        if params is not None and getattr(given, "params", params) != params:
            raise ValueError(f"{kind}: expected a plant built with {kind}_params (or {kind}_params=None), "
                             f"got one with {given.params!r}")
        return given
    raise TypeError(f"{kind}: expected None, a plant meeting the plant contract (update/outputs/reset) or a "
                    f"factory(params, *, seed), got {type(given).__name__}")


class SilSession:
    """Firmware + drive and spindle plants in lockstep. Use as a context manager, or start()/stop().

    Args:
        drive_params: drive plant parameters (defaults: AS2317-class motors, 3S LiPo, 15 mm wheels).
        spindle_params: spindle plant parameters (AX-12A, T8 lead screw, 180 mm stroke).
        drive: the drive plant: None builds a DrivePlant(drive_params, seed=seed); a plant meeting the plant
            contract with DriveInputs -> DriveOutputs (and a ``params`` DriveParams) is used as given; a callable
            ``factory(drive_params, *, seed)`` (a plant class itself) is called with the session's params and seed.
        seed: plant noise seed.
        tick_us: control tick, microseconds (the firmware's period; 1000 = 1 kHz as on the board).
        speedup: pacing factor for run_for/background running; None = unpaced.
        cmd_port: UDP port of the firmware's command link on 127.0.0.1 (0 = a free port).
        trace_every: keep a PlantSample every this many ticks (0 = none).
        key: the link key provisioned into the SIL device over its USB serial at start (None: a fresh random
            one; read it from ``key``). provision=False starts an unprovisioned device (it refuses WiFi).
        state_file: the SIL device's flash (configuration record, boot counter = session id); None: a file in
            a temporary folder removed at stop().
        spindle: the spindle plant the firmware's servo bus drives, as ``drive`` (SpindleInputs -> SpindleOutputs;
            None builds a SpindlePlant(spindle_params, seed=seed), so the register noise follows the seed).
        model: a drive model file written by `wrangler diagnose` (model.json) or a DiagnosedModel: its refitted
            DriveParams drive the plant and its effect terms act through the actuator filters, ``loads`` and a
            tick hook (robowrangler_sim.diagnose.sil_effects).
        tick_timeout_s: how often the lockstep checks that a slow firmware is still alive while it waits for a
            tick's answer; a busy machine only makes the wait longer, only a firmware that exited (or stays
            silent for minutes) ends the session (lockstep.LockstepLink).
        spindle_bus_us: bus time of one spindle transaction in the firmware's bus model (rw_sil
            --spindle-bus-us, firmware/hal/sil/sil_spindle_bus.h; None: its default, 350 us). The firmware
            steps the spindle with the reading its bus side completed since the previous step, as on the board.
        wifi: the board's NINA WiFi module in the firmware (robowrangler_sim.sil.wifi_module): None or a default
            WifiModule is a healthy module (the link up from the first tick); a WifiModule, or its spec text (e.g.
            "boot=never", "lost=3.0-3.8", "busy_us=3000"), scripts its faults. A module that is slow to boot
            delays the firmware's control tick as the board's setup() does: start() steps the plant until the
            device's USB says how the WiFi boot ended (``usb_notes``), then provisions it.

    Each tick the session composes the plants through the contract only: the drive gets DriveInputs (the
    firmware's ESC pulse after the actuator filters, the scene's ``loads``, the rope exposed = the spindle's
    loop length), the spindle SpindleInputs (the firmware's moving speed, ``loads.guide_load_n``); the sensors the
    firmware sees and the trace come from their outputs (``drive_out``, ``spindle_out``). ``plant`` is the drive
    plant (its older name).

    Fault hooks (fault injection at the HAL boundary, see plant_faults.py): ``sensor_filters`` and
    ``actuator_filters`` are lists of callables applied in order every tick. A sensor filter gets the
    SensorValues and returns the (possibly altered) values the firmware sees, or None: then no
    SIL_SENSORS is sent, the firmware misses the tick and the plant runs on with the last ESC pulse (a
    stalled control loop). An actuator filter maps the ESC pulse the firmware drives to the pulse the
    plant's ESC receives (applied on missed ticks too). Change the lists between steps or in at().

    Plant coupling (``tick_hooks``): callables hook(session) run every tick right after the drive and spindle
    plants stepped, in order; a hook may read their outputs and set ``loads`` for the next tick (see
    robowrangler_sim.scenarios.chain_bridge, which steps the rope chain this way).
    """

    def __init__(self, *, drive_params: DriveParams | None = None, spindle_params: SpindleParams | None = None,
                 seed: int = 0, tick_us: int = 1000,
                 speedup: float | None = 1.0, cmd_port: int = 0, trace_every: int = 10,
                 plant_timeout_s: int = 10, key: bytes | None = None, provision: bool = True,
                 state_file: str | Path | None = None,
                 drive: Plant | Callable[..., Plant] | None = None,
                 spindle: Plant | Callable[..., Plant] | None = None,
                 spindle_bus_us: int | None = None,
                 tick_timeout_s: float = 2.0, model=None, wifi: WifiModule | str | None = None) -> None:
        diagnosed = None
        if model is not None:  # a drive model file written by `wrangler diagnose` (or a DiagnosedModel)
            from robowrangler_sim.diagnose.model_file import DiagnosedModel, load_model

            if drive_params is not None or drive is not None:
                raise ValueError("model: expected either model or drive_params/drive, got both")
            diagnosed = model if isinstance(model, DiagnosedModel) else load_model(model)
            drive_params = diagnosed.sil_drive_params()
            if spindle_params is None and spindle is None:  # its spindle terms (dead band, backlash) too
                spindle_params = diagnosed.sil_spindle_params()
        if not isinstance(tick_us, int) or not 100 <= tick_us <= 5000:
            raise ValueError(f"tick_us: expected an int in [100, 5000] us, got {tick_us!r}")
        if speedup is not None and not (isinstance(speedup, (int, float)) and speedup > 0):
            raise ValueError(f"speedup: expected a positive factor or None (unpaced), got {speedup!r}")
        self.drive = _make_plant("drive", drive, drive_params, seed, DrivePlant)
        self.spindle = _make_plant("spindle", spindle, spindle_params, seed, SpindlePlant)
        self.loads = PlantLoads()
        self.drive_out: DriveOutputs = self.drive.outputs()
        self.spindle_out: SpindleOutputs = self.spindle.outputs()
        self._rope_loop_length_m = self.drive.params.rope_loop_length_m
        self.last_spindle_speed_raw = 0
        self.tick_us = tick_us
        self.speedup = speedup
        if not (isinstance(tick_timeout_s, (int, float)) and tick_timeout_s > 0):
            raise ValueError(f"tick_timeout_s: expected a positive number of seconds, got {tick_timeout_s!r}")
        self.tick_timeout_s = float(tick_timeout_s)
        self.trace_every = trace_every
        self.trace: list[PlantSample] = []
        self.ticks = 0
        self.last_esc_pulse_us = 0
        self.last_esc_pulse_fine_us = 0.0
        self.sensor_filters: list[SensorFilter] = []
        self.actuator_filters: list[ActuatorFilter] = []
        self.tick_hooks: list[TickHook] = []
        self.key = secrets.token_bytes(KEY_LEN) if key is None else bytes(key)
        self._provision_on_start = provision
        self._tmpdir = None if state_file is not None else tempfile.TemporaryDirectory(prefix="rw_sil_")
        self.state_file = Path(state_file) if state_file is not None else Path(self._tmpdir.name) / "flash.bin"
        if isinstance(wifi, str):
            wifi = WifiModule.parse(wifi)
        elif wifi is None:
            wifi = WifiModule()
        elif not isinstance(wifi, WifiModule):
            raise WifiModuleError("wifi", "None, a WifiModule or its spec text (e.g. 'boot=never')", wifi)
        self.wifi = wifi
        self.usb_notes: list[tuple[float, str]] = []  # status lines read by start() while the WiFi booted
        self._firmware = FirmwareProcess(cmd_port=cmd_port, plant_timeout_s=plant_timeout_s, tick_us=tick_us,
                                         state_file=self.state_file, spindle_bus_us=spindle_bus_us,
                                         wifi_args=wifi.firmware_args())
        self._link: LockstepLink | None = None
        self._actions: list[tuple[int, int, Callable[[], None]]] = []
        self._action_counter = itertools.count()
        self._lock = threading.Lock()
        self._thread: threading.Thread | None = None
        self._stop = threading.Event()
        self._error: BaseException | None = None
        self._pace_origin: tuple[float, int] | None = None
        self.model = diagnosed
        if diagnosed is not None:
            diagnosed.install(self)

    # ---------------------------------------------------------------------------------------------
    @property
    def cmd_port(self) -> int:
        return self._firmware.cmd_port

    @property
    def cmd_url(self) -> str:
        """Where a host talks to this SIL device: the same protocol as the board on WiFi."""
        return f"udp://127.0.0.1:{self.cmd_port}"

    @property
    def plant(self):
        """The drive plant (its older name; ``drive``)."""
        return self.drive

    @property
    def time_s(self) -> float:
        return self.drive_out.time_us * 1e-6

    @property
    def firmware_pid(self) -> int | None:
        """The SIL firmware's process id (None before start)."""
        return self._firmware.pid

    @property
    def lockstep(self) -> LockstepLink | None:
        """The plant's end of the lockstep socket (None before start)."""
        return self._link

    @property
    def serial_path(self) -> str:
        """The SIL device's USB serial (a pseudo-terminal): pyserial opens it like /dev/ttyACM0."""
        return self._firmware.serial_path

    def start(self) -> SilSession:
        self._firmware.start()
        self._link = LockstepLink(self._firmware.plant_port, tick_timeout_s=self.tick_timeout_s,
                                  alive=lambda: self._firmware.poll() is None)
        if self.wifi.boot_takes_time:
            self._power_up()
        if self._provision_on_start:
            self.provision(key=self.key)
        return self

    def _power_up(self) -> None:
        """Step the plant while the board's WiFi boot runs (its control tick has not started: USB is not served),
        until the device's USB says how it ended (``wifi UP``, ``wifi CONNECTING``, ``wifi NO_MODULE: ...``)."""
        end_us = self.drive_out.time_us + round(BOOT_LIMIT_S * 1e6)
        with UsbNotes(self.serial_path) as usb:
            while not any(text.startswith("wifi") for _, text in self.usb_notes):
                if self.drive_out.time_us >= end_us:
                    raise SilError(f"the SIL device's WiFi boot did not end within {BOOT_LIMIT_S:g} s of plant time "
                                   f"(module {self.wifi})")
                self.step()
                self.usb_notes += [(self.time_s, text) for text in usb.read()]

    def wifi_counters(self) -> dict[str, int | str]:
        """After stop(): the firmware's WiFi link counters ("rw_sil wifi" on its stderr): state, boot_ms, polls,
        connects, losses, attempts, deferred, module_busy, module_hangs, ready_waits_expired, calls, ... ."""
        return parse_counters(self.firmware_stderr, "rw_sil wifi")

    def led_counters(self) -> dict[str, int | str]:
        """After stop(): the status LED ("rw_sil led"): on (at the end), on_ticks, off_ticks, changes,
        last_change_ms; with the ticks the control tick ran and its overruns."""
        return parse_counters(self.firmware_stderr, "rw_sil led")

    def provision(self, **fields) -> ProvisionStatus:
        """Provision over the USB serial (the key, WiFi, parameters: Provisioner.provision's keywords) while
        the clock stands still, so provisioning leaves no trace in the simulated timeline."""
        transport = SerialTransport(self.serial_path, url=f"serial://{self.serial_path}")
        try:
            return Provisioner(transport, url=f"serial://{self.serial_path}", pump=self._tick_frozen).provision(**fields)
        finally:
            transport.close()

    def _tick_frozen(self) -> None:
        """A control tick at the current plant time, without advancing the plant (dt = 0 for the firmware)."""
        self._exchange(self._read_sensors(), host_frames_sent=0)
        time.sleep(0.0005)  # the pseudo-terminal hands bytes over asynchronously

    def _read_sensors(self) -> SensorValues:
        """What the plants' outputs show the firmware's HAL now."""
        d, sp = self.drive_out, self.spindle_out
        return SensorValues(d.time_us, d.encoder_counts, d.encoder_last_edge_us, round(d.battery_adc_v * 1000.0),
                            sp.position_raw, sp.speed_raw, sp.load_raw, sp.answering, sp.limit_switch)

    def _exchange(self, sensors: SensorValues, *, host_frames_sent: int):
        """One lockstep tick of the firmware with these sensor values; its SIL_ACTUATORS."""
        return self._link.exchange(
            time_us=sensors.time_us, encoder_counts=sensors.encoder_counts,
            encoder_last_edge_us=sensors.encoder_last_edge_us, battery_mv=sensors.battery_mv,
            host_frames_sent=host_frames_sent, spindle_position_raw=sensors.spindle_position_raw,
            spindle_speed_raw=sensors.spindle_speed_raw, spindle_load_raw=sensors.spindle_load_raw,
            spindle_answered=sensors.spindle_answered, limit_switch=sensors.limit_switch,
        )

    @property
    def firmware_stderr(self) -> str:
        """What the SIL firmware wrote on stderr, after stop() (its spindle bus counters among it)."""
        return self._firmware.exit_stderr

    def stop(self) -> None:
        self._stop.set()
        if self._thread is not None:
            self._thread.join(timeout=5)
            self._thread = None
        if self._link is not None:
            self._link.close()
            self._link = None
        self._firmware.stop()
        if self._tmpdir is not None:
            self._tmpdir.cleanup()
            self._tmpdir = None

    def __enter__(self) -> SilSession:
        return self.start()

    def __exit__(self, *exc: object) -> None:
        self.stop()

    # ---------------------------------------------------------------------------------------------
    def at(self, time_s: float, action: Callable[[], None]) -> None:
        """Run action() inside the loop at simulated time time_s (before that tick); thread-safe."""
        t_us = round(time_s * 1e6)
        with self._lock:
            heapq.heappush(self._actions, (t_us, next(self._action_counter), action))

    def set_rope_load(self, load_n: float, *, at_s: float | None = None) -> None:
        """Apply an external rope load (N) now, or at simulated time at_s."""
        if not (isinstance(load_n, (int, float)) and load_n >= 0.0 and load_n < float("inf")):
            raise ValueError(f"load_n: expected a finite force >= 0 N, got {load_n!r}")

        def apply() -> None:
            self.loads.external_rope_load_n = float(load_n)
        if at_s is None:
            self.at(self.time_s, apply)
        else:
            self.at(at_s, apply)

    def step(self, *, host_frames_sent: int = 0) -> None:
        """One control tick in lockstep."""
        if self._link is None:
            raise SilError("session not started: use `with SilSession(...) as sil:` or call start()")
        now_us = self.drive_out.time_us
        with self._lock:
            while self._actions and self._actions[0][0] <= now_us:
                _, _, action = heapq.heappop(self._actions)
                action()
        # the scene may have changed the servo between ticks (a fault: silent, stalled): its registers now
        self.spindle_out = self.spindle.outputs()
        sensors: SensorValues | None = self._read_sensors()
        for sensor_filter in self.sensor_filters:
            sensors = sensor_filter(sensors)
            if sensors is None:
                break
        if sensors is not None:
            try:
                out = self._exchange(sensors, host_frames_sent=host_frames_sent)
            except SilError:
                code = self._firmware.poll()
                if code is not None:
                    raise SilFirmwareError(f"SIL firmware exited with code {code}: {self._firmware.stderr_text()}") from None
                raise
            self.last_esc_pulse_us = out.esc_pulse_us
            # the pulse at the PWM timer's resolution (1/3 us), as the board's TCC1 outputs it
            self.last_esc_pulse_fine_us = out.esc_pulse_third_us / 3.0
            self.last_spindle_speed_raw = out.spindle_moving_speed_raw
        plant_pulse_us = self.last_esc_pulse_fine_us
        for actuator_filter in self.actuator_filters:
            plant_pulse_us = actuator_filter(plant_pulse_us)
        loads, dt_s = self.loads, self.tick_us * 1e-6
        exposed_m = (min(max(0.05, self.spindle_out.loop_length_m), self._rope_loop_length_m)
                     if loads.rope_exposed_length_m is None else loads.rope_exposed_length_m)
        self.drive_out = self.drive.update(DriveInputs(
            esc_pulse_us=float(plant_pulse_us), external_rope_load_n=loads.external_rope_load_n,
            rope_exposed_length_m=exposed_m, battery_aux_current_a=loads.battery_aux_current_a), dt_s)
        self.spindle_out = self.spindle.update(SpindleInputs(moving_speed_raw=self.last_spindle_speed_raw,
                                                             guide_load_n=loads.guide_load_n), dt_s)
        for hook in self.tick_hooks:
            hook(self)
        self.ticks += 1
        if self.trace_every and self.ticks % self.trace_every == 0:
            d, sp = self.drive_out, self.spindle_out
            self.trace.append(PlantSample(d.time_us * 1e-6, d.rope_speed_mps, self.last_esc_pulse_us, d.battery_v,
                                          d.external_rope_load_n, d.loop_airborne, sp.guide_position_mm,
                                          sp.loop_length_m, sp.rope_tension_n))
        self._pace()

    def _pace(self) -> None:
        if self.speedup is None:
            return
        now = time.perf_counter()
        now_us = self.drive_out.time_us
        if self._pace_origin is None:
            self._pace_origin = (now, now_us)
            return
        wall0, sim0_us = self._pace_origin
        ahead_s = (now_us - sim0_us) * 1e-6 / self.speedup - (now - wall0)
        if ahead_s > 0.002:
            time.sleep(ahead_s)
        elif ahead_s < -PACE_SLACK_S:
            # Behind: the machine is busy. The simulated clock waits for it instead of racing to catch up: a
            # burst of simulated time would pass while the hosts beside it (their heartbeats) are just as slow.
            self._pace_origin = (now, now_us)

    def run_for(self, duration_s: float, *, host_frames_sent: Callable[[], int] | None = None) -> None:
        """Step for duration_s simulated seconds at the session's pacing."""
        end_us = self.drive_out.time_us + round(duration_s * 1e6)
        while self.drive_out.time_us < end_us:
            self.step(host_frames_sent=host_frames_sent() if host_frames_sent else 0)

    # ---------------------------------------------------------------------------------------------
    def run_in_background(self) -> SilSession:
        """Step in a thread until stop(): for a live host (CLI, Client) on cmd_url."""
        if self._thread is not None:
            raise SilError("already running in the background")
        self._stop.clear()

        def loop() -> None:
            try:
                while not self._stop.is_set():
                    self.step()
            except BaseException as exc:  # reported by check()
                self._error = exc

        self._thread = threading.Thread(target=loop, name="sil-lockstep", daemon=True)
        self._thread.start()
        return self

    def check(self) -> None:
        """Raise the background loop's error, if it stopped on one."""
        if self._error is not None:
            raise self._error

    def wait_until(self, time_s: float, *, timeout_s: float = 60.0) -> None:
        """Block (background mode) until the simulated clock reaches time_s."""
        deadline = time.monotonic() + timeout_s
        while self.time_s < time_s:
            self.check()
            if time.monotonic() > deadline:
                raise SilError(f"simulated time stuck at {self.time_s:.3f} s, waiting for {time_s:.3f} s")
            time.sleep(0.002)
