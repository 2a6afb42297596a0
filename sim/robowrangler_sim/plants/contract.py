"""The plant contract: every plant is a small model with one ``update`` (as ArduPilot SITL's aircraft models are).

    outputs = plant.update(inputs, dt_s)

``inputs`` and ``outputs`` are frozen dataclasses with SI (or raw register) fields whose names carry their units;
``update`` advances the plant's own clock by ``dt_s`` seconds with the inputs held over the step and returns the
outputs at its end. ``outputs()`` reads them without stepping; ``reset()`` goes back to power-up. Whatever composes
plants (the SIL session, the chain bridge, diagnosis replaying a recording, a batched fit) does it through these
three methods and the dataclasses, never through a plant's internals. A plant that meets the contract plugs into
SilSession through its constructor (``SilSession(drive=..., spindle=...)``).

The plants and their dataclasses:
    drive    DrivePlant      DriveInputs   -> DriveOutputs     (plants/drive.py)
    spindle  SpindlePlant    SpindleInputs -> SpindleOutputs   (plants/spindle.py)
    chain    ChainPlant      PlantInputs   -> PlantOutputs     (chain/plant.py)
docs/architecture.md shows how the SIL session composes them.
"""

from __future__ import annotations

from typing import Protocol, TypeVar, runtime_checkable

InputsT = TypeVar("InputsT", contravariant=True)
OutputsT = TypeVar("OutputsT", covariant=True)


@runtime_checkable
class Plant(Protocol[InputsT, OutputsT]):
    """A plant: ``update(inputs, dt_s) -> outputs``, ``outputs()``, ``reset()``."""

    def update(self, inputs: InputsT, dt_s: float) -> OutputsT:
        """Advance dt_s seconds with ``inputs`` held; the outputs at the end of the step."""
        ...

    def outputs(self) -> OutputsT:
        """The outputs now, without stepping."""
        ...

    def reset(self) -> None:
        """Back to power-up (the seed the plant was built with)."""
        ...
