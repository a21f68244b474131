"""``dream export``: an experiment as a folder that the Robotarium lab runs.

The lab runs plain Python scripts with ``rps`` and the common scientific packages (numpy, scipy,
matplotlib, cvxopt), without DREAM's compiled extension. :func:`export` writes a folder with

- ``main.py``: the lab's explicit loop. It builds ``rps.robotarium.Robotarium`` with keyword
  arguments, calls ``get_poses``, ``set_velocities`` and ``step`` every iteration and ends with
  ``debug()`` (rps 2.x) or ``call_at_scripts_end()`` (rps 0.0.0); DREAM's part of each step is
  one call to :class:`LabRun`, which goes through the same :class:`~dream.experiments.stepper.Stepper`
  as :func:`dream.run`;
- ``dream/``: the pure-Python part of DREAM (its kernels fall back to the NumPy reference);
- the experiment's own file, when it is one.

``DREAM_HEADLESS=1 python main.py`` runs the bundle without rps's figure and real-time pacing
(rps 0.0.0's figure fails on current matplotlib); the last line it prints reads
``dream: success, 0 collisions, 0 boundary, 0 actuator`` when the run met its success test.
"""

from __future__ import annotations

import ast
import contextlib
import os
import shutil
import sys
import tempfile
import time
import warnings
from collections.abc import Iterator, Mapping
from pathlib import Path
from string import Template
from typing import Any

import numpy as np

from dream._checks import FloatArray, as_poses
from dream.backends.base import Backend
from dream.backends.robotarium import rps_generation
from dream.backends.startup import START_SPACING
from dream.experiments import EXPERIMENTS, ExperimentResult, find, load_file
from dream.experiments.stepper import Stepper
from dream.lab_libraries import lab_modules, version_note
from dream.specs import ROBOTARIUM, RULES, SimulatorSpec
from dream.world import World, reset_default_world

#: The lab's testbed takes at most 20 robots (Robotarium Python Guide, section 2.7.3); rps itself
#: accepts 50, and rps 2.1's start-up phase has 22 charger slots.
LAB_MAX_ROBOTS = 20
#: DREAM modules left out of a bundle, and why a script that uses one cannot go to the lab.
LEFT_OUT = {
    "_core": "the compiled extension (a bundle runs on the NumPy reference)",
    "__main__": "the command line",
    "cli": "the command line",
    "viz": "drawing and video (Pillow, imageio)",
    "sweep": "sweeps (Dask)",
    "sweep_plot": "sweeps (Dask)",
    "templates": "`dream new`'s templates",
    "trajectory_log": "the trajectory log (pyarrow)",
    "recording": "Rerun recordings (rerun-sdk)",
    "onboard": "onboard sensors, which DREAM simulates from the poses; the lab's robots need rps 2.1's own "
    "(use_distance_sensors=True, get_distances(), get_encoders())",
}
#: What imports a module by its name at run time, which the check cannot follow: a script imports
#: with ``import`` statements only.
DYNAMIC_IMPORTS = ("__import__", "importlib")
#: Public names of left-out modules that ``from dream import *`` brings into a script.
LEFT_OUT_NAMES = {"DistanceSensor": "onboard", "EncoderSensor": "onboard", "ImuSensor": "onboard", "sweep": "sweep"}

#: The file every bundle holds: ``--force`` replaces only a folder with it, a previous export.
MARKER = ".dream-export"
PACKAGE = Path(__file__).resolve().parent
DREAM_FILES = "DREAM's pure-Python package (without the compiled extension: its kernels run on NumPy)"

