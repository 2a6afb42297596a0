"""RoboWrangler host package: protocol codec, transports, client API, CLI, recorder."""
