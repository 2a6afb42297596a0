"""SecuredMonitor (sliding-window judgement) and the plant's object_secured / rope_tension outputs."""

from __future__ import annotations

import numpy as np
import pytest

from robowrangler_sim.chain.errors import ChainModelError
from robowrangler_sim.chain.grasp import GraspScript, grasp_inputs, grasp_scene
from robowrangler_sim.chain.params import ChainParams
from robowrangler_sim.chain.secured import SecuredMonitor


def _feed(mon, *, obj_step, base_step, force, n=21, dt=0.05):
    for k in range(n):
        mon.update(time_s=k * dt, object_com_m=np.array([obj_step * k, 0, 0]),
                   base_pos_m=np.array([base_step * k, 0, 0]), chain_force_n=force)


def test_secured_when_the_rope_holds_and_the_object_follows():
    mon = SecuredMonitor(drag_force_n=1.0, window_s=1.0)
    _feed(mon, obj_step=-0.009, base_step=-0.01, force=0.5)
    assert mon.secured and mon.follow_ratio == pytest.approx(0.9) and mon.touching_fraction == 1.0


@pytest.mark.parametrize("obj_step, force", [(0.0, 0.5),      # left behind although touched
                                             (-0.01, 0.0)])   # moved along without the rope (rolled)
def test_not_secured_when_left_behind_or_not_held(obj_step, force):
    mon = SecuredMonitor(drag_force_n=1.0)
    _feed(mon, obj_step=obj_step, base_step=-0.01, force=force)
    assert not mon.secured


def test_still_module_needs_only_the_hold_and_old_samples_leave_the_window():
    mon = SecuredMonitor(drag_force_n=1.0, window_s=0.5)
    _feed(mon, obj_step=0.0, base_step=0.0, force=0.2)
    assert mon.secured and np.isnan(mon.follow_ratio)
    for k in range(21, 40):
        mon.update(time_s=k * 0.05, object_com_m=np.zeros(3), base_pos_m=np.zeros(3), chain_force_n=0.0)
    assert not mon.secured and mon.touching_fraction == 0.0
    with pytest.raises(ChainModelError, match="drag_force_n"):
        SecuredMonitor(drag_force_n=0.0)


@pytest.mark.parametrize("name, secured", [("mug", True), ("tennis_ball", False)])
def test_plant_outputs_report_secured_and_rope_tension(table, name, secured):
    script = GraspScript()
    plant, base = grasp_scene(name, table=table, params=ChainParams(), script=script)
    tension_hold = None
    for k in range(int(round(script.duration_s / 0.05))):
        for _ in range(10):  # the script's inputs at every 5 ms plant step (the leg moves continuously)
            phase, inputs = grasp_inputs(script, plant.time_s, base_pos_m=base)
            plant.step(inputs)
        out = plant.outputs()
        if phase == "hold":
            tension_hold = out.rope_tension_n
    assert out.object_secured[name] is secured
    assert np.isfinite(out.rope_tension_n) and out.rope_tension_n >= 0.0 and tension_hold is not None
    if secured:
        assert out.rope_tension_n > 0.01  # the loop carries the dragged mug
        assert np.linalg.norm(out.chain_object_net_force_n[name]) > 0.0
