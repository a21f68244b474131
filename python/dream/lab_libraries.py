"""The libraries the Robotarium lab installs for every script, from rps 2.1's ``libraries.txt``
(vendored as ``dream/data/rps21_libraries.txt``; ``dream/data/README.md`` says where it came from).

:func:`lab_modules` maps each importable module to its distribution, :func:`version_note` says
when the version installed here is not the lab's. The file is read on first use, never at import:
a lab bundle's copy of DREAM imports this module without its data.
"""

from __future__ import annotations

import re
from functools import cache
from importlib import metadata
from pathlib import Path

LIBRARIES = Path(__file__).with_name("data") / "rps21_libraries.txt"
#: The simulator itself, which the list does not name.
RPS = "rps"
#: Distributions whose modules have other names than theirs (the others: the name in lower case,
#: ``-`` as ``_``).
MODULES = {
    "cuda-bindings": ("cuda",),
    "gtsam-develop": ("gtsam",),
    "opencv-python": ("cv2",),
    "pillow": ("PIL",),
    "pyocclient": ("owncloud",),
    "python-dateutil": ("dateutil",),
    "PyYAML": ("yaml",),
    "scikit-learn": ("sklearn",),
}
#: DREAM's own dependencies: a bundle runs on the lab's versions of these whatever is installed
#: here (tested on the newest), so a difference is not worth a warning.
DREAM_NEEDS = ("numpy", "scipy", "matplotlib", "cvxopt")


@cache
def lab_versions() -> dict[str, str]:
    """Each distribution the lab installs, and its version."""
    pins = {}
    for line in LIBRARIES.read_text(encoding="utf-8").splitlines():
        match = re.fullmatch(r"([A-Za-z0-9_.\-]+)==(\S+)", line.strip())
        if match:
            pins[match[1]] = match[2]
    return pins


@cache
def lab_modules() -> dict[str, str]:
    """Each top-level module the lab can import (``rps`` included), and its distribution."""
    modules = {RPS: RPS}
    for name in lab_versions():
        for module in MODULES.get(name, (name.lower().replace("-", "_"),)):
            modules[module] = name
    return modules


def version_note(module: str) -> str | None:
    """A sentence when ``module``'s distribution is installed here at another major.minor version
    than the lab's (or not installed), ``None`` when it agrees or is one of :data:`DREAM_NEEDS`."""
    name = lab_modules().get(module)
    if name is None or name == RPS or name in DREAM_NEEDS:
        return None
    lab = lab_versions()[name]
    try:
        here = metadata.version(name)
    except metadata.PackageNotFoundError:
        return f"{module} ({name}) is not installed here: the lab runs {lab}, so check the bundle on it there"
    if here.split(".")[:2] != lab.split(".")[:2]:
        return f"{module} ({name}) is {here} here but {lab} at the lab: what it computes or loads may differ"
    return None
