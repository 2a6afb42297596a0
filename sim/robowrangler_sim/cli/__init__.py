"""The simulator's `wrangler` verbs (plugins of the host CLI)."""
