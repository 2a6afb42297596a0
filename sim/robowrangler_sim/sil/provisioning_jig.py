"""The SIL device's factory provisioning jig: PROVISION_* over its USB serial while the plant clock stands still.

Hosts provision a board with robowrangler's Client over serial:// (`wrangler provision set`), which waits on
the wall clock. A SIL session provisions its device at start instead, between lockstep ticks that do not
advance the plant (``pump``), so that provisioning leaves no trace in the simulated timeline and runs stay
reproducible. Each step is a command answered by ACK or NACK; PROVISION_COMMIT writes the record.
"""

from __future__ import annotations

import time
from collections.abc import Callable, Mapping

from robowrangler.errors import CommandRefused, LinkTimeout
from robowrangler.protocol import generated as gen
from robowrangler.provisioning import staging_messages
from robowrangler.session_epoch import new_session_epoch
from robowrangler.telemetry import ProvisionStatus
from robowrangler.transport import Transport


class Provisioner:
    """Sends PROVISION_* and PARAM_SET over a trusted transport and waits for each answer.

    pump: called while waiting (a SIL stepped in lockstep advances its clock here); None sleeps briefly.
    timeout_s: how long to wait for each answer before LinkTimeout: a bound for a firmware that is not there,
        generous because a busy machine (a test suite on both cores) delays a present one by seconds.
    """

    def __init__(self, transport: Transport, *, url: str = "serial", timeout_s: float = 15.0,
                 pump: Callable[[], None] | None = None) -> None:
        self._transport = transport
        self._url = url
        self._timeout_s = timeout_s
        self._pump = pump
        self._seq = int(time.time() * 1000) & 0xFFFF
        self._pending: list[gen.Message] = []

    def _wait(self, accept: Callable[[gen.Message], bool]) -> gen.Message:
        deadline = time.monotonic() + self._timeout_s
        while time.monotonic() < deadline:
            for i, msg in enumerate(self._pending):
                if accept(msg):
                    return self._pending.pop(i)
            if self._pump is not None:
                self._pump()
                poll_s = 0.0
            else:
                poll_s = 0.02
            data = self._transport.recv(poll_s)
            if data is None:
                continue
            try:
                _, msg = gen.decode_message(data)
            except gen.FrameError:
                continue
            self._pending.append(msg)
        raise LinkTimeout(f"no answer from the device on {self._url} within {self._timeout_s:g} s: is it the right "
                          "port, and is the firmware running?", url=self._url, waited_s=self._timeout_s)

    def command(self, message: gen.Message) -> gen.Ack:
        seq = self._seq
        self._seq = (self._seq + 1) & 0xFFFF
        self._transport.send(gen.encode_frame(message, seq))
        reply = self._wait(lambda m: isinstance(m, (gen.Ack, gen.Nack)) and m.cmd_seq == seq
                           and m.cmd_msg_id == message.MSG_ID)
        if isinstance(reply, gen.Nack):
            raise CommandRefused(command_msg_id=message.MSG_ID, reason=reply.reason, state=reply.state,
                                 detail=reply.detail)
        return reply

    def status(self) -> ProvisionStatus:
        self.command(gen.ProvisionGet())
        return ProvisionStatus.from_wire(self._wait(lambda m: isinstance(m, gen.ProvisionStatus)))

    def provision(self, *, key: bytes | None = None, wifi_ssid: str | None = None, wifi_password: str | None = None,
                  params: Mapping[str, float] | None = None, session_epoch: int | None = None) -> ProvisionStatus:
        """Stage what is given, commit it to flash, and return the stored status.

        session_epoch: the base of the session ids from this commit on (0 <= epoch < 2^31); None draws a fresh
        one from the OS CSPRNG, as a host does at every provisioning.
        """
        for message in staging_messages(key=key, wifi_ssid=wifi_ssid, wifi_password=wifi_password, params=params):
            self.command(message)
        self.command(gen.ProvisionCommit(new_session_epoch() if session_epoch is None else session_epoch))
        return self.status()
