"""The README's Python example runs as written, and gives what its comments say."""

import re


def test_the_readme_example_runs(root, tmp_path, monkeypatch):
    readme = (root / "README.md").read_text()
    block = re.search(r"```python\n(.*?)```", readme, re.S).group(1)
    monkeypatch.chdir(tmp_path)
    scope = {}
    exec(compile(block, "README.md", "exec"), scope)
    assert scope["sol"].success
    assert scope["states"].shape == (1000, 51, 13)
    assert list(scope["run"].columns[:2]) == ["t", "psi"]
    assert (tmp_path / "three_body.html").is_file()
