"""For a seed and an action sequence, the Python module's trajectory equals
task::MultiTaskEnv's driven from C++ (python_trajectory_reference), bit for
bit: observations, rewards, terminated, truncated and the termination reason."""
import subprocess

import numpy as np
import pytest

import comorph
from conftest import SIM_CONFIG, SPIN, actions, tool


def cpp_trajectory(seed, modules, acts):
    program = tool("COMORPH_TRAJECTORY_REFERENCE")
    text = "\n".join(" ".join(repr(float(x)) for x in a) for a in acts) + "\n"
    out = subprocess.run([program, str(SIM_CONFIG), str(seed), str(modules)], input=text, capture_output=True,
                         text=True, check=True).stdout
    rows = []
    for line in out.splitlines():
        head, depth, state, clearance, _ = line.split("|")
        reward, terminated, truncated, reason = head.split()
        floats = lambda s: np.array([float.fromhex(x) for x in s.split()], np.float32)
        rows.append((float.fromhex(reward), terminated == "1", truncated == "1", reason,
                     floats(depth), floats(state), floats(clearance)))
    return rows


def python_trajectory(seed, modules, acts):
    env = comorph.make(modules=modules)
    obs, info = env.reset(seed=seed)
    rows = [(0.0, False, False, info["termination"], obs["depth"].ravel(), obs["state"], obs["clearance"])]
    for a in acts:
        obs, reward, terminated, truncated, info = env.step(a)
        rows.append((reward, terminated, truncated, info["termination"], obs["depth"].ravel(), obs["state"],
                     obs["clearance"]))
        if terminated or truncated:
            break
    return rows


@pytest.mark.parametrize("seed,modules,acts", [
    (700001, 4, actions(7, 300, -0.3, 1.0)),   # random forward-ish actions
    (42, 2, np.tile(SPIN, (400, 1))),          # ends in a failure (left_area) within the sequence
])
def test_python_trajectory_equals_cpp(seed, modules, acts):
    cpp = cpp_trajectory(seed, modules, acts)
    py = python_trajectory(seed, modules, acts)
    assert len(py) == len(cpp) > 100
    for t, (p, c) in enumerate(zip(py, cpp)):
        assert p[:4] == c[:4], f"step {t}: {p[:4]} != {c[:4]}"
        for name, x, y in zip(("depth", "state", "clearance"), p[4:], c[4:]):
            np.testing.assert_array_equal(x, y, err_msg=f"step {t}: {name}")
    if modules == 2:
        assert py[-1][1] and py[-1][3] == "left_area"
