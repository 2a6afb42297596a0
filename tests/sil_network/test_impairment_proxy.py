"""The ImpairmentProxy on its own, between two plain UDP sockets: validation, statistics, determinism."""

from __future__ import annotations

import hashlib
import socket
import time
from collections.abc import Iterator

import numpy as np
import pytest

from robowrangler_sim.sil.impairment import ImpairmentConfig, ImpairmentProxy, LinkImpairment


class Pair:
    """A 'device' socket behind the proxy and a 'host' socket in front of it."""

    def __init__(self, config: ImpairmentConfig, *, seed: int = 0) -> None:
        self.device = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
        self.device.setsockopt(socket.SOL_SOCKET, socket.SO_RCVBUF, 1 << 20)
        self.device.bind(("127.0.0.1", 0))
        self.device.settimeout(0.5)
        self.proxy = ImpairmentProxy(device_port=self.device.getsockname()[1], config=config, seed=seed,
                                     keep_log=True)
        self.host = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
        self.host.bind(("127.0.0.1", 0))
        self.host.settimeout(0.5)
        self.host.connect(self.proxy.address)

    def drain(self, sock: socket.socket) -> list[bytes]:
        sock.setblocking(False)
        out = []
        try:
            while True:
                out.append(sock.recv(4096))
        except BlockingIOError:
            pass
        sock.settimeout(0.5)
        return out

    def send_to_device(self, payloads: list[bytes], *, now_us: int) -> list[bytes]:
        """Send through the proxy in lockstep at now_us and return what reached the device by then."""
        sent_before = self.proxy.counters["to_device"].received
        for p in payloads:
            self.host.send(p)
        self.proxy.pump(now_us, expect_from_host=sent_before + len(payloads))
        time.sleep(0.001)
        return self.drain(self.device)

    def close(self) -> None:
        self.proxy.close()
        self.device.close()
        self.host.close()


@pytest.fixture
def make_pair() -> Iterator:
    pairs: list[Pair] = []

    def make(config: ImpairmentConfig, *, seed: int = 0) -> Pair:
        pairs.append(Pair(config, seed=seed))
        return pairs[-1]
    yield make
    for p in pairs:
        p.close()


def numbered(n: int, start: int = 0) -> list[bytes]:
    """Distinct datagrams (a 4-byte big-endian index, then 12 bytes of its hash: one bit flip never makes another)."""
    return [i.to_bytes(4, "big") + hashlib.blake2b(i.to_bytes(4, "big")).digest()[:12] for i in range(start, start + n)]


@pytest.mark.parametrize("field", ["loss_prob_good", "loss_prob_bad", "good_to_bad_prob", "bad_to_good_prob",
                                   "duplicate_prob", "corrupt_prob", "reorder_prob"])
@pytest.mark.parametrize("value", [-0.1, 1.5, float("nan"), "0.3", True])
def test_probability_fields_reject_values_outside_0_1_naming_the_field(field: str, value: object) -> None:
    with pytest.raises(ValueError, match=f"^{field}: expected a probability in \\[0, 1\\]"):
        LinkImpairment(**{field: value})


@pytest.mark.parametrize("field", ["delay_ms", "jitter_ms", "reorder_delay_ms"])
@pytest.mark.parametrize("value", [-1.0, float("inf"), 1e9, None])
def test_delay_fields_reject_bad_values_naming_the_field_and_unit(field: str, value: object) -> None:
    with pytest.raises(ValueError, match=f"^{field}: expected a delay in .* ms"):
        LinkImpairment(**{field: value})


def test_config_and_proxy_arguments_are_checked() -> None:
    with pytest.raises(ValueError, match="^bad_to_good_prob: expected > 0"):
        LinkImpairment(good_to_bad_prob=0.1, bad_to_good_prob=0.0)
    with pytest.raises(ValueError, match="^to_host: expected a LinkImpairment"):
        ImpairmentConfig(to_host=0.3)
    with pytest.raises(ValueError, match="^device_port: expected the firmware's bound command port"):
        ImpairmentProxy(device_port=0)
    with pytest.raises(ValueError, match="^seed: expected an int >= 0"):
        ImpairmentProxy(device_port=9, seed=-1)
    with pytest.raises(AttributeError):
        LinkImpairment().delay_ms = 3.0  # frozen


def test_random_loss_rate_matches_the_configured_probability(make_pair) -> None:
    pair = make_pair(ImpairmentConfig(to_device=LinkImpairment(loss_prob_good=0.3)), seed=11)
    got = []
    for k in range(40):
        got += pair.send_to_device(numbered(100, 100 * k), now_us=k)
    c = pair.proxy.counters["to_device"]
    assert c.received == 4000 and c.dropped + c.delivered == 4000 and len(got) == c.delivered
    assert abs(c.dropped / 4000 - 0.3) < 0.025  # 4000 Bernoulli(0.3): sd 0.0072
    assert got == sorted(got)  # no delay, no reorder: order kept


