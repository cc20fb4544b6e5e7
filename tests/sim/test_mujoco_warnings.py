"""MuJoCo's warnings never write MUJOCO_LOG.TXT into the current folder."""

from __future__ import annotations

import subprocess
import sys


def test_warnings_go_to_the_logger_not_a_file(tmp_path):
    code = ("import evomotion.sim, mujoco\n"
            "mujoco.MjModel.from_xml_string('<mujoco><worldbody><body pos=\"nan 0 0\">"
            "<geom size=\"0.1\"/></body></worldbody></mujoco>')\n")
    r = subprocess.run([sys.executable, "-c", code], cwd=tmp_path, capture_output=True,
                       text=True, timeout=60)
    assert r.returncode == 0, r.stderr
    assert "MuJoCo: XML contains a 'NaN'" in r.stderr
    assert list(tmp_path.iterdir()) == []
