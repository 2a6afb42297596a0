"""Designed identification runs (`wrangler excite`): profiles as data files, checked against the device's limits,
run over any link while the run is recorded.

- profile: the profile format (TOML), the shipped profiles (profiles/*.toml), loading and the limit checks.
- runner: runs a checked profile with a Client (ARM, HOME if needed, the steps, SPINDOWN, DISARM).
"""

from robowrangler.excite.profile import (Limits, Profile, ProfileError, Step, list_profiles, load_profile,
                                         profile_path)
from robowrangler.excite.runner import ExciteResult, run_profile

__all__ = ["ExciteResult", "Limits", "Profile", "ProfileError", "Step", "list_profiles", "load_profile",
           "profile_path", "run_profile"]
