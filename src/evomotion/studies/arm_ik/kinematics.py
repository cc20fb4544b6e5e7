"""Forward kinematics of an arm + fingers limb, vectorized over the population (paper 001).

Genome layout (degrees): the arm's joint angles in file order, then every finger's joint
angles, finger by finger, then (optionally) one random key per finger that encodes the
finger -> target assignment (see :mod:`.objective`). Angle ``theta_k`` is the
counter-clockwise rotation of bone ``k`` relative to the previous bone (0 = straight on); the
first arm bone is relative to +x, the first bone of each finger to the last arm bone. So bone
``k`` points along ``phi_k = sum_{i<=k} theta_i`` and joint ``k+1 = joint k + L_k (cos, sin)``.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from evomotion.studies.arm_ik.scenario import Scenario


@dataclass(frozen=True)
class Layout:
    """Where each angle lives in the genome, and the genome's box bounds (degrees)."""

    n_arm: int
    finger_bones: tuple[int, ...]
    with_keys: bool
    lower: np.ndarray
    upper: np.ndarray
    finger_idx: np.ndarray  # (F, Lmax) genome column of each finger bone (0 where padded)
    finger_mask: np.ndarray  # (F, Lmax) True for real bones
    finger_len: np.ndarray  # (F, Lmax) bone lengths, 0 where padded
    arm_len: np.ndarray  # (A,)

    @classmethod
    def of(cls, scn: Scenario, with_keys: bool = False) -> Layout:
        bones = tuple(f.n_bones for f in scn.fingers)
        n_f, l_max = len(bones), max(bones)
        idx = np.zeros((n_f, l_max), dtype=int)
        mask = np.zeros((n_f, l_max), dtype=bool)
        flen = np.zeros((n_f, l_max))
        col = scn.arm.n_bones
        for j, f in enumerate(scn.fingers):
            idx[j, : f.n_bones] = np.arange(col, col + f.n_bones)
            mask[j, : f.n_bones] = True
            flen[j, : f.n_bones] = f.length
            col += f.n_bones
        lower = [scn.arm.min_deg, *(f.min_deg for f in scn.fingers)]
        upper = [scn.arm.max_deg, *(f.max_deg for f in scn.fingers)]
        if with_keys:
            lower.append(np.zeros(n_f))
            upper.append(np.ones(n_f))
        return cls(scn.arm.n_bones, bones, with_keys, np.concatenate(lower),
                   np.concatenate(upper), idx, mask, flen, scn.arm.length.copy())

    @property
    def n_fingers(self) -> int:
        return len(self.finger_bones)

    @property
    def dim(self) -> int:
        return int(self.lower.size)

    @property
    def arm(self) -> slice:
        return slice(0, self.n_arm)

    @property
    def fingers(self) -> slice:
        """Finger angles and, when present, the assignment keys."""
        return slice(self.n_arm, self.dim)

    @property
    def keys(self) -> slice | None:
        return slice(self.dim - self.n_fingers, self.dim) if self.with_keys else None

    @property
    def full_circle(self) -> np.ndarray:
        """Genes whose range is the whole circle (wrapped rather than clipped)."""
        circ = (self.upper - self.lower) >= 360.0
        if self.with_keys:
            circ[self.keys] = False
        return circ

    def split(self, genome: np.ndarray) -> tuple[list[float], list[list[float]]]:
        """One genome -> (arm_deg, fingers_deg) lists in file order."""
        g = np.asarray(genome, dtype=float)
        arm = g[self.arm].tolist()
        fingers = [g[self.finger_idx[j, : b]].tolist() for j, b in enumerate(self.finger_bones)]
        return arm, fingers


@dataclass
class Pose:
    """Joint positions of a batch of limbs (board units)."""

    arm_joints: np.ndarray  # (n, A+1, 2): start, ..., wrist
    finger_joints: np.ndarray  # (n, F, Lmax+1, 2): wrist, ..., tip (tip repeated where padded)

    @property
    def wrist(self) -> np.ndarray:
        return self.arm_joints[:, -1]

    @property
    def tips(self) -> np.ndarray:
        return self.finger_joints[:, :, -1]

    def arm_segments(self) -> np.ndarray:
        """(n, A, 2, 2) arm bones as segments."""
        j = self.arm_joints
        return np.stack([j[:, :-1], j[:, 1:]], axis=2)

    def finger_segments(self) -> np.ndarray:
        """(n, F*Lmax, 2, 2) finger bones (padded ones are zero-length; see Layout.finger_mask)."""
        j = self.finger_joints
        s = np.stack([j[:, :, :-1], j[:, :, 1:]], axis=3)
        return s.reshape(j.shape[0], -1, 2, 2)


def forward(scn: Scenario, layout: Layout, genomes: np.ndarray) -> Pose:
    """Joint positions of every limb in ``genomes[n, dim]`` (angles in degrees)."""
    g = np.atleast_2d(np.asarray(genomes, dtype=float))
    n = g.shape[0]
    phi = np.cumsum(np.deg2rad(g[:, layout.arm]), axis=1)  # (n, A)
    steps = layout.arm_len * np.stack([np.cos(phi), np.sin(phi)], axis=-1).transpose(2, 0, 1)
    arm = np.concatenate([np.zeros((n, 1, 2)), np.cumsum(steps.transpose(1, 2, 0), axis=1)], 1)
    arm += scn.start
    theta = np.where(layout.finger_mask, g[:, layout.finger_idx], 0.0)  # (n, F, Lmax)
    psi = phi[:, -1, None, None] + np.cumsum(np.deg2rad(theta), axis=2)
    fsteps = layout.finger_len[..., None] * np.stack([np.cos(psi), np.sin(psi)], axis=-1)
    wrist = arm[:, -1][:, None, None, :]
    fingers = np.concatenate(
        [np.broadcast_to(wrist, (n, layout.n_fingers, 1, 2)), wrist + np.cumsum(fsteps, axis=2)],
        axis=2,
    )
    return Pose(arm, fingers)