MAIN = Template('''\
"""$label for the Robotarium, exported by DREAM $version with

    dream export $command

Submit all of these files, keeping dream/ a folder, and mark main.py as the main file:
$files
Check the bundle before submitting:

    python main.py                       # rps's figure, in real time, as the lab runs it
    DREAM_HEADLESS=1 python main.py      # no figure, no real-time pacing

The last line says whether the run met the experiment's success test:
"dream: success, 0 collisions, 0 boundary, 0 actuator".
"""

import os
import sys

import numpy as np
import rps.robotarium as robotarium

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)  # this folder's DREAM, before any installed copy

from dream.export import LabRun  # noqa: E402

EXPERIMENT = $experiment
N = $n
SEED = $seed
PARAMS = $params
ITERATIONS = $iterations  # at most; the loop ends when the experiment is done
SHOW = os.environ.get("DREAM_HEADLESS", "0") in ("", "0")

POLICY = $policy  # the trained policy's weights file in this folder, if its robots run one
lab = LabRun(EXPERIMENT, N, SEED, PARAMS, folder=HERE, policy=POLICY)
r = robotarium.Robotarium(
    number_of_robots=N, show_figure=SHOW, initial_conditions=lab.initial_conditions, sim_in_real_time=SHOW
)

x = r.get_poses()
for t in range(ITERATIONS):
    dxu = lab.decide(t, x)  # DREAM: the robots' timers, sensors, radios and controllers
    r.set_velocities(np.arange(N), dxu)
    r.step()
    x = r.get_poses()
    if lab.stepped(t, x):  # DREAM: the experiment's bookkeeping; True once it is done
        break

# rps 2.x renamed rps 0.0.0's call_at_scripts_end() to debug().
if hasattr(r, "debug"):
    r.debug()
else:
    r.call_at_scripts_end()
print(lab.report())
''')


class ExportError(ValueError):
    """An experiment, size or output folder that ``dream export`` cannot make a lab bundle of."""


class ExportWarning(UserWarning):
    """A bundle that runs, but not quite as `dream run` does here (on rps 2.1, say)."""


# -- in the bundle: DREAM's side of main.py -----------------------------------------------------
class LabSimulator(Backend):
    """DREAM's bookkeeping beside the lab's simulator in an exported ``main.py``.

    The lab's ``rps.robotarium.Robotarium`` moves the robots; this backend holds the poses its
    ``get_poses()`` returned (:meth:`follow`), takes the same commands and counts violations by
    the rules of the rps generation installed, as :class:`~dream.backends.Robotarium` does. It
    only uses rps's public calls, which the lab's testbed also has.

    Parameters
    ----------
    initial_conditions : (3, n) array_like
        The poses the run starts from (rps 2.x's start-up phase ends near them; :meth:`follow`
        brings the real ones).
    spec : SimulatorSpec
        The rules of the installed rps generation.
    """

    name = "lab"

    def __init__(self, initial_conditions: Any, spec: SimulatorSpec) -> None:
        super().__init__(initial_conditions, ROBOTARIUM, spec)

    def follow(self, x: Any) -> None:
        """Take ``x`` ``(3, n)``, what the lab's ``get_poses()`` returned, as the current poses."""
        self._poses = as_poses(x, "x", self.number_of_robots).copy()

    def _advance(self) -> None:
        """Nothing to move: the lab's simulator has moved the robots, and :meth:`follow` brings their poses."""


