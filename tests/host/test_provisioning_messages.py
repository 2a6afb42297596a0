"""robowrangler.provisioning.staging_messages: what a provisioning stages, in the device's order, and only that."""

from __future__ import annotations

import pytest

from robowrangler.protocol import generated as gen
from robowrangler.provisioning import staging_messages


def test_everything_given_is_staged_in_order() -> None:
    key = bytes(range(16))
    msgs = staging_messages(key=key, wifi_ssid="lab", wifi_password="correct horse",
                            params={"tov_mps": 2.7, "telemetry_rate_hz": 100})
    assert [type(m) for m in msgs] == [gen.ProvisionSetKey, gen.ProvisionSetWifiSsid, gen.ProvisionSetWifiPassword,
                                       gen.ParamSet, gen.ParamSet]
    assert msgs[0].key == key and msgs[1].ssid == "lab" and msgs[2].password == "correct horse"
    assert [(m.param_id, m.value) for m in msgs[3:]] == [(gen.PARAMS_BY_NAME["tov_mps"].id, 2.7),
                                                          (gen.PARAMS_BY_NAME["telemetry_rate_hz"].id, 100.0)]


def test_nothing_given_stages_nothing_and_an_unknown_parameter_is_named() -> None:
    assert staging_messages() == []
    with pytest.raises(KeyError, match="no_such_param"):
        staging_messages(params={"no_such_param": 1.0})
