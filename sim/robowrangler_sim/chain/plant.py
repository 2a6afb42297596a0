"""ChainPlant: the paper's rope-loop chain in MuJoCo, driven by SI plant inputs, read by named outputs.

A lockstep bridge drives it once per tick::

    plant = ChainPlant(table=..., params=ChainParams(), objects=(...), floor_height_m=0.0)
    plant.advance(PlantInputs(rope_speed_mps=5.0, guide_position_mm=0.0,
                              base_pos_m=(0, 0, 1), base_quat_wxyz=(1, 0, 0, 0)), duration_s=0.001)
    out = plant.outputs()          # PlantOutputs: tip, closure gap, contact forces, objects ...

Each step: the lift factor follows the rope speed (lift.py); the inclination phi is read from the base
pose; the in-plane drive targets come from the shape table at phi (targets.py); the link length
follows the loop length the guide leaves outside; the module moves to the base pose with a real
velocity (prescribed motion, see _move_module) and takes its orientation; MuJoCo steps; divergence raises ChainDivergenceError.

Time: the plant owns its clock, ``time_s = steps * timestep_s``. ``advance(duration_s)`` runs the
whole number of steps that brings the clock nearest to the requested end time (the remainder is
carried, so a 1 kHz bridge on a 2 ms plant steps every other tick, deterministically).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import mujoco
import numpy as np

from robowrangler_sim.chain.builder import build_chain_model
from robowrangler_sim.chain.errors import ChainDivergenceError, ChainModelError
from robowrangler_sim.chain.lift import LiftState
from robowrangler_sim.chain.objects import ObjectPlacement
from robowrangler_sim.chain.params import ChainParams
from robowrangler_sim.chain.rope_contacts import RopeContact, rope_object_contacts
from robowrangler_sim.chain.secured import SecuredMonitor
from robowrangler_sim.chain.targets import ShapeTargets
from robowrangler_sim.shape_table import ShapeTable

MAX_JOINT_SPEED_RAD_S = 1.0e4


@dataclass(frozen=True, kw_only=True)
class ContactSummary:
    """The contact forces of one instant, N.

    Attributes:
        chain_on_object_n: {object name: normal force of the chain on it}.
        module_on_object_n: {object name: normal force of the module on it}.
        chain_on_floor_n: normal force between the chain and the floor.
        chain_net_on_object_n: {object name: shape (3,) world, net force (normal + friction) of the chain on it}.
    """

    chain_on_object_n: dict
    module_on_object_n: dict
    chain_on_floor_n: float
    chain_net_on_object_n: dict


@dataclass(frozen=True, kw_only=True)
class PlantInputs:
    """Inputs of one tick (SI).

    Attributes:
        rope_speed_mps: rope speed from the drive plant, m/s.
        guide_position_mm: spindle guide position, 0..guide_stroke_mm.
        base_pos_m: shape (3,), module exit point in the world, metres.
        base_quat_wxyz: shape (4,), module orientation (x = launch axis, z = up), unit quaternion.
    """

    rope_speed_mps: float
    guide_position_mm: float = 0.0
    base_pos_m: tuple[float, float, float] = (0.0, 0.0, 1.0)
    base_quat_wxyz: tuple[float, float, float, float] = (1.0, 0.0, 0.0, 0.0)

    def __post_init__(self) -> None:
        if not math.isfinite(self.rope_speed_mps):
            raise ChainModelError(f"rope_speed_mps: expected a finite speed, got {self.rope_speed_mps}")
        pos = np.asarray(self.base_pos_m, dtype=float)
        if pos.shape != (3,) or not np.all(np.isfinite(pos)):
            raise ChainModelError(f"base_pos_m: expected 3 finite numbers, got {self.base_pos_m}")
        q = np.asarray(self.base_quat_wxyz, dtype=float)
        if q.shape != (4,) or not np.all(np.isfinite(q)) or abs(np.linalg.norm(q) - 1.0) > 1e-6:
            raise ChainModelError(f"base_quat_wxyz: expected a unit quaternion (w, x, y, z), got "
                                  f"{self.base_quat_wxyz}")


@dataclass(frozen=True)
class PlantOutputs:
    """Named outputs after a tick (SI, world frame).

    Attributes:
        time_s: plant clock.
        loop_tip_pos_m: shape (3,), the chain point farthest from the exit.
        closure_gap_m: distance between the last link's end and the return point.
        loop_length_m: rope outside the device.
        phi_rad: module inclination read from the base pose.
        lift: lift factor in [0, 1] (1 = airborne).
        chain_object_force_n: {object name: total normal contact force from the chain, N}.
        module_object_force_n: {object name: total normal contact force from the module housing, N}.
        chain_floor_force_n: total normal force between chain and floor, N.
        object_pos_m: {object name: shape (3,) body origin}.
        object_quat_wxyz: {object name: shape (4,)}.
        chain_object_net_force_n: {object name: shape (3,) net chain force (normal + friction), N}.
        object_secured: {free object name: bool}, SecuredMonitor over the outputs() calls of the last
            ``secured_window_s`` (rope presses on it; if the module moved, it followed).
        rope_tension_n: closure load (constraint force, or tendon spring force in free flight), N;
            what the spindle's load would feel.
    """

    time_s: float
    loop_tip_pos_m: np.ndarray
    closure_gap_m: float
    loop_length_m: float
    phi_rad: float
    lift: float
    chain_object_force_n: dict
    module_object_force_n: dict
    chain_floor_force_n: float
    object_pos_m: dict
    object_quat_wxyz: dict
    chain_object_net_force_n: dict
    object_secured: dict
    rope_tension_n: float


def base_inclination_rad(quat_wxyz: np.ndarray) -> float:
    """Inclination of the module's launch axis (its x axis) above the horizontal, rad."""
    mat = np.empty(9)
    mujoco.mju_quat2Mat(mat, np.asarray(quat_wxyz, dtype=float))
    x_axis = mat.reshape(3, 3)[:, 0]
    return math.atan2(x_axis[2], math.hypot(x_axis[0], x_axis[1]))