class LabRun:
    """One run of an experiment inside the lab's loop (the ``lab`` of an exported ``main.py``).

    Parameters
    ----------
    experiment : str
        A built-in experiment's name, or the name of its ``.py`` file in ``folder``.
    n, seed : int
        Number of robots and the seed of the run's generator.
    params : mapping
        Values of the experiment's parameters.
    folder : str or Path
        Where the experiment's file is.
    world : World, optional
        The run's world; default: a fresh default world (:func:`dream.reset_default_world`).
    rules : {"rps0", "rps2"}, optional
        The rps generation to run with; default: the installed rps's (else rps 2.x's, the lab's).
    policy : str, optional
        A :class:`~dream.rl.LinearPolicy` weights file in ``folder`` that drives the robots
        (:func:`dream.rl.learner.driven`) instead of the experiment's own decisions.
    """

    def __init__(
        self,
        experiment: str,
        n: int,
        seed: int,
        params: Mapping[str, Any],
        folder: str | Path = ".",
        world: World | None = None,
        rules: str | None = None,
        policy: str | None = None,
    ) -> None:
        source = experiment if experiment in EXPERIMENTS else str(Path(folder) / experiment)
        cls = find(source)
        if policy is not None:
            from dream.rl.learner import driven
            from dream.rl.policy import LinearPolicy

            cls = driven(cls, LinearPolicy.load(Path(folder) / policy))
        exp = cls(**params)
        exp.check(n, "robotarium")
        spec = RULES[rules or rps_generation() or "rps2"]  # the lab's, should the bundle run without rps
        # rps 2.x drives the robots from the chargers first: start where that phase gets them.
        startup = spec.rules == "rps2"
        self.stepper = Stepper(exp, n, reset_default_world(seed) if world is None else world, spec, startup=startup)
        #: ``(3, n)`` poses to start the lab's simulator at.
        self.initial_conditions: FloatArray = self.stepper.initial_conditions
        self.sim = LabSimulator(self.initial_conditions, spec)
        self.stepper.attach(self.sim)
        self.done_at: int | None = None
        self._everyone = np.arange(n)
        self._start = time.perf_counter()

    def decide(self, step: int, x: Any) -> FloatArray:
        """The commands ``(2, n)`` for step ``step`` (0-based), from ``x``, this step's ``get_poses()``."""
        self.sim.follow(x)
        commands = self.stepper.decide(step, self.sim.get_poses())
        self.sim.set_velocities(self._everyone, commands)
        # rps clips the array it is given in place and keeps it: hand it a copy, not the robots' own.
        return np.array(commands, dtype=np.float64)

    def stepped(self, step: int, x: Any) -> bool:
        """After the lab's ``step()`` of step ``step``, with ``x`` from the next ``get_poses()``:
        counts the step's violations and runs the experiment's hooks; True once it is done."""
        self.sim.step()
        self.sim.follow(x)
        if self.stepper.after(step + 1, self.sim.poses):
            self.done_at = step + 1
        return self.done_at is not None

    def result(self) -> ExperimentResult:
        """The run's metrics so far, as :func:`dream.run` returns them (backend ``"lab"``)."""
        return self.stepper.result(self.done_at, time.perf_counter() - self._start)

    def report(self) -> str:
        """The metrics table and a last line that a script can parse:
        ``dream: success, 0 collisions, 0 boundary, 0 actuator`` (else ``dream: failure, ...``)."""
        result = self.result()
        verdict = "success" if result.success else "failure" if result.completed else "failure (not completed)"
        counts = f"{result.collisions} collisions, {result.boundary} boundary, {result.actuator} actuator"
        return f"{result.summary()}\ndream: {verdict}, {counts}"


# -- on the researcher's machine: writing the bundle ----------------------------------------------
def check_script(path: Path) -> None:
    """Raise :class:`ExportError` if the experiment file ``path`` uses what the lab cannot run.

    Every import must be of the standard library, the lab's libraries
    (:func:`dream.lab_libraries.lab_modules`: rps 2.1's ``libraries.txt``) or DREAM's pure part
    (not :data:`LEFT_OUT`), made by an ``import`` statement (not :data:`DYNAMIC_IMPORTS`); the
    onboard sensors are refused by name too, for ``from dream import *``. A lab library installed
    here at another version than the lab's gets an :class:`ExportWarning`.
    """
    try:
        tree = ast.parse(path.read_text(encoding="utf-8"), filename=str(path))
    except SyntaxError as err:
        raise ExportError(f"{path}, line {err.lineno}: syntax error: {err.msg}") from None
    for node in ast.walk(tree):
        where = f"{path}, line {getattr(node, 'lineno', '?')}"
        if isinstance(node, ast.ImportFrom) and node.level:
            raise ExportError(f"{where}: a relative import; the bundle holds only this one file of yours")
        if isinstance(node, ast.Import):
            modules = [alias.name for alias in node.names]
        elif isinstance(node, ast.ImportFrom):
            base = node.module or ""
            modules = [base] + ([f"{base}.{alias.name}" for alias in node.names] if base == "dream" else [])
        else:
            name = node.id if isinstance(node, ast.Name) else node.attr if isinstance(node, ast.Attribute) else ""
            if name in DYNAMIC_IMPORTS:
                raise ExportError(f"{where}: uses {name}, {_DYNAMIC}")
            if name in LEFT_OUT_NAMES and LEFT_OUT_NAMES[name] == "onboard":
                raise ExportError(f"{where}: uses {name}: {LEFT_OUT['onboard']}")
            continue
        for module in modules:
            _check_module(module, where)


