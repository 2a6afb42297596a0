"""A PARAM_SET is staged (rw_core_params.c): the value is stored at once, and only the modules the parameter
feeds (rw_params_modules) are converted again, later, one per tick at the tick's end, so no tick carries both a
command and the float work of a conversion. Guards:

- for every parameter, a core that took the new value through rw_core_set_param and then converted its staged
  modules is byte for byte the core that took it and re-applied everything (the module table is complete);
- until then the controllers are untouched (the value waits in params, its modules in params_pending);
- a parameter settable in flight feeds at most one of the speed loop's modules, so the speed step sees its old
  or its new gains, never half of each.
"""

from __future__ import annotations

import ctypes

import pytest
from robowrangler.protocol import generated as proto

MODULE_SPEED_LOOP = 0x001F  # RW_PARAM_MODULES_SPEED_LOOP (rw_params.h)


@pytest.fixture(scope="module")
def lib(rw_core: ctypes.CDLL) -> ctypes.CDLL:
    rw_core.rw_core_sizeof.restype = ctypes.c_size_t
    rw_core.rw_core_init.argtypes = [ctypes.c_void_p]
    rw_core.rw_core_set_param.restype = ctypes.c_int
    rw_core.rw_core_set_param.argtypes = [ctypes.c_void_p, ctypes.c_uint8, ctypes.c_float]
    rw_core.rw_core_apply_params.argtypes = [ctypes.c_void_p]
    rw_core.rw_core_params_settle_all.argtypes = [ctypes.c_void_p]
    rw_core.rw_core_params_pending.restype = ctypes.c_uint16
    rw_core.rw_core_params_pending.argtypes = [ctypes.c_void_p]
    rw_core.rw_params_modules.restype = ctypes.c_uint16
    rw_core.rw_params_modules.argtypes = [ctypes.c_uint8]
    rw_core.rw_params_set.restype = ctypes.c_int
    rw_core.rw_params_set.argtypes = [ctypes.c_void_p, ctypes.c_uint8, ctypes.c_float, ctypes.c_bool]
    return rw_core


def _new_core(lib: ctypes.CDLL) -> ctypes.Array:
    core = ctypes.create_string_buffer(lib.rw_core_sizeof())
    lib.rw_core_init(core)
    return core


def _new_value(spec: proto.ParamSpec) -> float:
    value = spec.min + 0.37 * (spec.max - spec.min)
    value = float(round(value)) if spec.integer else value
    return spec.max if value == spec.default else value


@pytest.mark.parametrize("spec", proto.PARAMS, ids=lambda p: p.name)
def test_a_changed_parameter_reaches_everything_it_feeds(lib: ctypes.CDLL, spec: proto.ParamSpec) -> None:
    value = _new_value(spec)
    partial, full = _new_core(lib), _new_core(lib)
    assert lib.rw_core_set_param(partial, spec.id, value) == 0  # RW_DECODE_OK
    assert lib.rw_core_params_pending(partial) == lib.rw_params_modules(spec.id)
    lib.rw_core_params_settle_all(partial)
    assert lib.rw_core_params_pending(partial) == 0
    assert lib.rw_params_set(full, spec.id, value, True) == 0  # rw_core.params is the struct's first member
    lib.rw_core_apply_params(full)
    assert partial.raw == full.raw, f"{spec.name}: its modules leave a controller unconverted"


@pytest.mark.parametrize("spec", [p for p in proto.PARAMS if p.name in ("speed_kp", "tov_mps", "spindle_kp_per_s",
                                                                        "load_loss_drop_n", "telemetry_rate_hz")],
                         ids=lambda p: p.name)
def test_a_staged_value_leaves_the_controllers_alone_until_converted(lib: ctypes.CDLL, spec: proto.ParamSpec) -> None:
    staged, untouched = _new_core(lib), _new_core(lib)
    assert lib.rw_core_set_param(staged, spec.id, _new_value(spec)) == 0
    assert lib.rw_core_params_pending(staged) != 0
    params_bytes = 4 * len(proto.PARAMS)  # rw_core.params first, then the controllers
    assert staged.raw[:params_bytes] != untouched.raw[:params_bytes], "the value is stored at once"
    # everything after the parameter values but the pending bits is the same: no controller converted yet
    diff = [i for i in range(params_bytes, len(staged.raw)) if staged.raw[i] != untouched.raw[i]]
    assert len(diff) <= 2, f"{spec.name}: bytes changed before the conversion at {diff}"


@pytest.mark.parametrize("spec", proto.PARAMS, ids=lambda p: p.name)
def test_a_parameter_settable_in_flight_feeds_at_most_one_speed_loop_module(lib: ctypes.CDLL,
                                                                             spec: proto.ParamSpec) -> None:
    speed_modules = lib.rw_params_modules(spec.id) & MODULE_SPEED_LOOP
    if not spec.locked:
        assert bin(speed_modules).count("1") <= 1, f"{spec.name} feeds speed loop modules {speed_modules:#x}"
