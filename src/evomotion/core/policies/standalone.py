"""Run an exported evomotion policy with numpy alone (this file is written out as policy.py).

    from policy import load
    policy = load("policy.npz")
    action = policy(observation)          # raw observation in, action out

or, from a shell, ``python policy.py policy.npz --obs 0.1,0.2,...`` (or observations on
standard input, one per line, numbers separated by commas or spaces): one action per line.

The observation is normalised with the stored running mean and std, clipped to ``±clip_obs``,
passed through the layers (tanh between layers, and after the last one when ``output_tanh``),
mapped to ``offset + scale * y`` and clipped to ``[low, high]``. A "structured" policy's ``y``
is instead ``tape(phi) + K x``: a Fourier series of the phase read from the RAW sin/cos
columns ``phase_columns`` (``tape_coef[a, 1 + 2H]`` on ``1, sin phi, cos phi, ...,
sin H phi, cos H phi``, the multiples by angle addition; with ``command_columns`` the
features are those and each raw command value times them; with ``command_gain`` ``G`` the
command plus ``G`` times the normalised observation) plus the gains ``feedback_gain`` on
the normalised observation without the two phase columns. Only numpy and the standard library are
imported.
"""

from __future__ import annotations

import math
import sys
from pathlib import Path

import numpy as np

FORMAT_VERSION = 1


class Policy:
    """A loaded policy; ``policy(obs[o]) -> action[a]`` (``obs[n, o]`` gives ``[n, a]``)."""

    def __init__(self, arrays: dict) -> None:
        self.kind = str(arrays["kind"])
        self.mean = np.asarray(arrays["obs_mean"], dtype=np.float64)
        self.std = np.asarray(arrays["obs_std"], dtype=np.float64)
        self.clip_obs = float(arrays["clip_obs"])
        self.layers = []
        if self.kind == "structured":
            self.harmonics = int(arrays["harmonics"])
            self.phase_columns = [int(c) for c in arrays["phase_columns"]]
            self.command_columns = [int(c) for c in arrays.get("command_columns", [])]
            self.tape = np.asarray(arrays["tape_coef"], dtype=np.float64)
            self.gain = np.asarray(arrays["feedback_gain"], dtype=np.float64)
            cg = arrays.get("command_gain")  # command feedback: c' = c + G x
            self.command_gain = None if cg is None else np.asarray(cg, dtype=np.float64)
        for k in range(0 if self.kind == "structured" else int(arrays["n_layers"])):
            W = np.asarray(arrays[f"layer{k}_weight"], dtype=np.float64)
            b = arrays.get(f"layer{k}_bias")
            self.layers.append((W, None if b is None else np.asarray(b, dtype=np.float64)))
        self.output_tanh = bool(arrays["output_tanh"])
        self.scale = np.asarray(arrays["action_scale"], dtype=np.float64)
        self.offset = np.asarray(arrays["action_offset"], dtype=np.float64)
        self.low = np.asarray(arrays["action_low"], dtype=np.float64)
        self.high = np.asarray(arrays["action_high"], dtype=np.float64)
        self.obs_dim = int(self.mean.shape[0])
        self.act_dim = int(self.scale.shape[0])

    def __call__(self, obs) -> np.ndarray:
        x = np.asarray(obs, dtype=np.float64)
        if x.shape[-1:] != (self.obs_dim,) or x.ndim > 2:
            raise ValueError(f"expected an observation of {self.obs_dim} numbers (or a batch "
                             f"[n, {self.obs_dim}]), got shape {x.shape}")
        h = (x - self.mean) / self.std
        if math.isfinite(self.clip_obs):
            h = np.clip(h, -self.clip_obs, self.clip_obs)
        if self.kind == "structured":
            h = self._structured(np.atleast_2d(x), np.atleast_2d(h)).reshape(
                x.shape[:-1] + (self.act_dim,))
        for k, (W, b) in enumerate(self.layers):
            h = h @ W.T
            if b is not None:
                h = h + b
            if k < len(self.layers) - 1 or self.output_tanh:
                h = np.tanh(h)
        return np.clip(self.offset + self.scale * h, self.low, self.high)

    def _structured(self, x, h):
        """``tape(phi) + K h`` for raw ``x[n, o]`` and normalised ``h[n, o]``."""
        i, j = self.phase_columns
        s1, c1 = x[:, i], x[:, j]
        features = [np.ones_like(s1)]
        s, c = s1, c1
        for k in range(1, self.harmonics + 1):
            features += [s, c]
            if k < self.harmonics:
                s, c = s * c1 + c * s1, c * c1 - s * s1
        f = np.stack(features, axis=-1)
        keep = [k for k in range(self.obs_dim) if k not in (i, j)]
        c = x[:, self.command_columns]
        if self.command_gain is not None and self.gain.shape[1]:
            c = c + _row_dot(self.command_gain, h[:, keep])
        f = np.concatenate([f] + [c[:, m, None] * f for m in range(c.shape[1])], axis=-1)
        y = _row_dot(self.tape, f)
        if self.gain.shape[1]:
            y = y + _row_dot(self.gain, h[:, keep])
        return y


def _row_dot(W, v):
    """``sum_m W[a, m] v[n, m]`` summed in column order (``[n, a]``): the training code's bits."""
    y = W[..., 0] * v[..., None, 0]
    for m in range(1, W.shape[-1]):
        y = y + W[..., m] * v[..., None, m]
    return y


def load(path="policy.npz") -> Policy:
    """The policy stored at ``path`` (a ``policy.npz`` written by evomotion)."""
    with np.load(path, allow_pickle=False) as data:
        arrays = {name: data[name] for name in data.files}
    version = int(arrays.get("format_version", -1))
    if version != FORMAT_VERSION:
        raise ValueError(f"{path}: policy format version {version}, this reader knows "
                         f"{FORMAT_VERSION}")
    return Policy(arrays)


def main(argv: list[str]) -> int:
    args = list(argv)
    obs_text = None
    if "--obs" in args:
        i = args.index("--obs")
        if i + 1 >= len(args):
            print("usage: python policy.py [policy.npz] [--obs N,N,...]", file=sys.stderr)
            return 2
        obs_text = [args[i + 1]]
        del args[i:i + 2]
    path = args[0] if args else str(Path(__file__).with_name("policy.npz"))
    try:
        policy = load(path)
        lines = obs_text if obs_text is not None else sys.stdin.read().splitlines()
        for line in lines:
            if line.strip():
                obs = [float(t) for t in line.replace(",", " ").split()]
                print(",".join(repr(float(v)) for v in policy(obs)))
    except (OSError, ValueError, KeyError) as e:
        print(f"error: {e}", file=sys.stderr)
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
