"""Commands over an impaired, signed link: lost, duplicated, reordered, corrupted and blacked-out datagrams.

The firmware must execute every command at most once: a copy the network made, or a frame a later one
overtook, carries a counter the firmware has already passed and is dropped unanswered as a replay
(rx_replayed); a host retransmission, signed afresh with the same seq and payload, is answered from the
duplicate cache (rx_duplicates). A corrupted frame never acts: the checksum refuses it (NACK), or, if the
flip is in the signature block the checksum does not cover, the tag does (dropped, rx_auth_failed). The
firmware spins the rope down when the host falls silent and takes commands again when the link returns.
The device-side truth comes from the proxy's log (link_ledger): what the firmware really received and sent.
"""

from __future__ import annotations

from pathlib import Path

import pytest
from link_ledger import COMMAND_IDS, LinkLedger

from robowrangler.client import Client
from robowrangler.errors import LinkTimeout
from robowrangler.protocol import generated as gen
from robowrangler.protocol.generated import EventKind, State
from robowrangler_sim.sil import SilSession
from robowrangler_sim.sil.impairment import ImpairmentConfig, ImpairmentProxy, LinkImpairment
from robowrangler_sim.sil.scripted_host import ScriptedHost

CLEAN = ImpairmentConfig()
HEARTBEAT_TIMEOUT_MS = 500
TICK_MS = 1


def command_transitions(ledger: LinkLedger) -> list[tuple[State, State]]:
    return [(State(e.state_from), State(e.state_to)) for e in ledger.device_events(EventKind.STATE_CHANGED)
            if e.arg == gen.Cause.COMMAND]


def test_every_command_completes_exactly_once_through_30_percent_loss(native_build_dir: Path) -> None:
    """The real Client (retries reuse the seq) against the SIL in real time, 30 % loss both ways."""
    link = LinkImpairment(loss_prob_good=0.3)
    with SilSession(speedup=1.0) as sil:
        sil.run_in_background()
        sil.wait_until(0.6)
        with ImpairmentProxy(device_port=sil.cmd_port, config=ImpairmentConfig.symmetric(link), seed=3,
                             keep_log=True).start() as proxy:
            # 13 transmissions per command: all lost with p = (1 - 0.7^2)^13 = 1.6e-4
            with Client(proxy.url, key=sil.key, ack_timeout_s=0.1, retries=12, heartbeat_hz=20.0) as rw:
                assert rw.arm() == State.ARMED
                assert rw.set_param("speed_kp", 0.05) == pytest.approx(0.05)
                rw.spin(4.0)
                rw.wait_for_state(State.AIRBORNE, timeout_s=3.0)
                assert rw.spin(5.0) == State.AIRBORNE
                assert rw.set_param("collapse_time_s", 0.4) == pytest.approx(0.4)
                rw.spindown()
                rw.wait_for_state(State.ARMED, timeout_s=3.0)
                assert rw.disarm() == State.DISARMED
                done_s = rw.latest_telemetry.time_s  # 0.2 s more of device time (not wall time: a loaded machine
                rw.wait_for(lambda s: s.time_s >= done_s + 0.2, timeout_s=30.0)  # slows the SIL): the final counters
                stats = rw.stats
            proxy.check()
            ledger = LinkLedger(key=sil.key)
            ledger.feed(proxy.take_log())
            counters = proxy.counters
    sil.check()
    assert counters["to_device"].dropped > 5 and counters["to_host"].dropped > 10  # the loss was real
    assert stats.retransmissions > 0
    # executed once: the device counted every re-signed repeat it got as a duplicate, and acted once per command
    assert ledger.duplicate_deliveries > 0
    t = ledger.last_device_telemetry
    assert t.rx_duplicates == ledger.duplicate_deliveries
    # every frame the client sent verified; a loss-only link makes no replays (none counted unless the ledger saw one)
    assert t.rx_auth_failed == ledger.auth_failed_deliveries == 0
    assert t.rx_replayed == ledger.replayed_deliveries
    # a PARAM_VALUE lost on the way back makes the client read the value again (PARAM_GET, a new command that
    # changes nothing: Client._param_exchange); every state-changing command ran exactly once, in order
    executed = [m.NAME for _, m in ledger.executed_commands]
    assert [name for name in executed if name != "PARAM_GET"] == [
        "ARM", "PARAM_SET", "SET_ROPE_SPEED", "SET_ROPE_SPEED", "PARAM_SET", "SPINDOWN", "DISARM"]
    assert executed.count("PARAM_GET") <= 2 * 12  # two parameter exchanges, at most `retries` re-reads each
    changed = ledger.device_events(EventKind.PARAM_CHANGED)
    assert [e.arg for e in changed] == [gen.PARAMS_BY_NAME["speed_kp"].id, gen.PARAMS_BY_NAME["collapse_time_s"].id]
    assert command_transitions(ledger) == [(State.DISARMED, State.ARMED), (State.ARMED, State.SPINUP),
                                           (State.AIRBORNE, State.SPINDOWN), (State.ARMED, State.DISARMED)]
    # every frame the firmware got has its one verdict (answered again for each repeat)
    verdicts = [v for v in ledger.device_messages(gen.Ack) + ledger.device_messages(gen.Nack)
                if v.cmd_msg_id in COMMAND_IDS]  # (not the answers to a session handshake, if the client makes one)
    assert len(verdicts) == ledger.command_frames_delivered
    assert ledger.device_seqs_never_sent <= t.tx_dropped  # every hole the device made, it counted (none, usually)


