"""Every number of the rope-loop chain model, with units, defaults and where each comes from.

Interpretation of the paper's IsaacGym model (details and reasons in docs/chain_model.md):
in IsaacGym a DOF's "stiffness" and "damping" are the gains of its position drive,
``tau = stiffness * (q_target - q) - damping * qdot``. The paper's in-plane joints of the upper
branch have stiffness 1e4 N m/rad and damping 5e3 N m s/rad; "zero stiffness" joints (lower branch
in-plane, every out-of-plane joint) have no drive at all. We implement the drives as MuJoCo
``general`` actuators with the same gains (affine bias), integrated with ``implicitfast`` so that the
large drive damping is implicit, as PhysX's drives are.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, fields

from robowrangler_sim.chain.errors import ChainModelError
from robowrangler_sim.rope import RopeParams

N_LINKS_MIN = 10
N_LINKS_MAX = 80


@dataclass(frozen=True, kw_only=True)
class ChainParams:
    """Parameters of the chain plant (SI units, suffix names the unit).

    Geometry and rope:
        n_links: links in the chain, 10..80 (paper: 20).
        rope_length_m: total rope length (loop outside plus rope kept inside the device).
        rope_inside_at_home_m: rope inside the device when the guide is at 0 mm.
        guide_take_up_ratio: metres of rope drawn inside per metre of guide travel (2.0: the loop's two
            ends pass over the moving guide like a pulley; an assumption to re-measure on hardware).
        guide_stroke_mm: guide travel of the lead screw (hardware: 180 mm).
        rope: the rope's material, the one RopeParams of every model (robowrangler_sim/rope.py): its density
            gives the link masses (0.221 g/m: a 2 m / 20-link chain has 2.2e-5 kg links), its diameter the links'
            collision radius (rope_radius_m, 1 mm), its C_f the takeoff speed (takeoff_speed_mps, 2.6 m/s).
        visual_rope_radius_m: radius of the drawn rope (visual only, no contact, no mass).
    Drives (IsaacGym drive gains, see module doc):
        kp_upper_nm_per_rad, kd_upper_nms_per_rad: in-plane drives of the upper branch (1e4, 5e3).
        kp_lower_nm_per_rad, kd_lower_nms_per_rad: in-plane drives of the lower branch (0, 0).
        kp_out_of_plane_nm_per_rad, kd_out_of_plane_nms_per_rad: out-of-plane drives (0, 0).
        upper_branch_fraction: share of the in-plane joints, counted from the exit, in the upper branch.
    Closure:
        closure_stiffness_n_per_m, closure_damping_ns_per_m: the artificial spring (rest length 0)
            from the end of the last link to the return point on the module.
        closure_constraint_timeconst_s: if > 0, the closure is (also) a soft equality ``connect`` of the
            same two points with this MuJoCo solref time constant: a spring stiff enough to carry grasp
            loads that the constraint solver integrates stably (the explicit tendon spring cannot be
            stiff on 2e-5 kg links). 0 = tendon spring only.
    Numerics (stability choices, docs/chain_model.md):
        timestep_s: MuJoCo timestep.
        passive_damping_nms_per_rad: passive damping on the in-plane hinges (implicit; stabilises free links).
        out_of_plane_damping_nms_per_rad: passive damping on the out-of-plane hinges (stiffness stays 0, as
            in the paper). Air drag on a rope that runs axially at U has a normal force linear in the swing
            velocity, about 0.5 rho U (C_f pi d) per metre (rope.py: C_f pi d = 5.3e-4 m): at 4 m/s,
            1.3e-3 N s/m2, i.e. about 4e-4 N m s/rad for a 1 m arm swinging about a joint. 5e-4 stops the
            loop plane from swinging on after every leg move (the door handle's perturbed rollouts: 9/9 held
            instead of 4/9 with 1e-4); it does not restore the plane. docs/chain_model.md.
        armature_kgm2: rotor-like inertia added to every hinge (the links' own inertia is ~1e-8 kg m2).
        drive_armature_factor: driven joints get an extra armature of factor * lift * kd * timestep_s,
            the inertia their implicit drive damping has within one step, so that the contact solver
            does not answer the huge drive torques with huge forces on the light links (0 = off).
        module_mass_kg: mass of the module's carriage. Its position is prescribed (the robot's leg: the
            plant sets the slide velocities every step so that it reaches the commanded position at the end
            of the step), so that the rope and the housing move with a velocity the contact solver sees (a
            teleported mocap body has none). Rope loads deflect it a little within a step; the next step's
            velocity takes that back. Gravity-compensated. A numerical device, not the device's mass (1e4 kg
            was tried and made the solver chaotic).
        module_max_step_m: a commanded position farther than this from the present one (per step) is a
            re-placement, applied at once with zero velocity, not a motion (5 mm per 5 ms step = 1 m/s).
            The orientation is set directly (no angular velocity): no scenario turns the module while the
            rope touches something.
    Lift:
        lift_ramp_s: time for the lift factor to go 1 -> 0 (falling) or 0 -> 1 (rising).
    Contact:
        rope_friction: sliding friction of the rope links (MuJoCo takes the larger of a pair's values).
        floor_friction: sliding friction of the floor/table plane.
        rope_floor_clearance_m: the chain rests this far above the floor (contact margin of the explicit
            chain-floor pairs). 0: the rope lies on the floor and meets objects at their base. (It was
            10 mm while the module was a teleported mocap body: the rope was then driven 2-6 mm into
            objects and under their rims at floor level; docs/chain_model.md, "Rope on the floor".)
        contact_impedance_min, contact_impedance_max, contact_impedance_width_m: MuJoCo solimp of the
            rope's contacts (the rope's value dominates its pairs through solmix; objects, floor and
            module keep MuJoCo's default). MuJoCo scales a contact's softness with the effective mass it
            acts on; on 2e-5 kg links the default (0.9, 0.95, 1 mm) lets a heavy object squeeze the rope
            through the floor and under its rim. Impedance near 1 makes rope contacts nearly hard.
    """

    n_links: int = 20
    rope_length_m: float = 2.2
    rope_inside_at_home_m: float = 0.2
    guide_take_up_ratio: float = 2.0
    guide_stroke_mm: float = 180.0
    rope: RopeParams = field(default_factory=RopeParams)
    visual_rope_radius_m: float = 5.0e-3
    kp_upper_nm_per_rad: float = 1.0e4
    kd_upper_nms_per_rad: float = 5.0e3
    kp_lower_nm_per_rad: float = 0.0
    kd_lower_nms_per_rad: float = 0.0
    kp_out_of_plane_nm_per_rad: float = 0.0
    kd_out_of_plane_nms_per_rad: float = 0.0
    upper_branch_fraction: float = 0.5
    closure_stiffness_n_per_m: float = 20.0
    closure_damping_ns_per_m: float = 0.05
    closure_constraint_timeconst_s: float = 0.02
    timestep_s: float = 0.005
    passive_damping_nms_per_rad: float = 1.0e-4
    out_of_plane_damping_nms_per_rad: float = 5.0e-4
    armature_kgm2: float = 1.0e-5
    drive_armature_factor: float = 1.0
    module_mass_kg: float = 1.0
    module_max_step_m: float = 0.005
    lift_ramp_s: float = 0.2
    rope_friction: float = 0.3
    rope_floor_clearance_m: float = 0.0
    contact_impedance_min: float = 0.99
    contact_impedance_max: float = 0.9999
    contact_impedance_width_m: float = 0.001
    floor_friction: float = 0.6

    def __post_init__(self) -> None:
        if not isinstance(self.n_links, int) or isinstance(self.n_links, bool):
            raise ChainModelError(f"n_links: expected an int, got {type(self.n_links).__name__}")
        if not N_LINKS_MIN <= self.n_links <= N_LINKS_MAX:
            raise ChainModelError(
                f"n_links: expected {N_LINKS_MIN}..{N_LINKS_MAX}, got {self.n_links}")
        if not isinstance(self.rope, RopeParams):
            raise ChainModelError(f"rope: expected RopeParams, got {self.rope!r}")
        for f in fields(self):
            if f.name in ("n_links", "rope"):
                continue
            value = getattr(self, f.name)
            if not isinstance(value, (int, float)) or isinstance(value, bool) or not math.isfinite(value):
                raise ChainModelError(f"{f.name}: expected a finite number, got {value!r}")
            if value < 0:
                raise ChainModelError(f"{f.name}: expected >= 0, got {value}")
        for name in ("rope_length_m", "timestep_s", "guide_take_up_ratio", "module_mass_kg"):
            if getattr(self, name) <= 0:
                raise ChainModelError(f"{name}: expected > 0, got {getattr(self, name)}")
        if not 0.0 < self.upper_branch_fraction < 1.0:
            raise ChainModelError(
                f"upper_branch_fraction: expected in (0, 1), got {self.upper_branch_fraction}")
        if not (0.0 < self.contact_impedance_min <= self.contact_impedance_max < 1.0):
            raise ChainModelError(
                "contact_impedance_min/max: expected 0 < min <= max < 1, got "
                f"{self.contact_impedance_min}, {self.contact_impedance_max}")
        if self.timestep_s > 0.02:
            raise ChainModelError(f"timestep_s: expected <= 0.02 s, got {self.timestep_s}")
        if self.min_loop_length_m < 0.1:
            raise ChainModelError(
                "rope_length_m: expected a loop of at least 0.1 m at full guide stroke, got "
                f"{self.min_loop_length_m:.3f} m")

    # --- derived quantities ----------------------------------------------------------------
    @property
    def rope_linear_density_kg_per_m(self) -> float:
        """The rope's mass per metre (self.rope)."""
        return self.rope.linear_density_kg_per_m

    @property
    def rope_radius_m(self) -> float:
        """Collision radius of the chain links: half the rope's diameter."""
        return self.rope.radius_m

    @property
    def takeoff_speed_mps(self) -> float:
        """ToV: at and above it the loop is airborne (the rope's, in standard air: 2.6 m/s for the paper's rope)."""
        return self.rope.takeoff_speed_mps()

    @property
    def home_loop_length_m(self) -> float:
        """Loop length outside the device with the guide at 0 mm, metres."""
        return self.rope_length_m - self.rope_inside_at_home_m

    @property
    def min_loop_length_m(self) -> float:
        """Loop length with the guide at the end of its stroke, metres."""
        return self.home_loop_length_m - self.guide_take_up_ratio * self.guide_stroke_mm * 1e-3

    @property
    def n_upper(self) -> int:
        """Number of in-plane joints (from the exit) driven as the upper branch."""
        return max(1, min(self.n_links - 1, int(round(self.upper_branch_fraction * self.n_links))))

    @property
    def link_mass_kg(self) -> float:
        """Mass of one link at the home loop length, kg."""
        return self.rope_linear_density_kg_per_m * self.home_loop_length_m / self.n_links

    def loop_length_m(self, guide_position_mm: float) -> float:
        """Loop length outside the device for a guide position (0..guide_stroke_mm), metres."""
        if not math.isfinite(guide_position_mm) or not 0.0 <= guide_position_mm <= self.guide_stroke_mm:
            raise ChainModelError(
                f"guide_position_mm: expected 0..{self.guide_stroke_mm}, got {guide_position_mm}")
        return self.home_loop_length_m - self.guide_take_up_ratio * guide_position_mm * 1e-3
