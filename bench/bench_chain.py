"""Benchmark of the chain plant: simulated seconds per wall second, one core, and batch rollouts.

Prints (never asserts):
  * for N = 20 / 40 / 80, free air (airborne, no contact) and contact (loop fallen on the floor,
    20-40 chain-floor contacts): real-time factor of (a) bare mj_step on the plant's model (column
    "mj_step RTF", the README's chain figure), (b) ChainPlant.step (column "plant RTF": the per-step
    Python work: lift, phi, targets, gains, divergence check) and (c) ChainPlant.update(inputs, h), one
    step through the plant contract with its PlantOutputs (column "update RTF": what the SIL's chain
    bridge runs per chain step);
  * mujoco.rollout on 2 threads: rollouts per second (1 s each, open-loop drive targets) and the
    speed-up over 1 thread.
The full SIL figure (firmware + plant, lockstep) belongs to the SIL bridge and is not measured here.

Run:  uv run python bench/bench_chain.py [--quick]
"""

from __future__ import annotations

import argparse
import math
import os
import time

import mujoco
import numpy as np
from mujoco import rollout

from robowrangler_sim.chain.params import ChainParams
from robowrangler_sim.chain.plant import ChainPlant, PlantInputs, pitch_quat_wxyz
from robowrangler_sim.chain.synthetic_table import synthetic_ellipse_table


def _plant(n_links: int, *, contact: bool) -> tuple[ChainPlant, PlantInputs]:
    table = synthetic_ellipse_table()
    pos = (0.0, 0.0, 0.25) if contact else (0.0, 0.0, 0.6)
    quat = pitch_quat_wxyz(math.radians(30 if contact else -10))
    up = PlantInputs(rope_speed_mps=5.0, base_pos_m=pos, base_quat_wxyz=quat)
    plant = ChainPlant(table=table, params=ChainParams(n_links=n_links), initial=up,
                       floor_height_m=0.0 if contact else None)
    if contact:
        down = PlantInputs(rope_speed_mps=1.0, base_pos_m=pos, base_quat_wxyz=quat)
        plant.advance(down, duration_s=2.5)
        return plant, down
    plant.advance(up, duration_s=0.5)
    return plant, up


def _rtf_mj_step(plant: ChainPlant, wall_s: float) -> tuple[float, float]:
    m, d = plant.model, plant.data
    n, t0 = 0, time.perf_counter()
    while time.perf_counter() - t0 < wall_s:
        for _ in range(200):
            mujoco.mj_step(m, d)
        n += 200
    el = time.perf_counter() - t0
    return n * m.opt.timestep / el, el / n * 1e6


def _rtf_plant(plant: ChainPlant, inputs: PlantInputs, wall_s: float) -> tuple[float, float]:
    n, t0 = 0, time.perf_counter()
    while time.perf_counter() - t0 < wall_s:
        for _ in range(200):
            plant.step(inputs)
        n += 200
    el = time.perf_counter() - t0
    return n * plant.params.timestep_s / el, el / n * 1e6


def _rtf_update(plant: ChainPlant, inputs: PlantInputs, wall_s: float) -> tuple[float, float]:
    h_s = plant.params.timestep_s
    n, t0 = 0, time.perf_counter()
    while time.perf_counter() - t0 < wall_s:
        for _ in range(200):
            plant.update(inputs, h_s)
        n += 200
    el = time.perf_counter() - t0
    return n * h_s / el, el / n * 1e6


def _rollouts_per_s(n_links: int, *, nbatch: int, nthread: int, horizon_s: float = 1.0) -> float:
    plant, _ = _plant(n_links, contact=False)
    m = plant.model
    nstep = int(round(horizon_s / m.opt.timestep))
    spec = mujoco.mjtState.mjSTATE_FULLPHYSICS
    state0 = np.empty(mujoco.mj_stateSize(m, spec))
    mujoco.mj_getState(m, plant.data, state0, spec)
    rng = np.random.default_rng(0)
    init = np.repeat(state0[None, :], nbatch, axis=0)
    ctrl = plant.data.ctrl[None, None, :] + rng.normal(0.0, 0.05, (nbatch, 1, m.nu))
    ctrl = np.repeat(ctrl, nstep, axis=1)
    datas = [mujoco.MjData(m) for _ in range(nthread)]
    rollout.rollout(m, datas, init[:2], ctrl[:2], nstep=nstep)  # warm-up
    t0 = time.perf_counter()
    rollout.rollout(m, datas, init, ctrl, nstep=nstep)
    return nbatch / (time.perf_counter() - t0)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--quick", action="store_true", help="shorter timing windows")
    args = ap.parse_args()
    wall = 0.5 if args.quick else 2.0
    print(f"machine: {os.cpu_count()} cores, MuJoCo {mujoco.__version__}, timestep "
          f"{ChainParams().timestep_s * 1e3:.0f} ms, implicitfast")
    print(f"{'N':>3} {'case':>8} {'mj_step us':>11} {'mj_step RTF':>12} {'plant us':>9} {'plant RTF':>10} "
          f"{'update us':>9} {'update RTF':>10} {'contacts':>8}")
    for n in (20, 40, 80):
        for contact in (False, True):
            plant, inputs = _plant(n, contact=contact)
            ncon = plant.data.ncon
            rtf_p, us_p = _rtf_plant(plant, inputs, wall)
            rtf_u, us_u = _rtf_update(plant, inputs, wall)
            rtf_m, us_m = _rtf_mj_step(plant, wall)
            print(f"{n:>3} {'contact' if contact else 'free':>8} {us_m:>11.1f} {rtf_m:>11.0f}x {us_p:>9.1f} "
                  f"{rtf_p:>9.0f}x {us_u:>9.1f} {rtf_u:>9.0f}x {ncon:>8}")
    nbatch = 32 if args.quick else 128
    for n in (20, 40):
        r1 = _rollouts_per_s(n, nbatch=nbatch, nthread=1)
        r2 = _rollouts_per_s(n, nbatch=nbatch, nthread=2)
        print(f"rollout N={n}: {nbatch} x 1 s open-loop: {r1:.1f}/s on 1 thread, {r2:.1f}/s on 2 threads "
              f"({r2 / r1:.2f}x)")


if __name__ == "__main__":
    main()
