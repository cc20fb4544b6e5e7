"""The dm_control suite quadruped: its spec ``dm-quadruped.toml`` points at
``dm_control/suite/quadruped.xml`` in the ``dm-control`` wheel (Apache-2.0; extra
``[robots]``). No code capabilities."""
