"""The examples under examples/ run from a fresh build: random_agent.py, and
train_reinforce.py learns (its --check). The training example needs PyTorch
(Debian's python3-torch); without it that test is skipped, nothing else
depends on torch in Python."""
import os
import subprocess
import sys

import pytest

from conftest import SOURCE_DIR

EXAMPLES = SOURCE_DIR / "examples"


def run(script, *args):
    return subprocess.run([sys.executable, str(EXAMPLES / script), *args], capture_output=True, text=True,
                          env=dict(os.environ), timeout=900)


def test_random_agent_runs_an_episode():
    out = run("random_agent.py")
    assert out.returncode == 0, out.stderr
    assert "steps, return" in out.stdout and "ended by" in out.stdout


def test_reinforce_example_learns():
    pytest.importorskip("torch", reason="python3-torch is not installed")
    out = run("train_reinforce.py", "--iterations", "12", "--check")
    assert out.returncode == 0, out.stdout + out.stderr
    assert "mean return of the first" in out.stdout