_DYNAMIC = "an import by name that the check cannot follow: import modules with `import` statements"


def _check_module(module: str, where: str) -> None:
    parts = module.split(".")
    if parts[0] in DYNAMIC_IMPORTS:
        raise ExportError(f"{where}: imports {parts[0]}, {_DYNAMIC}")
    if parts[0] == "dream":
        inner = parts[1] if len(parts) > 1 else ""
        left_out = LEFT_OUT_NAMES.get(inner, inner)
        if left_out in LEFT_OUT:
            raise ExportError(f"{where}: uses dream.{inner}, which a lab bundle leaves out: {LEFT_OUT[left_out]}")
    elif parts[0] not in lab_modules() and parts[0] not in sys.stdlib_module_names:
        raise ExportError(
            f"{where}: imports {module}, which the lab does not have (it runs the standard library and the "
            "libraries of rps 2.1's libraries.txt: numpy, scipy, matplotlib, torch, scikit-learn, gym, ...)"
        )
    else:
        note = version_note(parts[0])
        if note is not None:
            warnings.warn(f"{where}: {note}", ExportWarning, stacklevel=4)


def export(
    source: str | Path,
    output: str | Path,
    *,
    n: int | None = None,
    seed: int = 0,
    params: Mapping[str, Any] | None = None,
    force: bool = False,
    policy: str | Path | None = None,
) -> Path:
    """Write the lab bundle of ``source`` (a built-in experiment's name or a ``.py`` file) to ``output``.

    Parameters
    ----------
    n : int, optional
        Number of robots (default: the experiment's), at most :data:`LAB_MAX_ROBOTS`.
    seed : int
        Seed of the run's generator (initial poses, noise), baked into ``main.py`` like ``n``.
    params : mapping, optional
        Parameter values (Python values, or text as on the command line).
    force : bool
        Replace ``output`` if it holds a previous export (its :data:`MARKER` file). Whatever
        ``force``, the working folder, a folder above it and the home folder are never replaced.
    policy : path, optional
        A :class:`~dream.rl.LinearPolicy` weights file (``.npz``): the bundle carries it as
        :data:`POLICY_FILE` and its robots run it (:func:`dream.rl.learner.driven`).

    Returns
    -------
    Path
        The bundle's folder. It is written beside ``output`` and renamed into place, so a
        failure leaves nothing half-written.

    Raises
    ------
    ExportError
        A missing file, an experiment that uses what the lab lacks (:func:`check_script`), a
        size the lab or the experiment refuses, bad parameters, or an output folder in the way.
    """
    script = None
    if not str(source).endswith(".py"):
        try:
            cls = find(str(source))  # a built-in's name
        except ValueError as err:
            raise ExportError(str(err)) from None
    else:
        script = Path(source)
        if not script.is_file():
            raise ExportError(f"{script}: no such file")
        check_script(script)
        try:
            cls = load_file(script)
        except ValueError as err:
            raise ExportError(str(err)) from None
    n = cls.default_n if n is None else n
    if isinstance(n, bool) or not isinstance(n, int) or not 1 <= n <= LAB_MAX_ROBOTS:
        raise ExportError(
            f"-n {n}: the lab's testbed runs 1 to {LAB_MAX_ROBOTS} robots (rps simulates up to 50, "
            "but the Robotarium has 20)"
        )
    try:
        baked = cls(**dict(params or {})).params
        with World(seed) as world, _dry_folder(cls.name, script, policy) as (name, folder, weights):  # a dry build
            lab = LabRun(
                name, n, seed, baked, folder, world, rules="rps2", policy=weights
            )  # as the lab's rps 2.1 runs it
    except ValueError as err:
        raise ExportError(str(err)) from None
    exp = lab.stepper.exp
    if exp.arena != ROBOTARIUM:
        raise ExportError(f"{exp.label()} with {n} robots needs a larger arena than the Robotarium's")
    moved = np.hypot(*(lab.initial_conditions - lab.stepper.requested)[:2])
    if moved.any():
        warnings.warn(
            f"on rps 2.x, {np.count_nonzero(moved)} of {exp.label()}'s {n} robots start up to {moved.max():.2f} m "
            f"from the experiment's initial poses: its start-up phase, which the lab's verifier runs, cannot reach "
            f"poses closer than {START_SPACING} m apart (the bundle keeps them on rps 0.0.0)",
            ExportWarning,
            stacklevel=2,
        )
    target = _target(Path(output), force)
    bundled = cls.name if script is None else _bundled_name(script)
    files = [
        ("main.py", "the lab's loop"),
        *([] if script is None else [(bundled, "the experiment")]),
        *([] if policy is None else [(POLICY_FILE, "the trained policy's weights")]),
        ("dream/", DREAM_FILES),
    ]
    width = max(len(name) for name, _ in files)
    text = MAIN.substitute(
        label=exp.label(),
        version=_version(),
        command=_command(source, output, n, seed, params, policy),
        files="".join(f"    {name:<{width}}  {what}\n" for name, what in files),
        experiment=repr(bundled),
        n=n,
        seed=seed,
        params=repr(baked),
        iterations=exp.steps(n),
        policy=repr(None if policy is None else POLICY_FILE),
    )
    folder = Path(tempfile.mkdtemp(prefix=f".{target.name}-", dir=target.parent))
    try:
        (folder / "main.py").write_text(text, encoding="utf-8")
        (folder / MARKER).write_text(
            f"A bundle written by DREAM {_version()}'s `dream export`: `--force` replaces this folder.\n",
            encoding="utf-8",
        )
        if script is not None:
            shutil.copyfile(script, folder / _bundled_name(script))
        if policy is not None:
            shutil.copyfile(policy, folder / POLICY_FILE)
        _copy_package(folder / "dream")
        _replace(folder, target)
    except BaseException:
        shutil.rmtree(folder, ignore_errors=True)
        raise
    return target


