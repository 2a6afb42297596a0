"""A PARAM_SET converts again only what the changed parameter feeds (rw_core.c's apply_param), to keep the
float work of a full rw_core_apply_params out of that tick. Guard: for every parameter, a core that took the
new value through rw_core_set_param is byte for byte the core that took it and then re-applied everything."""

from __future__ import annotations

import ctypes

import pytest
from robowrangler.protocol import generated as proto


@pytest.fixture(scope="module")
def lib(rw_core: ctypes.CDLL) -> ctypes.CDLL:
    rw_core.rw_core_sizeof.restype = ctypes.c_size_t
    rw_core.rw_core_init.argtypes = [ctypes.c_void_p]
    rw_core.rw_core_set_param.restype = ctypes.c_int
    rw_core.rw_core_set_param.argtypes = [ctypes.c_void_p, ctypes.c_uint8, ctypes.c_float]
    rw_core.rw_core_apply_params.argtypes = [ctypes.c_void_p]
    rw_core.rw_params_set.restype = ctypes.c_int
    rw_core.rw_params_set.argtypes = [ctypes.c_void_p, ctypes.c_uint8, ctypes.c_float, ctypes.c_bool]
    return rw_core


def _new_core(lib: ctypes.CDLL) -> ctypes.Array:
    core = ctypes.create_string_buffer(lib.rw_core_sizeof())
    lib.rw_core_init(core)
    return core


@pytest.mark.parametrize("spec", proto.PARAMS, ids=lambda p: p.name)
def test_a_changed_parameter_reaches_everything_it_feeds(lib: ctypes.CDLL, spec: proto.ParamSpec) -> None:
    value = spec.min + 0.37 * (spec.max - spec.min)
    value = float(round(value)) if spec.integer else value
    if value == spec.default:
        value = spec.max
    partial, full = _new_core(lib), _new_core(lib)
    assert lib.rw_core_set_param(partial, spec.id, value) == 0  # RW_DECODE_OK
    assert lib.rw_params_set(full, spec.id, value, True) == 0  # rw_core.params is the struct's first member
    lib.rw_core_apply_params(full)
    assert partial.raw == full.raw, f"{spec.name}: set alone leaves a controller unconverted"
