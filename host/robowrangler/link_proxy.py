"""LinkProxy: one owner of the device link that serves local tools, as MAVProxy does for MAVLink.

The device sends its telemetry to the host that sent the last valid frame, so two hosts on one device
each see part of the stream (a recorder beside a commanding tool recorded 18 Hz of 50 and none of the
other tool's commands). With a proxy the device hears one host only. The proxy connects with its own
Client (whose transport may record everything: `wrangler proxy --record FILE`), and local tools connect
to the proxy's loopback UDP port exactly as they would to the device (`--url udp://127.0.0.1:14551`):

- every TELEMETRY and EVENT the device sends (and the Client accepted: signed frames must verify) goes
  to every local tool heard within TOOL_FORGET_S, with the device's own frame seq;
- a tool's command is carried by the proxy's Client (its seq, session, counter and retries) and the
  device's ACK/NACK goes back to that tool under the tool's seq; PARAM_GET/PARAM_SET are answered with
  the ACK, then a PARAM_VALUE read back from the device. A retransmission of a command still in progress
  is not carried twice; one already answered gets the same answer again (as the device's own cache does);
- HELLO is answered with SESSION_INFO for the proxy's session. With a key every frame to a tool is signed
  and every frame from a tool must verify (tag, session, a counter above the tool's last), as on the
  device; without one the local link is unsigned. The port is bound to loopback only;
- tools' HEARTBEATs are not forwarded. The proxy heartbeats the device only while a tool was heard within
  tool_timeout_s, so the device's live-host rule still follows the tools: a rope spun (or a guide moved)
  by a tool that exits or dies stops heartbeat_timeout_s later, through the proxy as without it.
"""

from __future__ import annotations

import collections
import secrets
import socket
import threading
import time
from collections.abc import Callable
from dataclasses import dataclass, field

from robowrangler.client import Client
from robowrangler.errors import InvalidArgument
from robowrangler.protocol import generated as gen
from robowrangler.protocol.generated import MsgId, NackReason, PARAMS, State
from robowrangler.transport import Transport

DEFAULT_PROXY_PORT = 14551
TOOL_TIMEOUT_S = 0.3  # a tool silent this long no longer counts as a live host (tools heartbeat at 10 Hz)
TOOL_FORGET_S = 5.0  # a tool silent this long gets no more telemetry
ANSWER_CACHE_LEN = 512  # answered commands remembered per proxy (tool, message id, seq)
LOOPBACK = ("127.0.0.1", "::1", "localhost")
_FANNED_OUT = (MsgId.TELEMETRY, MsgId.EVENT)
_PROVISIONING = (MsgId.PROVISION_SET_KEY, MsgId.PROVISION_SET_WIFI_SSID, MsgId.PROVISION_SET_WIFI_PASSWORD,
                 MsgId.PROVISION_COMMIT, MsgId.PROVISION_GET)


@dataclass
class ProxyStats:
    """Counters of one proxy run: frames passed to tools, commands carried, frames refused from tools."""

    tools_seen: int = 0
    frames_to_tools: int = 0
    commands_carried: int = 0
    retransmissions_answered: int = 0
    rejected_from_tools: int = 0
    device_frames_refused: int = 0  # signed device frames that did not verify or were not fresh
    by_tool: dict[str, int] = field(default_factory=dict)  # commands carried per tool address


@dataclass
class _Tool:
    address: tuple
    last_heard_s: float
    last_counter: int = -1


class TeeTransport(Transport):
    """A Transport that hands every received frame to on_received after passing it on (the proxy's tap)."""

    def __init__(self, inner: Transport, on_received: Callable[[bytes], None]) -> None:
        self.inner = inner
        self.on_received = on_received
        self.url = inner.url

    @property
    def framing_errors(self) -> int:  # type: ignore[override]
        return self.inner.framing_errors

    def send(self, frame: bytes) -> None:
        self.inner.send(frame)

    def recv(self, timeout_s: float) -> bytes | None:
        data = self.inner.recv(timeout_s)
        if data is not None:
            self.on_received(data)
        return data

    def close(self) -> None:
        self.inner.close()


