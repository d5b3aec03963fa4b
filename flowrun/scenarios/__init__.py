"""Flow's old name for networks: ``flowrun.scenarios.loop.LoopScenario`` is the ring."""
