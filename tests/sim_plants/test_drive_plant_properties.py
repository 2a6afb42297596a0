"""Drive plant invariants under arbitrary (valid) input sequences, found with hypothesis."""

from __future__ import annotations

import math

from hypothesis import given, settings
from hypothesis import strategies as st

from robowrangler_sim.plants import DriveParams, DrivePlant

PARAMS = DriveParams()

pulses = st.one_of(st.sampled_from([0.0, 989.0, 1000.0, 1005.0, 1010.0, 2000.0, 2500.0]),
                   st.floats(min_value=0.0, max_value=2500.0))
segments = st.lists(
    st.tuples(pulses,
              st.integers(min_value=1, max_value=5000),  # dt_us
              st.integers(min_value=1, max_value=60),    # steps
              st.floats(min_value=0.0, max_value=5.0)),  # external load, N
    min_size=1, max_size=12)


@settings(max_examples=40, deadline=None)
@given(segments=segments, seed=st.integers(min_value=0, max_value=2**32 - 1))
def test_outputs_stay_physical_for_any_input_sequence(segments, seed):
    plant = DrivePlant(seed=seed)
    plant.step_us(esc_pulse_us=1000.0, dt_us=5000)
    for _ in range(50):  # arm it so the sequences actually drive the motor
        plant.step_us(esc_pulse_us=1000.0, dt_us=5000)
    assert plant.esc_armed
    t_expected = plant.time_us
    prev_counts, prev_edge = plant.encoder_counts, plant.encoder_last_edge_us
    for pulse, dt_us, steps, load in segments:
        plant.external_rope_load_n = load
        for _ in range(steps):
            plant.step_us(esc_pulse_us=pulse, dt_us=dt_us)
            t_expected += dt_us
            snap = plant.snapshot()
            assert plant.time_us == t_expected
            assert all(math.isfinite(v) for v in snap.values())
            assert plant.rope_speed_mps >= 0.0  # the ESC cannot reverse the motor
            assert abs(plant.motor_current_a) <= PARAMS.esc_current_limit_a + 1e-9
            assert 0.0 < plant.battery_v < 20.0
            if not plant.esc_armed:
                assert plant.motor_current_a == 0.0
            assert plant.encoder_counts >= prev_counts
            assert prev_edge <= plant.encoder_last_edge_us <= plant.time_us
            revs = plant.shaft_angle_rad / (2.0 * math.pi)
            assert abs(plant.encoder_counts - revs * PARAMS.encoder_counts_per_rev) < 1.0
            prev_counts, prev_edge = plant.encoder_counts, plant.encoder_last_edge_us
