"""comorph.load_run on the policy `make run` ships (results/quick-hier-td3):
the configuration model's choice for the first decision image is one its
committed evaluation records (eval-default.json: the chains its 300 episodes
started with per stair height), higher stairs get more modules, and the motion
model's greedy action drives the chosen chain up the stairs."""
import json
import os

import numpy as np
import pytest

import comorph
from conftest import SOURCE_DIR

RUN = SOURCE_DIR / "results" / "quick-hier-td3"


@pytest.fixture(scope="module")
def run(work):
    here = os.getcwd()
    os.chdir(work)  # the run's config names runs/classifier; loading checks it is there
    try:
        return comorph.load_run(RUN)
    finally:
        os.chdir(here)


def first_choices():
    """Per stair height the chain lengths the committed evaluation episodes started with."""
    summary = json.loads((RUN / "eval-default.json").read_text())
    return {float(h): {int(c.split("->")[0]) for c in configurations}
            for h, configurations in summary["configurations"].items()}


def test_first_choice_is_the_committed_evaluations(run):
    assert run.hierarchical
    env = run.make_env()
    choices = first_choices()
    assert set(choices) == {0.04, 0.06, 0.08}
    chosen = {}
    for height, recorded in sorted(choices.items()):
        for seed in (8200000, 8200001):
            obs, info = env.reset(seed=seed, options={"modules": 10, "stair_height": height})
            chosen[height, seed] = run.choose_modules(env.decision_depth(), 10, info["scene"])
            assert chosen[height, seed] in recorded, (height, seed, recorded)
    for seed in (8200000, 8200001):  # the trend of the paper: more modules for higher stairs
        assert chosen[0.04, seed] < chosen[0.08, seed], chosen
    obs, info = env.reset(seed=8200000, options={"modules": 10, "stair_height": 0.08})
    assert 2 <= run.choose_modules(env.decision_depth(), 3, info["scene"]) <= 3  # within [2, C_n]


def test_greedy_action_climbs_the_stairs(run):
    env = run.make_env()
    obs, info = env.reset(seed=8200003, options={"modules": 10, "stair_height": 0.04})
    modules = run.choose_modules(env.decision_depth(), 10, info["scene"])
    obs, info = env.reset(seed=8200003, options={"modules": modules, "stair_height": 0.04})
    a = run.act(obs)
    assert a.dtype == np.float32 and a.shape == (5,) and np.all(np.abs(a) <= 1)
    np.testing.assert_array_equal(a, run.act(obs))  # greedy: no noise
    climbed = False
    for _ in range(1500):
        obs, reward, terminated, truncated, info = env.step(run.act(obs))
        if info["stairs_climbed"]:
            climbed = True
            break
        assert not (terminated or truncated), info
    assert climbed, "the trained policy did not climb 0.04 m stairs in 1500 steps"
    idle = run.make_env(modules=modules)
    obs, _ = idle.reset(seed=8200003, options={"stair_height": 0.04})
    for _ in range(300):
        obs, *_ , info = idle.step(np.zeros(5, np.float32))
    assert not info["stairs_climbed"]  # standing still does not


def test_wrong_observations_and_runs_are_refused(run, tmp_path):
    obs, _ = comorph.make(modules=4).reset(seed=1)  # default sensors: 16 clearance columns, the run has 24
    with pytest.raises(ValueError, match="clearance: 16 floats, expected 24"):
        run.act(obs)
    with pytest.raises(ValueError, match="max_modules must be in 2..10"):
        run.choose_modules(np.zeros((1, 32, 32), np.float32), 11, 0)
    with pytest.raises(ValueError, match="image: 4 floats, expected 1024"):
        run.choose_modules(np.zeros(4, np.float32), 10, 0)
    with pytest.raises(ValueError, match="not a training run"):
        comorph.load_run(tmp_path)
