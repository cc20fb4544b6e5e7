"""Scenes built on the NAO MJCF: extra bodies and sensors added to :func:`model_xml`.

The NAO files are not edited: :func:`scene_xml` inserts MJCF fragments (bodies before the end
of ``<worldbody>``, sensors in a second ``<sensor>`` block after the model's own sole
``framepos`` sensors), so the model's sensors keep their order and come first.
:data:`SOLE_SENSORS` adds per sole the ``contact`` sensor with the floor reduced to the net
force (``found, force[3], pos[3]``; MuJoCo XML reference, ``sensor/contact``) and the sole
site's ``framexaxis``.
"""

from __future__ import annotations

import mujoco

from evomotion.sim.robots.nao.model import model_xml

SOLE_SENSORS = """<contact name="l_contact" geom1="l_sole" geom2="floor" data="found force pos" reduce="netforce"/>
<contact name="r_contact" geom1="r_sole" geom2="floor" data="found force pos" reduce="netforce"/>
<framexaxis name="l_xaxis" objtype="site" objname="l_sole_site"/>
<framexaxis name="r_xaxis" objtype="site" objname="r_sole_site"/>
"""  # noqa: E501 - MJCF lines


def scene_xml(bodies: str = "", sensors: str = "") -> str:
    """The NAO MJCF with ``bodies`` (MJCF ``<body>`` elements) added to the world and
    ``sensors`` (MJCF sensor elements) added after the model's own sensors."""
    xml = model_xml()
    if bodies:
        xml = xml.replace("</worldbody>", bodies + "</worldbody>", 1)
    if sensors:
        end = xml.rindex("</mujoco>")
        xml = xml[:end] + "<sensor>\n" + sensors + "</sensor>\n</mujoco>"
    return xml


def sensor_slices(model: mujoco.MjModel) -> dict[str, slice]:
    """Slices of ``sensordata`` by sensor name."""
    out = {}
    for i in range(model.nsensor):
        adr, dim = model.sensor_adr[i], model.sensor_dim[i]
        out[model.sensor(i).name] = slice(int(adr), int(adr + dim))
    return out
