"""Issue 18 item 5 through the real SIL firmware and `wrangler`: guide_min_mm 150 then guide_max_mm 50 -> the
second is refused (exit 3, PARAM_CONFLICT naming guide_min_mm); in the consistent order the same limits are
taken. (That SET_LOOP works inside limits set so is tests/firmware_core/test_core_param_rules.py.)"""

from __future__ import annotations

import io
from pathlib import Path

from robowrangler.cli.environment import Environment
from robowrangler.cli.exit_status import ExitStatus
from robowrangler.cli.main import main
from robowrangler_sim.sil import SilSession

KEY = bytes(range(16))


def test_dependent_parameters_are_checked_together_on_the_device(native_build_dir: Path, tmp_path: Path) -> None:
    key_file = tmp_path / "link.key"
    key_file.write_text(KEY.hex())

    def wrangler(*argv: str) -> tuple[ExitStatus, str, str]:
        out, err = io.StringIO(), io.StringIO()
        status = main(["--url", sil.cmd_url, "--key-file", str(key_file), *argv], Environment(out, err, {}))
        return status, out.getvalue(), err.getvalue()

    with SilSession(speedup=None, key=KEY) as sil:
        sil.run_in_background()
        sil.wait_until(0.6)
        assert wrangler("param", "set", "guide_min_mm", "150")[0] == ExitStatus.OK
        status, _, err = wrangler("param", "set", "guide_max_mm", "50")
        assert status == ExitStatus.NACK
        assert "PARAM_CONFLICT" in err and "guide_min_mm must stay below guide_max_mm" in err
        status, out, _ = wrangler("param", "get", "guide_max_mm")
        assert out == "guide_max_mm = 180 mm\n"
        status, _, err = wrangler("param", "set", "max_rope_speed_mps", "2.9")  # under 2.6 x 1.15
        assert status == ExitStatus.NACK and "with tov_mps" in err
        for name, value in (("guide_min_mm", "5"), ("guide_max_mm", "50")):
            status, out, err = wrangler("param", "set", name, value)
            assert status == ExitStatus.OK and out == f"{name} = {value} mm\n", err
