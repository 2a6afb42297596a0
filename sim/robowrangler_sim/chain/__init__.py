"""The paper's rope-loop chain model in MuJoCo (issue 5): builder, parameters, plant, objects, accuracy.

Entry points: ChainParams (params.py), ChainPlant / PlantInputs (plant.py), OBJECTS (objects.py),
steady_state_accuracy (accuracy.py), render_frames / write_mp4 (render.py).
"""

from robowrangler_sim.chain.errors import ChainDivergenceError, ChainModelError
from robowrangler_sim.chain.params import ChainParams
from robowrangler_sim.chain.plant import ChainPlant, PlantInputs, PlantOutputs, pitch_quat_wxyz

__all__ = ["ChainDivergenceError", "ChainModelError", "ChainParams", "ChainPlant", "PlantInputs",
           "PlantOutputs", "pitch_quat_wxyz"]