def test_gilbert_elliott_loss_comes_in_bursts_of_the_configured_mean_length(make_pair) -> None:
    link = LinkImpairment(loss_prob_good=0.0, loss_prob_bad=1.0, good_to_bad_prob=0.02, bad_to_good_prob=0.25)
    pair = make_pair(ImpairmentConfig(to_device=link), seed=5)
    sent = numbered(4000)
    got = set()
    for k in range(40):
        got.update(pair.send_to_device(sent[100 * k: 100 * (k + 1)], now_us=k))
    lost = np.array([p not in got for p in sent])
    edges = np.flatnonzero(np.diff(np.concatenate(([0], lost.astype(int), [0]))))
    bursts = edges[1::2] - edges[::2]
    assert abs(lost.mean() - link.mean_loss_prob) < 0.03  # 0.074 in the long run
    assert 3.0 < bursts.mean() < 5.5  # 1 / bad_to_good_prob = 4 datagrams
    # the same mean loss as independent drops would give bursts of about 1.08
    assert pair.proxy.counters["to_device"].bad_state_entries == len(bursts)


def test_delay_jitter_and_reordering_in_simulated_time(make_pair) -> None:
    link = LinkImpairment(delay_ms=5.0, jitter_ms=2.0, reorder_prob=0.2, reorder_delay_ms=10.0)
    pair = make_pair(ImpairmentConfig(to_device=link), seed=2)
    sent = numbered(200)
    assert pair.send_to_device(sent, now_us=0) == []  # all still in flight
    assert pair.send_to_device([], now_us=4_999) == []
    early = pair.send_to_device([], now_us=7_000)  # delay + full jitter: every on-time datagram is out
    late = pair.send_to_device([], now_us=17_000)
    c = pair.proxy.counters["to_device"]
    assert len(early) == 200 - c.reordered and len(late) == c.reordered and 20 < c.reordered < 60
    assert sorted(early + late) == sorted(sent)
    assert early != sorted(early)  # the jitter alone already reorders
    assert pair.proxy.in_flight("to_device") == 0


def test_corruption_flips_exactly_one_bit_and_duplication_sends_two_copies(make_pair) -> None:
    pair = make_pair(ImpairmentConfig(to_device=LinkImpairment(corrupt_prob=0.5, duplicate_prob=0.5)), seed=4)
    sent = numbered(300)
    got = pair.send_to_device(sent, now_us=0)
    c = pair.proxy.counters["to_device"]
    assert len(got) == 300 + c.duplicated and 100 < c.duplicated < 200
    changed = 0
    for entry in (e for e in pair.proxy.take_log() if e.kind == "out"):
        flips = min(sum(bin(a ^ b).count("1") for a, b in zip(entry.data, p)) for p in sent)
        assert flips == (1 if entry.corrupted else 0)
        changed += entry.corrupted
    assert changed == c.corrupted and 150 < changed < 330


def test_same_seed_same_fates_and_more_loss_drops_a_superset(make_pair) -> None:
    def delivered(prob: float, seed: int) -> set[bytes]:
        pair = make_pair(ImpairmentConfig(to_device=LinkImpairment(loss_prob_good=prob)), seed=seed)
        return set(pair.send_to_device(numbered(500), now_us=0))
    assert delivered(0.3, 1) == delivered(0.3, 1)
    assert delivered(0.3, 1) != delivered(0.3, 2)
    assert delivered(0.3, 1) <= delivered(0.2, 1)


def test_wall_clock_mode_forwards_both_ways_with_the_delay(make_pair) -> None:
    link = LinkImpairment(delay_ms=30.0)
    pair = make_pair(ImpairmentConfig(to_device=link, to_host=LinkImpairment(delay_ms=30.0)))
    pair.proxy.start()
    t0 = time.monotonic()
    pair.host.send(b"ping")
    data, proxy_addr = pair.device.recvfrom(100)
    t1 = time.monotonic()
    pair.device.sendto(b"pong", proxy_addr)
    assert pair.host.recv(100) == b"pong"
    t2 = time.monotonic()
    assert data == b"ping" and t1 - t0 >= 0.029 and t2 - t1 >= 0.029
    with pytest.raises(RuntimeError, match="wall-clock thread"):
        pair.proxy.pump(0)
    pair.proxy.config = ImpairmentConfig.symmetric(LinkImpairment.blackout())
    pair.host.send(b"lost")
    with pytest.raises(TimeoutError):
        pair.device.recv(100)
    pair.proxy.check()
    assert pair.proxy.counters["to_device"].dropped == 1
