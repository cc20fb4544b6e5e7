"""evomotion: evolve and search robot motions (gaits, steps, kicks, reaches, plans, paths)."""

__version__ = "0.1.0"
