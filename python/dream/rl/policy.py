"""A linear policy in NumPy: an action ``tanh(obs @ weights + bias)`` per observation row, kept in a
``.npz`` weights file with the settings it was trained under, which the lab bundle
(``dream export --policy``) carries and its ``main.py`` loads."""

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
    k : int
        The observation's slots (:mod:`dream.rl.observation`) it was trained with.
    avoid : bool
        Whether it was trained with the HRVO safety layer (its wishes are velocities).
    """

    def __init__(self, weights: Any, bias: Any, *, k: int = 4, avoid: bool = False) -> None:
        self.weights = np.asarray(weights, dtype=np.float64)
        self.bias = np.asarray(bias, dtype=np.float64)
        if self.weights.ndim != 2 or self.weights.shape[1] != 2 or self.bias.shape != (2,):
            raise ValueError(
                f"weights must have shape (size, 2) and bias (2,), got {self.weights.shape} and {self.bias.shape}"
            )
        if not (np.isfinite(self.weights).all() and np.isfinite(self.bias).all()):
            raise ValueError("weights and bias must be finite")
        self.k, self.avoid = int(k), bool(avoid)

    @classmethod
    def zeros(cls, size: int, **settings: Any) -> LinearPolicy:
        """The untrained policy: every action 0 (stand still)."""
        return cls(np.zeros((size, 2)), np.zeros(2), **settings)

    @property
    def size(self) -> int:
        """The observation row's length."""
        return int(self.weights.shape[0])

    @property
    def flat(self) -> np.ndarray:
        """The parameters as one vector (for derivative-free training)."""
        return np.concatenate((self.weights.ravel(), self.bias))

    def with_flat(self, flat: np.ndarray) -> LinearPolicy:
        """This policy's settings with the parameters ``flat`` (see :attr:`flat`)."""
        size = self.size
        return LinearPolicy(flat[: 2 * size].reshape(size, 2), flat[2 * size :], k=self.k, avoid=self.avoid)

    def __call__(self, obs: np.ndarray) -> np.ndarray:
        # A stack of one-row products, each (1, size) @ (size, 2) computed alike, not one matrix
        # product, whose rounding depends on how many rows it multiplies: a robot acts alike
        # whether it decides alone or with the swarm.
        rows = np.asarray(obs, dtype=np.float64)[:, None, :]
        return np.tanh(np.matmul(rows, self.weights)[:, 0] + self.bias)

    def save(self, path: str | os.PathLike[str]) -> None:
        """Write the weights file (``.npz``: ``weights``, ``bias``, ``k``, ``avoid``), whole or not at all."""
        with replaced(path, "wb") as out:
            np.savez(out, weights=self.weights, bias=self.bias, k=self.k, avoid=self.avoid)

    @classmethod
    def load(cls, path: str | os.PathLike[str]) -> LinearPolicy:
        """Read a weights file written by :meth:`save`.

        Raises
        ------
        ValueError
            Not such a file (naming what it lacks).
        """
        try:
            with np.load(path, allow_pickle=False) as data:
                return cls(data["weights"], data["bias"], k=int(data["k"]), avoid=bool(data["avoid"]))
        except (KeyError, OSError, EOFError) as err:  # np.load's ways of refusing a file
            raise ValueError(f"{path}: not a LinearPolicy weights file ({err})") from None
