"""The README's code runs as printed."""

from __future__ import annotations

import re
from pathlib import Path

README = Path(__file__).resolve().parents[1] / "README.md"


def test_readme_example_runs_without_collision(capsys):
    code = re.findall(r"```python\n(.*?)```", README.read_text(), re.S)[0]
    namespace: dict = {}
    exec(compile(code, "README.md", "exec"), namespace)
    r = namespace["r"]
    assert r.iterations == 300
    assert r.violations.collision == 0
    assert "300 iterations" in capsys.readouterr().out


def test_readme_test_command_is_what_ci_runs():
    lines = (README.parent / ".ci" / "run").read_text().splitlines()
    commands = [line.strip("()") for line in lines if line.startswith(("pip ", "(pip "))]
    assert len(commands) == 1
    assert f"```bash\n{commands[0]}\n```" in README.read_text()
