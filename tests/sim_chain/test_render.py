"""Headless rendering: a PNG of the airborne loop shows the rope, an MP4 is written (OSMesa, OpenCV)."""

from __future__ import annotations

import os
import subprocess
import sys
import textwrap
from pathlib import Path

import pytest

SCRIPT = textwrap.dedent("""
    import math, sys
    import numpy as np
    from robowrangler_sim.chain.render import ChainRenderer, write_png, write_mp4
    from robowrangler_sim.chain.plant import ChainPlant, PlantInputs, pitch_quat_wxyz
    from robowrangler_sim.chain.synthetic_table import synthetic_ellipse_table
    out = sys.argv[1]
    inputs = PlantInputs(rope_speed_mps=5.0, base_pos_m=(0, 0, 0.8), base_quat_wxyz=pitch_quat_wxyz(0.2))
    plant = ChainPlant(table=synthetic_ellipse_table(), initial=inputs, floor_height_m=0.0)
    frames = []
    with ChainRenderer(plant, width_px=320, height_px=180) as r:
        for _ in range(5):
            plant.advance(inputs, duration_s=0.1)
            frames.append(r.frame())
    write_png(out + "/loop.png", frames[-1])
    write_mp4(out + "/loop.mp4", frames, fps=10)
    f = frames[-1].astype(int)
    rope = (f[..., 0] > 120) & (f[..., 0] - f[..., 2] > 80)  # orange/yellow: red well above blue
    print(int(rope.sum()), f.shape)
""")


def test_render_png_shows_the_rope_and_mp4_is_written(tmp_path: Path, skip_unless_ci):
    env = dict(os.environ, MUJOCO_GL="osmesa", PYOPENGL_PLATFORM="osmesa")
    res = subprocess.run([sys.executable, "-c", SCRIPT, str(tmp_path)], env=env, capture_output=True, text=True,
                         timeout=120)
    if res.returncode != 0 and ("osmesa" in res.stderr.lower() or "OSMesa" in res.stderr):
        skip_unless_ci(f"OSMesa not available (apt-get install -y libosmesa6): {res.stderr.strip()[-200:]}")
    assert res.returncode == 0, res.stderr
    rope_pixels = int(res.stdout.split()[0])
    assert rope_pixels > 150, "the orange rope is not visible in the frame"
    assert (tmp_path / "loop.png").stat().st_size > 5_000
    assert (tmp_path / "loop.mp4").stat().st_size > 5_000
