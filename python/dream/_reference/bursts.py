"""Loss bursts: each radio link a Gilbert-Elliott channel, the links in a burst a sorted array."""

from __future__ import annotations

import numpy as np

from dream._checks import FloatArray


def bursts(
    lossy: np.ndarray, links: np.ndarray, draws: FloatArray, enter: float, leave: float
) -> tuple[np.ndarray, np.ndarray]:
    """Whether each message over ``links`` (int64, one a message) is sent in a loss burst, and the
    links in a burst after them (int64, strictly increasing, as ``lossy`` before): a message's link
    flips state where its draw (``draws``, uniform) is below ``leave`` (in a burst) or ``enter``
    (not), each from the state before the step; a link's burst ends if one of its messages ends
    it, begins if one begins it. The links are looked up by bisection."""
    for name, values in (("lossy", lossy), ("links", links)):
        if not isinstance(values, np.ndarray) or values.dtype != np.int64:
            raise ValueError(f"`{name}` must be a NumPy array of int64")
    if len(draws) != len(links):
        raise ValueError(f"`draws` must have shape ({len(links)},), got {list(np.shape(draws))}")
    for name, p in (("enter", enter), ("leave", leave)):
        if not 0.0 <= p <= 1.0:
            raise ValueError(f"`{name}` must be finite and a probability in [0, 1], got {p}")
    falls = np.flatnonzero(lossy[1:] <= lossy[:-1])  # compared, not subtracted: no overflow
    if len(falls):
        raise ValueError(f"`lossy` is not strictly increasing at index {falls[0] + 1}")
    at = np.searchsorted(lossy, links)
    was = np.zeros(len(links), dtype=bool)
    inside = at < len(lossy)
    was[inside] = lossy[at[inside]] == links[inside]
    now = was ^ (draws < np.where(was, leave, enter))
    stays = np.ones(len(lossy), dtype=bool)
    stays[at[was & ~now]] = False  # bursts that end
    kept, began = lossy[stays], np.unique(links[now & ~was])
    return now, np.insert(kept, np.searchsorted(kept, began), began)
