"""Software in the loop: the SIL firmware process in lockstep with the plants, over real UDP.

- firmware.FirmwareProcess: starts ``rw_sil`` (the firmware core with the sil HAL) and reads its ports.
- lockstep.LockstepLink: the plant side of the lockstep socket (SIL_SENSORS out, SIL_ACTUATORS back).
- session.SilSession: firmware + drive plant + lockstep; steps, paces, runs in a thread for a live host.
- wifi_module.WifiModule: the board's NINA WiFi module in the firmware and its scripted faults.
- scripted_host.ScriptedHost: a deterministic host that sends commands at simulated times (scenarios, tests).
"""

from robowrangler_sim.sil.errors import SilError, SilFirmwareError, SilTimeout
from robowrangler_sim.sil.firmware import FirmwareProcess, find_sil_binary
from robowrangler_sim.sil.session import SilSession
from robowrangler_sim.sil.usb_notes import UsbNotes
from robowrangler_sim.sil.wifi_module import WifiModule, WifiModuleError

__all__ = ["FirmwareProcess", "SilError", "SilFirmwareError", "SilSession", "SilTimeout", "UsbNotes", "WifiModule",
           "WifiModuleError", "find_sil_binary"]