def resend_until_answered(host: ScriptedHost, message: gen.Message, seq: int, *, attempts: int = 30) -> None:
    """Retransmit like the Client: same seq and payload, signed afresh, every 60 ms until a verdict arrives."""
    for _ in range(attempts):
        if host.verdict_for(seq) is not None:
            return
        host.send(message, seq=seq)
        host.run_until(lambda h: h.verdict_for(seq) is not None, timeout_s=0.06)
    assert host.verdict_for(seq) is not None, f"no verdict for {message.NAME} seq {seq} after {attempts} attempts"


def test_network_duplicates_and_overtaken_frames_are_replays_and_never_act(lossy_host) -> None:
    link = LinkImpairment(duplicate_prob=0.5, reorder_prob=0.3, reorder_delay_ms=30.0, delay_ms=1.0, jitter_ms=4.0)
    host: ScriptedHost = lossy_host(ImpairmentConfig.symmetric(link), seed=24)
    proxy = host.sil.proxy
    resend_until_answered(host, gen.Arm(), host.send(gen.Arm()))
    host.run_for(0.05)
    commands: list[tuple[int, gen.Message]] = []
    for mmps in [4000, 4500, 5000, 5500, 6000, 5200, 4800, 6500]:
        message = gen.SetRopeSpeed(mmps)
        commands.append((host.send(message), message))
        host.run_for(0.02)  # closer than the reorder delay: a held-back command is overtaken by the next
    params = [("speed_filter_tau_s", 0.012), ("collapse_time_s", 0.35), ("ramp_up_mps2", 25.0)]
    for name, value in params:
        message = gen.ParamSet(gen.PARAMS_BY_NAME[name].id, value)
        commands.append((host.send(message), message))
        host.run_for(0.02)
    host.run_for(0.5)
    ledger = LinkLedger(key=host.key)
    ledger.feed(proxy.take_log())
    c = proxy.counters["to_device"]
    assert c.duplicated >= 3 and c.reordered >= 2  # the network did mess the order up
    # each copy the network made, and each frame delivered after a newer one, was a replay: none acted
    assert ledger.replayed_deliveries >= c.duplicated and ledger.replayed_commands
    assert not [k for k, n in ledger.command_deliveries.items() if n > 1 and k[0] != gen.MsgId.ARM]  # none twice
    executed_first = [m.pack() for _, m in ledger.executed_commands if not isinstance(m, gen.Arm)]
    assert len(executed_first) < len(commands)  # some were lost to the replay rule (all their copies overtaken)
    assert executed_first == [m.pack() for _, m in commands if m.pack() in executed_first]  # in the host's order

    # the host retransmits what went unanswered, re-signed: each executes once, late repeats hit the cache
    for seq, message in commands:
        resend_until_answered(host, message, seq)
    proxy.config = CLEAN  # nothing in flight, the telemetry catches up with every delivered frame
    host.run_for(0.2)
    ledger.feed(proxy.take_log())
    assert sorted(k[:2] for k in ledger.command_deliveries if k[0] != gen.MsgId.ARM) == \
        sorted((m.MSG_ID, seq) for seq, m in commands)  # every command reached the firmware, once as a first
    executed = [m for _, m in ledger.executed_commands]
    assert len(executed) == len(commands) + 1  # + ARM: no command executed twice
    executed_speeds = [m.rope_speed_mmps for m in executed if isinstance(m, gen.SetRopeSpeed)]
    t = ledger.last_device_telemetry
    assert t.rx_duplicates == ledger.duplicate_deliveries > 0  # re-signed repeats of executed commands: the cache
    assert t.rx_replayed == ledger.replayed_deliveries and t.rx_auth_failed == ledger.auth_failed_deliveries == 0
    assert t.rope_speed_target_mmps == executed_speeds[-1]  # the last one executed wins, no replay after it
    assert host.received.telemetry[-1].rope_speed_target_mmps == executed_speeds[-1]
    changed = ledger.device_events(EventKind.PARAM_CHANGED)
    assert sorted(e.arg for e in changed) == sorted(gen.PARAMS_BY_NAME[n].id for n, _ in params)


