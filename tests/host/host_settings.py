"""Settings shared by the host tests (a module of its own: `conftest` is a name every suite has)."""

# Short timeouts keep the suite fast; the logic under test is the same at any value.
FAST = dict(ack_timeout_s=0.1, retries=3, connect_timeout_s=10.0, heartbeat_hz=20.0)  # connect: a bound, generous for a busy machine
QUICK_ARM = {"arm_hold_s": 0.2}  # the shortest ESC arming hold the core takes
