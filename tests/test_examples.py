"""Every script in examples/ runs to completion (exit code 0) in a fresh interpreter.

New examples are picked up automatically. Each runs in a temporary working directory (so
files it writes land there) with a non-interactive matplotlib backend. The timeout only
guards against a hang; it is not a speed requirement.
"""

import os
import subprocess
import sys
from pathlib import Path

import pytest

EXAMPLES = Path(__file__).resolve().parents[1] / "examples"
SCRIPTS = sorted(EXAMPLES.glob("*.py"))
HANG_GUARD_S = 900


def test_foundation_examples_exist():
    names = {p.name for p in SCRIPTS}
    assert {"slider_crank_2d.py", "four_bar.py"} <= names


@pytest.mark.parametrize("script", SCRIPTS, ids=[p.name for p in SCRIPTS])
def test_example_runs(script, tmp_path):
    env = dict(os.environ, MPLBACKEND="Agg", PYTHONDONTWRITEBYTECODE="1")
    proc = subprocess.run([sys.executable, str(script)], cwd=tmp_path, env=env,
                          capture_output=True, text=True, timeout=HANG_GUARD_S)
    assert proc.returncode == 0, (
        f"{script.name} exited with {proc.returncode}\n--- stdout ---\n{proc.stdout[-3000:]}"
        f"\n--- stderr ---\n{proc.stderr[-3000:]}")
