"""The dm_control suite humanoid: its spec ``dm-humanoid.toml`` points at
``dm_control/suite/humanoid.xml`` in the ``dm-control`` wheel (Apache-2.0; extra
``[robots]``). No code capabilities."""
