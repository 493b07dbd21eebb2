"""Shared fixtures of the Python module's tests (docs/python.md). CTest sets
PYTHONPATH to build/python and the paths below; run alone:
  PYTHONPATH=build/python COMORPH_EXE=build/apps/comorph \
  COMORPH_TRAJECTORY_REFERENCE=build/tests/python/python_trajectory_reference \
  /usr/bin/python3 -m pytest tests/python
"""
import os
import pathlib
import re
import shutil
import subprocess

import numpy as np
import pytest

import comorph

SOURCE_DIR = pathlib.Path(os.environ.get("COMORPH_SOURCE_DIR", pathlib.Path(__file__).resolve().parents[2]))
SIM_CONFIG = SOURCE_DIR / "configs" / "sim"


def tool(name):
    """A program the build made, from the environment CTest sets; the test is skipped without it."""
    path = os.environ.get(name)
    if not path or not os.path.exists(path):
        pytest.skip(f"{name} not set (run through ctest, or set it to the built program)")
    return path


def config_dir_with(tmp_path, **task_keys):
    """A copy of configs/sim with task.yaml's top-level keys replaced (e.g. max_steps=40)."""
    out = tmp_path / "sim"
    shutil.copytree(SIM_CONFIG, out)
    text = (out / "task.yaml").read_text()
    for key, value in task_keys.items():
        text, n = re.subn(rf"^{key}:.*$", f"{key}: {value}", text, flags=re.M)
        assert n == 1, key
    (out / "task.yaml").write_text(text)
    return out


# A trained run's config names its scene classifier relative to the working
# directory (trainer.classifier_dir: runs/classifier), and evaluating it loads
# the classifier from there. `work` is a directory that has it: trained once by
# `comorph classifier prepare` (seeded: always the same weights, ~2 min) and kept in
# $COMORPH_TEST_WORK (build/tests/python/work under ctest);
# COMORPH_CLASSIFIER_DIR may point to one already trained instead.
@pytest.fixture(scope="session")
def work(tmp_path_factory):
    exe = tool("COMORPH_EXE")
    work = os.environ.get("COMORPH_TEST_WORK")
    work = pathlib.Path(work) if work else tmp_path_factory.mktemp("work")
    work.mkdir(parents=True, exist_ok=True)
    classifier = work / "runs" / "classifier"
    if not (classifier / "classifier.pt").exists():
        if classifier.is_symlink() or classifier.exists():
            classifier.unlink() if classifier.is_symlink() else shutil.rmtree(classifier)  # an interrupted prepare
        classifier.parent.mkdir(parents=True, exist_ok=True)
        given = os.environ.get("COMORPH_CLASSIFIER_DIR")
        if given:
            classifier.symlink_to(os.path.abspath(given))
        else:
            subprocess.run([exe, "classifier", "prepare", "--out", "runs/classifier", "--config",
                            str(SOURCE_DIR / "configs" / "perception.yaml"), "--config-dir",
                            str(SOURCE_DIR / "configs" / "sim")], cwd=work, check=True, capture_output=True)
    return work


@pytest.fixture
def short_episodes(tmp_path):
    """configs/sim with a 40-step cap: episodes end by truncation quickly."""
    return config_dir_with(tmp_path, max_steps=40)


def actions(seed, steps, low=-1.0, high=1.0):
    """A reproducible action sequence, float32 (steps, 5)."""
    return np.random.default_rng(seed).uniform(low, high, (steps, 5)).astype(np.float32)


FORWARD = np.array([1.0, 0.0, 0.5, -0.5, 0.5], np.float32)  # straight ahead with a wave: climbs, reaches 'none' for long
SPIN = np.array([1.0, 1.0, -1.0, 0.0, -1.0], np.float32)    # full turn: leaves the lane (terminated) in ~250 steps
