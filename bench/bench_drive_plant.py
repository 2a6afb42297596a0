"""Per-step cost of the drive plant at 1 kHz, and the steady throttle / rope-speed map it implies.

Run: uv run python bench/bench_drive_plant.py
Prints figures only (no assertions). The SIL steps the plant once per 1 ms tick from Python.
"""

from __future__ import annotations

import time

from robowrangler_sim.plants import (
    DriveParams,
    DrivePlant,
    kv_throttle_for_speed,
    speed_time_constant_s,
    steady_battery_v,
    steady_throttle_for_speed,
)


def per_step_us(pulse_us: float, steps: int, dt_s: float = 0.001) -> float:
    plant = DrivePlant(seed=1)
    for _ in range(300):
        plant.step(esc_pulse_us=1000.0, dt_s=0.001)
    for _ in range(500):  # reach the operating point first
        plant.step(esc_pulse_us=pulse_us, dt_s=dt_s)
    best = float("inf")
    for _ in range(5):
        t0 = time.perf_counter()
        for _ in range(steps):
            plant.step(esc_pulse_us=pulse_us, dt_s=dt_s)
        best = min(best, (time.perf_counter() - t0) / steps * 1e6)
    return best


def main() -> None:
    params = DriveParams()
    print("drive plant step cost (best of 5 x 5000 steps, one core):")
    for label, pulse, dt in [("at rest, armed, 1 ms", 1000.0, 0.001), ("3 m/s, 1 ms", 1170.0, 0.001),
                             ("full throttle, 1 ms", 2000.0, 0.001), ("full throttle, 5 ms", 2000.0, 0.005)]:
        print(f"  {label:26s} {per_step_us(pulse, 5000, dt):6.1f} us/step")
    print()
    print("steady state (12.0 V open circuit, no external load):")
    print("  v_mps   rpm     throttle  pulse_us  kv_map   kv_err   battery_v  I_motor_A  tau_mech_ms")
    for v in [0.5, 1.0, 2.0, 2.6, 3.12, 5.0, 7.5, 10.0, 12.5, 15.0, 17.5, 20.0, 22.0]:
        thr = steady_throttle_for_speed(params, v)
        vb = steady_battery_v(params, v)
        kv = kv_throttle_for_speed(params, v, battery_v=vb)
        rpm = v / params.wheel_radius_m * 60.0 / (2.0 * 3.141592653589793)
        plant_i = (steady_torque_current_a(params, v))
        tau_ms = speed_time_constant_s(params, v) * 1e3
        print(f"  {v:5.2f} {rpm:7.0f}   {thr:7.4f}   {1000 + 1000 * thr:7.1f}  {kv:7.4f}  {kv - thr:+7.4f}"
              f"   {vb:8.3f}  {plant_i:8.3f}   {tau_ms:6.2f}")
    print()
    print("open loop in the plant (1.5 s at the pulse), firmware Kv map alone and with +deadband:")
    print("  target_mps  kv_map_mps  kv_map+deadband_mps")
    for v in [0.5, 1.0, 2.6, 5.0, 10.0, 20.0]:
        vb = steady_battery_v(params, v)
        pulse = 1000.0 + 1000.0 * kv_throttle_for_speed(params, v, battery_v=vb)
        print(f"  {v:9.2f}  {open_loop_speed_mps(params, pulse):10.3f}  "
              f"{open_loop_speed_mps(params, pulse + params.esc_deadband_us):10.3f}")
    full = DrivePlant(params)
    for _ in range(300):
        full.step(esc_pulse_us=1000.0, dt_s=0.001)
    for _ in range(1500):
        full.step(esc_pulse_us=2000.0, dt_s=0.001)
    print(f"  full throttle: {full.motor_rpm:.0f} rpm, {full.rope_speed_mps:.2f} m/s, "
          f"{full.motor_current_a:.2f} A/motor, battery {full.battery_v:.3f} V")


def open_loop_speed_mps(params: DriveParams, pulse_us: float) -> float:
    """Rope speed after 1.5 s at a fixed pulse (armed first)."""
    plant = DrivePlant(params)
    for _ in range(300):
        plant.step(esc_pulse_us=1000.0, dt_s=0.001)
    for _ in range(1500):
        plant.step(esc_pulse_us=pulse_us, dt_s=0.001)
    return plant.rope_speed_mps


def steady_torque_current_a(params: DriveParams, v: float) -> float:
    """Per-motor current in steady state at rope speed v (from a 1.5 s plant run at the steady throttle)."""
    plant = DrivePlant(params)
    for _ in range(300):
        plant.step(esc_pulse_us=1000.0, dt_s=0.001)
    pulse = 1000.0 + 1000.0 * steady_throttle_for_speed(params, v)
    for _ in range(1500):
        plant.step(esc_pulse_us=pulse, dt_s=0.001)
    return plant.motor_current_a


if __name__ == "__main__":
    main()