def pitch_quat_wxyz(phi_rad: float, *, yaw_rad: float = 0.0, roll_rad: float = 0.0) -> tuple[float, float, float, float]:
    """Module orientation: launch axis pitched up by phi, then yawed; roll turns the loop plane about
    the launch axis (roll pi/2: the loop plane is horizontal). Returns a unit quaternion (w, x, y, z)."""
    qy = np.array([math.cos(yaw_rad / 2), 0.0, 0.0, math.sin(yaw_rad / 2)])
    qp = np.array([math.cos(-phi_rad / 2), 0.0, math.sin(-phi_rad / 2), 0.0])  # about +y: x->-z, so -phi
    qr = np.array([math.cos(roll_rad / 2), math.sin(roll_rad / 2), 0.0, 0.0])
    tmp = np.empty(4)
    out = np.empty(4)
    mujoco.mju_mulQuat(tmp, qy, qp)
    mujoco.mju_mulQuat(out, tmp, qr)
    return tuple(float(v) for v in out)


class ChainPlant:
    """The rope-loop chain plant.

    Args:
        table: shape table (contours per phi); see default_table.py for the shipped default.
        params: chain parameters.
        objects: objects in the scene.
        floor_height_m: z of a floor plane, or None.
        initial: PlantInputs the plant starts from (base pose, speed, guide).
        airborne: True: start airborne in the target shape (lift 1); False: start at rest, lift 0,
            the loop collapsed into a doubled line along the launch axis (see _rest_angles).
        seed: seeds the optional initial joint noise (same seed -> same trajectory).
        initial_noise_rad: standard deviation of noise added to the initial joint angles.
        secured_window_s: window of the per-object SecuredMonitor fed by outputs().
    """

    def __init__(self, *, table: ShapeTable, params: ChainParams | None = None,
                 objects: tuple[ObjectPlacement, ...] = (), floor_height_m: float | None = None,
                 initial: PlantInputs | None = None, airborne: bool = True, seed: int = 0,
                 initial_noise_rad: float = 0.0, secured_window_s: float = 1.0) -> None:
        if not isinstance(table, ShapeTable):
            raise ChainModelError(f"table: expected a ShapeTable, got {type(table).__name__}")
        self.params = params if params is not None else ChainParams()
        self.table = table
        self.objects = tuple(objects)
        initial = initial if initial is not None else PlantInputs(rope_speed_mps=5.0)
        p = self.params
        n = p.n_links
        self.model = build_chain_model(p, objects=self.objects, floor_height_m=floor_height_m,
                                       module_pos_m=tuple(initial.base_pos_m))
        self.data = mujoco.MjData(self.model)
        self.targets = ShapeTargets(table, n_links=n)
        m = self.model
        name = lambda kind, s: mujoco.mj_name2id(m, kind, s)  # noqa: E731
        J, B, G, S, A = (mujoco.mjtObj.mjOBJ_JOINT, mujoco.mjtObj.mjOBJ_BODY, mujoco.mjtObj.mjOBJ_GEOM,
                         mujoco.mjtObj.mjOBJ_SITE, mujoco.mjtObj.mjOBJ_ACTUATOR)
        self._inplane_qpos = np.array([m.jnt_qposadr[name(J, f"inplane_{i}")] for i in range(n)])
        self._outplane_qpos = np.array([m.jnt_qposadr[name(J, f"outplane_{i}")] for i in range(n)])
        self._chain_dof = np.concatenate([[m.jnt_dofadr[name(J, f"inplane_{i}")],
                                           m.jnt_dofadr[name(J, f"outplane_{i}")]] for i in range(n)])
        self._link_body = np.array([name(B, f"link_{i}") for i in range(n)])
        self._link_geom = np.array([name(G, f"link_{i}") for i in range(n)])
        self._visual_geom = np.array([name(G, f"link_{i}_visual") for i in range(n)])
        self._end_site = np.array([name(S, f"link_{i}_end") for i in range(n)])
        self._exit_site = name(S, "exit")
        self._return_site = name(S, "return")
        act_joint = {}
        for i in range(n):
            a = name(A, f"drive_inplane_{i}")
            if a >= 0:
                act_joint[a] = i
        self._drive_act = np.array(sorted(act_joint), dtype=int)
        self._drive_joint = np.array([act_joint[a] for a in self._drive_act], dtype=int)
        self._drive_kp = m.actuator_gainprm[self._drive_act, 0].copy()
        self._drive_kd = -m.actuator_biasprm[self._drive_act, 2].copy()
        self._drive_dof = np.array([m.jnt_dofadr[m.actuator_trnid[a, 0]] for a in self._drive_act], dtype=int)
        self._base_armature = m.dof_armature[self._drive_dof].copy()
        self._closure_eq = mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_EQUALITY, "closure_constraint")
        self._module_qpos = int(m.jnt_qposadr[name(J, "module_x")])  # x, y, z slides are consecutive
        self._module_dof = int(m.jnt_dofadr[name(J, "module_x")])
        self._carriage_origin_m = m.body_pos[name(B, "module_carriage")].copy()
        self._module_body = name(B, "module")
        self._module_quat_applied = None
        self._has_contacts = floor_height_m is not None or bool(self.objects)
        self._floor_geom = name(G, "floor")
        self._module_geom = name(G, "module_housing")
        self._object_body = {o.spec.name: name(B, o.spec.name) for o in self.objects}
        self._geom_object = {}
        for o in self.objects:
            bid = self._object_body[o.spec.name]
            for g in range(m.ngeom):  # the object's own geoms and those of its moving parts (a door's leaf)
                if m.geom_bodyid[g] == bid or m.body_rootid[m.geom_bodyid[g]] == bid:
                    self._geom_object[g] = o.spec.name
        self._chain_geoms = set(self._link_geom.tolist())
        self._secured_window_s = secured_window_s
        self._start = (initial, airborne, seed, initial_noise_rad)
        self._module_max_step2_m2 = p.module_max_step_m ** 2
        self._module_qpos_view = self.data.qpos[self._module_qpos:self._module_qpos + 3]  # views into MjData
        self._module_qvel_view = self.data.qvel[self._module_dof:self._module_dof + 3]
        self._module_dp_buf = np.zeros(3)
        self._inv_timestep_hz = 1.0 / p.timestep_s
        self._force6 = np.zeros(6)
        self._warning_badqacc = self.data.warning[mujoco.mjtWarning.mjWARN_BADQACC]
        self.reset()

    def reset(self) -> None:
        """Back to the start the plant was built with (pose, airborne or at rest, seeded initial noise): the plant
        contract's reset (plants/contract.py)."""
        initial, airborne, seed, initial_noise_rad = self._start
        p, n = self.params, self.params.n_links
        mujoco.mj_resetData(self.model, self.data)
        self.lift_state = LiftState(takeoff_speed_mps=p.takeoff_speed_mps, lift_ramp_s=p.lift_ramp_s,
                                    lift=1.0 if airborne else 0.0)
        self._monitors = {
            o.spec.name: SecuredMonitor(drag_force_n=max(self.params.floor_friction, o.spec.friction)
                                        * o.spec.mass_kg * 9.81, window_s=self._secured_window_s)
            for o in self.objects if o.spec.free}
        self._link_len_m = -1.0
        self._lift_applied = -1.0
        self._steps = 0
        self._warn_badqacc = int(self._warning_badqacc.number)
        self._inputs = initial
        self._inputs_applied = None
        self._module_quat_applied = None
        if hasattr(self, "_target_time_s"):
            del self._target_time_s
        self._apply_inputs(initial)
        self._place_module()
        if airborne:
            # the whole chain (both branches) starts on the target contour
            q = self.targets.joint_targets(self._phi_rad, speed_index=self._speed_index(initial.rope_speed_mps))
            self.data.qpos[self._inplane_qpos] = q
        else:
            self.data.qpos[self._inplane_qpos] = self._rest_angles()
        rng = np.random.default_rng(seed)
        if initial_noise_rad > 0:
            self.data.qpos[self._inplane_qpos] += rng.normal(0.0, initial_noise_rad, n)
            self.data.qpos[self._outplane_qpos] += rng.normal(0.0, initial_noise_rad, n)
        self._apply_drives()
        mujoco.mj_forward(self.model, self.data)

    # --- inputs ----------------------------------------------------------------------------
    def _speed_index(self, rope_speed_mps: float) -> int:
        return self.targets.speed_index(abs(rope_speed_mps))

    def _apply_inputs(self, inputs: PlantInputs) -> None:
        if inputs is self._inputs_applied or inputs == self._inputs_applied:
            return
        p = self.params
        self._inputs = inputs
        self._inputs_applied = inputs
        self._base_pos_target = np.asarray(inputs.base_pos_m, dtype=float) - self._carriage_origin_m
        quat = tuple(float(x) for x in inputs.base_quat_wxyz)
        if quat != self._module_quat_applied:
            self.model.body_quat[self._module_body] = quat
            self._module_quat_applied = quat
        self._phi_rad = base_inclination_rad(np.asarray(inputs.base_quat_wxyz))
        self._loop_length_m = p.loop_length_m(inputs.guide_position_mm)
        self._set_link_length(self._loop_length_m / p.n_links)
        s = self._speed_index(inputs.rope_speed_mps)
        ret = self._loop_length_m * self.targets.return_point_per_m(self._phi_rad, speed_index=s)
        self.model.site_pos[self._return_site] = (ret[0], 0.0, ret[1])
        if self._closure_eq >= 0:  # connect anchors: body1 (last link) frame, then body2 (module) frame
            self.model.eq_data[self._closure_eq, 0:6] = (self._link_len_m, 0.0, 0.0, ret[0], 0.0, ret[1])
        self._ctrl_targets = self.targets.joint_targets(self._phi_rad, speed_index=s)

    def _set_link_length(self, link_len_m: float) -> None:
        if link_len_m == self._link_len_m:
            return
        m = self.model
        r = self.params.rope_radius_m
        m.body_pos[self._link_body[1:], 0] = link_len_m
        m.geom_pos[self._link_geom, 0] = link_len_m / 2
        m.geom_size[self._link_geom, 1] = link_len_m / 2
        m.geom_rbound[self._link_geom] = r + link_len_m / 2
        m.geom_aabb[self._link_geom, 5] = r + link_len_m / 2
        m.site_pos[self._end_site, 0] = link_len_m
        rv = self.params.visual_rope_radius_m
        m.geom_pos[self._visual_geom, 0] = link_len_m / 2
        m.geom_size[self._visual_geom, 1] = link_len_m / 2
        m.geom_rbound[self._visual_geom] = rv + link_len_m / 2
        m.geom_aabb[self._visual_geom, 5] = rv + link_len_m / 2
        self._link_len_m = link_len_m

    def _apply_drives(self) -> None:
        a = self.lift_state.lift
        if a != self._lift_applied and self._closure_eq >= 0:
            # the closure constraint carries loads whenever something can touch the loop; a flying loop
            # in a scene without floor or objects is closed by the tendon spring alone (the
            # constraint costs ~40 % of a step at N = 20)
            self.data.eq_active[self._closure_eq] = a < 1.0 or self._has_contacts
        if a != self._lift_applied and self._drive_act.size:
            m = self.model
            kp = a * self._drive_kp
            m.actuator_gainprm[self._drive_act, 0] = kp
            m.actuator_biasprm[self._drive_act, 1] = -kp
            m.actuator_biasprm[self._drive_act, 2] = -a * self._drive_kd
            # drive armature = kd h: the constraint solver sees the inertia the implicit drive damping
            # gives the joint within one step (see docs/chain_model.md, "contact on the driven branch")
            m.dof_armature[self._drive_dof] = (self._base_armature
                                               + a * self._drive_kd * self.params.timestep_s
                                               * self.params.drive_armature_factor)
        self._lift_applied = a
        if self._drive_act.size:
            self.data.ctrl[self._drive_act] = self._ctrl_targets[self._drive_joint]

    def _place_module(self) -> None:
        """Put the module at the commanded position at once, at rest (construction, re-placement)."""
        self._module_qpos_view[:] = self._base_pos_target
        self._module_qvel_view[:] = 0.0

    def _move_module(self) -> None:
        """Prescribed module motion: the velocity that brings the module from its present position to the
        commanded one in this step (constant over the step), so that the rope and the housing move with a
        velocity the contact solver sees. A mocap body is teleported with zero velocity: a contact it
        drives into an object then settles at a penetration of about 2 x solref time constant x speed
        (6 mm at 0.15 m/s), more than the rope's radius (docs/chain_model.md, "Rope on the floor").
        A commanded position farther away than module_max_step_m is a re-placement: applied at once, at
        rest."""
        dp = self._module_dp_buf
        np.subtract(self._base_pos_target, self._module_qpos_view, out=dp)
        if dp @ dp > self._module_max_step2_m2:
            self._place_module()
            return
        np.multiply(dp, self._inv_timestep_hz, out=self._module_qvel_view)

    def _rest_angles(self) -> np.ndarray:
        """The loop at rest: collapsed into a doubled line along the launch axis, the upper branch out,
        the lower branch folded back under it to end at the return point."""
        n, n_up = self.params.n_links, self.params.n_upper
        q = np.zeros(n)
        ret = self.model.site_pos[self._return_site]
        half = self._link_len_m * max(n_up, n - n_up)
        delta = 2.0 * math.asin(min(1.0, abs(ret[2]) / (2.0 * half)))
        q[n_up] = -(math.pi - delta)
        return q

    # --- stepping --------------------------------------------------------------------------
    @property
    def time_s(self) -> float:
        return self._steps * self.params.timestep_s

    def step(self, inputs: PlantInputs | None = None) -> None:
        """One MuJoCo step with ``inputs`` (or the last inputs)."""
        if inputs is not None:
            if not isinstance(inputs, PlantInputs):
                raise ChainModelError(f"inputs: expected PlantInputs, got {type(inputs).__name__}")
            self._apply_inputs(inputs)
        self.lift_state.step(self._inputs.rope_speed_mps, self.params.timestep_s)
        self._apply_drives()
        self._move_module()
        mujoco.mj_step(self.model, self.data)
        self._steps += 1
        self._check_divergence()

    def update(self, inputs: PlantInputs, dt_s: float) -> PlantOutputs:
        """The plant contract (plants/contract.py): advance dt_s with ``inputs`` held (whole MuJoCo steps; the
        clock keeps the remainder, as advance() does); the outputs at the end."""
        if not isinstance(inputs, PlantInputs):
            raise ChainModelError(f"inputs: expected PlantInputs, got {type(inputs).__name__}")
        self.advance(inputs, duration_s=dt_s)
        return self.outputs()

    def advance(self, inputs: PlantInputs | None = None, *, duration_s: float) -> int:
        """Step until the clock is nearest to (start + duration_s); returns the number of steps."""
        if not (duration_s >= 0 and math.isfinite(duration_s)):
            raise ChainModelError(f"duration_s: expected a finite duration >= 0, got {duration_s}")
        if inputs is not None:
            if not isinstance(inputs, PlantInputs):
                raise ChainModelError(f"inputs: expected PlantInputs, got {type(inputs).__name__}")
            self._apply_inputs(inputs)
        self._target_time_s = getattr(self, "_target_time_s", self.time_s) + duration_s
        n = int(math.floor(self._target_time_s / self.params.timestep_s - self._steps + 0.5))
        for _ in range(max(n, 0)):
            self.step()
        return max(n, 0)

    def _check_divergence(self) -> None:
        d = self.data
        bad = self._warning_badqacc.number
        if bad != self._warn_badqacc:
            self._warn_badqacc = int(bad)
            raise ChainDivergenceError(time_s=self.time_s, reason="badqacc",
                                       detail="MuJoCo reset the state after a non-finite acceleration")
        vmax = float(np.abs(d.qvel).max())
        if not vmax < MAX_JOINT_SPEED_RAD_S:  # also catches NaN
            if not np.all(np.isfinite(d.qpos)) or not np.all(np.isfinite(d.qvel)):
                raise ChainDivergenceError(time_s=self.time_s, reason="nonfinite", detail="qpos/qvel not finite")
            raise ChainDivergenceError(time_s=self.time_s, reason="velocity",
                                       detail=f"joint speed {vmax:.3g} (rad|m)/s > {MAX_JOINT_SPEED_RAD_S:g}")

    # --- named outputs ---------------------------------------------------------------------
    @property
    def phi_rad(self) -> float:
        return self._phi_rad

    @property
    def lift(self) -> float:
        return self.lift_state.lift

    def loop_length_m(self) -> float:
        return self._loop_length_m

    def link_length_m(self) -> float:
        return self._link_len_m

    def chain_points_m(self) -> np.ndarray:
        """Link joint points from the exit to the last link's end, shape (N + 1, 3), world frame."""
        d = self.data
        return np.vstack([d.xpos[self._link_body], d.site_xpos[self._end_site[-1]][None, :]])

    def chain_points_loop_plane_m(self) -> np.ndarray:
        """Chain points in the table frame: (x, z) from the exit, x horizontal along the launch
        direction, z up; shape (N + 1, 2)."""
        pts = self.chain_points_m() - self.data.site_xpos[self._exit_site]
        mat = self.data.xmat[self.model.site_bodyid[self._exit_site]].reshape(3, 3)
        fwd = mat[:, 0].copy()
        fwd[2] = 0.0
        fwd /= np.linalg.norm(fwd)
        return np.column_stack([pts @ fwd, pts[:, 2]])

    def module_pos_m(self) -> np.ndarray:
        """Module (exit point) position, world frame, shape (3,), metres."""
        return self._carriage_origin_m + self._module_qpos_view

    def module_velocity_mps(self) -> np.ndarray:
        """Module linear velocity (world frame, m/s, shape (3,)): the commanded motion over the last step."""
        return self._module_qvel_view.copy()

    def module_quat_wxyz(self) -> np.ndarray:
        """Module orientation, shape (4,) (set directly from the inputs)."""
        return self.model.body_quat[self._module_body].copy()

    def exit_pos_m(self) -> np.ndarray:
        return self.data.site_xpos[self._exit_site].copy()

    def return_pos_m(self) -> np.ndarray:
        return self.data.site_xpos[self._return_site].copy()

    def loop_tip_pos_m(self) -> np.ndarray:
        pts = self.chain_points_m()
        k = int(np.argmax(np.linalg.norm(pts - self.exit_pos_m(), axis=1)))
        return pts[k].copy()

    def closure_gap_m(self) -> float:
        d = self.data
        return float(np.linalg.norm(d.site_xpos[self._end_site[-1]] - d.site_xpos[self._return_site]))

    def joint_targets_rad(self) -> np.ndarray:
        """Current in-plane targets, shape (N,) (only the driven upper branch is servoed)."""
        return self._ctrl_targets.copy()

    def inplane_angles_rad(self) -> np.ndarray:
        return self.data.qpos[self._inplane_qpos].copy()

    def outplane_angles_rad(self) -> np.ndarray:
        return self.data.qpos[self._outplane_qpos].copy()

    def object_pos_m(self, name: str) -> np.ndarray:
        return self.data.xpos[self._body(name)].copy()

    def object_com_m(self, name: str) -> np.ndarray:
        """Centre of mass of an object (world, m): unlike the body origin it does not move when the
        object only rolls in place."""
        return self.data.xipos[self._body(name)].copy()

    def object_quat_wxyz(self, name: str) -> np.ndarray:
        return self.data.xquat[self._body(name)].copy()

    def _body(self, name: str) -> int:
        try:
            return self._object_body[name]
        except KeyError:
            raise ChainModelError(f"name: expected one of the scene objects {sorted(self._object_body)}, "
                                  f"got {name!r}") from None

    def contact_forces_n(self) -> tuple[dict, dict, float]:
        """Normal contact forces: (chain->object per object, module->object per object, chain<->floor), N."""
        c = self.contact_summary()
        return c.chain_on_object_n, c.module_on_object_n, c.chain_on_floor_n

    def chain_object_net_force_n(self) -> dict:
        """Net force (normal + friction) of the chain on each object, {name: shape (3,) world}, N."""
        return self.contact_summary().chain_net_on_object_n

    def contact_summary(self) -> ContactSummary:
        """Every contact force of the chain, the module and the objects now, in one pass over the contacts
        (for a caller that needs several of them each step, e.g. the SIL bridge)."""
        d = self.data
        chain_obj = {k: 0.0 for k in self._object_body}
        module_obj = {k: 0.0 for k in self._object_body}
        net = {k: np.zeros(3) for k in self._object_body}
        chain_floor = 0.0
        for i in range(d.ncon):
            c = d.contact[i]
            g1, g2 = int(c.geom1), int(c.geom2)
            in_chain = (g1 in self._chain_geoms, g2 in self._chain_geoms)
            obj = self._geom_object.get(g1) or self._geom_object.get(g2)
            if not (any(in_chain) or obj or self._module_geom in (g1, g2)):
                continue
            mujoco.mj_contactForce(self.model, d, i, self._force6)
            fn = abs(float(self._force6[0]))
            if any(in_chain) and obj:
                chain_obj[obj] += fn
                # contact frame rows: normal (geom1 -> geom2), tangents; the force acts on geom2
                f_world = c.frame.reshape(3, 3).T @ self._force6[:3]
                net[obj] += f_world if g2 in self._geom_object else -f_world
            elif any(in_chain) and self._floor_geom in (g1, g2):
                chain_floor += fn
            elif obj and self._module_geom in (g1, g2):
                module_obj[obj] += fn
        return ContactSummary(chain_on_object_n=chain_obj, module_on_object_n=module_obj, chain_on_floor_n=chain_floor,
                              chain_net_on_object_n=net)

    def rope_contacts(self, name: str) -> list[RopeContact]:
        """The rope's contacts with one object now: tilt, forces, friction use, slip (rope_contacts.py)."""
        body = self._body(name)
        geoms = {g for g, obj in self._geom_object.items() if obj == name}
        return rope_object_contacts(self.model, self.data, link_geoms=self._link_geom, object_geoms=geoms,
                                    object_body=body)

    def rope_tension_n(self) -> float:
        """Load on the closure, N: the constraint force when the closure constraint is active, else the
        tendon spring force."""
        d = self.data
        if self._closure_eq >= 0 and d.eq_active[self._closure_eq]:
            for i in range(d.nefc):
                if d.efc_type[i] == mujoco.mjtConstraint.mjCNSTR_EQUALITY and d.efc_id[i] == self._closure_eq:
                    # connect: three rows (x, y, z); collect their forces
                    return float(np.linalg.norm(d.efc_force[i:i + 3]))
            return 0.0
        return float(abs(d.ten_length[0] * self.model.tendon_stiffness[0]))

    def outputs(self) -> PlantOutputs:
        """Named outputs now; also feeds each object's SecuredMonitor (call it once per bridge tick)."""
        contacts = self.contact_summary()
        chain_obj, module_obj, chain_floor = (contacts.chain_on_object_n, contacts.module_on_object_n,
                                              contacts.chain_on_floor_n)
        net = contacts.chain_net_on_object_n
        base = self.module_pos_m()
        for name, mon in self._monitors.items():
            mon.update(time_s=self.time_s, object_com_m=self.object_com_m(name), base_pos_m=base,
                       chain_force_n=float(np.linalg.norm(net[name])))
        return PlantOutputs(
            time_s=self.time_s, loop_tip_pos_m=self.loop_tip_pos_m(), closure_gap_m=self.closure_gap_m(),
            loop_length_m=self._loop_length_m, phi_rad=self._phi_rad, lift=self.lift,
            chain_object_force_n=chain_obj, module_object_force_n=module_obj, chain_floor_force_n=chain_floor,
            object_pos_m={k: self.object_pos_m(k) for k in self._object_body},
            object_quat_wxyz={k: self.object_quat_wxyz(k) for k in self._object_body},
            chain_object_net_force_n=net,
            object_secured={k: m.secured for k, m in self._monitors.items()},
            rope_tension_n=self.rope_tension_n())
