"""Plant side of the lockstep socket: one SIL_SENSORS out, one SIL_ACTUATORS back, per control tick."""

from __future__ import annotations

import socket

from robowrangler.protocol import generated as gen
from robowrangler_sim.sil.errors import SilTimeout

_U32 = 0xFFFFFFFF


class LockstepLink:
    """UDP socket from the plant to the SIL firmware's plant port on 127.0.0.1."""

    def __init__(self, plant_port: int, *, tick_timeout_s: float = 2.0) -> None:
        self._sock = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
        self._sock.bind(("127.0.0.1", 0))
        self._sock.connect(("127.0.0.1", plant_port))
        self._sock.settimeout(tick_timeout_s)
        self._seq = 0
        self.bad_replies = 0

    def exchange(self, *, time_us: int, encoder_counts: int, encoder_last_edge_us: int, battery_mv: int,
                 host_frames_sent: int, spindle_position_raw: int = 0, spindle_speed_raw: int = 0,
                 spindle_load_raw: int = 0, spindle_answered: bool = False,
                 limit_switch: bool = False) -> gen.SilActuators:
        """Send this tick's sensors; return the firmware's outputs for it. Raises SilTimeout if it does not answer.

        Spindle registers are the AX-12A's raw register values (see the SIL_SENSORS message)."""
        msg = gen.SilSensors(time_us & _U32, encoder_counts & _U32, encoder_last_edge_us & _U32,
                             max(0, min(int(battery_mv), 0xFFFF)), host_frames_sent & _U32,
                             spindle_position_raw, spindle_speed_raw, spindle_load_raw, int(spindle_answered),
                             int(limit_switch))
        self._sock.send(gen.encode_frame(msg, self._seq))
        self._seq = (self._seq + 1) & 0xFFFF
        while True:
            try:
                data = self._sock.recv(256)
            except (TimeoutError, socket.timeout) as exc:
                raise SilTimeout(f"SIL firmware did not answer the tick at t={time_us} us") from exc
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
