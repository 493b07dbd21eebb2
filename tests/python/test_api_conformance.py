"""comorph/MultiTask-v0 against Gymnasium's documented Env contract
(gymnasium.Env, gymnasium.spaces, the env checker's rules), checked without
Gymnasium: spaces, reset/step signatures and types, observations inside the
observation space, seeding determinism, terminated vs truncated, step before
reset refused, render and close."""
import numbers

import numpy as np
import pytest

import comorph
from conftest import FORWARD, SPIN, actions


def check_space(space, kind):
    """A Box has shape, dtype, low, high (arrays of that shape), sample() and contains()."""
    for attr in ("shape", "dtype", "low", "high", "sample", "contains", "seed"):
        assert hasattr(space, attr), f"{kind} lacks {attr}"
    assert space.low.shape == space.shape and space.high.shape == space.shape
    assert space.low.dtype == space.dtype and space.high.dtype == space.dtype
    assert np.all(space.low <= space.high)
    space.seed(3)
    first = [space.sample() for _ in range(5)]
    space.seed(3)
    again = [space.sample() for _ in range(5)]
    for x, y in zip(first, again):
        assert x.shape == space.shape and x.dtype == space.dtype
        assert space.contains(x)
        np.testing.assert_array_equal(x, y)  # sample() is seeded
    assert not space.contains(np.zeros((7,) + space.shape, space.dtype))          # wrong shape
    if np.isfinite(space.high).all():
        assert not space.contains(space.high + np.ones(space.shape, space.dtype))  # out of bounds


def check_obs(env, obs):
    assert isinstance(obs, dict)
    assert set(obs) == set(env.observation_space.spaces)
    for key, space in env.observation_space.spaces.items():
        x = obs[key]
        assert isinstance(x, np.ndarray), key
        assert x.dtype == space.dtype and x.shape == space.shape, (key, x.dtype, x.shape)
        assert space.contains(x), f"obs[{key!r}] outside its space"
        assert np.all(np.isfinite(x)), key
    assert env.observation_space.contains(obs)


def run_episode(env, seed, action_fn, limit=100000):
    obs, info = env.reset(seed=seed)
    trace = [obs]
    for t in range(limit):
        obs, reward, terminated, truncated, info = env.step(action_fn(t))
        trace.append((obs, reward, terminated, truncated, info))
        if terminated or truncated:
            return trace
    raise AssertionError("episode did not end")


def check_env(env):
    """The checker: everything Gymnasium documents for Env.reset/step/spaces."""
    check_space(env.action_space, "action_space")
    for key, space in env.observation_space.spaces.items():
        check_space(space, f"observation_space[{key!r}]")
    assert env.action_space.dtype == np.float32
    assert isinstance(env.metadata, dict) and "render_modes" in env.metadata and env.metadata["render_fps"] > 0

    # reset -> (obs, info); the declared spec sizes the observation.
    out = env.reset(seed=5)
    assert isinstance(out, tuple) and len(out) == 2
    obs, info = out
    check_obs(env, obs)
    assert isinstance(info, dict)
    spec = env.env_spec
    assert obs["depth"].shape == spec["depth_shape"] and obs["state"].shape == (spec["state_size"],)

    # step -> (obs, reward, terminated, truncated, info) with these types.
    out = env.step(env.action_space.sample())
    assert isinstance(out, tuple) and len(out) == 5
    obs, reward, terminated, truncated, info = out
    check_obs(env, obs)
    assert isinstance(reward, numbers.Real) and not isinstance(reward, bool) and np.isfinite(reward)
    assert isinstance(terminated, bool) and isinstance(truncated, bool)
    assert isinstance(info, dict) and info["termination"] in comorph.TERMINATIONS

    # Seeding: the same seed and actions give the same episode; another seed another scene.
    acts = actions(1, 30)
    def rollout(seed):
        o, _ = env.reset(seed=seed)
        out = [o]
        for a in acts:
            out.append(env.step(a))
        return out
    a, b, c = rollout(11), rollout(11), rollout(12)
    np.testing.assert_array_equal(a[0]["state"], b[0]["state"])
    for x, y in zip(a[1:], b[1:]):
        for key in x[0]:
            np.testing.assert_array_equal(x[0][key], y[0][key])
        assert x[1:4] == y[1:4]
    assert not all(np.array_equal(x[0]["state"], y[0]["state"]) for x, y in zip(a[1:], c[1:]))
    # reset() without a seed continues the seeded stream: two envs seeded alike agree.
    env.reset(seed=21)
    _, first = env.reset()
    env.reset(seed=21)
    _, second = env.reset()
    assert first["seed"] == second["seed"] != 21


