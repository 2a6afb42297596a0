"""What a provisioning stages on the device before its commit: the one ordered list of PROVISION_* (and
PARAM_SET) messages, shared by the client (robowrangler.client.Client.provision) and the SIL's provisioning jig.

The commit (PROVISION_COMMIT with a session epoch, robowrangler.session_epoch) is the caller's: it decides
whether and with which epoch to commit.
"""

from __future__ import annotations

from collections.abc import Mapping

from robowrangler.protocol import generated as gen


def staging_messages(*, key: bytes | None = None, wifi_ssid: str | None = None, wifi_password: str | None = None,
                     params: Mapping[str, float] | None = None) -> list[gen.Message]:
    """The messages that stage what is given, in the order the device takes them: key, WiFi SSID, WiFi
    password, then each parameter (PARAM_SET, by protocol name, in its own unit). Values are not checked here:
    the message classes and the device do that."""
    staged: list[gen.Message] = []
    if key is not None:
        staged.append(gen.ProvisionSetKey(bytes(key)))
    if wifi_ssid is not None:
        staged.append(gen.ProvisionSetWifiSsid(wifi_ssid))
    if wifi_password is not None:
        staged.append(gen.ProvisionSetWifiPassword(wifi_password))
    for name, value in (params or {}).items():
        staged.append(gen.ParamSet(gen.PARAMS_BY_NAME[name].id, float(value)))
    return staged


__all__ = ["staging_messages"]
