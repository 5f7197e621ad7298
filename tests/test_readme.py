"""README's Python snippets run as written, in order, from the repository root."""

import re
import warnings
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]


def test_readme_python_snippets_run(monkeypatch):
    blocks = re.findall(r"```python\n(.*?)```", (ROOT / "README.md").read_text(encoding="utf-8"), re.S)
    assert blocks, "README has no Python snippets"
    monkeypatch.chdir(ROOT)
    namespace: dict = {}
    with warnings.catch_warnings(record=True):  # README shows the warnings a user would see; not failures here
        warnings.simplefilter("always")
        for code in blocks:
            exec(compile(code, "README.md", "exec"), namespace)
