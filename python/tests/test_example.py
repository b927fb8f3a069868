"""The tour (python/examples/tour.py) runs as a user would run it, and says what it should."""

import re
import subprocess
import sys


def test_the_tour_runs(tmp_path, root):
    out = subprocess.run(
        [sys.executable, "-W", "ignore", str(root / "python" / "examples" / "tour.py"), str(tmp_path)],
        capture_output=True,
        text=True,
        timeout=600,
        cwd=tmp_path,
    )
    assert out.returncode == 0, out.stderr[-3000:]
    text = out.stdout
    assert "the cluster's ensemble equals the local one: True" in text, text
    assert "states (1000, 51, 13)" in text, text
    spread = float(re.search(r"largest difference between the formulations at t = 10: (\S+)", text).group(1))
    assert spread < 1e-7, text
    page = tmp_path / "three_body.html"
    assert page.is_file() and page.stat().st_size > 10_000
