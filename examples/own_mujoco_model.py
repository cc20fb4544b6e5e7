"""Your own MuJoCo model: evolve an open-loop gait of a two-joint crawler with the GA.

The model is an MJCF string: a planar box body (slides along x and z, pitches at most 30
degrees) with a front and a back flipper on hinges, driven by position servos. A genome is
(amplitude front, amplitude back, phase of the back flipper, frequency); the whole population
is rolled out at once with ``mujoco.rollout`` and scored by how far the body moved along +x
in 4 s.

    python examples/own_mujoco_model.py [OUT_DIR]
"""

import sys

import mujoco
import numpy as np
from mujoco import rollout

import evomotion as em

XML = """
<mujoco model="crawler">
  <option timestep="0.01"/>
  <worldbody>
    <geom type="plane" size="5 5 0.1" friction="1 0.01 0.001"/>
    <body name="body" pos="0 0 0.05">
      <joint name="x" type="slide" axis="1 0 0"/>
      <joint name="z" type="slide" axis="0 0 1"/>
      <joint name="pitch" type="hinge" axis="0 1 0" range="-30 30" limited="true"/>
      <geom type="box" size="0.15 0.08 0.03" mass="1"/>
      <body pos="0.15 0 0">
        <joint name="front" type="hinge" axis="0 1 0" range="-60 60"/>
        <geom type="capsule" fromto="0 0 0 0.12 0 -0.03" size="0.02" mass="0.1"/>
      </body>
      <body pos="-0.15 0 0">
        <joint name="back" type="hinge" axis="0 1 0" range="-60 60"/>
        <geom type="capsule" fromto="0 0 0 -0.12 0 -0.03" size="0.02" mass="0.1"/>
      </body>
    </body>
  </worldbody>
  <actuator>
    <position joint="front" kp="4" ctrlrange="-1 1"/>
    <position joint="back" kp="4" ctrlrange="-1 1"/>
  </actuator>
</mujoco>
"""


class Crawler:
    """Forward distance (m, maximised) of a sinusoidal flipper gait."""

    genome = em.GenomeSpec(lower=np.array([0.0, 0.0, -np.pi, 0.25]),
                           upper=np.array([1.0, 1.0, np.pi, 2.0]),
                           names=("amp_front_rad", "amp_back_rad", "phase_back_rad", "freq_hz"))
    sense = "max"
    metric_names = ("forward_m", "peak_height_m")

    def __init__(self, seconds: float = 4.0) -> None:
        self.model = mujoco.MjModel.from_xml_string(XML)
        self.data = mujoco.MjData(self.model)
        self.nstep = int(seconds / self.model.opt.timestep)
        self.t = self.model.opt.timestep * np.arange(self.nstep)
        self.state0 = np.zeros(mujoco.mj_stateSize(self.model, mujoco.mjtState.mjSTATE_FULLPHYSICS))
        mujoco.mj_getState(self.model, self.data, self.state0, mujoco.mjtState.mjSTATE_FULLPHYSICS)

    def evaluate(self, genomes: np.ndarray) -> em.Evaluation:
        a_f, a_b, phase, freq = (genomes[:, i:i + 1] for i in range(4))
        w = 2 * np.pi * freq * self.t  # [pop, nstep]
        ctrl = np.stack([a_f * np.sin(w), a_b * np.sin(w + phase)], axis=2)
        init = np.tile(self.state0, (len(genomes), 1))
        states, _ = rollout.rollout(self.model, self.data, init, ctrl)
        x = states[:, -1, 1] - states[:, 0, 1]  # qpos[0]: the body's x slide (m)
        peak = states[:, :, 2].max(axis=1)  # qpos[1]: its height above the start (m)
        return em.Evaluation(x, {"forward_m": x, "peak_height_m": peak})


def main(out: str = "runs/crawler") -> None:
    result = em.run(Crawler(), {"algorithm": {"name": "ga", "pop_size": 24},
                                "run": {"generations": 12, "seed": 2}}, out)
    gait = {n: round(float(v), 2) for n, v in zip(Crawler.genome.names, result.best_genome)}
    print(f"best gait {gait}: "
          f"{result.best_metrics['forward_m']:.3f} m forward in 4 s")


if __name__ == "__main__":
    main(*sys.argv[1:])
