"""RoboWrangler simulator: plants, SIL bridge, chain model, diagnosis."""