def test_corrupted_frames_are_refused_and_never_act(lossy_host) -> None:
    host: ScriptedHost = lossy_host(CLEAN, seed=8)
    proxy = host.sil.proxy
    host.arm_and_spin(5000, settle_s=1.0)
    ledger = LinkLedger(key=host.key)
    ledger.feed(proxy.take_log())
    before = ledger.last_device_telemetry
    nacks_before = len(host.received.nacks)
    proxy.config = ImpairmentConfig(to_device=LinkImpairment(corrupt_prob=1.0),
                                    to_host=LinkImpairment(corrupt_prob=0.2))
    for message in (gen.SetRopeSpeed(8000), gen.Spindown(), gen.Estop(), gen.SetRopeSpeed(3500),
                    gen.ParamSet(gen.PARAMS_BY_NAME["tov_mps"].id, 3.0)) * 4:
        host.send(message)
        host.run_for(0.01)
    proxy.config = CLEAN
    host.run_for(0.3)
    ledger.feed(proxy.take_log())
    t = ledger.last_device_telemetry
    corrupted = proxy.counters["to_device"].corrupted
    assert corrupted >= 20 and ledger.corrupted_to_device + ledger.corrupted_unauthentic_to_device == corrupted
    # a flip the checksum sees is refused as a bad frame; one in the signature block (not under the checksum)
    # decodes, and the tag refuses it: dropped unanswered and counted as an authentication failure
    assert ledger.corrupted_to_device > 0 and ledger.corrupted_unauthentic_to_device > 0
    assert t.rx_bad - before.rx_bad == ledger.corrupted_to_device
    assert t.rx_auth_failed - before.rx_auth_failed == ledger.corrupted_unauthentic_to_device
    assert t.rx_replayed == before.rx_replayed == ledger.replayed_deliveries == 0
    assert t.state == State.AIRBORNE and t.rope_speed_target_mmps == 5000  # none of them acted
    assert not ledger.device_events(EventKind.PARAM_CHANGED)
    assert abs(host.sil.plant.rope_speed_mps - 5.0) < 0.1
    nack_reasons = {gen.NackReason(n.reason) for n in ledger.device_messages(gen.Nack)}
    assert gen.NackReason.BAD_CHECKSUM in nack_reasons
    assert nack_reasons <= {gen.NackReason.BAD_CHECKSUM, gen.NackReason.BAD_MAGIC, gen.NackReason.BAD_VERSION,
                            gen.NackReason.UNSUPPORTED_FLAGS, gen.NackReason.UNKNOWN_MESSAGE,
                            gen.NackReason.TRUNCATED, gen.NackReason.BAD_LENGTH, gen.NackReason.OVERSIZE}
    # the host saw the NACKs that were not lost, and rejected every corrupted frame sent its way: by the
    # checksum, or (a flip in the signature block) by the tag
    assert len(host.received.nacks) > nacks_before
    assert ledger.corrupted_to_host > 0
    assert host.received.auth_failed == ledger.corrupted_unauthentic_to_host
    assert host.received.decode_errors == ledger.corrupted_to_host - ledger.corrupted_unauthentic_to_host