def test_env_passes_the_checker():
    env = comorph.make("comorph/MultiTask-v0", modules=4)
    check_env(env)
    env.close()


@pytest.mark.parametrize("scenario,modules", [("obstacles8", 2), ("mixed", 10)])
def test_other_scenarios_pass_the_checker(scenario, modules):
    env = comorph.make("comorph/MultiTask-v0", modules=modules, scenario=scenario)
    check_env(env)
    obs, info = env.reset(seed=4)
    assert info["modules"] == modules
    assert obs["state"][32:42].sum() == modules  # the module mask


def test_terminated_is_a_failure_or_success_truncated_is_the_step_cap(short_episodes):
    env = comorph.make(modules=2)
    trace = run_episode(env, 3, lambda t: SPIN)
    _, reward, terminated, truncated, info = trace[-1]
    assert terminated and not truncated
    assert info["termination"] == "left_area" and reward < -9  # r_u = -10
    assert all(not (s[2] or s[3]) for s in trace[1:-1])
    for key in ("T", "E", "D", "F", "time_s", "episode_energy_J"):
        assert key in info and np.isfinite(info[key])
    assert "F" not in trace[1][4]  # metrics only at the end

    capped = comorph.make(modules=2, config_dir=short_episodes)
    trace = run_episode(capped, 3, lambda t: FORWARD)
    _, _, terminated, truncated, info = trace[-1]
    assert truncated and not terminated and info["termination"] == "step_cap" and info["step"] == 40
    assert len(trace) == 41


def test_step_before_reset_is_refused():
    env = comorph.make()
    with pytest.raises(RuntimeError, match="before reset"):
        env.step(env.action_space.sample())


def test_reset_options_set_modules_and_stair_height():
    env = comorph.make(modules=4)
    obs, info = env.reset(seed=2, options={"modules": 7, "stair_height": 0.08})
    assert info["modules"] == 7 and info["stair_height"] == pytest.approx(0.08)
    obs, info = env.reset(seed=2)
    assert info["modules"] == 4 and info["stair_height"] in (0.04, 0.06, 0.08)


def test_reconfigure_sheds_modules_mid_episode():
    env = comorph.make(modules=6)
    env.reset(seed=1)
    for _ in range(5):
        env.step(FORWARD)
    env.reconfigure(3)
    obs, _, _, _, info = env.step(FORWARD)
    assert info["modules"] == 3 and env.modules == 3
    np.testing.assert_array_equal(obs["state"][32:42], [1, 1, 1, 0, 0, 0, 0, 0, 0, 0])
    with pytest.raises(ValueError, match="2..2"):
        env.reconfigure(3)


def test_render_gives_rgb_frames_of_the_episode():
    env = comorph.make(modules=3, render_mode="rgb_array")
    env.reset(seed=1)
    first = env.render()
    assert first.dtype == np.uint8 and first.shape == (480, 640, 3)
    assert first.std() > 5  # a scene, not a blank frame
    for _ in range(40):
        env.step(FORWARD)
    assert not np.array_equal(env.render(), first)  # the camera follows a moving robot
    env.close()
    with pytest.raises(RuntimeError, match="render_mode"):
        comorph.make().render()


def test_context_manager_and_unwrapped():
    with comorph.make() as env:
        assert env.unwrapped is env
        env.reset(seed=0)


def test_registered_with_gymnasium_when_it_is_installed():
    gym = pytest.importorskip("gymnasium")
    env = gym.make("comorph/MultiTask-v0", modules=3)
    obs, _ = env.reset(seed=1)
    assert env.observation_space.contains(obs)