#: The name of the policy's weights file in a bundle.
POLICY_FILE = "policy.npz"


@contextlib.contextmanager
def _dry_folder(name: str, script: Path | None, policy: str | Path | None) -> Iterator[tuple[str, Path, str | None]]:
    """Where the dry build finds the experiment (its name and folder) and the policy's weights (their
    name there): with a policy, a folder that holds both under their bundled names."""
    if policy is None:
        yield (name, Path("."), None) if script is None else (script.name, script.parent, None)
        return
    if not Path(policy).is_file():
        raise ExportError(f"--policy {policy}: no such file")
    with tempfile.TemporaryDirectory() as folder:
        if script is not None:
            name = _bundled_name(script)
            shutil.copyfile(script, Path(folder) / name)
        shutil.copyfile(policy, Path(folder) / POLICY_FILE)
        yield name, Path(folder), POLICY_FILE


def _bundled_name(script: Path) -> str:
    # main.py is the lab's entry point, and a file named like the package would hide it.
    return "experiment.py" if script.name in ("main.py", "dream.py") else script.name


def _target(output: Path, force: bool) -> Path:
    """The bundle's folder, ``output`` resolved, once it is sure that replacing it loses nothing:
    a new or empty folder, or with ``force`` a previous export, never the working folder, a
    folder above it or the home folder."""
    if output.exists() and not output.is_dir():
        raise ExportError(f"-o {output}: is a file; give a folder")
    target = output.resolve()
    if target.is_dir():
        if Path.cwd().resolve().is_relative_to(target):
            raise ExportError(f"-o {output}: is the working folder or one above it; give a new folder's name")
        if target == Path.home().resolve():
            raise ExportError(f"-o {output}: is the home folder; give a new folder's name")
        if any(target.iterdir()) and not (target / MARKER).is_file():
            raise ExportError(
                f"-o {output}: exists and is not empty, and holds no previous export (no {MARKER} file); choose "
                "another folder"
            )
        if any(target.iterdir()) and not force:
            raise ExportError(f"-o {output}: holds a previous export; pass --force to replace it")
    parent = target.parent
    if not parent.is_dir():
        raise ExportError(f"-o {output}: the folder {parent} does not exist")
    if not os.access(parent, os.W_OK):
        raise ExportError(f"-o {output}: the folder {parent} is not writable")
    return target