def test_total_loss_spins_down_within_the_heartbeat_timeout_in_lockstep(lossy_host) -> None:
    host: ScriptedHost = lossy_host(CLEAN, seed=1)
    proxy = host.sil.proxy
    host.arm_and_spin(6000, settle_s=1.0)
    ledger = LinkLedger(key=host.key)
    ledger.feed(proxy.take_log())
    proxy.config = ImpairmentConfig.symmetric(LinkImpairment.blackout())
    host.run_for(2.0)
    entries = proxy.take_log()
    ledger.feed(entries)
    last_delivered_ms = max(e.time_us for e in entries if e.direction == "to_device" and e.kind == "out") // 1000 \
        if any(e.direction == "to_device" and e.kind == "out" for e in entries) else None
    lost = ledger.device_events(EventKind.HEARTBEAT_LOST)
    spindown = [e for e in ledger.device_events(EventKind.STATE_CHANGED) if e.state_to == State.SPINDOWN]
    assert len(lost) == 1 and len(spindown) == 1 and spindown[0].arg == gen.Cause.HEARTBEAT_LOST
    assert spindown[0].time_ms == lost[0].time_ms
    assert HEARTBEAT_TIMEOUT_MS < lost[0].arg <= HEARTBEAT_TIMEOUT_MS + TICK_MS
    if last_delivered_ms is not None:
        assert lost[0].time_ms - last_delivered_ms <= HEARTBEAT_TIMEOUT_MS + TICK_MS
    assert ledger.last_device_telemetry.state == State.ARMED and host.sil.plant.rope_speed_mps < 0.2
    assert len(host.received.events) < len(ledger.device_frames)  # the host heard none of it
    # the link returns: the same host spins up again
    proxy.config = CLEAN
    host.run_for(0.2)
    host.arm_and_spin(4000, settle_s=1.0)
    assert host.last_telemetry.state == State.AIRBORNE and abs(host.sil.plant.rope_speed_mps - 4.0) < 0.1


