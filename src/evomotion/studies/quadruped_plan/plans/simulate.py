"""A plan or an executed walk on the simulated quadruped (:mod:`evomotion.sim.quadruped`).

``evomotion quadruped-plan simulate RUN_OR_PLAN [--video FILE] [--json]`` reads a
``plan.json`` / ``mission.json`` (or the run folder holding one), builds the MuJoCo robot to
the plan's model dimensions (one paper unit = 0.1 m) and executes every transition
quasi-statically; it reports whether the body stayed up, the least support margin measured
from the foot contact forces and the final pose error. The video draws the world's
obstacles (grey walls) and no-step zones (orange) as visual-only outlines: they are not
simulated (the plan keeps the body clear of them; a leg may reach over an obstacle).
"""

from __future__ import annotations

import math
from pathlib import Path
from typing import Any

from evomotion.errors import InputError
from evomotion.outfile import check_target
from evomotion.sim.quadruped import QuadrupedSpec, execute_plan
from evomotion.sim.quadruped.execute import (
    FINAL_SECONDS,
    LEG_SECONDS,
    MAX_SECONDS,
    METRES_PER_SECOND,
    RADIANS_PER_SECOND,
    SETTLE_SECONDS,
)
from evomotion.sim.quadruped.trajectory import plan_seconds

OUTLINE_HEIGHT_M = {"obstacle": 0.06, "nostep": 0.002}
OUTLINE_RGBA = {"obstacle": [0.45, 0.45, 0.45, 1.0], "nostep": [0.95, 0.55, 0.1, 1.0]}


def spec_for(doc: dict[str, Any]) -> QuadrupedSpec:
    """The simulated robot for the plan's model (ValueError: it cannot be built so)."""
    m = doc["model"]
    return QuadrupedSpec(a=m["a"], b=m["b"], l_min=m["l_min"], l_max=m["l_max"],
                         sector_half_width=m["sector_half_width"])


def check_document(doc: dict[str, Any], source: str | Path = "plan") -> QuadrupedSpec:
    """The robot for ``doc`` after checking, before any simulation, that it can be built and
    that the execution stays within ``MAX_SECONDS`` simulated seconds; one-line
    :class:`InputError` naming ``source`` otherwise."""
    try:
        spec = spec_for(doc)
    except ValueError as e:
        raise InputError(f"{source}: model: the simulated robot cannot be built to these "
                         f"dimensions ({e})") from None
    secs = plan_seconds(spec, doc["states"], leg_seconds=LEG_SECONDS,
                        metres_per_second=METRES_PER_SECOND,
                        radians_per_second=RADIANS_PER_SECOND, settle_seconds=SETTLE_SECONDS,
                        final_seconds=FINAL_SECONDS)
    if secs > MAX_SECONDS:
        raise InputError(f"{source}: states: the execution would last {secs:.4g} simulated "
                         f"seconds, at most {MAX_SECONDS:g}")
    return spec


def scene_xml(doc: dict[str, Any], spec: QuadrupedSpec) -> str:
    """The robot's MJCF with the world's polygons as visual-only outlines."""
    import mujoco

    from evomotion.sim.quadruped.model import build_spec

    mj = build_spec(spec)
    k = 0
    for p in (doc.get("world") or {}).get("polygons", []):
        pts = p["points"]
        height = OUTLINE_HEIGHT_M[p["kind"]]
        for (ax, ay), (bx, by) in zip(pts, pts[1:] + pts[:1]):
            ax, ay, bx, by = (v * spec.unit_m for v in (ax, ay, bx, by))
            length = math.hypot(bx - ax, by - ay)
            if length == 0:
                continue
            angle = math.atan2(by - ay, bx - ax)
            mj.worldbody.add_geom(
                name=f"outline_{k}", type=mujoco.mjtGeom.mjGEOM_BOX,
                size=[length / 2, 0.004, height / 2], pos=[(ax + bx) / 2, (ay + by) / 2,
                                                          height / 2],
                quat=[math.cos(angle / 2), 0, 0, math.sin(angle / 2)],
                rgba=OUTLINE_RGBA[p["kind"]], contype=0, conaffinity=0, mass=0.0,
                density=0.0)
            k += 1
    mj.compile()
    return mj.to_xml()


def simulate_document(doc: dict[str, Any], video: Path | None = None, speed: float = 8.0,
                      source: str | Path = "plan") -> dict[str, Any]:
    """Execute the document's states; ``video``: also render an MP4 there (checked before
    the simulation, written atomically: no partial video survives a failure)."""
    spec = check_document(doc, source)
    if video is not None:
        check_target(video, "video")
    res = execute_plan(doc["states"], spec)
    out = res.to_dict()
    if video is not None:
        from evomotion.sim.quadruped.video import render_plan_video

        # render_video checks the path first and writes the MP4 atomically
        render_plan_video(doc["states"], video, spec, speed=speed, xml=scene_xml(doc, spec))
        out["video"] = str(video)
    return out
