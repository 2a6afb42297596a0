"""A lockstep scripted host whose run is recorded: the simulator's side of the one public recording API.

RecordingHost is a ScriptedHost (commands at simulated times over the real signed UDP link) that hands every
frame it sends and receives to a robowrangler.recorder.RecordingSession, stamped with simulated time, and calls
after_tick() after each lockstep tick. read_params reads every device parameter into the recording's
/device/params as `wrangler record` does, scheduled so that the replies never reorder the device's frames.

    with SilSession(speedup=None, key=key) as sil, RecordingSession(path, source="sil", time_base="simulation",
                                                                    clock_ns=lambda: sil.plant.time_us * 1000) as rec:
        host = RecordingHost(sil, rec)
        read_params(host)
        host.send(gen.SetRopeSpeed(4000)); host.run_for(2.0)
        rec.close(host_s=sil.time_s)

Used by the string-shooter recordings, the burst tests and (later) the diagnosis proof's recordings.
"""

from __future__ import annotations

from collections.abc import Callable

from robowrangler import units
from robowrangler.protocol import generated as gen
from robowrangler.protocol.generated import PARAMS
from robowrangler.recorder import RecordingSession
from robowrangler_sim.sil.scripted_host import ScriptedHost
from robowrangler_sim.sil.session import SilSession

PARAM_REPLY_TIMEOUT_S = 0.1  # simulated time a PARAM_GET may take before the run gives up
PARAM_BURST = 6  # PARAM_GETs (2 ticks each) after each telemetry frame


class RecordingRunError(RuntimeError):
    """The SIL did not answer as a recording run needs (a parameter not read, no telemetry)."""


class RecordingHost(ScriptedHost):
    """A ScriptedHost whose every sent and received frame goes to a RecordingSession (stamped with simulated
    time), and which calls after_tick() (if given) after each lockstep tick."""

    def __init__(self, sil: SilSession, recording: RecordingSession, *,
                 after_tick: Callable[[], None] | None = None, **host_options) -> None:
        self.recording = recording
        self._after_tick = after_tick
        self._fed = 0
        super().__init__(sil, **host_options)

    def send_raw(self, data: bytes) -> None:
        self.recording.tap_sent(data, host_s=self.sil.time_s)
        super().send_raw(data)

    def tick(self) -> None:
        super().tick()
        raw = self.received.raw
        while self._fed < len(raw):
            self.recording.tap_received(raw[self._fed], host_s=self.sil.time_s)
            self._fed += 1
        if self._after_tick is not None:
            self._after_tick()


def read_params(host: RecordingHost) -> dict[str, float]:
    """PARAM_GET every parameter into the recording's /device/params, as `wrangler record` does; returns them.

    The device sends one datagram per tick, an ACK at once and everything else (PARAM_VALUE, events,
    telemetry) from its outbox, numbered when queued: a telemetry frame queued while replies stream out
    would leave its turn after a higher seq (a reordering the recorder writes as a gap). So the reads go
    in short bursts right after each telemetry frame, well inside the 20 ms telemetry period.
    RecordingRunError when the SIL does not answer within PARAM_REPLY_TIMEOUT_S of simulated time."""
    values: dict[str, float] = {}
    specs = list(PARAMS)
    while specs:
        n_tel = len(host.received.telemetry)
        if not host.run_until(lambda h: len(h.received.telemetry) > n_tel, timeout_s=PARAM_REPLY_TIMEOUT_S):
            raise RecordingRunError(f"no TELEMETRY from the SIL firmware within {PARAM_REPLY_TIMEOUT_S} s")
        for spec in specs[:PARAM_BURST]:
            n0 = len(host.received.param_values)
            host.send(gen.ParamGet(spec.id))
            got = host.run_until(lambda h: any(v.param_id == spec.id for v in h.received.param_values[n0:]),
                                 timeout_s=PARAM_REPLY_TIMEOUT_S)
            if not got:
                raise RecordingRunError(f"parameter {spec.name}: no PARAM_VALUE from the SIL firmware within "
                                        f"{PARAM_REPLY_TIMEOUT_S} s of simulated time")
            value = next(v.value for v in host.received.param_values[n0:] if v.param_id == spec.id)
            values[spec.name] = units.float32_to_si(value)
        del specs[:PARAM_BURST]
    host.recording.write_params(values)
    return values
