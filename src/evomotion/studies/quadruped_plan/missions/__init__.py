"""Missions: a walk replanned as the world is discovered (events, recovery, one-shot
baseline, the mission document, driver and experiment)."""