def _replace(folder: Path, target: Path) -> None:
    """Rename the finished ``folder`` to ``target``, moving an old ``target`` away first."""
    if not target.exists():
        folder.rename(target)
        return
    old = Path(tempfile.mkdtemp(prefix=f".{target.name}-old-", dir=target.parent))
    target.rename(old / target.name)
    try:
        folder.rename(target)
    except OSError:
        (old / target.name).rename(target)  # put the old bundle back
        raise
    shutil.rmtree(old, ignore_errors=True)


def _copy_package(destination: Path) -> None:
    """DREAM's ``.py`` files but :data:`LEFT_OUT`; the package's ``__init__`` without their names."""
    for path in sorted(PACKAGE.rglob("*.py")):
        relative = path.relative_to(PACKAGE)
        if relative.parts[0].removesuffix(".py") in LEFT_OUT or "__pycache__" in relative.parts:
            continue
        (destination / relative).parent.mkdir(parents=True, exist_ok=True)
        text = path.read_text(encoding="utf-8")
        (destination / relative).write_text(
            _without_left_out(text) if relative == Path("__init__.py") else text, encoding="utf-8"
        )


def _without_left_out(text: str) -> str:
    """The package's ``__init__`` source without its imports of left-out modules, and their names
    taken out of ``__all__`` (so that ``from dream import *`` still works in the bundle)."""
    tree = ast.parse(text)
    lines = text.splitlines(keepends=True)
    dropped: set[str] = set()
    spans: list[tuple[int, int, str]] = []
    for node in tree.body:
        if not isinstance(node, ast.ImportFrom):
            continue
        parts = (node.module or "").split(".")
        if parts[0] == "dream" and len(parts) > 1 and parts[1] in LEFT_OUT:
            dropped.update(alias.asname or alias.name for alias in node.names)
            spans.append((node.lineno, node.end_lineno or node.lineno, ""))
    for node in tree.body:
        if isinstance(node, ast.Assign) and any(getattr(t, "id", None) == "__all__" for t in node.targets):
            kept = [name for name in ast.literal_eval(node.value) if name not in dropped]
            listing = "".join(f"    {name!r},\n" for name in kept)
            spans.append((node.lineno, node.end_lineno or node.lineno, f"__all__ = [\n{listing}]\n"))
    for first, last, replacement in sorted(spans, reverse=True):
        lines[first - 1 : last] = [replacement]
    return "".join(lines)


def _version() -> str:
    from dream import __version__

    return __version__


def _command(
    source: str | Path, output: str | Path, n: int, seed: int, params: Mapping[str, Any] | None, policy: Any = None
) -> str:
    settings = "".join(f" --param {key}={value}" for key, value in (params or {}).items())
    return f"{source} -o {output} -n {n} --seed {seed}{settings}" + ("" if policy is None else f" --policy {policy}")
