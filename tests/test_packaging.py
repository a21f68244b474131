"""Packaging conventions: one version, ``python -m dream``, the distribution name, the API pages."""

from __future__ import annotations

import os
import re
import subprocess
import sys
import types
from importlib import metadata
from pathlib import Path

import dream
import dream.kernels
from dream import _version, errors

ROOT = Path(__file__).resolve().parents[1]


def _cargo_version() -> str:
    text = (ROOT / "Cargo.toml").read_text()
    match = re.search(r'(?m)^\[workspace\.package\]\n(?:[^\[].*\n)*?version = "([^"]+)"', text)
    assert match, "no version in [workspace.package] of Cargo.toml"
    return match[1]


def _project_table() -> str:
    text = (ROOT / "pyproject.toml").read_text()
    return text.split("[project]\n", 1)[1].split("\n[", 1)[0]


def test_version_is_cargos():
    assert dream.__version__ == _cargo_version()


def test_version_is_written_only_in_cargo():
    project = _project_table()
    assert 'dynamic = ["version"]' in project
    assert not re.search(r"(?m)^version\s*=", project)
    assert _cargo_version() not in (ROOT / "python" / "dream" / "__init__.py").read_text()


def test_tests_read_nothing_outside_the_repository():
    # A fresh clone has nothing beside it: every folder a test reaches from its own file is in the
    # checkout (golden data lives in tests/data, with the script that records it).
    reach = re.compile(r"Path\(__file__\)(?:\.resolve\(\))?\.parents\[(\d+)\]")
    for path in (ROOT / "tests").rglob("*.py"):
        for depth in reach.findall(path.read_text()):
            base = path.resolve().parents[int(depth)]
            assert base == ROOT or ROOT in base.parents, f"{path.relative_to(ROOT)} reads from {base}"


def test_distribution_name_is_dream_robotics():
    assert re.search(r'(?m)^name = "dream-robotics"$', _project_table())
    assert _version.DISTRIBUTION == "dream-robotics"


def test_python_m_dream_lists_the_experiments():
    # The subprocess imports the same copy of dream as this test run.
    env = dict(os.environ, PYTHONPATH=os.pathsep.join([str(Path(dream.__file__).parents[1]), *sys.path]))
    run = subprocess.run(
        [sys.executable, "-m", "dream", "list"], capture_output=True, text=True, env=env, timeout=120, check=False
    )
    assert run.returncode == 0, run.stderr
    listed = [line.split()[0] for line in run.stdout.splitlines() if line.strip() and not line.startswith("`")]
    assert listed == sorted(["hrvo-circle", "line-consensus", "voronoi-coverage", "affine-formation"])


def test_geometry_error_is_exported():
    assert dream.GeometryError is errors.GeometryError
    assert issubclass(dream.GeometryError, ValueError)


def _documented(page: str) -> set[str]:
    """The names listed under ``members:`` on an API page."""
    return set(re.findall(r"(?m)^\s+- (\w+)$", (ROOT / "docs" / "api" / page).read_text()))


def test_api_page_lists_every_public_name_of_dream():
    public = {
        name
        for name in dir(dream)
        if not name.startswith("_") and not isinstance(getattr(dream, name), types.ModuleType)
    }
    assert public == _documented("dream.md")


def test_api_page_renders_all_of_dream_kernels():
    # With no member list, mkdocstrings renders the package's __all__: it must hold every public
    # function and class its modules define, the IMPLEMENTATION flag, GeometryError and Loss (a
    # radio's loss, defined beside the reference's draws, which the NumPy kernels read too).
    page = (ROOT / "docs" / "api" / "kernels.md").read_text()
    assert "::: dream.kernels\n" in page and "members:" not in page
    defined = {
        name
        for name, value in vars(dream.kernels).items()
        if not name.startswith("_") and (getattr(value, "__module__", None) or "").startswith("dream.kernels.")
    }
    assert defined | {"IMPLEMENTATION", "GeometryError", "Loss"} == set(dream.kernels.__all__)


def test_version_without_the_extension_comes_from_the_metadata(monkeypatch):
    # A pure-Python copy: `from dream import _core` fails, the installed metadata answers.
    monkeypatch.delattr(dream, "_core", raising=False)
    monkeypatch.setitem(sys.modules, "dream._core", None)
    try:
        installed = metadata.version(_version.DISTRIBUTION)
    except metadata.PackageNotFoundError:
        installed = None
    got = _version.version()
    if installed is None:
        assert got == "unknown"
    else:
        assert got == installed == _cargo_version()


def test_import_sets_the_allocator_unless_the_environment_does():
    """``import dream`` sets mimalloc's options before the extension loads, and a user's own win."""
    script = "import os, dream; print(os.environ['MIMALLOC_PURGE_DELAY'], os.environ['MIMALLOC_ARENA_EAGER_COMMIT'])"
    env = {k: v for k, v in os.environ.items() if not k.startswith("MIMALLOC_")}
    env["PYTHONPATH"] = os.pathsep.join([str(Path(dream.__file__).parents[1]), *sys.path])  # this copy of dream
    ours = subprocess.run([sys.executable, "-c", script], env=env, capture_output=True, text=True, check=True)
    assert ours.stdout.split() == ["10000", "0"]
    env |= {"MIMALLOC_PURGE_DELAY": "0", "MIMALLOC_ARENA_EAGER_COMMIT": "1"}
    theirs = subprocess.run([sys.executable, "-c", script], env=env, capture_output=True, text=True, check=True)
    assert theirs.stdout.split() == ["0", "1"]
