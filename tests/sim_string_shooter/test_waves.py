"""Waves on the moving rope travel at v - c and v + c, c = sqrt(T / lambda)."""

import pytest

from robowrangler_sim.string_shooter.waves import measure_wave_speeds


@pytest.mark.parametrize("rope_speed_mps, wave_speed_mps", [(4.0, 2.0), (1.0, 2.0), (3.0, 3.0)])
def test_pluck_splits_into_pulses_at_v_minus_c_and_v_plus_c(rope_speed_mps, wave_speed_mps):
    res = measure_wave_speeds(rope_speed_mps=rope_speed_mps, wave_speed_mps=wave_speed_mps, span_m=2.0,
                              segment_length_m=0.0125)
    assert res.wave_speed_mps == pytest.approx(wave_speed_mps, rel=0.02)  # tension as set up
    assert res.relative_error.max() < 0.03, (res.measured_mps, res.predicted_mps)


def test_at_tension_lambda_v_squared_one_wave_stands_still():
    res = measure_wave_speeds(rope_speed_mps=3.0, wave_speed_mps=3.0, span_m=2.0, segment_length_m=0.0125)
    assert abs(res.measured_mps[0]) < 0.1
    assert res.measured_mps[1] == pytest.approx(6.0, rel=0.03)


def test_pluck_on_the_flying_loop_travels_at_v_plus_minus_local_c():
    """On the returning branch of a 2 m loop at 5 m/s: the fast pulse runs to the eyelet at v + c, the slow
    one creeps back toward the tip at v - c (c from the loop's own tension profile)."""
    from robowrangler_sim.string_shooter.waves import measure_waves_on_loop

    res = measure_waves_on_loop(rope_speed_mps=5.0, loop_length_m=2.0, start_fraction=0.6)
    scale = res.rope_speed_mps + (res.tension_n / 0.221e-3) ** 0.5
    assert res.measured_mps[0] < 0  # upstream: the loop's tension there exceeds lambda v^2
    assert abs(res.measured_mps - res.predicted_mps).max() / scale < 0.03, (res.measured_mps, res.predicted_mps)
