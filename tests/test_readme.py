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


def test_docs_repeat_the_readmes_script_and_test_command():
    # The docs own their pages; where they repeat the README, they repeat it exactly.
    docs = README.parent / "docs"
    readme = README.read_text()
    first_script = re.findall(r"```python\n(.*?)```", readme, re.S)[0]
    assert re.findall(r"```python\n(.*?)```", (docs / "getting-started.md").read_text(), re.S)[0] == first_script
    test_command = re.search(r"```bash\npip install \"\.\[test\]\".*?```", readme, re.S).group(0)
    assert test_command in (docs / "development.md").read_text()
