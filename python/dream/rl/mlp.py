"""A small multilayer perceptron policy in torch (the ``rl`` extra), for gradient learners: the torch
counterpart of :class:`~dream.rl.policy.LinearPolicy`, every robot running the same network on
its own observation row.

``examples/train_rendezvous.py --torch`` trains one by a policy gradient on
:func:`dream.rl.batch_env`. torch is imported here only: the rest of :mod:`dream.rl`, and a lab
bundle's NumPy policy, run without it.
"""

from __future__ import annotations

import os
import pickle
from typing import Any

import numpy as np
import torch
from torch import nn

from dream._files import replaced


class MlpPolicy(nn.Module):
    """``action = tanh(mlp(obs))``: observation rows ``(m, size)`` to actions ``(m, 2)`` in
    ``[-1, 1]``, with a learned spread for Gaussian exploration.

    Parameters
    ----------
    size : int
        The observation row's length (``env.single_observation_space.shape[0]``).
    hidden : tuple of int
        The hidden layers' widths (tanh between layers).
    k : int
        The observation's slots (:mod:`dream.rl.observation`) it is trained with.
    avoid : bool
        Whether it is trained with the HRVO safety layer.
    spread : float
        The exploration's initial standard deviation (in action units).
    """

    def __init__(
        self, size: int, hidden: tuple[int, ...] = (64, 64), *, k: int = 4, avoid: bool = False, spread: float = 0.5
    ) -> None:
        super().__init__()
        widths = (size, *hidden)
        if any(isinstance(w, bool) or not isinstance(w, (int, np.integer)) or w < 1 for w in widths):
            raise ValueError(f"size and hidden widths must be whole numbers >= 1, got size {size!r}, hidden {hidden!r}")
        if not (np.isfinite(spread) and spread > 0):
            raise ValueError(f"spread must be > 0, got {spread!r}")
        layers: list[nn.Module] = []
        for inputs, outputs in zip(widths[:-1], widths[1:]):
            layers += [nn.Linear(int(inputs), int(outputs)), nn.Tanh()]
        layers.append(nn.Linear(int(widths[-1]), 2))
        self.body = nn.Sequential(*layers)
        self.log_spread = nn.Parameter(torch.full((2,), float(np.log(spread))))
        self.size, self.hidden, self.k, self.avoid = int(size), tuple(int(w) for w in hidden), int(k), bool(avoid)

    def forward(self, obs: torch.Tensor) -> torch.Tensor:
        """The mean actions ``(m, 2)`` of observation rows ``(m, size)``."""
        return torch.tanh(self.body(obs))

    def distribution(self, obs: torch.Tensor) -> torch.distributions.Normal:
        """The exploring actions' distribution: Gaussian about :meth:`forward`, per action
        component (the environments clip a sample to ``[-1, 1]``)."""
        return torch.distributions.Normal(self(obs), self.log_spread.exp())

    def act(self, obs: np.ndarray) -> np.ndarray:
        """The mean actions ``(m, 2)`` of NumPy observation rows, as NumPy (no exploration, no
        gradient): what an environment's ``step`` takes."""
        with torch.no_grad():
            return self(torch.as_tensor(np.asarray(obs, dtype=np.float32))).numpy().astype(np.float64)

    def save(self, path: str | os.PathLike[str]) -> None:
        """Write the weights file (torch's format: the parameters and the settings), whole or not at all."""
        settings = {"size": self.size, "hidden": list(self.hidden), "k": self.k, "avoid": self.avoid}
        with replaced(path, "wb") as out:
            torch.save({"settings": settings, "parameters": self.state_dict()}, out)

    @classmethod
    def load(cls, path: str | os.PathLike[str]) -> MlpPolicy:
        """Read a weights file written by :meth:`save` (tensors and plain values only: no code runs).

        Raises
        ------
        ValueError
            Not such a file.
        """
        try:
            data: Any = torch.load(path, weights_only=True)
            settings = data["settings"]
            policy = cls(settings["size"], tuple(settings["hidden"]), k=settings["k"], avoid=settings["avoid"])
            policy.load_state_dict(data["parameters"])
        except (KeyError, TypeError, OSError, RuntimeError, EOFError, pickle.UnpicklingError) as err:  # refusals
            raise ValueError(f"{path}: not an MlpPolicy weights file ({err})") from None
        return policy
