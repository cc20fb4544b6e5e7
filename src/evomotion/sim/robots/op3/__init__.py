"""ROBOTIS OP3: ``op3.xml`` (authored in this project from ROBOTIS's published link data;
sources in ``README.md`` here, ``check_op3.py`` its standalone check) and its spec
``op3.toml``. No code capabilities: the studies drive it through the generic robot code
(numerical leg IK, joint-space gait)."""
