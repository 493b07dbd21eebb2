"""Bad input raises ValueError or RuntimeError with a message that names the
fault, never a crash: wrong action shape or dtype, NaN or out-of-range
actions, step after the end, 11 modules, a bad config_dir, bad options."""
import numpy as np
import pytest

import comorph
from conftest import SPIN


@pytest.fixture
def env():
    e = comorph.make(modules=3)
    e.reset(seed=1)
    return e


@pytest.mark.parametrize("action,message", [
    (np.zeros(4, np.float32), r"shape \(4,\), expected \(5,\)"),
    (np.zeros((1, 5), np.float32), r"shape \(1, 5\)"),
    (np.zeros(5, np.int64), "dtype int64"),
    (np.array(["a"] * 5), "dtype <U1"),
    (np.array([0, 0, np.nan, 0, 0], np.float32), r"action\[2\] is nan"),
    (np.array([0, 0, 0, np.inf, 0], np.float64), r"action\[3\] is inf"),
    (np.array([1.5, 0, 0, 0, 0], np.float32), r"action\[0\] = 1.5.* outside the action space \[-1, 1\]"),
    (np.array([0, 0, 0, 0, -1.01], np.float32), r"action\[4\] = -1.01"),
    (None, "dtype object, expected a floating dtype"),
])
def test_bad_actions_raise_value_error(env, action, message):
    with pytest.raises(ValueError, match=message):
        env.step(action)
    obs, *_ = env.step(np.zeros(5, np.float32))  # the env is still usable
    assert obs["state"].shape == (46,)


def test_step_after_the_end_raises_runtime_error(env):
    env.reset(seed=3, options={"modules": 2})
    while True:
        _, _, terminated, truncated, _ = env.step(SPIN)
        if terminated or truncated:
            break
    with pytest.raises(RuntimeError, match=r"step after the episode ended \(left_area\); call reset\(\)"):
        env.step(SPIN)
    with pytest.raises(RuntimeError, match="reconfigure after the episode ended"):
        env.reconfigure(2)
    env.reset(seed=3)
    env.step(SPIN)  # reset makes it usable again


@pytest.mark.parametrize("modules", [11, 1, 0, -3])
def test_module_counts_outside_2_to_10_raise_value_error(modules):
    with pytest.raises(ValueError, match=rf"modules must be in 2..10, got {modules}"):
        comorph.make(modules=modules)
    with pytest.raises(ValueError, match="modules must be in 2..10"):
        comorph.VectorEnv(2, modules=modules)


def test_reset_options_are_checked(env):
    with pytest.raises(ValueError, match="modules must be in 2..10, got 11"):
        env.reset(seed=1, options={"modules": 11})
    with pytest.raises(ValueError, match=r"unknown reset option\(s\) \['height'\]"):
        env.reset(options={"height": 0.04})
    with pytest.raises(ValueError, match=r"stair_height must be in \[0, 0.3\] m"):
        env.reset(options={"stair_height": 0.5})
    with pytest.raises(ValueError, match="seed must be >= 0"):
        env.reset(seed=-1)
    with pytest.raises(ValueError, match="seed must be a whole number"):
        env.reset(seed=1.5)
    with pytest.raises(ValueError, match="reconfigure sheds tail modules: modules must be in 2..2, got 5"):
        env.reconfigure(5)


def test_bad_config_dir_names_the_directory(tmp_path):
    with pytest.raises(RuntimeError, match=f"{tmp_path}/missing: no such config directory"):
        comorph.make(config_dir=tmp_path / "missing")
    (tmp_path / "file").write_text("")
    with pytest.raises(RuntimeError, match="not a directory"):
        comorph.make(config_dir=tmp_path / "file")
    bad = tmp_path / "bad"
    bad.mkdir()
    (bad / "robot.yaml").write_text("depth_widht: 16\n")
    with pytest.raises(RuntimeError, match="robot.yaml.*depth_widht"):
        comorph.make(config_dir=bad)
    with pytest.raises(ValueError, match="config_dir must be a path"):
        comorph.make(config_dir=3)


def test_bad_make_arguments():
    with pytest.raises(ValueError, match="unknown env id 'comorph/Other-v0'"):
        comorph.make("comorph/Other-v0")
    with pytest.raises(ValueError, match="scenario 'stairs' is not one of default, obstacles7"):
        comorph.make(scenario="stairs")
    with pytest.raises(ValueError, match="obstacles must be in 0..10"):
        comorph.make(obstacles=11)
    with pytest.raises(ValueError, match="render_mode 'human' is not supported"):
        comorph.make(render_mode="human")
    with pytest.raises(ValueError, match="num_envs must be >= 1"):
        comorph.VectorEnv(0)
