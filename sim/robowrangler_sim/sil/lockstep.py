"""Plant side of the lockstep socket: one SIL_SENSORS out, one SIL_ACTUATORS back, per control tick.

A busy machine may leave the firmware process unscheduled for seconds; that is not a failure. The plant waits
for the answer in slices of tick_timeout_s and, after each slice, asks whether the firmware is still alive:
a firmware that exited is reported at once (SilFirmwareError from the session), a live one is waited for until
it has been silent for stall_limit_s (then SilTimeout: alive but hung). The SIL_SENSORS is never sent twice
(the firmware would run a second tick at the same time).
"""

from __future__ import annotations

import socket

from robowrangler.protocol import generated as gen
from collections.abc import Callable

from robowrangler_sim.sil.errors import SilTimeout

_U32 = 0xFFFFFFFF


class LockstepLink:
    """UDP socket from the plant to the SIL firmware's plant port on 127.0.0.1.

    Args:
        plant_port: the firmware's plant port.
        tick_timeout_s: how long one wait for an answer lasts before the firmware's liveness is checked [s].
        alive: returns False once the firmware process has exited (None: always assumed alive).
        stall_limit_s: a live firmware silent this long is hung: SilTimeout [s].
    """

    def __init__(self, plant_port: int, *, tick_timeout_s: float = 2.0, alive: Callable[[], bool] | None = None,
                 stall_limit_s: float = 120.0) -> None:
        if not tick_timeout_s > 0 or not stall_limit_s >= tick_timeout_s:
            raise ValueError(f"tick_timeout_s, stall_limit_s: expected 0 < tick_timeout_s <= stall_limit_s, got "
                             f"{tick_timeout_s!r}, {stall_limit_s!r}")
        self._sock = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
        self._sock.bind(("127.0.0.1", 0))
        self._sock.connect(("127.0.0.1", plant_port))
        self._sock.settimeout(tick_timeout_s)
        self._tick_timeout_s = tick_timeout_s
        self._alive = alive
        self._stall_limit_s = stall_limit_s
        self._seq = 0
        self.bad_replies = 0
        self.slow_ticks = 0  # ticks whose answer took longer than tick_timeout_s (a busy machine), waited out

    def exchange(self, *, time_us: int, encoder_counts: int, encoder_last_edge_us: int, battery_mv: int,
                 host_frames_sent: int, spindle_position_raw: int = 0, spindle_speed_raw: int = 0,
                 spindle_load_raw: int = 0, spindle_answered: bool = False,
                 limit_switch: bool = False) -> gen.SilActuators:
        """Send this tick's sensors; return the firmware's outputs for it. Raises SilTimeout if the firmware has
        exited, or is alive but silent for stall_limit_s.

        Spindle registers are the AX-12A's raw register values (see the SIL_SENSORS message)."""
        msg = gen.SilSensors(time_us & _U32, encoder_counts & _U32, encoder_last_edge_us & _U32,
                             max(0, min(int(battery_mv), 0xFFFF)), host_frames_sent & _U32,
                             spindle_position_raw, spindle_speed_raw, spindle_load_raw, int(spindle_answered),
                             int(limit_switch))
        self._sock.send(gen.encode_frame(msg, self._seq))
        self._seq = (self._seq + 1) & 0xFFFF
        waited_s = 0.0
        while True:
            try:
                data = self._sock.recv(256)
            except (TimeoutError, socket.timeout) as exc:
                waited_s += self._tick_timeout_s
                if self._alive is not None and not self._alive():
                    raise SilTimeout(f"SIL firmware exited before answering the tick at t={time_us} us") from exc
                if waited_s >= self._stall_limit_s:
                    raise SilTimeout(f"SIL firmware is running but has not answered the tick at t={time_us} us for "
                                     f"{waited_s:g} s: it is hung (or the machine is stopped)") from exc
                if waited_s <= self._tick_timeout_s:
                    self.slow_ticks += 1
                continue  # a busy machine: the firmware is alive and will answer
            except ConnectionRefusedError as exc:
                raise SilTimeout("SIL firmware is gone (connection refused on its plant port)") from exc
            try:
                _, reply = gen.decode_message(data)
            except gen.FrameError:
                self.bad_replies += 1
                continue
            if isinstance(reply, gen.SilActuators) and reply.time_us == msg.time_us:
                return reply
            self.bad_replies += 1

    def close(self) -> None:
        self._sock.close()