def test_client_rides_out_a_blackout_and_flies_again(native_build_dir: Path) -> None:
    """Real time, the real Client: commands time out during a total loss, the rope lands, then all works again."""
    with SilSession(speedup=1.0) as sil:
        sil.run_in_background()
        sil.wait_until(0.6)
        with ImpairmentProxy(device_port=sil.cmd_port, seed=5, keep_log=True).start() as proxy:
            with Client(proxy.url, key=sil.key, ack_timeout_s=0.1, retries=2, connect_timeout_s=3.0) as rw:
                rw.arm()
                rw.spin(5.0)
                rw.wait_for_state(State.AIRBORNE, timeout_s=3.0)
                proxy.config = ImpairmentConfig.symmetric(LinkImpairment.blackout())
                blackout_s = sil.time_s
                with pytest.raises(LinkTimeout):
                    rw.spin(6.0)
                sil.wait_until(blackout_s + 0.8)  # > heartbeat_timeout_s of silence, on the device's clock
                proxy.config = CLEAN
                landed = rw.wait_for_state(State.ARMED, timeout_s=3.0)
                assert landed.rope_speed_mps < 0.2
                assert rw.arm() == State.ARMED
                rw.spin(4.0)
                flying = rw.wait_for_state(State.AIRBORNE, timeout_s=3.0)
                assert flying.rope_speed_target_mps == pytest.approx(4.0)
                rw.spindown()
                rw.wait_for_state(State.ARMED, timeout_s=3.0)
            ledger = LinkLedger(key=sil.key)
            ledger.feed(proxy.take_log())
    sil.check()
    lost = ledger.device_events(EventKind.HEARTBEAT_LOST)
    assert len(lost) == 1 and HEARTBEAT_TIMEOUT_MS < lost[0].arg <= HEARTBEAT_TIMEOUT_MS + TICK_MS
    causes = [gen.Cause(e.arg) for e in ledger.device_events(EventKind.STATE_CHANGED) if e.state_to == State.SPINDOWN]
    assert causes == [gen.Cause.HEARTBEAT_LOST, gen.Cause.COMMAND]
    # the 6 m/s command sent into the blackout never reached the device
    assert all(not (isinstance(m, gen.SetRopeSpeed) and m.rope_speed_mmps == 6000) for _, m in ledger.executed_commands)


def test_a_late_network_copy_behind_16_newer_commands_is_a_replay(plain_host: ScriptedHost) -> None:
    """The duplicate cache holds 16 commands, but a network copy needs none of it on the signed link: its
    counter is long passed, so it is dropped as a replay however late it comes."""
    host = plain_host
    host.arm_and_spin(5000, settle_s=1.0)
    late = host.frame(gen.SetRopeSpeed(7000), 40_000)
    host.send_raw(late)
    host.run_for(0.03)
    assert host.last_telemetry.rope_speed_target_mmps == 7000
    for _ in range(30):
        assert isinstance(host.command(gen.ParamGet(gen.PARAMS_BY_NAME["tov_mps"].id)), gen.Ack)
    assert isinstance(host.command(gen.SetRopeSpeed(6000)), gen.Ack)  # the 31st newer command
    before = host.last_telemetry
    answered = len(host.received.acks) + len(host.received.nacks)
    host.send_raw(late)  # the network's late copy, 0.3 s after the original: the same bytes
    host.run_for(0.1)
    t = host.last_telemetry
    assert t.rope_speed_target_mmps == 6000
    assert t.rx_replayed == before.rx_replayed + 1 and t.rx_duplicates == before.rx_duplicates
    assert len(host.received.acks) + len(host.received.nacks) == answered  # dropped unanswered


# The device remembers the last RW_DUPLICATE_CACHE_SIZE (32) commands for RW_DUPLICATE_WINDOW_MS (5 s): a
# host retransmission (re-signed: fresh counter, same seq and payload) behind 31 newer commands is still
# answered from the cache. Only a host with more than 31 commands in flight could get past it; network copies
# are replays and never reach the cache.
def test_a_retransmission_behind_31_newer_commands_is_not_executed_again(plain_host: ScriptedHost) -> None:
    host = plain_host
    host.arm_and_spin(5000, settle_s=1.0)
    host.send(gen.SetRopeSpeed(7000), seq=40_000)
    host.run_for(0.01)
    for _ in range(30):
        assert isinstance(host.command(gen.ParamGet(gen.PARAMS_BY_NAME["tov_mps"].id)), gen.Ack)
    assert isinstance(host.command(gen.SetRopeSpeed(6000)), gen.Ack)  # the 31st newer command
    before = host.last_telemetry.rx_duplicates
    host.send(gen.SetRopeSpeed(7000), seq=40_000)  # retransmitted after the original, signed afresh
    host.run_for(0.1)
    t = host.last_telemetry
    assert t.rope_speed_target_mmps == 6000 and t.rx_duplicates == before + 1
