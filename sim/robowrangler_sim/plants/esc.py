"""BLHeli_32-style ESC input stage: 400 Hz pulse latching, arming, deadband, duty lag.

What is modelled (numbers in DriveParams):

* The ESC takes one pulse width per input frame (2500 us at 400 Hz) and holds it until the next frame
  (``on_frame``). So a new command acts up to one frame late.
* A pulse shorter than ``esc_invalid_below_us`` (a pulse below the ESC's minimum, or 0 = no signal) stops the
  bridge and disarms: the ESC needs a fresh arming hold.
* Arming: the ESC arms on the first frame that comes ``esc_arm_hold_us`` after the first of an unbroken run
  of valid zero-throttle frames (min <= pulse <= min + deadband); any other frame restarts the run.
* Armed: throttle = (pulse - min - deadband) / (max - min - deadband) clipped to [0, 1]; zero throttle turns
  the bridge off (the motor coasts, BLHeli "brake on stop" off).
* The applied duty follows throttle x ``esc_max_duty`` through a first-order lag ``esc_lag_s``
  (``advance``); with the bridge off the duty is zero. When the bridge switches on while the motor still
  turns, the duty starts at the back-EMF's share of the supply (the ESC synchronises to the coasting motor;
  assumption) so a re-applied throttle does not brake it from zero duty first.

Active braking (damped light) and the current limit act on the motor current, in bldc_motor.py.
"""

from __future__ import annotations

import math

from robowrangler_sim.plants.drive_params import DriveParams


class Esc:
    """ESC state machine and duty lag. ``duty`` is the applied duty (0..1); ``bridge_on`` says if it drives.

    Attributes:
        armed: True once armed, False after an invalid frame.
        bridge_on: True while armed with non-zero throttle (the motor is driven).
        throttle: latched throttle fraction 0..1 (0 when disarmed).
        duty: applied duty 0..esc_max_duty, lagging throttle.
        arm_hold_us: microseconds of valid zero-throttle frames counted towards arming.
    """

    def __init__(self, params: DriveParams) -> None:
        self._p = params
        self._zero_top_us = params.esc_min_pulse_us + params.esc_deadband_us
        self._span_us = params.esc_max_pulse_us - self._zero_top_us
        self.reset()

    def reset(self) -> None:
        """Power-up state: disarmed, bridge off, no arming progress."""
        self.armed = False
        self.bridge_on = False
        self.throttle = 0.0
        self.duty = 0.0
        self.arm_hold_us = 0

    def on_frame(self, pulse_us: float, back_emf_duty: float = 0.0) -> None:
        """Latch one input frame's pulse width (us; 0 = no signal). Called once per ``esc_frame_us``.

        back_emf_duty: the motor's back-EMF over the supply voltage now; when the bridge switches on, the
        duty starts there (the ESC synchronises to a coasting motor) rather than at zero.
        """
        p = self._p
        if pulse_us < p.esc_invalid_below_us:
            self.armed = False
            self.bridge_on = False
            self.throttle = 0.0
            self.duty = 0.0
            self.arm_hold_us = 0
            return
        if pulse_us <= self._zero_top_us:
            throttle = 0.0
        elif pulse_us >= p.esc_max_pulse_us:
            throttle = 1.0
        else:
            throttle = (pulse_us - self._zero_top_us) / self._span_us
        if not self.armed:
            if throttle == 0.0:
                # arm_hold_us = time since the first frame of this unbroken run of zero-throttle frames
                if self.arm_hold_us >= p.esc_arm_hold_us:
                    self.armed = True
                else:
                    self.arm_hold_us += p.esc_frame_us
            else:
                self.arm_hold_us = 0
            return
        self.throttle = throttle
        if throttle == 0.0:
            self.bridge_on = False
            self.duty = 0.0
        elif not self.bridge_on:
            self.bridge_on = True
            # pick up a still-turning motor at the duty that matches its back-EMF (no braking jolt)
            self.duty = min(throttle * p.esc_max_duty, max(0.0, back_emf_duty))

    def advance(self, dt_s: float) -> float:
        """Advance the duty lag by dt_s seconds; returns the mean applied duty over the interval."""
        if not self.bridge_on:
            return 0.0
        target = self.throttle * self._p.esc_max_duty
        d0 = self.duty
        tau = self._p.esc_lag_s
        if tau <= 0.0:
            self.duty = target
            return target
        decay = math.exp(-dt_s / tau)
        self.duty = target + (d0 - target) * decay
        # exact mean of the exponential approach over the interval
        return target + (d0 - target) * (1.0 - decay) * tau / dt_s
