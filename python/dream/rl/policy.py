"""A linear policy in NumPy: an action ``tanh(W obs + b)`` per observation row, kept in a ``.npz``
weights file that the lab bundle (``dream export --policy``) carries and its ``main.py`` loads."""

from __future__ import annotations

import os
from typing import Any

import numpy as np

from dream._files import replaced


class LinearPolicy:
    """``action = tanh(obs @ weights + bias)``: ``(m, size)`` observation rows to ``(m, 2)`` actions.

    Parameters
    ----------
    weights : (size, 2) array
    bias : (2,) array
    """

    def __init__(self, weights: Any, bias: Any) -> None:
        self.weights = np.asarray(weights, dtype=np.float64)
        self.bias = np.asarray(bias, dtype=np.float64)
        if self.weights.ndim != 2 or self.weights.shape[1] != 2 or self.bias.shape != (2,):
            raise ValueError(f"weights must have shape (size, 2) and bias (2,), got {self.weights.shape} and {self.bias.shape}")
        if not (np.isfinite(self.weights).all() and np.isfinite(self.bias).all()):
            raise ValueError("weights and bias must be finite")

    @classmethod
    def zeros(cls, size: int) -> LinearPolicy:
        """The untrained policy: every action 0 (stand still)."""
        return cls(np.zeros((size, 2)), np.zeros(2))

    @property
    def size(self) -> int:
        """The observation row's length."""
        return self.weights.shape[0]

    @property
    def flat(self) -> np.ndarray:
        """The parameters as one vector (for derivative-free training)."""
        return np.concatenate((self.weights.ravel(), self.bias))

    @classmethod
    def from_flat(cls, flat: np.ndarray, size: int) -> LinearPolicy:
        return cls(flat[: 2 * size].reshape(size, 2), flat[2 * size :])

    def __call__(self, obs: np.ndarray) -> np.ndarray:
        return np.tanh(np.asarray(obs, dtype=np.float64) @ self.weights + self.bias)

    def save(self, path: str | os.PathLike[str]) -> None:
        """Write the weights file (``.npz``: ``weights``, ``bias``), whole or not at all."""
        with replaced(path, "wb") as out:
            np.savez(out, weights=self.weights, bias=self.bias)

    @classmethod
    def load(cls, path: str | os.PathLike[str]) -> LinearPolicy:
        """Read a weights file written by :meth:`save`."""
        with np.load(path, allow_pickle=False) as data:
            return cls(data["weights"], data["bias"])
