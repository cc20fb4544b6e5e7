"""A MuJoCo quadruped that executes paper-003 walking plans quasi-statically.

Paper 003 (Ondroušek & Březina) plans the free gait of a rectangular four-legged body whose
feet stay in annular sectors about the hips; a plan (the ``states`` of a quadruped-plan
``plan.json``, paper units, feet in world coordinates) alternates body moves with all feet
down and single-foot moves with the body still. Here one paper unit is ``unit_m`` = 0.1 m:
the torso is 0.25 m x 0.30 m, the feet reach 0.1 to 0.2 m from the hips, the robot spans
about 0.6 m.

- :mod:`.geometry`: the body geometry (Tab. 1), defined once for the robot and the planner;
- :mod:`.model`: :class:`QuadrupedSpec` and the MjSpec-built model (3 hinges per leg);
- :mod:`.ik`: closed-form leg inverse / forward kinematics;
- :mod:`.trajectory`: joint targets per physics step for a plan;
- :mod:`.support`: support margin from contact forces (centre of pressure vs. hull);
- :mod:`.execute`: :func:`execute_plan` and its :class:`ExecutionResult`;
- :mod:`.video`: :func:`render_plan_video`.

Defaults: swings of 0.6 s lifting the foot 12 mm, body moves at 0.05 m/s and 0.5 rad/s.
The paper's plans often lift a leg with the body centre exactly on the edge of the remaining
support triangle (margin 0): the robot then leans towards the lifted foot until that foot
touches down. A quick, low swing limits the lean (higher or slower swings tip further); no
support or constraint is added to hide it.
"""

from evomotion.sim.quadruped.execute import (
    ExecutionResult,
    execute_plan,
    plan_qpos,
    simulate_plan,
)
from evomotion.sim.quadruped.ik import leg_fk, leg_ik, legs_fk, legs_ik
from evomotion.sim.quadruped.model import QuadrupedSpec, build_model, model_xml
from evomotion.sim.quadruped.support import support_margin, support_margins

__all__ = [
    "ExecutionResult",
    "QuadrupedSpec",
    "build_model",
    "execute_plan",
    "leg_fk",
    "leg_ik",
    "legs_fk",
    "legs_ik",
    "model_xml",
    "plan_qpos",
    "simulate_plan",
    "support_margin",
    "support_margins",
]
