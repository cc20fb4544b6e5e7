"""Adam (Kingma & Ba 2015, "Adam: A Method for Stochastic Optimization", ICLR, Algorithm 1).

A pure function over explicit state arrays (first and second moment estimates and the step
count), returning new arrays; used by OpenAI-ES on its gradient estimate.
"""

from __future__ import annotations

import numpy as np


def adam_step(theta: np.ndarray, grad: np.ndarray, m: np.ndarray, v: np.ndarray, t: int, *,
              learning_rate: float, beta1: float = 0.9, beta2: float = 0.999,
              eps: float = 1e-8) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """One Adam step *descending* ``grad`` (the gradient of a loss): returns
    ``(theta_t, m_t, v_t)``; ``t`` is the number of this step (1 for the first)."""
    if t < 1:
        raise ValueError(f"adam: the step count t must be >= 1, got {t}")
    m_t = beta1 * m + (1.0 - beta1) * grad  # Alg. 1: m_t = β1 m_{t-1} + (1 - β1) g_t
    v_t = beta2 * v + (1.0 - beta2) * grad * grad  # Alg. 1: v_t = β2 v_{t-1} + (1 - β2) g_t²
    m_hat = m_t / (1.0 - beta1**t)  # Alg. 1: bias-corrected first moment
    v_hat = v_t / (1.0 - beta2**t)  # Alg. 1: bias-corrected second raw moment
    theta_t = theta - learning_rate * m_hat / (np.sqrt(v_hat) + eps)  # Alg. 1: the update
    return theta_t, m_t, v_t