class LinkProxy:
    """Serve local tools on listen_host:listen_port through `upstream`, a Client the caller connects.

    Build the Client with transport=TeeTransport(transport, proxy.from_device) so the proxy sees the
    device's frames, then call start(); close() stops serving (it does not close the Client).

    Args:
        key: the link key (the same as the Client's) for the local side, None for an unsigned local link.
        listen_host: a loopback address (the local side never leaves the machine).
        listen_port: UDP port for the tools (0 picks a free one: see `port`).
        tool_timeout_s: a tool heard within this counts as a live host (the proxy heartbeats the device).
    """

    def __init__(self, *, key: bytes | None, listen_host: str = "127.0.0.1", listen_port: int = DEFAULT_PROXY_PORT,
                 tool_timeout_s: float = TOOL_TIMEOUT_S) -> None:
        if listen_host not in LOOPBACK:
            raise InvalidArgument("listen_host", f"a loopback address {LOOPBACK} (the proxy serves this machine only)",
                                  listen_host)
        if isinstance(listen_port, bool) or not isinstance(listen_port, int) or not 0 <= listen_port <= 65535:
            raise InvalidArgument("listen_port", "a UDP port 0..65535", listen_port)
        self.key = key
        self.tool_timeout_s = tool_timeout_s
        self.session_id = secrets.randbelow(2**31) + 1 if key is not None else 0
        family = socket.AF_INET6 if ":" in listen_host else socket.AF_INET
        self._sock = socket.socket(family, socket.SOCK_DGRAM)
        try:
            self._sock.bind((listen_host, listen_port))
        except OSError as err:
            self._sock.close()
            raise InvalidArgument("--listen", "a free local UDP port", f"{listen_port} ({err.strerror})") from None
        self.port = self._sock.getsockname()[1]
        self.stats = ProxyStats()
        self.on_param: Callable[[str, float], None] | None = None  # a parameter a tool read or set (device's value)
        self._upstream: Client | None = None
        self._tools: dict[tuple, _Tool] = {}
        self._answers: collections.OrderedDict[tuple, list[bytes] | None] = collections.OrderedDict()
        self._lock = threading.Lock()
        self._send_lock = threading.Lock()
        self._seq = secrets.randbelow(0x10000)
        self._counter = 0
        self._device_session = -1
        self._device_counter = -1
        self._stop = threading.Event()
        self._thread: threading.Thread | None = None

    # ------------------------------------------------------------------------------------------ lifecycle
    def start(self, upstream: Client) -> LinkProxy:
        """Serve tools through the connected upstream Client; its heartbeats now follow the tools."""
        self._upstream = upstream
        upstream.pause_heartbeats_while(lambda: not self.tools_alive())
        self._thread = threading.Thread(target=self._serve, name="robowrangler-proxy", daemon=True)
        self._thread.start()
        return self

    def close(self) -> None:
        self._stop.set()
        if self._thread is not None:
            self._thread.join(timeout=2.0)
        if self._upstream is not None:
            self._upstream.pause_heartbeats_while(None)
        self._sock.close()

    def __enter__(self) -> LinkProxy:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    def tools_alive(self, now_s: float | None = None) -> int:
        """How many tools were heard within tool_timeout_s (live hosts)."""
        now_s = time.monotonic() if now_s is None else now_s
        with self._lock:
            return sum(1 for t in self._tools.values() if now_s - t.last_heard_s <= self.tool_timeout_s)

    # ------------------------------------------------------------------------------------ device -> tools
    def from_device(self, data: bytes) -> None:
        """A frame the upstream transport received: TELEMETRY and EVENT go to every tool (if authentic)."""
        try:
            frame, msg = gen.decode_message(data)
        except Exception:  # noqa: BLE001 - the Client counts bad frames; nothing to pass on
            return
        if frame.msg_id not in _FANNED_OUT or not self._authentic(frame):
            return
        now_s = time.monotonic()
        with self._lock:
            tools = [t.address for t in self._tools.values() if now_s - t.last_heard_s <= TOOL_FORGET_S]
        for address in tools:
            self._send_to(address, msg, seq=frame.seq)

    def _authentic(self, frame: gen.Frame) -> bool:
        """With a key: a device frame counts only if its tag verifies and it is newer than the last one."""
        if self.key is None:
            return True
        if not frame.signed or not gen.tag_valid(frame, self.key):
            self.stats.device_frames_refused += 1
            return False
        with self._lock:
            if (frame.session_id, frame.counter) <= (self._device_session, self._device_counter):
                self.stats.device_frames_refused += 1
                return False
            self._device_session, self._device_counter = frame.session_id, frame.counter
        return True

    def _send_to(self, address: tuple, message: gen.Message, *, seq: int | None = None) -> None:
        with self._send_lock:
            if seq is None:
                seq, self._seq = self._seq, (self._seq + 1) & 0xFFFF
            if self.key is None:
                data = gen.encode_frame(message, seq)
            else:
                self._counter = max(self._counter + 1, time.time_ns() // 1000)
                data = gen.encode_frame(message, seq, key=self.key, session_id=self.session_id, counter=self._counter)
            try:
                self._sock.sendto(data, address)
            except OSError:
                return
        self.stats.frames_to_tools += 1

    # ------------------------------------------------------------------------------------ tools -> device
    def _serve(self) -> None:
        self._sock.settimeout(0.1)
        while not self._stop.is_set():
            try:
                data, address = self._sock.recvfrom(2048)
            except TimeoutError:
                continue
            except OSError:
                if self._stop.is_set():
                    return
                continue
            try:
                self._from_tool(data, address)
            except Exception:  # noqa: BLE001 - one bad datagram must not end the proxy; counted
                self.stats.rejected_from_tools += 1

    def _from_tool(self, data: bytes, address: tuple) -> None:
        try:
            frame, msg = gen.decode_message(data)
        except Exception:  # noqa: BLE001 - unreadable: dropped and counted (the tool retransmits)
            self.stats.rejected_from_tools += 1
            return
        now_s = time.monotonic()
        if frame.msg_id == MsgId.HELLO:
            self._hear(address, now_s, counter=None)
            self._send_to(address, gen.SessionInfo(msg.host_nonce, self.session_id, int(self.key is not None),
                                                   gen.SCHEMA_HASH))
            return
        if self.key is not None and not self._tool_frame_valid(frame, address):
            self.stats.rejected_from_tools += 1
            return
        self._hear(address, now_s, counter=frame.counter if self.key is not None else None)
        if frame.msg_id == MsgId.HEARTBEAT:
            return
        if gen.MESSAGES[frame.msg_id].KIND != gen.MsgKind.COMMAND:
            self._send_to(address, gen.Nack(frame.msg_id, frame.seq, NackReason.NOT_A_COMMAND, self._state(), 0))
            return
        key = (address, frame.msg_id, frame.seq)
        with self._lock:
            if key in self._answers:  # a retransmission: answer again (or wait for the carried one)
                answer = self._answers[key]
                self.stats.retransmissions_answered += 1
            else:
                answer = None
                self._answers[key] = None
                while len(self._answers) > ANSWER_CACHE_LEN:
                    self._answers.popitem(last=False)
                self.stats.commands_carried += 1
                name = f"{address[0]}:{address[1]}"
                self.stats.by_tool[name] = self.stats.by_tool.get(name, 0) + 1
                threading.Thread(target=self._carry, args=(key, msg), daemon=True).start()
                return
        for reply in answer or []:
            self._send_to(address, reply)

    def _tool_frame_valid(self, frame: gen.Frame, address: tuple) -> bool:
        if not frame.signed or frame.session_id != self.session_id or not gen.tag_valid(frame, self.key):
            return False
        with self._lock:
            tool = self._tools.get(address)
            return tool is None or frame.counter > tool.last_counter

    def _hear(self, address: tuple, now_s: float, *, counter: int | None) -> None:
        with self._lock:
            tool = self._tools.get(address)
            if tool is None:
                tool = self._tools[address] = _Tool(address, now_s)
                self.stats.tools_seen += 1
            tool.last_heard_s = now_s
            if counter is not None:
                tool.last_counter = counter

    def _carry(self, key: tuple, msg: gen.Message) -> None:
        """Carry one tool command to the device and the answer back (in its own thread: commands wait)."""
        address, msg_id, seq = key
        replies: list[gen.Message] = []
        upstream = self._upstream
        if msg_id in _PROVISIONING:
            replies = [gen.Nack(msg_id, seq, NackReason.NOT_ON_THIS_LINK, self._state(), 0)]
        elif upstream is None:
            return
        else:
            try:
                answer = upstream.request(msg)
                replies = [_for_tool(answer, msg_id, seq)]
                if isinstance(answer, gen.Ack) and msg_id in (MsgId.PARAM_GET, MsgId.PARAM_SET):
                    value = upstream.get_param(PARAMS[msg.param_id].name)
                    replies.append(gen.ParamValue(msg.param_id, value, len(PARAMS)))
                    if self.on_param is not None:
                        self.on_param(PARAMS[msg.param_id].name, value)
            except Exception:  # noqa: BLE001 - LinkTimeout, a closing link: the tool times out and retries
                with self._lock:  # no answer: the tool times out; a retransmission tries again
                    self._answers.pop(key, None)
                return
        with self._lock:
            if key in self._answers:
                self._answers[key] = replies
        for reply in replies:
            self._send_to(address, reply)

    def _state(self) -> int:
        sample = self._upstream.latest_telemetry if self._upstream is not None else None
        return int(sample.state) if sample is not None else int(State.DISARMED)


def _for_tool(answer: gen.Ack | gen.Nack, msg_id: int, seq: int) -> gen.Message:
    """The device's answer under the tool's seq."""
    if isinstance(answer, gen.Ack):
        return gen.Ack(msg_id, seq, answer.state)
    return gen.Nack(msg_id, seq, answer.reason, answer.state, answer.detail)
